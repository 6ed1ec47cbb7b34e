//! Real-time property of both least-squares solvers: after construction and
//! reset, `Algorithm::step` performs no heap allocation (counted by a global
//! allocator, per thread), with the structured solver at long horizons and
//! the dense QR named explicitly.

use common::alloc_counter;

mod common;

use common::{CoupledModel, TwoLinkArm};
use ofmpc::control::{new_controller, ControllerKind, MpcSettings, Solver, Weight};
use ofmpc::dynamics::JointSpaceDynamics;

#[global_allocator]
static GLOBAL: alloc_counter::Counting = alloc_counter::Counting;

use alloc_counter::allocations;

fn count_steps(model: &mut dyn JointSpaceDynamics, settings: &MpcSettings) {
    let n = model.dof();
    for kind in ControllerKind::PAPER {
        let mut ctrl = new_controller(kind, n, settings).unwrap();
        let x0: Vec<f64> = (0..2 * n).map(|i| 0.05 * i as f64).collect();
        ctrl.reset(&x0).unwrap();
        let mut x = x0.clone();
        let wk = vec![0.3; n];
        let preview: Vec<f64> = (0..n * settings.horizon)
            .map(|i| 0.3 + 1e-3 * i as f64)
            .collect();
        let mut tau = vec![0.0; n];
        let bad_x = vec![f64::NAN; 2 * n];
        let before = allocations();
        for k in 0..50 {
            // Vary the state so that f0 and the number of ZOH squarings change.
            for (i, xi) in x.iter_mut().enumerate() {
                *xi = x0[i] + 0.01 * k as f64 * if i % 2 == 0 { 1.0 } else { -3.0 };
            }
            ctrl.step(
                model,
                &ofmpc::control::StepInput {
                    x: &x,
                    w_k: &wk,
                    preview: &preview,
                },
                &mut tau,
            )
            .unwrap();
            // Failed steps allocate nothing either.
            assert!(ctrl
                .step(
                    model,
                    &ofmpc::control::StepInput {
                        x: &bad_x,
                        w_k: &wk,
                        preview: &preview
                    },
                    &mut tau
                )
                .is_err());
            assert!(ctrl
                .step(
                    model,
                    &ofmpc::control::StepInput {
                        x: &x[1..],
                        w_k: &wk,
                        preview: &preview
                    },
                    &mut tau
                )
                .is_err());
        }
        let after = allocations();
        assert_eq!(
            after - before,
            0,
            "{kind} ({:?}), n = {n}, N = {}: {} allocations in 150 steps",
            settings.solver,
            settings.horizon,
            after - before
        );
        assert!(ctrl.increments().iter().any(|v| *v != 0.0));
    }
}

#[test]
fn structured_and_dense_steps_allocate_nothing() {
    // Sanity: the counter sees allocations.
    let before = allocations();
    let v = std::hint::black_box(vec![1u8; 10]);
    assert!(allocations() > before);
    drop(v);

    for solver in [Solver::Structured, Solver::DenseQr, Solver::Auto] {
        for nh in [1usize, 10, 40] {
            let s = MpcSettings {
                horizon: nh,
                solver,
                ..MpcSettings::default()
            };
            count_steps(&mut CoupledModel::new(6, 1), &s);
        }
        let diagonal = MpcSettings {
            horizon: 25,
            solver,
            q_yw: Weight::Diagonal(vec![1.0, 2.0]),
            q_dy: Weight::Diagonal(vec![0.5, 0.0]),
            ..MpcSettings::default()
        };
        count_steps(&mut TwoLinkArm::new(), &diagonal);
    }
}
