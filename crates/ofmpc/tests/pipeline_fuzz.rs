//! The whole pipeline never panics: mutated programs through parsing, timing
//! and inverse kinematics; random (valid or not) tunings and payloads through
//! the closed loop. Errors and divergences are fine; panics are not.

use ofmpc::control::{ControllerKind, MpcSettings, Weight};
use ofmpc::gcode::{parse, ParseOptions, PAPER_TABLE1};
use ofmpc::motion::{build_reference, JointReference, Orientation};
use ofmpc::motion::{CartesianTrajectory, TimingOptions};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{Experiment, ExperimentError, LoopSettings, PlantSettings, RunStatus};
use proptest::prelude::*;

fn mutate(text: &str, edits: &[(usize, u8)]) -> String {
    let mut b = text.as_bytes().to_vec();
    for &(pos, c) in edits {
        let i = pos % b.len();
        b[i] = b"0123456789-.XYZIJKRGF \n"[c as usize % 23];
    }
    String::from_utf8_lossy(&b).into_owned()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn mutated_programs_never_panic_through_ik(edits in proptest::collection::vec((0usize..10_000, 0u8..23), 1..6),
                                               speed in 0.05f64..3.0, accel in 0.1f64..20.0) {
        let robot = Robot::irb140();
        let text = mutate(PAPER_TABLE1, &edits);
        if let Ok(program) = parse(&text, &ParseOptions::default()) {
            let timing = TimingOptions { max_speed: speed, max_accel: accel, ..Default::default() };
            if let Ok(traj) = CartesianTrajectory::new(&program, &timing) {
                if traj.duration() < 60.0 {
                    match build_reference(&robot, &traj, Orientation::AtZero, 0.02) {
                        Ok(r) => prop_assert!((0..r.len()).all(|k| r.q(k).iter().all(|x| x.is_finite()))),
                        Err(e) => prop_assert!(e.to_string().contains("program line")),
                    }
                }
            }
        }
    }

    #[test]
    fn random_tunings_and_payloads_never_panic_in_the_loop(
        horizon in 1usize..25, q_dy in 0.0f64..5.0, q_du in -1e-3f64..1e-2, q_u in 1e-6f64..1e-2,
        payload in 0.0f64..10.0, kind in 0usize..3, ts in prop_oneof![Just(0.01), Just(0.005), Just(0.02)],
        friction in 0.0f64..2.0, noise in 0.0f64..1e-4,
    ) {
        let q = vec![0.2, 0.5, -0.3, 0.4, 0.9, -0.2];
        let reference = JointReference::from_samples(6, ts, q, vec![[0.0; 3]], vec![0]).unwrap();
        let mpc = MpcSettings { ts, horizon, q_dy: Weight::Scalar(q_dy), q_du: Weight::Scalar(q_du), q_u: Weight::Scalar(q_u), ..Default::default() };
        let exp = Experiment {
            conditions: Default::default(),
            robot: Robot::irb140(),
            reference,
            mpc,
            plant: PlantSettings { coulomb_friction: vec![friction], position_noise: noise, torque_limits: true, ..Default::default() },
            loop_settings: LoopSettings { hold_s: 0.6, ..Default::default() },
            baselines: Default::default(),
        };
        match exp.run(ControllerKind::PAPER[kind], &Payload::point_mass(payload), &mut |_, _| {}) {
            Ok((r, m)) => {
                prop_assert_eq!(m.diverged, r.outcome.status() == RunStatus::Diverged);
                prop_assert_eq!(m.status, r.outcome.status());
                prop_assert_eq!(m.stopped_at_s, r.outcome.stopped_at());
                prop_assert!(r.record.q.iter().all(|x| x.is_finite()));
            }
            // Invalid settings (e.g. q_du ≤ 0) are reported as such.
            Err(e) => prop_assert!(matches!(e, ExperimentError::Mpc(_)), "{e:?}"),
        }
    }
}
