//! Closed-loop runs on arms nobody on this project wrote (issue #19, target 2): on each of
//! UR3, UR5, UR10, Panda (arm), iiwa, LWR, Kinova and Z1, a G-code square with an arc
//! (100 mm, around the tool point of a mid-range start pose) is planned and run with
//! `second-adaptive` at the arm's rated payload (the controller is not told): the run ends
//! "ok" and the steady joint error is at most 1e-9 rad. And the usual MPC on the Kinova at
//! 1.6 kg and the UR10 at 10 kg (issue item 5: stable runs with a large offset) completes
//! "ok" at the default settings, reporting its offset.
//!
//! The URDFs are the vendored ones (`tests/data/robots/`, no drives file: armature 0, the
//! URDF's limits). `cargo test --release --workspace --test arms_closed_loop -- --nocapture`
//! prints each run.

mod common;

use common::experiment::{run, steady};
use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::dynamics::RobotDynamics;
use ofmpc::gcode::{parse, ParseOptions};
use ofmpc::ik::ForwardKinematics;
use ofmpc::motion::{build_reference, Orientation};
use ofmpc::motion::{CartesianTrajectory, TimingOptions};
use ofmpc::robot::{ChainOptions, Robot};
use ofmpc::sim::{Experiment, LoopSettings, RunStatus};
use std::path::Path;

/// (name, file, tip, start pose, rated payload in kg: the makers' data sheets).
type Arm = (
    &'static str,
    &'static str,
    Option<&'static str>,
    [f64; 7],
    f64,
);

const ARMS: [Arm; 8] = [
    (
        "UR3",
        "ur/ur3_robot.urdf",
        None,
        [0.3, -1.3, 2.0, -0.6, 0.9, 0.4, 0.0],
        3.0,
    ),
    (
        "UR5",
        "ur/ur5_robot.urdf",
        None,
        [0.3, -0.8, 1.2, -0.6, 0.9, 0.4, 0.0],
        5.0,
    ),
    (
        "UR10",
        "ur/ur10_robot.urdf",
        None,
        [0.3, -0.8, 1.2, -0.6, 0.9, 0.4, 0.0],
        10.0,
    ),
    (
        "Panda",
        "panda/panda.urdf",
        Some("panda_hand"),
        [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785],
        3.0,
    ),
    (
        "iiwa",
        "iiwa/model.urdf",
        None,
        [0.0, 0.6, 0.0, -1.4, 0.0, 0.9, 0.0],
        14.0,
    ),
    (
        "LWR",
        "lwr/kuka.urdf",
        None,
        [0.0, 0.6, 0.0, -1.4, 0.0, 0.9, 0.0],
        7.0,
    ),
    (
        "Kinova",
        "kinova/kinova.urdf",
        None,
        [0.3, 2.9, 1.3, -2.1, 1.4, 1.3, 0.0],
        1.6,
    ),
    (
        "Z1",
        "z1/z1.urdf",
        Some("link06"),
        [0.3, 1.2, -1.0, -0.3, 0.4, 0.2, 0.0],
        2.0,
    ),
];

/// The square with an arc (mm), relative to the start pose's tool point.
const PROGRAM: &str = "G21 G91 G17\nG1 X50 F6000\nG1 Y100\nG3 X-100 I-50 J0\nG1 Y-100\nG1 X50\n";

/// The arm's experiment: the square from its start pose (the pose in [`ARMS`]).
fn experiment(arm: &Arm) -> Experiment {
    let (name, file, tip, pose, _) = *arm;
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/robots")
        .join(file);
    let options = ChainOptions {
        tip: tip.map(str::to_string),
        tcp: None,
    };
    let mut robot = Robot::from_urdf_file_with(&path, &options).unwrap();
    robot
        .set_start_q(&pose[..robot.dof()])
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let q = robot.start_q().to_vec();
    let start = RobotDynamics::new(robot.clone())
        .flange_pose(&q)
        .translation
        .vector;
    // The Jaco's joints are slow (0.63 rad/s on joints 1–3): 40 mm/s instead of 100.
    let text = if name == "Kinova" {
        PROGRAM.replace("F6000", "F2400")
    } else {
        PROGRAM.to_string()
    };
    let program = parse(
        &text,
        &ParseOptions {
            start: Some(start),
            ..ParseOptions::default()
        },
    )
    .unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let reference = build_reference(&robot, &traj, Orientation::AtZero, 0.01)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc: MpcSettings::default(),
        plant: Default::default(),
        loop_settings: LoopSettings::default(),
        baselines: Default::default(),
    }
}

#[test]
fn second_adaptive_holds_the_rated_payload_on_eight_arms() {
    let mut failures = Vec::new();
    for arm in &ARMS {
        let exp = experiment(arm);
        let m = run(&exp, ControllerKind::SecondAdaptive, arm.4);
        println!(
            "{:7} second-adaptive at {} kg: {:?} ({}), steady {:.1e} rad, {} samples",
            arm.0,
            arm.4,
            m.status,
            m.reason,
            steady(&m),
            exp.reference.len()
        );
        if m.status != RunStatus::Ok || steady(&m) > 1e-9 {
            failures.push(format!("{}: {:?} steady {:e}", arm.0, m.status, steady(&m)));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// The usual MPC (no integral action) at the rated payload the controller does not know: a
/// stable run with a steady offset, which ends "ok" at the default settings (divergence is
/// growth) and reports the offset.
#[test]
fn the_usual_mpc_completes_with_its_offset_on_the_kinova_and_the_ur10() {
    for name in ["Kinova", "UR10"] {
        let arm = ARMS.iter().find(|a| a.0 == name).unwrap();
        let m = run(&experiment(arm), ControllerKind::Usual, arm.4);
        let max = m.joint_error_max_rad.iter().copied().fold(0.0, f64::max);
        println!(
            "{name:7} usual at {} kg: {:?} ({}), steady offset {:.3} rad, largest error {max:.3} rad",
            arm.4,
            m.status,
            m.reason,
            steady(&m)
        );
        assert_eq!(m.status, RunStatus::Ok, "{name}: {}", m.reason);
        assert!(steady(&m) > 1e-3, "{name}: the usual MPC has an offset");
    }
}
