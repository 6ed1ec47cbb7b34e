//! A run stopped from another thread (issue #22 item 16: Ctrl-C during
//! `ofmpc.run()`): the cancel flag is checked before every sample, the run ends
//! with the typed `ExperimentError::Interrupted` at the sample where it stopped,
//! and a flag never set changes nothing (bit-identical records).

mod common;

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{Experiment, ExperimentError, LoopSettings, PlantSettings};
use std::sync::atomic::{AtomicBool, Ordering};

fn paper() -> Experiment {
    let robot = Robot::irb140();
    let reference = common::paper_reference(&robot);
    Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc: MpcSettings::default(),
        plant: PlantSettings::default(),
        loop_settings: LoopSettings {
            hold_s: 0.2,
            steady_window_s: 0.1,
            ..Default::default()
        },
        baselines: Default::default(),
    }
}

#[test]
fn a_flag_never_set_changes_nothing() {
    let exp = paper();
    let payload = Payload::point_mass(0.5);
    let (a, ma) = exp
        .run(ControllerKind::Second, &payload, &mut |_, _| {})
        .unwrap();
    let never = AtomicBool::new(false);
    let (b, mb) = exp
        .run_cancellable(ControllerKind::Second, &payload, &mut |_, _| {}, &never)
        .unwrap();
    assert_eq!(a.record.q, b.record.q);
    assert_eq!(a.record.tau, b.record.tau);
    assert_eq!(a.outcome, b.outcome);
    assert_eq!(ma.joint_error_rms_rad, mb.joint_error_rms_rad);
}

#[test]
fn a_run_stops_at_the_sample_after_the_flag_is_set() {
    let exp = paper();
    let ts = exp.reference.ts();
    let payload = Payload::point_mass(0.5);
    let cancel = AtomicBool::new(false);
    // Set from the progress callback (called at sample 200 before the next sample):
    // the loop stops before sample 201.
    let err = exp
        .run_cancellable(
            ControllerKind::Second,
            &payload,
            &mut |k, _| {
                if k >= 200 {
                    cancel.store(true, Ordering::Relaxed);
                }
            },
            &cancel,
        )
        .unwrap_err();
    let ExperimentError::Interrupted { t } = err else {
        panic!("expected an interruption, got {err}");
    };
    assert!((t - 201.0 * ts).abs() < 1e-9, "t = {t}");
    assert_eq!(err.to_string(), format!("interrupted at t = {t} s"));
}

#[test]
fn a_flag_set_before_the_run_stops_it_at_its_first_sample() {
    let exp = paper();
    let ts = exp.reference.ts();
    let cancel = AtomicBool::new(true);
    let payload = Payload::point_mass(0.5);
    let err = exp
        .run_cancellable(ControllerKind::Second, &payload, &mut |_, _| {}, &cancel)
        .unwrap_err();
    assert_eq!(err, ExperimentError::Interrupted { t: 0.0 });
    // An adaptive controller's identification at rest is interrupted too (t < 0).
    let err = exp
        .run_cancellable(
            ControllerKind::SecondAdaptive,
            &payload,
            &mut |_, _| {},
            &cancel,
        )
        .unwrap_err();
    let pre_roll = exp.loop_settings.identification_samples(ts);
    assert!(pre_roll > 0);
    assert_eq!(
        err,
        ExperimentError::Interrupted {
            t: -(pre_roll as f64) * ts
        }
    );
}
