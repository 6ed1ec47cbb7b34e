//! `ofmpc trajectory`: a program's timed path and joint reference.

use super::parse_vector;
use crate::cli::TrajectoryArgs;
use crate::figures;
use crate::output::atomic::write_atomic;
use crate::output::plot::render_both;
use crate::scenario::{
    load_robot, parse_mode, parse_profile, plan_error_message, read_program, SettingNames,
};
use anyhow::Context;
use ofmpc::gcode::ParseOptions;
use ofmpc::motion::{plan, Orientation, PlanOptions, TimingOptions};
use std::path::Path;

/// The command line's names of the planning settings.
const FLAGS: SettingNames = SettingNames {
    speed: "--speed",
    accel: "--accel",
    jerk: "--jerk",
    tolerance: "--tolerance",
    ts: "--ts",
    origin: "--origin X,Y,Z (mm)",
};

/// Parses, times and maps the program; writes the CSV and the figure.
pub fn trajectory(a: &TrajectoryArgs) -> anyhow::Result<()> {
    let robot = load_robot(&a.robot, a.drives.as_deref())?;
    let file =
        (a.program != "paper" || Path::new(&a.program).exists()).then(|| Path::new(&a.program));
    let (name, text) = read_program(file)?;
    let origin = match &a.origin {
        Some(o) => {
            let v = parse_vector("--origin", o, Some(3))?;
            Some([v[0] * 1e-3, v[1] * 1e-3, v[2] * 1e-3])
        }
        None => None,
    };
    let orientation = match &a.rpy {
        Some(t) => {
            let v = parse_vector("--rpy", t, Some(3))?;
            Orientation::Fixed(nalgebra::UnitQuaternion::from_euler_angles(
                v[0].to_radians(),
                v[1].to_radians(),
                v[2].to_radians(),
            ))
        }
        None => Orientation::AtZero,
    };
    let options = PlanOptions {
        parse: ParseOptions { origin },
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
    };
    let planned = plan(&text, &robot, &options)
        .map_err(|e| anyhow::anyhow!("{name}: {}", plan_error_message(&e, &FLAGS)))?;
    for w in &planned.program.warnings {
        eprintln!("warning: {name}: {w}");
    }
    let (traj, reference) = (&planned.trajectory, &planned.reference);
    write_atomic(&a.out, crate::tables::reference_csv(reference).as_bytes())
        .with_context(|| format!("writing {}", a.out.display()))?;
    let stem = a.out.with_extension("");
    let fig = render_both(&figures::path(
        &format!("{name}: path and joint reference"),
        reference,
    ))?;
    let png = stem.with_file_name(format!(
        "{}_path.png",
        stem.file_name()
            .map(|s| s.to_string_lossy())
            .unwrap_or_default()
    ));
    let svg = png.with_extension("svg");
    write_atomic(&png, &fig.png).with_context(|| format!("writing {}", png.display()))?;
    write_atomic(&svg, fig.svg.as_bytes()).with_context(|| format!("writing {}", svg.display()))?;
    let cart = render_both(&figures::cartesian_reference(
        &format!("{name}: Cartesian reference"),
        traj,
        a.ts,
    ))?;
    let cpng = png.with_file_name(
        png.file_name()
            .map(|n| n.to_string_lossy().replace("_path.png", "_cartesian.png"))
            .unwrap_or_default(),
    );
    write_atomic(&cpng, &cart.png).with_context(|| format!("writing {}", cpng.display()))?;
    let csvg = cpng.with_extension("svg");
    write_atomic(&csvg, cart.svg.as_bytes())
        .with_context(|| format!("writing {}", csvg.display()))?;
    let limits: Vec<f64> = robot.joints().iter().map(|j| j.limits.velocity).collect();
    let motion = render_both(&figures::motion_profile(
        &format!("{name}: path speed and joint speeds"),
        reference,
        &limits,
    ))?;
    let mpng = png.with_file_name(
        png.file_name()
            .map(|n| n.to_string_lossy().replace("_path.png", "_speed.png"))
            .unwrap_or_default(),
    );
    write_atomic(&mpng, &motion.png).with_context(|| format!("writing {}", mpng.display()))?;
    let msvg = mpng.with_extension("svg");
    write_atomic(&msvg, motion.svg.as_bytes())
        .with_context(|| format!("writing {}", msvg.display()))?;
    println!(
        "{name}: {} segments ({} blended runs), {:.3} s, {} samples at Ts = {} s → {} (+ {}, {}, {}, {}, {}, {})",
        traj.segments().len(),
        planned.diagnostics.runs,
        traj.duration(),
        reference.len(),
        a.ts,
        a.out.display(),
        png.display(),
        svg.display(),
        cpng.display(),
        csvg.display(),
        mpng.display(),
        msvg.display()
    );
    Ok(())
}
