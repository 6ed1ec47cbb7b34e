//! The scenario file (TOML) as written, defaults filled in: [`ScenarioFile`]
//! and its sections. The sections that configure the library are the
//! library's own settings types, deserialized as they are (`[mpc]` =
//! [`MpcSettings`], `[simulation]` = [`LoopSettings`], `[plant]` =
//! [`PlantSettings`], `[faults]` = [`MeasurementFaults`], `[safety]` =
//! [`ofmpc::sim::SafetySettings`], `[baselines]` = [`BaselineSettings`]; with
//! `[payload]`'s pick-up time `[faults]` and `[safety]` are the run's
//! [`RunConditions`], [`ScenarioFile::run_conditions`]). Overrides ([`Override`], `key=value` with a dotted key)
//! are applied to the document before it is deserialized, so they meet the
//! same checks and messages as the key written in the file.

use crate::error::ScenarioError;
use ofmpc::control::{BaselineSettings, ControllerKind, MpcSettings};
use ofmpc::gcode::PathMode;
use ofmpc::motion::Profile;
use ofmpc::motion::TimingOptions;
use ofmpc::sim::{LoopSettings, MeasurementFaults, PlantSettings, RunConditions};
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
    /// The start pose (rad; m for a prismatic joint), one value per joint, within the
    /// limits: the robot's initial state and the inverse kinematics' first seed. Default
    /// q = 0 where that is inside the limits, else the limits' centre.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start_q: Option<Vec<f64>>,
    /// The URDF link that ends the chain (the flange): joints beyond it, or on other
    /// branches, are held rigid, so a hand with fingers loads. Default: the one path of
    /// moving joints, ending at `tool0`, `flange` or an end-effector link if there is one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tip: Option<String>,
    /// Tool centre point relative to the tip (mm, tip frame): planning, IK, metrics and
    /// figures use it. Default: the tip itself.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tcp_mm: Option<[f64; 3]>,
    /// Orientation of the tool centre point relative to the tip, roll, pitch, yaw (degrees,
    /// R = Rz Ry Rx). Default none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tcp_rpy_deg: Option<[f64; 3]>,
}

impl Default for RobotSection {
    fn default() -> Self {
        Self {
            model: "irb140".into(),
            drives: None,
            start_q: None,
            tip: None,
            tcp_mm: None,
            tcp_rpy_deg: None,
        }
    }
}

impl RobotSection {
    /// The chain options of `tip`, `tcp_mm` and `tcp_rpy_deg`.
    pub fn chain_options(&self) -> ofmpc::robot::ChainOptions {
        let tcp = (self.tcp_mm.is_some() || self.tcp_rpy_deg.is_some()).then(|| {
            let p = self.tcp_mm.unwrap_or([0.0; 3]);
            let r = self.tcp_rpy_deg.unwrap_or([0.0; 3]);
            ofmpc::spatial::Transform::from_xyz_rpy(
                [p[0] * 1e-3, p[1] * 1e-3, p[2] * 1e-3],
                [r[0].to_radians(), r[1].to_radians(), r[2].to_radians()],
            )
        });
        ofmpc::robot::ChainOptions {
            tip: self.tip.clone(),
            tcp,
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
    /// Tool table (LinuxCNC's .tbl format, lengths in mm; relative to the scenario file)
    /// for `G43 H<n>`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tool_table: Option<PathBuf>,
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

/// The title of a scenario that sets none. A run of another robot or program than the
/// paper's is titled after the robot and program that ran instead
/// ([`crate::Scenario::resolve`]).
pub const DEFAULT_TITLE: &str = "Offset-free MPC of the ABB IRB 140 on the paper's path";

/// A scenario file as written, defaults filled in.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScenarioFile {
    /// A title for the report.
    pub title: String,
    /// Which controllers to run: any of `"usual"`, `"first"`, `"second"`,
    /// `"first-adaptive"`, `"second-adaptive"`, and the baselines `"pid"`,
    /// `"ctc"`, `"ctc-adaptive"`, `"dob-mpc"`; `"all"` stands for every one
    /// ([`ControllerKind::ALL`]), `"baselines"` for the four baselines.
    #[serde(deserialize_with = "controllers_with_shorthands")]
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
    /// `[baselines]`: the baseline controllers' bandwidths (rad/s; a number
    /// or one per joint): `pid_bandwidth`, `ctc_bandwidth`,
    /// `dob_observer_bandwidth`; the run's [`ofmpc::sim::Experiment::baselines`]
    /// as read. Written with the results only when set.
    #[serde(skip_serializing_if = "is_default_baselines")]
    pub baselines: BaselineSettings,
    /// `[output]`: how much of each run's time series is written. Written with the results
    /// only when set.
    #[serde(skip_serializing_if = "is_default_output")]
    pub output: OutputSection,
}

fn is_default_output(o: &OutputSection) -> bool {
    *o == OutputSection::default()
}

/// `[output] timeseries`: which samples of each run `timeseries.csv` holds. The metrics
/// and figures use every sample whatever is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum TimeseriesOutput {
    /// Every sample when a run's file stays within [`AUTO_TIMESERIES_BYTES`], else decimated.
    #[default]
    Auto,
    /// Every sample, whatever the size.
    Full,
    /// Every `stride`-th sample (default: the stride that keeps a run's file within
    /// [`AUTO_TIMESERIES_BYTES`]), the last sample always included.
    Decimated,
    /// No `timeseries.csv`.
    None,
}

/// The size (bytes) a run's `timeseries.csv` keeps under `[output] timeseries = "auto"`
/// (and "decimated" without a stride): 12 MB, so a 30-minute path with two payloads and
/// the paper's three controllers writes well under 100 MB.
pub const AUTO_TIMESERIES_BYTES: u64 = 12_000_000;

/// The size (bytes) all runs' `timeseries.csv` keep together under `"auto"` when there are
/// many runs ([`OutputSection::timeseries_stride_of`]): 48 MB, so that `reproduce --compare`
/// (45 runs) writes tens of MB, not 80 (issue #38).
pub const AUTO_TIMESERIES_TOTAL_BYTES: u64 = 48_000_000;

/// `[output]`
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputSection {
    /// `"auto"` (the default), `"full"`, `"decimated"` or `"none"` ([`TimeseriesOutput`]).
    pub timeseries: TimeseriesOutput,
    /// Under `"decimated"`: write every `stride`-th sample (at least 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stride: Option<std::num::NonZeroUsize>,
}

impl OutputSection {
    /// The stride of the time series of a run of `rows` samples whose file would take
    /// `bytes_per_row` bytes a row: `None` for no file, `Some(1)` for every sample.
    pub fn timeseries_stride(&self, rows: usize, bytes_per_row: u64) -> Option<usize> {
        self.timeseries_stride_of(rows, bytes_per_row, 1)
    }

    /// [`Self::timeseries_stride`] for one of `runs` runs written together: under `"auto"`
    /// a run keeps at most [`AUTO_TIMESERIES_BYTES`] and the runs together at most
    /// [`AUTO_TIMESERIES_TOTAL_BYTES`] (the smaller share wins).
    pub fn timeseries_stride_of(
        &self,
        rows: usize,
        bytes_per_row: u64,
        runs: usize,
    ) -> Option<usize> {
        let budget = AUTO_TIMESERIES_BYTES.min(AUTO_TIMESERIES_TOTAL_BYTES / runs.max(1) as u64);
        let auto = || {
            let total = rows as u64 * bytes_per_row;
            (total.div_ceil(budget.max(1)).max(1)) as usize
        };
        match self.timeseries {
            TimeseriesOutput::None => None,
            TimeseriesOutput::Full => Some(1),
            TimeseriesOutput::Auto => Some(auto()),
            TimeseriesOutput::Decimated => Some(self.stride.map_or_else(auto, |s| s.get())),
        }
    }
}

fn is_default_baselines(b: &BaselineSettings) -> bool {
    *b == BaselineSettings::default()
}

/// A controller name, or a shorthand for several (`"all"`, `"baselines"`).
#[derive(Deserialize)]
#[serde(untagged)]
enum ControllerName {
    Kind(ControllerKind),
    Shorthand(String),
}

/// `controllers = [...]` with the shorthands `"all"` (every controller) and
/// `"baselines"` expanded in place; repeats are kept (the runner removes them).
fn controllers_with_shorthands<'de, D>(d: D) -> Result<Vec<ControllerKind>, D::Error>
where
    D: serde::Deserializer<'de>,
{
    let names = Vec::<ControllerName>::deserialize(d)?;
    let mut out = Vec::new();
    for name in names {
        match name {
            ControllerName::Kind(k) => out.push(k),
            ControllerName::Shorthand(s) => match expand_shorthand(&s) {
                Some(kinds) => out.extend_from_slice(kinds),
                None => {
                    return Err(serde::de::Error::custom(format!(
                        "unknown controller {s:?}: expected one of {}, or \"all\", \"baselines\"",
                        ControllerKind::ALL
                            .iter()
                            .map(|k| format!("\"{k}\""))
                            .collect::<Vec<_>>()
                            .join(", ")
                    )))
                }
            },
        }
    }
    Ok(out)
}

/// The kinds a shorthand stands for: `"all"` every controller,
/// `"baselines"` the four baselines, `"paper"` the paper's three.
pub fn expand_shorthand(s: &str) -> Option<&'static [ControllerKind]> {
    match s.trim().to_ascii_lowercase().as_str() {
        "all" => Some(&ControllerKind::ALL),
        "baselines" => Some(&ControllerKind::BASELINES),
        "paper" => Some(&ControllerKind::PAPER),
        _ => None,
    }
}

/// `[faults]`: the measurement is NaN at the samples at `nan_at_s` (s, path
/// time); no measurement arrives in the intervals `dropout_s = [[from, to], …]`.
/// The controller runs on its own prediction over them; metrics.json counts
/// them (`faults`). The library's type, deserialized as it is.
pub type FaultsSection = MeasurementFaults;

/// `[safety]`: when a joint's error passes `max_joint_error_rad`, the robot
/// brakes to rest and holds within its torque limits; the run ends "stopped".
/// The library's type, deserialized as it is.
pub type SafetySection = ofmpc::sim::SafetySettings;

impl Default for ScenarioFile {
    fn default() -> Self {
        Self {
            title: DEFAULT_TITLE.into(),
            controllers: ControllerKind::PAPER.to_vec(),
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
            baselines: BaselineSettings::default(),
            output: OutputSection::default(),
        }
    }
}

impl ScenarioFile {
    /// Reads a scenario. Relative paths inside (`program.file`, `robot.drives`, and
    /// `robot.model` when it ends in `.urdf` or names a file there) are resolved against the
    /// scenario file's folder, not the working directory, and made absolute: the scenario
    /// written with the results (`scenario.toml`) then re-runs from any working directory.
    pub fn from_file(path: &Path) -> Result<Self, ScenarioError> {
        Self::from_file_with(path, &[])
    }

    /// Reads a scenario as [`ScenarioFile::from_file`] does, with `overrides` applied to
    /// the document before it is deserialized (in order; a later one wins). A path set by
    /// an override is relative to the working directory, not to the scenario's folder.
    pub fn from_file_with(path: &Path, overrides: &[Override]) -> Result<Self, ScenarioError> {
        let text =
            read_text_limited(path, MAX_SCENARIO_BYTES).map_err(|source| ScenarioError::Read {
                path: path.to_path_buf(),
                source,
            })?;
        let parse_error = |e: toml::de::Error| ScenarioError::Parse {
            origin: path.display().to_string(),
            message: plain_types(&e.to_string()),
        };
        // The sections' shapes first (an array is never read by position), then the file
        // alone: its errors carry their line and column.
        let doc: toml::Table = toml::from_str(&text).map_err(parse_error)?;
        check_sections(doc.iter().map(|(k, v)| (k.as_str(), toml_kind(v)))).map_err(|message| {
            ScenarioError::Parse {
                origin: path.display().to_string(),
                message,
            }
        })?;
        let mut s: ScenarioFile = toml::from_str(&text).map_err(parse_error)?;
        if !overrides.is_empty() {
            let doc: toml::Table = toml::from_str(&text).map_err(parse_error)?;
            s = apply_overrides(doc, overrides)?;
        }
        s.resolve_paths(path, overrides);
        Ok(s)
    }

    /// Makes the paths of the file (robot, drives, plant robot and drives, program, tool
    /// table) absolute: against the folder of `file`, or the working directory for a path set
    /// by one of `overrides`; a built-in model's name stays a name.
    fn resolve_paths(&mut self, file: &Path, overrides: &[Override]) {
        let dir = absolute(file.parent().unwrap_or(Path::new(".")));
        let set = |key: &str| overrides.iter().any(|o| o.key == key);
        let base = |key: &str| {
            if set(key) {
                absolute(Path::new("."))
            } else {
                dir.clone()
            }
        };
        let resolve = |key: &str, p: &Path| absolute(&base(key).join(p));
        let model = resolve("robot.model", Path::new(&self.robot.model));
        let builtin = ofmpc::robot::Robot::builtin(&self.robot.model).is_ok();
        if self.robot.model.ends_with(".urdf")
            || self.robot.model.contains(['/', std::path::MAIN_SEPARATOR])
            || (!builtin && model.is_file())
        {
            self.robot.model = model.display().to_string();
        }
        self.robot.drives = self
            .robot
            .drives
            .as_deref()
            .map(|p| resolve("robot.drives", p));
        for (key, p) in [
            ("plant.robot", &mut self.plant.robot),
            ("plant.drives", &mut self.plant.drives),
        ] {
            let builtin = p
                .as_deref()
                .and_then(Path::to_str)
                .is_some_and(|m| ofmpc::robot::Robot::builtin(m).is_ok());
            if !builtin {
                *p = p.as_deref().map(|p| resolve(key, p));
            }
        }
        self.program.file = self
            .program
            .file
            .as_deref()
            .map(|p| resolve("program.file", p));
        self.program.tool_table = self
            .program
            .tool_table
            .as_deref()
            .map(|p| resolve("program.tool_table", p));
    }

    /// This scenario with `overrides` applied (as to a file's document; a path set by one
    /// is made absolute against the working directory).
    pub fn with_overrides(&self, overrides: &[Override]) -> Result<Self, ScenarioError> {
        if overrides.is_empty() {
            return Ok(self.clone());
        }
        let write_error = |message: String| ScenarioError::Write {
            what: "the scenario",
            message,
        };
        let doc = match toml::Value::try_from(self).map_err(|e| write_error(e.to_string()))? {
            toml::Value::Table(t) => t,
            other => return Err(write_error(format!("a {}, not a table", other.type_str()))),
        };
        let mut s = apply_overrides(doc, overrides)?;
        let set = |key: &str| overrides.iter().any(|o| o.key == key);
        if set("robot.model")
            && (s.robot.model.ends_with(".urdf") || Path::new(&s.robot.model).is_file())
        {
            s.robot.model = absolute(Path::new(&s.robot.model)).display().to_string();
        }
        if set("robot.drives") {
            s.robot.drives = s.robot.drives.as_deref().map(absolute);
        }
        if set("plant.robot") {
            let builtin = s
                .plant
                .robot
                .as_deref()
                .and_then(Path::to_str)
                .is_some_and(|m| ofmpc::robot::Robot::builtin(m).is_ok());
            if !builtin {
                s.plant.robot = s.plant.robot.as_deref().map(absolute);
            }
        }
        if set("plant.drives") {
            s.plant.drives = s.plant.drives.as_deref().map(absolute);
        }
        if set("program.file") {
            s.program.file = s.program.file.as_deref().map(absolute);
        }
        if set("program.tool_table") {
            s.program.tool_table = s.program.tool_table.as_deref().map(absolute);
        }
        Ok(s)
    }

    /// The closed loop's settings: `[simulation]` as it is.
    pub fn loop_settings(&self) -> LoopSettings {
        self.simulation.clone()
    }

    /// The run's conditions, each section as it is: the pick-up time of
    /// `[payload]`, `[safety]` and `[faults]` (no horizon recorded).
    pub fn run_conditions(&self) -> RunConditions {
        RunConditions {
            pick_up_at_s: self.payload.pick_up_at_s,
            safety: self.safety.clone(),
            faults: self.faults.clone(),
            horizons: None,
        }
    }

    /// The drive, sensor and fault effects this scenario turns on, in its keys' words
    /// (empty: the paper's ideal drives and sensors).
    pub fn effects(&self) -> Vec<String> {
        let (mpc, plant, sim) = (&self.mpc, &self.plant, &self.simulation);
        let mut e = Vec::new();
        let mut on = |cond: bool, text: String| {
            if cond {
                e.push(text);
            }
        };
        on(
            mpc.torque_limits,
            "[mpc] torque_limits (QP over the horizon)".into(),
        );
        on(
            mpc.friction_compensation,
            "[mpc] friction_compensation".into(),
        );
        on(mpc.delay_compensation, "[mpc] delay_compensation".into());
        on(mpc.state_observer, "[mpc] state_observer".into());
        on(mpc.observer_friction, "[mpc] observer_friction".into());
        on(mpc.friction_creep, "[mpc] friction_creep".into());
        on(mpc.identify_at_rest, "[mpc] identify_at_rest".into());
        on(
            mpc.identification_raw_mass,
            "[mpc] identification_raw_mass".into(),
        );
        on(mpc.friction_coupled, "[mpc] friction_coupled".into());
        on(
            mpc.payload_com_max_m > 0.0,
            format!("[mpc] payload_com_max_m = {} m", mpc.payload_com_max_m),
        );
        plant_effects(plant, &mut on);
        on(
            !self.faults.nan_at_s.is_empty(),
            format!("[faults] nan_at_s = {:?}", self.faults.nan_at_s),
        );
        on(
            !self.faults.dropout_s.is_empty(),
            format!("[faults] dropout_s = {:?}", self.faults.dropout_s),
        );
        on(
            sim.plausibility_check,
            "[simulation] plausibility_check".into(),
        );
        on(sim.safe_stop, "[simulation] safe_stop".into());
        if let Some(v) = self.safety.max_joint_error_rad {
            e.push(format!("[safety] max_joint_error_rad = {v}"));
        }
        e
    }

    /// Whether the runs record the measurement the controller was given apart from the
    /// true state (the plant's sensing is not ideal, or `[faults]` sets some): their
    /// records then have [`ofmpc::sim::Record::has_measurement`].
    pub fn records_measurement(&self) -> bool {
        ofmpc::sim::records_measurement(&self.plant, &self.faults)
    }

    /// The scenario as TOML text, every default filled in.
    pub fn to_toml(&self) -> Result<String, ScenarioError> {
        toml::to_string(self).map_err(|e| ScenarioError::Write {
            what: "the scenario",
            message: e.to_string(),
        })
    }
}

/// The `[plant]` part of [`ScenarioFile::effects`]: `on(condition, text)` for each setting.
fn plant_effects(plant: &PlantSettings, on: &mut dyn FnMut(bool, String)) {
    on(
        plant.torque_limits,
        "[plant] torque_limits (saturation)".into(),
    );
    on(
        !plant.coulomb_friction.is_empty(),
        format!(
            "[plant] coulomb_friction = {:?} N·m",
            plant.coulomb_friction
        ),
    );
    on(
        !plant.viscous_friction.is_empty(),
        format!(
            "[plant] viscous_friction = {:?} N·m·s/rad",
            plant.viscous_friction
        ),
    );
    sensor_effects(plant, on);
    on(
        plant.inertia_error > 0.0,
        format!(
            "[plant] inertia_error = {} (seed {})",
            plant.inertia_error, plant.seed
        ),
    );
    on(
        !plant.stribeck_friction.is_empty(),
        format!(
            "[plant] stribeck_friction = {:?} N·m",
            plant.stribeck_friction
        ),
    );
    for (key, path) in [("robot", &plant.robot), ("drives", &plant.drives)] {
        on(
            path.is_some(),
            format!(
                "[plant] {key} = {}",
                path.as_deref().unwrap_or(Path::new("")).display()
            ),
        );
    }
    on(
        !plant.faults.is_empty(),
        format!("[plant] faults ({})", plant.faults.len()),
    );
}

/// The sensing part of [`plant_effects`]: encoder, delay and noise.
fn sensor_effects(plant: &PlantSettings, on: &mut dyn FnMut(bool, String)) {
    on(
        plant.encoder_counts > 0,
        format!("[plant] encoder_counts = {}", plant.encoder_counts),
    );
    on(
        plant.velocity_from_encoder,
        "[plant] velocity_from_encoder".into(),
    );
    on(
        plant.delay_samples > 0,
        format!("[plant] delay_samples = {}", plant.delay_samples),
    );
    on(
        plant.position_noise > 0.0 || plant.velocity_noise > 0.0,
        "[plant] measurement noise".into(),
    );
}

/// One override of a scenario key: `key=value`, the key a dotted path into the
/// document (`mpc.horizon`, `plant.substep`, `title`), the value a TOML value
/// (`20`, `1e-3`, `true`, `[1.0, 2.0]`, `"text"`) or, when it does not parse as
/// one, a string (`G64`).
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// The dotted key.
    pub key: String,
    /// The value as given.
    pub raw: String,
    /// The value.
    pub value: toml::Value,
}

impl std::str::FromStr for Override {
    type Err = ScenarioError;

    fn from_str(text: &str) -> Result<Self, ScenarioError> {
        let syntax = || ScenarioError::OverrideSyntax { text: text.into() };
        let (key, raw) = text.split_once('=').ok_or_else(syntax)?;
        let key = key.trim();
        if key.split('.').any(|part| part.trim().is_empty()) {
            return Err(syntax());
        }
        let key: String = key.split('.').map(str::trim).collect::<Vec<_>>().join(".");
        let raw = raw.trim();
        let value = toml::from_str::<toml::Table>(&format!("v = {raw}"))
            .ok()
            .and_then(|mut t| t.remove("v"));
        // A whole number TOML cannot hold is too large, not a string (issue #36).
        let digits = raw.strip_prefix(['+', '-']).unwrap_or(raw).replace('_', "");
        if value.is_none() && !digits.is_empty() && digits.bytes().all(|c| c.is_ascii_digit()) {
            return Err(ScenarioError::Override {
                key,
                value: ofmpc::input::quote(raw, ofmpc::input::QUOTE_CHARS),
                message: format!(
                    "too large: a whole number here is at most {} (TOML's 64-bit integers)",
                    i64::MAX
                ),
            });
        }
        let value = value.unwrap_or_else(|| toml::Value::String(raw.into()));
        Ok(Self {
            key,
            raw: raw.into(),
            value,
        })
    }
}

/// The largest scenario file read (bytes): 4 MiB, far above any real scenario.
pub const MAX_SCENARIO_BYTES: u64 = 4 << 20;

/// The largest G-code program read (bytes): 64 MiB (several million lines; a reference of
/// that length would already pass the recorder's limit at the paper's sample time).
pub const MAX_PROGRAM_BYTES: u64 = 64 << 20;

/// Reads a text file of at most `limit` bytes: stops reading past the limit (a `/dev/zero` or
/// a runaway file is never read whole) and says the limit; text that is not UTF-8 is an error
/// naming the byte offset, line and column of the first bad byte and the encoding to use.
/// Errors are of kind `InvalidData` (the caller adds the file's name); a named pipe, a device
/// or a folder is refused without waiting, saying what it is ([`ofmpc::input::open_regular`]).
pub fn read_text_limited(path: &Path, limit: u64) -> std::io::Result<String> {
    let bytes = match ofmpc::input::read_limited(path, limit) {
        Ok(b) => b,
        Err(ofmpc::input::ReadLimitedError::Io(e)) => return Err(e),
        Err(ofmpc::input::ReadLimitedError::TooLarge { .. }) => {
            return Err(too_large(limit));
        }
    };
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let b = e.as_bytes();
        let line = b[..at].iter().filter(|&&c| c == b'\n').count() + 1;
        let col = at
            - b[..at]
                .iter()
                .rposition(|&c| c == b'\n')
                .map_or(0, |i| i + 1)
            + 1;
        let (hint, from) = if b.starts_with(&[0xff, 0xfe]) || b.starts_with(&[0xfe, 0xff]) {
            ("it looks like UTF-16", "UTF-16")
        } else {
            ("it may be Latin-1 or another 8-bit encoding", "LATIN1")
        };
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "not UTF-8 text: byte {at} (line {line}, column {col}) is 0x{:02x} ({hint}): save \
                 it as UTF-8 (e.g. iconv -f {from} -t UTF-8)",
                b[at]
            ),
        )
    })
}

/// The error for a file past its byte limit.
fn too_large(limit: u64) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        format!(
            "it is larger than the limit of {limit} bytes ({} MiB; reading stopped there): \
             split it, or check that it is the file you meant",
            limit >> 20
        ),
    )
}

/// A deserializer's message with Rust type names in words ("expected usize" → "expected a
/// whole number ≥ 0").
pub(crate) fn plain_types(message: &str) -> String {
    let mut m = message.to_string();
    for (rust, words) in [
        ("expected usize", "expected a whole number ≥ 0"),
        ("expected u64", "expected a whole number ≥ 0"),
        ("expected u32", "expected a whole number ≥ 0"),
        ("expected a nonzero usize", "expected a whole number ≥ 1"),
        ("expected f64", "expected a number"),
    ] {
        m = m.replace(rust, words);
    }
    short_snippet(&m)
}

/// The longest source line a TOML error's snippet keeps whole (characters).
const SNIPPET_CHARS: usize = 80;

/// `message` (a TOML error: a header naming `line L, column C`, then the source line and a
/// caret line, each after `| `) with each snippet line longer than [`SNIPPET_CHARS`] cut to
/// a window around column C, so that a huge line of input makes a short message.
fn short_snippet(message: &str) -> String {
    let column = message
        .split_once("column ")
        .and_then(|(_, r)| r.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|c| c.parse::<usize>().ok())
        .unwrap_or(1);
    let from = column.saturating_sub(40);
    let lines: Vec<String> = message
        .split('\n')
        .map(|line| match line.split_once("| ") {
            Some((prefix, rest)) if rest.chars().count() > SNIPPET_CHARS => {
                let n = rest.chars().count();
                let window: String = rest.chars().skip(from).take(SNIPPET_CHARS - 20).collect();
                let head = if from > 0 { "…" } else { "" };
                let tail = if from + SNIPPET_CHARS - 20 < n {
                    "…"
                } else {
                    ""
                };
                format!("{prefix}| {head}{window}{tail}")
            }
            _ => line.to_string(),
        })
        .collect();
    lines.join("\n")
}

/// The scenario's sections: each a table of keys. A derived deserializer would also read a
/// section from an array, by position (`mpc = [0.02, 3]` as ts and horizon): refused instead.
const SECTIONS: [&str; 11] = [
    "output",
    "robot",
    "payload",
    "program",
    "timing",
    "orientation",
    "mpc",
    "simulation",
    "plant",
    "faults",
    "safety",
];

/// What a TOML value is, in words (`table` for a table).
fn toml_kind(v: &toml::Value) -> &'static str {
    match v {
        toml::Value::Table(_) => "table",
        toml::Value::Array(_) => "an array",
        toml::Value::String(_) => "a string",
        toml::Value::Boolean(_) => "a boolean",
        toml::Value::Datetime(_) => "a date",
        _ => "a number",
    }
}

/// Checks that every section among the top-level `(key, type)` pairs of a document is a table
/// (`"table"` in TOML, `"object"` in JSON); the message names the key.
fn check_sections<'a>(top: impl Iterator<Item = (&'a str, &'a str)>) -> Result<(), String> {
    for (key, kind) in top {
        if SECTIONS.contains(&key) && kind != "table" && kind != "object" {
            return Err(format!(
                "{key} is written as {kind} (`{key} = …`), but [{key}] is a section: a table of \
                 named keys (`[{key}]` followed by `key = value` lines, or a dict in JSON); \
                 examples/scenario.toml lists every key"
            ));
        }
    }
    Ok(())
}

impl ScenarioFile {
    /// Reads a scenario from JSON text with the keys of the TOML file (as `ofmpc.run` gives a
    /// dict); a section written as anything but an object is refused, naming it.
    pub fn from_json(text: &str) -> Result<Self, ScenarioError> {
        let error = |message: String| ScenarioError::Parse {
            origin: "scenario".into(),
            message,
        };
        // The JSON position means nothing to the caller (it wrote a dict).
        let plain = |e: serde_json::Error| {
            let m = e.to_string();
            plain_types(m.split(" at line ").next().unwrap_or(&m))
        };
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| error(plain(e)))?;
        if let serde_json::Value::Object(top) = &value {
            check_sections(top.iter().map(|(k, v)| {
                let kind = match v {
                    serde_json::Value::Object(_) => "object",
                    serde_json::Value::Array(_) => "an array",
                    serde_json::Value::Null => "null",
                    serde_json::Value::Bool(_) => "a boolean",
                    serde_json::Value::Number(_) => "a number",
                    serde_json::Value::String(_) => "a string",
                };
                (k.as_str(), kind)
            }))
            .map_err(error)?;
        }
        serde_json::from_value(value).map_err(|e| error(plain(e)))
    }
}

/// Sets `o` in `doc` (tables on the way are made when absent).
fn set_key(doc: &mut toml::Table, o: &Override) -> Result<(), ScenarioError> {
    let error = |message: String| ScenarioError::Override {
        key: o.key.clone(),
        value: o.raw.clone(),
        message,
    };
    let parts: Vec<&str> = o.key.split('.').collect();
    let (last, path) = parts
        .split_last()
        .ok_or_else(|| error("empty key".into()))?;
    let mut table = doc;
    for (i, part) in path.iter().enumerate() {
        let entry = table
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        table = match entry {
            toml::Value::Table(t) => t,
            other => {
                return Err(error(format!(
                    "{} is not a table (its value is of type {})",
                    parts[..=i].join("."),
                    other.type_str()
                )))
            }
        };
    }
    table.insert(last.to_string(), o.value.clone());
    Ok(())
}

/// Applies `overrides` in order to `doc` and deserializes the result; an override that
/// does not fit is reported with its key and value and the deserializer's message (the
/// message the key written in the file gets, without the file position).
fn apply_overrides(
    mut doc: toml::Table,
    overrides: &[Override],
) -> Result<ScenarioFile, ScenarioError> {
    let mut file = None;
    for o in overrides {
        set_key(&mut doc, o)?;
        check_sections(doc.iter().map(|(k, v)| (k.as_str(), toml_kind(v)))).map_err(|message| {
            ScenarioError::Override {
                key: o.key.clone(),
                value: o.raw.clone(),
                message,
            }
        })?;
        let parsed = ScenarioFile::deserialize(toml::Value::Table(doc.clone())).map_err(|e| {
            ScenarioError::Override {
                key: o.key.clone(),
                value: o.raw.clone(),
                message: plain_types(e.message().trim_end()),
            }
        })?;
        file = Some(parsed);
    }
    match file {
        Some(f) => Ok(f),
        None => {
            ScenarioFile::deserialize(toml::Value::Table(doc)).map_err(|e| ScenarioError::Parse {
                origin: "scenario".into(),
                message: plain_types(e.message().trim_end()),
            })
        }
    }
}

/// `p` as an absolute path (joined to the working directory if relative; `.` components
/// dropped, symbolic links not resolved). Falls back to `p` if the working directory is unknown.
pub fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
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
pub fn parse_profile(s: &str) -> Result<Profile, ScenarioError> {
    match s.to_ascii_lowercase().as_str() {
        "septic" | "paper" => Ok(Profile::Septic),
        "quintic" => Ok(Profile::Quintic),
        _ => Err(ScenarioError::Profile {
            key: "profile".into(),
            value: s.into(),
        }),
    }
}

/// Parses a path mode: `G61` (exact stop) or `G64` (blend). `what` names the setting.
pub fn parse_mode(s: &str, what: &str) -> Result<PathMode, ScenarioError> {
    match s.to_ascii_uppercase().as_str() {
        "G61" | "EXACT" => Ok(PathMode::ExactStop),
        "G64" | "BLEND" => Ok(PathMode::Blend { tolerance: None }),
        _ => Err(ScenarioError::Mode {
            key: what.into(),
            value: s.into(),
        }),
    }
}
