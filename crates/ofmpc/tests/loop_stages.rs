//! The closed loop's stages are enough to build one's own loop: a loop
//! written here from `Sensor`, `Supervisor`, `Estimator`, `Actuator` and
//! `Recorder` (the order `ClosedLoop` documents) reproduces `ClosedLoop`'s
//! record bit for bit on a run with lost samples, a noisy delayed encoder,
//! an encoder glitch and the plausibility check, and allocates nothing per
//! sample (counted on this thread).

mod common;

use common::alloc_counter;

use alloc_counter::allocations_during;
use ofmpc::control::{new_controller, ControllerKind, MpcSettings, StateObserver};
use ofmpc::dynamics::RobotDynamics;
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{
    ClosedLoop, Estimator, Fault, LoopSettings, LossSchedule, MeasurementFaults, Plant,
    PlantSettings, Record, Recorder, RunConditions, Sample, Sensor, Supervisor,
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

fn observer(s: &Setup) -> StateObserver {
    StateObserver::new(
        s.robot.dof(),
        s.mpc.ts,
        plant_settings().delay_samples,
        ofmpc::sim::OBSERVER_POLE,
    )
}

fn with_closed_loop(s: &Setup) -> Record {
    let n = s.robot.dof();
    let mut controller = new_controller(ControllerKind::Second, n, &s.mpc).unwrap();
    let mut model = RobotDynamics::new(s.robot.clone());
    let mut plant = Plant::with_period(
        s.plant_robot.clone(),
        plant_settings(),
        s.reference.q(0),
        s.reference.ts(),
    )
    .unwrap();
    let settings = loop_settings();
    let conditions = conditions();
    let mut obs = observer(s);
    let run = ClosedLoop::with_conditions(
        controller.as_mut(),
        &mut model,
        &mut plant,
        &s.reference,
        &settings,
        &conditions,
        Some(&mut obs),
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
    let mut controller = new_controller(ControllerKind::Second, n, &s.mpc).unwrap();
    let mut model = RobotDynamics::new(s.robot.clone());
    let mut plant = Plant::with_period(
        s.plant_robot.clone(),
        plant_settings(),
        s.reference.q(0),
        ts,
    )
    .unwrap();
    let mut obs = observer(s);
    let total = s.reference.len() + settings.hold_samples(ts);
    let conditions = conditions();
    let lost = LossSchedule::new(&conditions.faults, ts);
    let mut sensor = Sensor::new(plant.settings(), n, ts, lost).unwrap();
    let mut supervisor =
        Supervisor::with_period(plant.robot(), settings.supervisor(&conditions.safety), ts);
    let mut estimator = Estimator::new(n, Some(&mut obs));
    let mut actuator = plant.settings().actuator(plant.robot(), ts);
    let mut rec = Recorder::new(n, total, true, false);
    let (mut x, mut tau) = (vec![0.0; 2 * n], vec![0.0; n]);
    let mut preview = vec![0.0; controller.horizon() * n];
    let mut x_true = vec![0.0; 2 * n];
    sensor.measure(&plant.state(), &mut x).unwrap();
    estimator.reset(&x);
    controller.reset(&x).unwrap();
    sensor.reset(&x);
    supervisor.reset(&x);
    let allocations = allocations_during(|| {
        for k in 0..total {
            let t = k as f64 * ts;
            sensor.read(&plant.state(), k, k > 0, &mut x).unwrap();
            x_true[..n].copy_from_slice(plant.q());
            x_true[n..].copy_from_slice(plant.qd());
            rec.reading(&x);
            let w = s.reference.q(k);
            let repaired = sensor.repair(&mut model, &mut x);
            let inspection = supervisor.inspect(&mut x, w);
            rec.fault(repaired || inspection.rejected);
            let flange = plant.flange_position();
            s.reference.preview(k, controller.horizon(), &mut preview);
            let xs = estimator.estimate(&mut model, &x).unwrap();
            controller
                .step(
                    &mut model,
                    &ofmpc::control::StepInput {
                        x: xs,
                        w_k: w,
                        preview: &preview,
                    },
                    &mut tau,
                )
                .unwrap();
            estimator.record_torque(&tau);
            sensor.record_torque(&tau);
            rec.loading(actuator.account(&tau));
            supervisor.record_torque(&tau);
            let applied = actuator.apply(&tau, plant.state().path_sample).unwrap();
            plant.advance(applied).unwrap();
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
            assert!(supervisor.divergence(w, &x_true[..n]).is_none());
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
