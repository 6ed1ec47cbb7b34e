//! URDFs as ROS packages ship them (issue #19): ROS-Industrial's ABB IRB 2400 and
//! IRB 6640 write `effort="0"` ("not given") and carry no `<inertial>`. They load for
//! kinematics with warnings, plan a program, and what needs the dynamics names the links
//! that lack inertials. Principal moments off the triangle inequality by at most 1 % are
//! accepted with a warning naming the link and the excess; beyond, an error says so.

use ofmpc::dynamics::RobotDynamics;
use ofmpc::gcode::ParseOptions;
use ofmpc::ik::ForwardKinematics;
use ofmpc::motion::{plan, PlanOptions};
use ofmpc::robot::{ChainOptions, Robot, UrdfWarning};
use std::path::Path;

/// The IRB 6640's counterbalance (cylinder and piston) is a second moving branch: its
/// chain is chosen by its tip, `tool0`, and the branch is held rigid.
fn abb(file: &str) -> Robot {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/robots/abb")
        .join(file);
    let options = ChainOptions {
        tip: Some("tool0".into()),
        tcp: None,
    };
    Robot::from_urdf_file_with(&p, &options).unwrap_or_else(|e| panic!("{file}: {e}"))
}

#[test]
fn ros_industrial_abb_urdfs_plan_and_name_their_missing_inertials() {
    for file in ["irb2400.urdf", "irb6640_185_280.urdf"] {
        let mut robot = abb(file);
        assert_eq!(robot.dof(), 6);
        assert_eq!(robot.flange_name(), "tool0");
        let unspecified = robot
            .warnings()
            .iter()
            .filter(|w| matches!(w, UrdfWarning::UnspecifiedLimit { attribute, .. } if *attribute == "effort"))
            .count();
        assert_eq!(unspecified, 6, "{file}: {:?}", robot.warnings());
        assert!(robot
            .joints()
            .iter()
            .all(|j| j.limits.effort == f64::INFINITY));
        let e = robot.require_inertials().unwrap_err().to_string();
        for l in ["link_1", "link_2", "link_3", "link_4", "link_5", "link_6"] {
            assert!(e.contains(&format!("link '{l}'")), "{file}: {e}");
        }
        assert!(
            e.contains("<inertial>") && e.contains("<mass value>"),
            "{e}"
        );
        // A square in front of a bent pose plans.
        let q = [0.2, 0.3, 0.2, 0.1, 0.6, 0.2];
        robot.set_start_q(&q).unwrap();
        let p = RobotDynamics::new(robot.clone())
            .flange_pose(&q)
            .translation
            .vector;
        let options = PlanOptions {
            parse: ParseOptions {
                origin: Some([p.x, p.y, p.z]),
                ..ParseOptions::default()
            },
            ..PlanOptions::default()
        };
        let program = "G21 G90\nG0 X0 Y0 Z0\nG1 X100 F3000\nY100\nX0\nY0\n";
        let planned = plan(program, &robot, &options).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(planned.reference.len() > 100);
    }
}

fn one_link(moments: [f64; 3]) -> String {
    let [a, b, c] = moments;
    format!(
        "<robot name=\"t\"><link name=\"b\"/><link name=\"l\"><inertial><mass value=\"1\"/>\
         <inertia ixx=\"{a}\" ixy=\"0\" ixz=\"0\" iyy=\"{b}\" iyz=\"0\" izz=\"{c}\"/></inertial></link>\
         <joint name=\"j\" type=\"revolute\"><parent link=\"b\"/><child link=\"l\"/><axis xyz=\"0 0 1\"/>\
         <limit lower=\"-1\" upper=\"1\" velocity=\"1\" effort=\"1\"/></joint></robot>"
    )
}

#[test]
fn inertia_off_the_triangle_inequality_by_at_most_one_percent_is_a_warning() {
    // c = 2.015: (c − a − b)/c = 0.74 % (the xArm 6's link 2 is off by 0.75 %).
    let r = Robot::from_urdf_str(&one_link([1.0, 1.0, 2.015])).unwrap();
    match &r.warnings()[0] {
        UrdfWarning::InertiaTriangle { link, excess, .. } => {
            assert_eq!(link, "l");
            assert!((excess - 0.015 / 2.015).abs() < 1e-12);
        }
        w => panic!("{w:?}"),
    }
    assert!(r.warnings()[0].to_string().contains("0.744 %"));
    // c = 2.05: 2.4 %, an error that gives the excess and the tolerance.
    let e = Robot::from_urdf_str(&one_link([1.0, 1.0, 2.05]))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("link 'l'") && e.contains("2.44 %") && e.contains("1 %"),
        "{e}"
    );
}
