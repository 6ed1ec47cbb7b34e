//! Reading speed of the G-code reader (issue #20): a 100,000-line CAM-like program (N
//! numbers, G1 with X Y Z and F, arcs every 50 lines, comments, M/S events) and an endless
//! `while` stopped by the step limit, against the paper's 8-move program in the same run.
//!
//! `cargo bench -p ofmpc --bench gcode -- --warm-up-time 1 --measurement-time 5`

use criterion::{criterion_group, criterion_main, Criterion};
use ofmpc::gcode::{parse, ParseOptions, PAPER_TABLE1};
use std::fmt::Write;

/// A CAM-like program of `n` lines.
fn cam_program(n: usize) -> String {
    let mut text = String::from("%\n(CAM output)\nG21 G90 G17 G64 P0.01\nS12000 M3\n");
    let _ = writeln!(text, "G0 X0 Y0 Z5");
    for k in 0..n {
        let a = k as f64 * 0.001;
        let (x, y, z) = (
            100.0 * a.cos(),
            100.0 * a.sin(),
            -1.0 + 0.5 * (9.0 * a).sin(),
        );
        let _ = if k % 50 == 49 {
            writeln!(text, "N{k} G2 X{x:.4} Y{y:.4} R300 (arc)")
        } else {
            writeln!(text, "N{k} G1 X{x:.4} Y{y:.4} Z{z:.4} F1500")
        };
    }
    text.push_str("M5\nM30\n%\n");
    text
}

fn bench(c: &mut Criterion) {
    let cam = cam_program(100_000);
    let opts = ParseOptions::default();
    if let Err(e) = parse(&cam, &opts) {
        panic!("the benchmark program does not read: {e}");
    }
    let mut g = c.benchmark_group("gcode_read");
    g.sample_size(10);
    g.bench_function("paper_table1", |b| b.iter(|| parse(PAPER_TABLE1, &opts)));
    g.bench_function("cam_100k_lines", |b| b.iter(|| parse(&cam, &opts)));
    let endless = "G0 X0 Y0 Z0\no1 while [1]\n#1 = [#1 + 1]\no1 endwhile\n";
    g.bench_function("endless_while_to_step_limit", |b| {
        b.iter(|| parse(endless, &opts).unwrap_err())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
