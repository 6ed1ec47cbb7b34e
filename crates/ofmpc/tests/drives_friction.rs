//! Friction compensation (#11 item 2) on the paper's path, 0.25 kg: the
//! plant has 1 N·m Coulomb friction on every joint, the controller's drives
//! file says 0.8 N·m (20 % off). The compensation adds the estimate at the
//! reference's velocity to the torque; the second algorithm's aggregated
//! error restarts from the current error on a joint whose reference rests
//! over the whole horizon (`control/second.rs`, `restart_in_hold`).
//!
//! Measured (probe `drives_probe friction` / `friction-comp` with `VISC0=1
//! SUBSTEP=2e-4`, the estimates and the plant substep of this test): usual RMS
//! 0.155 → 0.085 mm, first steady 1.35e-3 → 3.3e-4 mm (RMS 0.0238 → 0.0234
//! mm), second RMS 0.0192 → 0.0053 mm and steady 0.046 mm (stick–slip hunting
//! on the wrist) → 4.7e-4 mm. (With the default 1 ms substep the sticking is
//! not resolved and the steady errors read 1e4 times smaller: 6.3e-9 and
//! 1.0e-8 mm.)

mod common;

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{Experiment, LoopSettings, PlantSettings, RunMetrics};

/// The paper's path, 0.25 kg; plant Coulomb friction `plant_nm` on every
/// joint, controller estimate `estimate_nm` (viscous 0), horizon `n`.
fn run_n(
    kind: ControllerKind,
    compensate: bool,
    plant_nm: f64,
    estimate_nm: f64,
    n: usize,
) -> RunMetrics {
    let mut robot = Robot::irb140();
    let text: String = (1..=6)
        .map(|j| format!("[joints.joint_{j}]\ncoulomb_nm = {estimate_nm}\nviscous_nms = 0.0\n"))
        .collect();
    robot
        .apply_drives(&Drives::from_toml_str(&text).unwrap())
        .unwrap();
    let reference = common::paper_reference(&robot);
    let exp = Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc: MpcSettings {
            friction_compensation: compensate,
            horizon: n,
            ..Default::default()
        },
        plant: PlantSettings {
            coulomb_friction: vec![plant_nm],
            // Resolves the friction's sticking (time constant at rest
            // H_66·v_s/F_c ≈ 5e-5 s on the wrist; converged from 2e-4 s:
            // `Plant::coulomb_time_constant`).
            substep: 2e-4,
            ..Default::default()
        },
        loop_settings: LoopSettings::default(),
        baselines: Default::default(),
    };
    let (r, m) = exp
        .run(kind, &Payload::point_mass(0.25), &mut |_, _| {})
        .unwrap();
    assert!(r.outcome.is_completed(), "{kind}: {}", r.outcome);
    assert!(r
        .record
        .tau
        .iter()
        .chain(&r.record.q)
        .all(|v| v.is_finite()));
    m
}

fn run_with(kind: ControllerKind, compensate: bool, plant_nm: f64, estimate_nm: f64) -> RunMetrics {
    run_n(kind, compensate, plant_nm, estimate_nm, 10)
}

fn run(kind: ControllerKind, compensate: bool) -> RunMetrics {
    run_with(kind, compensate, 1.0, 0.8)
}

#[test]
fn compensation_helps_tracking_and_the_first_algorithm_is_no_worse() {
    let (u0, u1) = (
        run(ControllerKind::Usual, false),
        run(ControllerKind::Usual, true),
    );
    assert!(
        u1.cartesian_error_rms_mm < 0.7 * u0.cartesian_error_rms_mm,
        "usual RMS {} → {}",
        u0.cartesian_error_rms_mm,
        u1.cartesian_error_rms_mm
    );
    // Measured: 0.0824 mm.
    assert!(
        u1.cartesian_error_rms_mm < 0.085,
        "usual RMS {}",
        u1.cartesian_error_rms_mm
    );
    let (f0, f1) = (
        run(ControllerKind::First, false),
        run(ControllerKind::First, true),
    );
    assert!(f1.cartesian_error_rms_mm <= f0.cartesian_error_rms_mm * 1.001);
    assert!(f1.steady_cartesian_error_mm <= f0.steady_cartesian_error_mm.max(1e-9));
}

#[test]
fn the_second_algorithm_holds_without_hunting() {
    // Issue #11, item 2: steady error ≤ 0.001 mm in the hold (measured
    // 4.7e-4 mm; 0.046 mm of stick–slip hunting before the hold rule).
    let (s0, s1) = (
        run(ControllerKind::Second, false),
        run(ControllerKind::Second, true),
    );
    assert!(
        s1.steady_cartesian_error_mm <= 1e-3,
        "second steady {} mm",
        s1.steady_cartesian_error_mm
    );
    assert!(
        s1.cartesian_error_rms_mm < 0.6 * s0.cartesian_error_rms_mm,
        "second RMS {} → {}",
        s0.cartesian_error_rms_mm,
        s1.cartesian_error_rms_mm
    );
    // Not tied to the estimate: exact (1 N·m) and 60 % off (0.4 N·m); the
    // structured solver (N = 20). The hunting stays away (≤ 0.002 mm, against
    // 0.046 mm without the rule; measured 1.9e-5, 1.1e-3 and 4.7e-4 mm).
    for (est, n) in [(1.0, 10), (0.4, 10), (0.8, 20)] {
        let m = run_n(ControllerKind::Second, true, 1.0, est, n);
        eprintln!(
            "estimate {est} N·m, N = {n}: second steady {:.2e} mm",
            m.steady_cartesian_error_mm
        );
        assert!(
            m.steady_cartesian_error_mm <= 2e-3,
            "estimate {est}, N = {n}: second steady {} mm",
            m.steady_cartesian_error_mm
        );
    }
}

#[test]
fn the_hold_rule_keeps_the_second_algorithm_offset_free_without_friction() {
    // Friction-free plant, estimates 0: compensation on only switches the
    // hold rule of ē on; the steady error still vanishes (measured 4.7e-13
    // mm with it, 1.6e-12 mm without).
    let off = run_with(ControllerKind::Second, false, 0.0, 0.0);
    let on = run_with(ControllerKind::Second, true, 0.0, 0.0);
    assert!(
        on.steady_cartesian_error_mm <= 1e-9,
        "{}",
        on.steady_cartesian_error_mm
    );
    assert!(
        off.steady_cartesian_error_mm <= 1e-9,
        "{}",
        off.steady_cartesian_error_mm
    );
    assert!(on.cartesian_error_rms_mm <= off.cartesian_error_rms_mm * 1.05);
}
