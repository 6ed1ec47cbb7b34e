//! Safe stops that must happen and stops that must not be called safe
//! (issue #22 items 9 and 10): the adaptive controllers' identification
//! phase is supervised like the path, and a "stop" whose robot is not at
//! rest within its limits is reported as a failed stop.

mod common;

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{
    Experiment, Fault, LoopSettings, PlantSettings, RunOutcome, RunStatus, StopReason,
};

fn paper(plant: PlantSettings, mpc: MpcSettings) -> Experiment {
    let robot = Robot::irb140();
    let reference = common::paper_reference(&robot);
    Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc,
        plant,
        loop_settings: LoopSettings {
            plausibility_check: true,
            safe_stop: true,
            ..Default::default()
        },
        baselines: Default::default(),
    }
}

/// The case: a one-sample delay, the check and the stop on, 2 kg.
/// The second algorithm is stopped on the path; second-adaptive's
/// identification at rest diverges (t < 0), which used to end the run
/// "diverged" with nothing recorded: now the stop law takes over there too.
#[test]
fn the_identification_phase_is_stopped_safely_not_diverged() {
    let exp = paper(
        PlantSettings {
            delay_samples: 1,
            ..Default::default()
        },
        MpcSettings::default(),
    );
    let payload = Payload::point_mass(2.0);
    let (second, _) = exp
        .run(ControllerKind::Second, &payload, &mut |_, _| {})
        .unwrap();
    assert!(
        matches!(second.outcome, RunOutcome::Stopped { .. }),
        "{}",
        second.outcome
    );
    let (r, m) = exp
        .run(ControllerKind::SecondAdaptive, &payload, &mut |_, _| {})
        .unwrap();
    let RunOutcome::Stopped { t, reason, .. } = &r.outcome else {
        panic!("expected a safe stop, got {}", r.outcome);
    };
    assert!(*t < 0.0, "the stop began in the identification phase: {t}");
    assert!(matches!(reason, StopReason::Diverged { .. }), "{reason}");
    assert!(matches!(
        m.status,
        RunStatus::Stopped | RunStatus::FailedStop
    ));
    assert_ne!(m.status, RunStatus::Diverged);
    // The stop is recorded: one second of braking and holding.
    assert!(r.record.len() >= 90, "{} samples", r.record.len());
    assert!(r.record.q.iter().all(|v| v.is_finite()));
}

/// Every encoder drops out for 5 s while the arm moves: the stop law
/// dead-reckons at best one joint, the arm runs away. That is a failed
/// stop (status "failed_stop", a failure), not "stopped".
#[test]
fn a_stop_that_does_not_stop_the_robot_is_a_failed_stop() {
    let faults = (1..=6)
        .map(|joint| Fault::EncoderDropout {
            t: 2.0,
            joint,
            duration_s: 5.0,
        })
        .collect();
    let exp = paper(
        PlantSettings {
            torque_limits: true,
            faults,
            ..Default::default()
        },
        MpcSettings {
            torque_limits: true,
            ..Default::default()
        },
    );
    let robot = Robot::irb140();
    let (lower, upper) = (robot.lower_limits(), robot.upper_limits());
    let (r, m) = exp
        .run(
            ControllerKind::Second,
            &Payload::point_mass(0.25),
            &mut |_, _| {},
        )
        .unwrap();
    assert!(r.outcome.is_failed_stop(), "{}", r.outcome);
    assert_eq!(m.status, RunStatus::FailedStop);
    assert!(m.status.is_failure());
    let json = serde_json::to_value(&m).unwrap();
    assert_eq!(json["status"], "failed_stop");
    assert!(m.reason.contains("failed"), "{}", m.reason);
    // The independent check: the record's last sample is not at rest
    // within the limits.
    let n = 6;
    let last = r.record.len() - 1;
    let moving = (0..n).any(|i| r.record.qd[last * n + i].abs() >= 1e-3);
    let outside = (0..n).any(|i| {
        let q = r.record.q[last * n + i];
        q < lower[i] || q > upper[i]
    });
    assert!(moving || outside);
}
