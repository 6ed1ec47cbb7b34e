//! Everything at once (#11 item 5): torque limits in the controller and the
//! plant, Coulomb friction with the controller's 20 %-off estimate, a 22-bit
//! encoder with encoder-derived velocity and one sample of delay (observer
//! and delay compensation), an encoder glitch, the plausibility check and the
//! safe stop; and random combinations of them, which never panic.

mod common;

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::motion::JointReference;
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{Experiment, Fault, LoopSettings, PlantSettings, RunStatus};
use proptest::prelude::*;

fn robot_with_friction_estimate() -> Robot {
    let mut robot = Robot::irb140();
    let text: String = (1..=6)
        .map(|j| format!("[joints.joint_{j}]\ncoulomb_nm = 0.8\nviscous_nms = 0.0\n"))
        .collect();
    robot
        .apply_drives(&Drives::from_toml_str(&text).unwrap())
        .unwrap();
    robot
}

#[test]
fn all_effects_together_on_the_paper_path() {
    let robot = robot_with_friction_estimate();
    let reference = common::paper_reference(&robot);
    let exp = Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc: MpcSettings {
            torque_limits: true,
            friction_compensation: true,
            delay_compensation: true,
            ..Default::default()
        },
        plant: PlantSettings {
            torque_limits: true,
            coulomb_friction: vec![1.0],
            encoder_counts: 1 << 22,
            velocity_from_encoder: true,
            delay_samples: 1,
            faults: vec![Fault::EncoderGlitch {
                t: 2.0,
                joint: 1,
                offset_rad: 0.01,
            }],
            ..Default::default()
        },
        loop_settings: LoopSettings {
            plausibility_check: true,
            safe_stop: true,
            ..Default::default()
        },
        baselines: Default::default(),
    };
    for kind in ControllerKind::PAPER {
        let (r, m) = exp
            .run(kind, &Payload::point_mass(0.25), &mut |_, _| {})
            .unwrap();
        // The second algorithm's friction hunting on the wrist (open, see the
        // README) trips the plausibility check here: it is stopped safely.
        if kind == ControllerKind::Second {
            assert!(
                matches!(m.status, RunStatus::Ok | RunStatus::Stopped),
                "{}",
                r.outcome
            );
        } else {
            assert!(r.outcome.is_completed(), "{kind}: {}", r.outcome);
        }
        assert!(r
            .record
            .q
            .iter()
            .chain(&r.record.qd)
            .chain(&r.record.tau)
            .all(|v| v.is_finite()));
        for (i, j) in exp.robot.joints().iter().enumerate() {
            assert!(
                m.torque_max_nm[i] <= j.limits.effort,
                "{kind}: joint {}",
                i + 1
            );
        }
        if kind == ControllerKind::First {
            assert!(
                m.cartesian_error_rms_mm < 0.1,
                "{kind}: {}",
                m.cartesian_error_rms_mm
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    #[test]
    fn random_combinations_never_panic(
        kind in 0usize..3, limits in any::<bool>(), plant_limits in any::<bool>(),
        friction in 0.0f64..2.0, compensate in any::<bool>(), encoder_bits in prop_oneof![Just(0u32), 12u32..24],
        from_encoder in any::<bool>(), delay in 0usize..3, observe in any::<bool>(), supervise in any::<bool>(),
        fault in 0usize..4, fault_joint in 1usize..7, fault_t in 0.0f64..0.8, payload in 0.0f64..2.0,
    ) {
        let q = vec![0.2, 0.5, -0.3, 0.4, 0.9, -0.2];
        let reference = JointReference::from_samples(6, 0.01, q, vec![[0.0; 3]], vec![0]).unwrap();
        let faults = match fault {
            1 => vec![Fault::EncoderGlitch { t: fault_t, joint: fault_joint, offset_rad: 0.01 }],
            2 => vec![Fault::EncoderDropout { t: fault_t, joint: fault_joint, duration_s: 0.1 }],
            3 => vec![Fault::TorqueDrop { t: fault_t, joint: fault_joint, fraction: 0.3, duration_s: 0.2 }],
            _ => Vec::new(),
        };
        let exp = Experiment {
            conditions: Default::default(),
            robot: robot_with_friction_estimate(),
            reference,
            mpc: MpcSettings {
                torque_limits: limits,
                friction_compensation: compensate,
                delay_compensation: observe,
                ..Default::default()
            },
            plant: PlantSettings {
                torque_limits: plant_limits,
                coulomb_friction: vec![friction],
                encoder_counts: if encoder_bits == 0 { 0 } else { 1u64 << encoder_bits },
                velocity_from_encoder: from_encoder,
                delay_samples: delay,
                faults,
                ..Default::default()
            },
            loop_settings: LoopSettings { hold_s: 0.8, plausibility_check: supervise, safe_stop: supervise, ..Default::default() },
            baselines: Default::default(),
        };
        let (r, m) = exp
            .run(ControllerKind::PAPER[kind], &Payload::point_mass(payload), &mut |_, _| {})
            .unwrap();
        // The outcome's status, but a completed run whose hold moved by more than 2
        // encoder counts is judged "hunting" (issue 35).
        let hunting = m.status == RunStatus::Hunting
            && r.outcome.status() == RunStatus::Ok
            && m.hold_error_pp_counts.is_some_and(|p| p > 2.0);
        prop_assert!(m.status == r.outcome.status() || hunting, "{:?} {:?}", m.status, r.outcome);
        prop_assert_eq!(m.stopped_at_s, r.outcome.stopped_at());
        prop_assert!(r.record.q.iter().chain(&r.record.tau).all(|x| x.is_finite()));
        if supervise {
            // With the safe stop nothing ends as "diverged".
            prop_assert!(m.status != RunStatus::Diverged);
        }
    }
}

/// Stick–slip of the wrist under Coulomb friction (1 N·m; no compensation, or
/// the compensation with an estimate of 1.0 N·m) on the paper path: the
/// friction stops the light wrist within a sample, faster than the
/// plausibility check's constant-acceleration prediction allows. The check
/// used to reject that (real) velocity and hand the second algorithm its
/// prediction (a joint still moving), which then braked against a motion
/// that was not there until the wrist ran away and the loop stopped it
/// (t = 2.87 s and 7.0 s). A velocity that explains the accepted position
/// better than the prediction is now accepted: with the check on the run is
/// the unchecked one, sample for sample.
#[test]
fn friction_stick_slip_passes_the_plausibility_check() {
    for (compensate, estimate, rms_max) in [(false, 0.8, 0.021), (true, 1.0, 0.011)] {
        let mut robot = Robot::irb140();
        let text: String = (1..=6)
            .map(|j| format!("[joints.joint_{j}]\ncoulomb_nm = {estimate}\n"))
            .collect();
        robot
            .apply_drives(&Drives::from_toml_str(&text).unwrap())
            .unwrap();
        let reference = common::paper_reference(&robot);
        let run = |check: bool| {
            let exp = Experiment {
                conditions: Default::default(),
                robot: robot.clone(),
                reference: reference.clone(),
                mpc: MpcSettings {
                    friction_compensation: compensate,
                    ..Default::default()
                },
                plant: PlantSettings {
                    coulomb_friction: vec![1.0],
                    ..Default::default()
                },
                loop_settings: LoopSettings {
                    plausibility_check: check,
                    safe_stop: check,
                    ..Default::default()
                },
                baselines: Default::default(),
            };
            exp.run(
                ControllerKind::Second,
                &Payload::point_mass(0.25),
                &mut |_, _| {},
            )
            .unwrap()
        };
        let (r, m) = run(true);
        let (r0, m0) = run(false);
        assert!(r.outcome.is_completed(), "{compensate}: {}", r.outcome);
        assert_eq!(r.record.faults, 0, "{compensate}");
        assert_eq!(r.record.tau, r0.record.tau, "{compensate}");
        assert_eq!(m.cartesian_error_rms_mm, m0.cartesian_error_rms_mm);
        assert!(
            m.cartesian_error_rms_mm < rms_max,
            "{compensate}: {}",
            m.cartesian_error_rms_mm
        );
    }
}

/// The combined scenario of `examples/drives_probe.rs` (`all`: torque limits
/// in the controller and the plant, Coulomb friction 1 N·m with the
/// estimate 0.8 N·m compensated, a 22-bit encoder with encoder-derived
/// velocity and one sample of delay compensated by the observer, the
/// plausibility check and the safe stop) with `observer_friction`: the
/// observer's model carries the friction estimate, so its disturbance does
/// not have to follow the friction's sign changes within a sample. Without
/// it the second algorithm's wrist chatters (±7.7 N·m, period 3 samples) and
/// is stopped (11.87 s); with it all three complete, the usual's and the
/// first's RMS halve or better (0.20 → 0.10 mm, 0.088 → 0.032 mm).
#[test]
fn all_effects_with_the_friction_aware_observer_complete() {
    let robot = robot_with_friction_estimate();
    let reference = common::paper_reference(&robot);
    let exp = |observer_friction: bool| Experiment {
        conditions: Default::default(),
        robot: robot.clone(),
        reference: reference.clone(),
        mpc: MpcSettings {
            torque_limits: true,
            friction_compensation: true,
            delay_compensation: true,
            observer_friction,
            ..Default::default()
        },
        plant: PlantSettings {
            torque_limits: true,
            coulomb_friction: vec![1.0],
            encoder_counts: 1 << 22,
            velocity_from_encoder: true,
            delay_samples: 1,
            ..Default::default()
        },
        loop_settings: LoopSettings {
            plausibility_check: true,
            safe_stop: true,
            ..Default::default()
        },
        baselines: Default::default(),
    };
    let payload = Payload::point_mass(0.25);
    let (r, _) = exp(false)
        .run(ControllerKind::Second, &payload, &mut |_, _| {})
        .unwrap();
    assert_eq!(r.outcome.status(), RunStatus::Stopped, "{}", r.outcome);
    for (kind, rms_max) in [
        (ControllerKind::Usual, 0.11),
        (ControllerKind::First, 0.035),
        (ControllerKind::Second, 0.03),
    ] {
        let (r, m) = exp(true).run(kind, &payload, &mut |_, _| {}).unwrap();
        assert!(r.outcome.is_completed(), "{kind}: {}", r.outcome);
        assert!(
            m.cartesian_error_rms_mm < rms_max,
            "{kind}: {}",
            m.cartesian_error_rms_mm
        );
        assert!(m.steady_cartesian_error_mm < 0.09, "{kind}");
    }
}
