//! The structured solver (square-root Riccati, `solver = "structured"`)
//! against the dense Householder QR of the paper's stacked system
//! (`solver = "dense-qr"`, the reference): the same whole `ΔU`, the same
//! `J_min` and `|R_ii|` ratio, on random states of the IRB 140, at a tiny
//! input weight, and in lockstep along the whole paper path.

mod common;

use common::{CoupledModel, Rng};
use ofmpc::control::{
    new_controller, Algorithm, ControllerKind, MpcSettings, Solver, StepFailure, StepInfo, Weight,
};
use ofmpc::dynamics::{JointSpaceDynamics, RobotDynamics};
use ofmpc::gcode::{parse, ParseOptions, PAPER_TABLE1};
use ofmpc::motion::{build_reference, Orientation};
use ofmpc::motion::{CartesianTrajectory, TimingOptions};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{run_closed_loop, LoopSettings, Plant, PlantSettings};

/// `‖a − b‖₂ / ‖b‖₂`.
fn rel(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    let nb: f64 = b.iter().map(|y| y * y).sum();
    (d / nb).sqrt()
}

fn pair(kind: ControllerKind, n: usize, s: &MpcSettings) -> [Box<dyn Algorithm + Send>; 2] {
    let dense = MpcSettings {
        solver: Solver::DenseQr,
        ..s.clone()
    };
    let structured = MpcSettings {
        solver: Solver::Structured,
        ..s.clone()
    };
    [
        new_controller(kind, n, &dense).unwrap(),
        new_controller(kind, n, &structured).unwrap(),
    ]
}

/// Runs both solvers through the same sequence of random states (so that
/// `Δx`, `u_{k−1}` and `ē` are non-trivial) and returns the worst relative
/// differences of (ΔU, J_min, R-diagonal ratio, τ) and the largest
/// `max|R_ii|/min|R_ii|` (a lower bound of the condition number) seen.
fn compare_random(
    kind: ControllerKind,
    model: &mut dyn JointSpaceDynamics,
    s: &MpcSettings,
    q_center: &[f64],
    rng: &mut Rng,
    steps: usize,
) -> ([f64; 4], f64) {
    let n = model.dof();
    let nh = s.horizon;
    let mut ctrls = pair(kind, n, s);
    let x0: Vec<f64> = (0..2 * n)
        .map(|i| {
            if i < n {
                q_center[i] + 0.3 * rng.next()
            } else {
                0.5 * rng.next()
            }
        })
        .collect();
    for c in &mut ctrls {
        c.reset(&x0).unwrap();
    }
    let mut worst = [0.0f64; 4];
    let mut kappa = 0.0f64;
    for _ in 0..steps {
        let x: Vec<f64> = x0
            .iter()
            .enumerate()
            .map(|(i, v)| v + if i < n { 0.05 } else { 0.5 } * rng.next())
            .collect();
        let wk: Vec<f64> = (0..n).map(|i| x[i] + 0.02 * rng.next()).collect();
        let preview: Vec<f64> = (0..nh * n)
            .map(|i| wk[i % n] + 0.01 * (i / n + 1) as f64 * rng.next())
            .collect();
        let mut taus = [vec![0.0; n], vec![0.0; n]];
        let mut infos = [None, None];
        for ((c, tau), info) in ctrls.iter_mut().zip(&mut taus).zip(&mut infos) {
            *info = Some(
                c.step(
                    model,
                    &ofmpc::control::StepInput {
                        x: &x,
                        w_k: &wk,
                        preview: &preview,
                    },
                    tau,
                )
                .unwrap(),
            );
        }
        let (d, st) = (infos[0].unwrap(), infos[1].unwrap());
        let du = rel(ctrls[1].increments(), ctrls[0].increments());
        assert!(ctrls[0].increments().iter().any(|v| *v != 0.0));
        let cost = (st.cost - d.cost).abs() / d.cost;
        let ratio = (st.r_diag_ratio - d.r_diag_ratio).abs() / d.r_diag_ratio;
        let tau = rel(&taus[1], &taus[0]);
        kappa = kappa.max(d.r_diag_ratio);
        for (w, v) in worst.iter_mut().zip([du, cost, ratio, tau]) {
            *w = w.max(v);
        }
    }
    (worst, kappa)
}

#[test]
fn structured_equals_dense_qr_on_random_irb140_states() {
    let mut model = RobotDynamics::new(Robot::irb140());
    let center = [-0.27, 1.0, -0.5, -0.3, -0.7, 0.3];
    let mut rng = Rng(11);
    for kind in ControllerKind::PAPER {
        for nh in [1usize, 2, 5, 10, 30] {
            for (q_du, q_u) in [(1e-5, 1e-4), (1e-3, 1e-2)] {
                let s = MpcSettings {
                    horizon: nh,
                    q_du: Weight::Scalar(q_du),
                    q_u: Weight::Scalar(q_u),
                    ..MpcSettings::default()
                };
                let (w, _) = compare_random(kind, &mut model, &s, &center, &mut rng, 6);
                assert!(
                    w[0] <= 1e-9 && w[3] <= 1e-9,
                    "{kind} N = {nh} q_du = {q_du}: rel. diff ΔU {:e}, τ {:e}",
                    w[0],
                    w[3]
                );
                assert!(
                    w[1] <= 1e-8 && w[2] <= 1e-8,
                    "{kind} N = {nh}: rel. diff J_min {:e}, R ratio {:e}",
                    w[1],
                    w[2]
                );
            }
        }
    }
}

/// Per-joint diagonal weights (some zero) and a different robot: the stage
/// cost's diagonal `D` and input weights are placed per joint.
#[test]
fn structured_equals_dense_qr_with_diagonal_weights() {
    let n = 4;
    let mut model = CoupledModel::new(n, 3);
    let mut rng = Rng(5);
    for kind in ControllerKind::PAPER {
        let s = MpcSettings {
            horizon: 7,
            ts: 0.02,
            q_yw: Weight::Diagonal(vec![1.0, 2.0, 0.0, 0.7]),
            q_dy: Weight::Diagonal(vec![0.5, 0.0, 0.9, 0.1]),
            q_du: Weight::Diagonal(vec![1e-3, 3e-4, 1e-2, 1e-3]),
            q_u: Weight::Diagonal(vec![1e-2, 3e-3, 1e-2, 5e-2]),
            ..MpcSettings::default()
        };
        let (w, _) = compare_random(kind, &mut model, &s, &[0.1, -0.2, 0.3, 0.0], &mut rng, 5);
        assert!(w[0] <= 1e-9 && w[3] <= 1e-9, "{kind}: {w:?}");
        assert!(w[1] <= 1e-8 && w[2] <= 1e-8, "{kind}: {w:?}");
    }
}

/// Random states for the single-step comparisons: `(x_{k−1}, x_k, w_k, preview)`.
fn random_sample(
    n: usize,
    nh: usize,
    center: &[f64],
    rng: &mut Rng,
) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let x_prev: Vec<f64> = (0..2 * n)
        .map(|i| if i < n { center[i] } else { 0.0 } + 0.3 * rng.next())
        .collect();
    let x: Vec<f64> = x_prev.iter().map(|v| v + 0.01 * rng.next()).collect();
    let wk: Vec<f64> = (0..n).map(|i| x[i] + 0.02 * rng.next()).collect();
    let preview: Vec<f64> = (0..nh * n)
        .map(|i| wk[i % n] + 0.01 * (i / n + 1) as f64 * rng.next())
        .collect();
    (x_prev, x, wk, preview)
}

/// One step of both solvers from `reset(x_prev)`: their whole ΔU.
fn one_step_pair(
    kind: ControllerKind,
    model: &mut dyn JointSpaceDynamics,
    s: &MpcSettings,
    (x_prev, x, wk, preview): (&[f64], &[f64], &[f64], &[f64]),
) -> [Vec<f64>; 2] {
    let n = model.dof();
    let mut out = [Vec::new(), Vec::new()];
    for (c, o) in pair(kind, n, s).iter_mut().zip(&mut out) {
        c.reset(x_prev).unwrap();
        let mut tau = vec![0.0; n];
        c.step(
            model,
            &ofmpc::control::StepInput {
                x,
                w_k: wk,
                preview,
            },
            &mut tau,
        )
        .unwrap();
        *o = c.increments().to_vec();
    }
    out
}

/// At `q_du = 1e-8` (`q_u = 1e-8`) the system is badly conditioned: a method
/// that squares the condition number (normal equations, a Riccati recursion
/// on `P`) would lose about twice as many digits. The square-root recursion
/// agrees with the dense QR to 1e-9 up to N = 20 and to 1e-8 at N = 50 (the
/// dense right-hand side of the second algorithm cancels terms of size
/// `j·y_k`, see the next test).
#[test]
fn structured_equals_dense_qr_at_tiny_input_weight() {
    let n = 6;
    let mut model = RobotDynamics::new(Robot::irb140());
    let center = [0.2, 0.6, -0.3, 0.4, 0.9, -0.2];
    let mut rng = Rng(23);
    for kind in ControllerKind::PAPER {
        for nh in [10usize, 20, 50] {
            let s = MpcSettings {
                horizon: nh,
                q_du: Weight::Scalar(1e-8),
                q_u: Weight::Scalar(1e-8),
                ..MpcSettings::default()
            };
            let mut worst = 0.0f64;
            for _ in 0..4 {
                let (xp, x, w, p) = random_sample(n, nh, &center, &mut rng);
                let [d, st] = one_step_pair(kind, &mut model, &s, (&xp, &x, &w, &p));
                worst = worst.max(rel(&st, &d));
            }
            eprintln!("{kind} N = {nh} q_du = 1e-8: rel. diff ΔU {worst:.1e}");
            let tol = if nh <= 20 { 1e-9 } else { 1e-8 };
            assert!(worst <= tol, "{kind} N = {nh}: rel. diff ΔU {worst:e}");
        }
    }
}

/// The IRB 140's dynamics do not depend on the base joint angle `q1`, so
/// adding a constant to `q1` in the state, the reference and the preview
/// leaves the control problem unchanged. The structured solver works in
/// deviations from the measured output and its ΔU does not move (≤ 1e-13);
/// the dense system's right-hand side (`W − F_I y_k`, `W + W_s − j·y_k`)
/// cancels larger numbers and moves by more: the structured solver is the
/// more accurate of the two where they differ (`q_du = 1e-8`, N = 50).
#[test]
fn structured_solution_is_invariant_to_a_base_joint_offset() {
    let n = 6;
    let nh = 50;
    let mut model = RobotDynamics::new(Robot::irb140());
    let mut rng = Rng(29);
    let s = MpcSettings {
        horizon: nh,
        q_du: Weight::Scalar(1e-8),
        q_u: Weight::Scalar(1e-8),
        ..MpcSettings::default()
    };
    for kind in ControllerKind::PAPER {
        let (xp, x, w, p) = random_sample(n, nh, &[0.2, 0.6, -0.3, 0.4, 0.9, -0.2], &mut rng);
        let base = one_step_pair(kind, &mut model, &s, (&xp, &x, &w, &p));
        let (mut moved_dense, mut moved_structured) = (0.0f64, 0.0f64);
        for shift in [1.0, 3.0, -3.0] {
            let sh = |v: &[f64], stride: usize| -> Vec<f64> {
                v.iter()
                    .enumerate()
                    .map(|(i, a)| if i % stride == 0 { a + shift } else { *a })
                    .collect()
            };
            let [d, st] = one_step_pair(
                kind,
                &mut model,
                &s,
                (&sh(&xp, 2 * n), &sh(&x, 2 * n), &sh(&w, n), &sh(&p, n)),
            );
            moved_dense = moved_dense.max(rel(&d, &base[0]));
            moved_structured = moved_structured.max(rel(&st, &base[1]));
        }
        eprintln!(
            "{kind}: q1 offset moves ΔU by {moved_structured:.1e} (structured), {moved_dense:.1e} (dense)"
        );
        assert!(moved_structured <= 1e-13, "{kind}: {moved_structured:e}");
        assert!(moved_structured <= moved_dense, "{kind}");
    }
}

/// Runs the dense controller in closed loop and the structured one beside it
/// on the same measurements, recording the worst relative difference of ΔU.
struct Lockstep {
    dense: Box<dyn Algorithm + Send>,
    structured: Box<dyn Algorithm + Send>,
    tau2: Vec<f64>,
    /// Per step: `‖ΔU_dense‖` and `‖ΔU_structured − ΔU_dense‖`.
    norms: Vec<(f64, f64)>,
    steps: usize,
}

impl Algorithm for Lockstep {
    fn kind(&self) -> ControllerKind {
        self.dense.kind()
    }
    fn dof(&self) -> usize {
        self.dense.dof()
    }
    fn horizon(&self) -> usize {
        self.dense.horizon()
    }
    fn settings(&self) -> &MpcSettings {
        self.dense.settings()
    }
    fn reset(&mut self, x0: &[f64]) -> Result<(), StepFailure> {
        self.structured.reset(x0)?;
        self.dense.reset(x0)
    }
    fn input(&self) -> &[f64] {
        self.dense.input()
    }
    fn increments(&self) -> &[f64] {
        self.dense.increments()
    }
    fn step(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        input: &ofmpc::control::StepInput<'_>,
        tau: &mut [f64],
    ) -> Result<StepInfo, StepFailure> {
        let (x, w_k, preview) = (input.x, input.w_k, input.preview);
        let info = self
            .dense
            .step(model, &ofmpc::control::StepInput { x, w_k, preview }, tau)?;
        self.structured
            .step(
                model,
                &ofmpc::control::StepInput { x, w_k, preview },
                &mut self.tau2,
            )
            .expect("the structured solver fails where the dense one succeeds");
        let (a, b) = (self.structured.increments(), self.dense.increments());
        let nb = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        self.norms.push((nb, rel(a, b) * nb));
        self.steps += 1;
        Ok(info)
    }
}

#[test]
fn structured_equals_dense_qr_along_the_paper_path() {
    let robot = Robot::irb140();
    let program = parse(PAPER_TABLE1, &ParseOptions::default()).unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let s = MpcSettings::default();
    let reference = build_reference(&robot, &traj, Orientation::AtZero, s.ts).unwrap();
    for kind in ControllerKind::PAPER {
        let [dense, structured] = pair(kind, 6, &s);
        let mut lock = Lockstep {
            dense,
            structured,
            tau2: vec![0.0; 6],
            norms: Vec::new(),
            steps: 0,
        };
        let mut plant_robot = robot.clone();
        plant_robot
            .set_payload(Some(Payload::point_mass(0.25)))
            .unwrap();
        let mut plant = Plant::with_period(
            plant_robot,
            PlantSettings::default(),
            reference.q(0),
            reference.ts(),
        )
        .unwrap();
        let mut model = RobotDynamics::new(robot.clone());
        let result = run_closed_loop(
            &mut lock,
            &mut model,
            &mut plant,
            &reference,
            &LoopSettings {
                hold_s: 0.5,
                ..LoopSettings::default()
            },
            &mut |_, _| {},
        );
        assert!(result.outcome.is_completed(), "{kind}: {}", result.outcome);
        assert_eq!(lock.steps, result.record.len());
        assert!(lock.steps > 300, "{kind}: only {} steps", lock.steps);
        // Relative difference at every step whose ΔU is not round-off: in
        // the hold at the end ΔU is ~1e-11 (the tracking error is zero), a
        // relative difference of two noises means nothing; there the
        // absolute difference is compared with the path's typical ΔU.
        let scale = lock.norms.iter().map(|p| p.0).fold(0.0, f64::max);
        let mut worst_rel = 0.0f64;
        let mut worst_abs = 0.0f64;
        let mut compared = 0;
        for &(nb, diff) in &lock.norms {
            worst_abs = worst_abs.max(diff / scale);
            if nb >= 1e-4 * scale {
                worst_rel = worst_rel.max(diff / nb);
                compared += 1;
            }
        }
        eprintln!(
            "{kind}: {compared} of {} steps compared, worst rel. diff {worst_rel:.1e}, worst abs. diff / max‖ΔU‖ {worst_abs:.1e}",
            lock.steps
        );
        assert!(compared > lock.steps / 2);
        assert!(
            worst_rel <= 1e-9,
            "{kind}: worst rel. diff of ΔU along the path {worst_rel:e}"
        );
        assert!(
            worst_abs <= 1e-11,
            "{kind}: worst abs. diff of ΔU along the path {worst_abs:e} of max‖ΔU‖"
        );
    }
}

/// `solver = "auto"` (the default) is the dense QR below the controller's
/// crossover (`structured_from_horizon`) and the structured solver from there
/// on: its ΔU is bit for bit the one of the solver it stands for.
#[test]
fn auto_solver_is_dense_for_short_and_structured_for_long_horizons() {
    use ofmpc::control::{structured_from_horizon, STRUCTURED_FROM_HORIZON};
    assert_eq!(MpcSettings::default().solver, Solver::Auto);
    let n = 6;
    let mut model = RobotDynamics::new(Robot::irb140());
    let mut rng = Rng(37);
    for kind in [
        ControllerKind::Usual,
        ControllerKind::First,
        ControllerKind::Second,
    ] {
        let from = structured_from_horizon(kind);
        assert!(from <= STRUCTURED_FROM_HORIZON);
        for (nh, expected) in [
            (10, Solver::DenseQr),
            (from - 1, Solver::DenseQr),
            (from, Solver::Structured),
            (60, Solver::Structured),
        ] {
            assert_eq!(Solver::Auto.for_controller(kind, nh), expected);
            let (xp, x, w, p) = random_sample(n, nh, &[0.1, 0.8, -0.4, 0.2, 0.5, 0.1], &mut rng);
            let mut out = Vec::new();
            for solver in [Solver::Auto, expected] {
                let s = MpcSettings {
                    horizon: nh,
                    solver,
                    ..MpcSettings::default()
                };
                let mut c = new_controller(kind, n, &s).unwrap();
                c.reset(&xp).unwrap();
                let mut tau = vec![0.0; n];
                c.step(
                    &mut model,
                    &ofmpc::control::StepInput {
                        x: &x,
                        w_k: &w,
                        preview: &p,
                    },
                    &mut tau,
                )
                .unwrap();
                out.push(c.increments().to_vec());
            }
            assert_eq!(out[0], out[1], "{kind} N = {nh}");
        }
    }
    assert_eq!(
        Solver::Auto.for_horizon(STRUCTURED_FROM_HORIZON - 1),
        Solver::DenseQr
    );
    assert_eq!(
        Solver::Auto.for_horizon(STRUCTURED_FROM_HORIZON),
        Solver::Structured
    );
}
