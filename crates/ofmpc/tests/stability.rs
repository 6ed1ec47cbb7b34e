//! Stability near rest against an inertia mismatch: the interval computed
//! from the linearized real controller step agrees with nonlinear
//! closed-loop simulations just inside and just outside each boundary, and
//! with the paper tuning's known intervals (NOTES.md).

use ofmpc::analysis::{
    alpha_interval, inertia_ratio_range, max_payload, simulated_growth, StabilityError,
    StabilityOptions,
};
use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::robot::{Payload, Robot};

const Q0: [f64; 6] = [0.0, 0.4, 0.1, 0.0, 0.9, 0.0];

#[test]
fn interval_agrees_with_simulation_at_each_boundary() {
    let robot = Robot::irb140();
    let s = MpcSettings::default();
    let opts = StabilityOptions::default();
    for kind in [ControllerKind::First, ControllerKind::Second] {
        let (lo, hi) = alpha_interval(&robot, kind, &s, &Q0, &opts).unwrap();
        for (edge, inward) in [(lo, 1.0), (hi, -1.0)] {
            let inside = edge + inward * 0.02;
            let outside = edge - inward * 0.02;
            let g_in = simulated_growth(&robot, kind, &s, &Q0, inside, 1e-5, 1000).unwrap();
            let g_out = simulated_growth(&robot, kind, &s, &Q0, outside, 1e-5, 1000).unwrap();
            assert!(g_in < 0.5, "{kind} α = {inside} (inside): growth {g_in}");
            assert!(
                g_out > 2.0,
                "{kind} α = {outside} (outside): growth {g_out}"
            );
        }
    }
}

#[test]
fn paper_tuning_reproduces_the_known_intervals_and_payloads() {
    let robot = Robot::irb140();
    let s = MpcSettings::default();
    let opts = StabilityOptions::default();
    let known = [
        (ControllerKind::First, (0.53, 1.12), 4.6),
        (ControllerKind::Second, (0.78, 1.09), 1.5),
    ];
    // The payloads are along the paper's path (NOTES.md).
    use ofmpc::gcode::{parse, ParseOptions, PAPER_TABLE1};
    use ofmpc::motion::reference::{build_reference, Orientation};
    use ofmpc::motion::trajectory::{CartesianTrajectory, TimingOptions};
    let program = parse(PAPER_TABLE1, &ParseOptions::default()).unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let reference = build_reference(&robot, &traj, Orientation::AtZero, 0.01).unwrap();
    let poses: Vec<&[f64]> = (0..reference.len())
        .step_by(10)
        .map(|k| reference.q(k))
        .collect();
    for (kind, (lo, hi), payload) in known {
        let iv = alpha_interval(&robot, kind, &s, &Q0, &opts).unwrap();
        assert!(
            (iv.0 - lo).abs() < 0.01 && (iv.1 - hi).abs() < 0.01,
            "{kind}: {iv:?}"
        );
        let m = max_payload(&robot, iv, &poses, 50.0).unwrap();
        assert!((m - payload).abs() < 0.1, "{kind}: {m} kg");
        // At that payload the inertia ratios touch the interval's lower end.
        let (a, _) = inertia_ratio_range(&robot, &Payload::point_mass(m), &poses).unwrap();
        assert!((a - iv.0).abs() < 1e-3, "{kind}: α {a} at {m} kg");
    }
    // The usual MPC tolerates far more (about 0.01..2).
    let (lo, hi) = alpha_interval(&robot, ControllerKind::Usual, &s, &Q0, &opts).unwrap();
    assert!(lo <= 0.011 && (hi - 2.0).abs() < 0.02, "usual: {lo}..{hi}");
}

#[test]
fn adaptive_variants_and_bad_options_are_errors() {
    let robot = Robot::irb140();
    let s = MpcSettings::default();
    let e = alpha_interval(
        &robot,
        ControllerKind::SecondAdaptive,
        &s,
        &Q0,
        &StabilityOptions::default(),
    );
    assert!(matches!(e, Err(StabilityError::Adaptive(_))));
    let bad = StabilityOptions {
        alpha_max: 0.5,
        ..Default::default()
    };
    assert!(matches!(
        alpha_interval(&robot, ControllerKind::First, &s, &Q0, &bad),
        Err(StabilityError::Option {
            what: "alpha_max",
            ..
        })
    ));
    assert!(matches!(
        alpha_interval(
            &robot,
            ControllerKind::First,
            &s,
            &Q0[..3],
            &StabilityOptions::default()
        ),
        Err(StabilityError::Model(_))
    ));
}
