//! `dob-mpc`'s payload from its own hold at rest (issue 35,
//! `BaselineSettings::dob_identify_at_rest`): as an industrial controller
//! identifies its load before it moves (ABB's LoadIdentify, KUKA's load
//! data), the disturbance-observer MPC fits a point mass to the torque it
//! holds the arm with at rest, and gives its model that payload before the
//! path starts.
//!
//! # The fit
//!
//! At rest the plant holds `τ = g_plant(q) + f`, `f` the friction at rest
//! (within its Coulomb band `±F_c`; the smoothed law creeps it to 0). With
//! the observer converged the controller's torque is that torque, so the
//! window's mean `τ̄` (over the last [`WINDOW_S`] of the rest, at the mean
//! pose `q̄`) less the bare model's gravity is what the model misses,
//!
//! ```text
//! r = τ̄ − g_0(q̄) = m y(q̄) + e,   y(q) = g_{1 kg}(q) − g_0(q) = J_v(q)ᵀ (−m⁻¹ g⃗ m),
//! ```
//!
//! `g_0` the model without a payload, `g_{1 kg}` with a 1 kg point mass at
//! the flange (the payload's gravity is linear in its mass), `e` the
//! friction at rest and the model's own error. Each joint's error is bounded
//! by its friction band `b_i` (the Coulomb estimate × [`BAND_FACTOR`], the
//! estimate being known to 20 %; at least [`MIN_BAND_NM`]); weighted by it,
//! the least-squares mass and its standard deviation (friction uniform in
//! `±b_i`: variance `b_i²/3`) are
//!
//! ```text
//! m̂ = Σ y_i r_i / b_i² / Σ y_i² / b_i²,   σ_m = 1 / √(3 Σ y_i² / b_i²).
//! ```
//!
//! # When it is trusted ([`fit_point_mass`])
//!
//! * observable: `σ_m ≤` [`MAX_SIGMA_FRACTION`] × the mass bound — a pose
//!   whose gravity does not load the payload (the flange above the axes
//!   that gravity acts on) refuses, never guesses;
//! * physical: `m̂` within `[0, max_mass]` by more than `3 σ_m` refuses; within
//!   that it is clipped to the bound;
//! * consistent: every joint's residual `|r_i − m̂ y_i|` within
//!   [`RESIDUAL_BANDS`] bands — a torque a point mass cannot explain (a
//!   collision, a wrong model) refuses;
//! * settled ([`RestIdentification`]): the window full of samples at rest.
//!
//! Refused, the model keeps its nominal payload (`MpcSettings::model_payload_kg`).

use crate::dynamics::{gravity, JointSpaceDynamics};
use crate::robot::Payload;

/// The averaging window at the end of the rest (s).
pub const WINDOW_S: f64 = 0.2;
/// The friction band of a joint: its Coulomb estimate × this (the estimate
/// known to 20 %: the true value up to `1/0.8`).
pub const BAND_FACTOR: f64 = 1.25;
/// The least band of a joint (N·m): the rounding and noise of the torque
/// when no friction is estimated.
pub const MIN_BAND_NM: f64 = 0.05;
/// Largest standard deviation of the mass, as a fraction of the mass bound.
pub const MAX_SIGMA_FRACTION: f64 = 0.1;
/// Largest residual of a joint, in its friction bands.
pub const RESIDUAL_BANDS: f64 = 3.0;

/// A trusted fit: the mass (kg, clipped to the bound) and its standard
/// deviation (kg).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassFit {
    /// The payload mass (kg).
    pub mass_kg: f64,
    /// Its standard deviation from the friction bands (kg).
    pub sigma_kg: f64,
}

/// Why a fit was refused (the model keeps its nominal payload).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FitRefusal {
    /// The pose does not observe the mass: `σ_m` (kg) above the limit.
    Unobservable {
        /// The mass's standard deviation (kg; infinite with no gravity load).
        sigma_kg: f64,
    },
    /// The fitted mass (kg) is outside `[0, max]` by more than `3 σ_m`.
    Unphysical {
        /// The unclipped fit (kg).
        mass_kg: f64,
    },
    /// A joint's torque is not a point mass's (N·m residual).
    Inconsistent {
        /// The joint.
        joint: usize,
        /// Its residual (N·m).
        residual_nm: f64,
    },
    /// The rest before the motion was shorter than the window, or the model
    /// could not be evaluated.
    NoData,
}

/// The weighted least-squares point mass of `r ≈ m y` with the bands `band`
/// (module docs), bounded to `[0, max_mass]`. Allocates nothing.
pub fn fit_point_mass(
    y: &[f64],
    r: &[f64],
    band: &[f64],
    max_mass: f64,
) -> Result<MassFit, FitRefusal> {
    let (mut yy, mut yr) = (0.0, 0.0);
    for ((yi, ri), bi) in y.iter().zip(r).zip(band) {
        yy += yi * yi / (bi * bi);
        yr += yi * ri / (bi * bi);
    }
    let sigma_kg = 1.0 / (3.0 * yy).sqrt();
    if !(sigma_kg.is_finite() && sigma_kg <= MAX_SIGMA_FRACTION * max_mass) {
        return Err(FitRefusal::Unobservable { sigma_kg });
    }
    let raw = yr / yy;
    if !(raw >= -3.0 * sigma_kg && raw <= max_mass + 3.0 * sigma_kg) {
        return Err(FitRefusal::Unphysical { mass_kg: raw });
    }
    let mass_kg = raw.clamp(0.0, max_mass);
    for (joint, ((yi, ri), bi)) in y.iter().zip(r).zip(band).enumerate() {
        let residual_nm = ri - mass_kg * yi;
        if !(residual_nm.is_finite() && residual_nm.abs() <= RESIDUAL_BANDS * bi) {
            return Err(FitRefusal::Inconsistent { joint, residual_nm });
        }
    }
    Ok(MassFit { mass_kg, sigma_kg })
}

/// The window of torques and poses at rest, and the fit from it, once per
/// run: sized at construction, allocation-free.
#[derive(Debug, Clone)]
pub struct RestIdentification {
    n: usize,
    max_mass: f64,
    band: Vec<f64>,
    /// `W × n` torques and poses, a ring.
    tau: Vec<f64>,
    q: Vec<f64>,
    next: usize,
    filled: usize,
    decided: bool,
    /// The model's payload mass (kg): the nominal until a fit is trusted.
    mass: f64,
    nominal_kg: f64,
    /// The model's payload and `mass` before the last trusted fit ([`Self::undo`]).
    saved: (Option<Payload>, f64),
    q_mean: Vec<f64>,
    r: Vec<f64>,
    y: Vec<f64>,
}

impl RestIdentification {
    /// For `n` joints at the period `ts` (s), the mass bound `max_mass`
    /// (kg, > 0) and the nominal model payload mass `nominal_kg`.
    pub fn new(n: usize, ts: f64, max_mass: f64, nominal_kg: f64) -> Self {
        let w = ((WINDOW_S / ts).round() as usize).max(1);
        Self {
            n,
            max_mass,
            band: vec![MIN_BAND_NM; n],
            tau: vec![0.0; w * n],
            q: vec![0.0; w * n],
            next: 0,
            filled: 0,
            decided: false,
            mass: nominal_kg,
            nominal_kg,
            saved: (None, nominal_kg),
            q_mean: vec![0.0; n],
            r: vec![0.0; n],
            y: vec![0.0; n],
        }
    }

    /// The friction bands from the drives' Coulomb estimates (N·m).
    pub fn set_coulomb(&mut self, coulomb_nm: &[f64]) {
        for (b, c) in self.band.iter_mut().zip(coulomb_nm) {
            *b = (BAND_FACTOR * c).max(MIN_BAND_NM);
        }
    }

    /// Forgets the window and the fit (the controller's reset puts the
    /// model's nominal payload back).
    pub fn reset(&mut self) {
        self.next = 0;
        self.filled = 0;
        self.decided = false;
        self.mass = self.nominal_kg;
    }

    /// The payload mass the model carries (kg).
    pub fn mass(&self) -> f64 {
        self.mass
    }

    /// Whether the fit is still to come (the arm has not moved yet).
    pub fn pending(&self) -> bool {
        !self.decided
    }

    /// Whether the window is full.
    pub fn window_full(&self) -> bool {
        self.filled * self.n == self.tau.len()
    }

    /// No more fits (the reference moves).
    pub fn stop(&mut self) {
        self.decided = true;
    }

    /// Records one sample at rest: the pose `q` and the torque `tau` applied.
    pub fn record(&mut self, q: &[f64], tau: &[f64]) {
        let n = self.n;
        let w = self.tau.len() / n;
        let at = self.next * n;
        self.q[at..at + n].copy_from_slice(q);
        self.tau[at..at + n].copy_from_slice(tau);
        self.next = (self.next + 1) % w;
        self.filled = (self.filled + 1).min(w);
    }

    /// A full window at rest: fits it (and starts the next window), and on
    /// a trusted fit gives `model` the point mass (`true`); else the model
    /// stays as it is. Allocates nothing.
    pub fn decide(&mut self, model: &mut dyn JointSpaceDynamics) -> bool {
        let fit = self.fit(model);
        self.filled = 0;
        let Ok(fit) = fit else { return false };
        let Some(rd) = model.robot_dynamics_mut() else {
            return false;
        };
        self.saved = (rd.robot().payload().copied(), self.mass);
        if rd
            .robot_mut()
            .set_payload(Some(Payload::point_mass(fit.mass_kg)))
            .is_err()
        {
            return false;
        }
        self.mass = fit.mass_kg;
        true
    }

    /// The last trusted fit undone: the model's payload and the mass as
    /// before it (a step that failed after it).
    pub fn undo(&mut self, model: &mut dyn JointSpaceDynamics) {
        if let Some(rd) = model.robot_dynamics_mut() {
            // The payload was the model's own: it validates again.
            let _ = rd.robot_mut().set_payload(self.saved.0);
        }
        self.mass = self.saved.1;
    }

    fn fit(&mut self, model: &mut dyn JointSpaceDynamics) -> Result<MassFit, FitRefusal> {
        let n = self.n;
        let w = self.tau.len() / n;
        if self.filled < w {
            return Err(FitRefusal::NoData);
        }
        self.q_mean.fill(0.0);
        self.r.fill(0.0);
        for (q, t) in self.q.chunks_exact(n).zip(self.tau.chunks_exact(n)) {
            for i in 0..n {
                self.q_mean[i] += q[i] / w as f64;
                self.r[i] += t[i] / w as f64;
            }
        }
        self.gravity_column(model)?;
        fit_point_mass(&self.y, &self.r, &self.band, self.max_mass)
    }

    /// `r ← r − g_0(q̄)`, `y ← g_{1 kg}(q̄) − g_0(q̄)` on the model's robot
    /// (its payload restored).
    fn gravity_column(&mut self, model: &mut dyn JointSpaceDynamics) -> Result<(), FitRefusal> {
        let rd = model.robot_dynamics_mut().ok_or(FitRefusal::NoData)?;
        let saved = rd.robot().payload().copied();
        let mut eval = |payload: Option<Payload>, out: &mut [f64], sign: f64| {
            rd.robot_mut()
                .set_payload(payload)
                .map_err(|_| FitRefusal::NoData)?;
            let (robot, ws) = rd.parts();
            let g = gravity(robot, ws, &self.q_mean).map_err(|_| FitRefusal::NoData)?;
            for (o, gi) in out.iter_mut().zip(g.iter()) {
                *o += sign * gi;
            }
            Ok(())
        };
        self.y.fill(0.0);
        let bare = eval(None, &mut self.y, -1.0);
        for (r, y) in self.r.iter_mut().zip(&self.y) {
            *r += y;
        }
        let loaded = bare.and_then(|_| eval(Some(Payload::point_mass(1.0)), &mut self.y, 1.0));
        rd.robot_mut()
            .set_payload(saved)
            .map_err(|_| FitRefusal::NoData)?;
        loaded
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::RobotDynamics;
    use crate::robot::Robot;

    /// The weighted fit is the minimum of `Σ ((r_i − m y_i)/b_i)²` over
    /// `[0, max]`, found by brute force on a 1e-5 kg grid.
    #[test]
    fn the_fit_is_the_brute_force_minimum() {
        let y = [0.0, -7.2, -3.7, 0.14, -0.59, 0.0];
        let band = [5.0, 5.0, 3.0, 1.0, 1.0, 0.5];
        let noise = [0.3, -2.0, 1.5, 0.2, -0.4, 0.1];
        for m_true in [0.0, 0.4, 2.0, 6.0, 8.9] {
            let r: Vec<f64> = y.iter().zip(&noise).map(|(y, e)| m_true * y + e).collect();
            let fit = fit_point_mass(&y, &r, &band, 9.0).unwrap();
            let cost = |m: f64| -> f64 {
                let e = |i: usize| (r[i] - m * y[i]) / band[i];
                (0..6).map(|i| e(i) * e(i)).sum()
            };
            let best = (0..=900_000)
                .map(|k| k as f64 * 1e-5)
                .min_by(|a, b| cost(*a).total_cmp(&cost(*b)))
                .unwrap();
            assert!(
                (fit.mass_kg - best).abs() <= 1e-5,
                "{m_true}: {fit:?} vs {best}"
            );
            // σ_m = 1/√(3 Σ y²/b²).
            let yy: f64 = y.iter().zip(&band).map(|(y, b)| y * y / (b * b)).sum();
            assert!((fit.sigma_kg - 1.0 / (3.0 * yy).sqrt()).abs() < 1e-12);
        }
    }

    #[test]
    fn the_fit_refuses_what_it_cannot_trust() {
        let band = [1.0; 3];
        // No gravity load on the payload: unobservable, whatever the torque.
        let none = fit_point_mass(&[0.0; 3], &[1.0, 2.0, 3.0], &band, 9.0);
        assert!(
            matches!(none, Err(FitRefusal::Unobservable { sigma_kg }) if sigma_kg.is_infinite()),
            "{none:?}"
        );
        // A weak load: σ_m = 1/√(3·0.02²·2) = 20 kg > 0.9 kg.
        let weak = fit_point_mass(&[0.02, 0.02, 0.0], &[0.1, 0.1, 0.0], &band, 9.0);
        assert!(
            matches!(weak, Err(FitRefusal::Unobservable { .. })),
            "{weak:?}"
        );
        let y = [5.0, 4.0, 0.0];
        // 20 kg against a 9 kg bound, and −3 kg.
        let heavy = fit_point_mass(&y, &[100.0, 80.0, 0.0], &band, 9.0);
        assert!(
            matches!(heavy, Err(FitRefusal::Unphysical { .. })),
            "{heavy:?}"
        );
        let negative = fit_point_mass(&y, &[-15.0, -12.0, 0.0], &band, 9.0);
        assert!(
            matches!(negative, Err(FitRefusal::Unphysical { .. })),
            "{negative:?}"
        );
        // Just above the bound (within 3 σ): clipped to it.
        let clipped = fit_point_mass(&y, &[46.0, 36.8, 0.0], &band, 9.0).unwrap();
        assert_eq!(clipped.mass_kg, 9.0);
        // 4 N·m on a joint the payload does not load: not a point mass.
        let odd = fit_point_mass(&y, &[10.0, 8.0, 4.0], &band, 9.0);
        assert!(
            matches!(odd, Err(FitRefusal::Inconsistent { joint: 2, .. })),
            "{odd:?}"
        );
    }

    /// The torques that hold the IRB 140 at a pose with a known point mass,
    /// recorded over the window at rest.
    fn held(robot: &Robot, q: &[f64], mass: f64, ri: &mut RestIdentification, samples: usize) {
        let mut plant = robot.clone();
        plant.set_payload(Some(Payload::point_mass(mass))).unwrap();
        let mut ws = crate::dynamics::Workspace::new(&plant);
        let tau = gravity(&plant, &mut ws, q).unwrap().as_slice().to_vec();
        for _ in 0..samples {
            ri.record(q, &tau);
        }
    }

    #[test]
    fn a_known_mass_at_a_known_pose_is_recovered_and_given_to_the_model() {
        let robot = Robot::irb140();
        let q = [-0.27, 1.53, -0.93, -0.46, -0.66, 0.37];
        let w = (WINDOW_S / 0.01).round() as usize;
        for mass in [0.0, 2.0, 6.0] {
            let mut ri = RestIdentification::new(6, 0.01, 9.0, 0.0);
            ri.set_coulomb(&[4.0, 4.0, 2.4, 0.8, 0.8, 0.4]);
            let mut model = RobotDynamics::new(robot.clone());
            held(&robot, &q, mass, &mut ri, w - 1);
            // One sample short of the window: nothing fitted yet.
            assert!(!ri.window_full());
            held(&robot, &q, mass, &mut ri, 1);
            assert!(ri.window_full());
            assert!(ri.decide(&mut model));
            assert!((ri.mass() - mass).abs() < 1e-9, "{mass}: {}", ri.mass());
            let carried = model.robot().payload().unwrap().mass;
            assert!((carried - mass).abs() < 1e-9);
            // The window starts again after a fit.
            assert!(!ri.window_full());
            // Undone (a step that failed after it): the nominal model again.
            ri.undo(&mut model);
            assert_eq!(model.robot().payload(), None);
            assert_eq!(ri.mass(), 0.0);
        }
    }

    #[test]
    fn an_unobservable_pose_keeps_the_nominal_model() {
        // Without gravity no pose loads the payload: the fit refuses, the
        // model keeps its nominal 3 kg.
        let mut robot = Robot::irb140();
        robot.set_gravity(nalgebra::Vector3::zeros());
        let nominal = Payload::point_mass(3.0);
        let mut model_robot = robot.clone();
        model_robot.set_payload(Some(nominal)).unwrap();
        let mut model = RobotDynamics::new(model_robot);
        let mut ri = RestIdentification::new(6, 0.01, 9.0, 3.0);
        let q = [0.0, 0.5, -0.3, 0.0, 0.4, 0.0];
        held(&robot, &q, 6.0, &mut ri, 20);
        assert!(!ri.decide(&mut model));
        assert_eq!(ri.mass(), 3.0);
        assert_eq!(model.robot().payload(), Some(&nominal));
        let mut ri = RestIdentification::new(6, 0.01, 9.0, 3.0);
        assert_eq!(ri.fit(&mut model), Err(FitRefusal::NoData));
    }
}
