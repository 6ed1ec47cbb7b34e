//! The rigid-body algorithms and the plant allocate nothing after construction.

use ofmpc::dynamics::*;
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{LossSchedule, Plant, PlantSettings, Sensor};
mod common;
use common::alloc_counter;

#[global_allocator]
static A: alloc_counter::Counting = alloc_counter::Counting;

#[test]
fn algorithms_and_plant_do_not_allocate() {
    let mut robot = Robot::irb140();
    robot.set_payload(Some(Payload::point_mass(1.0))).unwrap();
    let mut ws = Workspace::new(&robot);
    let sensing = PlantSettings {
        position_noise: 1e-6,
        ..Default::default()
    };
    let mut plant = Plant::with_period(robot.clone(), sensing.clone(), &[0.1; 6], 0.01).unwrap();
    let mut sensor = Sensor::new(&sensing, 6, 0.01, LossSchedule::default()).unwrap();
    let mut d = RobotDynamics::new(robot.clone());
    let (mut h, mut c, mut g) = (
        nalgebra::DMatrix::zeros(6, 6),
        nalgebra::DMatrix::zeros(6, 6),
        nalgebra::DVector::zeros(6),
    );
    let mut x = [0.0; 12];
    let q = [0.1, 0.4, -0.3, 0.7, 0.5, -0.2];
    let qd = [0.3, -0.2, 0.4, 0.5, -0.6, 0.7];
    let count = |f: &mut dyn FnMut()| alloc_counter::allocations_during(f);
    assert_eq!(
        count(&mut || {
            forward_kinematics(&robot, &mut ws, &q).unwrap();
        }),
        0,
        "fk"
    );
    assert_eq!(
        count(&mut || {
            flange_jacobian(&robot, &mut ws, &q).unwrap();
        }),
        0,
        "jac"
    );
    assert_eq!(
        count(&mut || {
            rnea(&robot, &mut ws, &q, &qd, &qd).unwrap();
        }),
        0,
        "rnea"
    );
    assert_eq!(
        count(&mut || {
            joint_space_terms(&robot, &mut ws, &q, &qd).unwrap();
        }),
        0,
        "terms"
    );
    assert_eq!(
        count(&mut || {
            forward_dynamics(&robot, &mut ws, &q, &qd, &qd).unwrap();
        }),
        0,
        "fd"
    );
    assert_eq!(
        count(&mut || {
            d.terms(&q, &qd, &mut h, &mut c, &mut g);
        }),
        0,
        "d.terms"
    );
    assert_eq!(
        count(&mut || {
            sensor.measure(&plant.state(), &mut x).unwrap();
        }),
        0,
        "measure"
    );
    assert_eq!(
        count(&mut || {
            plant.advance(&[1.0; 6]).unwrap();
        }),
        0,
        "pstep"
    );
    let before = alloc_counter::allocations();
    for _ in 0..100 {
        forward_kinematics(&robot, &mut ws, &q).unwrap();
        flange_jacobian(&robot, &mut ws, &q).unwrap();
        rnea(&robot, &mut ws, &q, &qd, &qd).unwrap();
        crba(&robot, &mut ws, &q).unwrap();
        coriolis_matrix(&robot, &mut ws, &q, &qd).unwrap();
        gravity(&robot, &mut ws, &q).unwrap();
        joint_space_terms(&robot, &mut ws, &q, &qd).unwrap();
        forward_dynamics(&robot, &mut ws, &q, &qd, &qd).unwrap();
        d.terms(&q, &qd, &mut h, &mut c, &mut g);
        sensor.measure(&plant.state(), &mut x).unwrap();
        plant.advance(&[1.0; 6]).unwrap();
    }
    assert_eq!(alloc_counter::allocations() - before, 0);
}

/// Negative control: the counter sees this thread's allocations.
#[test]
fn the_counter_counts_this_threads_allocations() {
    let n = alloc_counter::allocations_during(|| {
        let v = std::hint::black_box(vec![1u8; 64]);
        drop(v);
    });
    assert_eq!(n, 1);
    // ... and not another thread's.
    let n = alloc_counter::allocations_during(|| {
        std::thread::scope(|s| {
            s.spawn(|| std::hint::black_box(vec![0u8; 64]));
        })
    });
    assert!(
        n < 8,
        "thread spawn bookkeeping only, not the other thread's vec: {n}"
    );
}
