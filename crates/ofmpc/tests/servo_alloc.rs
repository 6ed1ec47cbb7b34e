//! The servo interface stage allocates nothing per sample (issue 37): a run
//! through each kind of interface (a torque low-pass, a position/velocity
//! joint loop with a 40 ms lag line, a velocity loop, ur-servoj's smoothing
//! under the command's stream model), with injected late steps bridged by
//! extrapolation, and an adaptive kind identifying its payload from the
//! drives' reported torque and sending it as a torque feed-forward,
//! allocates the same number of times whatever its length. Counted per
//! thread by a global allocator.

mod common;

use common::alloc_counter;

use alloc_counter::allocations_during;
use ofmpc::control::{ControllerKind, MpcSettings, OutputMode, Weight};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{Experiment, LateSteps, LoopSettings, OnLate, ServoProfile, ServoSettings};

#[global_allocator]
static GLOBAL: alloc_counter::Counting = alloc_counter::Counting;

fn experiment(hold_s: f64, servo: ServoSettings) -> Experiment {
    let robot = Robot::irb140();
    let reference = common::paper_reference(&robot);
    let mut e = Experiment {
        robot,
        reference,
        mpc: MpcSettings {
            q_du: Weight::Scalar(1e-3),
            output: servo.kind(),
            ..Default::default()
        },
        plant: Default::default(),
        loop_settings: LoopSettings {
            hold_s,
            steady_window_s: 0.3,
            ..Default::default()
        },
        conditions: Default::default(),
        baselines: Default::default(),
    };
    e.plant.servo = Some(servo);
    e
}

#[test]
fn a_longer_run_through_a_servo_allocates_no_more() {
    let late = vec![LateSteps {
        t: 1.0,
        duration_s: 0.02,
    }];
    let servos = [
        ServoSettings::profile(ServoProfile::FrankaTorque),
        ServoSettings {
            on_late: Some(OnLate::Extrapolate),
            late: late.clone(),
            ..ServoSettings::profile(ServoProfile::AbbEgm)
        },
        ServoSettings {
            kind: Some(OutputMode::Velocity),
            late,
            ..ServoSettings::profile(ServoProfile::KukaRsi)
        },
        ServoSettings {
            reports_torque: Some(true),
            torque_feedforward: Some(true),
            ..ServoSettings::profile(ServoProfile::AbbEgm)
        },
        // The smoothing inverted by the command's stream model; one late
        // step (five missed cycles: its watchdog trips at ten).
        ServoSettings {
            gain: Some(2000.0),
            late: vec![LateSteps {
                t: 1.0,
                duration_s: 0.0,
            }],
            ..ServoSettings::profile(ServoProfile::UrServoj)
        },
    ];
    // Warm up lazily initialised statics.
    let _ = experiment(0.3, servos[0].clone()).run(
        ControllerKind::Second,
        &Payload::point_mass(0.25),
        &mut |_, _| {},
    );
    for servo in servos {
        let kind = if servo.reports_applied_torque() {
            ControllerKind::SecondAdaptive
        } else {
            ControllerKind::Second
        };
        let mut counts = Vec::new();
        for hold_s in [0.3, 2.0] {
            let exp = experiment(hold_s, servo.clone());
            let n = allocations_during(|| {
                let (_, m) = exp
                    .run(kind, &Payload::point_mass(0.25), &mut |_, _| {})
                    .unwrap();
                assert_eq!(
                    m.status.to_string(),
                    "ok",
                    "{:?}: {}",
                    servo.profile,
                    m.reason
                );
                if servo.reports_applied_torque() {
                    assert!(m.payload_estimate_kg.is_some());
                }
                let report = m.servo.unwrap();
                assert!(report.cycles > 1000, "{report:?}");
            });
            counts.push(n);
        }
        assert_eq!(
            counts[0], counts[1],
            "{:?}: {} allocations for a 0.3 s hold, {} for 2 s",
            servo.profile, counts[0], counts[1]
        );
    }
}
