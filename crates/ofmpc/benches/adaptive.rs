//! Per-step cost of online payload identification: the second algorithm
//! against its adaptive variant (estimator update + model update + the same
//! step) on the IRB 140 at N = 10, and the estimator update alone.
//!
//! Run: `cargo bench -p ofmpc --bench adaptive`.

use criterion::{criterion_group, criterion_main, Criterion};
use ofmpc::control::{new_controller, ControllerKind, MpcSettings};
use ofmpc::dynamics::RobotDynamics;
use ofmpc::ident::{PayloadEstimator, PayloadParams, RlsSettings};
use ofmpc::robot::Robot;
use std::hint::black_box;
use std::time::Duration;

fn steps(c: &mut Criterion) {
    let n = 6;
    let s = MpcSettings::default();
    let mut group = c.benchmark_group("adaptive_irb140_n10");
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(1));
    group.sample_size(20);
    let x = vec![
        -0.27, 1.45, -0.85, -0.3, -0.7, 0.3, 0.2, -0.1, 0.15, 0.3, -0.2, 0.25,
    ];
    let wk: Vec<f64> = x[..n].iter().map(|q| q + 1e-3).collect();
    let preview: Vec<f64> = (0..s.horizon)
        .flat_map(|j| x[..n].iter().map(move |q| q + 1e-3 * (j + 2) as f64))
        .collect();
    for kind in [ControllerKind::Second, ControllerKind::SecondAdaptive] {
        let mut ctrl = new_controller(kind, n, &s).unwrap();
        let mut model = RobotDynamics::new(Robot::irb140());
        ctrl.reset(&x).unwrap();
        let mut tau = vec![0.0; n];
        // One step first, so that the adaptive variant has a previous sample.
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
    let mut est = PayloadEstimator::new(n, RlsSettings::default(), PayloadParams::zeros()).unwrap();
    let mut model = RobotDynamics::new(Robot::irb140());
    let x1: Vec<f64> = x.iter().map(|v| v + 1e-3).collect();
    let tau = vec![1.0; n];
    group.bench_function("estimator_update", |b| {
        b.iter(|| black_box(est.update(&mut model, black_box(&x), &x1, &tau, 0.01)))
    });
    group.finish();
}

criterion_group!(benches, steps);
criterion_main!(benches);
