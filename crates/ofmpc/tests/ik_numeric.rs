//! Numeric (damped least squares) IK on an independent IRB 140 chain built from the
//! URDF joint origins and axes; allocation checks for the whole ik module.

mod common;
use common::alloc_counter;
use common::ik_model as ik_common;
use std::f64::consts::PI;

use ik_common::*;
use nalgebra::{DMatrix, Isometry3};
use ofmpc::ik::{
    rotation_log, ForwardKinematics, IkError, IkSolver, NumericIk, NumericIkSettings, OpwParameters,
};

#[global_allocator]
static GLOBAL: alloc_counter::Counting = alloc_counter::Counting;

use alloc_counter::allocations;

fn numeric() -> NumericIk {
    NumericIk::new(6, &LOWER, &UPPER, NumericIkSettings::default()).unwrap()
}

#[test]
fn test_chain_jacobian_matches_finite_differences_of_opw_forward() {
    // Validates the helper used below against the library's closed-form FK.
    let opw = OpwParameters::irb140();
    let mut rng = Rng::new(20);
    let mut j = DMatrix::zeros(6, 6);
    let h = 1e-6;
    for _ in 0..100 {
        let q = rng.joints_in_limits(0.0);
        UrdfChain.flange_jacobian(&q, &mut j);
        for i in 0..6 {
            let (mut qp, mut qm) = (q, q);
            qp[i] += h;
            qm[i] -= h;
            let (tp, tm) = (opw.forward(&qp), opw.forward(&qm));
            let v = (tp.translation.vector - tm.translation.vector) / (2.0 * h);
            let w = rotation_log(&(tp.rotation * tm.rotation.inverse())) / (2.0 * h);
            for r in 0..3 {
                assert!((j[(r, i)] - v[r]).abs() < 1e-8, "q {q:?} col {i}");
                assert!((j[(r + 3, i)] - w[r]).abs() < 1e-8, "q {q:?} col {i}");
            }
        }
    }
}

#[test]
fn converges_from_a_nearby_seed_to_machine_precision() {
    let opw = OpwParameters::irb140();
    let mut ik = numeric();
    let mut rng = Rng::new(21);
    let mut max_iterations = 0;
    for _ in 0..300 {
        let q = rng.joints_in_limits(0.1);
        let target = opw.forward(&q);
        let mut sol: [f64; 6] = std::array::from_fn(|i| q[i] + rng.uniform(-0.1, 0.1));
        let report = ik.solve(&mut UrdfChain, &target, &mut sol).unwrap();
        assert!(report.position_error <= 1e-10 && report.orientation_error <= 1e-10);
        // Independent check with the closed-form FK.
        let back = opw.forward(&sol);
        assert!(position_distance(&back, &target) <= 1e-10, "q {q:?}");
        assert!(rotation_distance(&back, &target) <= 1e-10, "q {q:?}");
        assert!((0..6).all(|i| sol[i] >= LOWER[i] && sol[i] <= UPPER[i]));
        max_iterations = max_iterations.max(report.iterations);
    }
    assert!(max_iterations <= 30, "max iterations {max_iterations}");
}

#[test]
fn converges_from_a_singular_seed() {
    // q = 0 is wrist-singular (q5 = 0): JᵀJ is rank deficient, the damping copes.
    let opw = OpwParameters::irb140();
    let target = opw.forward(&[0.1, 0.1, -0.1, 0.2, 0.3, 0.1]);
    let mut q = [0.0; 6];
    let report = numeric().solve(&mut UrdfChain, &target, &mut q).unwrap();
    assert!(report.iterations > 0);
    assert!(position_distance(&opw.forward(&q), &target) <= 1e-10);
    assert!(rotation_distance(&opw.forward(&q), &target) <= 1e-10);
}

#[test]
fn every_numeric_solution_is_one_of_the_analytic_solutions() {
    // Completeness of the closed form: from random seeds, damped least squares
    // converges to various configurations; each must be among the OPW solutions.
    let opw = OpwParameters::irb140();
    let wide = [-10.0; 6];
    let settings = NumericIkSettings {
        max_iterations: 300,
        ..Default::default()
    };
    let mut ik = NumericIk::new(6, &wide, &[10.0; 6], settings).unwrap();
    let mut rng = Rng::new(22);
    for q in [
        [0.3, -0.2, -0.4, 0.5, 0.7, -0.2],
        [-1.0, 0.4, -1.9, -2.0, 1.2, 2.5],
    ] {
        let target = opw.forward(&q);
        let analytic = opw.inverse(&target);
        let mut found = Vec::new();
        for _ in 0..60 {
            let mut sol: [f64; 6] = std::array::from_fn(|_| rng.uniform(-PI, PI));
            if ik.solve(&mut UrdfChain, &target, &mut sol).is_ok() {
                let idx = analytic
                    .as_slice()
                    .iter()
                    .position(|a| max_angle_diff_mod_2pi(a, &sol) < 1e-7)
                    .unwrap_or_else(|| panic!("numeric solution {sol:?} not analytic"));
                if !found.contains(&idx) {
                    found.push(idx);
                }
            }
        }
        assert!(
            found.len() >= 4,
            "only {} configurations reached",
            found.len()
        );
    }
}

#[test]
fn unreachable_pose_reports_failure_and_keeps_limits() {
    let mut ik = numeric();
    let target = Isometry3::translation(3.0, 0.0, 0.5);
    let mut q = [0.1; 6];
    match ik.solve(&mut UrdfChain, &target, &mut q) {
        Err(IkError::NotConverged { position_error, .. }) => assert!(position_error > 2.0),
        other => panic!("expected NotConverged, got {other:?}"),
    }
    assert!((0..6).all(|i| q[i].is_finite() && q[i] >= LOWER[i] && q[i] <= UPPER[i]));
}

#[test]
fn pose_outside_the_joint_limits_is_not_reached() {
    let opw = OpwParameters::irb140();
    let mut lower = LOWER;
    let mut upper = UPPER;
    lower[4] = 0.5;
    upper[4] = 1.0;
    let mut ik = NumericIk::new(6, &lower, &upper, NumericIkSettings::default()).unwrap();
    let target = opw.forward(&[0.2, 0.1, -0.3, 0.4, 0.2, 0.3]);
    let mut q = [0.2, 0.1, -0.3, 0.4, 0.8, 0.3];
    assert!(matches!(
        ik.solve(&mut UrdfChain, &target, &mut q),
        Err(IkError::NotConverged { .. })
    ));
    assert!(q[4] >= 0.5 && q[4] <= 1.0);
}

#[test]
fn bad_input_is_an_error_and_leaves_q_unchanged() {
    let opw = OpwParameters::irb140();
    let mut ik = numeric();
    let target = opw.forward(&[0.1; 6]);
    let nan_target = Isometry3::translation(f64::NAN, 0.0, 0.0);
    let mut q = [0.2; 6];
    assert!(matches!(
        ik.solve(&mut UrdfChain, &nan_target, &mut q),
        Err(IkError::NonFinite {
            what: "target pose"
        })
    ));
    assert_eq!(q, [0.2; 6]);
    let mut q = [0.2, 0.2, f64::NAN, 0.2, 0.2, 0.2];
    assert!(matches!(
        ik.solve(&mut UrdfChain, &target, &mut q),
        Err(IkError::NonFinite { .. })
    ));
    let mut short = [0.0; 5];
    assert!(matches!(
        ik.solve(&mut UrdfChain, &target, &mut short),
        Err(IkError::DimensionMismatch {
            expected: 6,
            got: 5,
            ..
        })
    ));
}

#[test]
fn solvers_do_not_allocate_after_construction() {
    let opw = OpwParameters::irb140();
    let mut ik = numeric();
    let mut solver = IkSolver::irb140();
    let q0 = [0.3, -0.2, -0.4, 0.5, 0.7, -0.2];
    solver.set_previous(&q0).unwrap();
    let targets: Vec<Isometry3<f64>> = (0..20)
        .map(|k| {
            let t = f64::from(k) * 0.01;
            opw.forward(&[0.3 + t, -0.2 + t, -0.4, 0.5 + t, 0.7 - t, -0.2])
        })
        .collect();
    let before = allocations();
    let mut q = q0;
    for target in &targets {
        let sols = opw.inverse(target);
        assert!(!sols.is_empty());
        let r = solver.solve(target).unwrap();
        ik.solve(&mut UrdfChain, target, &mut q).unwrap();
        assert!(max_abs_diff(&r, &q) < 1e-9);
    }
    assert_eq!(allocations() - before, 0, "allocations in the solve loop");
}
