//! The adaptive variants (online payload identification) against the issue's
//! targets: the paper's path at 2 kg and 6 kg (where the paper's tuning makes
//! the plain second algorithm diverge), a payload picked up mid-path, other
//! programs, and a robot that is not an IRB 140.

mod common;

use common::experiment::{experiment, run, steady};
use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{Experiment, LoopSettings, RunConditions, RunMetrics, RunStatus};

fn arm6() -> Robot {
    let mut r = Robot::from_urdf_str(include_str!("data/arm6.urdf")).unwrap();
    let d = Drives::from_toml_str(include_str!("data/arm6_drives.toml")).unwrap();
    r.apply_drives(&d).unwrap();
    r
}

/// Offset-free, never diverged, mass estimate within 5 %.
fn assert_adaptive_target(m: &RunMetrics, mass: f64, rms_mm: Option<f64>) {
    assert_eq!(m.status, RunStatus::Ok, "{}: {}", m.name, m.reason);
    assert!(
        steady(m) <= 1e-9,
        "{}: steady {:?}",
        m.name,
        m.steady_joint_error_max_rad
    );
    let est = m
        .payload_estimate_kg
        .expect("an adaptive run reports its estimate");
    assert!(
        (est - mass).abs() <= 0.05 * mass.max(0.1),
        "{}: estimate {est} kg",
        m.name
    );
    if let Some(limit) = rms_mm {
        assert!(
            m.cartesian_error_rms_mm <= limit,
            "{}: RMS {} mm",
            m.name,
            m.cartesian_error_rms_mm
        );
    }
}

#[test]
fn paper_path_at_2_and_6_kg() {
    let exp = experiment(Robot::irb140(), PAPER_TABLE1, None);
    for mass in [2.0, 6.0] {
        // The paper's second algorithm diverges there (docs/guide/paper-notes.md,
        // "The experiment") ...
        let plain = run(&exp, ControllerKind::Second, mass);
        assert_eq!(plain.status, RunStatus::Diverged, "second at {mass} kg");
        assert!(plain.payload_estimate_kg.is_none());
        // ... its adaptive variant does not, nor the first's.
        let second = run(&exp, ControllerKind::SecondAdaptive, mass);
        assert_eq!(second.controller, "second-adaptive");
        assert_eq!(second.name, format!("second-adaptive_m{mass}"));
        assert_adaptive_target(&second, mass, Some(0.01));
        let first = run(&exp, ControllerKind::FirstAdaptive, mass);
        assert_eq!(first.controller, "first-adaptive");
        assert_adaptive_target(&first, mass, Some(0.03));
    }
}

#[test]
fn a_payload_picked_up_mid_path() {
    let mut exp = experiment(Robot::irb140(), PAPER_TABLE1, None);
    exp.conditions.pick_up_at_s = Some(5.0);
    for kind in [
        ControllerKind::FirstAdaptive,
        ControllerKind::SecondAdaptive,
    ] {
        let (r, m) = exp
            .run(kind, &Payload::point_mass(4.0), &mut |_, _| {})
            .unwrap();
        assert_adaptive_target(&m, 4.0, None);
        // Before the pick-up the estimate is (about) nothing, after it 4 kg.
        let k5 = r.record.t.iter().position(|&t| t >= 5.0 - 1e-9).unwrap();
        assert!(
            r.record.payload_mass_est[k5 - 1] < 0.05,
            "{}",
            r.record.payload_mass_est[k5 - 1]
        );
        let after = r.record.payload_mass_est[k5 + 50];
        assert!(
            (after - 4.0).abs() < 0.2,
            "{kind}: 0.5 s after the pick-up {after} kg"
        );
    }
    // The plant really carried nothing before: the plain first algorithm,
    // offset-free, shows the pick-up as an error jump at 5 s only.
    let (r, _) = exp
        .run(
            ControllerKind::First,
            &Payload::point_mass(4.0),
            &mut |_, _| {},
        )
        .unwrap();
    let err = |k: usize| {
        (0..6)
            .map(|i| r.record.joint_error(k, i).abs())
            .fold(0.0, f64::max)
    };
    let k5 = r.record.t.iter().position(|&t| t >= 5.0 - 1e-9).unwrap();
    let before = (k5 - 100..k5).map(err).fold(0.0, f64::max);
    let after = (k5..k5 + 50).map(err).fold(0.0, f64::max);
    assert!(after > 10.0 * before, "before {before}, after {after}");
}

#[test]
fn other_programs_on_the_irb140() {
    // Arcs in the XZ plane and a circle in the YZ plane, other work offsets.
    let cases = [
        (include_str!("data/arc_xz.gcode"), [0.55, 0.1, 0.45]),
        (include_str!("data/arc_yz.gcode"), [0.6, -0.1, 0.6]),
    ];
    for (program, origin) in cases {
        let exp = experiment(Robot::irb140(), program, Some(origin));
        let lag = first_exact_lag(&exp);
        for mass in [2.0, 6.0] {
            assert_adaptive_target(
                &run(&exp, ControllerKind::SecondAdaptive, mass),
                mass,
                Some(0.01),
            );
            assert_adaptive_target(
                &run(&exp, ControllerKind::FirstAdaptive, mass),
                mass,
                Some(lag),
            );
        }
    }
}

/// The first algorithm's single integrator lags the ramps even with an exact
/// model (0.023 mm RMS on the paper's path, 0.032–0.037 mm on the faster
/// arcs here): the first adaptive variant is held to that, +5 %.
fn first_exact_lag(exp: &Experiment) -> f64 {
    let exact = run(exp, ControllerKind::First, 0.0);
    assert_eq!(exact.status, RunStatus::Ok);
    1.05 * exact.cartesian_error_rms_mm
}

#[test]
fn a_robot_that_is_not_an_irb140() {
    let exp = experiment(
        arm6(),
        include_str!("data/arc_yz.gcode"),
        Some([0.5, 0.11, 0.5]),
    );
    let lag = first_exact_lag(&exp);
    // The paper's tuning cannot carry 0.5 kg on this arm ...
    assert_eq!(
        run(&exp, ControllerKind::Second, 0.5).status,
        RunStatus::Diverged
    );
    // ... the adaptive variants carry its whole rated range.
    for mass in [0.5, 2.0, 5.0] {
        assert_adaptive_target(
            &run(&exp, ControllerKind::SecondAdaptive, mass),
            mass,
            Some(0.01),
        );
        assert_adaptive_target(
            &run(&exp, ControllerKind::FirstAdaptive, mass),
            mass,
            Some(lag),
        );
    }
}

mod never_panics {
    use super::*;
    use ofmpc::motion::JointReference;
    use ofmpc::sim::PlantSettings;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]
        /// Random tunings, payloads, pick-up and identification times and plant
        /// effects the estimator does not model (friction, noise, saturation):
        /// an outcome, never a panic, and the mass estimate stays physical.
        #[test]
        fn adaptive_runs_never_panic(
            q_dy in 0.0f64..5.0, q_du in 1e-6f64..1e-2, payload in 0.0f64..20.0,
            second in any::<bool>(), pick_up in prop::option::of(0.0f64..0.8),
            identification in 0.0f64..1.0, friction in 0.0f64..2.0, noise in 0.0f64..1e-4,
        ) {
            let q = vec![0.2, 0.5, -0.3, 0.4, 0.9, -0.2];
            let reference = JointReference::from_samples(6, 0.01, q, vec![[0.0; 3]], vec![0]).unwrap();
            let exp = Experiment {
                robot: Robot::irb140(),
                reference,
                mpc: MpcSettings { q_dy: ofmpc::control::Weight::Scalar(q_dy), q_du: ofmpc::control::Weight::Scalar(q_du), ..Default::default() },
                plant: PlantSettings { coulomb_friction: vec![friction], position_noise: noise, torque_limits: true, ..Default::default() },
                loop_settings: LoopSettings { hold_s: 0.8, identification_s: identification, ..Default::default() },
                conditions: RunConditions { pick_up_at_s: pick_up, ..Default::default() },
                baselines: Default::default(),
            };
            let kind = if second { ControllerKind::SecondAdaptive } else { ControllerKind::FirstAdaptive };
            let (r, m) = exp.run(kind, &Payload::point_mass(payload), &mut |_, _| {}).unwrap();
            prop_assert_eq!(m.status, r.outcome.status());
            prop_assert_eq!(r.record.payload_mass_est.len(), r.record.len());
            prop_assert!(r.record.payload_mass_est.iter().all(|m| m.is_finite() && *m >= 0.0));
        }
    }
}

#[test]
fn controller_names_round_trip() {
    for k in ControllerKind::WITH_ADAPTIVE {
        assert_eq!(k.name().parse::<ControllerKind>().unwrap(), k);
        let json = serde_json::to_string(&k).unwrap();
        assert_eq!(json, format!("\"{}\"", k.name()));
        assert_eq!(serde_json::from_str::<ControllerKind>(&json).unwrap(), k);
        assert_eq!(k.is_adaptive(), k.name().ends_with("-adaptive"));
        assert!(!k.base().is_adaptive());
    }
    let err = "third".parse::<ControllerKind>().unwrap_err().to_string();
    assert!(err.contains("second-adaptive"), "{err}");
    // The usual MPC has no adaptive variant.
    assert!(ofmpc::control::AdaptiveMpc::new(
        ControllerKind::Usual,
        6,
        &MpcSettings::default(),
        &ofmpc::control::BaselineSettings::default()
    )
    .is_err());
}
