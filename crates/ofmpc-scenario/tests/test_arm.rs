//! Issue 35 on the test arm: `examples/test-arm.toml` as shipped (three
//! samples of delay, its own friction known 20 % low, 20-bit encoders, noise,
//! torque limits; `friction_coupled`, `identify_at_rest`,
//! `identification_min_samples`, the wrist's hold at `× 0.1`), read and run
//! as `ofmpc run` does, so the numbers are the CLI's (docs/guide/real-arm.md,
//! "The test arm"). About 10 s in release.

use ofmpc::control::ControllerKind;
use ofmpc::robot::Payload;
use ofmpc::sim::{RunMetrics, RunStatus};
use ofmpc_scenario::{Scenario, ScenarioFile};
use std::path::Path;

fn preset() -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/test-arm.toml");
    Scenario::resolve(&ScenarioFile::from_file(&path).unwrap()).unwrap()
}

fn run(s: &Scenario, kind: ControllerKind, mass: f64) -> RunMetrics {
    let m = s
        .experiment
        .run(kind, &Payload::point_mass(mass), &mut |_, _| {})
        .unwrap()
        .1;
    eprintln!(
        "{}: {} RMS {:.4} steady {:.4} mm, est {:?}, hold p-p {:?} counts",
        m.name,
        m.status,
        m.cartesian_error_rms_mm,
        m.steady_cartesian_error_mm,
        m.payload_estimate_kg,
        m.hold_error_pp_counts
    );
    m
}

/// The targets where the preset meets them: first-adaptive and
/// ctc-adaptive at half and rated payload, RMS ≤ 0.25 mm, steady ≤ 0.01 mm,
/// the estimate within 10 % of the rated 5 kg (measured 0.178 / 0.172 and
/// 0.197 / 0.182 mm, ≤ 0.0064 mm, 2.53 / 4.99 kg; before the round 20 / 59
/// and 6.6 / 70 mm RMS); the holds within 3–4 and 5–6 counts ("hunting" by
/// the 2-count rule); at 0 kg both hold to 0.007 mm with RMS 0.38 / 0.34 mm
/// (the target, 0.25 mm, not met there).
#[test]
fn the_test_arm_meets_the_error_targets_with_the_adaptive_kinds_under_a_payload() {
    let s = preset();
    for (mass, rms) in [(0.0, 0.45), (2.5, 0.25), (5.0, 0.25)] {
        for kind in [ControllerKind::FirstAdaptive, ControllerKind::CtcAdaptive] {
            let m = run(&s, kind, mass);
            assert!(
                matches!(m.status, RunStatus::Ok | RunStatus::Hunting),
                "{}",
                m.reason
            );
            assert!(m.cartesian_error_rms_mm <= rms, "{}: RMS", m.name);
            assert!(m.steady_cartesian_error_mm <= 0.01, "{}: steady", m.name);
            let est = m.payload_estimate_kg.unwrap();
            assert!((est - mass).abs() <= 0.5, "{}: estimate {est} kg", m.name);
            let hold = if kind == ControllerKind::FirstAdaptive {
                5.0
            } else {
                12.0
            };
            assert!(m.hold_error_pp_counts.unwrap() <= hold, "{}", m.reason);
        }
    }
}

/// What each key of the round does, one removed at a time at 2.5 kg
/// (first-adaptive; measured): without `friction_coupled` the hold cycles at
/// about 7 Hz by thousands of counts; without `identify_at_rest` the unknown
/// payload swings the arm until the path has identified it (RMS in mm).
#[test]
fn without_the_coupled_creep_or_the_identification_at_rest_the_test_arm_is_off() {
    let mut s = preset();
    s.experiment.mpc.friction_coupled = false;
    let m = run(&s, ControllerKind::FirstAdaptive, 2.5);
    assert_eq!(m.status, RunStatus::Hunting, "{}", m.reason);
    assert!(m.hold_error_pp_counts.unwrap() > 100.0, "{}", m.reason);
    let mut s = preset();
    s.experiment.mpc.identify_at_rest = false;
    let m = run(&s, ControllerKind::FirstAdaptive, 2.5);
    assert!(m.cartesian_error_rms_mm > 1.0, "{}: RMS", m.name);
}
