//! `ofmpc trajectory`: a program's timed path and joint reference.

use super::robot::{load_model_with, parse_fixed};
use crate::cli::TrajectoryArgs;
use crate::figures;
use crate::output::atomic::{check_destinations, Input};
use crate::output::console;
use crate::output::plot::render_both;
use crate::tables::reference_csv;
use anyhow::Context;
use ofmpc::gcode::ParseOptions;
use ofmpc::motion::{plan, Orientation, Plan, PlanOptions, TimingOptions};
use ofmpc_scenario::{parse_mode, parse_profile, plan_error_message, read_program, SettingNames};
use std::path::{Path, PathBuf};

/// The command line's names of the planning settings.
const FLAGS: SettingNames = SettingNames {
    speed: "--speed",
    accel: "--accel",
    jerk: "--jerk",
    tolerance: "--tolerance",
    ts: "--ts",
    origin: "--origin X,Y,Z (mm)",
    start_q: "--start-q",
};

/// The files `trajectory --out DIR/NAME.csv` writes: the CSV and, beside it,
/// `NAME_path.png/.svg`, `NAME_cartesian.png/.svg` and `NAME_speed.png/.svg`. Returns the
/// folder and the file names.
fn outputs(out: &Path) -> anyhow::Result<(PathBuf, [PathBuf; 7])> {
    let name = out
        .file_name()
        .filter(|_| !out.as_os_str().to_string_lossy().ends_with('/'))
        .ok_or_else(|| {
            anyhow::anyhow!(
                "--out {}: give the path of the CSV file to write (e.g. --out ref.csv)",
                out.display()
            )
        })?;
    let dir = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let stem = Path::new(name)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let files = [
        PathBuf::from(name),
        PathBuf::from(format!("{stem}_path.png")),
        PathBuf::from(format!("{stem}_path.svg")),
        PathBuf::from(format!("{stem}_cartesian.png")),
        PathBuf::from(format!("{stem}_cartesian.svg")),
        PathBuf::from(format!("{stem}_speed.png")),
        PathBuf::from(format!("{stem}_speed.svg")),
    ];
    Ok((dir, files))
}

/// The files the command reads (none of them may be overwritten by its outputs).
fn inputs(a: &TrajectoryArgs) -> Vec<Input> {
    let mut inputs = vec![Input::new(&a.program, "the program")];
    if Path::new(&a.robot).is_file() {
        inputs.push(Input::new(&a.robot, "the robot model"));
    }
    if let Some(d) = &a.drives {
        inputs.push(Input::new(d, "the drives file"));
    }
    inputs
}

/// The planner's options from the command's flags (work offset, tool orientation, tool table,
/// timing), every value checked.
fn plan_options(a: &TrajectoryArgs) -> anyhow::Result<PlanOptions> {
    let origin = match &a.origin {
        Some(o) => {
            let v = parse_fixed(
                "--origin",
                o,
                3,
                "the work offset's x,y,z in mm",
                "150,0,-250",
            )?;
            Some([v[0] * 1e-3, v[1] * 1e-3, v[2] * 1e-3])
        }
        None => None,
    };
    let orientation = match &a.rpy {
        Some(t) => {
            let v = parse_fixed("--rpy", t, 3, "roll,pitch,yaw in degrees", "0,90,0")?;
            Orientation::Fixed(nalgebra::UnitQuaternion::from_euler_angles(
                v[0].to_radians(),
                v[1].to_radians(),
                v[2].to_radians(),
            ))
        }
        None => Orientation::AtZero,
    };
    Ok(PlanOptions {
        parse: ParseOptions {
            tool_table: super::values::read_tool_table(a.tool_table.as_deref())?,
            ..ParseOptions::with_origin(origin)
        },
        timing: TimingOptions {
            profile: parse_profile(&a.profile)?,
            max_speed: a.speed,
            max_accel: a.accel,
            max_jerk: a.jerk,
            blend_tolerance: a.tolerance * 1e-3,
            default_mode: parse_mode(&a.mode, "--mode")?,
        },
        orientation,
        ts: a.ts,
    })
}

/// The planner's warnings on stderr: the program's, the start turn and the joint-limited moves.
fn warn_plan(name: &str, planned: &Plan) {
    for w in &planned.program.warnings {
        console::warn(&format!("{name}: {w}"));
    }
    if let Some(turn) = &planned.diagnostics.start_turn {
        console::warn(&format!("{name}: {turn}"));
    }
    for w in &planned.diagnostics.joint_limited {
        console::warn(&format!("{name}: {w}"));
    }
}

/// Parses, times and maps the program; writes the CSV and the figure.
pub fn trajectory(a: &TrajectoryArgs) -> anyhow::Result<()> {
    // The outputs are checked before any work: no device, FIFO, folder or symbolic link is
    // replaced, and no input of this run is overwritten.
    let (out_dir, files) = outputs(&a.out)?;
    let inputs = inputs(a);
    check_destinations(&out_dir, &files, &inputs)?;
    let robot = load_model_with(&a.robot, a.drives.as_deref(), &a.chain)?;
    let file =
        (a.program != "paper" || Path::new(&a.program).exists()).then(|| Path::new(&a.program));
    let (name, text) = read_program(file)?;
    let options = plan_options(a)?;
    let planned = plan(&text, &robot, &options)
        .map_err(|e| anyhow::anyhow!("{name}: {}", plan_error_message(&e, &FLAGS)))?;
    warn_plan(&name, &planned);
    let (traj, reference) = (&planned.trajectory, &planned.reference);
    let fig = render_both(&figures::path(
        &format!("{name}: path and joint reference"),
        reference,
    ))?;
    let cart = render_both(&figures::cartesian_reference(
        &format!("{name}: Cartesian reference"),
        traj,
        a.ts,
    ))?;
    let limits: Vec<f64> = robot.joints().iter().map(|j| j.limits.velocity).collect();
    let speed = render_both(&figures::motion_profile(
        &format!("{name}: path speed and joint speeds"),
        reference,
        &limits,
    ))?;
    // All seven files as one set: they appear together or not at all.
    let mut dir = super::experiment::open_output(&out_dir, inputs, &files)?;
    dir.write(&files[0], reference_csv(reference).as_bytes())?;
    dir.write(&files[1], &fig.png)?;
    dir.write(&files[2], fig.svg.as_bytes())?;
    dir.write(&files[3], &cart.png)?;
    dir.write(&files[4], cart.svg.as_bytes())?;
    dir.write(&files[5], &speed.png)?;
    dir.write(&files[6], speed.svg.as_bytes())?;
    dir.commit()
        .with_context(|| format!("moving the results into {}", out_dir.display()))?;
    let shown: Vec<String> = files
        .iter()
        .map(|f| a.out.with_file_name(f).display().to_string())
        .collect();
    console::println(&format!(
        "{name}: {} segments ({} blended runs), {:.3} s, {} samples at Ts = {} s → {} (+ {})",
        traj.segments().len(),
        planned.diagnostics.runs,
        traj.duration(),
        reference.len(),
        a.ts,
        shown[0],
        shown[1..].join(", ")
    ))?;
    Ok(())
}
