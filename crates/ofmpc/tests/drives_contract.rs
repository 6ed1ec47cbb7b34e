//! Issue #11's measurement faults, safety limit and counters on the paper's
//! path with 0.25 kg: invalid (NaN) and missing measurements
//! (`MeasurementFaults`), the run's fault and saturation counters, the record
//! holding the plant's true state beside what the controller was given, and
//! the safe stop on a joint error limit (`max_joint_error_rad`).

mod common;

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{
    Experiment, LoopSettingsError, MeasurementFaults, PlantSettings, RunConditions, RunMetrics,
    RunOutcome, RunResult, SafetySettings, StopReason,
};

fn experiment(
    robot: Robot,
    mpc: MpcSettings,
    plant: PlantSettings,
    conditions: RunConditions,
) -> Experiment {
    let reference = common::paper_reference(&robot);
    Experiment {
        conditions,
        robot,
        reference,
        mpc,
        plant,
        loop_settings: Default::default(),
        baselines: Default::default(),
    }
}

fn run(exp: &Experiment, kind: ControllerKind, mass: f64) -> (RunResult, RunMetrics) {
    exp.run(kind, &Payload::point_mass(mass), &mut |_, _| {})
        .unwrap()
}

fn faults() -> MeasurementFaults {
    MeasurementFaults {
        nan_at_s: vec![1.0, 3.0],
        dropout_s: vec![[2.0, 2.1]],
    }
}

/// Two NaN measurements and a 0.1 s dropout while every joint moves: the
/// controllers run on the model's prediction (with the disturbance it learnt),
/// never output a non-finite torque, count 12 faults, and converge as before.
#[test]
fn nan_and_missing_measurements_run_on_the_prediction() {
    let robot = Robot::irb140();
    for kind in [ControllerKind::First, ControllerKind::Second] {
        let clean = experiment(
            robot.clone(),
            MpcSettings::default(),
            PlantSettings::default(),
            RunConditions::default(),
        );
        let faulty = experiment(
            robot.clone(),
            MpcSettings::default(),
            PlantSettings::default(),
            RunConditions {
                faults: faults(),
                ..Default::default()
            },
        );
        let (rc, mc) = run(&clean, kind, 0.25);
        let (rf, mf) = run(&faulty, kind, 0.25);
        assert!(rf.outcome.is_completed(), "{kind}: {}", rf.outcome);
        assert_eq!((mc.faults, mf.faults), (0, 12), "{kind}");
        let rec = &rf.record;
        let n = rec.n;
        // The true state and the torque are finite everywhere; the
        // measurement columns are NaN exactly at the 12 lost samples.
        for v in rec.q.iter().chain(&rec.qd).chain(&rec.tau) {
            assert!(v.is_finite());
        }
        assert!(rec.has_measurement() && !rc.record.has_measurement());
        let lost: Vec<usize> = (0..rec.len())
            .filter(|&k| rec.q_meas[k * n..(k + 1) * n].iter().all(|v| v.is_nan()))
            .collect();
        assert_eq!(lost.len(), 12, "{kind}: {lost:?}");
        assert_eq!((lost[0], lost[1], lost[11]), (100, 200, 300), "{kind}");
        assert!(rec.q_meas.iter().filter(|v| v.is_nan()).count() == 12 * n);
        // Elsewhere the measurement is the true state (ideal sensors).
        assert!((0..rec.len())
            .filter(|k| !lost.contains(k))
            .all(|k| rec.q_meas[k * n..(k + 1) * n] == rec.q[k * n..(k + 1) * n]));
        // Converges as without faults; the transient stays small.
        for (f, c) in mf
            .steady_joint_error_max_rad
            .iter()
            .zip(&mc.steady_joint_error_max_rad)
        {
            assert!(*f <= 1e-9 && *c <= 1e-9, "{kind}: steady {f:e} / {c:e}");
        }
        assert!(
            mf.cartesian_error_rms_mm <= 2.5 * mc.cartesian_error_rms_mm + 1e-3,
            "{kind}: RMS {} vs {} mm",
            mf.cartesian_error_rms_mm,
            mc.cartesian_error_rms_mm
        );
        assert!(
            mf.max_torque_ratio <= 1.1 * mc.max_torque_ratio,
            "{kind}: torque ratio {} vs {}",
            mf.max_torque_ratio,
            mc.max_torque_ratio
        );
    }
}

/// A measurement lost at t = 0 (nothing learnt yet) and one through the
/// whole hold's end: still no non-finite torque, and the run completes.
#[test]
fn a_first_measurement_lost_is_predicted_from_rest() {
    let exp = experiment(
        Robot::irb140(),
        MpcSettings::default(),
        PlantSettings::default(),
        RunConditions {
            faults: MeasurementFaults {
                nan_at_s: vec![0.0],
                dropout_s: vec![[0.02, 0.05]],
            },
            ..Default::default()
        },
    );
    let (r, m) = run(&exp, ControllerKind::Second, 0.25);
    assert!(r.outcome.is_completed(), "{}", r.outcome);
    assert_eq!(m.faults, 4);
    assert!(r.record.tau.iter().all(|t| t.is_finite()));
    assert!(m.steady_joint_error_max_rad.iter().all(|e| *e <= 1e-9));
}

/// Lowered limit on joint 1 (24 N·m, the path asks 26.4): with the limits in
/// the controller the commanded torque never passes them (`max_torque_ratio`
/// ≤ 1) and sits at the limit on some samples; with the plant's saturation
/// alone the controller asks for more (ratio > 1).
#[test]
fn torque_counters_see_the_limits() {
    let mut robot = Robot::irb140();
    let name = robot.joints()[0].name.clone();
    robot
        .apply_drives(
            &Drives::from_toml_str(&format!("[joints.{name}]\nmax_torque_nm = 24.0\n")).unwrap(),
        )
        .unwrap();
    let plant = PlantSettings {
        torque_limits: true,
        ..Default::default()
    };
    let limited = experiment(
        robot.clone(),
        MpcSettings {
            torque_limits: true,
            ..Default::default()
        },
        plant.clone(),
        RunConditions::default(),
    );
    let (r, m) = run(&limited, ControllerKind::First, 0.25);
    assert!(r.outcome.is_completed(), "{}", r.outcome);
    assert!(m.max_torque_ratio <= 1.0 + 1e-9, "{}", m.max_torque_ratio);
    assert!(m.saturated_samples > 0);
    let plant_only = experiment(
        robot,
        MpcSettings::default(),
        plant,
        RunConditions::default(),
    );
    let (_, m) = run(&plant_only, ControllerKind::Usual, 0.25);
    assert!(m.max_torque_ratio > 1.0, "{}", m.max_torque_ratio);
    assert!(m.saturated_samples > 0);
    assert_eq!(m.faults, 0);
}

/// With a 22-bit encoder the record keeps the plant's true positions in `q`
/// and the quantized ones, as the controller got them, in `q_meas`.
#[test]
fn the_record_holds_the_true_state_and_the_measurement() {
    let counts = 1u64 << 22;
    let exp = experiment(
        Robot::irb140(),
        MpcSettings::default(),
        PlantSettings {
            encoder_counts: counts,
            ..Default::default()
        },
        RunConditions::default(),
    );
    let (r, _) = run(&exp, ControllerKind::First, 0.25);
    let rec = &r.record;
    assert!(rec.has_measurement());
    let res = 2.0 * std::f64::consts::PI / counts as f64;
    let mut differ = 0;
    for (m, q) in rec.q_meas.iter().zip(&rec.q) {
        let steps = m / res;
        assert!((steps - steps.round()).abs() < 1e-6, "{m} is not a count");
        assert!((m - q).abs() <= 0.5 * res * (1.0 + 1e-9), "{m} vs {q}");
        differ += usize::from(m != q);
    }
    assert!(differ > rec.q.len() / 2);
}

/// The safety function: the second algorithm with the paper's tuning and
/// 6 kg would diverge; with `max_joint_error_rad` = 0.05 it is stopped when
/// an error passes 0.05 rad, brakes within the torque limits, comes to rest
/// within the joint limits, and the record ends at rest.
#[test]
fn a_joint_error_limit_stops_the_robot_safely() {
    let exp = experiment(
        Robot::irb140(),
        MpcSettings::default(),
        PlantSettings {
            torque_limits: true,
            ..Default::default()
        },
        RunConditions {
            safety: SafetySettings {
                max_joint_error_rad: Some(0.05),
            },
            ..Default::default()
        },
    );
    let free = experiment(
        Robot::irb140(),
        MpcSettings::default(),
        PlantSettings::default(),
        RunConditions::default(),
    );
    let (rd, _) = run(&free, ControllerKind::Second, 6.0);
    assert!(
        matches!(rd.outcome, RunOutcome::Diverged { .. }),
        "{}",
        rd.outcome
    );
    let (r, m) = run(&exp, ControllerKind::Second, 6.0);
    match &r.outcome {
        RunOutcome::Stopped {
            reason:
                StopReason::JointErrorLimit {
                    error_rad,
                    limit_rad,
                    ..
                },
            at_rest_after_s,
            within_limits,
            ..
        } => {
            assert!(error_rad.abs() > 0.05 && *limit_rad == 0.05);
            assert!(at_rest_after_s.is_some(), "{}", r.outcome);
            assert!(*within_limits, "{}", r.outcome);
        }
        other => panic!("expected a stop on the error limit, got {other}"),
    }
    assert_eq!(m.status.to_string(), "stopped");
    let robot = Robot::irb140();
    let n = 6;
    for k in 0..r.record.len() {
        for (i, j) in robot.joints().iter().enumerate() {
            let t = r.record.tau[k * n + i];
            assert!(t.is_finite() && t.abs() <= j.limits.effort * (1.0 + 1e-12));
        }
    }
    let last = &r.record.qd[(r.record.len() - 1) * n..];
    assert!(last.iter().all(|v| v.abs() < 1e-3), "{last:?}");
}

#[test]
fn bad_fault_settings_are_errors_with_the_value() {
    let bad = [
        (
            MeasurementFaults {
                nan_at_s: vec![1.0, f64::NAN],
                dropout_s: vec![],
            },
            "invalid-measurement time 1",
        ),
        (
            MeasurementFaults {
                nan_at_s: vec![],
                dropout_s: vec![[2.0, 1.0]],
            },
            "dropout interval 0 is [2, 1]",
        ),
        (
            MeasurementFaults {
                nan_at_s: vec![-1.0],
                dropout_s: vec![],
            },
            "is -1 s",
        ),
    ];
    for (f, text) in bad {
        let ls = RunConditions {
            faults: f,
            ..Default::default()
        };
        let e = ls.validate().unwrap_err();
        assert!(e.to_string().contains(text), "{e}");
    }
    let ls = RunConditions {
        safety: SafetySettings {
            max_joint_error_rad: Some(0.0),
        },
        ..Default::default()
    };
    assert_eq!(ls.validate(), Err(LoopSettingsError::MaxJointError(0.0)));
}
