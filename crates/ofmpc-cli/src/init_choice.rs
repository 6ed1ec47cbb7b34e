//! What `ofmpc init robot` chooses for one's own robot so that its scenario runs at once: the
//! chain's tip of a branched arm, a start pose and the paper's program placed where the arm
//! reaches it ([`ofmpc_scenario::place_paper_program`]), and the next commands it prints.

use anyhow::Context;
use ofmpc::robot::{ChainOptions, ModelError, Robot, UrdfError};
use ofmpc_scenario::{Placement, ScenarioFile};
use std::path::Path;

/// The file init writes the placed program to, beside the scenario.
pub const PROGRAM_FILE: &str = "program.gcode";

/// The robot as init reads it and the tip it chose.
pub struct Chain {
    /// The robot (chain cut at `tip` when given).
    pub robot: Robot,
    /// The tip: the one given, or for a branched arm the link where it branches.
    pub tip: Option<String>,
    /// Whether init chose the tip (the URDF is not a serial chain without it).
    pub tip_chosen: bool,
}

/// Reads the URDF with `tip`; without one, a tree that branches into moving joints (an arm
/// with a hand and fingers) is read again with the branching link as its tip.
pub fn read_chain(urdf: &Path, tip: Option<&str>) -> anyhow::Result<Chain> {
    let options = |tip: Option<&str>| ChainOptions {
        tip: tip.map(str::to_string),
        tcp: None,
    };
    let context = || format!("reading the URDF {}", urdf.display());
    match Robot::from_urdf_file_with(urdf, &options(tip)) {
        Ok(robot) => Ok(Chain {
            robot,
            tip: tip.map(str::to_string),
            tip_chosen: false,
        }),
        Err(ModelError::Structure {
            error: UrdfError::NotSerial { link, .. },
            ..
        }) if tip.is_none() => {
            let robot = Robot::from_urdf_file_with(urdf, &options(Some(&link)))
                .with_context(|| format!("{} with --tip {link}", context()))?;
            Ok(Chain {
                robot,
                tip: Some(link),
                tip_chosen: true,
            })
        }
        Err(e) => Err(anyhow::Error::new(e).context(context())),
    }
}

/// The placement of the paper's program for the robot of `model` (absolute, or relative to
/// the working directory) with `tip`, its limits as the URDF gives them (what init's drives
/// file holds).
pub fn place(model: &Path, tip: Option<&str>) -> Result<Placement, ofmpc_scenario::ScenarioError> {
    let mut f = ScenarioFile::default();
    f.robot.model = model.display().to_string();
    f.robot.tip = tip.map(str::to_string);
    ofmpc_scenario::place_paper_program(&f)
}

/// `path` relative to the folder `base` (both absolute): `../robots/ur5.urdf`; `path` itself
/// when they share no root.
pub fn relative_to(path: &Path, base: &Path) -> std::path::PathBuf {
    let (p, b): (Vec<_>, Vec<_>) = (path.components().collect(), base.components().collect());
    let common = p.iter().zip(&b).take_while(|(x, y)| x == y).count();
    // Only the root in common (or nothing): the absolute path reads better.
    if common <= 1 {
        return path.to_path_buf();
    }
    let mut out = std::path::PathBuf::new();
    for _ in common..b.len() {
        out.push("..");
    }
    for c in &p[common..] {
        out.push(c);
    }
    out
}

/// A list of numbers as TOML (`[0.1, -0.2]`) with 4 decimals.
pub fn toml_list(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{:.4}", round4(*x))).collect();
    format!("[{}]", parts.join(", "))
}

/// The same numbers comma-separated, as `--start-q` and `--origin` take them.
pub fn flag_list(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{:.4}", round4(*x))).collect();
    parts.join(",")
}

/// `x` rounded to 4 decimals, without a negative zero.
fn round4(x: f64) -> f64 {
    let r = (x * 1e4).round() / 1e4;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

/// The tool position (mm, base frame) at the start pose of `p`: where a program placed with
/// `--origin` there starts.
pub fn tool_position_mm(p: &Placement) -> [f64; 3] {
    let c = [430.0, 0.0, 400.0];
    [
        p.offset_mm[0] + c[0],
        p.offset_mm[1] + c[1],
        p.offset_mm[2] + c[2],
    ]
}

/// The scenario init writes: the robot (`model` as the scenario finds it, `tip`), its drives
/// file, the start pose and program of the placement `p`, two payloads.
pub fn scenario_text(robot_name: &str, model: &str, tip: Option<&str>, p: &Placement) -> String {
    let tip = tip.map(|t| format!("tip = {t:?}\n")).unwrap_or_default();
    let placed = if p.as_published {
        ""
    } else {
        " (placed for it)"
    };
    let (start, program, timing) = if p.as_published {
        (
            String::new(),
            "# file = \"my-program.gcode\"      # default: the paper's Table I program\n"
                .to_string(),
            String::new(),
        )
    } else {
        (
            format!(
                "start_q = {}    # chosen by init: inside the limits, away from singularities\n",
                toml_list(&p.start_q)
            ),
            format!(
                "file = \"{PROGRAM_FILE}\"    # the paper's program, placed by init where this arm reaches it\n"
            ),
            if p.max_speed_m_s == ofmpc::motion::TimingOptions::default().max_speed {
                String::new()
            } else {
                format!(
                    "\n[timing]\nmax_speed_m_s = {}    # what this arm's joint speed limits allow on the program\n",
                    p.max_speed_m_s
                )
            },
        )
    };
    format!(
        "# Written by `ofmpc init robot`: `ofmpc run scenario.toml`. Every key left out keeps its\n\
         # default (examples/scenario.toml, docs/guide/reference/scenario.md). A relative path is\n\
         # relative to this file; an absolute one (the URDF's when it lies elsewhere) is used as is.\n\
         title = \"Offset-free MPC of {robot_name} on the paper's path{placed}\"\n\
         controllers = [\"usual\", \"first\", \"second\"]\n\n\
         [robot]\n\
         model = {model:?}\n{tip}\
         drives = \"drives.toml\"\n{start}\n\
         [program]\n{program}\
         # origin_mm = [400.0, 0.0, 300.0]  # G54 work offset (mm, base frame) of a program that sets none\n{timing}\n\
         [payload]\n\
         masses_kg = [0.0, 0.5]           # the load the controllers do not know (kg)\n"
    )
}

/// What init prints after writing the files: the choice, and the commands to run next.
pub fn next_steps(urdf: &Path, out: &Path, chain: &Chain, p: &Placement) -> String {
    let scenario = out.join("scenario.toml");
    let drives = out.join("drives.toml");
    let mut s = String::new();
    if chain.tip_chosen {
        if let Some(t) = &chain.tip {
            s.push_str(&format!(
                "the URDF branches into moving joints below link {t:?} (a hand with fingers): its \
                 chain ends there (written as [robot] tip; pass --tip {t} to trajectory, run, \
                 reproduce and inspect)\n"
            ));
        }
    }
    let tip_flag = chain
        .tip
        .as_deref()
        .map(|t| format!(" --tip {t}"))
        .unwrap_or_default();
    let at = tool_position_mm(p).map(|v| (v * 10.0).round() / 10.0);
    // Printed whether init chose the pose or the robot's own default runs the paper's
    // program as published: the README's next steps (a program of yours) take both values.
    let (x, y, z) = (at[0], at[1], at[2]);
    let whose = if p.as_published {
        " (the robot's default)"
    } else {
        ""
    };
    s.push_str(&format!(
        "start pose {}{whose} (--start-q {}); the tool there is at [{x:.1}, {y:.1}, {z:.1}] mm: a \
         program of yours placed with --origin {x:.1},{y:.1},{z:.1} starts where the tool is\n",
        toml_list(&p.start_q),
        flag_list(&p.start_q),
    ));
    s.push_str(&format!(
        "next:\n  ofmpc run {}\n  ofmpc inspect robot --robot {}{tip_flag} --drives {}",
        scenario.display(),
        urdf.display(),
        drives.display()
    ));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_round_to_four_decimals_without_negative_zero() {
        assert_eq!(
            toml_list(&[0.123456, -0.00001, 2.0]),
            "[0.1235, 0.0000, 2.0000]"
        );
        assert_eq!(flag_list(&[-1.5, 0.0]), "-1.5000,0.0000");
    }

    #[test]
    fn a_path_relative_to_a_folder() {
        assert_eq!(
            relative_to(Path::new("/a/robots/ur5.urdf"), Path::new("/a/work/ur5")),
            Path::new("../../robots/ur5.urdf")
        );
        assert_eq!(
            relative_to(Path::new("/a/w/x.urdf"), Path::new("/a/w")),
            Path::new("x.urdf")
        );
    }
}
