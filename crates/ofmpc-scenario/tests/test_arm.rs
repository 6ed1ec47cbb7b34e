//! Issue 35 on the test arm: `examples/test-arm.toml` as shipped (three
//! samples of delay, its own friction known 20 % low, 20-bit encoders, noise,
//! torque limits; `friction_coupled`, `identify_at_rest`,
//! `identification_min_samples`, `identification_raw_mass`, the wrist's hold
//! at `× 0.1`, its `q_dy` × 1.5, `hold_ebar_scale = 0` and the CTC's wrist
//! `kp` × 1.75 at the hold), read and run
//! as `ofmpc run` does, so the numbers are the CLI's (docs/guide/real-arm.md,
//! "The test arm"). About 15 s in release.

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

/// The preset as shipped (a 3 s hold): first-adaptive, second-adaptive and
/// ctc-adaptive at 0, half and rated payload all "ok" (the hold within 2
/// counts over its last 0.5 s), RMS ≤ 0.25 mm, steady ≤ 0.01 mm, the estimate
/// within 10 % of the rated 5 kg (measured: holds 1–2 counts, RMS 0.156–0.195
/// mm, steady ≤ 0.0045 mm, estimates within 0.02 kg; seeds 2 and 3 the same,
/// 27 of 27 "ok").
#[test]
fn the_test_arm_meets_every_target_with_the_adaptive_kinds() {
    let s = preset();
    assert_eq!(s.experiment.loop_settings.hold_s, 3.0);
    for mass in [0.0, 2.5, 5.0] {
        for kind in [
            ControllerKind::FirstAdaptive,
            ControllerKind::SecondAdaptive,
            ControllerKind::CtcAdaptive,
        ] {
            let m = run(&s, kind, mass);
            assert_eq!(m.status, RunStatus::Ok, "{}: {}", m.name, m.reason);
            assert!(m.cartesian_error_rms_mm <= 0.25, "{}: RMS", m.name);
            assert!(m.steady_cartesian_error_mm <= 0.01, "{}: steady", m.name);
            let est = m.payload_estimate_kg.unwrap();
            assert!((est - mass).abs() <= 0.1, "{}: estimate {est} kg", m.name);
        }
    }
}

/// Why the preset holds 3 s: with the paper's 2 s the wrist's creep ring
/// (period 0.85 s, damping 0.13) has not settled — the same nine runs are
/// within 4 counts, "ok" in four (measured 4 / 3 / 2, 3 / 2 / 2 and 4 / 2 / 3
/// counts; before this round 5 / 3 / 2, 1360 / 709 / 746 and 10 / 8 / 5) —
/// and their RMS along the path still within 0.25 mm (0.174–0.217 mm): a
/// decay, not a cycle.
#[test]
fn with_a_two_second_hold_the_test_arm_is_still_settling() {
    let mut s = preset();
    s.experiment.loop_settings.hold_s = 2.0;
    let mut ok = 0;
    for mass in [0.0, 2.5, 5.0] {
        for kind in [
            ControllerKind::FirstAdaptive,
            ControllerKind::SecondAdaptive,
            ControllerKind::CtcAdaptive,
        ] {
            let m = run(&s, kind, mass);
            assert!(
                matches!(m.status, RunStatus::Ok | RunStatus::Hunting),
                "{}",
                m.reason
            );
            assert!(m.cartesian_error_rms_mm <= 0.25, "{}: RMS", m.name);
            assert!(m.hold_error_pp_counts.unwrap() < 4.5, "{}", m.reason);
            ok += usize::from(m.status == RunStatus::Ok);
        }
    }
    assert!((4..9).contains(&ok), "{ok} of 9 runs ok");
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

/// The hold's keys of this round, one removed at a time (measured): with the
/// second algorithm's aggregated error restarting from the current error
/// (`hold_ebar_scale = 1`) second-adaptive at 2.5 kg cycles on the wrist by
/// 700 counts (1–2 with 0); with the CTC's wrist `kp` unscaled at the hold
/// ctc-adaptive at 0 kg still rings by 4 counts at the end of the 3 s hold
/// (10 at 2 s), "hunting" (1 count with × 1.75).
#[test]
fn without_the_holds_of_this_round_the_test_arm_hunts() {
    let mut s = preset();
    s.experiment.mpc.hold_ebar_scale = 1.0;
    let m = run(&s, ControllerKind::SecondAdaptive, 2.5);
    assert!(m.hold_error_pp_counts.unwrap() > 100.0, "{}", m.reason);
    let mut s = preset();
    s.experiment.baselines.ctc_hold_gain_scale = ofmpc::control::Weight::Scalar(1.0);
    let m = run(&s, ControllerKind::CtcAdaptive, 0.0);
    assert!(m.hold_error_pp_counts.unwrap() > 2.5, "{}", m.reason);
    assert_eq!(m.status, RunStatus::Hunting, "{}", m.reason);
}

/// `identification_raw_mass` at 0 kg (first-adaptive, measured): the
/// estimate projected onto the physically consistent set carries 0.15 kg of
/// nothing into the model and the RMS is 0.59 mm (0.30 kg and 0.38 mm before
/// the wrist's `q_dy`); the raw point mass 0.03 kg and 0.21 mm (the test
/// above).
#[test]
fn without_the_raw_mass_the_test_arm_identifies_a_payload_at_0_kg() {
    let mut s = preset();
    s.experiment.mpc.identification_raw_mass = false;
    let m = run(&s, ControllerKind::FirstAdaptive, 0.0);
    assert!(m.payload_estimate_kg.unwrap() > 0.1, "{}: estimate", m.name);
    assert!(m.cartesian_error_rms_mm > 0.3, "{}: RMS", m.name);
}

/// dob-mpc with its payload fitted at rest (`[baselines]
/// dob_identify_at_rest`) and the wrist's stiffer hold (`dob_hold_gain_scale
/// = [1, 1, 1, 10, 10, 10]`) at 0, half and rated payload: "ok" (the hold
/// within 2 counts), RMS ≤ 0.25 mm, steady ≤ 0.01 mm, the fit within 10 % of
/// the rated 5 kg (measured RMS 0.203 / 0.126 / 0.094 mm, steady ≤ 0.0056
/// mm, fits 0.00 / 2.54 / 4.99 kg; before the fit at rest: 0.227 / 10.3 /
/// 94 mm, hunting by 5 / 43196 / 137969 counts).
#[test]
fn the_test_arm_meets_the_targets_with_dob_mpc_fitted_at_rest() {
    let s = preset();
    for mass in [0.0, 2.5, 5.0] {
        let m = run(&s, ControllerKind::DobMpc, mass);
        assert_eq!(m.status, RunStatus::Ok, "{}: {}", m.name, m.reason);
        assert!(m.hold_error_pp_counts.unwrap() <= 2.0 + 1e-6, "{}", m.name);
        assert!(m.cartesian_error_rms_mm <= 0.25, "{}: RMS", m.name);
        assert!(m.steady_cartesian_error_mm <= 0.01, "{}: steady", m.name);
        let est = m.payload_estimate_kg.unwrap();
        assert!((est - mass).abs() <= 0.5, "{}: estimate {est} kg", m.name);
    }
}

/// dob-mpc's rest on the noise seed that diverged it (`plant.seed = 2`): at
/// 2.5 and 5 kg the first fit at rest (0.2 s in) changed the model while the
/// wrist was still sagging, and the observer's correction at that sample
/// compared the last period's velocity change with the new model's
/// prediction from the carried input: one kick that saturated the wrist
/// (28 N·m) and took it past 0.2 rad ("diverged" at t ≈ −0.7 s). The
/// observer now keeps its carried estimate at the sample of a fit: "ok"
/// within 2 counts, the rest's peak 0.074 / 0.129 rad (before 0.203 /
/// 0.216 rad), RMS 0.135 / 0.100 mm, fits 2.51 / 4.95 kg (measured).
#[test]
fn dob_mpc_rests_under_the_threshold_on_the_seed_that_diverged() {
    let mut s = preset();
    s.experiment.plant.seed = 2;
    for mass in [2.5, 5.0] {
        let m = run(&s, ControllerKind::DobMpc, mass);
        assert_eq!(m.status, RunStatus::Ok, "{}: {}", m.name, m.reason);
        assert!(m.hold_error_pp_counts.unwrap() <= 2.0 + 1e-6, "{}", m.name);
        assert!(m.cartesian_error_rms_mm <= 0.25, "{}: RMS", m.name);
        assert!(m.steady_cartesian_error_mm <= 0.01, "{}: steady", m.name);
        let peak = m.pre_roll_peak_joint_rad;
        assert!(peak <= 0.15, "{}: the rest's peak {peak} rad", m.name);
        let est = m.payload_estimate_kg.unwrap();
        assert!((est - mass).abs() <= 0.5, "{}: estimate {est} kg", m.name);
    }
}

/// Why the wrist's stiffer hold (measured): without it the unknown 5 kg
/// swings the wrist at rest in a growing cycle under 30 ms of delay, no
/// window of the rest is ever still enough for the fit, and the run diverges
/// (at 0 kg the hold hunts by 5 counts).
#[test]
fn without_its_stiffer_hold_dob_mpc_cannot_fit_5_kg_at_rest() {
    let mut s = preset();
    s.experiment.baselines.dob_hold_gain_scale = ofmpc::control::Weight::Scalar(1.0);
    let m = run(&s, ControllerKind::DobMpc, 5.0);
    assert!(
        m.diverged || m.cartesian_error_rms_mm > 10.0,
        "{}: RMS {}",
        m.name,
        m.cartesian_error_rms_mm
    );
}
