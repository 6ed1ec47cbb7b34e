//! The motion planner as a CNC user sees it: G61 exact stop (the paper's law, unchanged),
//! G64 P blending within the tolerance, time-optimal timing under path and joint limits,
//! long programs that never stop, and bounded allocation.

use nalgebra::Vector3;
use ofmpc::gcode::{parse, ParseOptions, PAPER_TABLE1};
use ofmpc::motion::build_reference;
use ofmpc::motion::{
    plan, CartesianTrajectory, Orientation, Plan, PlanError, PlanOptions, SampleCause,
    TimingOptions, MAX_PLAN_VALUES,
};
use ofmpc::robot::Robot;
use std::fmt::Write;

fn plan_ok(text: &str, robot: &Robot) -> Plan {
    plan(text, robot, &PlanOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// Every sample of the reference within every joint's speed and acceleration limit.
fn assert_joint_limits(p: &Plan, robot: &Robot) -> (f64, f64) {
    let r = &p.reference;
    let (mut worst_v, mut worst_a) = (0.0f64, 0.0f64);
    for k in 0..r.len() {
        for (i, j) in robot.joints().iter().enumerate() {
            let (v, a) = (r.qd(k)[i].abs(), r.qdd(k)[i].abs());
            assert!(
                v <= j.limits.velocity * (1.0 + 1e-9),
                "joint {} speed {v} > {} at sample {k}",
                i + 1,
                j.limits.velocity
            );
            assert!(
                a <= j.limits.acceleration * (1.0 + 1e-9),
                "joint {} acceleration {a} > {} at sample {k}",
                i + 1,
                j.limits.acceleration
            );
            worst_v = worst_v.max(v / j.limits.velocity);
            worst_a = worst_a.max(a / j.limits.acceleration);
        }
    }
    (worst_v, worst_a)
}

/// The default plan options with the program placed at `origin` (m), Ts = 0.01 s.
fn at_origin(origin: [f64; 3]) -> PlanOptions {
    PlanOptions {
        parse: ParseOptions {
            origin: Some(origin),
            ..Default::default()
        },
        ts: 0.01,
        ..PlanOptions::default()
    }
}

fn dist_to_segment(p: Vector3<f64>, a: Vector3<f64>, b: Vector3<f64>) -> f64 {
    let u = b - a;
    let t = ((p - a).dot(&u) / u.norm_squared()).clamp(0.0, 1.0);
    (p - (a + u * t)).norm()
}

/// Largest distance (m) of the trajectory, sampled every `dt`, from the polygon `corners`.
fn deviation(tr: &CartesianTrajectory, corners: &[Vector3<f64>], dt: f64) -> f64 {
    let n = (tr.duration() / dt).ceil() as usize;
    (0..=n)
        .map(|k| {
            let p = tr.sample(k as f64 * dt).position;
            corners
                .windows(2)
                .map(|w| dist_to_segment(p, w[0], w[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// A closed polygon program around (x, y) = (cx, cy) mm at z mm, starting at angle 0.
fn polygon(n: usize, radius_mm: f64, feed: f64, mode: &str) -> (String, Vec<Vector3<f64>>) {
    let (cx, cy, z) = (500.0, 0.0, 400.0);
    let mut text = format!("G21 G90 {mode}\n");
    let mut corners = Vec::new();
    for k in 0..=n {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        let (x, y) = (cx + radius_mm * a.cos(), cy + radius_mm * a.sin());
        corners.push(Vector3::new(x, y, z) * 1e-3);
        if k == 0 {
            writeln!(text, "G0 X{x:.6} Y{y:.6} Z{z}").unwrap();
        } else if k == 1 {
            writeln!(text, "G1 X{x:.6} Y{y:.6} F{feed}").unwrap();
        } else {
            writeln!(text, "X{x:.6} Y{y:.6}").unwrap();
        }
    }
    (text, corners)
}

#[test]
fn the_papers_program_is_planned_exactly_as_before() {
    // G61 (the default): the entry point gives bit for bit the reference of the
    // rest-to-rest pipeline assembled by hand.
    let robot = Robot::irb140();
    let p = plan_ok(PAPER_TABLE1, &robot);
    let program = parse(PAPER_TABLE1, &ParseOptions::default()).unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let r = build_reference(&robot, &traj, Orientation::AtZero, 0.01).unwrap();
    assert_eq!(p.trajectory, traj);
    assert_eq!(p.reference, r);
    assert_eq!(p.diagnostics.runs, 0);
    // The septic law's duration of the eight moves at 0.5 m/s and 2.5 m/s² (as before
    // this planner existed: 11.623 s).
    assert!(
        (traj.duration() - 11.6228).abs() < 1e-4,
        "{}",
        traj.duration()
    );
}

#[test]
fn circle_polygon_blends_within_tolerance_at_the_programmed_feed() {
    // 360 segments approximating a circle of radius 100 mm, F6000 (0.1 m/s), G64 P0.05.
    let robot = Robot::irb140();
    let (text, corners) = polygon(360, 100.0, 6000.0, "G64 P0.05");
    let p = plan_ok(&text, &robot);
    let tr = &p.trajectory;
    let dev = deviation(tr, &corners, 1e-3);
    assert!(dev <= 0.05e-3, "deviation {} mm", dev * 1e3);
    let length: f64 = corners.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let f = 0.1;
    assert!(
        tr.duration() <= 1.2 * length / f + 1.0,
        "duration {} s for {} s at F",
        tr.duration(),
        length / f
    );
    // Between the end of the first segment and the start of the last, never below F/2.
    let seg = length / 360.0;
    let mut min_speed = f64::INFINITY;
    let mut s = 0.0;
    let n = (tr.duration() / 1e-3) as usize;
    let mut prev = tr.sample(0.0).position;
    for k in 1..=n {
        let smp = tr.sample(k as f64 * 1e-3);
        s += (smp.position - prev).norm();
        prev = smp.position;
        if s > seg && s < length - seg {
            min_speed = min_speed.min(smp.velocity.norm());
        }
    }
    assert!(min_speed >= 0.5 * f, "min speed {min_speed} m/s");
    assert_joint_limits(&p, &robot);
    eprintln!(
        "circle: deviation {:.4} mm, duration {:.3} s (L/F = {:.3} s), min speed {:.4} m/s",
        dev * 1e3,
        tr.duration(),
        length / f,
        min_speed
    );
}

#[test]
fn square_keeps_moving_through_corners_under_g64_and_stops_under_g61() {
    let robot = Robot::irb140();
    let square =
        |mode: &str| format!("G21 G90 {mode}\nG0 X450 Y-50 Z400\nG1 X550 F3000\nY50\nX450\nY-50\n");
    let corners: Vec<Vector3<f64>> = [
        (450.0, -50.0),
        (550.0, -50.0),
        (550.0, 50.0),
        (450.0, 50.0),
        (450.0, -50.0),
    ]
    .iter()
    .map(|&(x, y)| Vector3::new(x, y, 400.0) * 1e-3)
    .collect();
    let blended = plan_ok(&square("G64 P0.5"), &robot);
    let exact = plan_ok(&square("G61"), &robot);
    // Speed near each interior corner: the slowest sample within 5 mm of it.
    let slowest_near = |tr: &CartesianTrajectory, c: Vector3<f64>| {
        let n = (tr.duration() / 1e-3) as usize;
        (0..=n)
            .map(|k| tr.sample(k as f64 * 1e-3))
            .filter(|s| (s.position - c).norm() < 5e-3)
            .map(|s| s.velocity.norm())
            .fold(f64::INFINITY, f64::min)
    };
    for c in &corners[1..4] {
        let vb = slowest_near(&blended.trajectory, *c);
        let ve = slowest_near(&exact.trajectory, *c);
        assert!(vb > 0.01, "G64 slows to {vb} m/s at a corner");
        assert!(ve < 1e-6, "G61 does not stop at a corner: {ve} m/s");
    }
    let dev = deviation(&blended.trajectory, &corners, 1e-3);
    assert!(dev <= 0.5e-3 && dev > 0.1e-3, "deviation {} mm", dev * 1e3);
    assert!(blended.trajectory.duration() < exact.trajectory.duration());
    assert_joint_limits(&blended, &robot);
    eprintln!(
        "square: G64 P0.5 {:.3} s, deviation {:.3} mm; G61 {:.3} s",
        blended.trajectory.duration(),
        dev * 1e3,
        exact.trajectory.duration()
    );
}

#[test]
fn straight_line_duration_is_near_the_jerk_limited_optimum() {
    // One 300 mm line under G64 at F6000 (0.1 m/s), 2.5 m/s², 50 m/s³: the 1-D jerk-limited
    // minimum time is L/v + 2√(v/j) (v < a²/j: the acceleration never saturates).
    let robot = Robot::irb140();
    let p = plan_ok("G64\nG0 X400 Y-150 Z400\nG1 Y150 F6000\n", &robot);
    let (l, v, j): (f64, f64, f64) = (0.3, 0.1, 50.0);
    let optimum = l / v + 2.0 * (v / j).sqrt();
    let d = p.trajectory.duration();
    assert!(
        d >= optimum * (1.0 - 1e-3),
        "{d} beats the optimum {optimum}"
    );
    assert!(d <= 1.03 * optimum, "{d} vs optimum {optimum}");
    // Path speed, acceleration and jerk within their limits on a 1 ms grid.
    let h = 1e-3;
    let n = (d / h) as usize;
    let speed: Vec<f64> = (0..=n)
        .map(|k| p.trajectory.sample(k as f64 * h).velocity.norm())
        .collect();
    for w in speed.windows(3) {
        assert!(w[1] <= v * (1.0 + 1e-6));
        assert!(((w[2] - w[0]) / (2.0 * h)).abs() <= 2.5 * 1.01);
    }
    for w in speed.windows(4) {
        let jerk = (w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0]) / (h * h) / 1.0;
        assert!(jerk.abs() <= j * 1.05 + 1.0, "jerk {jerk}");
    }
    eprintln!("line: {d:.4} s, jerk-limited optimum {optimum:.4} s");
}

#[test]
fn a_feed_beyond_the_joints_is_slowed_where_needed() {
    // Joint 1 limited to 0.2 rad/s: a line across the front of the robot at x = 0.4 m needs
    // q1' ≈ 1/0.4 rad/m, so about 0.08 m/s at most, far below F30000 (0.5 m/s).
    let mut robot = Robot::irb140();
    let drives =
        ofmpc::robot::Drives::from_toml_str("[joints.joint_1]\nmax_speed_rad_s = 0.2\n").unwrap();
    robot.apply_drives(&drives).unwrap();
    let text = "G64\nG0 X400 Y-150 Z400\nG1 Y150 F30000\n";
    let p = plan_ok(text, &robot);
    let (wv, wa) = assert_joint_limits(&p, &robot);
    assert!(wv > 0.95, "the joint speed limit is reached: {wv}");
    // Brute force: the time at the joint-limited speed, scanned along the line with the
    // analytic IK every 0.1 mm, is a lower bound; the plan is within a few percent of it
    // (plus the ramps at the ends: v/a and the jerk filter 2a/j).
    let opw = robot.opw_parameters().unwrap();
    let mut ws = ofmpc::dynamics::Workspace::new(&robot);
    let rot0 = ofmpc::dynamics::forward_kinematics(&robot, &mut ws, &[0.0; 6])
        .unwrap()
        .rot;
    let rotation = nalgebra::UnitQuaternion::from_matrix(&rot0);
    let n = 3000;
    let ds = 0.3 / n as f64;
    let q_at = |y: f64| {
        let pose =
            nalgebra::Isometry3::from_parts(nalgebra::Translation3::new(0.4, y, 0.4), rotation);
        let sols = opw.inverse(&pose);
        sols.as_slice()
            .iter()
            .min_by(|a, b| {
                let d = |q: &[f64; 6]| q.iter().map(|x| x * x).sum::<f64>();
                d(a).total_cmp(&d(b))
            })
            .copied()
            .unwrap()
    };
    let mut bound = 0.0;
    for k in 0..n {
        let y = -0.15 + (k as f64 + 0.5) * ds;
        let (qa, qb) = (q_at(y - ds / 2.0), q_at(y + ds / 2.0));
        let mut vmax: f64 = 0.5;
        for (i, jt) in robot.joints().iter().enumerate() {
            let dq = ((qb[i] - qa[i]) / ds).abs();
            if dq > 0.0 {
                vmax = vmax.min(jt.limits.velocity / dq);
            }
        }
        bound += ds / vmax;
    }
    let d = p.trajectory.duration();
    let ramps = 0.1 / 2.5 + 2.0 * 2.5 / 50.0;
    assert!(d >= bound * (1.0 - 1e-3), "{d} beats the bound {bound}");
    assert!(d <= 1.03 * bound + ramps, "{d} vs bound {bound}");
    eprintln!(
        "joint-limited line: {d:.3} s, brute-force bound {bound:.3} s (+ ramps {ramps:.2} s), peak speed/limit {wv:.4}, accel/limit {wa:.4}"
    );
}

/// A CAM-like program: `n` segments of about 1 mm along a wavy circle.
fn long_program(n: usize) -> String {
    let mut text = String::from("G21 G90 G64 P0.01\n");
    for k in 0..=n {
        let a = k as f64 * 0.01; // 1 mm at r = 100 mm
        let r = 100.0 + 10.0 * (7.0 * a).sin();
        let (x, y) = (500.0 + r * a.cos(), r * a.sin());
        let z = 400.0 + 5.0 * (3.0 * a).sin();
        if k == 0 {
            writeln!(text, "G0 X{x:.4} Y{y:.4} Z{z:.4}").unwrap();
        } else if k == 1 {
            writeln!(text, "G1 X{x:.4} Y{y:.4} Z{z:.4} F6000").unwrap();
        } else {
            writeln!(text, "X{x:.4} Y{y:.4} Z{z:.4}").unwrap();
        }
    }
    text
}

#[test]
fn ten_thousand_short_segments_never_stop() {
    let robot = Robot::irb140();
    let p = plan_ok(&long_program(10_000), &robot);
    assert_eq!(p.program.moves.len(), 10_000);
    assert_eq!(p.diagnostics.runs, 1);
    let r = &p.reference;
    // Between the first and the last 20 mm the flange never slows below half the feed.
    let speed = |k: usize| {
        let (a, b) = (r.position(k - 1), r.position(k + 1));
        ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt()
            / (2.0 * r.ts())
    };
    let skip = (0.02 / 0.1 / r.ts()) as usize;
    let min = (skip..r.len() - skip)
        .map(speed)
        .fold(f64::INFINITY, f64::min);
    assert!(min > 0.05, "slows to {min} m/s");
    assert_joint_limits(&p, &robot);
}

#[test]
fn huge_sample_counts_are_refused_before_allocating_with_their_cause() {
    let robot = Robot::irb140();
    let base = "G0 X500 Y0 Z400\n";
    let err = |text: &str, options: &PlanOptions| match plan(text, &robot, options) {
        Err(PlanError::TooManySamples {
            cause,
            count,
            limit,
        }) => {
            assert!(count > limit as f64 && limit == MAX_PLAN_VALUES);
            cause
        }
        other => panic!("{:?}", other.map(|p| p.diagnostics)),
    };
    let d = PlanOptions::default();
    assert_eq!(
        err(&format!("{base}G1 X600 F0.0001\n"), &d),
        SampleCause::Feed { line: 2 }
    );
    assert_eq!(
        err(&format!("{base}G1 X600\nG04 P100000000\n"), &d),
        SampleCause::Dwell { line: 3 }
    );
    let tiny_ts = PlanOptions {
        ts: 1e-9,
        ..PlanOptions::default()
    };
    assert_eq!(
        err(&format!("{base}G1 X600\n"), &tiny_ts),
        SampleCause::SamplePeriod
    );
    let tiny_accel = PlanOptions {
        timing: TimingOptions {
            max_accel: 1e-12,
            ..TimingOptions::default()
        },
        ..PlanOptions::default()
    };
    assert_eq!(
        err(&format!("{base}G1 X600\n"), &tiny_accel),
        SampleCause::PathAcceleration { line: 2 }
    );
    let tiny_speed = PlanOptions {
        timing: TimingOptions {
            max_speed: 1e-9,
            ..TimingOptions::default()
        },
        ..PlanOptions::default()
    };
    assert_eq!(
        err(&format!("{base}G0 X600\n"), &tiny_speed),
        SampleCause::PathSpeed { line: 2 }
    );
    // The message names the cause, the count and the limit, and no internal name.
    let e = plan(&format!("{base}G1 X600 F0.0001\n"), &robot, &d).unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains("program line 2") && m.contains("feed") && m.contains("50000000"),
        "{m}"
    );
    assert!(!m.contains("::") && !m.contains("max_"), "{m}");
    // Under G64 the run's own timing is bounded too.
    let e = plan(&format!("G64\n{base}G1 X600 F0.0001\n"), &robot, &d).unwrap_err();
    assert!(e.to_string().contains("program line 3"), "{e}");
}

#[test]
fn joint_acceleration_limits_hold_on_every_sample() {
    // Joint 1 limited to 0.5 rad/s² (and 1 rad/s): a square around the robot's front at
    // F30000 must slow its accelerations down to what joint 1 allows.
    let mut robot = Robot::irb140();
    let drives = ofmpc::robot::Drives::from_toml_str(
        "[joints.joint_1]\nmax_speed_rad_s = 1.0\nmax_accel_rad_s2 = 0.5\n",
    )
    .unwrap();
    robot.apply_drives(&drives).unwrap();
    let text = "G64 P0.5\nG0 X400 Y-150 Z400\nG1 Y150 F30000\nX550\nY-150\nX400\n";
    let p = plan_ok(text, &robot);
    let (wv, wa) = assert_joint_limits(&p, &robot);
    assert!(wa > 0.8, "the acceleration limit binds: {wa}");
    eprintln!(
        "joint-1 acceleration limited: {:.3} s, speed/limit {wv:.3}, accel/limit {wa:.3}, {:?}",
        p.trajectory.duration(),
        p.diagnostics
    );
}

/// A program whose first move leaves the IRB 140's start pose q = 0 (the wrist straight, a
/// singularity) sideways needs joint 4 to turn a quarter turn at once: the plan turns the
/// wrist in place first (joints 4 and 6, the tool holding still, within the joints' limits)
/// and then follows the path without a jump; with the wrist bent (q5 = 0.5 rad) the same
/// program plans without a turn. A path that later passes next to the singularity is refused
/// for that cause.
#[test]
fn a_singular_start_pose_turns_the_wrist_in_place_before_the_first_move() {
    use ofmpc::dynamics::{forward_kinematics, Workspace};
    use ofmpc::motion::ReferenceFailure;
    // The IRB 140's q = 0 is a wrist singularity (joints 4 and 6 on one axis): leaving it
    // along this path at a constant orientation needs joint 4 to jump by about 90°.
    let text = "G17\nG1 X0 Y20 F200\nG1 X-20 Y40\n";
    let options = at_origin([0.505, -0.010, 0.600]);
    let robot = Robot::irb140();
    let planned = plan(text, &robot, &options).expect("plans with a turn at the start");
    let turn = planned
        .diagnostics
        .start_turn
        .clone()
        .expect("a start turn");
    let r = &planned.reference;
    let ts = options.ts;
    // It starts at the robot's start pose and turns joints 4 and 6 only, by opposite angles
    // (q4 + q6 is the wrist's rotation about the common axis).
    assert_eq!(r.q(0), robot.start_q());
    assert_eq!(turn.from, robot.start_q());
    for i in [0, 1, 2, 4] {
        assert!(
            (turn.to[i] - turn.from[i]).abs() < 1e-6,
            "joint {} moved: {:?}",
            i + 1,
            turn.to
        );
    }
    assert!(turn.to[3].abs() > 0.5, "joint 4 turns: {:?}", turn.to);
    assert!((turn.to[3] + turn.to[5]).abs() < 1e-9, "{:?}", turn.to);
    assert!(turn.to_string().contains("joint 4 (joint_4) by"), "{turn}");
    // The tool holds still during the turn (forward kinematics of every sample), the joints
    // keep their speed and acceleration limits, and the path then starts: the trajectory is
    // the turn longer than without it.
    let mut ws = Workspace::new(&robot);
    let p0 = forward_kinematics(&robot, &mut ws, robot.start_q())
        .unwrap()
        .pos;
    let turn_samples = (turn.duration / ts).round() as usize;
    assert!(turn_samples >= 2);
    for k in 0..=turn_samples {
        let p = forward_kinematics(&robot, &mut ws, r.q(k)).unwrap().pos;
        assert!(
            (p - p0).norm() < 1e-9,
            "sample {k}: tool moved by {:e} m",
            (p - p0).norm()
        );
        let held = (planned.trajectory.sample(k as f64 * ts).position - p0).norm();
        assert!(
            held < 1e-12,
            "the Cartesian path holds its start during the turn"
        );
    }
    for k in 1..r.len() {
        for (i, j) in robot.joints().iter().enumerate() {
            let v = (r.q(k)[i] - r.q(k - 1)[i]).abs() / ts;
            assert!(
                v <= j.limits.velocity * (1.0 + 1e-9),
                "sample {k} joint {}: {v} rad/s",
                i + 1
            );
        }
    }
    for k in 1..turn_samples {
        for (i, j) in robot.joints().iter().enumerate() {
            let a = (r.q(k + 1)[i] - 2.0 * r.q(k)[i] + r.q(k - 1)[i]).abs() / (ts * ts);
            assert!(
                a <= j.limits.acceleration * 1.001,
                "sample {k} joint {}: {a} rad/s²",
                i + 1
            );
        }
    }
    // An arc back past the singularity (0.1 mm from the wrist straight) is refused for that
    // cause, not for the path speed.
    let back = format!("{text}G2 X20 Y0 I0 J-40\n");
    match plan(&back, &robot, &options) {
        Err(ofmpc::motion::PlanError::Reference(e)) => assert!(
            matches!(e.failure, ReferenceFailure::SingularPass { joint: 4, .. }),
            "{e}"
        ),
        other => panic!("expected the singularity to be named, got {other:?}"),
    }
    // From a bent wrist (not singular) the same path plans without a turn, and the turned
    // plan is that much longer.
    let mut bent = Robot::irb140();
    bent.set_start_q(&[0.0, 0.0, 0.0, 0.0, 0.5, 0.0]).unwrap();
    let fine = plan(text, &bent, &options).expect("plans from a bent wrist");
    assert!(fine.diagnostics.start_turn.is_none());
    assert!(fine.diagnostics.duration > 0.0);
}

/// The turn's error message remains for what a turn cannot cure.
#[test]
fn the_singular_start_message_names_the_start_pose() {
    use ofmpc::motion::ReferenceFailure;
    let f = ReferenceFailure::StartSingular {
        joint: 4,
        name: "joint_4".into(),
        speed: 157.0,
        limit: 6.0,
    };
    assert!(
        f.to_string().contains("start pose is at a singularity"),
        "{f}"
    );
}

/// A program that leaves the robot's reach is refused for that, even where a joint's speed
/// fails first on the way out (UGS's 1000 mm square on the IRB 140: joint 2 at 4.04 rad/s
/// near the edge of the workspace before the corner that no configuration reaches).
#[test]
fn a_path_out_of_reach_is_refused_for_its_reach_not_for_a_joint_speed_before_it() {
    use ofmpc::motion::PlanError;
    use ofmpc::motion::ReferenceFailure;
    let text = "G21 G90\nG0 X0 Y0 Z0\nG1 X0 Y0 F10000\nG1 X1000\nG1 Y1000\nG1 X0\nG1 Y0\n";
    let options = at_origin([0.0, -0.5, 0.35]);
    let robot = Robot::irb140();
    match plan(text, &robot, &options) {
        Err(PlanError::Reference(e)) => {
            assert!(matches!(e.failure, ReferenceFailure::Ik(_)), "{e}");
            assert_eq!(e.line, 4, "{e}");
            // The wrist centre (the flange c4 back along the tool axis, base +x) is farther
            // from the shoulder than the arm reaches (c2 + √(c3² + a2²)).
            let o = ofmpc::ik::OpwParameters::irb140();
            let p = e.position;
            let w = [p[0] - o.c4, p[1], p[2]];
            let from_shoulder = (w[0].hypot(w[1]) - o.a1).hypot(w[2] - o.c1);
            let reach = o.c2 + o.c3.hypot(o.a2);
            assert!(
                from_shoulder > reach,
                "{e}: {from_shoulder} m from the shoulder"
            );
        }
        other => panic!("expected the reach to be named, got {other:?}"),
    }
}

/// A `G61` move that passes 0.5 mm from the IRB 140's wrist singularity turns joint 4 half a
/// turn within a few millimetres: its uniform slow-down finds the peak between the timing
/// grid's points (sampled again finely where a joint steps fast), so the move is slowed for
/// joint 4 and the reference keeps its speed limit, tightly (before, the grid missed the peak
/// and the reference was refused at 7.1 rad/s against 6.28).
#[test]
fn a_g61_move_next_to_the_wrist_singularity_is_slowed_for_the_peak_between_grid_points() {
    use ofmpc::motion::JointQuantity;
    let text = "G21 G90 G61\nG1 X505 Y10 Z712.5 F2000\nG1 X505 Y-10 Z712.5\n";
    let options = at_origin([0.0, 0.0, 0.0]);
    let robot = Robot::irb140();
    let planned = plan(text, &robot, &options).expect("plans, slowed down");
    let limited = &planned.diagnostics.joint_limited;
    assert!(
        limited.iter().any(|m| m.line == 3
            && m.joint == 4
            && m.quantity == JointQuantity::Speed
            && m.factor > 5.0),
        "{limited:?}"
    );
    let r = &planned.reference;
    let limit = robot.joints()[3].limits.velocity;
    let peak = (1..r.len())
        .map(|k| (r.q(k)[3] - r.q(k - 1)[3]).abs() / options.ts)
        .fold(0.0, f64::max);
    assert!(
        peak <= limit && peak > 0.9 * limit,
        "joint 4 peaks at {peak} rad/s, limit {limit}"
    );
}

/// A blended (`G64`) run that passes 2 mm from the wrist singularity: the timing grid's
/// joint derivatives miss part of joint 4's peak, the sampled reference shows it, and the run
/// is timed again with the joint speed limits scaled down until every sample keeps them (it
/// was refused at the first sample over the limit).
#[test]
fn a_blended_run_whose_samples_exceed_a_joint_speed_is_timed_again_slower() {
    let text = "G21 G90 G64 P0.01\nG1 X505 Y10 Z714 F3000\nG1 X505 Y-10 Z714\nG1 X520 Y-10 Z714\n";
    let options = at_origin([0.0, 0.0, 0.0]);
    let robot = Robot::irb140();
    let planned = plan(text, &robot, &options).expect("plans, timed again");
    let d = &planned.diagnostics;
    assert!(d.attempts > 1 && d.limit_scale[0] < 1.0, "{d:?}");
    let r = &planned.reference;
    for k in 1..r.len() {
        for (i, j) in robot.joints().iter().enumerate() {
            let v = (r.q(k)[i] - r.q(k - 1)[i]).abs() / options.ts;
            assert!(
                v <= j.limits.velocity * 1.01,
                "sample {k}, joint {}: {v} rad/s",
                i + 1
            );
        }
    }
}
