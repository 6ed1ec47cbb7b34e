//! Bad robot descriptions get clear errors, never panics.

mod common;

use ofmpc::dynamics::{crba, rnea, Workspace};
use ofmpc::robot::{Drives, ModelError, Payload, Robot};

fn err(text: &str) -> String {
    Robot::from_urdf_str(text)
        .expect_err("must be rejected")
        .to_string()
}

const LINK: &str = "<inertial><mass value=\"1\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial>";

fn joint(name: &str, kind: &str, parent: &str, child: &str) -> String {
    format!("<joint name=\"{name}\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"{child}\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" velocity=\"1\" effort=\"1\"/></joint>")
}

#[test]
fn branching_tree_is_not_a_serial_chain() {
    let t = format!(
        "<robot name=\"y\"><link name=\"b\"/><link name=\"l\">{LINK}</link><link name=\"r\">{LINK}</link>{}{}</robot>",
        joint("jl", "revolute", "b", "l"),
        joint("jr", "revolute", "b", "r")
    );
    let e = err(&t);
    assert!(
        e.contains("not a serial chain")
            && e.contains("'b'")
            && e.contains("jl")
            && e.contains("jr"),
        "{e}"
    );
}

#[test]
fn fixed_side_branches_are_allowed_and_add_their_mass() {
    let t = format!(
        "<robot name=\"y\"><link name=\"b\"/><link name=\"l\">{LINK}</link><link name=\"cam\">{LINK}</link>{}{}</robot>",
        joint("jl", "revolute", "b", "l"),
        joint("jc", "fixed", "l", "cam")
    );
    let r = Robot::from_urdf_str(&t).unwrap();
    assert_eq!(r.dof(), 1);
    assert!((r.moving_mass() - 2.0).abs() < 1e-12);
}

#[test]
fn missing_inertial_is_named() {
    // Issue #19: the file loads for kinematics (with a warning); what needs the dynamics
    // asks `require_inertials`, which names the link, its joint and what to add.
    let t = format!(
        "<robot name=\"m\"><link name=\"b\"/><link name=\"l\"/>{}</robot>",
        joint("j", "revolute", "b", "l")
    );
    let r = Robot::from_urdf_str(&t).unwrap();
    assert!(
        r.warnings()
            .iter()
            .any(|w| w.to_string().contains("'l'") || w.to_string().contains(" l ")),
        "{:?}",
        r.warnings()
    );
    let e = r.require_inertials().unwrap_err().to_string();
    assert!(e.contains("<inertial>") && e.contains("<mass"), "{e}");
    assert!(
        e.contains("link 'l'") && e.contains("no inertial") && e.contains("joint 'j'"),
        "{e}"
    );
}

#[test]
fn unsupported_joint_types_and_bad_numbers_are_rejected() {
    let t = format!(
        "<robot name=\"m\"><link name=\"b\"/><link name=\"l\">{LINK}</link>{}</robot>",
        joint("j", "floating", "b", "l")
    );
    assert!(err(&t).contains("floating") || err(&t).contains("Floating"));
    let bad_inertia = LINK.replace("ixx=\"0.01\"", "ixx=\"-1\"");
    let t = format!(
        "<robot name=\"m\"><link name=\"b\"/><link name=\"l\">{bad_inertia}</link>{}</robot>",
        joint("j", "revolute", "b", "l")
    );
    assert!(err(&t).contains("link 'l'"), "{}", err(&t));
    let t = format!(
        "<robot name=\"m\"><link name=\"b\"/><link name=\"l\">{LINK}</link>{}</robot>",
        joint("j", "revolute", "b", "l").replace("0 0 1", "0 0 0")
    );
    assert!(err(&t).contains("axis"));
    assert!(err("<robot name=\"x\"><link name=\"a\"").contains("invalid URDF"));
    assert!(
        err("<robot name=\"x\"><link name=\"a\"/></robot>").contains("no revolute or prismatic")
    );
    let loop_ = format!(
        "<robot name=\"m\"><link name=\"b\"/><link name=\"l\">{LINK}</link>{}{}</robot>",
        joint("j", "revolute", "b", "l"),
        joint("k", "revolute", "l", "b")
    );
    assert!(err(&loop_).contains("root"), "{}", err(&loop_));
}

#[test]
fn wrong_lengths_and_nan_are_errors() {
    let robot = Robot::irb140();
    let mut ws = Workspace::new(&robot);
    let e = crba(&robot, &mut ws, &[0.0; 5]).unwrap_err();
    assert!(
        matches!(
            e,
            ModelError::Dimension {
                expected: 6,
                got: 5,
                ..
            }
        ),
        "{e}"
    );
    let e = rnea(
        &robot,
        &mut ws,
        &[0.0; 6],
        &[0.0, f64::NAN, 0.0, 0.0, 0.0, 0.0],
        &[0.0; 6],
    )
    .unwrap_err();
    assert!(e.to_string().contains("qd[1] (joint 2) is NaN"), "{e}");
}

#[test]
fn bad_drives_and_payloads_are_errors() {
    let e = Drives::from_toml_str("[joints.joint_1]\narmature_kgm2 = -1.0\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("armature_kgm2") && e.contains("≥ 0"), "{e}");
    let e = Drives::from_toml_str("[joints.joint_1]\narmature_kgm2 = \n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 2"), "{e}");
    let e = Drives::from_toml_str("[joints.joint_1]\narmature = 1.0\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown key 'armature'"), "{e}");
    let mut robot = Robot::irb140();
    let e = robot
        .apply_drives(&Drives::from_toml_str("[joints.joint_9]\narmature_kgm2 = 1.0\n").unwrap())
        .unwrap_err();
    assert!(e.to_string().contains("joint_9"));
    assert!(robot.set_payload(Some(Payload::point_mass(-1.0))).is_err());
    assert!(robot
        .set_payload(Some(Payload::point_mass(f64::NAN)))
        .is_err());
    assert!(Robot::builtin("puma")
        .unwrap_err()
        .to_string()
        .contains("irb140"));
}

#[test]
fn random_garbage_urdf_never_panics() {
    let mut rng = common::robots::Rng(11);
    let base = common::robots::random_urdf(&mut rng, 4, true);
    let bytes = base.as_bytes();
    for _ in 0..300 {
        let mut b = bytes.to_vec();
        for _ in 0..5 {
            let i = (rng.uniform() * b.len() as f64) as usize % b.len();
            b[i] = b"<>/\"= 0-.e9xyz"[(rng.uniform() * 14.0) as usize % 14];
        }
        let text = String::from_utf8_lossy(&b);
        if let Ok(r) = Robot::from_urdf_str(&text) {
            let mut ws = Workspace::new(&r);
            let _ = crba(&r, &mut ws, &vec![0.1; r.dof()]);
        }
    }
}

/// Issue 9 item 5: a misspelled table or key, or an empty file, is an error
/// that names it; joints a file sets nothing for are reported.
#[test]
fn drives_files_are_read_strictly() {
    use ofmpc::robot::DrivesError;
    let err = |text: &str| match Drives::from_toml_str(text).unwrap_err() {
        ofmpc::robot::ModelError::Drives { error, .. } => error,
        e => panic!("expected a drives error, got {e:?}"),
    };
    // `[joint.joint_1]` (singular) is an unknown table, `jionts = 1` an unknown key.
    match err("[joint.joint_1]\narmature_kgm2 = 1.0\n") {
        DrivesError::UnknownKey { what, key, .. } => {
            assert_eq!((what, key.as_str()), ("table", "joint"))
        }
        e => panic!("{e:?}"),
    }
    match err("jionts = 1\n[joints.joint_1]\narmature_kgm2 = 1.0\n") {
        DrivesError::UnknownKey { what, key, .. } => {
            assert_eq!((what, key.as_str()), ("key", "jionts"))
        }
        e => panic!("{e:?}"),
    }
    assert_eq!(err(""), DrivesError::Empty);
    assert_eq!(
        err("# only a comment\n[meta]\nrobot = \"x\"\n"),
        DrivesError::Empty
    );
    let e = err("[joints.joint_1]\nmax_torque_nm = -3\n");
    assert!(
        matches!(e, DrivesError::Value { value, .. } if value == -3.0),
        "{e:?}"
    );
    // A file that sets two joints of six: the other four are named.
    let mut robot = Robot::from_urdf_str(ofmpc::robot::IRB140_URDF).unwrap();
    let d = Drives::from_toml_str(
        "[joints.joint_1]\narmature_kgm2 = 1.0\n[joints.joint_6]\narmature_kgm2 = 0.1\n",
    )
    .unwrap();
    let unset = robot.apply_drives(&d).unwrap();
    assert_eq!(unset, ["joint_2", "joint_3", "joint_4", "joint_5"]);
    assert_eq!(robot.joints()[0].armature, 1.0);
    let all = Drives::from_toml_str(ofmpc::robot::IRB140_DRIVES).unwrap();
    assert!(robot.apply_drives(&all).unwrap().is_empty());
    // An unknown joint names the robot's joints.
    let e = robot
        .apply_drives(&Drives::from_toml_str("[joints.joint_9]\narmature_kgm2 = 1.0\n").unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("joint_9") && e.contains("joint_1, joint_2"),
        "{e}"
    );
}

fn one_joint(limit: &str, extra: &str, kind: &str) -> String {
    format!(
        "<robot name=\"r\"><link name=\"b\"/><link name=\"l\">{LINK}</link>\
         <joint name=\"j1\" type=\"{kind}\"><parent link=\"b\"/><child link=\"l\"/><axis xyz=\"0 0 1\"/>{limit}{extra}</joint></robot>"
    )
}

fn urdf_error(text: &str) -> ofmpc::robot::UrdfError {
    match Robot::from_urdf_str(text).expect_err("must be rejected") {
        ModelError::Structure { error, .. } => error,
        e => panic!("expected a structure error, got {e:?}"),
    }
}

/// Issue 9 item 6: the URDF specification's required limits, `<mimic>`, and
/// what is ignored is said, never reinterpreted silently.
#[test]
fn urdf_limits_follow_the_specification() {
    use ofmpc::robot::{UrdfError, UrdfWarning};
    let full = "<limit lower=\"-1\" upper=\"1\" velocity=\"2\" effort=\"30\"/>";
    let r = Robot::from_urdf_str(&one_joint(full, "", "revolute")).unwrap();
    assert_eq!(r.joints()[0].limits.effort, 30.0);
    assert!(r.warnings().is_empty());
    // lower == upper: an empty range, not "continuous".
    let e = urdf_error(&one_joint(
        "<limit lower=\"0.5\" upper=\"0.5\" velocity=\"2\" effort=\"30\"/>",
        "",
        "revolute",
    ));
    assert!(
        matches!(&e, UrdfError::EmptyRange { joint, value, .. } if joint == "j1" && *value == 0.5),
        "{e:?}"
    );
    // No <limit> at all on a revolute or prismatic joint.
    for kind in ["revolute", "prismatic"] {
        let e = urdf_error(&one_joint("", "", kind));
        assert!(
            matches!(
                e,
                UrdfError::EmptyRange { .. } | UrdfError::MissingLimit { .. }
            ),
            "{kind}: {e:?}"
        );
        assert!(e.to_string().contains("URDF specification"), "{e}");
    }
    // velocity or effort = 0: "not given" as ROS tools read it (issue #19), a warning and
    // no limit; < 0: an error.
    for attr in ["velocity", "effort"] {
        let lim = if attr == "velocity" {
            "<limit lower=\"-1\" upper=\"1\" velocity=\"0\" effort=\"30\"/>"
        } else {
            "<limit lower=\"-1\" upper=\"1\" velocity=\"2\" effort=\"0\"/>"
        };
        let r = Robot::from_urdf_str(&one_joint(lim, "", "revolute")).unwrap();
        let l = r.joints()[0].limits;
        let unlimited = if attr == "velocity" {
            l.velocity
        } else {
            l.effort
        };
        assert_eq!(unlimited, f64::INFINITY);
        assert!(
            matches!(&r.warnings()[0], UrdfWarning::UnspecifiedLimit { attribute, .. } if *attribute == attr),
            "{:?}",
            r.warnings()
        );
    }
    for (lim, attr) in [
        (
            "<limit lower=\"-1\" upper=\"1\" velocity=\"-1\" effort=\"30\"/>",
            "velocity",
        ),
        (
            "<limit lower=\"-1\" upper=\"1\" velocity=\"2\" effort=\"-5\"/>",
            "effort",
        ),
    ] {
        let e = urdf_error(&one_joint(lim, "", "revolute"));
        assert!(
            matches!(&e, UrdfError::MissingLimit { attribute, .. } if *attribute == attr),
            "{e:?}"
        );
    }
    // A continuous joint may omit them: unlimited.
    let r = Robot::from_urdf_str(&one_joint("", "", "continuous")).unwrap();
    let l = r.joints()[0].limits;
    assert!(
        l.lower == f64::NEG_INFINITY && l.velocity == f64::INFINITY && l.effort == f64::INFINITY
    );
    // <mimic> is rejected by name.
    let e = urdf_error(&one_joint(
        full,
        "<mimic joint=\"j0\" multiplier=\"2\"/>",
        "revolute",
    ));
    assert!(
        matches!(&e, UrdfError::Mimic { joint, of } if joint == "j1" && of == "j0"),
        "{e:?}"
    );
    // <dynamics> and <safety_controller> are ignored with a warning each.
    let r = Robot::from_urdf_str(&one_joint(
        full,
        "<dynamics damping=\"0.5\" friction=\"1\"/><safety_controller soft_lower_limit=\"-0.9\" soft_upper_limit=\"0.9\" k_velocity=\"1\"/>",
        "revolute",
    ))
    .unwrap();
    assert_eq!(
        r.warnings(),
        [
            UrdfWarning::IgnoredDynamics {
                joint: "j1".into(),
                damping: 0.5,
                friction: 1.0
            },
            UrdfWarning::IgnoredSafetyController("j1".into())
        ]
    );
}

/// Issue 9 item 3: thousands of chained fixed joints load without
/// recursion (no stack overflow) and in linear time, and fold their masses.
#[test]
fn a_long_chain_of_fixed_frames_loads() {
    let n_fixed = 5_000;
    let mut s = String::from("<robot name=\"long\"><link name=\"b\"/>");
    s += &format!("<link name=\"l\">{LINK}</link>");
    s += "<joint name=\"j1\" type=\"revolute\"><parent link=\"b\"/><child link=\"l\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" velocity=\"1\" effort=\"1\"/></joint>";
    let mut parent = "l".to_string();
    for i in 0..n_fixed {
        let child = format!("f{i}");
        s += &format!("<link name=\"{child}\">{LINK}</link><joint name=\"x{i}\" type=\"fixed\"><parent link=\"{parent}\"/><child link=\"{child}\"/><origin xyz=\"0 0 0.001\"/></joint>");
        parent = child;
    }
    s += "</robot>";
    // Run on a thread with a small stack: a recursive walk would overflow it.
    let robot = std::thread::Builder::new()
        .stack_size(256 * 1024)
        .spawn(move || Robot::from_urdf_str(&s))
        .unwrap()
        .join()
        .expect("no stack overflow")
        .unwrap();
    assert_eq!(robot.dof(), 1);
    assert!((robot.moving_mass() - (n_fixed + 1) as f64).abs() < 1e-6);
    // The flange is the last link of the chain, 20 m up.
    assert_eq!(robot.flange_name(), format!("f{}", n_fixed - 1));
    assert!((robot.flange_offset().pos.z - n_fixed as f64 * 0.001).abs() < 1e-9);
}

/// Issue 9 items 7 and 18: a workspace of another robot is an error (it
/// panicked), and so is a result that overflows (q̇ = 1e160).
#[test]
fn workspace_mismatch_and_overflowing_results_are_errors() {
    use ofmpc::dynamics::{coriolis_matrix, forward_dynamics, gravity, joint_space_terms};
    let robot = Robot::irb140();
    let small = Robot::from_urdf_str(&one_joint(
        "<limit lower=\"-1\" upper=\"1\" velocity=\"2\" effort=\"30\"/>",
        "",
        "revolute",
    ))
    .unwrap();
    let mut ws = Workspace::new(&small);
    let z = [0.0; 6];
    let mismatch = |e: ModelError| {
        matches!(
            e,
            ModelError::WorkspaceMismatch {
                workspace: 1,
                robot: 6
            }
        )
    };
    assert!(mismatch(rnea(&robot, &mut ws, &z, &z, &z).unwrap_err()));
    assert!(mismatch(crba(&robot, &mut ws, &z).unwrap_err()));
    assert!(mismatch(gravity(&robot, &mut ws, &z).unwrap_err()));
    assert!(mismatch(
        coriolis_matrix(&robot, &mut ws, &z, &z).unwrap_err()
    ));
    assert!(mismatch(
        forward_dynamics(&robot, &mut ws, &z, &z, &z).unwrap_err()
    ));
    assert!(mismatch(
        joint_space_terms(&robot, &mut ws, &z, &z).unwrap_err()
    ));
    assert!(mismatch(
        ofmpc::dynamics::forward_kinematics(&robot, &mut ws, &z).unwrap_err()
    ));
    assert!(mismatch(
        ofmpc::dynamics::flange_jacobian(&robot, &mut ws, &z).unwrap_err()
    ));
    let mut ws = Workspace::new(&robot);
    let qd = [1e160, 0.0, 0.0, 0.0, 0.0, 0.0];
    let e = rnea(&robot, &mut ws, &z, &qd, &z).unwrap_err();
    assert!(
        matches!(e, ModelError::NonFiniteResult { what: "tau", .. }),
        "{e:?}"
    );
}

/// Issue 9 item 17: an absurd payload is blamed on the payload.
#[test]
fn an_absurd_payload_is_named() {
    use ofmpc::robot::PayloadError;
    let mut robot = Robot::irb140();
    let e = robot
        .set_payload(Some(Payload::point_mass(1e20)))
        .unwrap_err();
    assert!(
        matches!(e, ModelError::InvalidPayload(PayloadError::TooHeavy { mass, .. }) if mass == 1e20),
        "{e:?}"
    );
    assert!(e.to_string().contains("payload"), "{e}");
    robot.set_payload(Some(Payload::point_mass(6.0))).unwrap();
    robot
        .set_payload(Some(Payload::point_mass(1e-300)))
        .unwrap();
}
