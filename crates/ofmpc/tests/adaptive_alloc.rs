//! Real-time property of the adaptive variants: after construction and
//! reset, a step (payload identification, model update, the algorithm's own
//! step) performs no heap allocation (counted per thread) and never panics,
//! also on failed steps and with a model that has no rigid-body behind it.

mod common;
use common::alloc_counter;

use nalgebra::{DMatrix, DVector};
use ofmpc::control::{new_controller, ControllerKind, MpcSettings, StepFailure};
use ofmpc::dynamics::{JointSpaceDynamics, RobotDynamics};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{LossSchedule, Plant, PlantSettings, Sensor};

#[global_allocator]
static GLOBAL: alloc_counter::Counting = alloc_counter::Counting;

use alloc_counter::allocations;

/// A model with no rigid body behind it (the adaptive step must refuse it).
struct Opaque(RobotDynamics);
impl JointSpaceDynamics for Opaque {
    fn dof(&self) -> usize {
        self.0.dof()
    }
    fn terms(
        &mut self,
        q: &[f64],
        qd: &[f64],
        h: &mut DMatrix<f64>,
        c: &mut DMatrix<f64>,
        g: &mut DVector<f64>,
    ) {
        self.0.terms(q, qd, h, c, g)
    }
}

#[test]
fn adaptive_steps_allocate_nothing() {
    let before = allocations();
    let v = std::hint::black_box(vec![1u8; 10]);
    assert!(allocations() > before);
    drop(v);

    let robot = Robot::irb140();
    let mut loaded = robot.clone();
    loaded.set_payload(Some(Payload::point_mass(3.0))).unwrap();
    let settings = MpcSettings::default();
    let q0 = [0.1, 0.4, -0.2, 0.3, 0.8, 0.1];
    for kind in [
        ControllerKind::FirstAdaptive,
        ControllerKind::SecondAdaptive,
    ] {
        let mut ctrl = new_controller(kind, 6, &settings).unwrap();
        let mut model = RobotDynamics::new(robot.clone());
        let mut plant =
            Plant::with_period(loaded.clone(), PlantSettings::default(), &q0, settings.ts).unwrap();
        let mut sensor = Sensor::ideal(6, settings.ts, LossSchedule::default());
        let mut x = vec![0.0; 12];
        sensor.measure(&plant.state(), &mut x).unwrap();
        ctrl.reset(&x).unwrap();
        let preview = q0.repeat(settings.horizon);
        let mut tau = vec![0.0; 6];
        let bad_x = vec![f64::NAN; 12];
        let before = allocations();
        for _ in 0..150 {
            sensor.measure(&plant.state(), &mut x).unwrap();
            ctrl.step(
                &mut model,
                &ofmpc::control::StepInput {
                    x: &x,
                    w_k: &q0,
                    preview: &preview,
                },
                &mut tau,
            )
            .unwrap();
            plant.advance(&tau).unwrap();
            assert!(ctrl
                .step(
                    &mut model,
                    &ofmpc::control::StepInput {
                        x: &bad_x,
                        w_k: &q0,
                        preview: &preview
                    },
                    &mut tau
                )
                .is_err());
            assert!(ctrl
                .step(
                    &mut model,
                    &ofmpc::control::StepInput {
                        x: &x[1..],
                        w_k: &q0,
                        preview: &preview
                    },
                    &mut tau
                )
                .is_err());
        }
        let after = allocations();
        assert_eq!(after - before, 0, "{kind}: {} allocations", after - before);
        // It identified the load and put it into the model.
        let m = ctrl.payload_estimate().unwrap();
        assert!((m - 3.0).abs() < 0.05, "{kind}: {m}");
        let in_model = model.robot().payload().unwrap().mass;
        assert!((in_model - m).abs() < 1e-12);
        // A failed step leaves the estimate and the model as they were.
        assert_eq!(ctrl.payload_estimate(), Some(m));
        // No rigid-body model: a typed error, not a panic.
        let mut opaque = Opaque(RobotDynamics::new(robot.clone()));
        assert_eq!(
            ctrl.step(
                &mut opaque,
                &ofmpc::control::StepInput {
                    x: &x,
                    w_k: &q0,
                    preview: &preview
                },
                &mut tau
            ),
            Err(StepFailure::NoRigidBodyModel)
        );
    }
}
