//! What the baseline controllers share: their tuning (one bandwidth each),
//! the PID gains of a discrete triple pole, the reference's velocity and
//! acceleration from the sampled preview, and the PID law with anti-windup.
//!
//! # Gains: a discrete triple pole at `p = e^(−ωn·Ts)`
//!
//! With the acceleration `v_k` held over each period (zero-order hold) the
//! error `e = q_ref − q` of a joint whose acceleration the controller sets
//! evolves as the discretized double integrator with an integral state
//! `z_k = Ts Σ_{j<k} e_j`:
//!
//! ```text
//! e_{k+1} = e_k + Ts ė_k − Ts²/2 v_k,   ė_{k+1} = ė_k − Ts v_k,   z_{k+1} = z_k + Ts e_k,
//! v_k = kp e_k + kd ė_k + ki z_k.
//! ```
//!
//! Its characteristic polynomial is
//! `(z−1)³ + (kp Ts²/2)(z²−1) + kd Ts (z−1)² + (ki Ts³/2)(z+1)`; matching it
//! to `(z − p)³` gives, with `a = kp Ts²/2`, `b = kd Ts`, `c = ki Ts³/2`,
//!
//! ```text
//! b = (7 − 3p − 3p² − p³)/4,   a = 3 − 3p − b,   c = 3p² − 3 + 2b
//! ```
//!
//! (pole placement of a sampled PID, Franklin, Powell & Workman, *Digital
//! Control of Dynamic Systems*, 3rd ed., ch. 8; [`triple_pole_gains`]). The
//! continuous limit (`Ts → 0`) is `kp = 3ωn²`, `kd = 3ωn`, `ki = ωn³`.
//!
//! # Robustness to an unmodelled inertia (Routh, Jury)
//!
//! When the plant's inertia is `r` times the one the gains were scaled by
//! (a payload the nominal model leaves out), the loop gain of the error
//! dynamics is `γ = 1/r` and the characteristic polynomial becomes
//!
//! ```text
//! P_γ(z) = (z−1)³ + γ [a(z²−1) + b(z−1)² + c(z+1)]
//!        = z³ + (γ(a+b) − 3) z² + (γ(c−2b) + 3) z + (γ(b+c−a) − 1).
//! ```
//!
//! In continuous time (`Ts → 0`) this is `s³ + γ(kd s² + kp s + ki)`, which
//! Routh–Hurwitz keeps stable only while `γ kd kp > ki`, i.e. `r < kd kp / ki
//! = 9` for the triple pole. Sampled, the Jury conditions on the monic cubic
//! `z³ + a₂z² + a₁z + a₀` (`P(1) > 0`, `−P(−1) > 0`, `|a₀| < 1`,
//! `|a₀² − 1| > |a₀a₂ − a₁|`; Franklin, Powell & Workman, §4.5; Åström &
//! Wittenmark, *Computer-Controlled Systems*, §3.3) bound `r` on both sides
//! ([`triple_pole_inertia_ratio_range`]); at `Ts` = 10 ms:
//!
//! ```text
//! ωn (rad/s)     20     60     100    150
//! r_min        0.248  0.536  0.680  0.771
//! r_max        7.02   4.71   3.56   2.83
//! ```
//!
//! For computed torque on the nominal `Ĥ` the plant's error dynamics are
//! `ë = H⁻¹Ĥ (…)`: the joints decouple along the eigenvectors of `Ĥ⁻¹H` and
//! the ratio that counts is its largest generalized eigenvalue
//! `r = λmax(Ĥ⁻¹H) = 1 + m λmax(J Ĥ⁻¹ Jᵀ)` for a point mass `m` at the point
//! of the translational Jacobian `J` (not the diagonal's ratio). For the PID
//! scaled by `D = diag Ĥ(q₀)` it is the spread of the eigenvalues of `D⁻¹H`,
//! which the joints' coupling widens on both sides even without a payload.
//!
//! # Reference velocity and acceleration from the samples
//!
//! The controllers see the reference at the samples only. A double
//! integrator driven by a held acceleration `a_k` passes through every
//! sample `w_k` when `a_k + a_{k−1} = 2 Δ²w_k / Ts²`; its smooth solution, to
//! `O(Ts²)`, and the velocity that then reaches `w_{k+1}` exactly are
//!
//! ```text
//! a_k = (w_{k+2} − w_{k+1} − w_k + w_{k−1}) / (2 Ts²),   v_k = (w_{k+1} − w_k)/Ts − Ts a_k / 2
//! ```
//!
//! (`RefDerivatives`): the feed-forward of the computed-torque law and the
//! reference velocity of every baseline's derivative term.
//!
//! # Anti-windup
//!
//! Conditional integration: the integral of a joint whose torque the drives'
//! limit clipped at this sample is not accumulated (as the incremental
//! algorithms' aggregated error, [`crate::control::MpcSettings::torque_limits`]).

use crate::control::drive_model::DriveModel;
use crate::control::mpc::core::{check_finite, check_len, check_result, check_step_input};
use crate::control::mpc::model::LinearLikeModel;
use crate::control::settings::{MpcSettings, SettingsError};
use crate::control::step::{StepFailure, StepInfo};
use crate::dynamics::JointSpaceDynamics;

/// `(kp, kd, ki)` that place the three poles of the sampled PID loop of a
/// double integrator at `e^(−ωn·Ts)` (module docs).
pub fn triple_pole_gains(omega_n: f64, ts: f64) -> (f64, f64, f64) {
    let p = (-omega_n * ts).exp();
    let b = (7.0 - 3.0 * p - 3.0 * p * p - p * p * p) / 4.0;
    let a = 3.0 - 3.0 * p - b;
    let c = 3.0 * p * p - 3.0 + 2.0 * b;
    (2.0 * a / (ts * ts), b / ts, 2.0 * c / (ts * ts * ts))
}

/// Whether the sampled triple-pole loop of [`triple_pole_gains`] at `omega_n`
/// stays stable when the plant's inertia is `1/gamma` times the nominal one:
/// the Jury conditions on `P_γ` (module docs).
pub fn triple_pole_is_stable(omega_n: f64, ts: f64, gamma: f64) -> bool {
    let (kp, kd, ki) = triple_pole_gains(omega_n, ts);
    let (a, b, c) = (kp * ts * ts / 2.0, kd * ts, ki * ts * ts * ts / 2.0);
    let a2 = gamma * (a + b) - 3.0;
    let a1 = gamma * (c - 2.0 * b) + 3.0;
    let a0 = gamma * (b + c - a) - 1.0;
    let p1 = 1.0 + a2 + a1 + a0;
    let pm1 = -1.0 + a2 - a1 + a0;
    p1 > 0.0 && -pm1 > 0.0 && a0.abs() < 1.0 && (a0 * a0 - 1.0).abs() > (a0 * a2 - a1).abs()
}

/// The range `(r_min, r_max)` of inertia ratios (plant over nominal) over
/// which the sampled triple-pole loop at `omega_n` stays stable (module
/// docs), to a relative `1e-9`: the boundaries of the stable interval of
/// `γ = 1/r` around `γ = 1`, found by bisection on the Jury test
/// (`triple_pole_is_stable`). `(NaN, NaN)` when the loop is not stable at
/// the nominal inertia (`omega_n` or `ts` not finite and `> 0`).
pub fn triple_pole_inertia_ratio_range(omega_n: f64, ts: f64) -> (f64, f64) {
    let valid = omega_n > 0.0 && ts > 0.0 && omega_n.is_finite() && ts.is_finite();
    if !(valid && triple_pole_is_stable(omega_n, ts, 1.0)) {
        return (f64::NAN, f64::NAN);
    }
    let boundary = |mut stable: f64, mut unstable: f64| {
        while (stable - unstable).abs() > 1e-9 * stable.abs().max(unstable.abs()) {
            let mid = 0.5 * (stable + unstable);
            if triple_pole_is_stable(omega_n, ts, mid) {
                stable = mid;
            } else {
                unstable = mid;
            }
        }
        stable
    };
    // Small gains: the three poles meet at z = 1 as γ → 0 (unstable side).
    let gamma_min = boundary(1.0, 0.0);
    let mut hi = 2.0;
    while triple_pole_is_stable(omega_n, ts, hi) && hi < 1e12 {
        hi *= 2.0;
    }
    let gamma_max = boundary(1.0, hi);
    (1.0 / gamma_max, 1.0 / gamma_min)
}

/// The reference's velocity and held acceleration at sample `k` from
/// `w_{k−1}, w_k, w_{k+1}, w_{k+2}` (module docs). Keeps `w_{k−1}`.
#[derive(Debug, Clone)]
pub(crate) struct RefDerivatives {
    /// The control period (s).
    ts: f64,
    w_prev: Vec<f64>,
    has_prev: bool,
    /// `v_k` (n values).
    pub v: Vec<f64>,
    /// `a_k` (n values).
    pub a: Vec<f64>,
}

impl RefDerivatives {
    /// For `n` joints sampled every `ts` (s).
    pub fn new(n: usize, ts: f64) -> Self {
        Self {
            ts,
            w_prev: vec![0.0; n],
            has_prev: false,
            v: vec![0.0; n],
            a: vec![0.0; n],
        }
    }

    /// Forgets `w_{k−1}` (the next sample takes the reference at rest before).
    pub fn reset(&mut self) {
        self.has_prev = false;
    }

    /// Computes `v_k`, `a_k` from `w_k` and the preview (`w_{k+1}, …`, at
    /// least one block; `w_{k+2} = w_{k+1}` with a horizon of one).
    pub fn update(&mut self, w_k: &[f64], preview: &[f64]) {
        let (n, ts) = (w_k.len(), self.ts);
        let w1 = &preview[..n];
        let w2 = preview.get(n..2 * n).unwrap_or(w1);
        for i in 0..n {
            let wm = if self.has_prev {
                self.w_prev[i]
            } else {
                w_k[i]
            };
            let a = (w2[i] - w1[i] - w_k[i] + wm) / (2.0 * ts * ts);
            self.a[i] = a;
            self.v[i] = (w1[i] - w_k[i]) / ts - 0.5 * ts * a;
        }
    }

    /// Commits `w_{k−1} ← w_k` after a successful step.
    pub fn commit(&mut self, w_k: &[f64]) {
        self.w_prev.copy_from_slice(w_k);
        self.has_prev = true;
    }
}

/// The PID law of the baselines, per joint: `v = kp e + kd ė + ki z` with
/// conditional integration ([`JointPid::commit`]).
#[derive(Debug, Clone)]
pub(crate) struct JointPid {
    kp: Vec<f64>,
    kd: Vec<f64>,
    ki: Vec<f64>,
    ts: f64,
    z: Vec<f64>,
    e: Vec<f64>,
}

impl JointPid {
    /// Gains of the triple pole at `e^(−ωn_i·Ts)` for each joint.
    pub fn new(omega_n: &[f64], ts: f64) -> Self {
        let n = omega_n.len();
        let mut s = Self {
            kp: vec![0.0; n],
            kd: vec![0.0; n],
            ki: vec![0.0; n],
            ts,
            z: vec![0.0; n],
            e: vec![0.0; n],
        };
        for (i, w) in omega_n.iter().enumerate() {
            (s.kp[i], s.kd[i], s.ki[i]) = triple_pole_gains(*w, ts);
        }
        s
    }

    /// Clears the integral.
    pub fn reset(&mut self) {
        self.z.fill(0.0);
    }

    /// `v_i = s_i kp e_i + kd ė_i + ki z_i` with `e = w_k − q`, `ė = v_ref − q̇`
    /// and `s = kp_scale` (1: the triple pole; the stiffer hold of
    /// [`JointLawCore`]) (writes `out`; the integral is not changed until
    /// [`Self::commit`]).
    pub fn law(
        &mut self,
        x: &[f64],
        w_k: &[f64],
        v_ref: &[f64],
        kp_scale: &[f64],
        out: &mut [f64],
    ) {
        let n = w_k.len();
        for i in 0..n {
            let e = w_k[i] - x[i];
            let ed = v_ref[i] - x[n + i];
            self.e[i] = e;
            out[i] = kp_scale[i] * self.kp[i] * e + self.kd[i] * ed + self.ki[i] * self.z[i];
        }
    }

    /// `z_{k+1} = z_k + Ts e_k` on every joint whose torque was not clipped.
    pub fn commit(&mut self, clipped: &[bool]) {
        for i in 0..self.z.len() {
            if !clipped[i] {
                self.z[i] += self.ts * self.e[i];
            }
        }
    }
}

/// Clips `tau` to `±limits` (when given), marking the clipped joints.
pub(crate) fn clip(tau: &mut [f64], limits: Option<&[f64]>, clipped: &mut [bool]) {
    clipped.fill(false);
    if let Some(lim) = limits {
        for ((t, l), c) in tau.iter_mut().zip(lim).zip(clipped.iter_mut()) {
            if t.abs() > *l {
                *t = t.clamp(-l, *l);
                *c = true;
            }
        }
    }
}

/// Which joint-space law a [`JointLawCore`] runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Law {
    /// `τ = g(q) + D (kp e + kd ė + ki z)`, `D = diag H(q_0)` ([`crate::control::baselines::pid`]).
    Pid,
    /// `τ = H(q)(a_ref + kp e + kd ė + ki z) + C(q, q̇) q̇ + g(q)` ([`crate::control::baselines::ctc`]).
    Ctc,
}

/// Everything of the PID and computed-torque baselines but the kind:
/// buffers sized once, the model terms, the law, limits and friction.
#[derive(Debug, Clone)]
pub(crate) struct JointLawCore {
    law: Law,
    n: usize,
    settings: MpcSettings,
    model: LinearLikeModel,
    pid: JointPid,
    refd: RefDerivatives,
    /// `H_ii(q_0)` of the PID law (at the state of the last reset).
    scale: Vec<f64>,
    scale_ready: bool,
    x0: Vec<f64>,
    fb: Vec<f64>,
    u: Vec<f64>,
    increments: Vec<f64>,
    tau_new: Vec<f64>,
    clipped: Vec<bool>,
    /// Joints in the hold dead zone this sample ([`crate::control::dead_zone`]).
    hold: Vec<bool>,
    hold_band: Vec<f64>,
    /// Per joint: the factor on `kp` while the joint holds on the
    /// friction's damper (`ctc_hold_gain_scale`); `None` when every factor is 1.
    hold_gain: Option<Vec<f64>>,
    /// The factor on `kp` of this sample (1 but at a creeping hold).
    kp_scale: Vec<f64>,
    drives: Option<DriveModel>,
}

impl JointLawCore {
    /// Buffers for `n` joints; the gains from `omega_n` (rad/s, per joint).
    pub fn new(
        law: Law,
        n: usize,
        settings: &MpcSettings,
        omega_n: &[f64],
    ) -> Result<Self, SettingsError> {
        settings.validate_for_dof(n)?;
        Ok(Self {
            law,
            n,
            settings: settings.clone(),
            model: LinearLikeModel::new(n),
            pid: JointPid::new(omega_n, settings.ts),
            refd: RefDerivatives::new(n, settings.ts),
            scale: vec![1.0; n],
            scale_ready: false,
            x0: vec![0.0; 2 * n],
            fb: vec![0.0; n],
            u: vec![0.0; n],
            increments: vec![0.0; settings.horizon * n],
            tau_new: vec![0.0; n],
            clipped: vec![false; n],
            hold: vec![false; n],
            hold_band: crate::control::dead_zone::bands_rad(
                settings.encoder_counts,
                &settings.dead_zone_counts,
                n,
            ),
            hold_gain: None,
            kp_scale: vec![1.0; n],
            drives: None,
        })
    }

    pub fn dof(&self) -> usize {
        self.n
    }
    pub fn horizon(&self) -> usize {
        self.settings.horizon
    }
    pub fn settings(&self) -> &MpcSettings {
        &self.settings
    }
    pub fn input(&self) -> &[f64] {
        &self.u
    }
    pub fn increments(&self) -> &[f64] {
        &self.increments
    }

    /// Keeps the drives' limits and friction estimates.
    pub fn set_drive_model(&mut self, drives: &DriveModel) -> Result<(), SettingsError> {
        drives.validate(self.n)?;
        self.drives = Some(drives.clone());
        Ok(())
    }

    /// Integral, input and `w_{k−1}` cleared; the PID's scale is taken at
    /// `x0` at the next step.
    pub fn reset(&mut self, x0: &[f64]) -> Result<(), StepFailure> {
        check_len("x0", x0.len(), 2 * self.n)?;
        check_finite("x0", x0)?;
        self.x0.copy_from_slice(x0);
        self.scale_ready = false;
        self.pid.reset();
        self.refd.reset();
        self.u.fill(0.0);
        self.increments.fill(0.0);
        Ok(())
    }

    /// One step of the law (module docs); state committed only on success.
    pub fn step(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        x: &[f64],
        w_k: &[f64],
        preview: &[f64],
        tau: &mut [f64],
    ) -> Result<StepInfo, StepFailure> {
        let n = self.n;
        check_step_input(n, self.settings.horizon, x, w_k, preview, tau.len())?;
        let limited = self.settings.torque_limits;
        if (limited || self.settings.friction_compensation) && self.drives.is_none() {
            return Err(StepFailure::NoDriveModel);
        }
        if self.law == Law::Pid && !self.scale_ready {
            self.model.update(model, &self.x0[..n], &self.x0[n..])?;
            for (i, s) in self.scale.iter_mut().enumerate() {
                *s = self.model.h()[(i, i)];
            }
            self.scale_ready = true;
        }
        self.model.update(model, &x[..n], &x[n..])?;
        self.refd.update(w_k, preview);
        self.hold_gains(x, w_k, preview);
        self.pid
            .law(x, w_k, &self.refd.v, &self.kp_scale, &mut self.fb);
        match self.law {
            Law::Pid => {
                self.u.copy_from_slice(&self.fb);
                let g = self.model.g();
                for i in 0..n {
                    self.tau_new[i] = g[i] + self.scale[i] * self.fb[i];
                }
            }
            Law::Ctc => {
                for i in 0..n {
                    self.u[i] = self.refd.a[i] + self.fb[i];
                }
                self.model.torque(&self.u, &mut self.tau_new)?;
                let c = self.model.c().as_slice();
                for (j, col) in c.chunks_exact(n).enumerate() {
                    crate::control::solvers::dense::axpy(x[n + j], col, &mut self.tau_new);
                }
            }
        }
        if let Some(d) = self
            .drives
            .as_ref()
            .filter(|_| self.settings.friction_compensation)
        {
            // The friction estimate at the reference's velocity, as the
            // predictive controllers' feed-forward (MpcSettings::friction_compensation).
            for (i, t) in self.tau_new.iter_mut().enumerate() {
                let v = (preview[i] - w_k[i]) / self.settings.ts;
                *t += d.damping(i, v) * v;
            }
        }
        let limits = self
            .drives
            .as_ref()
            .filter(|_| limited)
            .map(|d| d.max_torque_nm.as_slice());
        clip(&mut self.tau_new, limits, &mut self.clipped);
        // The hold dead zone (dead_zone.rs): no integration within the
        // encoder's resolution while the reference rests.
        crate::control::dead_zone::in_dead_zone_bands(
            &self.hold_band,
            w_k,
            &x[..n],
            preview,
            &mut self.hold,
        );
        for (c, h) in self.clipped.iter_mut().zip(&self.hold) {
            *c |= *h;
        }
        check_result(&self.u, &self.tau_new)?;
        tau.copy_from_slice(&self.tau_new);
        self.pid.commit(&self.clipped);
        self.refd.commit(w_k);
        self.increments[..n].copy_from_slice(&self.u);
        Ok(StepInfo {
            cost: 0.0,
            r_diag_ratio: 1.0,
            zoh_squarings: 0,
        })
    }
}

impl JointLawCore {
    /// The factor on `kp` per joint at a creeping hold (`None`: none), the
    /// computed-torque baselines' `ctc_hold_gain_scale`.
    pub fn set_hold_gain(&mut self, scale: Option<Vec<f64>>) {
        self.hold_gain = scale;
    }

    /// `kp`'s factor of this sample: `ctc_hold_gain_scale` on the joints that
    /// hold on the compensated friction's stiff damper
    /// ([`crate::control::dead_zone::creeps_at_rest`]), 1 elsewhere. Against
    /// the damper `b` the PID's integral rings (`b s² + M kp s + M ki`,
    /// damped by `M kp / (2 √(M ki b))`); a stiffer proportional action damps
    /// it, and the damper keeps it stable through the delay.
    fn hold_gains(&mut self, x: &[f64], w_k: &[f64], preview: &[f64]) {
        let Some(scale) = &self.hold_gain else {
            return;
        };
        let n = self.n;
        let drives = self
            .drives
            .as_ref()
            .filter(|_| self.settings.friction_compensation);
        for (i, s) in self.kp_scale.iter_mut().enumerate() {
            let creeps =
                crate::control::dead_zone::creeps_at_rest(drives, i, x[n + i], w_k, preview);
            *s = if creeps { scale[i] } else { 1.0 };
        }
    }
}

impl crate::control::mpc::core::ControllerCore for JointLawCore {
    fn dof(&self) -> usize {
        JointLawCore::dof(self)
    }
    fn horizon(&self) -> usize {
        JointLawCore::horizon(self)
    }
    fn settings(&self) -> &MpcSettings {
        JointLawCore::settings(self)
    }
    fn reset(&mut self, x0: &[f64]) -> Result<(), StepFailure> {
        JointLawCore::reset(self, x0)
    }
    fn input(&self) -> &[f64] {
        JointLawCore::input(self)
    }
    fn increments(&self) -> &[f64] {
        JointLawCore::increments(self)
    }
    fn set_drive_model(&mut self, drives: &DriveModel) -> Result<(), SettingsError> {
        JointLawCore::set_drive_model(self, drives)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gains_place_a_triple_pole() {
        for (wn, ts) in [(60.0, 0.01), (150.0, 0.01), (5.0, 0.001)] {
            let (kp, kd, ki) = triple_pole_gains(wn, ts);
            let p: f64 = (-wn * ts).exp();
            // Closed-loop matrix of the module docs; its characteristic
            // polynomial evaluated at a few points equals (z − p)³.
            let a = [
                [
                    1.0 - ts * ts / 2.0 * kp,
                    ts - ts * ts / 2.0 * kd,
                    -ts * ts / 2.0 * ki,
                ],
                [-ts * kp, 1.0 - ts * kd, -ts * ki],
                [ts, 0.0, 1.0],
            ];
            for z in [-1.3, 0.2, 0.9, 2.0] {
                let m = |i: usize, j: usize| if i == j { z - a[i][j] } else { -a[i][j] };
                let det = m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1))
                    - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0))
                    + m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0));
                let want = (z - p).powi(3);
                assert!(
                    (det - want).abs() < 1e-9 * (1.0 + want.abs()),
                    "{det} vs {want}"
                );
            }
        }
        // Continuous limit.
        let (kp, kd, ki) = triple_pole_gains(10.0, 1e-5);
        assert!((kp / 300.0 - 1.0).abs() < 1e-3 && (kd / 30.0 - 1.0).abs() < 1e-3);
        assert!((ki / 1000.0 - 1.0).abs() < 1e-2);
    }

    /// Spectral radius of `P_γ` from its roots (the companion matrix's
    /// eigenvalues, an independent check of the Jury test).
    fn spectral_radius(omega_n: f64, ts: f64, gamma: f64) -> f64 {
        let (kp, kd, ki) = triple_pole_gains(omega_n, ts);
        let (a, b, c) = (kp * ts * ts / 2.0, kd * ts, ki * ts * ts * ts / 2.0);
        let (a2, a1, a0) = (
            gamma * (a + b) - 3.0,
            gamma * (c - 2.0 * b) + 3.0,
            gamma * (b + c - a) - 1.0,
        );
        let m = nalgebra::Matrix3::new(-a2, -a1, -a0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
        m.complex_eigenvalues()
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max)
    }

    #[test]
    fn jury_test_and_ratio_range_agree_with_the_roots() {
        // The module docs' table (Ts = 10 ms), and the continuous limit r < 9.
        let table = [
            (20.0, 0.248, 7.02),
            (60.0, 0.536, 4.71),
            (100.0, 0.680, 3.56),
            (150.0, 0.771, 2.83),
        ];
        for (wn, rmin, rmax) in table {
            let (lo, hi) = triple_pole_inertia_ratio_range(wn, 0.01);
            assert!((lo / rmin - 1.0).abs() < 2e-3, "{wn}: r_min {lo}");
            assert!((hi / rmax - 1.0).abs() < 2e-3, "{wn}: r_max {hi}");
            // Inside the range every root is inside the unit circle, just
            // outside it one is not.
            for r in [lo * 1.01, 1.0, (lo * hi).sqrt(), hi * 0.99] {
                assert!(spectral_radius(wn, 0.01, 1.0 / r) < 1.0, "{wn}, r {r}");
                assert!(triple_pole_is_stable(wn, 0.01, 1.0 / r));
            }
            for r in [lo * 0.99, hi * 1.01, hi * 3.0] {
                assert!(spectral_radius(wn, 0.01, 1.0 / r) > 1.0, "{wn}, r {r}");
                assert!(!triple_pole_is_stable(wn, 0.01, 1.0 / r));
            }
        }
        let (_, hi) = triple_pole_inertia_ratio_range(1.0, 1e-4);
        assert!((hi / 9.0 - 1.0).abs() < 1e-3, "{hi}");
        assert!(triple_pole_inertia_ratio_range(f64::NAN, 0.01).0.is_nan());
    }

    #[test]
    fn reference_derivatives_are_exact_for_a_cubic() {
        // w(t) = t³: the held acceleration reaches w_{k+1} exactly from
        // (w_k, v_k), and v_k, a_k are within O(Ts²) of w', mean w''.
        let ts = 0.01;
        let w = |k: f64| (k * ts).powi(3);
        let mut r = RefDerivatives::new(1, ts);
        let k = 50.0;
        r.commit(&[w(k - 1.0)]);
        r.update(&[w(k)], &[w(k + 1.0), w(k + 2.0)]);
        let reached = w(k) + ts * r.v[0] + 0.5 * ts * ts * r.a[0];
        assert!((reached - w(k + 1.0)).abs() < 1e-15);
        let t = k * ts;
        assert!((r.v[0] - 3.0 * t * t).abs() <= 0.5 * ts * ts + 1e-15);
        assert!((r.a[0] - 6.0 * (t + ts / 2.0)).abs() < 1e-9);
    }
}
