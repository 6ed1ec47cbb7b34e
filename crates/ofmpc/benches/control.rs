//! Per-step cost of the three controllers (model terms, f0, ZOH, predictions,
//! building 𝒜 and b, QR solve) with a 6-joint test model, N = 5 … 100, and
//! the least-squares solve alone.
//!
//! Run: `cargo bench -p ofmpc --bench control`.

#[path = "../tests/common/mod.rs"]
mod common;

use common::CoupledModel;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::{DMatrix, DVector};
use ofmpc::control::lsq::lsq_flops;
use ofmpc::control::{
    new_controller, ControllerKind, LinearLikeModel, LsqWorkspace, MpcSettings, Predictions, Zoh,
};
use ofmpc::dynamics::JointSpaceDynamics;
use std::hint::black_box;
use std::time::Duration;

fn steps(c: &mut Criterion) {
    let n = 6;
    let mut group = c.benchmark_group("step_n6");
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(1));
    group.sample_size(20);
    for nh in [5usize, 10, 20, 50, 100] {
        let s = MpcSettings {
            horizon: nh,
            ..MpcSettings::default()
        };
        for kind in ControllerKind::ALL {
            let mut ctrl = new_controller(kind, n, &s).unwrap();
            let mut model = CoupledModel::new(n, 1);
            let x: Vec<f64> = (0..2 * n).map(|i| 0.1 * i as f64 - 0.3).collect();
            ctrl.reset(&x).unwrap();
            let wk = vec![0.2; n];
            let preview = vec![0.2; n * nh];
            let mut tau = vec![0.0; n];
            group.bench_with_input(BenchmarkId::new(kind.name(), nh), &nh, |b, _| {
                b.iter(|| {
                    ctrl.step(&mut model, black_box(&x), &wk, &preview, &mut tau)
                        .unwrap();
                    black_box(&tau);
                })
            });
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
        let mut rnd = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let a: Vec<f64> = (0..m * p).map(|_| rnd()).collect();
        let b: Vec<f64> = (0..m).map(|_| rnd()).collect();
        for (name, prof) in [("dense", vec![m; p]), ("profile", profile)] {
            let mut ws = LsqWorkspace::with_profile(m, p, prof).unwrap();
            group.bench_function(BenchmarkId::new(name, nh), |bch| {
                bch.iter(|| {
                    ws.matrix_mut().copy_from_slice(&a);
                    ws.rhs_mut().copy_from_slice(&b);
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
    let mut group = c.benchmark_group("parts_n6_N10");
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(1));
    group.sample_size(20);
    let mut model = CoupledModel::new(n, 1);
    let x: Vec<f64> = (0..2 * n).map(|i| 0.1 * i as f64 - 0.3).collect();
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

criterion_group!(benches, steps, solve, parts);
criterion_main!(benches);
