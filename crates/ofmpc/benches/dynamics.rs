//! Rigid-body algorithms on the IRB 140: `cargo bench --bench dynamics`.

use criterion::measurement::WallTime;
use criterion::{black_box, criterion_group, criterion_main, BenchmarkGroup, Criterion};
use ofmpc::dynamics::*;
use ofmpc::robot::Robot;

fn bench(c: &mut Criterion) {
    let robot = Robot::irb140();
    let mut ws = Workspace::new(&robot);
    let q = [0.1, 0.4, -0.3, 0.7, 0.5, -0.2];
    let qd = [0.3, -0.2, 0.4, 0.5, -0.6, 0.7];
    let qdd = [1.0, -0.5, 0.3, 2.0, -1.0, 0.5];
    let tau = [10.0, 50.0, 20.0, 1.0, 2.0, 0.5];
    let mut g = c.benchmark_group("irb140");
    g.bench_function("forward_kinematics", |b| {
        b.iter(|| forward_kinematics(&robot, &mut ws, black_box(&q)).map(|f| f.pos.x))
    });
    g.bench_function("jacobian", |b| {
        b.iter(|| flange_jacobian(&robot, &mut ws, black_box(&q)).map(|j| j[(0, 0)]))
    });
    g.bench_function("rnea", |b| {
        b.iter(|| {
            rnea(
                &robot,
                &mut ws,
                black_box(&q),
                black_box(&qd),
                black_box(&qdd),
            )
            .map(|t| t[0])
        })
    });
    g.bench_function("crba", |b| {
        b.iter(|| crba(&robot, &mut ws, black_box(&q)).map(|h| h[(0, 0)]))
    });
    g.bench_function("coriolis_matrix", |b| {
        b.iter(|| {
            coriolis_matrix(&robot, &mut ws, black_box(&q), black_box(&qd)).map(|m| m[(0, 1)])
        })
    });
    g.bench_function("gravity", |b| {
        b.iter(|| gravity(&robot, &mut ws, black_box(&q)).map(|m| m[1]))
    });
    g.bench_function("joint_space_terms (H, C, g)", |b| {
        b.iter(|| joint_space_terms(&robot, &mut ws, black_box(&q), black_box(&qd)))
    });
    g.bench_function("forward_dynamics", |b| {
        b.iter(|| {
            forward_dynamics(
                &robot,
                &mut ws,
                black_box(&q),
                black_box(&qd),
                black_box(&tau),
            )
            .map(|a| a[0])
        })
    });
    bench_plant(&mut g, &robot, &q, &qd, &tau);
    bench_h_by_rnea(&mut g, &robot, &mut ws, &q);
    g.finish();
}

/// The simulated robot: one control period (10 ms) of RK4 in 1 ms substeps.
fn bench_plant(
    g: &mut BenchmarkGroup<'_, WallTime>,
    robot: &Robot,
    q: &[f64; 6],
    qd: &[f64; 6],
    tau: &[f64; 6],
) {
    let mut plant = ofmpc::sim::Plant::with_period(robot.clone(), Default::default(), q, 0.01)
        .unwrap_or_else(|e| panic!("{e}"));
    g.bench_function("plant step (10 ms, 10 RK4 substeps)", |b| {
        b.iter(|| {
            let _ = plant.set_state(q, qd);
            plant.advance(black_box(tau)).map(|_| plant.q()[0])
        })
    });
}

/// Baseline in the same run: H column by column from n inverse dynamics calls with unit
/// accelerations (what CRBA saves).
fn bench_h_by_rnea(
    g: &mut BenchmarkGroup<'_, WallTime>,
    robot: &Robot,
    ws: &mut Workspace,
    q: &[f64; 6],
) {
    let zero = [0.0; 6];
    let mut h = nalgebra::DMatrix::zeros(6, 6);
    g.bench_function("baseline: H by 6 RNEA calls", |b| {
        b.iter(|| {
            let g0 = rnea(robot, ws, black_box(q), &zero, &zero).map(|t| t.clone_owned());
            let g0 = g0.unwrap_or_else(|_| nalgebra::DVector::zeros(6));
            for j in 0..6 {
                let mut e = [0.0; 6];
                e[j] = 1.0;
                if let Ok(t) = rnea(robot, ws, q, &zero, &e) {
                    for i in 0..6 {
                        h[(i, j)] = t[i] - g0[i];
                    }
                }
            }
            h[(0, 0)]
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
