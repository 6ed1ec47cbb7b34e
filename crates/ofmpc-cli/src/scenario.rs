//! Scenario files (TOML): what `ofmpc run` reads and what `ofmpc reproduce`
//! builds from its defaults. Two stages, as in ripgrep: [`ScenarioFile`] is
//! what the user wrote (serde, defaults filled in), [`Scenario`] is the
//! resolved experiment (robot loaded, program parsed and timed, reference
//! built). `examples/scenario.toml` documents every key.

use anyhow::{bail, Context};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::gcode::{ParseOptions, PAPER_TABLE1};
use ofmpc::motion::reference::ReferenceFailure;
use ofmpc::motion::timelaw::Profile;
use ofmpc::motion::trajectory::{TimingLimit, TrajectoryError};
use ofmpc::motion::{
    plan, CartesianTrajectory, Orientation, PathMode, PlanError, PlanOptions, SampleCause,
    TimingOptions,
};
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{Experiment, LoopSettings, MeasurementFaults, PlantSettings};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// `[robot]`
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RobotSection {
    /// `"irb140"` or a URDF path (relative to the scenario file).
    pub model: String,
    /// Drives file (TOML) for a URDF; the built-in IRB 140 has its own.
    pub drives: Option<PathBuf>,
}

impl Default for RobotSection {
    fn default() -> Self {
        Self {
            model: "irb140".into(),
            drives: None,
        }
    }
}

/// `[payload]`: the rigid body at the flange that the controllers do not know.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PayloadSection {
    /// One run per mass and controller (kg).
    pub masses_kg: Vec<f64>,
    /// Centre of mass in the flange frame (m); default the flange centre.
    pub com_m: [f64; 3],
    /// Inertia about the centre of mass, flange axes: `[ixx, iyy, izz, ixy, ixz, iyz]` (kg·m²);
    /// default zero (a point mass).
    pub inertia_kgm2: [f64; 6],
    /// When the payload is picked up (s, path time): the plant carries none
    /// before and the payload from then on; the controllers are not told.
    /// Default: carried from the start.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pick_up_at_s: Option<f64>,
}

impl Default for PayloadSection {
    fn default() -> Self {
        Self {
            masses_kg: vec![0.0, 0.25],
            com_m: [0.0; 3],
            inertia_kgm2: [0.0; 6],
            pick_up_at_s: None,
        }
    }
}

/// `[program]`
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ProgramSection {
    /// G-code file (relative to the scenario file); default the paper's Table I program.
    pub file: Option<PathBuf>,
    /// G54 work offset (mm) for programs that set none.
    pub origin_mm: Option<[f64; 3]>,
}

/// `[timing]`
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TimingSection {
    /// `"septic"` (the paper's: acceleration a 5th-order polynomial) or `"quintic"`.
    pub profile: String,
    /// Path speed (m/s) of moves without an F word (peak under G61, cruise under G64).
    pub max_speed_m_s: f64,
    /// Path acceleration limit (m/s²).
    pub max_accel_m_s2: f64,
    /// Path jerk limit (m/s³) of blended (G64) moves.
    pub max_jerk_m_s3: f64,
    /// Corner tolerance (mm) of G64 without P.
    pub tolerance_mm: f64,
    /// Path mode of programs that select neither: `"G61"` (exact stop) or `"G64"`.
    pub mode: String,
}

impl Default for TimingSection {
    fn default() -> Self {
        let d = TimingOptions::default();
        Self {
            profile: profile_name(d.profile).into(),
            max_speed_m_s: d.max_speed,
            max_accel_m_s2: d.max_accel,
            max_jerk_m_s3: d.max_jerk,
            tolerance_mm: d.blend_tolerance * 1e3,
            mode: mode_name(d.default_mode).into(),
        }
    }
}

/// `[orientation]`
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OrientationSection {
    /// Fixed flange orientation as roll, pitch, yaw (degrees, base frame, R = Rz Ry Rx);
    /// default: the flange orientation at q = 0 (tool axis along base +x).
    pub rpy_deg: Option<[f64; 3]>,
}

/// A scenario file as written, defaults filled in.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScenarioFile {
    /// A title for the report.
    pub title: String,
    /// Which controllers to run: any of `"usual"`, `"first"`, `"second"`,
    /// `"first-adaptive"`, `"second-adaptive"`.
    pub controllers: Vec<ControllerKind>,
    /// `[robot]`
    pub robot: RobotSection,
    /// `[payload]`
    pub payload: PayloadSection,
    /// `[program]`
    pub program: ProgramSection,
    /// `[timing]`
    pub timing: TimingSection,
    /// `[orientation]`
    pub orientation: OrientationSection,
    /// `[mpc]`: the controllers' tuning (shared).
    pub mpc: MpcSettings,
    /// `[simulation]`: hold, divergence threshold, steady window.
    pub simulation: LoopSettings,
    /// `[plant]`: integration and the effects the model leaves out.
    pub plant: PlantSettings,
    /// `[faults]`: invalid and missing measurements.
    pub faults: FaultsSection,
    /// `[safety]`: the safe stop on a joint error limit.
    pub safety: SafetySection,
}

/// `[faults]`: the measurement is NaN at the samples at `nan_at_s` (s, path
/// time); no measurement arrives in the intervals `dropout_s = [[from, to], …]`.
/// The controller runs on its own prediction over them; metrics.json counts
/// them (`faults`).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FaultsSection {
    /// Times of invalid (NaN) measurements (s).
    pub nan_at_s: Vec<f64>,
    /// Intervals without a measurement, `[from, to]` (s).
    pub dropout_s: Vec<[f64; 2]>,
}

/// `[safety]`: when a joint's error passes `max_joint_error_rad`, the robot
/// brakes to rest and holds within its torque limits; the run ends "stopped".
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SafetySection {
    /// Joint error limit (rad); off when absent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_joint_error_rad: Option<f64>,
}

impl Default for ScenarioFile {
    fn default() -> Self {
        Self {
            title: "Offset-free MPC of the ABB IRB 140 on the paper's path".into(),
            controllers: ControllerKind::ALL.to_vec(),
            robot: RobotSection::default(),
            payload: PayloadSection::default(),
            program: ProgramSection::default(),
            timing: TimingSection::default(),
            orientation: OrientationSection::default(),
            mpc: MpcSettings::default(),
            simulation: LoopSettings::default(),
            plant: PlantSettings::default(),
            faults: FaultsSection::default(),
            safety: SafetySection::default(),
        }
    }
}

impl ScenarioFile {
    /// Reads a scenario. Relative paths inside (`program.file`, `robot.drives`, and
    /// `robot.model` when it ends in `.urdf` or names a file there) are resolved against the
    /// scenario file's folder, not the working directory, and made absolute: the scenario
    /// written with the results (`scenario.toml`) then re-runs from any working directory.
    pub fn from_file(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read scenario {}", path.display()))?;
        let mut s: ScenarioFile =
            toml::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        let dir = absolute(path.parent().unwrap_or(Path::new(".")));
        let resolve = |p: &Path| absolute(&dir.join(p));
        let model = resolve(Path::new(&s.robot.model));
        if s.robot.model.ends_with(".urdf") || model.is_file() {
            s.robot.model = model.display().to_string();
        }
        s.robot.drives = s.robot.drives.as_deref().map(resolve);
        s.program.file = s.program.file.as_deref().map(resolve);
        Ok(s)
    }
}

/// `p` as an absolute path (joined to the working directory if relative; `.` components
/// dropped, symbolic links not resolved). Falls back to `p` if the working directory is unknown.
pub fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

/// A resolved scenario: the experiment and what to run.
pub struct Scenario {
    /// The file it was resolved from, every default filled in (written to the
    /// output directory as `scenario.toml`, so `ofmpc run` repeats the run).
    pub file: ScenarioFile,
    /// The program's name (its path, or the built-in program's).
    pub program_name: String,
    /// The payloads (from `file.payload`, validated).
    pub payloads: Vec<Payload>,
    /// Everything but controller and payload.
    pub experiment: Experiment,
    /// The timed Cartesian path (for the paper's Fig. 4).
    pub trajectory: CartesianTrajectory,
    /// Parser warnings, to print.
    pub warnings: Vec<String>,
}

/// Loads a robot by name or URDF path, with an optional drives file.
pub fn load_robot(model: &str, drives: Option<&Path>) -> anyhow::Result<Robot> {
    let path = Path::new(model);
    let from_urdf = model.ends_with(".urdf") || path.is_file();
    let mut robot = if from_urdf {
        let robot = Robot::from_urdf_file(path)?;
        for w in robot.warnings() {
            crate::output::console::warn(&format!("{}: {w}", path.display()));
        }
        robot
    } else {
        Robot::builtin(model)?
    };
    if let Some(d) = drives {
        let drives = Drives::from_file(d)?;
        let unset = robot
            .apply_drives(&drives)
            .with_context(|| format!("applying {}", d.display()))?;
        if !unset.is_empty() {
            crate::output::console::warn(&format!(
                "{} sets nothing for joint(s) {}: they keep {}",
                d.display(),
                unset.join(", "),
                if from_urdf {
                    "the URDF's limits and have no armature"
                } else {
                    "the built-in robot's drive data"
                }
            ));
        }
    }
    Ok(robot)
}

/// The name of a profile, as [`parse_profile`] reads it.
pub const fn profile_name(p: Profile) -> &'static str {
    match p {
        Profile::Septic => "septic",
        Profile::Quintic => "quintic",
    }
}

/// The name of a path mode, as [`parse_mode`] reads it (the tolerance is a separate setting).
pub const fn mode_name(m: PathMode) -> &'static str {
    match m {
        PathMode::ExactStop => "G61",
        PathMode::Blend { .. } => "G64",
    }
}

/// Parses `septic` / `quintic`.
pub fn parse_profile(s: &str) -> anyhow::Result<Profile> {
    match s.to_ascii_lowercase().as_str() {
        "septic" | "paper" => Ok(Profile::Septic),
        "quintic" => Ok(Profile::Quintic),
        _ => bail!("profile '{s}': use 'septic' (the paper's) or 'quintic'"),
    }
}

/// Parses a path mode: `G61` (exact stop) or `G64` (blend). `what` names the setting.
pub fn parse_mode(s: &str, what: &str) -> anyhow::Result<PathMode> {
    match s.to_ascii_uppercase().as_str() {
        "G61" | "EXACT" => Ok(PathMode::ExactStop),
        "G64" | "BLEND" => Ok(PathMode::Blend { tolerance: None }),
        _ => bail!("{what} '{s}': use 'G61' (exact stop) or 'G64' (blend corners)"),
    }
}

/// How a front end names the planning settings in its messages.
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
}

/// The scenario file's names of the planning settings.
pub const SCENARIO_KEYS: SettingNames = SettingNames {
    speed: "[timing] max_speed_m_s",
    accel: "[timing] max_accel_m_s2",
    jerk: "[timing] max_jerk_m_s3",
    tolerance: "[timing] tolerance_mm",
    ts: "[mpc] ts",
    origin: "[program] origin_mm",
};

/// A planning error in the front end's words: the library's message, followed by the
/// setting (flag or key) to change where the library names one.
pub fn plan_error_message(e: &PlanError, names: &SettingNames) -> String {
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
            ReferenceFailure::Ik(_) | ReferenceFailure::BranchLimit { .. } => Some(names.origin),
            ReferenceFailure::JointSpeed { .. } => Some(names.speed),
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

/// Reads a program: a file, or the built-in paper program when `None`.
pub fn read_program(file: Option<&Path>) -> anyhow::Result<(String, String)> {
    match file {
        None => Ok((
            "paper-table1.gcode (built in)".into(),
            PAPER_TABLE1.to_string(),
        )),
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read program {}", p.display()))?;
            Ok((p.display().to_string(), text))
        }
    }
}

impl Scenario {
    /// Resolves a scenario file: loads, parses, times and maps to joint space.
    pub fn resolve(f: &ScenarioFile) -> anyhow::Result<Self> {
        if f.controllers.is_empty() {
            bail!("controllers = []: name at least one of \"usual\", \"first\", \"second\", \"first-adaptive\", \"second-adaptive\"");
        }
        if f.payload.masses_kg.is_empty() {
            bail!("payload.masses_kg = []: give at least one mass (0 for none)");
        }
        let robot = load_robot(&f.robot.model, f.robot.drives.as_deref())?;
        let n = robot.dof();
        f.mpc
            .validate_for_dof(n)
            .map_err(|e| anyhow::anyhow!("[mpc] {e}"))?;
        let mut loop_settings = f.simulation.clone();
        loop_settings.pick_up_at_s = f.payload.pick_up_at_s;
        loop_settings.max_joint_error_rad = f.safety.max_joint_error_rad;
        loop_settings.measurement_faults = MeasurementFaults {
            nan_at_s: f.faults.nan_at_s.clone(),
            dropout_s: f.faults.dropout_s.clone(),
        };
        loop_settings
            .validate()
            .map_err(|e| anyhow::anyhow!(crate::errors::experiment_error(&e.into())))?;
        f.plant
            .validate_for(n, f.mpc.ts)
            .map_err(|e| anyhow::anyhow!(crate::errors::experiment_error(&e.into())))?;
        let [ixx, iyy, izz, ixy, ixz, iyz] = f.payload.inertia_kgm2;
        let inertia = Matrix3::new(ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz);
        let mut payloads = Vec::new();
        for &m in &f.payload.masses_kg {
            let p = Payload {
                mass: m,
                com: Vector3::from(f.payload.com_m),
                inertia,
            };
            p.validate()
                .map_err(|e| anyhow::anyhow!("[payload] mass {m} kg: {e}"))?;
            payloads.push(p);
        }
        let (program_name, text) = read_program(f.program.file.as_deref())?;
        let origin = f
            .program
            .origin_mm
            .map(|o| [o[0] * 1e-3, o[1] * 1e-3, o[2] * 1e-3]);
        let orientation = match f.orientation.rpy_deg {
            None => Orientation::AtZero,
            Some([r, p, y]) => Orientation::Fixed(UnitQuaternion::from_euler_angles(
                r.to_radians(),
                p.to_radians(),
                y.to_radians(),
            )),
        };
        let options = PlanOptions {
            parse: ParseOptions { origin },
            timing: TimingOptions {
                profile: parse_profile(&f.timing.profile)?,
                max_speed: f.timing.max_speed_m_s,
                max_accel: f.timing.max_accel_m_s2,
                max_jerk: f.timing.max_jerk_m_s3,
                blend_tolerance: f.timing.tolerance_mm * 1e-3,
                default_mode: parse_mode(&f.timing.mode, "[timing] mode")?,
            },
            orientation,
            ts: f.mpc.ts,
        };
        let planned = plan(&text, &robot, &options).map_err(|e| {
            anyhow::anyhow!("{program_name}: {}", plan_error_message(&e, &SCENARIO_KEYS))
        })?;
        let mut warnings: Vec<String> = planned
            .program
            .warnings
            .iter()
            .map(|w| format!("{program_name}: {w}"))
            .collect();
        if f.mpc.observer_friction && !(f.mpc.state_observer || f.mpc.delay_compensation) {
            warnings.push(
                "[mpc] observer_friction = true without an observer (state_observer or \
                 delay_compensation): it has no effect"
                    .into(),
            );
        }
        if f.mpc.friction_compensation {
            let d = ofmpc::control::DriveModel::from_robot(&robot);
            if d.coulomb_nm.iter().chain(&d.viscous_nms).all(|v| *v == 0.0) {
                warnings.push(
                    "[mpc] friction_compensation = true but the robot's drives give no friction \
                     estimate (coulomb_nm, viscous_nms): nothing is compensated"
                        .into(),
                );
            }
        }
        if let Some(w) = friction_substep_warning(
            &robot,
            &f.plant,
            reference_start(&planned.reference),
            f.mpc.ts,
        ) {
            warnings.push(w);
        }
        let (trajectory, reference) = (planned.trajectory, planned.reference);
        let experiment = Experiment {
            robot,
            reference,
            mpc: f.mpc.clone(),
            plant: f.plant.clone(),
            loop_settings,
        };
        experiment.validate().map_err(|e| {
            anyhow::anyhow!("{program_name}: {}", crate::errors::experiment_error(&e))
        })?;
        Ok(Self {
            file: f.clone(),
            program_name,
            payloads,
            experiment,
            trajectory,
            warnings,
        })
    }
}

/// The path's first joint position (where the plant starts).
fn reference_start(reference: &ofmpc::motion::JointReference) -> &[f64] {
    reference.q(0)
}

/// A warning when the plant's RK4 substep is too coarse for its smoothed
/// Coulomb friction: more than 4 of the friction's time constants at rest
/// ([`ofmpc::sim::Plant::coulomb_time_constant`] at the path's start; measured
/// on the IRB 140: converged from 4τ, steady errors 1e4 times off at 20τ).
fn friction_substep_warning(
    robot: &ofmpc::robot::Robot,
    plant: &PlantSettings,
    q0: &[f64],
    ts: f64,
) -> Option<String> {
    if plant.coulomb_friction.iter().all(|c| *c <= 0.0) {
        return None;
    }
    let mut p = ofmpc::sim::Plant::new(robot.clone(), plant.clone(), q0).ok()?;
    let tau = p.coulomb_time_constant().ok()??;
    if plant.substep <= 4.0 * tau {
        return None;
    }
    // The largest substep ≤ 4τ that divides the control period.
    let suggest = ts / (ts / (4.0 * tau)).ceil();
    Some(format!(
        "[plant] substep = {} s is coarser than 4 time constants of the Coulomb friction at rest \
         (τ = {tau:.1e} s = min H_ii·coulomb_velocity/coulomb_friction): a joint's sticking is not \
         resolved and steady errors are not to be trusted; use substep = {suggest:.3e} s or smaller",
        plant.substep
    ))
}
