//! The closed loop's stages are enough to build one's own loop: a loop
//! written here from `Sensor`, `SupervisedController` (the built controller
//! behind its guard), `Actuator` and `Recorder` (the order `ClosedLoop`
//! documents) reproduces `ClosedLoop`'s
//! record bit for bit on a run with lost samples, a noisy delayed encoder,
//! an encoder glitch and the plausibility check, and allocates nothing per
//! sample (counted on this thread).

mod common;

use common::alloc_counter;

use alloc_counter::allocations_during;
use ofmpc::control::{
    Controller, ControllerBuilder, ControllerKind, MpcSettings, ObserverSettings,
};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{
    ClosedLoop, Fault, LoopSettings, LossSchedule, MeasurementFaults, Plant, PlantSettings, Record,
    Recorder, RunConditions, Sample, Sensor, SupervisedController, SupervisedInput,
    SupervisedStatus,
};

#[global_allocator]
static GLOBAL: alloc_counter::Counting = alloc_counter::Counting;

fn loop_settings() -> LoopSettings {
    LoopSettings {
        hold_s: 0.5,
        steady_window_s: 0.2,
        plausibility_check: true,
        ..Default::default()
    }
}

fn conditions() -> RunConditions {
    RunConditions {
        faults: MeasurementFaults {
            nan_at_s: vec![1.0, 3.0],
            dropout_s: vec![[2.0, 2.05]],
        },
        ..Default::default()
    }
}

fn plant_settings() -> PlantSettings {
    PlantSettings {
        encoder_counts: 1 << 20,
        delay_samples: 1,
        faults: vec![Fault::EncoderGlitch {
            t: 4.0,
            joint: 2,
            offset_rad: 0.02,
        }],
        ..Default::default()
    }
}

struct Setup {
    robot: Robot,
    plant_robot: Robot,
    reference: ofmpc::motion::JointReference,
    mpc: MpcSettings,
}

fn setup() -> Setup {
    let robot = Robot::irb140();
    let reference = common::paper_reference(&robot);
    let mut plant_robot = robot.clone();
    plant_robot
        .set_payload(Some(Payload::point_mass(0.5)))
        .unwrap();
    let mpc = MpcSettings {
        delay_compensation: true,
        ..Default::default()
    };
    Setup {
        robot,
        plant_robot,
        reference,
        mpc,
    }
}

/// The controller of the runs: the second-order one with the observer
/// that compensates the encoder's delay.
fn controller(s: &Setup) -> Controller {
    ControllerBuilder::new(ControllerKind::Second, &s.robot)
        .settings(s.mpc.clone())
        .observer(ObserverSettings {
            pole: ofmpc::sim::OBSERVER_POLE,
            measurement_delay: plant_settings().delay_samples,
        })
        .accept_ineffective_settings()
        .build()
        .unwrap()
}

fn with_closed_loop(s: &Setup) -> Record {
    let mut plant = Plant::with_period(
        s.plant_robot.clone(),
        plant_settings(),
        s.reference.q(0),
        s.reference.ts(),
    )
    .unwrap();
    let settings = loop_settings();
    let conditions = conditions();
    let run = ClosedLoop::with_conditions(
        controller(s),
        &mut plant,
        &s.reference,
        &settings,
        &conditions,
    )
    .run(&mut |_, _| {});
    assert!(run.outcome.is_completed(), "{:?}", run.outcome);
    run.record
}

/// The same run, the loop written out from the public stages.
fn by_hand(s: &Setup) -> (Record, usize) {
    let n = s.robot.dof();
    let ts = s.reference.ts();
    let settings = loop_settings();
    let mut plant = Plant::with_period(
        s.plant_robot.clone(),
        plant_settings(),
        s.reference.q(0),
        ts,
    )
    .unwrap();
    let total = s.reference.len() + settings.hold_samples(ts);
    let conditions = conditions();
    let lost = LossSchedule::new(&conditions.faults, ts);
    let mut sensor = Sensor::new(plant.settings(), n, ts, lost).unwrap();
    let mut controller = SupervisedController::new(
        controller(s),
        plant.robot(),
        settings.supervisor(&conditions.safety),
        plant_settings().delay_samples,
        sensor.loses_samples(),
    )
    .unwrap();
    let mut actuator = plant.settings().actuator(plant.robot(), ts);
    let mut rec = Recorder::new(n, total, true, false);
    let mut x = vec![0.0; 2 * n];
    let mut preview = vec![0.0; controller.horizon() * n];
    let mut x_true = vec![0.0; 2 * n];
    sensor.measure(&plant.state(), &mut x).unwrap();
    controller.reset(&x).unwrap();
    let allocations = allocations_during(|| {
        for k in 0..total {
            let t = k as f64 * ts;
            sensor.read(&plant.state(), k, k > 0, &mut x).unwrap();
            x_true[..n].copy_from_slice(plant.q());
            x_true[n..].copy_from_slice(plant.qd());
            rec.reading(&x);
            let w = s.reference.q(k);
            let flange = plant.flange_position();
            s.reference.preview(k, controller.horizon(), &mut preview);
            let input = SupervisedInput {
                t,
                x: &x,
                w_k: w,
                preview: &preview,
                truth: Some(&x_true[..n]),
            };
            let status = controller.step(&input).unwrap().status;
            assert!(matches!(
                status,
                SupervisedStatus::Controlled | SupervisedStatus::RepairedMeasurement
            ));
            rec.fault(controller.repaired());
            rec.loading(actuator.account(controller.torque()));
            let applied = actuator
                .apply(controller.torque(), plant.state().path_sample)
                .unwrap();
            plant.advance(applied).unwrap();
            controller.watch(plant.q(), plant.qd(), t);
            rec.push(&Sample {
                t,
                q: &x_true[..n],
                qd: &x_true[n..],
                tau: plant.applied_torque(),
                w,
                flange_ref: s.reference.position(k),
                flange,
                step_us: 0.0,
                payload_mass_est: None,
            });
        }
    });
    (rec.into_record(), allocations)
}

#[test]
fn a_loop_of_the_public_stages_is_the_closed_loop() {
    let s = setup();
    let a = with_closed_loop(&s);
    let (b, allocations) = by_hand(&s);
    assert_eq!(allocations, 0, "the stages allocated in the loop");
    assert_eq!(a.len(), b.len());
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a.q), bits(&b.q), "joint positions");
    assert_eq!(bits(&a.qd), bits(&b.qd), "joint velocities");
    assert_eq!(bits(&a.tau), bits(&b.tau), "torques");
    assert_eq!(bits(&a.q_meas), bits(&b.q_meas), "readings");
    assert_eq!(a.faults, b.faults);
    // Lost samples (2 NaN + 5 of the dropout) and the glitch were handled.
    assert!(a.faults >= 7, "faults: {}", a.faults);
    assert_eq!(a.max_torque_ratio.to_bits(), b.max_torque_ratio.to_bits());
    assert_eq!(a.flange, b.flange);
}
