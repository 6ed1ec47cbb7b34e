//! Telemetry of the built controller (`StepOutput::telemetry`): consistent
//! with the step's own status and QP, filled without allocation.

mod common;

use common::alloc_counter;
use ofmpc::control::{ControllerKind, FallbackLevel, MpcSettings, StepInput};
use ofmpc::robot::Robot;
use ofmpc::ControllerBuilder;

/// Deadline checks of a check budget the controller keeps back for the
/// step's work after the QP (`TAIL_CHECKS` in `control/mpc/torque_limits.rs`).
const TAIL_CHECKS: u32 = 1;

#[global_allocator]
static GLOBAL: alloc_counter::Counting = alloc_counter::Counting;

/// A target far from the start, so that the torque limits bind.
fn far_target(n: usize, horizon: usize) -> (Vec<f64>, Vec<f64>) {
    (vec![1.5; n], vec![1.5; n * horizon])
}

#[test]
fn telemetry_matches_the_step_and_allocates_nothing() {
    let robot = Robot::irb140();
    for kind in [ControllerKind::Second, ControllerKind::Usual] {
        let settings = MpcSettings {
            torque_limits: true,
            ..MpcSettings::default()
        };
        let mut mpc = ControllerBuilder::new(kind, &robot)
            .settings(settings)
            .build()
            .unwrap();
        let n = mpc.dof();
        let x = vec![0.0; 2 * n];
        mpc.reset(&x).unwrap();
        let nh = mpc.horizon();
        let (w_k, preview) = far_target(n, nh);
        let input = StepInput {
            x: &x,
            w_k: &w_k,
            preview: &preview,
        };
        let mut qp_ran = 0;
        let before = alloc_counter::allocations();
        for _ in 0..50 {
            let out = mpc.step(&input).unwrap();
            let t = out.telemetry;
            let qp = out.qp_status.unwrap();
            assert_eq!(t.qp_iterations, qp.iterations);
            assert_eq!(t.active_constraints, qp.active_constraints);
            assert!(t.active_constraints as usize <= n * nh);
            if qp.active {
                qp_ran += 1;
                assert!(t.qp_iterations >= 1 && t.active_constraints >= 1);
            }
            assert!(t.model_time > std::time::Duration::ZERO);
            assert!(t.model_time <= t.solve_time && t.solve_time <= t.total_time);
            assert_eq!(t.total_time, out.solve_time);
            assert_eq!(t.budget_slack_us, None);
            assert_eq!(
                t.fallback,
                if qp.fallback {
                    FallbackLevel::BestFeasible
                } else {
                    FallbackLevel::None
                }
            );
        }
        assert_eq!(alloc_counter::allocations() - before, 0, "{kind}");
        assert!(qp_ran > 0, "{kind}: the limits never bound");
    }
}

/// The controller with torque limits at `budget_us`, reset at rest, and
/// the step input toward a far target (the limits bind).
fn limited(
    kind: ControllerKind,
    robot: &Robot,
    budget_us: Option<f64>,
) -> (ofmpc::Controller, Vec<f64>, Vec<f64>, Vec<f64>) {
    let settings = MpcSettings {
        torque_limits: true,
        step_budget_us: budget_us,
        ..MpcSettings::default()
    };
    let mut mpc = ControllerBuilder::new(kind, robot)
        .settings(settings)
        .build()
        .unwrap();
    let n = mpc.dof();
    let x = vec![0.0; 2 * n];
    mpc.reset(&x).unwrap();
    let (w_k, preview) = far_target(n, mpc.horizon());
    (mpc, x, w_k, preview)
}

/// A spent budget (0 µs: the deadline has passed before the QP's build)
/// falls back deterministically: a step with no plan to shift solves the QP
/// past its budget (a fresh plan), the next shifts that plan by one sample
/// (at most one shift in a row), and so on; every such step a budget hit,
/// every torque within the limits, nothing allocated.
#[test]
fn a_spent_budget_alternates_fresh_and_shifted_plans_within_the_limits() {
    let robot = Robot::irb140();
    let (mut mpc, x, w_k, preview) = limited(ControllerKind::Second, &robot, Some(0.0));
    let tau_max = mpc.drives().unwrap().max_torque_nm.clone();
    let nh = mpc.horizon();
    let input = StepInput {
        x: &x,
        w_k: &w_k,
        preview: &preview,
    };
    let mut levels = Vec::with_capacity(64);
    let before = alloc_counter::allocations();
    for _ in 0..3 * nh {
        let out = mpc.step(&input).unwrap();
        let qp = out.qp_status.unwrap();
        let t = out.telemetry;
        assert!(t.budget_slack_us.unwrap() <= 0.0);
        assert_eq!(t.fallback, qp.fallback_level);
        assert!(qp.active && qp.budget_hit && t.budget_hit);
        for (tau, lim) in out.tau.iter().zip(&tau_max) {
            assert!(tau.abs() <= *lim, "{tau} over {lim}");
        }
        levels.push(t.fallback);
    }
    assert_eq!(alloc_counter::allocations() - before, 0);
    for (k, l) in levels.iter().enumerate() {
        let expected = if k % 2 == 0 {
            FallbackLevel::None
        } else {
            FallbackLevel::ShiftedPlan
        };
        assert_eq!(*l, expected, "step {k}: {levels:?}");
    }
}

/// The fallback levels in order as the budget grows, with a budget counted
/// in deadline checks (no clock): the shifted plan (spent while the QP was
/// built), the best feasible answer after exactly the iterations the
/// budget left, then the optimum; the QP's iterations never exceed its
/// worst-case bound 4·N·n; the torque always within the limits.
#[test]
fn the_fallback_levels_follow_the_budget_in_order() {
    let robot = Robot::irb140();
    let (mut reference, x, w_k, preview) = limited(ControllerKind::Second, &robot, None);
    let input = StepInput {
        x: &x,
        w_k: &w_k,
        preview: &preview,
    };
    // The unbudgeted run: per step, the QP's iterations.
    let steps = 12;
    let mut free_iters = Vec::new();
    for _ in 0..steps {
        free_iters.push(
            reference
                .step(&input)
                .unwrap()
                .qp_status
                .unwrap()
                .iterations,
        );
    }
    let (n, nh) = (reference.dof(), reference.horizon());
    // Checks before the QP iterates: per horizon block and Hessian column of
    // its build, before its factorization, and the one kept back for the
    // step's work after the QP (TAIL_CHECKS).
    let build_checks = (nh + n * nh + 1) as u32 + TAIL_CHECKS;
    assert!(free_iters.iter().all(|&i| i as usize <= 4 * n * nh));
    let tau_max = reference.drives().unwrap().max_torque_nm.clone();
    let mut seen = [false; 4];
    for checks in [
        0,
        nh as u32,
        build_checks,
        build_checks + 1,
        build_checks + 3,
        u32::MAX,
    ] {
        let (mut mpc, ..) = limited(ControllerKind::Second, &robot, Some(1e9));
        mpc.set_check_budget(Some(checks));
        for k in 0..steps {
            let out = mpc.step(&input).unwrap();
            let qp = out.qp_status.unwrap();
            let level = out.telemetry.fallback;
            seen[level.index()] = true;
            for (tau, lim) in out.tau.iter().zip(&tau_max) {
                assert!(tau.abs() <= *lim, "{tau} over {lim}");
            }
            if !qp.active || k > 0 {
                continue;
            }
            // The first step starts from the same state as the reference's.
            let expected = if checks < build_checks - 1 {
                // The build interrupted, no plan to shift: the QP past its budget.
                assert!(qp.budget_hit);
                assert_eq!(qp.iterations, free_iters[0]);
                FallbackLevel::None
            } else if checks - build_checks < free_iters[0] {
                assert_eq!(qp.iterations, checks - build_checks, "{checks}");
                FallbackLevel::BestFeasible
            } else {
                assert_eq!(qp.iterations, free_iters[0]);
                FallbackLevel::None
            };
            assert_eq!(level, expected, "{checks} checks");
        }
    }
    // A plan made with budget to spare, then none left: the plan one
    // sample on, then the QP past its budget (a fresh plan), alternately.
    let (mut mpc, ..) = limited(ControllerKind::Second, &robot, Some(1e9));
    mpc.step(&input).unwrap();
    mpc.set_check_budget(Some(0));
    for k in 1..2 * nh {
        let out = mpc.step(&input).unwrap();
        let level = out.telemetry.fallback;
        seen[level.index()] = true;
        let expected = if k % 2 == 1 {
            FallbackLevel::ShiftedPlan
        } else {
            FallbackLevel::None
        };
        assert_eq!(level, expected, "sample {k}");
        assert!(out.telemetry.budget_hit);
        for (tau, lim) in out.tau.iter().zip(&tau_max) {
            assert!(tau.abs() <= *lim, "{tau} over {lim}");
        }
    }
    // The numerical failure's hold is not a budget level.
    assert!(
        seen[..3].iter().all(|s| *s) && !seen[3],
        "levels seen {seen:?}"
    );
}

/// The work after the QP (the torque, the command, the telemetry) is
/// accounted inside the budget: counted in deadline checks, one check
/// ([`TAIL_CHECKS`]) is kept back from the QP's, so a budget of exactly
/// the build's checks plus `k` runs `k − 1` iterations, never `k`; on the
/// clock, the controller keeps back the longest tail it measured (from the
/// QP's return to the end of its step), at most a quarter of the budget.
#[test]
fn the_work_after_the_qp_is_kept_back_from_the_budget() {
    let robot = Robot::irb140();
    let (probe, ..) = limited(ControllerKind::Second, &robot, None);
    let (n, nh) = (probe.dof(), probe.horizon());
    // The build's checks and the one before the factorization.
    let before_iterating = (nh + n * nh + 1) as u32;
    for k in 1..4u32 {
        let (mut mpc, x, w_k, preview) = limited(ControllerKind::Second, &robot, Some(1e9));
        mpc.set_check_budget(Some(before_iterating + k));
        let out = mpc
            .step(&StepInput {
                x: &x,
                w_k: &w_k,
                preview: &preview,
            })
            .unwrap();
        let qp = out.qp_status.unwrap();
        assert!(qp.active && qp.budget_hit, "{k}: {qp:?}");
        assert_eq!(qp.iterations, k - TAIL_CHECKS, "{k} checks after the build");
        assert_eq!(out.telemetry.fallback, FallbackLevel::BestFeasible);
    }
    // On the clock: no reserve without a budget; with one, a measured tail
    // (positive) kept back, at least a tenth and at most a quarter of the
    // budget.
    let (mut free, x, w_k, preview) = limited(ControllerKind::Second, &robot, None);
    let input = StepInput {
        x: &x,
        w_k: &w_k,
        preview: &preview,
    };
    free.step(&input).unwrap();
    assert_eq!(free.budget_reserve_us(), None);
    for budget in [1e9, 40.0, 0.0] {
        let (mut mpc, ..) = limited(ControllerKind::Second, &robot, Some(budget));
        assert_eq!(
            mpc.budget_reserve_us(),
            Some(0.1 * budget),
            "none measured yet: the floor"
        );
        for _ in 0..5 {
            mpc.step(&input).unwrap();
        }
        let r = mpc.budget_reserve_us().unwrap();
        assert!((0.1 * budget..=0.25 * budget).contains(&r), "{budget}: {r}");
    }
}

/// A budget beyond the clock's range is no deadline (never a panic).
#[test]
fn a_huge_budget_is_no_deadline() {
    let robot = Robot::irb140();
    let (mut mpc, x, w_k, preview) = limited(ControllerKind::Second, &robot, Some(1e300));
    let input = StepInput {
        x: &x,
        w_k: &w_k,
        preview: &preview,
    };
    let out = mpc.step(&input).unwrap();
    assert!(out.qp_status.unwrap().active && !out.telemetry.budget_hit);
}

#[test]
fn a_negative_or_infinite_budget_is_refused() {
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        let s = MpcSettings {
            step_budget_us: Some(bad),
            ..MpcSettings::default()
        };
        assert!(s.validate().is_err(), "{bad}");
    }
}
