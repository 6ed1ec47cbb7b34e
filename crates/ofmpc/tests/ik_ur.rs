//! The closed-form inverse kinematics of the Universal Robots family (issue #19, deliver 1)
//! on the UR3, UR5 and UR10 as example-robot-data ships them (`tests/data/robots/ur`):
//! the analytic solver is chosen from the joint axes alone; 100 poses that are the forward
//! kinematics of random joint vectors within the limits are all solved to 1e-9 m and
//! 1e-9 rad (checked with the model's own forward kinematics, not the solver's); every
//! branch it returns reproduces the pose (8 on most poses); the numeric solvers' answers
//! (multi-start, and damped least squares from random seeds) are among them; and a tool centre point is solved directly.

mod common;
use common::ik as ik_common;
use common::rng;
use ik_common::{distance, limits, random_q, same_angle};

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use ofmpc::dynamics::RobotDynamics;
use ofmpc::ik::{
    ForwardKinematics, NumericIk, NumericIkSettings, RobustIk, RobustIkSettings, UrSolver,
};
use ofmpc::robot::{IkMethod, Robot};
use ofmpc::spatial::Transform;
use std::path::Path;

const ARMS: [&str; 3] = ["ur3", "ur5", "ur10"];
const POSES: usize = 100;

fn load(name: &str) -> Robot {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/robots/ur")
        .join(format!("{name}_robot.urdf"));
    Robot::from_urdf_file(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn the_ur_arms_use_the_closed_form_and_solve_every_reachable_pose() {
    for (k, name) in ARMS.iter().enumerate() {
        let robot = load(name);
        assert_eq!(robot.ik_method(), IkMethod::Ur, "{name}");
        assert!(robot.ik_method().description().contains("UR closed form"));
        let kin = robot.ur_kinematics().unwrap();
        let (lo, up) = limits(&robot);
        let solver = UrSolver::new(kin, lo, up).unwrap();
        let mut fk = RobotDynamics::new(robot.clone());
        let mut robust =
            RobustIk::new(6, &lo, &up, robot.start_q(), RobustIkSettings::default()).unwrap();
        let mut plain = NumericIk::new(6, &lo, &up, NumericIkSettings::default()).unwrap();
        let mut rng = rng::SplitMix64::new(0x5552_0000 + k as u64);
        let (mut worst_p, mut worst_r, mut eight, mut agree, mut both) = (0.0f64, 0.0f64, 0, 0, 0);
        let mut seeded = 0;
        for _ in 0..POSES {
            let q = random_q(&robot, &mut rng);
            let target = fk.flange_pose(&q);
            // The planner's choice: the solution nearest to the start pose, within limits.
            let start: [f64; 6] = std::array::from_fn(|i| robot.start_q()[i]);
            let sol = solver
                .solve_near(&target, &start)
                .unwrap_or_else(|e| panic!("{name} q = {q:?}: {e}"));
            assert!(sol
                .iter()
                .zip(lo.iter().zip(&up))
                .all(|(v, (l, u))| v >= l && v <= u));
            let (dp, dr) = distance(&target, &fk.flange_pose(&sol));
            assert!(dp <= 1e-9 && dr <= 1e-9, "{name}: {dp:e} m {dr:e} rad");
            (worst_p, worst_r) = (worst_p.max(dp), worst_r.max(dr));
            // Every branch reproduces the pose; the generating q is one of them.
            let all = kin.inverse_near(&target, &q);
            for b in all.as_slice() {
                let (dp, dr) = distance(&target, &fk.flange_pose(b));
                assert!(
                    dp <= 1e-9 && dr <= 1e-9,
                    "{name} branch {b:?}: {dp:e} m {dr:e} rad"
                );
            }
            let has = |x: &[f64]| {
                all.as_slice()
                    .iter()
                    .any(|b| b.iter().zip(x).all(|(a, c)| same_angle(*a, *c)))
            };
            assert!(
                has(&q),
                "{name}: the generating q {q:?} is not among the branches"
            );
            if all.len() == 8 {
                eight += 1;
            }
            // Completeness: damped least squares from random seeds converges only to
            // branches the closed form returned.
            for _ in 0..4 {
                let mut x = random_q(&robot, &mut rng).to_vec();
                if plain.solve(&mut fk, &target, &mut x).is_ok() {
                    seeded += 1;
                    assert!(
                        has(&x),
                        "{name}: numeric solution {x:?} missed by the closed form"
                    );
                }
            }
            // The numeric solver's solution, where it finds one, is a branch of the closed form.
            let mut x = robot.start_q().to_vec();
            if robust.solve(&mut fk, &target, &mut x).is_ok() {
                both += 1;
                if has(&x) {
                    agree += 1;
                }
            }
        }
        println!(
            "{name}: {POSES}/{POSES} solved, worst {worst_p:.1e} m {worst_r:.1e} rad; 8 branches on \
             {eight}; numeric solution among the branches {agree}/{both} (multi-start), {seeded} of \
             {seeded} converged random seeds"
        );
        assert_eq!(agree, both, "{name}");
        assert!(eight > 0 && seeded > 0, "{name}");
    }
}

#[test]
fn the_closed_form_solves_for_the_tool_centre_point() {
    let mut robot = load("ur5");
    let tcp = Isometry3::from_parts(
        Translation3::new(0.02, -0.01, 0.18),
        UnitQuaternion::from_euler_angles(0.3, -0.2, 0.5),
    );
    robot.set_tcp(Transform::from_isometry(&tcp)).unwrap();
    assert_eq!(robot.ik_method(), IkMethod::Ur);
    let kin = robot.ur_kinematics().unwrap();
    let mut fk = RobotDynamics::new(robot.clone());
    let mut rng = rng::SplitMix64::new(7);
    for _ in 0..20 {
        let q = random_q(&robot, &mut rng);
        let target = fk.flange_pose(&q);
        let all = kin.inverse(&target);
        assert!(!all.is_empty());
        for b in all.as_slice() {
            let (dp, dr) = distance(&target, &fk.flange_pose(b));
            assert!(dp <= 1e-9 && dr <= 1e-9, "{dp:e} m {dr:e} rad");
        }
        // The closed form's own forward kinematics is the model's.
        let (dp, dr) = distance(&target, &kin.forward(&q));
        assert!(dp <= 1e-12 && dr <= 1e-12, "{dp:e} {dr:e}");
    }
}

#[test]
fn other_arms_are_not_taken_for_urs_and_far_poses_are_out_of_reach() {
    // The IRB 140 keeps OPW; a 7-joint arm and the Kinova are not of the UR family.
    assert_eq!(Robot::irb140().ik_method(), IkMethod::Opw);
    assert!(Robot::irb140().ur_kinematics().is_none());
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/robots");
    for file in ["kinova/kinova.urdf", "iiwa/model.urdf"] {
        let r = Robot::from_urdf_file(&dir.join(file)).unwrap();
        assert_eq!(r.ik_method(), IkMethod::Numeric, "{file}");
    }
    let robot = load("ur5");
    let (lo, up) = limits(&robot);
    let solver = UrSolver::new(robot.ur_kinematics().unwrap(), lo, up).unwrap();
    let far = Isometry3::translation(3.0, 0.0, 0.5);
    let err = solver.solve_near(&far, &[0.0; 6]).unwrap_err();
    assert!(
        matches!(err, ofmpc::ik::IkError::Unreachable { .. }),
        "{err}"
    );
}
