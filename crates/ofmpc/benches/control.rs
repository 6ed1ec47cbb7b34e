//! Per-step cost of the three controllers on the IRB 140 model with both
//! least-squares solvers (dense Householder QR of 𝒜, structured square-root
//! Riccati), N = 5 … 200, and the dense least-squares solve alone; the
//! baselines (pid, ctc, ctc-adaptive, dob-mpc) beside them at N = 10.
//!
//! Run: `cargo bench -p ofmpc --bench control`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::{DMatrix, DVector};
use ofmpc::control::lsq_flops;
use ofmpc::control::{
    new_controller, ControllerKind, LinearLikeModel, LsqWorkspace, MpcSettings, Predictions,
    Solver, Zoh,
};
use ofmpc::dynamics::{JointSpaceDynamics, RobotDynamics};
use ofmpc::robot::Robot;
use std::hint::black_box;
use std::time::Duration;

/// One whole step (model terms, f0, ZOH, the least-squares problem and its
/// solve) for every controller, both solvers, N = 5 … 200. Benchmark ids:
/// `step_irb140/<controller>-<solver>/<N>`. `OFMPC_BENCH_KINDS=second`
/// restricts the controllers, `OFMPC_BENCH_MAX_N=100` the horizons, and
/// `OFMPC_BENCH_HORIZONS=15,20,25` replaces them (the solvers' crossover).
fn steps(c: &mut Criterion) {
    let n = 6;
    let mut group = c.benchmark_group("step_irb140");
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(1));
    group.sample_size(20);
    let kinds: Vec<ControllerKind> = match std::env::var("OFMPC_BENCH_KINDS") {
        Ok(list) => list.split(',').filter_map(|k| k.parse().ok()).collect(),
        Err(_) => ControllerKind::PAPER.to_vec(),
    };
    let max_n: usize = std::env::var("OFMPC_BENCH_MAX_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(200);
    let horizons: Vec<usize> = match std::env::var("OFMPC_BENCH_HORIZONS") {
        Ok(list) => list
            .split(',')
            .filter_map(|h| h.trim().parse().ok())
            .collect(),
        Err(_) => vec![5, 10, 20, 50, 100, 200],
    };
    for nh in horizons {
        if nh > max_n {
            continue;
        }
        for solver in [Solver::Structured, Solver::DenseQr] {
            let s = MpcSettings {
                horizon: nh,
                solver,
                ..MpcSettings::default()
            };
            for &kind in &kinds {
                let mut ctrl = new_controller(kind, n, &s).unwrap();
                let mut model = RobotDynamics::new(Robot::irb140());
                // A state on the paper's path (moving), and a reference near it.
                let x = vec![
                    -0.27, 1.45, -0.85, -0.3, -0.7, 0.3, 0.2, -0.1, 0.15, 0.3, -0.2, 0.25,
                ];
                ctrl.reset(&x).unwrap();
                let wk: Vec<f64> = x[..n].iter().map(|q| q + 1e-3).collect();
                let preview: Vec<f64> = (0..nh)
                    .flat_map(|j| x[..n].iter().map(move |q| q + 1e-3 * (j + 2) as f64))
                    .collect();
                let mut tau = vec![0.0; n];
                let id = format!("{}-{}", kind.name(), solver.name());
                group.bench_with_input(BenchmarkId::new(id, nh), &nh, |b, _| {
                    b.iter(|| {
                        ctrl.step(
                            &mut model,
                            &ofmpc::control::StepInput {
                                x: black_box(&x),
                                w_k: &wk,
                                preview: &preview,
                            },
                            &mut tau,
                        )
                        .unwrap();
                        black_box(&tau);
                    })
                });
            }
        }
    }
    group.finish();
}

fn solve(c: &mut Criterion) {
    let n = 6;
    let mut group = c.benchmark_group("lsq_n6");
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(1));
    group.sample_size(20);
    for nh in [10usize, 20] {
        let p = nh * n;
        let m = 3 * p;
        let profile: Vec<usize> = (0..p).map(|col| 3 * n * (col / n + 1)).collect();
        eprintln!(
            "N = {nh}: 𝒜 {m}x{p}, flops dense {:.3} M, profile {:.3} M",
            lsq_flops(p, &vec![m; p]) as f64 / 1e6,
            lsq_flops(p, &profile) as f64 / 1e6
        );
        let mut seed = 1u64;
        let mut rnd = move || ofmpc::random::uniform(&mut seed) - 0.5;
        let a: Vec<f64> = (0..m * p).map(|_| rnd()).collect();
        let b: Vec<f64> = (0..m).map(|_| rnd()).collect();
        // The incremental algorithms' layout after the tracking rows'
        // reduction (control/tracking.rs): 2 row groups per level.
        let m2 = 2 * p;
        let reduced: Vec<usize> = (0..p).map(|col| 2 * n * (col / n + 1)).collect();
        eprintln!(
            "N = {nh}: reduced {m2}x{p}, flops {:.3} M",
            lsq_flops(p, &reduced) as f64 / 1e6
        );
        for (name, rows, prof) in [
            ("dense", m, vec![m; p]),
            ("profile", m, profile),
            ("reduced", m2, reduced),
        ] {
            let mut ws = LsqWorkspace::with_profile(rows, p, prof).unwrap();
            // A random (m2 × p) system: the first rows·p entries as a matrix.
            let a = &a[..rows * p];
            let b = &b[..rows];
            group.bench_function(BenchmarkId::new(name, nh), |bch| {
                bch.iter(|| {
                    ws.matrix_mut().copy_from_slice(a);
                    ws.rhs_mut().copy_from_slice(b);
                    black_box(ws.solve().unwrap());
                })
            });
        }
    }
    group.finish();
}

fn parts(c: &mut Criterion) {
    let n = 6;
    let nh = 10;
    let mut group = c.benchmark_group("parts_irb140_N10");
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(1));
    group.sample_size(20);
    let mut model = RobotDynamics::new(Robot::irb140());
    let x = vec![
        -0.27, 1.45, -0.85, -0.3, -0.7, 0.3, 0.2, -0.1, 0.15, 0.3, -0.2, 0.25,
    ];
    let (mut h, mut cc, mut g) = (
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
        DVector::zeros(n),
    );
    group.bench_function("model_terms", |b| {
        b.iter(|| model.terms(black_box(&x[..n]), &x[n..], &mut h, &mut cc, &mut g))
    });
    let mut lin = LinearLikeModel::new(n);
    group.bench_function("terms_and_f0", |b| {
        b.iter(|| lin.update(&mut model, black_box(&x[..n]), &x[n..]).unwrap())
    });
    let mut zoh = Zoh::new(n);
    group.bench_function("zoh", |b| {
        b.iter(|| zoh.discretize(black_box(lin.f0()), 0.01).unwrap())
    });
    eprintln!("ZOH squarings: {}", zoh.squarings());
    let mut pred = Predictions::new(2 * n, n, n, nh);
    group.bench_function("predictions", |b| {
        b.iter(|| pred.update_from_zoh(black_box(&zoh)).unwrap())
    });
    group.finish();
}

/// One step with the torque-limit QP active (#11): limits at 90 % of the
/// unconstrained step's torques (+0.1 N·m), so that the QP runs on every
/// iteration (the controller is reset each time: identical steps), against
/// the same step without limits. Ids `step_limits_irb140/<kind>-{qp,free}`.
/// The IRB 140's drives with peak torques 10 % (+ 0.1 N·m) below the unconstrained step's
/// torques `tau`, so that the torque limits bind.
fn binding_limits(tau: &[f64]) -> ofmpc::control::DriveModel {
    let mut drives = ofmpc::control::DriveModel::from_robot(&Robot::irb140());
    for (l, t) in drives.max_torque_nm.iter_mut().zip(tau) {
        *l = 0.9 * t.abs() + 0.1;
    }
    drives
}

fn limits(c: &mut Criterion) {
    let n = 6;
    let mut group = c.benchmark_group("step_limits_irb140");
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(1));
    group.sample_size(20);
    let x = vec![
        -0.27, 1.45, -0.85, -0.3, -0.7, 0.3, 0.2, -0.1, 0.15, 0.3, -0.2, 0.25,
    ];
    let nh = 10;
    let wk: Vec<f64> = x[..n].iter().map(|q| q + 1e-3).collect();
    let preview: Vec<f64> = (0..nh)
        .flat_map(|j| x[..n].iter().map(move |q| q + 1e-3 * (j + 2) as f64))
        .collect();
    for kind in [
        ControllerKind::Usual,
        ControllerKind::First,
        ControllerKind::Second,
    ] {
        let mut model = RobotDynamics::new(Robot::irb140());
        let free_settings = MpcSettings {
            solver: Solver::DenseQr,
            ..MpcSettings::default()
        };
        let mut free = new_controller(kind, n, &free_settings).unwrap();
        let mut tau = vec![0.0; n];
        free.reset(&x).unwrap();
        free.step(
            &mut model,
            &ofmpc::control::StepInput {
                x: &x,
                w_k: &wk,
                preview: &preview,
            },
            &mut tau,
        )
        .unwrap();
        let drives = binding_limits(&tau);
        let s = MpcSettings {
            torque_limits: true,
            ..MpcSettings::default()
        };
        let mut ctrl = new_controller(kind, n, &s).unwrap();
        ctrl.set_drive_model(&drives).unwrap();
        ctrl.reset(&x).unwrap();
        ctrl.step(
            &mut model,
            &ofmpc::control::StepInput {
                x: &x,
                w_k: &wk,
                preview: &preview,
            },
            &mut tau,
        )
        .unwrap();
        assert!(
            ctrl.qp_status().is_some_and(|q| q.active),
            "{kind}: QP not active"
        );
        group.bench_function(format!("{}-qp", kind.name()), |b| {
            b.iter(|| {
                ctrl.reset(&x).unwrap();
                ctrl.step(
                    &mut model,
                    &ofmpc::control::StepInput {
                        x: black_box(&x),
                        w_k: &wk,
                        preview: &preview,
                    },
                    &mut tau,
                )
                .unwrap();
                black_box(&tau);
            })
        });
        group.bench_function(format!("{}-free", kind.name()), |b| {
            b.iter(|| {
                free.reset(&x).unwrap();
                free.step(
                    &mut model,
                    &ofmpc::control::StepInput {
                        x: black_box(&x),
                        w_k: &wk,
                        preview: &preview,
                    },
                    &mut tau,
                )
                .unwrap();
                black_box(&tau);
            })
        });
    }
    group.finish();
}

/// One step of each baseline beside the paper's controllers and the
/// adaptive second algorithm, N = 10 (the paper's tuning), same state and
/// reference as `step_irb140`. Ids: `step_baselines/<controller>`. Run:
/// `cargo bench -p ofmpc --bench control -- step_baselines`.
fn baselines(c: &mut Criterion) {
    let n = 6;
    let nh = 10;
    let mut group = c.benchmark_group("step_baselines");
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(1));
    group.sample_size(20);
    let s = MpcSettings::default();
    let kinds = ControllerKind::PAPER
        .into_iter()
        .chain([ControllerKind::SecondAdaptive])
        .chain(ControllerKind::BASELINES);
    for kind in kinds {
        let mut ctrl = new_controller(kind, n, &s).unwrap();
        let mut model = RobotDynamics::new(Robot::irb140());
        let x = vec![
            -0.27, 1.45, -0.85, -0.3, -0.7, 0.3, 0.2, -0.1, 0.15, 0.3, -0.2, 0.25,
        ];
        ctrl.reset(&x).unwrap();
        let wk: Vec<f64> = x[..n].iter().map(|q| q + 1e-3).collect();
        let preview: Vec<f64> = (0..nh)
            .flat_map(|j| x[..n].iter().map(move |q| q + 1e-3 * (j + 2) as f64))
            .collect();
        let mut tau = vec![0.0; n];
        group.bench_function(kind.name(), |b| {
            b.iter(|| {
                ctrl.step(
                    &mut model,
                    &ofmpc::control::StepInput {
                        x: black_box(&x),
                        w_k: &wk,
                        preview: &preview,
                    },
                    &mut tau,
                )
                .unwrap();
                black_box(&tau);
            })
        });
    }
    group.finish();
}

criterion_group!(benches, steps, solve, parts, limits, baselines);
criterion_main!(benches);
