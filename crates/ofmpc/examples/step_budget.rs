//! The step budget (`[mpc] step_budget_us`) measured on the saturation example
//! (`examples/drives-saturation.toml`: joint 1 limited to 26 N·m, limits in the
//! plant and in the controllers, constraint horizon 5, N = 10, 0.25 kg).
//!
//! For each algorithm it measures the QP's cost per iteration (the median step
//! time with the QP stopped after 2 and after 22 iterations, by a budget counted
//! in deadline checks), then runs the path with the budget: the largest step, the steps over
//! `budget + one iteration`, the fallback levels, the largest commanded torque
//! over its limit (≤ 1: never exceeded) and how the run ended.
//!
//! ```sh
//! cargo run --release -p ofmpc --example step_budget            # 50 µs
//! cargo run --release -p ofmpc --example step_budget -- 5       # 5 µs: the fallbacks
//! ```
//!
//! Wall-clock numbers: on a loaded machine the operating system's preemptions
//! show as steps over the bound whatever the budget; measure on an idle one.

#[path = "common/realtime.rs"]
mod realtime;

use ofmpc::control::{ControllerBuilder, ControllerKind, MpcSettings, StepInput};
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::motion::{plan, PlanOptions};
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{quantile, Experiment, PlantSettings, RunMetrics, RunResult};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let budget: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(50.0);
    let mut robot = Robot::irb140();
    robot.apply_drives(&Drives::from_toml_str(
        "[joints.joint_1]\nmax_torque_nm = 26.0\n",
    )?)?;
    let reference = plan(PAPER_TABLE1, &robot, &PlanOptions::default())?.reference;
    let experiment = |budget_us: Option<f64>| Experiment {
        conditions: Default::default(),
        robot: robot.clone(),
        reference: reference.clone(),
        mpc: MpcSettings {
            torque_limits: true,
            constraint_horizon: Some(5),
            step_budget_us: budget_us,
            ..MpcSettings::default()
        },
        plant: PlantSettings {
            torque_limits: true,
            ..PlantSettings::default()
        },
        loop_settings: Default::default(),
        baselines: Default::default(),
    };
    let payload = Payload::point_mass(0.25);
    println!("step budget {budget} µs, N = 10, the QP's worst case 4·N·n = 240 iterations");
    // Pinned, memory locked and SCHED_FIFO when the process may, as a
    // deployed loop is (`realtime_loop`'s requests; OFMPC_RT=0: none): the
    // torque-limit QP's buffers are first written at the first constrained
    // step, and a page faulted in there would show as a slow step.
    for line in realtime::request() {
        println!("real-time: {line}");
    }
    for kind in [
        ControllerKind::Usual,
        ControllerKind::First,
        ControllerKind::Second,
    ] {
        let (first_us, later_us) = iteration_cost(kind, &robot)?;
        let iteration_us = first_us.max(later_us);
        println!("{kind:7} QP: first iteration (factorization) {first_us:.2} µs, later ones {later_us:.2} µs");
        let (r, m) = experiment(Some(budget)).run(kind, &payload, &mut |_, _| {})?;
        report(kind, budget, iteration_us, &r, &m);
    }
    Ok(())
}

/// The QP's cost of its first iteration (with the factorization of its free
/// block) and of a later one (µs), measured on one constrained step of
/// `kind` (at rest, the target far: the limits bind): the median time of
/// the step with the QP stopped (a budget counted in deadline checks) after
/// no, 1, 2 and 22 iterations, repeated from the same state.
fn iteration_cost(
    kind: ControllerKind,
    robot: &Robot,
) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    let settings = MpcSettings {
        torque_limits: true,
        step_budget_us: Some(1e9),
        ..MpcSettings::default()
    };
    let mut mpc = ControllerBuilder::new(kind, robot)
        .settings(settings)
        .build()?;
    let (n, nh) = (mpc.dof(), mpc.horizon());
    let x = vec![0.0; 2 * n];
    let (w_k, preview) = (vec![1.5; n], vec![1.5; n * nh]);
    let input = StepInput {
        x: &x,
        w_k: &w_k,
        preview: &preview,
    };
    // The build's checks, the one before the factorization and the one
    // kept back for the work after the QP.
    let build_checks = (nh + n * nh + 2) as u32;
    let mut median_us = |iterations: i64| -> Result<(f64, u32), Box<dyn std::error::Error>> {
        mpc.set_check_budget(Some((i64::from(build_checks) + iterations) as u32));
        let mut times = Vec::with_capacity(400);
        let mut done = 0;
        for _ in 0..400 {
            mpc.reset(&x)?;
            let t0 = Instant::now();
            let out = mpc.step(&input)?;
            times.push(t0.elapsed().as_secs_f64() * 1e6);
            done = out.qp_status.map_or(0, |q| q.iterations);
        }
        Ok((quantile(&times, 0.5), done))
    };
    // The first iteration with the factorization of the free block (the
    // costliest), then the following ones (factor updates).
    let (before, _) = median_us(-1)?;
    let (first, _) = median_us(1)?;
    let (t0, i0) = median_us(2)?;
    let (t1, i1) = median_us(22)?;
    let later = (t1 - t0) / f64::from(i1.saturating_sub(i0).max(1));
    Ok((first - before, later))
}

fn report(kind: ControllerKind, budget: f64, iteration_us: f64, r: &RunResult, m: &RunMetrics) {
    let steps = &r.record.telemetry.controller_us;
    let bound = budget + iteration_us;
    let over = steps.iter().filter(|s| **s > bound).count();
    let t = &m.telemetry;
    if std::env::var_os("STEP_BUDGET_DEBUG").is_some() {
        let lt = &r.record.telemetry;
        for (k, s) in steps.iter().enumerate().filter(|(_, s)| **s > bound) {
            eprintln!(
                "  k {k} step {s:.1} µs qp {} model {:.1} µs",
                lt.qp_iterations[k], lt.model_us[k]
            );
        }
    }
    println!(
        "{kind:7} QP iteration {iteration_us:5.2} µs | step p50 {:6.1} p99 {:6.1} p99.9 {:6.1} max {:7.1} µs | over {bound:.1} µs: {over}/{} | fallbacks none {} best {} shifted {} hold {} (budget hits {}) | max |τ|/τmax {:.4} | {:?}",
        quantile(steps, 0.5),
        quantile(steps, 0.99),
        quantile(steps, 0.999),
        steps.iter().copied().fold(0.0, f64::max),
        steps.len(),
        t.fallback_steps.none,
        t.fallback_steps.best_feasible,
        t.fallback_steps.shifted_plan,
        t.fallback_steps.hold,
        t.budget_hits,
        m.max_torque_ratio,
        m.status,
    );
}
