//! The supervised controller (`sim::SupervisedController`): the built
//! controller behind its guard, stepped without any plant.

use ofmpc::control::{ControllerBuilder, ControllerKind, MpcSettings};
use ofmpc::robot::Robot;
use ofmpc::sim::{
    DivergenceRule, StopReason, SupervisedController, SupervisedInput, SupervisedStatus,
    SupervisorSettings,
};

fn guarded(safe_stop: bool) -> (SupervisedController, Vec<f64>, usize) {
    let robot = Robot::irb140();
    let mpc = ControllerBuilder::new(ControllerKind::Second, &robot)
        .settings(MpcSettings::default())
        .build()
        .unwrap();
    let horizon = mpc.horizon();
    let settings = SupervisorSettings {
        divergence_threshold_rad: 0.2,
        divergence: DivergenceRule::Growth,
        plausibility_check: true,
        safe_stop,
        max_joint_error_rad: None,
    };
    let mut s = SupervisedController::new(mpc, &robot, settings, 0, true).unwrap();
    let mut x0 = vec![0.0; 12];
    x0[..6].copy_from_slice(&[0.0, 0.3, 0.2, 0.0, 0.5, 0.0]);
    s.reset(&x0).unwrap();
    (s, x0, horizon)
}

/// At rest on its reference the controller's torque is given ("controlled");
/// readings of joint 2 that jump ±0.5 rad from sample to sample are first
/// replaced by predictions ("repaired measurement"), and once they are
/// rejected more than `MAX_REJECTED` times in a row the guard stops the
/// robot with the stop law: the status says so, the reason is an
/// implausible measurement of joint 2, and the torque stays finite and
/// within the drives' ratings.
#[test]
fn an_implausible_measurement_brings_a_safe_stop() {
    let (mut s, x0, horizon) = guarded(true);
    let w = x0[..6].to_vec();
    let preview = w.repeat(horizon);
    let mut x = x0.clone();
    for k in 0..10 {
        let input = SupervisedInput {
            t: k as f64 * 0.01,
            x: &x,
            w_k: &w,
            preview: &preview,
            truth: None,
        };
        let out = s.step(&input).unwrap();
        assert_eq!(out.status, SupervisedStatus::Controlled, "k = {k}");
    }
    let mut seen = Vec::new();
    for k in 10..30 {
        x[1] = x0[1] + if k % 2 == 0 { 0.5 } else { -0.5 };
        let input = SupervisedInput {
            t: k as f64 * 0.01,
            x: &x,
            w_k: &w,
            preview: &preview,
            truth: None,
        };
        let out = s.step(&input).unwrap();
        assert!(out.tau.iter().all(|t| t.is_finite()), "k = {k}");
        let limits = Robot::irb140();
        for (t, j) in out.tau.iter().zip(limits.joints()) {
            assert!(t.abs() <= j.limits.effort + 1e-9, "k = {k}: {t}");
        }
        seen.push(out.status);
    }
    assert_eq!(seen[0], SupervisedStatus::RepairedMeasurement);
    assert!(
        seen.iter()
            .any(|s| matches!(s, SupervisedStatus::Stopping | SupervisedStatus::Stopped)),
        "{seen:?}"
    );
    assert!(matches!(
        s.stop_reason(),
        Some(StopReason::ImplausibleMeasurement { joint: 1, .. })
    ));
}

/// Without the safe stop the same readings are only repaired: no stop
/// begins, the controller keeps the robot ("repaired measurement").
#[test]
fn without_the_stop_law_the_readings_are_only_repaired() {
    let (mut s, x0, horizon) = guarded(false);
    let w = x0[..6].to_vec();
    let preview = w.repeat(horizon);
    let mut x = x0.clone();
    for k in 0..20 {
        x[1] = x0[1] + if k % 2 == 0 { 0.5 } else { -0.5 };
        let input = SupervisedInput {
            t: k as f64 * 0.01,
            x: &x,
            w_k: &w,
            preview: &preview,
            truth: None,
        };
        let out = s.step(&input).unwrap();
        assert_eq!(out.status, SupervisedStatus::RepairedMeasurement, "k = {k}");
    }
    assert!(s.stop_reason().is_none());
    // A reading of the wrong length is an error, not a panic.
    let input = SupervisedInput {
        t: 0.2,
        x: &x[..11],
        w_k: &w,
        preview: &preview,
        truth: None,
    };
    assert!(s.step(&input).is_err());
}
