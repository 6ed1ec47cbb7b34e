//! `ofmpc init robot URDF`: the starting files for one's own robot — a drives file with one
//! table per moving joint (the URDF's limits filled in, what a URDF lacks marked to fill) and a
//! scenario that runs the robot — so that the next command is `ofmpc run`.

use crate::cli::InitRobotArgs;
use crate::output::atomic::write_atomic;
use anyhow::{bail, Context};
use ofmpc::robot::Robot;
use std::fmt::Write as _;
use std::path::Path;

/// A TOML number for a known limit, or the line commented out with a note when unknown.
fn limit_line(key: &str, value: f64, unit: &str) -> String {
    if value.is_finite() {
        format!("{key} = {value:?}    # {unit}, from the URDF\n")
    } else {
        format!("# {key} =    # {unit}: the URDF gives none\n")
    }
}

/// The drives file skeleton of `robot`.
pub fn drives_skeleton(robot: &Robot, urdf: &Path) -> String {
    let mut s = format!(
        "# Drives of {} (written by `ofmpc init robot`): joint side, SI units (N·m, rad/s; N, m/s\n\
         # for a prismatic joint). Fill in what the URDF lacks; a key left out keeps the URDF's value\n\
         # or none. docs/guide/tutorials/own-robot.md explains each key.\n",
        urdf.display()
    );
    for j in robot.joints() {
        let _ = write!(
            s,
            "\n[joints.{}]\n\
             armature_kgm2 = 0.0    # rotor inertia J_motor·gear_ratio² (kg·m²): fill in, it matters for stability\n",
            toml_key(&j.name)
        );
        s.push_str(&limit_line("max_torque_nm", j.limits.effort, "peak torque"));
        s.push_str(&limit_line(
            "max_speed_rad_s",
            j.limits.velocity,
            "speed limit",
        ));
        s.push_str(
            "# max_accel_rad_s2 =    # acceleration limit (G64 timing)\n\
             # coulomb_nm =          # Coulomb friction estimate ([mpc] friction_compensation)\n\
             # viscous_nms =         # viscous friction estimate (N·m·s/rad)\n",
        );
    }
    s
}

/// A TOML key: bare when it can be, quoted otherwise.
fn toml_key(name: &str) -> String {
    if !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        name.to_string()
    } else {
        format!("{name:?}")
    }
}

/// The scenario skeleton for the URDF at `model` (as written in the scenario).
pub fn scenario_skeleton(model: &str) -> String {
    scenario_skeleton_with_tip(model, None)
}

/// [`scenario_skeleton`] with the chain's tip link written as `[robot] tip` when given.
pub fn scenario_skeleton_with_tip(model: &str, tip: Option<&str>) -> String {
    let tip = tip.map(|t| format!("tip = {t:?}\n")).unwrap_or_default();
    format!(
        "# Written by `ofmpc init robot`: `ofmpc run scenario.toml`. Every key left out keeps its\n\
         # default (examples/scenario.toml, docs/guide/reference/scenario.md). A relative path is\n\
         # relative to this file; an absolute one (the URDF's when it lies elsewhere) is used as is.\n\
         controllers = [\"usual\", \"first\", \"second\"]\n\n\
         [robot]\n\
         model = {model:?}\n{tip}\
         drives = \"drives.toml\"\n\n\
         [program]\n\
         # file = \"my-program.gcode\"      # default: the paper's Table I program\n\
         # origin_mm = [400.0, 0.0, 300.0]  # G54 work offset (mm, base frame): put the part within reach\n\n\
         [payload]\n\
         masses_kg = [0.0, 0.5]           # the load the controllers do not know (kg)\n"
    )
}

/// The scenario text for the placement (or, when none was found, the skeleton, with a
/// warning saying why).
fn scenario_for(
    placement: &Result<ofmpc_scenario::Placement, ofmpc_scenario::ScenarioError>,
    model: &str,
    chain: &crate::init_choice::Chain,
) -> String {
    match placement {
        Ok(p) => {
            crate::init_choice::scenario_text(chain.robot.name(), model, chain.tip.as_deref(), p)
        }
        Err(e) => {
            crate::output::console::warn(&format!(
                "no start pose found from which this robot runs the paper's program: {e}; the \
                 scenario written needs [robot] start_q and a program of yours ([program] file, \
                 origin_mm)"
            ));
            scenario_skeleton_with_tip(model, chain.tip.as_deref())
        }
    }
}

/// Runs `ofmpc init robot`: reads the URDF (choosing the tip of a branched arm), places the
/// paper's program for it ([`crate::init_choice`]), writes the drives file, the scenario and
/// the placed program, and prints the choice and the next commands.
pub fn robot(a: &InitRobotArgs) -> anyhow::Result<()> {
    let chain = crate::init_choice::read_chain(&a.urdf, a.tip.as_deref())?;
    let robot = &chain.robot;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    // The folder's lock, as every output takes (issue #36): a second `init` (or a run) into
    // the same folder meanwhile is refused, so the check below and both writes are one step
    // and a race leaves one complete set, never one robot's drives with another's scenario.
    let _lock = crate::output::atomic::DirLock::acquire(&a.out)
        .with_context(|| format!("writing into {}", a.out.display()))?;
    let drives = a.out.join("drives.toml");
    let scenario = a.out.join("scenario.toml");
    let program = a.out.join(crate::init_choice::PROGRAM_FILE);
    for p in [&drives, &scenario, &program] {
        if p.exists() {
            bail!(
                "{} exists: init never replaces a file; choose another --out",
                p.display()
            );
        }
    }
    // The URDF as the scenario will find it: relative to --out.
    let urdf = ofmpc_scenario::absolute(&a.urdf);
    let out = ofmpc_scenario::absolute(&a.out);
    let model = crate::init_choice::relative_to(&urdf, &out);
    let placement = crate::init_choice::place(&urdf, chain.tip.as_deref());
    write_atomic(&drives, drives_skeleton(robot, &a.urdf).as_bytes())
        .with_context(|| format!("writing {}", drives.display()))?;
    if let Some(p) = placement.as_ref().ok().filter(|p| !p.as_published) {
        write_atomic(&program, p.program.as_bytes())
            .with_context(|| format!("writing {}", program.display()))?;
    }
    let text = scenario_for(&placement, &model.display().to_string(), &chain);
    write_atomic(&scenario, text.as_bytes())
        .with_context(|| format!("writing {}", scenario.display()))?;
    let written = if placement.as_ref().is_ok_and(|p| !p.as_published) {
        format!(", {} and {}", scenario.display(), program.display())
    } else {
        format!(" and {}", scenario.display())
    };
    crate::output::console::println(&format!(
        "wrote {} ({} joints: fill in armature_kgm2 and what the URDF lacks){written}",
        drives.display(),
        robot.dof(),
    ))?;
    if let Ok(p) = &placement {
        crate::output::console::println(&crate::init_choice::next_steps(
            &a.urdf, &a.out, &chain, p,
        ))?;
    }
    Ok(())
}
