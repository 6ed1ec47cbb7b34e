//! Motion planning speed: a CAM-like program of 10,000 short segments under `G64 P0.01`
//! (parse, blend, time-optimal timing with the IRB 140's joint limits, the joint reference
//! every 10 ms), against the paper's 8-move program under `G61` in the same run; and the
//! same program with 100,000 segments (issue 26: planning stays linear, target ≤ 3 s).
//!
//! `cargo bench -p ofmpc --bench motion -- --warm-up-time 1 --measurement-time 10`
//! (the 100,000 segments alone: `... --bench motion -- 100k`)

use criterion::{criterion_group, criterion_main, Criterion};
use ofmpc::gcode::{parse, ParseOptions, PAPER_TABLE1};
use ofmpc::motion::{plan, plan_program, PlanOptions};
use ofmpc::robot::Robot;
use std::fmt::Write;

/// `n` segments of about 1 mm along a wavy circle of radius 100 mm, F6000.
fn long_program(n: usize) -> String {
    let mut text = String::from("G21 G90 G64 P0.01\n");
    for k in 0..=n {
        let a = k as f64 * 0.01;
        let r = 100.0 + 10.0 * (7.0 * a).sin();
        let (x, y) = (500.0 + r * a.cos(), r * a.sin());
        let z = 400.0 + 5.0 * (3.0 * a).sin();
        let _ = match k {
            0 => writeln!(text, "G0 X{x:.4} Y{y:.4} Z{z:.4}"),
            1 => writeln!(text, "G1 X{x:.4} Y{y:.4} Z{z:.4} F6000"),
            _ => writeln!(text, "X{x:.4} Y{y:.4} Z{z:.4}"),
        };
    }
    text
}

fn bench(c: &mut Criterion) {
    let robot = Robot::irb140();
    let options = PlanOptions::default();
    let text = long_program(10_000);
    let program = parse(&text, &ParseOptions::default()).expect("valid program");
    let big = parse(&long_program(100_000), &ParseOptions::default()).expect("valid program");
    let mut g = c.benchmark_group("plan");
    g.sample_size(10);
    g.bench_function("paper_g61_8_moves", |b| {
        b.iter(|| plan(PAPER_TABLE1, &robot, &options).expect("plans"))
    });
    g.bench_function("cam_g64_10k_segments_parsed", |b| {
        b.iter(|| plan_program(program.clone(), &robot, &options).expect("plans"))
    });
    g.bench_function("cam_g64_10k_segments_from_text", |b| {
        b.iter(|| plan(&text, &robot, &options).expect("plans"))
    });
    g.bench_function("cam_g64_100k_segments_parsed", |b| {
        b.iter(|| plan_program(big.clone(), &robot, &options).expect("plans"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
