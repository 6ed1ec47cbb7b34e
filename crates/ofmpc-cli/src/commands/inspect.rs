//! `ofmpc inspect dynamics`: the model's quantities at one state, as JSON, so
//! that any peer implementation can be checked against this one.

use super::robot::{load_robot, parse_fixed, parse_vector};
use crate::cli::{InspectDynamics, InspectProgram, InspectRobot};
use crate::output::console;
use nalgebra::DMatrix;
use ofmpc::dynamics::{forward_kinematics, joint_space_terms, rnea, Workspace};
use ofmpc::robot::JointKind;
use serde_json::json;

fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|r| m.row(r).iter().copied().collect())
        .collect()
}

/// Prints `{"robot", "dof", "q", "qd", "qdd", "H", "C", "g", "tau", "flange": {"position", "rotation"}}`.
pub fn dynamics(a: &InspectDynamics) -> anyhow::Result<()> {
    let robot = load_robot(&a.robot, a.payload)?;
    robot.require_inertials()?;
    let n = robot.dof();
    let q = parse_vector("--q", &a.q, Some(n))?;
    let zeros = vec![0.0; n];
    let qd = match &a.qd {
        Some(t) => parse_vector("--qd", t, Some(n))?,
        None => zeros.clone(),
    };
    let qdd = match &a.qdd {
        Some(t) => parse_vector("--qdd", t, Some(n))?,
        None => zeros,
    };
    let mut ws = Workspace::new(&robot);
    let tau: Vec<f64> = rnea(&robot, &mut ws, &q, &qd, &qdd)?
        .iter()
        .copied()
        .collect();
    joint_space_terms(&robot, &mut ws, &q, &qd)?;
    let flange = *forward_kinematics(&robot, &mut ws, &q)?;
    let rot: Vec<Vec<f64>> = (0..3)
        .map(|r| (0..3).map(|c| flange.rot[(r, c)]).collect())
        .collect();
    let out = json!({
        "robot": robot.name(),
        "dof": n,
        "joints": robot.joints().iter().map(|j| j.name.clone()).collect::<Vec<_>>(),
        "payload_kg": a.payload,
        "q": q,
        "qd": qd,
        "qdd": qdd,
        "H": rows(&ws.h),
        "C": rows(&ws.c),
        "g": ws.g.iter().copied().collect::<Vec<_>>(),
        "tau": tau,
        "flange": {
            "frame": robot.flange_name(),
            "position": [flange.pos.x, flange.pos.y, flange.pos.z],
            "rotation": rot,
        },
    });
    console::println(&serde_json::to_string_pretty(&out)?)?;
    Ok(())
}

/// Prints the robot as loaded: joints (kind, axis, limits, drive data, the
/// moved body's mass and centre of mass), flange frame, total moving mass, the inverse
/// kinematics (`ik_solver`, and `opw_parameters` when it is the OPW closed form).
/// Unknown limits (infinite) print as `null`.
pub fn robot(a: &InspectRobot) -> anyhow::Result<()> {
    let robot = load_robot(&a.robot, 0.0)?;
    let joints: Vec<serde_json::Value> = robot
        .joints()
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let body = robot.body_inertia(i);
            let com = body.com();
            json!({
                "name": j.name,
                "link": j.link,
                "type": match j.kind { JointKind::Revolute => "revolute", JointKind::Prismatic => "prismatic" },
                "axis": [j.axis.x, j.axis.y, j.axis.z],
                "lower": j.limits.lower,
                "upper": j.limits.upper,
                "max_speed": j.limits.velocity,
                "max_effort": j.limits.effort,
                "max_accel": j.limits.acceleration,
                "armature_kgm2": j.armature,
                "body_mass_kg": body.mass,
                "body_com_m": [com.x, com.y, com.z],
            })
        })
        .collect();
    let f = robot.flange_offset();
    let t = robot.tcp();
    let tcp_rpy = nalgebra::Rotation3::from_matrix_unchecked(t.rot).euler_angles();
    let out = json!({
        "robot": robot.name(),
        "dof": robot.dof(),
        "moving_mass_kg": robot.moving_mass(),
        "gravity": [robot.gravity().x, robot.gravity().y, robot.gravity().z],
        "flange": { "frame": robot.flange_name(), "offset_from_last_body_m": [f.pos.x, f.pos.y, f.pos.z] },
        "tip": robot.flange_name(),
        "tcp": {
            "position_mm": [t.pos.x * 1e3, t.pos.y * 1e3, t.pos.z * 1e3],
            "rpy_deg": [tcp_rpy.0.to_degrees(), tcp_rpy.1.to_degrees(), tcp_rpy.2.to_degrees()],
        },
        "start_q": robot.start_q(),
        "ik_solver": robot.ik_method().description(),
        "opw_parameters": robot.opw_parameters().filter(|_| robot.ik_method() == ofmpc::robot::IkMethod::Opw).map(|p| json!({
            "a1_m": p.a1, "a2_m": p.a2, "b_m": p.b, "c1_m": p.c1, "c2_m": p.c2, "c3_m": p.c3, "c4_m": p.c4,
            "offsets_rad": p.offsets, "signs": p.signs,
        })),
        "links_without_inertial": robot.require_inertials().err().map(|e| e.to_string()),
        "joints": joints,
    });
    console::println(&serde_json::to_string_pretty(&out)?)?;
    Ok(())
}

/// Prints the program as read: `{"units": "mm", "start", "tool_length_mm", "moves": [{"line",
/// "kind", "end", "center", "normal", "turns", "feed_mm_s", "seconds"}], "events", "messages",
/// "warnings"}` in machine coordinates (mm); the first move goes from the start (the robot's
/// start pose, or machine zero) to the program's first point.
pub fn program(a: &InspectProgram) -> anyhow::Result<()> {
    let (name, text) = ofmpc_scenario::read_program(Some(&a.file))?;
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
    let (start, tool_axis) = match &a.robot {
        None => {
            if a.start_q.is_some() {
                anyhow::bail!("--start-q needs --robot (the pose is a robot's)");
            }
            (nalgebra::Vector3::zeros(), None)
        }
        Some(r) => {
            let chain = crate::args::ChainArgs {
                start_q: a.start_q.clone(),
                ..Default::default()
            };
            let robot = super::robot::load_model_with(r, a.drives.as_deref(), &chain)?;
            let start = ofmpc::motion::start_position(&robot)
                .ok_or_else(|| anyhow::anyhow!("the robot's start pose has no tool position"))?;
            // A G43 tool length lies along the TCP's z axis (as `trajectory` plans it).
            let axis = ofmpc::motion::tool_axis(&robot, ofmpc::motion::Orientation::AtZero);
            (start, axis)
        }
    };
    let options = ofmpc::gcode::ParseOptions {
        origin,
        start: Some(start),
        tool_axis,
        tool_table: super::values::read_tool_table(a.tool_table.as_deref())?,
        ..Default::default()
    };
    let program = ofmpc::gcode::parse(&text, &options)
        .map_err(|e| anyhow::Error::new(e).context(name.clone()))?;
    let out = ofmpc_scenario::program_json_with_tool_axis(&program, start, tool_axis);
    console::println(&serde_json::to_string_pretty(&out)?)?;
    Ok(())
}
