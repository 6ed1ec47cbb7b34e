//! The scenario crate's errors. Each says where: the file, the scenario key
//! (`[section] key = value`) or the override (`section.key = value`), and
//! keeps the library's typed error. Front ends add their own advice (a
//! command-line flag, a Python argument); this crate never names one.

use ofmpc::analysis::StabilityError;
use ofmpc::control::{BuildError, ControllerKind, DriveQuantity, SettingsError};
use ofmpc::motion::PlanError;
use ofmpc::robot::{ModelError, PayloadError};
use ofmpc::sim::{
    ExperimentError, FrictionKind, LoopSettingsError, NoiseKind, PlantError, PlantSettingsError,
    ServoSettingsError,
};
use std::path::PathBuf;

/// What went wrong reading, resolving, running or analysing a scenario.
///
/// The `Display` of a variant says where and what; variants that wrap an
/// I/O or library error carrying a chain of its own expose it as
/// [`std::error::Error::source`] (print the chain, e.g. with `anyhow`'s `{:#}`).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ScenarioError {
    /// The scenario file could not be read.
    #[error("cannot read scenario {}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The scenario is not valid TOML, or a key or value does not fit
    /// (unknown key, wrong type): the parser's message, with its position.
    #[error("{origin}: {message}")]
    Parse {
        /// The file (or another name of the document).
        origin: String,
        /// The parser's message.
        message: String,
    },
    /// An override `key=value` is not of that form.
    #[error("'{text}': give key=value, the key a dotted path such as mpc.horizon")]
    OverrideSyntax {
        /// The override as given.
        text: String,
    },
    /// An override does not fit the scenario (unknown key, wrong type, or a
    /// key below a value that is not a table): the same message as the key
    /// written in the file.
    #[error("{key} = {value}: {message}")]
    Override {
        /// The dotted key.
        key: String,
        /// The value as given.
        value: String,
        /// Why it does not fit.
        message: String,
    },
    /// `controllers = []`.
    #[error("controllers = []: name at least one of \"usual\", \"first\", \"second\", \"first-adaptive\", \"second-adaptive\"")]
    NoControllers,
    /// `[payload] masses_kg = []`.
    #[error("payload.masses_kg = []: give at least one mass (0 for none)")]
    NoPayloads,
    /// The robot (built-in name or URDF) could not be loaded.
    #[error(transparent)]
    Robot(Box<ModelError>),
    /// A `[robot]` key does not fit the robot (start pose, tip).
    #[error("{key}: {error}")]
    RobotKey {
        /// The key, e.g. `"[robot] start_q"`.
        key: &'static str,
        /// Why.
        error: Box<ModelError>,
    },
    /// `[robot] tip` other than the flange for a built-in robot, whose chain always ends at
    /// its flange.
    #[error(
        "[robot] tip = {tip:?}: '{tip}' {} the built-in robot {robot}, whose chain always ends at its \
         flange '{flange}' (its links: {}); leave the tip unset (or give '{flange}'), place a \
         tool with the tool centre point (robot.tcp_mm), or bring a URDF to end the chain at \
         another link",
        if links.contains(tip) { "is a link of" } else { "is not a link of" },
        links.join(", ")
    )]
    BuiltinTip {
        /// The tip asked for (quoted short).
        tip: String,
        /// The robot's name.
        robot: String,
        /// Its flange link.
        flange: String,
        /// Its links.
        links: Vec<String>,
    },
    /// The drives file could not be read or applied.
    #[error("applying {}", path.display())]
    Drives {
        /// The drives file.
        path: PathBuf,
        /// Why.
        #[source]
        source: Box<ModelError>,
    },
    /// `[mpc]` does not fit the robot.
    #[error("[mpc] {error}")]
    Mpc {
        /// The library's error.
        error: Box<SettingsError>,
    },
    /// `[baselines]` does not fit the robot (a bandwidth ≤ 0, not finite,
    /// or a list of another length than the robot's joints).
    #[error("[baselines] {error}")]
    Baselines {
        /// The library's error.
        error: Box<SettingsError>,
    },
    /// A payload of `[payload]` is not a physical body.
    #[error("[payload] masses_kg: {error}")]
    Payload {
        /// The mass (kg).
        mass: f64,
        /// The library's error.
        error: Box<PayloadError>,
    },
    /// `[mpc] model_payload_kg` is not a payload the robot can carry.
    #[error("[mpc] model_payload_kg = {mass}: {error}")]
    ModelPayload {
        /// The mass (kg).
        mass: f64,
        /// The library's error.
        error: Box<ModelError>,
    },
    /// The program file could not be read.
    #[error("cannot read program {}", path.display())]
    ReadProgram {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A tool table file could not be read.
    #[error("cannot read the tool table {} ({key})", path.display())]
    ReadToolTable {
        /// The setting that names it (`[program] tool_table` or a command-line option).
        key: String,
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A tool table is not in LinuxCNC's .tbl format.
    #[error("tool table {} ({key}): {error}", path.display())]
    ToolTable {
        /// The setting that names it.
        key: String,
        /// The file.
        path: PathBuf,
        /// The library's error.
        error: Box<ofmpc::gcode::ToolTableError>,
    },
    /// An unknown time law.
    #[error("{key} '{value}': use 'septic' (the paper's) or 'quintic'")]
    Profile {
        /// The setting that holds it.
        key: String,
        /// The value.
        value: String,
    },
    /// An unknown path mode.
    #[error("{key} '{value}': use 'G61' (exact stop) or 'G64' (blend corners)")]
    Mode {
        /// The setting that holds it.
        key: String,
        /// The value.
        value: String,
    },
    /// The program could not be planned with these settings.
    #[error("{program}: {}", plan_error_message(.error, &SCENARIO_KEYS))]
    Plan {
        /// The program's name.
        program: String,
        /// The library's error.
        error: Box<PlanError>,
    },
    /// The experiment's settings do not fit (named by their scenario key).
    #[error("{}{}", .program.as_deref().map(|p| format!("{p}: ")).unwrap_or_default(), experiment_error(.error))]
    Experiment {
        /// The program's name, when the error is about the planned experiment.
        program: Option<String>,
        /// The library's error.
        error: Box<ExperimentError>,
    },
    /// A run could not start.
    #[error("{run}: {}", experiment_error(.error))]
    Run {
        /// The run's name (`<controller>_m<mass>`).
        run: String,
        /// The library's error.
        error: Box<ExperimentError>,
    },
    /// A controller's stability interval could not be computed.
    #[error("stability of {kind}")]
    Stability {
        /// The controller.
        kind: ControllerKind,
        /// Why.
        #[source]
        source: Box<StabilityError>,
    },
    /// A stability computation other than the interval failed.
    #[error(transparent)]
    Analysis(Box<StabilityError>),
    /// Robust tuning was asked for an adaptive controller (it identifies the payload).
    #[error("{kind}: tune the non-adaptive controllers (the adaptive ones identify the payload)")]
    AdaptiveTuning {
        /// The controller.
        kind: ControllerKind,
    },
    /// The payload range of robust tuning is not `0 ≤ lo ≤ hi`.
    #[error("payload range {lo},{hi}: give LO,HI with 0 ≤ LO ≤ HI (kg)")]
    PayloadRange {
        /// Lower end (kg).
        lo: f64,
        /// Upper end (kg).
        hi: f64,
    },
    /// No tuning of the search grid is robust over the range.
    #[error("no tuning of the grid keeps {controllers} stable and offset-free over {lo}..{hi} kg on this robot and program: narrow the payload range")]
    NoRobustTuning {
        /// The controllers, comma-separated.
        controllers: String,
        /// Lower end (kg).
        lo: f64,
        /// Upper end (kg).
        hi: f64,
    },
    /// A scenario or metrics document could not be written.
    #[error("writing {what}: {message}")]
    Write {
        /// What (e.g. "the scenario").
        what: &'static str,
        /// The serializer's message.
        message: String,
    },
}

impl From<ModelError> for ScenarioError {
    fn from(e: ModelError) -> Self {
        Self::Robot(Box::new(e))
    }
}

impl From<StabilityError> for ScenarioError {
    fn from(e: StabilityError) -> Self {
        Self::Analysis(Box::new(e))
    }
}

impl ScenarioError {
    /// An [`ExperimentError`] about the settings, named by its scenario key (prefixed by
    /// the program's name when it is about the planned experiment).
    pub fn experiment(program: Option<String>, error: ExperimentError) -> Self {
        Self::Experiment {
            program,
            error: Box::new(error),
        }
    }
}

/// How a front end names the planning settings in its messages.
#[derive(Debug, Clone, Copy)]
pub struct SettingNames {
    /// Path speed limit.
    pub speed: &'static str,
    /// Path acceleration limit.
    pub accel: &'static str,
    /// Path jerk limit.
    pub jerk: &'static str,
    /// Default corner tolerance.
    pub tolerance: &'static str,
    /// Sample period.
    pub ts: &'static str,
    /// Work offset of programs that set none.
    pub origin: &'static str,
    /// The robot's start pose.
    pub start_q: &'static str,
}

/// The scenario file's names of the planning settings.
pub const SCENARIO_KEYS: SettingNames = SettingNames {
    speed: "[timing] max_speed_m_s",
    accel: "[timing] max_accel_m_s2",
    jerk: "[timing] max_jerk_m_s3",
    tolerance: "[timing] tolerance_mm",
    ts: "[mpc] ts",
    origin: "[program] origin_mm",
    start_q: "[robot] start_q",
};

/// A planning error in the front end's words: the library's message, followed by the
/// setting (flag or key) to change where the library names one.
pub fn plan_error_message(e: &PlanError, names: &SettingNames) -> String {
    use ofmpc::motion::ReferenceFailure;
    use ofmpc::motion::SampleCause;
    use ofmpc::motion::{TimingLimit, TrajectoryError};
    let setting = match e {
        PlanError::SamplePeriod(_) => Some(names.ts),
        PlanError::TooManySamples { cause, .. } => match cause {
            SampleCause::PathSpeed { .. } => Some(names.speed),
            SampleCause::PathAcceleration { .. } => Some(names.accel),
            SampleCause::SamplePeriod => Some(names.ts),
            _ => None,
        },
        PlanError::Timing(TrajectoryError::InvalidLimit { limit, .. }) => Some(match limit {
            TimingLimit::PathSpeed => names.speed,
            TimingLimit::PathAcceleration => names.accel,
            TimingLimit::PathJerk => names.jerk,
            _ => names.tolerance,
        }),
        PlanError::Reference(r) => match &r.failure {
            ReferenceFailure::Ik(_)
            | ReferenceFailure::BranchLimit { .. }
            | ReferenceFailure::SingularPass { .. }
            | ReferenceFailure::ReachEdge { .. }
            | ReferenceFailure::BranchJump { .. } => Some(names.origin),
            ReferenceFailure::JointSpeed { .. } => Some(names.speed),
            ReferenceFailure::StartSingular { .. }
            | ReferenceFailure::StartStretched { .. }
            | ReferenceFailure::StartAtReach { .. } => Some(names.start_q),
            ReferenceFailure::SamplePeriod(_) => Some(names.ts),
            _ => None,
        },
        _ => None,
    };
    match setting {
        Some(s) => format!("{e} (setting: {s})"),
        None => e.to_string(),
    }
}

/// The scenario key that holds the value an [`ExperimentError`] is about,
/// with that value, e.g. `[plant] substep = 1e-300`.
pub fn experiment_key(e: &ExperimentError) -> Option<String> {
    Some(match e {
        ExperimentError::Loop(l) => loop_key(l),
        ExperimentError::Plant(PlantError::Settings(p)) => plant_key(p),
        ExperimentError::Mpc(SettingsError::DriveModelLength { what, .. })
        | ExperimentError::Mpc(SettingsError::DriveModelValue { what, .. }) => format!(
            "the drives file's {}",
            match what {
                DriveQuantity::MaxTorque => "max_torque_nm",
                DriveQuantity::Coulomb => "coulomb_nm",
                DriveQuantity::Viscous => "viscous_nms",
                _ => "values",
            }
        ),
        ExperimentError::Mpc(SettingsError::DrivesUnsupported(_)) => {
            "[mpc] torque_limits / friction_compensation".into()
        }
        ExperimentError::Mpc(_) => "[mpc]".into(),
        ExperimentError::Build(BuildError::OutputLead { lead_s, .. }) => {
            format!(
                "[mpc] output_lead_s = {lead_s} (default: [plant.servo] lag_s + half a period; \
                 lookahead_s is pre-compensated, output_smoothing_s)"
            )
        }
        ExperimentError::Build(BuildError::OutputSmoothing { smoothing_s }) => {
            format!("[mpc] output_smoothing_s = {smoothing_s}")
        }
        ExperimentError::Build(BuildError::OutputStream {
            cycle_s: Some(cycle_s),
            step_s,
            ..
        }) => format!(
            "[mpc] output_cycle_s = {cycle_s}, output_smoothing_step_s = {step_s} \
             (default with a [plant.servo] lookahead_s: its period_s and the substep)"
        ),
        ExperimentError::Build(BuildError::OutputStream { step_s, .. }) => {
            format!("[mpc] output_smoothing_step_s = {step_s} without output_cycle_s")
        }
        ExperimentError::Build(BuildError::OutputWithoutPrediction { output, .. }) => {
            format!("[mpc] output = \"{output}\"")
        }
        ExperimentError::Build(BuildError::GainsUnavailable { .. }) => "[mpc] gains = true".into(),
        ExperimentError::Build(_) => {
            "[mpc] torque_limits = true with no finite max_torque_nm (robot effort limits or \
             [robot] drives)"
                .into()
        }
        ExperimentError::TooManySamples { .. } => {
            "the program's duration with [simulation] hold_s at [mpc] ts".into()
        }
        ExperimentError::Model(_) => "[payload]".into(),
        _ => return None,
    })
}

/// The `[simulation]`, `[payload]`, `[faults]` or `[safety]` key of a loop setting's error.
fn loop_key(l: &LoopSettingsError) -> String {
    match l {
        LoopSettingsError::HoldTime(v) => format!("[simulation] hold_s = {v}"),
        LoopSettingsError::DivergenceThreshold(v) => {
            format!("[simulation] divergence_threshold_rad = {v}")
        }
        LoopSettingsError::SteadyWindow { value, .. } => {
            format!("[simulation] steady_window_s = {value}")
        }
        LoopSettingsError::IdentificationTime { value, .. } => {
            format!("[simulation] identification_s = {value}")
        }
        LoopSettingsError::SettleTime { value, .. } => {
            format!("[simulation] settle_s = {value}")
        }
        LoopSettingsError::PickUpTime(v) => format!("[payload] pick_up_at_s = {v}"),
        LoopSettingsError::FaultTime { index, value } => {
            format!("[faults] nan_at_s[{index}] = {value}")
        }
        LoopSettingsError::DropoutInterval { index, from, to } => {
            format!("[faults] dropout_s[{index}] = [{from}, {to}]")
        }
        LoopSettingsError::MaxJointError(v) => format!("[safety] max_joint_error_rad = {v}"),
        _ => "[simulation]".into(),
    }
}

/// The `[plant]` key of a plant setting's error.
fn plant_key(p: &PlantSettingsError) -> String {
    match p {
        PlantSettingsError::Substep(v) => format!("[plant] substep = {v}"),
        PlantSettingsError::SubstepRatio { ts, substep, .. } => {
            format!("[plant] substep = {substep} with [mpc] ts = {ts}")
        }
        PlantSettingsError::FrictionLength { kind, .. }
        | PlantSettingsError::FrictionValue { kind, .. } => format!(
            "[plant] {}",
            match kind {
                FrictionKind::Viscous => "viscous_friction",
                FrictionKind::Stribeck => "stribeck_friction",
                _ => "coulomb_friction",
            }
        ),
        PlantSettingsError::InertiaError(v) => format!("[plant] inertia_error = {v}"),
        PlantSettingsError::StribeckVelocity(v) => format!("[plant] stribeck_velocity = {v}"),
        PlantSettingsError::ModelMismatch { .. } => "[plant] robot".into(),
        PlantSettingsError::CoulombVelocity(v) => format!("[plant] coulomb_velocity = {v}"),
        PlantSettingsError::Delay(v) => format!("[plant] delay_samples = {v}"),
        PlantSettingsError::Fault {
            index, what, value, ..
        } => format!("[plant] faults[{index}].{what} = {value}"),
        PlantSettingsError::Noise { kind, value } => format!(
            "[plant] {} = {value}",
            match kind {
                NoiseKind::Position => "position_noise",
                _ => "velocity_noise",
            }
        ),
        PlantSettingsError::Servo(e) => servo_key(e),
        _ => "[plant]".into(),
    }
}

/// Where in `[plant.servo]` (or `[mpc] output`) a servo interface's error is.
fn servo_key(e: &ServoSettingsError) -> String {
    match e {
        ServoSettingsError::Value { key, value, .. } => format!("[plant.servo] {key} = {value}"),
        ServoSettingsError::Multiple { .. } => {
            "[plant.servo] period_s / lag_s with [plant] substep".into()
        }
        ServoSettingsError::Unused { key, .. } => format!("[plant.servo] {key}"),
        ServoSettingsError::FaultWithoutWatchdog => {
            "[plant.servo] on_late = \"fault\" with watchdog_misses = 0".into()
        }
        ServoSettingsError::Late { index, .. } => format!("[plant.servo] late[{index}]"),
        ServoSettingsError::LoopTooFast { .. } => {
            "[plant.servo] gain / bandwidth_hz with [plant] substep".into()
        }
        ServoSettingsError::OutputMismatch { .. } | ServoSettingsError::NoInterface { .. } => {
            "[mpc] output".into()
        }
        _ => "[plant.servo]".into(),
    }
}

/// `key: explanation` for an [`ExperimentError`].
pub fn experiment_error(e: &ExperimentError) -> String {
    match experiment_key(e) {
        Some(k) => format!("{k}: {e}"),
        None => e.to_string(),
    }
}

/// An error with its sources as `a: b: c` (what `anyhow`'s `{:#}` prints), leaving out a
/// source whose text the message already holds: a variant written `"...: {0}"` that also
/// names `{0}` its source would otherwise say it twice ("invalid payload: mass 1e6 kg …:
/// mass 1e6 kg …").
pub fn chain_text(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let m = c.to_string();
        if !m.is_empty() && !text.contains(&m) {
            text.push_str(": ");
            text.push_str(&m);
        }
        cause = c.source();
    }
    // Huge numbers short, huge lines cut (issue #36): one place for the command and Python.
    ofmpc::input::for_reader(&text)
}

#[cfg(test)]
mod chain_tests {
    use super::chain_text;

    #[test]
    fn a_source_already_in_the_message_is_said_once() {
        let e = ofmpc::robot::Robot::irb140()
            .set_payload(Some(ofmpc::robot::Payload::point_mass(1e6)))
            .unwrap_err();
        let a = anyhow_like(&e);
        assert_eq!(a.matches("more than").count(), 1, "{a}");
        let io = std::io::Error::other("disk full");
        let w = ScenarioLike(io);
        assert_eq!(chain_text(&w), "cannot write: disk full");
    }

    fn anyhow_like(e: &(dyn std::error::Error + 'static)) -> String {
        chain_text(e)
    }

    #[derive(Debug)]
    struct ScenarioLike(std::io::Error);
    impl std::fmt::Display for ScenarioLike {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("cannot write")
        }
    }
    impl std::error::Error for ScenarioLike {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }
}
