//! The OPW closed form detected from a URDF (issue #19, deliver 1): ROS-Industrial's ABB
//! IRB 2400 and IRB 6640 (`tests/data/robots/abb`) and this project's IRB 140 URDF are
//! recognised as ortho-parallel arms with a spherical wrist from their joint axes alone
//! ([`OpwParameters::detect`]); the IRB 140's detected parameters are the hand-written
//! ones (PARAMETERS.md); 100 poses that are the forward kinematics of random joint vectors
//! within the limits are all solved to 1e-9 m and 1e-9 rad (checked with the model's own
//! forward kinematics); every branch reproduces the pose and the generating q is among
//! them; the multi-start numeric solver's answers are branches too. A UR (offset wrist) and
//! chains perturbed by 1e-3 are not taken for OPW arms; a square with an arc on the
//! IRB 2400 with a tool centre point stays on one branch and on the path.
//!
//! `cargo test --workspace --test ik_opw_urdf -- --nocapture` prints the worst errors.

mod common;
use common::ik as ik_common;
use common::rng;
use ik_common::{distance, limits, random_q, same_angle};

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use ofmpc::dynamics::RobotDynamics;
use ofmpc::ik::{ForwardKinematics, IkSolver, OpwParameters, RobustIk, RobustIkSettings};
use ofmpc::robot::{ChainOptions, IkMethod, Robot, IRB140_URDF};
use ofmpc::spatial::Transform;
use std::f64::consts::PI;
use std::path::Path;

const POSES: usize = 100;

fn data(file: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/robots")
        .join(file);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A URDF text with the chain ending at `tool0` (the IRB 6640's counterbalance branch is
/// then held rigid).
fn load_str(text: &str, tip: Option<&str>) -> Robot {
    let options = ChainOptions {
        tip: tip.map(str::to_string),
        tcp: None,
    };
    Robot::from_urdf_str_with(text, &options).unwrap()
}

/// (name, robot) of the three ABB arms.
fn abb_arms() -> Vec<(&'static str, Robot)> {
    vec![
        (
            "IRB 2400",
            load_str(&data("abb/irb2400.urdf"), Some("tool0")),
        ),
        (
            "IRB 6640",
            load_str(&data("abb/irb6640_185_280.urdf"), Some("tool0")),
        ),
        ("IRB 140 URDF", load_str(IRB140_URDF, None)),
    ]
}

#[test]
fn the_irb140_urdf_gives_the_hand_written_parameters() {
    let robot = load_str(IRB140_URDF, None);
    assert_eq!(robot.ik_method(), IkMethod::Opw);
    let d = robot.detected_opw_parameters().unwrap();
    assert_eq!(robot.opw_parameters(), Some(&d));
    let h = OpwParameters::irb140();
    let pairs = [
        (d.a1, h.a1),
        (d.a2, h.a2),
        (d.b, h.b),
        (d.c1, h.c1),
        (d.c2, h.c2),
        (d.c3, h.c3),
        (d.c4, h.c4),
    ];
    for (k, (a, b)) in pairs.iter().enumerate() {
        assert!((a - b).abs() < 1e-15, "length {k}: {a} vs {b}");
    }
    for i in 0..6 {
        assert!(
            (d.offsets[i] - h.offsets[i]).abs() < 1e-15,
            "{:?}",
            d.offsets
        );
        assert_eq!(d.signs[i], h.signs[i]);
    }
    let (dp, dr) = distance(&d.tool, &h.tool);
    assert!(dp < 1e-15 && dr < 1e-15, "tool {dp:e} {dr:e}");
    println!("IRB 140 URDF: detected {d:?}");
}

/// The IRB 2400 URDF gives the parameters ROS-Industrial `opw_kinematics` publishes for
/// that arm (`opw_parameters_examples.h`, `makeIrb2400_10`: a1 0.100, a2 −0.135, b 0,
/// c1 0.615, c2 0.705, c3 0.755, c4 0.085 m, offsets (0, 0, −π/2, 0, 0, 0), signs +1),
/// with `tool0` the raw OPW end frame up to the URDF's rounded π/2 (`1.57079632679`).
#[test]
fn the_irb2400_urdf_gives_the_published_opw_parameters() {
    let robot = load_str(&data("abb/irb2400.urdf"), Some("tool0"));
    let d = robot.detected_opw_parameters().unwrap();
    let got = [d.a1, d.a2, d.b, d.c1, d.c2, d.c3, d.c4];
    let published = [0.100, -0.135, 0.0, 0.615, 0.705, 0.755, 0.085];
    for (g, p) in got.iter().zip(published) {
        assert!((g - p).abs() < 1e-12, "{got:?}");
    }
    let offsets = [0.0, 0.0, -PI / 2.0, 0.0, 0.0, 0.0];
    for (got, want) in d.offsets.iter().zip(offsets) {
        assert!((got - want).abs() < 1e-12, "{:?}", d.offsets);
    }
    assert_eq!(d.signs, [1.0; 6]);
    let (dp, dr) = distance(&d.tool, &Isometry3::identity());
    assert!(dp < 1e-12 && dr < 1e-10, "tool {dp:e} m {dr:e} rad");
}

#[test]
fn abb_urdfs_use_the_opw_closed_form_and_solve_every_reachable_pose() {
    for (k, (name, robot)) in abb_arms().into_iter().enumerate() {
        assert_eq!(robot.ik_method(), IkMethod::Opw, "{name}");
        assert!(robot.ik_method().description().contains("OPW closed form"));
        assert!(robot.ur_kinematics().is_none(), "{name}");
        let opw = *robot.opw_parameters().unwrap();
        let (lo, up) = limits(&robot);
        let solver = IkSolver::new(opw, lo, up).unwrap();
        let mut fk = RobotDynamics::new(robot.clone());
        let mut robust =
            RobustIk::new(6, &lo, &up, robot.start_q(), RobustIkSettings::default()).unwrap();
        let mut rng = rng::SplitMix64::new(0x0b00_0000 + k as u64);
        let (mut worst_p, mut worst_r, mut branches, mut agree, mut both) =
            (0.0f64, 0.0f64, 0, 0, 0);
        let start: [f64; 6] = std::array::from_fn(|i| robot.start_q()[i]);
        for _ in 0..POSES {
            let q = random_q(&robot, &mut rng);
            let target = fk.flange_pose(&q);
            // The closed form's own forward kinematics is the model's.
            let (dp, dr) = distance(&target, &opw.forward(&q));
            assert!(dp <= 1e-12 && dr <= 1e-12, "{name}: FK {dp:e} {dr:e}");
            // The planner's choice: nearest to the start pose, within the limits.
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
            let all = opw.inverse_near(&target, &q);
            branches += all.len();
            for b in all.as_slice() {
                let (dp, dr) = distance(&target, &fk.flange_pose(b));
                assert!(
                    dp <= 1e-9 && dr <= 1e-9,
                    "{name} {b:?}: {dp:e} m {dr:e} rad"
                );
                (worst_p, worst_r) = (worst_p.max(dp), worst_r.max(dr));
            }
            let has = |x: &[f64]| {
                all.as_slice()
                    .iter()
                    .any(|b| b.iter().zip(x).all(|(a, c)| same_angle(*a, *c)))
            };
            assert!(has(&q), "{name}: q {q:?} is not among the branches");
            // The numeric solver's solution, where it finds one, is a branch.
            let mut x = robot.start_q().to_vec();
            if robust.solve(&mut fk, &target, &mut x).is_ok() {
                both += 1;
                agree += usize::from(has(&x));
            }
        }
        println!(
            "{name}: {POSES}/{POSES} solved, worst {worst_p:.1e} m {worst_r:.1e} rad over the \
             chosen solutions and all {branches} branches; numeric solution among the \
             branches {agree}/{both}"
        );
        assert_eq!(agree, both, "{name}");
        assert!(both >= POSES * 9 / 10, "{name}: numeric solved {both}");
    }
}

#[test]
fn a_ur_and_perturbed_chains_are_not_opw() {
    let ur5 = load_str(&data("ur/ur5_robot.urdf"), None);
    assert!(ur5.detected_opw_parameters().is_none());
    assert_eq!(ur5.ik_method(), IkMethod::Ur);
    let text = data("abb/irb2400.urdf");
    let joint = |name: &str| {
        let at = text.find(&format!("<joint name=\"{name}\"")).unwrap();
        at + text[at..].find("</joint>").unwrap()
    };
    // (what, joint, old text, new text): each breaks one OPW condition by 1e-3.
    let cases = [
        (
            "axis 3 tilted out of ∥ axis 2",
            "joint_3",
            "<axis xyz=\"0 1 0\"/>",
            "<axis xyz=\"0 1 0.001\"/>",
        ),
        (
            "axis 5 tilted out of ⟂ axis 4",
            "joint_5",
            "<axis xyz=\"0 1 0\"/>",
            "<axis xyz=\"0.001 1 0\"/>",
        ),
        (
            "axis 2 tilted out of ⟂ axis 1",
            "joint_2",
            "<axis xyz=\"0 1 0\"/>",
            "<axis xyz=\"0 1 0.001\"/>",
        ),
        (
            "wrist axes 1 mm apart",
            "joint_5",
            "xyz=\"0.497 0 0\"",
            "xyz=\"0.497 0.001 0\"",
        ),
    ];
    for (what, name, old, new) in cases {
        let end = joint(name);
        let start = text[..end].rfind("<joint").unwrap();
        let block = &text[start..end];
        assert!(block.contains(old), "{what}: {block}");
        let changed = format!(
            "{}{}{}",
            &text[..start],
            block.replacen(old, new, 1),
            &text[end..]
        );
        let robot = load_str(&changed, Some("tool0"));
        assert!(robot.detected_opw_parameters().is_none(), "{what}");
        assert_eq!(robot.ik_method(), IkMethod::Numeric, "{what}");
    }
}

/// The OPW configuration of `q`: shoulder (wrist centre in front of or behind axis 1),
/// elbow (θ3 + ψ3 positive or negative) and wrist (sin θ5 positive or negative), from the
/// parameters' internal angles θᵢ = qᵢ·signᵢ − offsetᵢ (Brandstötter et al. 2014).
fn configuration(p: &OpwParameters, q: &[f64]) -> [bool; 3] {
    let t: Vec<f64> = (0..6).map(|i| q[i] * p.signs[i] - p.offsets[i]).collect();
    let (k, psi3) = (p.a2.hypot(p.c3), p.a2.atan2(p.c3));
    let x1 = p.c2 * t[1].sin() + k * (t[1] + t[2] + psi3).sin() + p.a1;
    [x1 > 0.0, (t[2] + psi3).sin() > 0.0, t[4].sin() > 0.0]
}

/// A 100 mm square with a semicircle, at a mid-range pose of the IRB 2400 with a tool
/// centre point 150 mm out and tilted: planned through the OPW closed form (G61, 10 ms),
/// every sample's tool pose on the path to 1e-9, one configuration throughout and no
/// joint step beyond 0.05 rad.
#[test]
fn a_square_with_an_arc_on_the_irb2400_stays_on_one_branch() {
    use ofmpc::gcode::ParseOptions;
    use ofmpc::motion::{plan, PlanOptions};
    let program = "G21 G90 G17\nG0 X0 Y0 Z0\nG1 X50 F1200\nG1 X50 Y100\nG3 X-50 Y100 I-50 J0\nG1 X-50 Y0\nG1 X0 Y0\n";
    let mut robot = load_str(&data("abb/irb2400.urdf"), Some("tool0"));
    let tcp = Isometry3::from_parts(
        Translation3::new(0.01, -0.02, 0.15),
        UnitQuaternion::from_euler_angles(0.2, -0.1, 0.3),
    );
    robot.set_tcp(Transform::from_isometry(&tcp)).unwrap();
    assert_eq!(robot.ik_method(), IkMethod::Opw);
    let q0 = [0.3, 0.4, -0.2, 0.5, -0.9, 0.4];
    robot.set_start_q(&q0).unwrap();
    let mut fk = RobotDynamics::new(robot.clone());
    let start = fk.flange_pose(&q0);
    let p = start.translation.vector;
    let options = PlanOptions {
        parse: ParseOptions {
            origin: Some([p.x, p.y - 0.05, p.z]),
            ..ParseOptions::default()
        },
        ..PlanOptions::default()
    };
    let planned = plan(program, &robot, &options).unwrap();
    let r = &planned.reference;
    let opw = *robot.opw_parameters().unwrap();
    let first = configuration(&opw, r.q(0));
    assert_eq!(first, configuration(&opw, &q0));
    let (mut max_step, mut worst_p, mut worst_r) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..r.len() {
        assert_eq!(configuration(&opw, r.q(k)), first, "sample {k}");
        if k > 0 {
            for i in 0..6 {
                max_step = max_step.max((r.q(k)[i] - r.q(k - 1)[i]).abs());
            }
        }
        let pose = fk.flange_pose(r.q(k));
        let target = Isometry3::from_parts(
            Translation3::from(nalgebra::Vector3::from(r.position(k))),
            start.rotation,
        );
        let (dp, dr) = distance(&target, &pose);
        (worst_p, worst_r) = (worst_p.max(dp), worst_r.max(dr));
    }
    println!(
        "IRB 2400 path with TCP: {} samples, one configuration {first:?}, largest joint step \
         {max_step:.4} rad, tool pose off the path by at most {worst_p:.1e} m {worst_r:.1e} rad",
        r.len()
    );
    assert!(
        max_step < 0.05,
        "a joint steps {max_step} rad in one sample"
    );
    assert!(
        worst_p <= 1e-9 && worst_r <= 1e-9,
        "{worst_p:e} m {worst_r:e} rad"
    );
}
