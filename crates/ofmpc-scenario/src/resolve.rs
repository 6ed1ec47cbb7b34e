//! The resolved scenario: robot loaded, program parsed and timed, reference
//! built, every setting checked ([`Scenario::resolve`]).

use crate::error::ScenarioError;
use crate::file::{parse_mode, parse_profile, ScenarioFile};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use ofmpc::control::ControllerKind;
use ofmpc::gcode::{ParseOptions, ToolTable, PAPER_TABLE1};
use ofmpc::motion::{plan, CartesianTrajectory, Orientation, PlanOptions, TimingOptions};
use ofmpc::robot::{ChainOptions, Drives, Payload, Robot};
use ofmpc::sim::{Experiment, PlantError, PlantSettings, MAX_SUBSTEPS};
use std::path::Path;

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
    /// Warnings to show: the robot's (URDF, drives file), the parser's, and settings
    /// that have no effect or are not to be trusted.
    pub warnings: Vec<String>,
}

/// Whether a `[robot] model` value names a file rather than a built-in robot: a path (it
/// holds a folder separator or ends in `.urdf`), or a name no built-in robot has that names an
/// existing file. A built-in name (`irb140`) always means the built-in robot, even when a file
/// of that name lies in the working directory or the scenario's folder.
pub fn is_model_path(model: &str) -> bool {
    model.ends_with(".urdf")
        || model.contains('/')
        || model.contains(std::path::MAIN_SEPARATOR)
        || (Robot::builtin(model).is_err() && Path::new(model).is_file())
}

/// Loads a robot by name or URDF path, with an optional drives file. Returns the robot
/// and the warnings to show (the URDF's, joints the drives file leaves unset).
pub fn load_robot(
    model: &str,
    drives: Option<&Path>,
) -> Result<(Robot, Vec<String>), ScenarioError> {
    load_robot_with(model, drives, &ChainOptions::default())
}

/// Loads the robot of a `[robot]` section: model, drives, tip, tool centre point and start
/// pose. Returns the robot and the warnings to show.
pub fn load_robot_section(
    section: &crate::file::RobotSection,
) -> Result<(Robot, Vec<String>), ScenarioError> {
    let (mut robot, warnings) = load_robot_with(
        &section.model,
        section.drives.as_deref(),
        &section.chain_options(),
    )?;
    if let Some(q) = &section.start_q {
        robot.set_start_q(q).map_err(|e| ScenarioError::RobotKey {
            key: "[robot] start_q",
            error: Box::new(e),
        })?;
    }
    Ok((robot, warnings))
}

/// The plant's own robot of `[plant] robot` / `[plant] drives` (`None` when neither is
/// set): the plant's URDF (default `[robot] model`) with the plant's drives file (default
/// `[robot] drives`), `[robot]`'s tip and tool centre point; refused when its joints do
/// not match the controllers' `robot`.
pub fn load_plant_robot(
    f: &ScenarioFile,
    robot: &Robot,
) -> Result<(Option<Robot>, Vec<String>), ScenarioError> {
    let p = &f.plant;
    if p.robot.is_none() && p.drives.is_none() {
        return Ok((None, Vec::new()));
    }
    let model = match &p.robot {
        Some(m) => m.display().to_string(),
        None => f.robot.model.clone(),
    };
    let drives = p.drives.as_deref().or(f.robot.drives.as_deref());
    let (mut plant, warnings) = load_robot_with(&model, drives, &f.robot.chain_options())?;
    ofmpc::sim::check_plant_model(&plant, robot)
        .map_err(|e| ScenarioError::experiment(None, PlantError::Settings(e).into()))?;
    if drives.is_none() && p.robot.is_some() {
        // No drives file for the plant: it has the controllers' robot's drives (rotor
        // inertia, torque limits), not none (a plant without rotor inertia is another arm).
        plant.apply_drives(&drive_data_of(robot))?;
    }
    plant.require_inertials()?;
    let warnings = warnings
        .into_iter()
        .map(|w| format!("[plant] robot: {w}"))
        .collect();
    Ok((Some(plant), warnings))
}

/// The drive data of `robot`'s joints (rotor inertia and torque limit), as a drives file
/// would give them.
fn drive_data_of(robot: &Robot) -> Drives {
    let mut d = Drives::default();
    for j in robot.joints() {
        let mut data = ofmpc::robot::DriveData::default();
        data.armature_kgm2 = Some(j.armature);
        data.max_torque_nm = j.limits.effort.is_finite().then_some(j.limits.effort);
        d.joints.insert(j.name.clone(), data);
    }
    d
}

/// [`load_robot_section`] for runs and the stability analysis, which need the dynamics:
/// an error names the moving links without `<inertial>`.
fn load_robot_for_dynamics(
    section: &crate::file::RobotSection,
) -> Result<(Robot, Vec<String>), ScenarioError> {
    let (robot, warnings) = load_robot_section(section)?;
    robot.require_inertials()?;
    Ok((robot, warnings))
}

/// A tip other than the flange asked of a built-in robot: its chain always ends at the
/// flange. Names the links it has (a link that exists is not called unknown) and what to do.
fn builtin_tip_error(robot: &Robot, tip: &str) -> ScenarioError {
    ScenarioError::BuiltinTip {
        tip: ofmpc::input::quote(tip, ofmpc::input::QUOTE_CHARS),
        robot: robot.name().to_string(),
        flange: robot.flange_name().to_string(),
        links: robot.link_frames().iter().map(|l| l.name.clone()).collect(),
    }
}

/// [`load_robot`] with a chosen tip and tool centre point ([`ChainOptions`]); the built-in
/// robot takes the tool centre point and refuses a tip other than its flange.
pub fn load_robot_with(
    model: &str,
    drives: Option<&Path>,
    chain: &ChainOptions,
) -> Result<(Robot, Vec<String>), ScenarioError> {
    let path = Path::new(model);
    let from_urdf = is_model_path(model);
    let mut warnings = Vec::new();
    let mut robot = if from_urdf {
        let robot = Robot::from_urdf_file_with(path, chain)?;
        warnings.extend(
            urdf_warning_lines(robot.warnings())
                .into_iter()
                .map(|w| format!("{}: {w}", path.display())),
        );
        robot
    } else {
        let mut robot = Robot::builtin(model)?;
        if let Some(tip) = chain.tip.as_deref().filter(|t| *t != robot.flange_name()) {
            return Err(builtin_tip_error(&robot, tip));
        }
        if let Some(t) = chain.tcp {
            robot.set_tcp(t)?;
        }
        robot
    };
    if let Some(d) = drives {
        let drives_error = |source| ScenarioError::Drives {
            path: d.to_path_buf(),
            source: Box::new(source),
        };
        let drives = Drives::from_file(d)?;
        let unset = robot.apply_drives(&drives).map_err(drives_error)?;
        if !unset.is_empty() {
            warnings.push(format!(
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
    Ok((robot, warnings))
}

/// A URDF's warnings, one line per kind: the ignored `<dynamics>` of every joint in one, the
/// ignored `<safety_controller>`s in one, the limits read as not given in one per attribute;
/// the others one each.
pub fn urdf_warning_lines(warnings: &[ofmpc::robot::UrdfWarning]) -> Vec<String> {
    use ofmpc::robot::UrdfWarning as W;
    // Per kind: the joints, and the warnings as the library words them (kept for one joint).
    let mut kinds: [(Vec<String>, Vec<String>); 4] = Default::default();
    let mut other = Vec::new();
    for w in warnings {
        let (kind, joint) = match w {
            W::IgnoredDynamics { joint, .. } => (0, joint),
            W::IgnoredSafetyController(joint) => (1, joint),
            W::UnspecifiedLimit { joint, attribute } if *attribute == "effort" => (2, joint),
            W::UnspecifiedLimit { joint, .. } => (3, joint),
            w => {
                other.push(w.to_string());
                continue;
            }
        };
        kinds[kind].0.push(format!("'{joint}'"));
        kinds[kind].1.push(w.to_string());
    }
    let what = [
        "<dynamics damping friction> ignored (the robot model has no joint friction; set the \
         simulated plant's friction instead)"
            .to_string(),
        "<safety_controller> soft limits ignored; the <limit> range is used".to_string(),
        "<limit effort=\"0\"> read as not given (no effort limit); give it in a drives file \
         (max_torque_nm) if a controller or the planner needs it"
            .to_string(),
        "<limit velocity=\"0\"> read as not given (no velocity limit); give it in a drives file \
         (max_speed_rad_s) if a controller or the planner needs it"
            .to_string(),
    ];
    let mut lines = Vec::new();
    for ((joints, words), what) in kinds.iter().zip(what) {
        match joints.len() {
            0 => {}
            1 => lines.push(words[0].clone()),
            n => lines.push(format!("{n} joints ({}): {what}", joints.join(", "))),
        }
    }
    lines.extend(other);
    lines
}

/// Reads a program: a file, or the built-in paper program when `None`. Returns its
/// name and text.
pub fn read_program(file: Option<&Path>) -> Result<(String, String), ScenarioError> {
    match file {
        None => Ok((
            "paper-table1.gcode (built in)".into(),
            PAPER_TABLE1.to_string(),
        )),
        Some(p) => {
            let text = crate::file::read_text_limited(p, crate::file::MAX_PROGRAM_BYTES).map_err(
                |source| ScenarioError::ReadProgram {
                    path: p.to_path_buf(),
                    source,
                },
            )?;
            Ok((p.display().to_string(), text))
        }
    }
}

/// Reads a tool table (LinuxCNC's .tbl format, lengths in mm) named by setting `key`
/// (`[program] tool_table`, or a command-line option).
pub fn read_tool_table(path: &Path, key: &str) -> Result<ToolTable, ScenarioError> {
    let text =
        crate::file::read_text_limited(path, crate::file::MAX_PROGRAM_BYTES).map_err(|source| {
            ScenarioError::ReadToolTable {
                key: key.into(),
                path: path.to_path_buf(),
                source,
            }
        })?;
    ToolTable::parse(&text).map_err(|error| ScenarioError::ToolTable {
        key: key.into(),
        path: path.to_path_buf(),
        error: Box::new(error),
    })
}

/// The tool table of `[program] tool_table`, if set.
fn program_tool_table(p: &crate::ProgramSection) -> Result<Option<ToolTable>, ScenarioError> {
    p.tool_table
        .as_deref()
        .map(|path| read_tool_table(path, "[program] tool_table"))
        .transpose()
}

/// Two different masses whose run folders would share a name (the label keeps 6 significant
/// digits) are not a repeat: refused, naming both (a true repeat is a warning). No mass at
/// all is refused too.
fn check_mass_labels(m: &[f64]) -> Result<(), ScenarioError> {
    if m.is_empty() {
        return Err(ScenarioError::NoPayloads);
    }
    for (i, &a) in m.iter().enumerate() {
        if let Some(&b) = m[..i].iter().find(|&&b| {
            b + 0.0 != a + 0.0 && ofmpc::sim::mass_label(a) == ofmpc::sim::mass_label(b)
        }) {
            return Err(ScenarioError::Parse {
                origin: format!("[payload] masses_kg = {m:?}"),
                message: format!(
                    "the masses {b} and {a} kg differ but would share the run folder \
                     _m{}: give masses that differ within 6 significant digits",
                    ofmpc::sim::mass_label(a)
                ),
            });
        }
    }
    Ok(())
}

/// The file's payloads (`[payload] masses_kg` with its centre of mass and inertia), each
/// checked.
fn file_payloads(f: &ScenarioFile) -> Result<Vec<Payload>, ScenarioError> {
    let [ixx, iyy, izz, ixy, ixz, iyz] = f.payload.inertia_kgm2;
    let inertia = Matrix3::new(ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz);
    let mut payloads = Vec::new();
    for &mass in &f.payload.masses_kg {
        let p = Payload {
            mass,
            com: Vector3::from(f.payload.com_m),
            inertia,
        };
        p.validate().map_err(|error| ScenarioError::Payload {
            mass,
            error: Box::new(error),
        })?;
        payloads.push(p);
    }
    Ok(payloads)
}

/// Warnings for friction settings that have no effect on `robot`.
fn friction_warnings(f: &ScenarioFile, robot: &Robot) -> Vec<String> {
    let mut warnings = Vec::new();
    if f.mpc.observer_friction && !(f.mpc.state_observer || f.mpc.delay_compensation) {
        warnings.push(
            "[mpc] observer_friction = true without an observer (state_observer or \
             delay_compensation): it has no effect"
                .into(),
        );
    }
    if f.mpc.friction_creep && !(f.mpc.friction_compensation || f.mpc.observer_friction) {
        warnings.push(
            "[mpc] friction_creep = true without friction_compensation or observer_friction: \
             it has no effect"
                .into(),
        );
    }
    if f.mpc.friction_coupled && !f.mpc.friction_creep {
        warnings
            .push("[mpc] friction_coupled = true without friction_creep: it has no effect".into());
    }
    if f.mpc.friction_compensation {
        let d = ofmpc::control::DriveModel::from_robot(robot);
        if d.coulomb_nm.iter().chain(&d.viscous_nms).all(|v| *v == 0.0) {
            warnings.push(
                "[mpc] friction_compensation = true but the robot's drives give no friction \
                 estimate (coulomb_nm, viscous_nms): nothing is compensated"
                    .into(),
            );
        }
    }
    warnings
}

impl Scenario {
    /// Resolves a scenario file: loads, parses, times and maps to joint space.
    pub fn resolve(f: &ScenarioFile) -> Result<Self, ScenarioError> {
        let (program_name, text) = read_program(f.program.file.as_deref())?;
        Self::resolve_program(f, program_name, &text)
    }

    /// [`Scenario::resolve`] with the program given as text (`program_name` names it in
    /// messages) instead of `[program] file`.
    pub fn resolve_program(
        f: &ScenarioFile,
        program_name: String,
        text: &str,
    ) -> Result<Self, ScenarioError> {
        if f.controllers.is_empty() {
            return Err(ScenarioError::NoControllers);
        }
        check_mass_labels(&f.payload.masses_kg)?;
        let (robot, mut warnings) = load_robot_for_dynamics(&f.robot)?;
        let (plant_model, plant_warnings) = load_plant_robot(f, &robot)?;
        warnings.extend(plant_warnings);
        let n = robot.dof();
        let (loop_settings, conditions) = checked_settings(f, n)?;
        let payloads = file_payloads(f)?;
        check_model_payload(&robot, f.mpc.model_payload_kg)?;
        let options = plan_options(f)?;
        let planned = plan(text, &robot, &options).map_err(|error| ScenarioError::Plan {
            program: program_name.clone(),
            error: Box::new(error),
        })?;
        warnings.extend(run_warnings(f, &robot, &program_name, &planned));
        let (trajectory, reference) = (planned.trajectory, planned.reference);
        // The program's tool length (G43) extends the TCP the run records and follows.
        let robot = robot.with_tool_length(planned.tool_length).unwrap_or(robot);
        // `[baselines]` is the library's `BaselineSettings` as read, checked for the robot's joints.
        f.baselines
            .validate_for_dof(n)
            .map_err(|error| ScenarioError::Baselines {
                error: Box::new(error),
            })?;
        let experiment = Experiment {
            robot,
            reference,
            mpc: f.mpc.clone(),
            plant: PlantSettings {
                model: plant_model,
                ..f.plant.clone()
            },
            loop_settings,
            conditions,
            baselines: f.baselines.clone(),
        };
        experiment
            .validate()
            .map_err(|error| ScenarioError::experiment(Some(program_name.clone()), error))?;
        let mut file = f.clone();
        file.title = run_title(f, &experiment.robot, &program_name);
        Ok(Self {
            file,
            program_name,
            payloads,
            experiment,
            trajectory,
            warnings,
        })
    }

    /// Samples one run simulates: the path and the hold.
    pub fn samples_per_run(&self) -> usize {
        let exp = &self.experiment;
        exp.reference.len() + (exp.loop_settings.hold_s / exp.reference.ts()).round() as usize
    }

    /// The scenario file of what runs: every default filled in, these payloads and
    /// controllers (e.g. [`crate::unique_runs`]'s, repeats removed). Its paths are
    /// absolute when it was read by [`ScenarioFile::from_file`], so it re-runs from any
    /// working directory.
    pub fn effective_file(
        &self,
        payloads: &[Payload],
        controllers: &[ControllerKind],
    ) -> ScenarioFile {
        let mut file = self.file.clone();
        file.payload.masses_kg = payloads.iter().map(|p| p.mass).collect();
        file.controllers = controllers.to_vec();
        file
    }
}

/// The report's title: the scenario's own, or for a scenario that keeps the default title
/// ([`crate::file::DEFAULT_TITLE`]) while running another robot or program than the
/// paper's, one that names the robot and program that run.
fn run_title(f: &ScenarioFile, robot: &Robot, program_name: &str) -> String {
    let paper_program = f.program.file.is_none();
    let builtin = !is_model_path(&f.robot.model);
    if f.title != crate::file::DEFAULT_TITLE || (paper_program && builtin) {
        return f.title.clone();
    }
    let robot_name = if builtin && f.robot.model == "irb140" {
        "the ABB IRB 140".to_string()
    } else {
        let name = robot.name().trim();
        if name.is_empty() {
            file_stem(&f.robot.model)
        } else {
            name.to_string()
        }
    };
    let program = if paper_program {
        "the paper's path".to_string()
    } else {
        Path::new(program_name)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| program_name.to_string())
    };
    format!("Offset-free MPC of {robot_name} on {program}")
}

/// The file name of `path` without its extension (or `path` itself).
fn file_stem(path: &str) -> String {
    Path::new(path)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.to_string())
}

/// The controllers' model carries `[mpc] model_payload_kg` (`Experiment::model_robot`):
/// checked at resolve to name the key (the run would only say "[payload]").
fn check_model_payload(robot: &Robot, mass: f64) -> Result<(), ScenarioError> {
    if mass > 0.0 {
        robot
            .clone()
            .set_payload(Some(Payload::point_mass(mass)))
            .map_err(|error| ScenarioError::ModelPayload {
                mass,
                error: Box::new(error),
            })?;
    }
    Ok(())
}

/// A warning when the plant's RK4 substep is too coarse for its smoothed
/// Coulomb friction: more than 4 of the friction's time constants at rest
/// ([`ofmpc::sim::Plant::coulomb_time_constant`] at the path's start; measured
/// on the IRB 140: converged from 4τ, steady errors 1e4 times off at 20τ).
fn friction_substep_warning(
    robot: &Robot,
    plant: &PlantSettings,
    q0: &[f64],
    ts: f64,
) -> Option<String> {
    if plant.coulomb_friction.iter().all(|c| *c <= 0.0) {
        return None;
    }
    // τ does not depend on the control period: one substep is a period every valid plant has.
    let mut p =
        ofmpc::sim::Plant::with_period(robot.clone(), plant.clone(), q0, plant.substep).ok()?;
    let tau = p.coulomb_time_constant().ok()??;
    if plant.substep <= 4.0 * tau {
        return None;
    }
    // The largest substep ≤ 4τ that divides the control period, unless it is finer than the
    // finest the plant allows (MAX_SUBSTEPS per period): then τ itself must grow
    // (τ ∝ coulomb_velocity).
    let k = (ts / (4.0 * tau)).ceil();
    let advice = if k <= MAX_SUBSTEPS as f64 {
        format!("use substep = {:.3e} s or smaller", ts / k)
    } else {
        let finest = ts / MAX_SUBSTEPS as f64;
        format!(
            "even the finest substep ({finest:.3e} s, {MAX_SUBSTEPS} per period) is too coarse: \
             raise [plant] coulomb_velocity (now {}; τ grows with it) to at least {:.3e} and use \
             substep = {finest:.3e} s",
            plant.coulomb_velocity,
            plant.coulomb_velocity * finest / (4.0 * tau)
        )
    };
    Some(format!(
        "[plant] substep = {} s is coarser than 4 time constants of the Coulomb friction at rest \
         (τ = {tau:.1e} s = min H_ii·coulomb_velocity/coulomb_friction): a joint's sticking is not \
         resolved and steady errors are not to be trusted; {advice}",
        plant.substep
    ))
}

/// Events the scenario schedules after the run ends (the path, then the hold: `end_s`), which
/// would silently do nothing: the payload's pick-up, `[faults]` and `[plant] faults`.
fn events_after_the_end(f: &ScenarioFile, end_s: f64) -> Vec<String> {
    use ofmpc::sim::Fault;
    let after = |t: f64| t > end_s;
    let end = format!(
        "after the run's end ({end_s:.3} s: the path, then the hold of {} s): it never happens",
        f.simulation.hold_s
    );
    let mut w = Vec::new();
    if let Some(t) = f.payload.pick_up_at_s.filter(|&t| after(t)) {
        w.push(format!("[payload] pick_up_at_s = {t} s is {end}"));
    }
    for &t in f.faults.nan_at_s.iter().filter(|&&t| after(t)) {
        w.push(format!("[faults] nan_at_s: {t} s is {end}"));
    }
    for &[a, b] in f.faults.dropout_s.iter().filter(|d| after(d[0])) {
        w.push(format!("[faults] dropout_s: [{a}, {b}] s starts {end}"));
    }
    for (i, fault) in f.plant.faults.iter().enumerate() {
        let t = match fault {
            Fault::EncoderGlitch { t, .. }
            | Fault::EncoderDropout { t, .. }
            | Fault::TorqueDrop { t, .. } => *t,
            _ => continue,
        };
        if after(t) {
            w.push(format!("[plant] faults[{i}]: t = {t} s is {end}"));
        }
    }
    w
}

/// The loop settings and run conditions of `f`, with `[mpc]`, `[simulation]` and `[plant]`
/// checked for a robot of `n` joints.
fn checked_settings(
    f: &ScenarioFile,
    n: usize,
) -> Result<(ofmpc::sim::LoopSettings, ofmpc::sim::RunConditions), ScenarioError> {
    f.mpc
        .validate_for_dof(n)
        .map_err(|error| ScenarioError::Mpc {
            error: Box::new(error),
        })?;
    let loop_settings = f.loop_settings();
    let conditions = f.run_conditions();
    let settings_error = |error| ScenarioError::experiment(None, error);
    loop_settings
        .validate()
        .map_err(|e| settings_error(e.into()))?;
    conditions
        .validate()
        .map_err(|e| settings_error(e.into()))?;
    f.plant
        .validate_for(n, f.mpc.ts)
        .map_err(|e| settings_error(e.into()))?;
    Ok((loop_settings, conditions))
}

/// The planner's options from `[program]`, `[orientation]`, `[timing]` and the sample time.
fn plan_options(f: &ScenarioFile) -> Result<PlanOptions, ScenarioError> {
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
    let profile = parse_profile(&f.timing.profile).map_err(|_| ScenarioError::Profile {
        key: "[timing] profile".into(),
        value: f.timing.profile.clone(),
    })?;
    Ok(PlanOptions {
        parse: ParseOptions {
            tool_table: program_tool_table(&f.program)?,
            ..ParseOptions::with_origin(origin)
        },
        timing: TimingOptions {
            profile,
            max_speed: f.timing.max_speed_m_s,
            max_accel: f.timing.max_accel_m_s2,
            max_jerk: f.timing.max_jerk_m_s3,
            blend_tolerance: f.timing.tolerance_mm * 1e-3,
            default_mode: parse_mode(&f.timing.mode, "[timing] mode")?,
        },
        orientation,
        ts: f.mpc.ts,
    })
}

/// The warnings of a planned run: the planner's, the friction settings', the substeps' and the
/// events scheduled after the run's end.
fn run_warnings(
    f: &ScenarioFile,
    robot: &Robot,
    program_name: &str,
    planned: &ofmpc::motion::Plan,
) -> Vec<String> {
    let mut warnings = plan_warnings(program_name, planned);
    warnings.extend(friction_warnings(f, robot));
    if let Some(w) = friction_substep_warning(robot, &f.plant, planned.reference.q(0), f.mpc.ts) {
        warnings.push(w);
    }
    let end_s = planned.reference.duration() + f.simulation.hold_s;
    warnings.extend(events_after_the_end(f, end_s));
    warnings
}

/// The plan's warnings to show, each prefixed with the program's name: the program's own and
/// the exact-stop moves a joint limit slowed down.
fn plan_warnings(program_name: &str, planned: &ofmpc::motion::Plan) -> Vec<String> {
    let program = planned.program.warnings.iter().map(|w| w.to_string());
    let slowed = planned
        .diagnostics
        .joint_limited
        .iter()
        .map(|w| w.to_string());
    let turn = planned.diagnostics.start_turn.iter().map(|t| t.to_string());
    program
        .chain(turn)
        .chain(slowed)
        .map(|w| format!("{program_name}: {w}"))
        .collect()
}
