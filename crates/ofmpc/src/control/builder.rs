//! A controller that works as configured, or a typed reason why not.
//!
//! [`ControllerBuilder`] gathers everything a controller needs — the kind,
//! the robot (from which the controller's own model is built), the tuning
//! ([`MpcSettings`]; a baseline's bandwidths, [`BaselineSettings`]), the
//! drives ([`DriveModel`]), the state observer and the payload estimator —
//! and [`ControllerBuilder::build`] checks that they fit together before
//! anything runs: a setting that would silently do nothing
//! (torque limits with no finite limit, friction compensation with no
//! friction estimate, …) is a [`BuildError`], never a quiet fallback.
//!
//! The built [`Controller`] owns its model of the robot (the nominal rigid-body
//! model, with the payload the tuning assumes; for the adaptive kinds the
//! copy whose payload it identifies), its drives and its observer, and runs
//! one sample per [`Controller::step`]:
//!
//! ```text
//! x̂_k = observer(x_k) (or x_k),   τ_k = H u_k + g (+ F̂(v_ref))   (Eq. (15))
//! ```
//!
//! with the algorithm's `u_k` (Eq. (32)/(37), (34)/(39) or (43)). The step
//! allocates nothing; its [`StepOutput`] is sized at build.
//!
//! ```
//! use ofmpc::control::{BuildError, ControllerKind, MpcSettings, StepInput};
//! use ofmpc::robot::Robot;
//! use ofmpc::ControllerBuilder;
//!
//! let robot = Robot::irb140();
//! let settings = MpcSettings { torque_limits: true, ..MpcSettings::default() };
//! // The drives come from the robot (its peak torques).
//! let mut mpc = ControllerBuilder::new(ControllerKind::Second, &robot)
//!     .settings(settings.clone())
//!     .build()?;
//! let x = vec![0.0; 12];
//! mpc.reset(&x)?;
//! let (w_k, preview) = (vec![0.0; 6], vec![0.0; 10 * 6]);
//! let out = mpc.step(&StepInput { x: &x, w_k: &w_k, preview: &preview })?;
//! assert_eq!(out.tau.len(), 6);
//! assert!(out.qp_status.is_some());
//!
//! // A robot whose drives have no finite peak torque: refused.
//! let unlimited = ofmpc::control::DriveModel {
//!     max_torque_nm: vec![f64::INFINITY; 6],
//!     ..ofmpc::control::DriveModel::from_robot(&robot)
//! };
//! let refused = ControllerBuilder::new(ControllerKind::Second, &robot)
//!     .settings(settings)
//!     .drives(unlimited)
//!     .build();
//! assert_eq!(refused.unwrap_err(), BuildError::NoTorqueLimits);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::time::{Duration, Instant};

use crate::control::adaptive::{AdaptiveMpc, RealArmIdentification};
use crate::control::algorithm::Algorithm;
use crate::control::command::{
    check_stream, lead_point, max_output_lead, OutputMode, PayloadFeedForward, Stream,
};
use crate::control::drive_model::DriveModel;
use crate::control::factory::new_controller_with_baselines;
use crate::control::kind::ControllerKind;
use crate::control::mpc::core::{check_finite, check_len};
use crate::control::observer::StateObserver;
use crate::control::settings::{BaselineSettings, MpcSettings, SettingsError, Solver};
use crate::control::step::{StepError, StepFailure, StepInfo, StepInput, StepOutput, StepStatus};
use crate::control::telemetry::{FallbackLevel, StepTelemetry};
use crate::dynamics::RobotDynamics;
use crate::ident::RlsSettings;
use crate::robot::{ModelError, Payload, Robot};

/// Default pole of the state observer's error dynamics (per sample), the
/// value measured best on the paper's path (22-bit encoder, one sample of
/// delay): see [`ObserverSettings`].
pub const DEFAULT_OBSERVER_POLE: f64 = 0.7;

/// Tuning of the state observer ([`StateObserver`]) a controller runs when
/// its settings ask for one ([`MpcSettings::state_observer`] or
/// [`MpcSettings::delay_compensation`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObserverSettings {
    /// The three poles `p` of the observer's error dynamics, in `(0, 1)`
    /// (default `DEFAULT_OBSERVER_POLE`).
    pub pole: f64,
    /// Age of the measurement in samples `D` (default 0). With
    /// [`MpcSettings::delay_compensation`] the observer predicts over it;
    /// without, the estimate is of the measured sample.
    pub measurement_delay: usize,
}

impl Default for ObserverSettings {
    fn default() -> Self {
        Self {
            pole: DEFAULT_OBSERVER_POLE,
            measurement_delay: 0,
        }
    }
}

/// What the drives' friction estimates were wanted for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrictionUse {
    /// The friction feed-forward of the torque ([`MpcSettings::friction_compensation`]).
    Compensation,
    /// The state observer's friction model ([`MpcSettings::observer_friction`]).
    Observer,
}

impl std::fmt::Display for FrictionUse {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FrictionUse::Compensation => "friction compensation",
            FrictionUse::Observer => "the observer's friction model",
        })
    }
}

/// Why a controller cannot be built as configured.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BuildError {
    /// The tuning does not fit the robot ([`MpcSettings::validate_for_dof`]),
    /// the drive model does not ([`DriveModel::validate`]), or the payload
    /// estimator's tuning is unusable.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The controller's model of the robot cannot carry the payload the
    /// tuning assumes.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Torque limits are on but no joint's drive has a finite peak torque:
    /// the limits would never bind.
    #[error("torque limits are on but no joint has a finite peak torque: give the drives' limits or turn the limits off")]
    NoTorqueLimits,
    /// Friction compensation, or the observer's friction model, is on but
    /// every friction estimate of the drives is zero: it would do nothing.
    #[error("{0} is on but the drives give no friction estimate (all Coulomb and viscous estimates are 0)")]
    NoFrictionEstimates(FrictionUse),
    /// The observer's friction model is on but the settings run no observer.
    #[error("the observer's friction model is on but no state observer runs: turn the observer (or delay compensation) on, or the friction model off")]
    ObserverFrictionWithoutObserver,
    /// Observer tuning was given but the settings run no observer.
    #[error("an observer tuning was given but no state observer runs: turn the observer (or delay compensation) on")]
    ObserverNotEnabled,
    /// Delay compensation is on but the measurement delay was not given.
    #[error("delay compensation is on but the measurement delay is not known: give the observer tuning with the delay in samples")]
    MeasurementDelayUnknown,
    /// The observer's pole is outside `(0, 1)`.
    #[error("the observer pole is {0}: it must lie in (0, 1)")]
    ObserverPole(f64),
    /// A drive model was given that no setting uses (no torque limits, no
    /// friction compensation, no observer friction model).
    #[error("a drive model was given but neither torque limits, friction compensation nor the observer's friction model is on: it would not be used")]
    DrivesUnused,
    /// A constraint horizon was given without torque limits.
    #[error("a constraint horizon of {0} samples was given but torque limits are off: it would not be used")]
    ConstraintHorizonWithoutLimits(usize),
    /// A payload estimator's tuning was given for a kind that identifies no
    /// payload.
    #[error(
        "the {0} controller identifies no payload: use an adaptive kind to run a payload estimator"
    )]
    EstimatorWithoutIdentification(ControllerKind),
    /// A baseline's bandwidths ([`BaselineSettings`]) were given for a kind
    /// that is not a baseline ([`ControllerKind::BASELINES`]): it reads none.
    #[error("the {0} controller is not a baseline and reads no baseline bandwidth: give the bandwidths only to pid, ctc, ctc-adaptive or dob-mpc")]
    BaselinesWithoutBaseline(ControllerKind),
    /// An adaptive kind was given a model payload (assumed by the tuning or
    /// carried by the robot): the identification replaces it from the first
    /// sample on.
    #[error("the {kind} controller identifies its payload from zero: the {mass} kg its model would assume is replaced at the first sample")]
    PayloadWithIdentification {
        /// The adaptive kind.
        kind: ControllerKind,
        /// The payload mass the model would carry (kg).
        mass: f64,
    },
    /// A position or velocity output ([`MpcSettings::output`]) for a kind
    /// whose step predicts nothing (the baselines `pid`, `ctc`,
    /// `ctc-adaptive`): there is no predicted state to command.
    #[error("the {kind} controller predicts no trajectory, so it cannot output a {output} command: use torque output or a predictive kind (usual, first, second, their adaptive variants, dob-mpc)")]
    OutputWithoutPrediction {
        /// The kind.
        kind: ControllerKind,
        /// The output asked for.
        output: OutputMode,
    },
    /// First-stage gains ([`MpcSettings::gains`]) asked for where the
    /// torque is not an affine function of the measured state through one
    /// stage-wise solve.
    #[error("the {kind} controller cannot hand out first-stage gains: {reason}")]
    GainsUnavailable {
        /// The kind.
        kind: ControllerKind,
        /// Why, and what to do.
        reason: &'static str,
    },
    /// The output's lead time is not within `[0, (N − 1)·Ts]` (or was given
    /// with a torque output, which has none).
    #[error("the output lead time is {lead_s} s: it must be from 0 to {max_s} s ((N − 1)·Ts) and needs a position or velocity output; lengthen the horizon or shorten the lead")]
    OutputLead {
        /// The lead time asked for (s).
        lead_s: f64,
        /// `(N − 1)·Ts` (s; 0 with a torque output).
        max_s: f64,
    },
    /// The smoothing the output pre-compensates is not a finite time `≥ 0`
    /// (or was given with a torque output, which has none).
    #[error("the output's smoothing time constant is {smoothing_s} s: it must be finite and at least 0 and needs a position or velocity output")]
    OutputSmoothing {
        /// The time constant asked for (s).
        smoothing_s: f64,
    },
    /// The interface's stream the output models
    /// ([`MpcSettings::output_cycle_s`]) cannot be modelled as given.
    #[error("the output's stream model (interface cycle {}, smoothing step {step_s} s) cannot be used: {reason}", cycle_s.map_or("unset".into(), |c| format!("{c} s")))]
    OutputStream {
        /// The interface's cycle (s; `None`: a step was given without it).
        cycle_s: Option<f64>,
        /// The smoothing's step (s).
        step_s: f64,
        /// Why, and what to do.
        reason: &'static str,
    },
    /// The robot already carries a payload and the tuning assumes another:
    /// one would silently replace the other.
    #[error("the robot carries a {carried} kg payload and the tuning assumes another of {assumed} kg: give one of the two")]
    TwoPayloads {
        /// Mass of the robot's payload (kg).
        carried: f64,
        /// Mass the tuning assumes (kg).
        assumed: f64,
    },
}

/// Builds an [`Controller`]: `ControllerBuilder::new(kind, &robot).settings(..)
/// .drives(..).build()?`. Unset parts: the paper's tuning
/// ([`MpcSettings::default`]), the robot's drives ([`DriveModel::from_robot`],
/// when a setting uses them), [`ObserverSettings::default`] (without delay
/// compensation), [`RlsSettings::default`] (adaptive kinds),
/// [`BaselineSettings::default`] (baselines).
#[derive(Debug, Clone)]
pub struct ControllerBuilder<'r> {
    kind: ControllerKind,
    robot: &'r Robot,
    settings: MpcSettings,
    drives: Option<DriveModel>,
    observer: Option<ObserverSettings>,
    estimator: Option<RlsSettings>,
    baselines: Option<BaselineSettings>,
    accept_ineffective: bool,
}

impl<'r> ControllerBuilder<'r> {
    /// A builder of controller `kind` for `robot` (the nominal rigid-body
    /// model the controller copies at [`Self::build`]).
    pub fn new(kind: ControllerKind, robot: &'r Robot) -> Self {
        Self {
            kind,
            robot,
            settings: MpcSettings::default(),
            drives: None,
            observer: None,
            estimator: None,
            baselines: None,
            accept_ineffective: false,
        }
    }

    /// The tuning (default: the paper's, [`MpcSettings::default`]).
    pub fn settings(mut self, settings: MpcSettings) -> Self {
        self.settings = settings;
        self
    }

    /// The drives as the controller models them (default: the robot's,
    /// [`DriveModel::from_robot`]); refused when no setting uses them.
    pub fn drives(mut self, drives: DriveModel) -> Self {
        self.drives = Some(drives);
        self
    }

    /// The state observer's tuning; needed with delay compensation (it
    /// carries the delay), refused when the settings run no observer.
    pub fn observer(mut self, observer: ObserverSettings) -> Self {
        self.observer = Some(observer);
        self
    }

    /// The payload estimator's tuning of an adaptive kind (default
    /// [`RlsSettings::default`]); refused for the other kinds.
    pub fn estimator(mut self, rls: RlsSettings) -> Self {
        self.estimator = Some(rls);
        self
    }

    /// The bandwidths of a baseline ([`ControllerKind::BASELINES`]; default
    /// [`BaselineSettings::default`]), checked at [`Self::build`] for the
    /// robot's joints ([`BaselineSettings::validate_for_dof`], all three);
    /// refused for the other kinds
    /// ([`BuildError::BaselinesWithoutBaseline`]).
    pub fn baselines(mut self, baselines: BaselineSettings) -> Self {
        self.baselines = Some(baselines);
        self
    }

    /// Accepts the settings of the tuning that would have no effect instead
    /// of refusing them, and builds the controller with them as they are (a
    /// scenario run warns about them and runs): a constraint horizon without
    /// torque limits ([`BuildError::ConstraintHorizonWithoutLimits`]), the
    /// observer's friction model without an observer
    /// ([`BuildError::ObserverFrictionWithoutObserver`]), friction use with
    /// no friction estimate ([`BuildError::NoFrictionEstimates`]: it adds
    /// zero), a model payload of an adaptive kind
    /// ([`BuildError::PayloadWithIdentification`]: the identification
    /// replaces it). Everything else is still refused, the parts given to
    /// this builder that nothing uses included.
    pub fn accept_ineffective_settings(mut self) -> Self {
        self.accept_ineffective = true;
        self
    }

    /// Checks that everything fits together and builds the controller: the
    /// buffers are sized here (this allocates; [`Controller::step`] does not).
    pub fn build(self) -> Result<Controller, BuildError> {
        let Self {
            kind,
            robot,
            settings: mut s,
            drives,
            observer,
            estimator,
            baselines,
            accept_ineffective: lenient,
        } = self;
        let n = robot.dof();
        s.validate_for_dof(n)?;
        if s.gains && s.solver == Solver::Auto {
            // The gain is the structured solver's: `auto` picks it.
            s.solver = Solver::Structured;
        }
        let baselines = baselines_for(kind, baselines, n)?;
        if let Some(nc) = s
            .constraint_horizon
            .filter(|_| !(s.torque_limits || lenient))
        {
            return Err(BuildError::ConstraintHorizonWithoutLimits(nc));
        }
        // The controller's model: the robot as given, with the payload the
        // tuning assumes (as `sim::Experiment::model_robot`).
        let carried = robot.payload().map(|p| p.mass);
        let assumed = (s.model_payload_kg > 0.0).then_some(s.model_payload_kg);
        if kind.is_adaptive() {
            if let Some(mass) = assumed.or(carried).filter(|_| !lenient) {
                return Err(BuildError::PayloadWithIdentification { kind, mass });
            }
        } else if estimator.is_some() {
            return Err(BuildError::EstimatorWithoutIdentification(kind));
        }
        if let (Some(carried), Some(assumed)) = (carried, assumed) {
            return Err(BuildError::TwoPayloads { carried, assumed });
        }
        let observed = s.state_observer || s.delay_compensation;
        if s.observer_friction && !observed && !lenient {
            return Err(BuildError::ObserverFrictionWithoutObserver);
        }
        let observer = match (observed, observer) {
            (false, Some(_)) => return Err(BuildError::ObserverNotEnabled),
            (false, None) => None,
            (true, None) if s.delay_compensation => {
                return Err(BuildError::MeasurementDelayUnknown)
            }
            (true, o) => Some(o.unwrap_or_default()),
        };
        if let Some(o) = observer.filter(|o| !(o.pole > 0.0 && o.pole < 1.0)) {
            return Err(BuildError::ObserverPole(o.pole));
        }
        let controller_drives = s.torque_limits || s.friction_compensation;
        let drives = match drives {
            Some(_) if !(controller_drives || s.observer_friction) => {
                return Err(BuildError::DrivesUnused)
            }
            Some(d) => Some(d),
            None if controller_drives || s.observer_friction => Some(DriveModel::from_robot(robot)),
            None => None,
        };
        if let Some(d) = &drives {
            check_drives(d, &s, n, lenient)?;
        }
        let model_robot = model_robot(robot, &s)?;
        let mut controller = new_algorithm(kind, n, &s, &baselines, estimator, observer)?;
        let predicted = check_output(kind, &s, n, controller.as_mut())?;
        let stream = output_stream(&s, n)?;
        check_gains(kind, &s, n, controller.as_mut())?;
        if let Some(d) = drives.as_ref().filter(|_| controller_drives) {
            controller.set_drive_model(d)?;
        }
        let observer = observer.map(|o| {
            let delay = if s.delay_compensation {
                o.measurement_delay
            } else {
                0
            };
            let mut obs = StateObserver::new(n, s.ts, delay, o.pole);
            if let Some(d) = drives.as_ref().filter(|_| s.observer_friction) {
                obs.set_friction(&d.coulomb_nm, &d.viscous_nms);
                if s.friction_creep {
                    obs.set_creep(d.coulomb_velocity_rad_s);
                    obs.set_creep_coupled(s.friction_coupled);
                }
            }
            obs
        });
        // An adaptive kind through a drive's own loop: the identified
        // payload reaches the drive as a torque feed-forward.
        let payload_ff = (kind.is_adaptive() && !s.output.is_torque())
            .then(|| Box::new(PayloadFeedForward::new(&model_robot)));
        Ok(Controller {
            kind,
            payload_ff,
            nominal_payload: model_robot.payload().copied(),
            model: RobotDynamics::new(model_robot),
            controller,
            drives,
            observer,
            x_est: vec![0.0; 2 * n],
            output: StepOutput::sized(n, s.gains),
            predicted,
            stream,
            started: false,
            tail_us: 0.0,
        })
    }
}

/// The output mode's checks ([`BuildError::OutputWithoutPrediction`],
/// [`BuildError::OutputLead`]) and the buffer of the predicted positions it
/// reads (N·n; empty with a torque output).
fn check_output(
    kind: ControllerKind,
    s: &MpcSettings,
    n: usize,
    algorithm: &mut (dyn Algorithm + Send),
) -> Result<Vec<f64>, BuildError> {
    let max_s = max_output_lead(s.horizon, s.ts);
    if let Some(smoothing_s) = s.output_smoothing_s {
        if s.output.is_torque() || !(smoothing_s.is_finite() && smoothing_s >= 0.0) {
            return Err(BuildError::OutputSmoothing { smoothing_s });
        }
    }
    if s.output.is_torque() {
        return match s.output_lead_s {
            Some(lead_s) => Err(BuildError::OutputLead { lead_s, max_s: 0.0 }),
            None => Ok(Vec::new()),
        };
    }
    let lead_s = s.output_lead_s.unwrap_or(0.0);
    if !(lead_s.is_finite() && lead_s >= 0.0 && lead_s <= max_s * (1.0 + 1e-12)) || s.horizon < 2 {
        return Err(BuildError::OutputLead { lead_s, max_s });
    }
    let mut predicted = vec![0.0; s.horizon * n];
    if !algorithm.predicted_outputs(&mut predicted) {
        return Err(BuildError::OutputWithoutPrediction {
            kind,
            output: s.output,
        });
    }
    Ok(predicted)
}

/// The stream model of [`MpcSettings::output_cycle_s`]
/// ([`BuildError::OutputStream`]); `None` without a cycle.
fn output_stream(s: &MpcSettings, n: usize) -> Result<Option<Stream>, BuildError> {
    let Some(cycle_s) = s.output_cycle_s else {
        return match s.output_smoothing_step_s {
            Some(step_s) => Err(BuildError::OutputStream {
                cycle_s: None,
                step_s,
                reason: "a smoothing step needs the interface's cycle: give output_cycle_s",
            }),
            None => Ok(None),
        };
    };
    let step_s = s.output_smoothing_step_s.unwrap_or(cycle_s);
    let smoothing = s.output_smoothing_s.filter(|_| !s.output.is_torque());
    check_stream(s.ts, cycle_s, step_s, smoothing, s.horizon).map_err(|reason| {
        BuildError::OutputStream {
            cycle_s: Some(cycle_s),
            step_s,
            reason,
        }
    })?;
    let smoothing_s = smoothing.unwrap_or(0.0);
    Ok(Some(Stream::new(n, s.ts, cycle_s, step_s, smoothing_s)))
}

/// The first-stage gains' checks ([`BuildError::GainsUnavailable`]): with
/// [`MpcSettings::gains`] on, no observer between the measurement and the
/// controller, no torque limits (the first input is then a QP's), the
/// structured solver and a kind whose step is one stage-wise solve.
fn check_gains(
    kind: ControllerKind,
    s: &MpcSettings,
    n: usize,
    algorithm: &mut (dyn Algorithm + Send),
) -> Result<(), BuildError> {
    if !s.gains {
        return Ok(());
    }
    let reason = if s.state_observer || s.delay_compensation {
        "an observer stands between the measured state and the controller; turn the observer and delay compensation off"
    } else if s.torque_limits {
        "with torque limits the first torque is a QP's, not an affine function of the state; turn torque limits off"
    } else if s.solver != Solver::Structured {
        "the gain is the structured solver's; use the structured (or auto) solver"
    } else if !algorithm.first_stage_gain(&mut vec![0.0; 2 * n * n]) {
        "its step is not one stage-wise solve; use usual, first, second or their adaptive variants"
    } else {
        return Ok(());
    };
    Err(BuildError::GainsUnavailable { kind, reason })
}

/// The controller's model of the robot: `robot` as given, with the payload
/// the tuning assumes (a point mass of [`MpcSettings::model_payload_kg`]
/// when that is positive). The one home of the rule "model = robot + assumed payload"
/// ([`ControllerBuilder::build`] uses it; so does a simulation that needs
/// the same model).
pub fn model_robot(robot: &Robot, settings: &MpcSettings) -> Result<Robot, ModelError> {
    let mut r = robot.clone();
    if settings.model_payload_kg > 0.0 {
        r.set_payload(Some(Payload::point_mass(settings.model_payload_kg)))?;
    }
    Ok(r)
}

/// The torque-limit rule: with [`MpcSettings::torque_limits`] on, the
/// drives need at least one finite peak torque, else the QP would never bind
/// and the controller would run unconstrained ([`BuildError::NoTorqueLimits`]).
pub fn check_torque_limits(settings: &MpcSettings, drives: &DriveModel) -> Result<(), BuildError> {
    if settings.torque_limits && drives.max_torque_nm.iter().all(|t| t.is_infinite()) {
        return Err(BuildError::NoTorqueLimits);
    }
    Ok(())
}

/// The baselines' bandwidths a build uses: the ones given, checked for `n`
/// joints and refused for a kind that is not a baseline; else the defaults.
fn baselines_for(
    kind: ControllerKind,
    given: Option<BaselineSettings>,
    n: usize,
) -> Result<BaselineSettings, BuildError> {
    match given {
        Some(_) if !kind.is_baseline() => Err(BuildError::BaselinesWithoutBaseline(kind)),
        Some(b) => {
            b.validate_for_dof(n)?;
            Ok(b)
        }
        None => Ok(BaselineSettings::default()),
    }
}

/// The drives' checks of [`ControllerBuilder::build`]: they fit `n` joints,
/// torque limits have a finite limit to bind, friction use has an estimate
/// (unless `lenient`).
fn check_drives(
    d: &DriveModel,
    s: &MpcSettings,
    n: usize,
    lenient: bool,
) -> Result<(), BuildError> {
    d.validate(n)?;
    check_torque_limits(s, d)?;
    let no_friction = d.coulomb_nm.iter().chain(&d.viscous_nms).all(|v| *v == 0.0);
    for (on, what) in [
        (s.friction_compensation, FrictionUse::Compensation),
        (s.observer_friction, FrictionUse::Observer),
    ] {
        if on && no_friction && !lenient {
            return Err(BuildError::NoFrictionEstimates(what));
        }
    }
    Ok(())
}

/// The parts of an [`Controller`] for a loop that interleaves its own law (a safe
/// stop) with the controller: the controller, its model and its observer.
pub struct MpcParts<'a> {
    /// The predictive controller; step it with [`MpcParts::model`].
    pub controller: &'a mut (dyn Algorithm + Send),
    /// The controller's own model of the robot.
    pub model: &'a mut RobotDynamics,
    /// The state observer, when the settings run one.
    pub observer: Option<&'a mut StateObserver>,
}

/// A controller built by [`ControllerBuilder`]: it owns its model of the
/// robot, its drives and its observer, and refuses nothing at run time that
/// it could have refused at build.
pub struct Controller {
    kind: ControllerKind,
    controller: Box<dyn Algorithm + Send>,
    model: RobotDynamics,
    /// The model's payload at build, restored by [`Controller::reset`] (the
    /// adaptive kinds change it).
    nominal_payload: Option<Payload>,
    drives: Option<DriveModel>,
    observer: Option<StateObserver>,
    x_est: Vec<f64>,
    output: StepOutput,
    /// The positions the last step predicted (N·n), read by a position or
    /// velocity output (empty with a torque output).
    predicted: Vec<f64>,
    /// The model of the interface's stream, with
    /// [`MpcSettings::output_cycle_s`] (`control/command.rs`).
    stream: Option<Stream>,
    /// Reset at a measured state since build.
    started: bool,
    /// An adaptive kind with a position or velocity output: the identified
    /// payload's feed-forward in the command (`control/command.rs`).
    payload_ff: Option<Box<PayloadFeedForward>>,
    /// With a step budget: the longest work after the torque-limit QP seen
    /// in a step (µs, up to the end of [`Controller::step`]), kept back
    /// from the next QP's deadline ([`Controller::budget_reserve_us`]).
    tail_us: f64,
}

/// At most this fraction of the step budget is kept back for the work
/// after the QP, whatever the longest tail seen: one tail stretched by a
/// preemption must not leave every later QP without time.
const MAX_RESERVE_FRACTION: f64 = 0.25;

/// At least this fraction of the step budget is kept back for the work
/// after the QP, whatever the longest tail seen so far: the tail of a
/// step whose QP stopped at its deadline (its best feasible point, or the
/// shifted plan) is longer than that of the steps before the limits first
/// bind, and is first seen only then.
const MIN_RESERVE_FRACTION: f64 = 0.1;

/// The per-kind algorithm; the adaptive kinds with the real arm's
/// identification ([`RealArmIdentification`]) when the settings say the
/// plant is one (delay or friction compensation, an observer, or a bound on
/// the payload's centre of mass).
fn new_algorithm(
    kind: ControllerKind,
    n: usize,
    s: &MpcSettings,
    baselines: &BaselineSettings,
    estimator: Option<RlsSettings>,
    observer: Option<ObserverSettings>,
) -> Result<Box<dyn Algorithm + Send>, BuildError> {
    let real_arm = s.delay_compensation
        || s.friction_compensation
        || s.state_observer
        || s.payload_com_max_m > 0.0;
    if real_arm && kind.is_adaptive() {
        let cfg = RealArmIdentification {
            delay: observer
                .filter(|_| s.delay_compensation)
                .map_or(0, |o| o.measurement_delay),
            max_mass_kg: if s.max_payload_kg > 0.0 {
                s.max_payload_kg
            } else {
                RealArmIdentification::default().max_mass_kg
            },
            max_com_m: s.payload_com_max_m,
            at_rest: s.identify_at_rest,
            raw_mass: s.identification_raw_mass,
            min_samples: if s.identification_min_samples > 0 {
                s.identification_min_samples
            } else {
                RealArmIdentification::default().min_samples
            },
            ..RealArmIdentification::default()
        };
        let rls = estimator.unwrap_or_default();
        let mut c = AdaptiveMpc::with_estimator(kind, n, s, baselines, rls)?;
        c.set_real_arm(cfg, rls)?;
        return Ok(Box::new(c));
    }
    Ok(match estimator {
        Some(rls) => Box::new(AdaptiveMpc::with_estimator(kind, n, s, baselines, rls)?),
        None => new_controller_with_baselines(kind, n, s, baselines)?,
    })
}

impl std::fmt::Debug for Controller {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Controller")
            .field("kind", &self.kind)
            .field("dof", &self.dof())
            .field("horizon", &self.horizon())
            .field("observer", &self.observer.is_some())
            .field("output", &self.output)
            .finish()
    }
}

impl Controller {
    /// One control step: the observer's estimate (when it runs) of the
    /// measured state, then the algorithm's torque. Allocates nothing and
    /// never panics.
    ///
    /// `Err` only for bad input ([`StepError`]: wrong length, non-finite,
    /// not reset): then nothing changed. Otherwise the numerical outcome is
    /// [`StepOutput::status`]: on a numerical failure
    /// ([`StepStatus::HeldLastTorque`]) the output keeps the last torque
    /// and the controller's state is as before the call (the observer's,
    /// when it runs, has taken the measurement).
    pub fn step(&mut self, input: &StepInput<'_>) -> Result<&StepOutput, StepError> {
        let start = Instant::now();
        self.check_input(input)?;
        if let Some(reserve) = self.budget_reserve_us() {
            self.controller.set_step_clock(start, reserve);
        }
        let result = self.solve(input);
        let solve_time = start.elapsed();
        match result {
            Ok(info) => {
                let out = &mut self.output;
                out.cost = info.cost;
                out.r_diag_ratio = info.r_diag_ratio;
                out.zoh_squarings = info.zoh_squarings;
                out.qp_status = self.controller.qp_status();
                out.payload_estimate = self.controller.payload_estimate();
                out.status = match out.qp_status {
                    Some(qp) if qp.fallback => StepStatus::QpIterationCap {
                        iterations: qp.iterations,
                    },
                    _ => StepStatus::Solved,
                };
                self.command(input.x);
                self.gains(input.x);
            }
            Err(failure) => self.output.status = StepStatus::HeldLastTorque(failure),
        }
        self.output.solve_time = start.elapsed();
        self.fill_telemetry(solve_time);
        self.learn_tail();
        Ok(&self.output)
    }

    /// With a step budget: the time kept back from the torque-limit QP's
    /// deadline for the step's work after it (µs): the longest such tail
    /// seen so far (measured from the QP's return to the end of
    /// [`Self::step`], on every budgeted step, with or without an active
    /// QP), at least a tenth and at most a quarter of the budget. `None`
    /// without a budget.
    pub fn budget_reserve_us(&self) -> Option<f64> {
        let budget = self.controller.settings().step_budget_us?;
        Some(
            self.tail_us
                .max(MIN_RESERVE_FRACTION * budget)
                .min(MAX_RESERVE_FRACTION * budget),
        )
    }

    /// With a step budget, after a step that reached its QP: the tail from
    /// the QP's return to now, into the reserve's maximum.
    fn learn_tail(&mut self) {
        if self.controller.settings().step_budget_us.is_none() {
            return;
        }
        if let Some(qp_end) = self.controller.qp_end() {
            self.tail_us = self.tail_us.max(qp_end.elapsed().as_secs_f64() * 1e6);
        }
    }

    /// The position/velocity command of a successful step one lead time
    /// ahead (`control/command.rs`), from the positions the step predicted
    /// and the state it acted on; nothing with a torque output.
    fn command(&mut self, x: &[f64]) {
        let s = self.controller.settings();
        let (torque, lead_s, ts) = (s.output.is_torque(), s.output_lead_s.unwrap_or(0.0), s.ts);
        let smoothing_s = s.output_smoothing_s.unwrap_or(0.0);
        if torque || !self.controller.predicted_outputs(&mut self.predicted) {
            return;
        }
        let n = self.x_est.len() / 2;
        let now = match self.observer {
            Some(_) => &self.x_est[..n],
            None => &x[..n],
        };
        let out = &mut self.output;
        let cmd = [
            &mut out.q_command[..],
            &mut out.qd_command[..],
            &mut out.qdd_command[..],
        ];
        if let Some(stream) = self.stream.as_mut() {
            stream.command(now, &self.predicted, lead_s, ts, cmd);
        } else {
            lead_point(now, &self.predicted, lead_s, smoothing_s, ts, cmd);
        }
        // Only while the model carries an identified payload (otherwise
        // the drive's model is the controller's: nothing to add). The
        // dynamics accepted this model and state in this very step; should
        // they refuse them here, `torque` writes nothing and the command
        // goes without a feed-forward.
        out.tau_command.fill(0.0);
        if let Some(ff) = self.payload_ff.as_mut() {
            if out.payload_estimate.is_some() {
                let model = self.model.robot();
                let _ = ff.torque(
                    model,
                    now,
                    &self.predicted,
                    lead_s,
                    ts,
                    &mut out.tau_command,
                );
            }
        }
    }

    /// The torque the drives applied over the period that just ended
    /// (`[t_{k−1}, t_k]`, n values, N·m), for an interface that closes its
    /// own joint loop and reports it (UR RTDE's joint torques, KUKA FRI's
    /// measured torque, libfranka's `tau_J`): call it before
    /// [`Self::step`] at `t_k`. The adaptive kinds then identify their
    /// payload from it also through a position or velocity output, and
    /// carry it to the drive as a torque feed-forward with the command
    /// ([`StepOutput::tau_command`], `control/command.rs`); with a torque
    /// output it replaces the
    /// controller's own `τ_{k−1}` in the identification. The other kinds
    /// ignore it. Allocates nothing.
    pub fn set_applied_torque(&mut self, tau: &[f64]) -> Result<(), StepError> {
        check_len("applied torque", tau.len(), self.dof())?;
        check_finite("applied torque", tau)?;
        self.controller.applied_torque(tau);
        Ok(())
    }

    /// With [`MpcSettings::gains`]: the first-stage gain of a successful
    /// step, its torque as the feed-forward and the state it acted on as
    /// the linearization point; nothing otherwise (empty fields).
    fn gains(&mut self, x: &[f64]) {
        let out = &mut self.output;
        if out.gain.is_empty() {
            return;
        }
        if self.controller.first_stage_gain(&mut out.gain) {
            out.tau_ff.copy_from_slice(&out.tau);
            out.x_lin.copy_from_slice(x);
        }
    }

    /// Counts the step budget of the torque-limit QP in deadline checks
    /// instead of µs (one per horizon block and Hessian column of its build
    /// and per active-set iteration; `None`: µs again): a deterministic
    /// budget, for tests of the fallback levels without a clock.
    #[doc(hidden)]
    pub fn set_check_budget(&mut self, checks: Option<u32>) {
        self.controller.set_check_budget(checks);
    }

    /// The step's [`StepTelemetry`] from its status, its QP and its times.
    fn fill_telemetry(&mut self, solve_time: Duration) {
        let out = &mut self.output;
        let qp = out.qp_status.unwrap_or_default();
        let held = matches!(out.status, StepStatus::HeldLastTorque(_));
        out.telemetry = StepTelemetry {
            model_time: self.controller.model_time().unwrap_or(Duration::ZERO),
            solve_time,
            total_time: out.solve_time,
            qp_iterations: if held { 0 } else { qp.iterations },
            active_constraints: if held { 0 } else { qp.active_constraints },
            budget_slack_us: self
                .controller
                .settings()
                .step_budget_us
                .map(|b| b - out.solve_time.as_secs_f64() * 1e6),
            fallback: match out.status {
                StepStatus::HeldLastTorque(_) => FallbackLevel::Hold,
                _ => qp.fallback_level,
            },
            budget_hit: !held && qp.budget_hit,
        };
    }

    /// The input checks of [`Self::step`]: reset first, every slice its
    /// length and finite.
    fn check_input(&self, input: &StepInput<'_>) -> Result<(), StepError> {
        if !self.started {
            return Err(StepError::NotReset);
        }
        let n = self.dof();
        check_len("x", input.x.len(), 2 * n)?;
        check_len("w_k", input.w_k.len(), n)?;
        check_len("preview", input.preview.len(), self.horizon() * n)?;
        check_finite("x", input.x)?;
        check_finite("w_k", input.w_k)?;
        check_finite("preview", input.preview)
    }

    /// Observer, algorithm, torque record: the torque into the output's
    /// `tau` (only on success).
    fn solve(&mut self, input: &StepInput<'_>) -> Result<StepInfo, StepFailure> {
        let x = match self.observer.as_mut() {
            Some(o) => {
                self.x_est
                    .copy_from_slice(o.update(&mut self.model, input.x)?);
                &self.x_est
            }
            None => input.x,
        };
        self.controller.measurement(input.x);
        let input = StepInput {
            x,
            w_k: input.w_k,
            preview: input.preview,
        };
        let info = self
            .controller
            .step(&mut self.model, &input, &mut self.output.tau)?;
        if let Some(o) = self.observer.as_mut() {
            if self.controller.take_model_change() {
                o.carry_model_change(&mut self.model, &self.output.tau)?;
            }
            o.record_torque(&self.output.tau);
        }
        Ok(info)
    }

    /// Starts a run at the measured state `x0 = [q; q̇]` (2n values):
    /// `x_{−1} = x0`, `u_{−1} = 0`, `ē_{−1} = 0`, the observer at rest at
    /// `q0`, the model's payload back to the nominal one. `Err` (and
    /// nothing changed) for an `x0` of the wrong length or not finite;
    /// [`StepError::ResetRefused`] when the algorithm cannot start there.
    pub fn reset(&mut self, x0: &[f64]) -> Result<(), StepError> {
        check_len("x0", x0.len(), 2 * self.dof())?;
        check_finite("x0", x0)?;
        self.reset_algorithm(x0).map_err(StepError::ResetRefused)?;
        if let Some(o) = self.observer.as_mut() {
            o.reset(x0);
        }
        self.x_est.copy_from_slice(x0);
        if let Some(stream) = self.stream.as_mut() {
            stream.reset();
        }
        self.started = true;
        Ok(())
    }

    /// The algorithm's reset and the nominal payload (its failures are
    /// ruled out by [`Self::reset`]'s checks).
    fn reset_algorithm(&mut self, x0: &[f64]) -> Result<(), StepFailure> {
        self.controller.reset(x0)?;
        if self.kind.is_adaptive() || self.controller.payload_estimate().is_some() {
            self.model
                .robot_mut()
                .set_payload(self.nominal_payload)
                .map_err(|_| StepFailure::Internal("the nominal payload was refused"))?;
        }
        Ok(())
    }

    /// Which algorithm this is.
    pub fn kind(&self) -> ControllerKind {
        self.kind
    }

    /// Number of joints `n`.
    pub fn dof(&self) -> usize {
        self.controller.dof()
    }

    /// Prediction horizon `N`.
    pub fn horizon(&self) -> usize {
        self.controller.horizon()
    }

    /// The tuning it was built with.
    pub fn settings(&self) -> &MpcSettings {
        self.controller.settings()
    }

    /// The input `u` of the last successful step, n values.
    pub fn input(&self) -> &[f64] {
        self.controller.input()
    }

    /// The optimal sequence of the last successful step, N·n values
    /// ([`Algorithm::increments`]).
    pub fn increments(&self) -> &[f64] {
        self.controller.increments()
    }

    /// The output of the last successful step (zeros before the first).
    pub fn output(&self) -> &StepOutput {
        &self.output
    }

    /// The controller's model of the robot (for the adaptive kinds, with the
    /// payload identified so far).
    pub fn model(&self) -> &RobotDynamics {
        &self.model
    }

    /// The drives as the controller models them (`None` when no setting
    /// uses them).
    pub fn drives(&self) -> Option<&DriveModel> {
        self.drives.as_ref()
    }

    /// The state observer, when the settings run one.
    pub fn observer(&self) -> Option<&StateObserver> {
        self.observer.as_ref()
    }

    /// The state the last step acted on: the observer's estimate, when it
    /// runs (`None` otherwise).
    pub fn state_estimate(&self) -> Option<&[f64]> {
        self.observer.as_ref().map(|_| self.x_est.as_slice())
    }

    /// The controller, its model and its observer, for a loop that steps
    /// them itself around another law (as the simulator's safe stop does);
    /// [`Controller::step`] is that loop without the other law.
    pub fn parts_mut(&mut self) -> MpcParts<'_> {
        MpcParts {
            controller: self.controller.as_mut(),
            model: &mut self.model,
            observer: self.observer.as_mut(),
        }
    }
}
