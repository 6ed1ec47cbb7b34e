//! Tuning of the predictive controllers: sampling period, horizon and the
//! square-root weights `Q` of the cost functions (30), (33) and (43).

use serde::{Deserialize, Serialize};

use crate::control::command::OutputMode;
use crate::control::kind::ControllerKind;

/// Largest prediction horizon accepted by [`MpcSettings::validate`].
pub const MAX_HORIZON: usize = 1000;

/// Largest accepted number of entries of the dense least-squares system
/// (rows·(cols + 1)), 64 Mi `f64` = 512 MiB.
pub const MAX_SYSTEM_ENTRIES: usize = 1 << 26;

/// A square-root weight `Q` of the cost (the cost uses `QᵀQ`, Eq. (31)).
///
/// Either a scalar `s` meaning `s·I` for any number of joints, or a per-joint
/// diagonal `diag(q_1, …, q_n)`. In TOML/JSON: a number (`q_yw = 1.0`) or an
/// array (`q_yw = [1.0, 1.0, 2.0, 1.0, 1.0, 1.0]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Weight {
    /// `s·I`, any number of joints.
    Scalar(f64),
    /// `diag(q_1, …, q_n)`, one entry per joint.
    Diagonal(Vec<f64>),
}

impl Weight {
    /// Entry `i` of the diagonal (the scalar for every `i` in the scalar case).
    /// Returns `None` for a diagonal shorter than `i + 1`.
    pub fn get(&self, i: usize) -> Option<f64> {
        match self {
            Weight::Scalar(s) => Some(*s),
            Weight::Diagonal(d) => d.get(i).copied(),
        }
    }

    /// Checks the entries (finite, `≥ 0`, or `> 0` when `positive`) and, for a
    /// diagonal, its length when `dof` is given.
    fn check(
        &self,
        name: &'static str,
        positive: bool,
        dof: Option<usize>,
    ) -> Result<(), SettingsError> {
        let entries: &[f64] = match self {
            Weight::Scalar(s) => std::slice::from_ref(s),
            Weight::Diagonal(d) => {
                if d.is_empty() {
                    return Err(SettingsError::EmptyWeight { name });
                }
                if let Some(n) = dof {
                    if d.len() != n {
                        return Err(SettingsError::WeightLength {
                            name,
                            expected: n,
                            got: d.len(),
                        });
                    }
                }
                d
            }
        };
        for (index, &value) in entries.iter().enumerate() {
            let bad = !value.is_finite() || value < 0.0 || (positive && value == 0.0);
            if bad {
                return Err(SettingsError::BadWeight {
                    name,
                    index,
                    value,
                    requirement: if positive {
                        "finite and > 0 (it keeps the least-squares system of full column rank)"
                    } else {
                        "finite and >= 0"
                    },
                });
            }
        }
        Ok(())
    }

    /// Writes the diagonal for `n` joints into `out` (length `n`).
    pub(crate) fn fill(&self, out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.get(i).unwrap_or(0.0);
        }
    }
}

/// How a controller solves its least-squares problem each sample. Serde
/// names: `"dense-qr"`, `"structured"`, `"auto"`. Both solvers return the
/// same `ΔU` (to rounding); they differ in cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Solver {
    /// The paper's dense system `𝒜 ΔU = b` (Eq. (40)–(42)) by Householder QR:
    /// `O((N·n)³)` flops per sample. The reference.
    DenseQr,
    /// The same problem as a stage-wise LQ problem solved by a square-root
    /// (Householder QR) Riccati recursion: `O(N·n³)` flops per sample.
    Structured,
    /// The faster of the two for the controller and horizon (the default):
    /// the dense QR for `N <` [`structured_from_horizon`], the structured
    /// solver from there on (the crossovers measured by `cargo bench --bench
    /// control` on the IRB 140).
    #[default]
    Auto,
}

/// Smallest horizon for which [`Solver::Auto`] picks the structured solver
/// for the second algorithm, the largest of the three crossovers (see
/// [`structured_from_horizon`]); [`Solver::for_horizon`] uses it when the
/// controller is not known.
pub const STRUCTURED_FROM_HORIZON: usize = 24;

/// Smallest horizon for which [`Solver::Auto`] picks the structured solver
/// for the controller `kind` (its base algorithm): where the two solvers'
/// step times cross on the IRB 140 (criterion medians, `OFMPC_BENCH_HORIZONS=
/// 15,17,19,20,21,23,25 cargo bench --bench control -- step_irb140/`): usual
/// ≈ 16 (26.7 µs each at 15), first ≈ 20 (50.2 / 50.6 µs at 19), second ≈ 24
/// (79.6 / 81.1 µs at 23). The incremental algorithms' dense system is halved
/// by their tracking rows' reduction, their stage-wise state is 3n or 4n
/// against the usual's 2n: hence the later crossovers.
pub fn structured_from_horizon(kind: ControllerKind) -> usize {
    match kind.base() {
        ControllerKind::Usual => 16,
        ControllerKind::First => 20,
        _ => STRUCTURED_FROM_HORIZON,
    }
}

impl Solver {
    /// The serde name (`"dense-qr"`, `"structured"` or `"auto"`).
    pub fn name(self) -> &'static str {
        match self {
            Solver::DenseQr => "dense-qr",
            Solver::Structured => "structured",
            Solver::Auto => "auto",
        }
    }

    /// The solver used at `horizon` when the controller is not known:
    /// [`Solver::Auto`] resolved with [`STRUCTURED_FROM_HORIZON`] (the dense
    /// QR wherever some controller would use it), the others unchanged.
    pub fn for_horizon(self, horizon: usize) -> Solver {
        match self {
            Solver::Auto if horizon < STRUCTURED_FROM_HORIZON => Solver::DenseQr,
            Solver::Auto => Solver::Structured,
            other => other,
        }
    }

    /// The solver controller `kind` uses at `horizon`: [`Solver::Auto`]
    /// resolved with [`structured_from_horizon`], the others unchanged.
    pub fn for_controller(self, kind: ControllerKind, horizon: usize) -> Solver {
        match self {
            Solver::Auto if horizon < structured_from_horizon(kind) => Solver::DenseQr,
            Solver::Auto => Solver::Structured,
            other => other,
        }
    }
}

/// Default bandwidth of the PID baseline (rad/s): the reference
/// tuning, stable over 0–6 kg on the IRB 140 at Ts = 10 ms.
pub const DEFAULT_PID_BANDWIDTH: f64 = 60.0;
/// Default bandwidth of the computed-torque baselines (rad/s).
pub const DEFAULT_CTC_BANDWIDTH: f64 = 150.0;
/// Default bandwidth of the disturbance observer of the MPC baseline (rad/s).
pub const DEFAULT_DOB_OBSERVER_BANDWIDTH: f64 = 100.0;

/// Tuning of the baselines: one bandwidth each (rad/s), a number for every
/// joint or one per joint. The PID and computed-torque error dynamics get a
/// discrete triple pole at `e^(−ωn·Ts)` (`crate::control::baselines::baseline`); the disturbance
/// observer of the MPC baseline a pole at `e^(−ω_o·Ts)`.
///
/// Its own settings type, given beside the [`MpcSettings`] where a baseline
/// is built (`PidController::new`, `CtcController::new`,
/// `DobMpc::new`, [`crate::control::AdaptiveMpc::new`],
/// [`crate::control::new_controller_with_baselines`],
/// [`crate::control::ControllerBuilder::baselines`]); the predictive controllers of
/// the paper do not read it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BaselineSettings {
    /// `ωn` of the PID baseline (default `DEFAULT_PID_BANDWIDTH`).
    pub pid_bandwidth: Weight,
    /// `ωn` of the computed-torque baselines, `ctc` and `ctc-adaptive`
    /// (default [`DEFAULT_CTC_BANDWIDTH`]).
    pub ctc_bandwidth: Weight,
    /// `ω_o` of the disturbance observer of `dob-mpc` (default
    /// `DEFAULT_DOB_OBSERVER_BANDWIDTH`).
    pub dob_observer_bandwidth: Weight,
    /// The factor (`≥ 1`) on the computed-torque baselines' `kp` on a joint
    /// that holds on the friction's stiff damper (`ctc`, `ctc-adaptive`;
    /// `control/dead_zone.rs`, `creeps_at_rest`: with
    /// `friction_compensation`, a Coulomb estimate, a resting reference,
    /// `|q̇| < 3 v_s`). Against the damper `b` the PID loop
    /// `b s² + M kp s + M ki = 0` is damped by `M kp / (2 √(M ki b))`: the
    /// factor raises that damping in proportion. Default 1: unchanged.
    pub ctc_hold_gain_scale: Weight,
    /// The factor (`≥ 1`) by which `dob-mpc` is stiffer on a joint that
    /// holds on the friction's stiff damper (the same condition): its inner
    /// usual MPC's `q_u` ÷ the factor and its observer's bandwidth × the
    /// factor. Default 1: unchanged.
    pub dob_hold_gain_scale: Weight,
    /// `dob-mpc` identifies its payload at rest before the path: the torque
    /// it holds the arm with over the rest is fitted by a point mass at the
    /// flange, bounded to `[0, MpcSettings::max_payload_kg]` (which must then
    /// be `> 0`) and gated on the fit's conditioning and residual against the
    /// drives' friction band; a trusted fit becomes the model's payload
    /// (`control/baselines/rest_identification.rs`). Only with a torque
    /// output. Default off: unchanged.
    pub dob_identify_at_rest: bool,
}

impl Default for BaselineSettings {
    fn default() -> Self {
        Self {
            pid_bandwidth: Weight::Scalar(DEFAULT_PID_BANDWIDTH),
            ctc_bandwidth: Weight::Scalar(DEFAULT_CTC_BANDWIDTH),
            dob_observer_bandwidth: Weight::Scalar(DEFAULT_DOB_OBSERVER_BANDWIDTH),
            ctc_hold_gain_scale: Weight::Scalar(1.0),
            dob_hold_gain_scale: Weight::Scalar(1.0),
            dob_identify_at_rest: false,
        }
    }
}

impl BaselineSettings {
    /// Checks every bandwidth: finite and `> 0`, one per joint for a diagonal.
    pub fn validate_for_dof(&self, n: usize) -> Result<(), SettingsError> {
        for (name, w) in [
            ("pid_bandwidth", &self.pid_bandwidth),
            ("ctc_bandwidth", &self.ctc_bandwidth),
            ("dob_observer_bandwidth", &self.dob_observer_bandwidth),
        ] {
            bandwidths(name, w, n)?;
        }
        for (name, w) in [
            ("ctc_hold_gain_scale", &self.ctc_hold_gain_scale),
            ("dob_hold_gain_scale", &self.dob_hold_gain_scale),
        ] {
            hold_gain_scales(name, w, n)?;
        }
        Ok(())
    }
}

/// The per-joint factors of a baseline's stiffer hold (`name`, e.g.
/// `ctc_hold_gain_scale`) for `n` joints, checked: finite and `≥ 1`, one per
/// joint for a diagonal; `None` when every one is 1 (nothing to gate).
pub(crate) fn hold_gain_scales(
    name: &'static str,
    w: &Weight,
    n: usize,
) -> Result<Option<Vec<f64>>, SettingsError> {
    if let Weight::Diagonal(d) = w {
        if d.len() != n {
            return Err(SettingsError::WeightLength {
                name,
                expected: n,
                got: d.len(),
            });
        }
    }
    let scale: Vec<f64> = (0..n).map(|i| w.get(i).unwrap_or(1.0)).collect();
    if let Some((index, &value)) = scale
        .iter()
        .enumerate()
        .find(|(_, v)| !(v.is_finite() && **v >= 1.0))
    {
        return Err(SettingsError::HoldGainScale { name, index, value });
    }
    Ok(scale.iter().any(|&f| f != 1.0).then_some(scale))
}

/// The per-joint bandwidths of `w` (setting `name`) for `n` joints, checked:
/// finite and `> 0`, one per joint for a diagonal.
pub fn bandwidths(name: &'static str, w: &Weight, n: usize) -> Result<Vec<f64>, SettingsError> {
    if let Weight::Diagonal(d) = w {
        if d.len() != n {
            return Err(SettingsError::WeightLength {
                name,
                expected: n,
                got: d.len(),
            });
        }
    }
    let out: Vec<f64> = (0..n).map(|i| w.get(i).unwrap_or(f64::NAN)).collect();
    if let Some(index) = out.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(SettingsError::BadBandwidth {
            name,
            index,
            value: out[index],
        });
    }
    Ok(out)
}

/// Settings shared by every controller (a baseline also takes its
/// bandwidth from [`BaselineSettings`], given beside these where it is
/// built). Defaults are the paper's tuning
/// (Section IV): `Ts = 0.01 s`, `N = 10`, `Q_yw = I`, `Q_Δy = 0.5 I`,
/// `Q_Δu = 1e-5 I`, and for the usual controller (43) `Q_u = 1e-4 I`.
///
/// All `Q` are square roots: the cost uses `QᵀQ` (Eq. (31)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MpcSettings {
    /// Sampling period `Ts` in seconds (default 0.01).
    pub ts: f64,
    /// Prediction horizon `N` in samples (default 10).
    pub horizon: usize,
    /// Output-error weight `Q_yw` of Eq. (30), (33) and (43) (default `1·I`).
    pub q_yw: Weight,
    /// Output-increment weight `Q_Δy` of Eq. (30) and (33) (default `0.5·I`).
    pub q_dy: Weight,
    /// Input-increment weight `Q_Δu` of Eq. (30) and (33) (default `1e-5·I`).
    pub q_du: Weight,
    /// Input weight `Q_u` of the usual controller, Eq. (43) (default `1e-4·I`).
    pub q_u: Weight,
    /// Least-squares solver (default [`Solver::Auto`]: the dense QR below
    /// the controller's crossover, [`structured_from_horizon`] — N = 16 for
    /// the usual controller, 20 for the first algorithm, 24 for the second —
    /// the structured solver from there on; both give the same `ΔU`).
    pub solver: Solver,
    /// The payload the controllers' model assumes, a point mass at the
    /// flange centre (kg, default 0: the paper's model knows no payload).
    /// Robust tuning over a payload range centres the model inside it.
    pub model_payload_kg: f64,
    /// Respect the drives' torque limits `|τ_i| ≤ τmax_i` over the whole
    /// horizon as constraints of the optimization (`crate::control::solvers::constrained`);
    /// the limits come from the controller's [`crate::control::DriveModel`]. Default off.
    /// With the dense solver the QP is built from the dense system's QR
    /// factor; with the structured one, on the steps whose plan passes a
    /// limit, from the condensed problem of the first `constraint_horizon`
    /// inputs (the rest of the horizon optimized out exactly by the
    /// recursion's cost-to-go): keep `constraint_horizon` short at long
    /// horizons.
    pub torque_limits: bool,
    /// With `torque_limits`: constrain (and check) only the first `N_c`
    /// torques of the horizon, `1 ≤ N_c ≤ N`; `None` (default): all `N`.
    /// The tail of an unconstrained plan often passes a limit that the
    /// applied torques never reach (its last inputs only serve the last
    /// predicted errors, and the frozen model is least accurate there):
    /// measured on the paper's path with joint 1 limited 0.4 % below its
    /// peak, the second algorithm's QP was active on ≈ 440 of 1364 steps with
    /// `N_c = N`, and its RMS error 4.4× that without limits; with `N_c = 5`,
    /// 1.0×. With limits that bind hard, the full horizon foresees more
    /// (see the README's table).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constraint_horizon: Option<usize>,
    /// Time budget of one step in µs (`None`, default: no budget). With
    /// torque limits, the QP checks the budget before each of its
    /// active-set iterations (at most `4·N·n` of them) and, when it is
    /// spent, returns its best feasible answer so far
    /// ([`crate::control::FallbackLevel::BestFeasible`]): a step exceeds the
    /// budget by at most one QP iteration's cost. Counted per step in
    /// [`crate::control::StepTelemetry`]. Finite and `≥ 0`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step_budget_us: Option<f64>,
    /// Use the drives' friction estimates (Coulomb, viscous) of the
    /// [`crate::control::DriveModel`]: the estimated friction at the reference's
    /// velocity is added to the torque (`τ = H u + g + F̂(v_ref)`). With it,
    /// the second algorithm restarts its aggregated error from the current
    /// error (`ē_k = w_k − y_k`) on a joint whose reference rests over the
    /// whole horizon, which removes its stick–slip hunting in a hold (the
    /// incremental input keeps the hold offset-free). Default off.
    pub friction_compensation: bool,
    /// Predict the state forward over the measurement delay with the model
    /// and the observer's disturbance estimate before optimizing (implies
    /// `state_observer`). Default off.
    pub delay_compensation: bool,
    /// Estimate the state with a [`crate::control::StateObserver`] (position,
    /// velocity, disturbance) from the measured positions instead of using
    /// the measured state directly. Default off; on whenever
    /// `delay_compensation` is.
    pub state_observer: bool,
    /// The state observer's model carries the drives' friction estimates
    /// (Coulomb, viscous, of the [`crate::control::DriveModel`]; the Coulomb part
    /// stick-aware: the torque that stops the joint within the step, bounded
    /// by `±F̂_c`) instead of leaving all of the friction to its disturbance
    /// estimate, which cannot follow a sign change of the friction within a
    /// sample. Only with an observer (`state_observer` or
    /// `delay_compensation`). Default off. Estimates above the true friction
    /// make it worse (the observer then predicts a stick where the joint
    /// slides): see the README's drives section.
    pub observer_friction: bool,
    /// Upper bound of the payload mass an adaptive controller identifies
    /// (kg; a multiple of the arm's rated payload, e.g. 1.5 × 6 kg for the
    /// IRB 140). `0` (default): no bound beyond the estimator's own. Read by
    /// the real-arm identification (`RealArmIdentification`).
    pub max_payload_kg: f64,
    /// Counts per revolution of the joint encoders the measurement comes
    /// from (e.g. 1048576 for 20 bits). When given (`> 0`), the integrating
    /// action of the offset-free controllers is held on a joint whose
    /// reference rests and whose error is within one count
    /// (`control/dead_zone.rs`): they settle instead of hunting under friction
    /// and quantization. `0` (default): no dead zone.
    pub encoder_counts: f64,
    /// The observer's friction model (`observer_friction`) as the drives'
    /// law is near rest: a smoothed Coulomb friction `F_v v + F_c tanh(v/v_s)`
    /// does not stick, it creeps (a stiff damper of slope `F_v + F_c/v_s`),
    /// and the observer integrates it implicitly over each sample
    /// (`control/mpc/creep.rs`) instead of the stick-aware clamp, so that its
    /// prediction over the measurement delay follows the creep. Only with
    /// `observer_friction`. Default off.
    pub friction_creep: bool,
    /// Bound on the distance of an identified payload's centre of mass from
    /// the flange (m) for the adaptive kinds on a real arm (and, with it, the
    /// model's payload moves to the estimate with the time constant
    /// `RealArmIdentification::model_time_s`,
    /// 0.5 s, instead of within a few samples):
    /// the first moment identified from delayed, quantized data is noise while
    /// the mass is small, and `h/m` then puts the mass metres away.
    /// A bound (`> 0`) also selects the real arm's identification when no
    /// other real-arm setting does (a plant whose links are not the model's
    /// makes the ideal plant's identification diverge).
    /// `0` (default): no bound, the model rate of the ideal plant.
    pub payload_com_max_m: f64,
    /// What the controller's output drives ([`OutputMode`], default
    /// torque): for an interface that closes its own joint loop, the state
    /// its model predicted [`Self::output_lead_s`] ahead
    /// ([`StepOutput::q_command`](crate::control::StepOutput::q_command)).
    #[serde(skip_serializing_if = "OutputMode::is_default")]
    pub output: OutputMode,
    /// How far ahead the position/velocity command is taken from the
    /// prediction (s, from 0 to `(N − 1)·Ts`): the interface's lag and
    /// smoothing. `None` (default): the simulated interface's own
    /// (`[plant.servo]`), else 0. Only with a position or velocity output.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output_lead_s: Option<f64>,
    /// The time constant `T` (s, ≥ 0) of a first-order smoothing the
    /// interface applies to the command (UR's `lookahead_time`), which the
    /// command pre-compensates: `q + T q̇`, `q̇ + T q̈`, `q̈ + T q⃛` instead of
    /// `q`, `q̇`, `q̈` one lead time ahead (`control/command.rs`), so that the
    /// smoothed setpoint is the predicted one and [`Self::output_lead_s`]
    /// covers the interface's lag alone. `None` (default): the simulated
    /// interface's own when its lead is also left to it (`[plant.servo]`),
    /// else 0 (none). Only with a position or velocity output.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output_smoothing_s: Option<f64>,
    /// The interface's cycle (s; UR's 2 ms at 500 Hz): with
    /// [`Self::output_smoothing_s`], the controller models the interface's
    /// stream — the command extrapolated along its `q̇`, `q̈` at each cycle
    /// of the period and smoothed every [`Self::output_smoothing_step_s`] —
    /// and keeps its own copy of the smoothed setpoint: the command is the
    /// smoothing's exact discrete inverse of the plan, corrected by what
    /// the copy lags behind the plan (`control/command.rs`). A whole
    /// divisor of `Ts`. `None` (default): the simulated interface's own
    /// when its lead and smoothing are also left to it (`[plant.servo]`
    /// with a smoothing), else no stream model (`q + T q̇` alone).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output_cycle_s: Option<f64>,
    /// The step (s) at which the interface runs its smoothing filter `f +=
    /// β (s − f)`, a whole divisor of [`Self::output_cycle_s`]; `None`: the
    /// simulated interface's integration substep when the cycle is its too,
    /// else the cycle. Only with [`Self::output_cycle_s`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output_smoothing_step_s: Option<f64>,
    /// The factor (in `(0, 1]`, one for every joint or one per joint) on the
    /// input-increment weight `q_du` of the incremental algorithms on a joint
    /// whose reference rests over the horizon: a stiffer hold. Near rest the
    /// smoothed Coulomb friction `F_c tanh(v/v_s)` is a stiff damper
    /// `b = F_c/v_s` (500–1000 N·m·s/rad on the wrist of the real-arm preset)
    /// against which the light wrist joints' gains, tuned for their inertia
    /// `M`, are far too soft: the loop `b s² + M k_p s + M k_i = 0` is damped
    /// by `M k_p / (2 √(M k_i b))`, about 0.1, and the hold rings at about
    /// 1 Hz by 4–13 encoder counts. The damper also keeps the stiffer hold
    /// stable through the delay, so the factor applies only where it is:
    /// with `friction_compensation`, on a joint with a Coulomb estimate, while
    /// `|q̇| < 3 v_s`. While the reference moves nothing changes. Both
    /// solvers (the structured one reads the sample's weight in its stage
    /// rows). The factor is a ratio of two `q_du`s and does not scale with
    /// `ts` (`q_du` does: the cost weighs increments against errors by
    /// `q_du²·Ts²`); measured, 0.01 at 10 ms and 0.1 at 1 ms with two samples
    /// of delay (docs/guide/real-arm.md). `1` (default): unchanged.
    pub hold_q_du_scale: Weight,
    /// Hand out the first stage's feedback gain with every step
    /// ([`StepOutput::gain`](crate::control::StepOutput::gain),
    /// `tau_ff`, `x_lin`), for a faster linear feedback between MPC samples
    /// (default off: nothing computed). Structured solver, a predictive
    /// kind, no torque limits and no observer only: else the build refuses.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub gains: bool,
    /// The adaptive kinds on a real arm also learn while the reference
    /// rests, from the joints that slide
    /// (`RealArmIdentification::min_joint_speed`, 0.02 rad/s, as on the
    /// path), not only while it moves. A settled hold never reaches that
    /// speed, so nothing is learnt from quantization, noise or stiction; an
    /// unknown heavy payload that sets the arm swinging before the path
    /// (three samples of delay on a light arm) is identified from that
    /// motion before the path starts. Default off: only while the reference
    /// moves.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub identify_at_rest: bool,
    /// The adaptive kinds on a real arm: the model carries the identified
    /// payload only after this many samples were learnt from (and the
    /// mass's standard deviation is below 0.5 kg). `0` (default): the
    /// library's 100 (1 s at 10 ms). Fewer let a heavy unknown payload
    /// reach the model before the loop it destabilizes swings far.
    #[serde(skip_serializing_if = "is_zero_u64")]
    pub identification_min_samples: u64,
    /// The adaptive kinds on a real arm: the model's point mass is the
    /// least-squares estimate's own (its mass clipped to
    /// `[0, max_payload_kg]`, its first moments), not the estimate projected
    /// onto the physically consistent set. The projection (`J ⪰ 0`) raises
    /// the mass to carry the noisy, weakly excited inertia entries: on the
    /// test arm at 0 kg the model carried 0.3 kg of nothing (the raw mass
    /// 0.03 kg), while under a payload the two agree. Default off.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub identification_raw_mass: bool,
    /// With `friction_creep`: the observer solves the creeping friction of
    /// all joints together through the whole inertia matrix,
    /// `H (x − s)/Ts + F(x) = 0`, instead of each joint through its diagonal
    /// `H_ii`. The plant's friction acts through `H⁻¹`: under a payload
    /// heavy for the arm, joints with parallel axes are coupled and the
    /// diagonal step mispredicts the creep over the delay (on the test arm
    /// with three samples of delay the hold then cycles by thousands of
    /// counts at 2.5 kg). Default off: joint by joint.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub friction_coupled: bool,
    /// The second algorithm (and its adaptive variant) with
    /// `friction_compensation`: on a joint whose reference rests over the
    /// horizon the aggregated error restarts as `ē_k = s·(w_k − y_k)` with
    /// this factor `s` in `[0, 1]` instead of carrying the past sum
    /// (`control/mpc/second.rs`). The restart at `s = 1` still puts the
    /// current error into the tracking rows a second time: at rest the
    /// second algorithm pushes twice as hard as the first on the same error,
    /// which through three samples of delay and the wrist's creeping friction
    /// cycles by hundreds of encoder counts. `0`: at rest the second
    /// algorithm is the first (its input increment keeps the hold
    /// offset-free; ramps are unaffected, the reference moves there). `1`
    /// (default): unchanged.
    #[serde(skip_serializing_if = "is_one")]
    pub hold_ebar_scale: f64,
    /// The hold dead zone's half-width in encoder counts (with
    /// `encoder_counts > 0`), one value for every joint or one per joint,
    /// each finite and `> 0`: the incremental algorithms and the PID/CTC
    /// baselines hold their integrating action on a resting joint whose
    /// error is within it (`control/dead_zone.rs`; `dob-mpc` keeps one
    /// count), e.g. wider on the wrist, whose counts move the flange little
    /// (on the test arm it did not settle the creeping wrist's hold:
    /// docs/guide/real-arm.md). `1` (default): one count, unchanged.
    #[serde(skip_serializing_if = "weight_is_one")]
    pub dead_zone_counts: Weight,
}

fn is_zero_u64(v: &u64) -> bool {
    *v == 0
}

fn is_one(v: &f64) -> bool {
    *v == 1.0
}

fn weight_is_one(w: &Weight) -> bool {
    *w == Weight::Scalar(1.0)
}

impl Default for MpcSettings {
    fn default() -> Self {
        Self {
            ts: 0.01,
            horizon: 10,
            q_yw: Weight::Scalar(1.0),
            q_dy: Weight::Scalar(0.5),
            q_du: Weight::Scalar(1e-5),
            q_u: Weight::Scalar(1e-4),
            solver: Solver::default(),
            model_payload_kg: 0.0,
            torque_limits: false,
            constraint_horizon: None,
            step_budget_us: None,
            friction_compensation: false,
            delay_compensation: false,
            state_observer: false,
            observer_friction: false,
            max_payload_kg: 0.0,
            encoder_counts: 0.0,
            friction_creep: false,
            payload_com_max_m: 0.0,
            output: OutputMode::Torque,
            output_lead_s: None,
            output_smoothing_s: None,
            output_cycle_s: None,
            output_smoothing_step_s: None,
            hold_q_du_scale: Weight::Scalar(1.0),
            gains: false,
            identify_at_rest: false,
            identification_min_samples: 0,
            identification_raw_mass: false,
            friction_coupled: false,
            hold_ebar_scale: 1.0,
            dead_zone_counts: Weight::Scalar(1.0),
        }
    }
}

impl MpcSettings {
    /// Checks the settings independently of the number of joints: `ts` finite
    /// and `> 0`, `1 ≤ horizon ≤` [`MAX_HORIZON`], weights finite and `≥ 0`,
    /// `q_du` and `q_u` `> 0`, diagonals non-empty and of one common length.
    pub fn validate(&self) -> Result<(), SettingsError> {
        self.check(None)
    }

    /// [`MpcSettings::validate`] plus: every diagonal weight has `dof` entries,
    /// and the dense least-squares system of the horizon fits in
    /// `MAX_SYSTEM_ENTRIES` when the dense solver is used (checked here,
    /// once, for the largest of the three controllers' systems: an
    /// incremental algorithm's, `2·N·n` rows and its tracking reduction),
    /// so that a setting that validates also builds.
    pub fn validate_for_dof(&self, dof: usize) -> Result<(), SettingsError> {
        if dof == 0 {
            return Err(SettingsError::ZeroDof);
        }
        self.check(Some(dof))?;
        if self.solver.for_horizon(self.horizon) == Solver::DenseQr {
            let p = self.horizon.saturating_mul(dof);
            let rows = p.saturating_mul(2);
            let entries = crate::control::solvers::tracking::dense_entries(dof, self.horizon, true);
            if !matches!(entries, Some(e) if e <= MAX_SYSTEM_ENTRIES) {
                return Err(SettingsError::TooLarge {
                    solver: Solver::DenseQr,
                    rows,
                    cols: p,
                    limit: MAX_SYSTEM_ENTRIES,
                });
            }
        } else if self.torque_limits {
            // The structured solver's condensed head (constrained.rs; the
            // second algorithm's state: 4n, of which 2n weighted).
            let nc = self.constraint_horizon.unwrap_or(self.horizon);
            let p = nc.saturating_mul(dof);
            let rows = p
                .saturating_add(nc.saturating_sub(1).saturating_mul(2 * dof))
                .saturating_add(4 * dof);
            if rows.saturating_mul(p + 1) > MAX_SYSTEM_ENTRIES {
                return Err(SettingsError::TooLarge {
                    solver: Solver::Structured,
                    rows,
                    cols: p,
                    limit: MAX_SYSTEM_ENTRIES,
                });
            }
        }
        Ok(())
    }

    fn check(&self, dof: Option<usize>) -> Result<(), SettingsError> {
        if !self.ts.is_finite() || self.ts <= 0.0 {
            return Err(SettingsError::BadSamplingPeriod(self.ts));
        }
        if !(self.model_payload_kg.is_finite() && self.model_payload_kg >= 0.0) {
            return Err(SettingsError::ModelPayload(self.model_payload_kg));
        }
        if !(self.max_payload_kg.is_finite() && self.max_payload_kg >= 0.0) {
            return Err(SettingsError::MaxPayload(self.max_payload_kg));
        }
        if !(self.encoder_counts.is_finite() && self.encoder_counts >= 0.0) {
            return Err(SettingsError::EncoderCounts(self.encoder_counts));
        }
        if !(self.payload_com_max_m.is_finite() && self.payload_com_max_m >= 0.0) {
            return Err(SettingsError::PayloadComBound(self.payload_com_max_m));
        }
        if self.identification_raw_mass && self.payload_com_max_m == 0.0 {
            return Err(SettingsError::RawMassWithoutComBound);
        }
        if let Some(b) = self
            .step_budget_us
            .filter(|b| !(b.is_finite() && *b >= 0.0))
        {
            return Err(SettingsError::StepBudget(b));
        }
        if !(0.0..=1.0).contains(&self.hold_ebar_scale) {
            return Err(SettingsError::HoldEbarScale(self.hold_ebar_scale));
        }
        let widths: &[f64] = match &self.dead_zone_counts {
            Weight::Scalar(v) => std::slice::from_ref(v),
            Weight::Diagonal(d) => d,
        };
        if let Some((index, &value)) = widths
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v > 0.0))
        {
            return Err(SettingsError::DeadZoneCounts { index, value });
        }
        let scales: &[f64] = match &self.hold_q_du_scale {
            Weight::Scalar(v) => std::slice::from_ref(v),
            Weight::Diagonal(d) => d,
        };
        if let Some((index, &value)) = scales
            .iter()
            .enumerate()
            .find(|(_, v)| !(**v > 0.0 && **v <= 1.0))
        {
            return Err(SettingsError::HoldQduScale { index, value });
        }
        if self.horizon == 0 || self.horizon > MAX_HORIZON {
            return Err(SettingsError::BadHorizon(self.horizon));
        }
        if let Some(nc) = self.constraint_horizon {
            if nc == 0 || nc > self.horizon {
                return Err(SettingsError::ConstraintHorizon {
                    value: nc,
                    horizon: self.horizon,
                });
            }
        }
        // Diagonals must agree among themselves even when n is not known yet.
        let mut common: Option<(&'static str, usize)> = None;
        for (name, w, positive) in [
            ("q_yw", &self.q_yw, false),
            ("q_dy", &self.q_dy, false),
            ("q_du", &self.q_du, true),
            ("q_u", &self.q_u, true),
            ("hold_q_du_scale", &self.hold_q_du_scale, true),
            ("dead_zone_counts", &self.dead_zone_counts, true),
        ] {
            w.check(name, positive, dof)?;
            if let Weight::Diagonal(d) = w {
                match common {
                    None => common = Some((name, d.len())),
                    Some((first, len)) if len != d.len() => {
                        return Err(SettingsError::InconsistentDiagonals {
                            first,
                            first_len: len,
                            second: name,
                            second_len: d.len(),
                        })
                    }
                    Some(_) => {}
                }
            }
        }
        Ok(())
    }
}

/// A setting that cannot be used, with what to change.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingsError {
    /// `ts` is not a finite positive number.
    #[error(
        "sampling period ts = {0} s is invalid: it must be finite and > 0 (the paper uses 0.01)"
    )]
    BadSamplingPeriod(f64),
    /// `horizon` is 0 or too large.
    #[error("prediction horizon {0} is invalid: it must be between 1 and {MAX_HORIZON} samples (the paper uses 10)")]
    BadHorizon(usize),
    /// The step budget is not a finite number of µs `≥ 0`.
    #[error("the step budget {0} µs is invalid: it must be a finite number of microseconds ≥ 0")]
    StepBudget(f64),
    /// The constraint horizon is 0 or longer than the prediction horizon.
    #[error("the constraint horizon is {value} samples: it must be between 1 and the prediction horizon ({horizon})")]
    ConstraintHorizon {
        /// The constraint horizon.
        value: usize,
        /// The prediction horizon.
        horizon: usize,
    },
    /// A weight entry is negative, zero where it must be positive, or not finite.
    #[error("weight {name}[{index}] = {value} is invalid: it must be {requirement}")]
    BadWeight {
        /// Setting name (`q_yw`, `q_dy`, `q_du`, `q_u`).
        name: &'static str,
        /// Index of the entry (0 for a scalar).
        index: usize,
        /// The offending value.
        value: f64,
        /// What the value must satisfy.
        requirement: &'static str,
    },
    /// A diagonal weight has no entry.
    #[error("weight {name} is an empty array: give a number (times I) or one entry per joint")]
    EmptyWeight {
        /// Setting name.
        name: &'static str,
    },
    /// A diagonal weight has the wrong number of entries.
    #[error("weight {name} has {got} entries but the robot has {expected} joints: give one entry per joint or a single number")]
    WeightLength {
        /// Setting name.
        name: &'static str,
        /// Number of joints.
        expected: usize,
        /// Number of entries given.
        got: usize,
    },
    /// Two diagonal weights have different lengths.
    #[error("weights {first} ({first_len} entries) and {second} ({second_len} entries) disagree on the number of joints")]
    InconsistentDiagonals {
        /// First diagonal weight.
        first: &'static str,
        /// Its length.
        first_len: usize,
        /// Second diagonal weight.
        second: &'static str,
        /// Its length.
        second_len: usize,
    },
    /// The drive model has another number of joints than the controller.
    #[error("the drive data give {got} values of the {what} but the robot has {expected} joints")]
    DriveModelLength {
        /// Which quantity.
        what: DriveQuantity,
        /// Joints.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// A drive-model value is out of range.
    #[error("the {what} of joint {} is {value}: limits must be > 0 (or infinite), friction finite and >= 0", index + 1)]
    DriveModelValue {
        /// Which quantity.
        what: DriveQuantity,
        /// 0-based joint.
        index: usize,
        /// The value.
        value: f64,
    },
    /// Torque limits or friction compensation are enabled but the controller
    /// was given no drive model, or cannot use one.
    #[error("the {0} controller does not support torque limits or friction compensation")]
    DrivesUnsupported(&'static str),
    /// A controller for zero joints was requested.
    #[error("the robot has 0 joints: a controller needs at least one")]
    ZeroDof,
    /// The least-squares system would be too large to allocate.
    #[error(
        "the least-squares system would have {rows} x {cols} entries, more than the limit of {limit}: {}",
        match solver {
            Solver::Structured => "reduce the horizon, or with torque limits the constraint horizon \
                (the structured solver's limited head grows with its square)",
            _ => "reduce the horizon, or use the structured solver (its size grows linearly with \
                the horizon)",
        }
    )]
    TooLarge {
        /// The solver whose system it is ([`Solver::DenseQr`] or [`Solver::Structured`]):
        /// the advice depends on it.
        solver: Solver,
        /// Rows of 𝒜 (dense solver) or of the stored stage factors
        /// (structured solver: N·n).
        rows: usize,
        /// Columns of 𝒜 (dense) or of a stage factor (structured).
        cols: usize,
        /// Largest accepted rows·cols.
        limit: usize,
    },
    /// The payload the model assumes is negative or not finite.
    #[error("the payload the model assumes is {0} kg: it must be a finite mass ≥ 0")]
    ModelPayload(f64),
    /// The payload mass bound is negative or not finite.
    #[error("the payload mass bound (mpc.max_payload_kg) is {0} kg: it must be finite and >= 0 (0: no bound)")]
    MaxPayload(f64),
    /// The encoder resolution is negative or not finite.
    #[error("the encoder resolution (mpc.encoder_counts) is {0} counts per revolution: it must be finite and >= 0 (0: no dead zone)")]
    EncoderCounts(f64),
    /// The bound on the payload's centre of mass is negative or not finite.
    #[error("the bound on the identified payload's centre of mass is {0} m: it must be finite and >= 0 (0: no bound)")]
    PayloadComBound(f64),
    /// The raw point mass without a bound on its centre of mass: a small
    /// raw mass with noisy first moments would put it far out (an inertia
    /// `|h|²/m` without limit).
    #[error("the identification's raw point mass (identification_raw_mass) needs a bound on the payload's centre of mass (payload_com_max_m > 0): a small raw mass with noisy first moments would lie far from the flange")]
    RawMassWithoutComBound,
    /// A factor of the input-increment weight at rest is not in `(0, 1]`.
    #[error("the factor of the input-increment weight at rest (hold_q_du_scale) is {value} at entry {index}: it must be within (0, 1] (1: unchanged)")]
    HoldQduScale {
        /// Entry (joint) of the setting.
        index: usize,
        /// The value given.
        value: f64,
    },
    /// The factor of the second algorithm's aggregated error at rest is not
    /// in `[0, 1]`.
    #[error("the factor of the second algorithm's aggregated error at rest (hold_ebar_scale) is {0}: it must be within [0, 1] (1: unchanged, 0: the first algorithm's hold)")]
    HoldEbarScale(f64),
    /// A half-width of the hold dead zone is not a finite number `> 0`.
    #[error("the hold dead zone's half-width (dead_zone_counts) is {value} encoder counts at entry {index}: it must be a finite number > 0 (1: one count)")]
    DeadZoneCounts {
        /// Entry (joint) of the setting.
        index: usize,
        /// The value given.
        value: f64,
    },
    /// A factor of a baseline's stiffer hold is not a finite number `≥ 1`.
    #[error("the factor of a baseline's stiffer hold ({name}) is {value} at entry {index}: it must be a finite number >= 1 (1: unchanged)")]
    HoldGainScale {
        /// The setting.
        name: &'static str,
        /// Entry (joint) of the setting.
        index: usize,
        /// The value given.
        value: f64,
    },
    /// A factor of the input-increment weight at rest other than 1 with the
    /// structured solver. No longer returned: the structured solver takes
    /// the factor (kept so that code matching on it still builds).
    #[error("the factor of the input-increment weight at rest (hold_q_du_scale) needs the dense solver: set solver = \"dense-qr\" or the factor to 1")]
    HoldQduScaleStructured,
    /// `dob-mpc`'s payload at rest without a mass bound.
    #[error("dob-mpc's payload identification at rest (dob_identify_at_rest) needs a bound on the payload mass: set max_payload_kg > 0 (e.g. 1.5 × the rated payload)")]
    IdentifyAtRestWithoutMassBound,
    /// A factor of `dob-mpc`'s stiffer hold other than 1 with the structured
    /// solver, which builds its weights once.
    #[error("the factor of dob-mpc's stiffer hold (dob_hold_gain_scale) needs the dense solver: set solver = \"dense-qr\" or the factor to 1")]
    HoldGainScaleStructured,
    /// An adaptive variant of the usual MPC was requested: it has none (no
    /// integrator to remove what the identification leaves).
    #[error("the usual MPC has no adaptive variant: use the first or the second algorithm")]
    NoAdaptiveVariant,
    /// A baseline's bandwidth is not a finite number `> 0`.
    #[error("bandwidth {name}[{index}] = {value} rad/s is invalid: it must be finite and > 0")]
    BadBandwidth {
        /// Setting name (`pid_bandwidth`, `ctc_bandwidth`, `dob_observer_bandwidth`).
        name: &'static str,
        /// Joint index (0 for a scalar).
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// The payload estimator's tuning cannot be used.
    #[error(transparent)]
    Estimator(#[from] crate::ident::RlsSettingsError),
}

/// Which quantity of a [`DriveModel`](crate::control::DriveModel) (in a [`SettingsError`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum DriveQuantity {
    /// Peak torque.
    MaxTorque,
    /// Coulomb friction.
    Coulomb,
    /// Viscous friction.
    Viscous,
    /// Velocity scale of the smoothed Coulomb friction.
    CoulombVelocity,
}

impl std::fmt::Display for DriveQuantity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            DriveQuantity::MaxTorque => "peak torque",
            DriveQuantity::Coulomb => "Coulomb friction estimate",
            DriveQuantity::Viscous => "viscous friction estimate",
            DriveQuantity::CoulombVelocity => "Coulomb friction velocity scale",
        })
    }
}
