//! The paper's path (Table I, with G17 and the work offset) in joint space.

use ofmpc::dynamics::{forward_kinematics, Workspace};
use ofmpc::gcode::{parse, ParseOptions, PAPER_TABLE1};
use ofmpc::motion::{build_reference, Orientation};
use ofmpc::motion::{CartesianTrajectory, TimingOptions};
use ofmpc::robot::Robot;

#[test]
fn ik_along_the_paper_path_is_exact_within_limits_and_speed() {
    let robot = Robot::irb140();
    let program = parse(PAPER_TABLE1, &ParseOptions::default()).unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let ts = 0.01;
    let r = build_reference(&robot, &traj, Orientation::AtZero, ts).unwrap();
    assert!(r.len() > 100);
    let mut ws = Workspace::new(&robot);
    let rot0 = forward_kinematics(&robot, &mut ws, &[0.0; 6]).unwrap().rot;
    let (mut max_p, mut max_r) = (0.0f64, 0.0f64);
    for k in 0..r.len() {
        let q = r.q(k);
        let f = *forward_kinematics(&robot, &mut ws, q).unwrap();
        let p = r.position(k);
        max_p = max_p.max((f.pos - nalgebra::Vector3::from(p)).norm());
        max_r = max_r.max((f.rot - rot0).abs().max());
        for (i, j) in robot.joints().iter().enumerate() {
            // Every joint well inside its limits (docs/guide/paper-notes.md, "The test path": at least 10°).
            let margin = (q[i] - j.limits.lower).min(j.limits.upper - q[i]);
            assert!(
                margin > 10f64.to_radians() - 1e-6,
                "joint {} margin {margin} at k = {k}",
                i + 1
            );
            if k > 0 {
                let step = (q[i] - r.q(k - 1)[i]).abs();
                assert!(
                    step <= j.limits.velocity * ts,
                    "joint {} step {step} at k = {k}",
                    i + 1
                );
            }
        }
        // Clear of the wrist singularity.
        assert!(q[4].abs() > 30f64.to_radians(), "q5 = {} at k = {k}", q[4]);
    }
    assert!(max_p < 1e-9, "FK(IK) position error {max_p:e}");
    assert!(max_r < 1e-9, "FK(IK) rotation error {max_r:e}");
    // The path in the base frame: x 380..780 mm, z 150 mm.
    let xs: Vec<f64> = (0..r.len()).map(|k| r.position(k)[0]).collect();
    let (lo, hi) = xs
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(
        (lo - 0.380).abs() < 1e-4 && (hi - 0.780).abs() < 1e-9,
        "x range {lo}..{hi}"
    );
    assert!((0..r.len()).all(|k| (r.position(k)[2] - 0.150).abs() < 1e-12));
}

#[test]
fn the_paper_program_read_in_the_base_frame_is_rejected_with_a_work_offset_hint() {
    let robot = Robot::irb140();
    let text = PAPER_TABLE1.replace("G10 L2 P1 X150 Y0 Z-250", "");
    let program = parse(&text, &ParseOptions::default()).unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let e = build_reference(&robot, &traj, Orientation::AtZero, 0.01).unwrap_err();
    let msg = e.to_string();
    eprintln!("{msg}");
    assert!(
        msg.contains("program line") && msg.contains("work offset"),
        "{msg}"
    );
    assert!(msg.contains("joint 3") && msg.contains("50.0°"), "{msg}");
}

#[test]
fn numeric_ik_is_used_for_other_robots_and_agrees() {
    // The same IRB 140 with a moved flange frame: OPW no longer matches, the
    // numeric solver takes over; FK(IK) must still be exact.
    let urdf = ofmpc::robot::IRB140_URDF.replace(
        "<origin xyz=\"0 0 0\" rpy=\"0 1.5707963267948966 0\"/>",
        "<origin xyz=\"0.01 0 0\" rpy=\"0 1.5707963267948966 0\"/>",
    );
    let robot = Robot::from_urdf_str(&urdf).unwrap();
    let program = parse(PAPER_TABLE1, &ParseOptions::default()).unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let r = build_reference(&robot, &traj, Orientation::AtZero, 0.02).unwrap();
    let mut ws = Workspace::new(&robot);
    for k in (0..r.len()).step_by(7) {
        let f = *forward_kinematics(&robot, &mut ws, r.q(k)).unwrap();
        assert!((f.pos - nalgebra::Vector3::from(r.position(k))).norm() < 1e-9);
    }
}

#[test]
fn reference_velocity_is_exact_and_agrees_with_differences() {
    let robot = Robot::irb140();
    let program = parse(PAPER_TABLE1, &ParseOptions::default()).unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let ts = 0.01;
    let r = build_reference(&robot, &traj, Orientation::AtZero, ts).unwrap();
    let mut ws = Workspace::new(&robot);
    let (mut worst_exact, mut worst_diff, mut peak) = (0.0f64, 0.0f64, 0.0f64);
    for k in 1..r.len() - 1 {
        let j = ofmpc::dynamics::flange_jacobian(&robot, &mut ws, r.q(k))
            .unwrap()
            .clone();
        let qd = nalgebra::DVector::from_column_slice(r.qd(k));
        let v = traj.sample(k as f64 * ts).velocity;
        let twist = &j * &qd;
        for c in 0..3 {
            worst_exact = worst_exact
                .max((twist[c] - v[c]).abs())
                .max(twist[c + 3].abs());
        }
        for i in 0..6 {
            let diff = (r.q(k + 1)[i] - r.q(k - 1)[i]) / (2.0 * ts);
            worst_diff = worst_diff.max((diff - r.qd(k)[i]).abs());
            peak = peak.max(r.qd(k)[i].abs());
        }
    }
    assert!(worst_exact < 1e-9, "J q̇ − [v; 0] = {worst_exact:e}");
    // Central differences are O(Ts²) accurate: within 1 % of the peak joint speed.
    assert!(worst_diff < 0.01 * peak, "{worst_diff} vs peak {peak}");
}
