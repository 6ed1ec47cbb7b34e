//! Path jerk of the timed Cartesian reference (issue 26): on every benchmark program of the
//! timing (the paper's path under `G64 P0.1`, a CAM zigzag of 0.2 mm segments, a torture
//! test of random lines and arcs, a spiral of tangent arcs with three-decimal kinks, and the
//! issue's single cases), under `G64` and `G61`, the jerk of the reference sampled every
//! 1 ms (finite differences of its acceleration) stays within twice the jerk setting.
//!
//! The programs are those of `crates/ofmpc-py/tests/timing_programs.py`, generated here
//! again (the torture test with this file's own random numbers).

use ofmpc::gcode::PathMode;
use ofmpc::motion::{plan, Plan, PlanOptions, TimingOptions};
use ofmpc::random::uniform;
use ofmpc::robot::Robot;
use std::fmt::Write;

const TS: f64 = 1e-3;

/// The paper's program (Table I) under `G64 P0.1`.
fn paper() -> String {
    ofmpc::gcode::PAPER_TABLE1.replacen("G21 G90", "G21 G90 G64 P0.1", 1)
}

/// A zigzag pocket at F3000: 11 passes of 40 mm in 0.2 mm segments, 2 mm apart, with a
/// 0.02 mm waviness, three decimals.
fn zigzag() -> String {
    let mut out = String::from("G21 G90 G64 P0.01\nG0 X480 Y-10 Z400\n");
    let mut first = true;
    for k in 0..11 {
        let y = -10.0 + 2.0 * k as f64;
        let mut xs: Vec<f64> = (0..=200).map(|i| 0.2 * i as f64).collect();
        if k % 2 == 1 {
            xs.reverse();
        }
        for (i, x) in xs.iter().enumerate() {
            let yy = y + 0.02 * (0.3 * x).sin();
            let word = format!("X{:.3} Y{yy:.3}", 480.0 + x);
            if first {
                let _ = writeln!(out, "G1 {word} F3000");
                first = false;
            } else if i > 0 || k > 0 {
                let _ = writeln!(out, "{word}");
            }
        }
    }
    out
}

/// 200 random lines (40 %), arcs (50 %) and rapids (10 %) in a 40 mm box, random feeds.
fn torture() -> String {
    let mut rng = 1u64;
    let mut out = String::from("G21 G90 G17 G64 P0.05\nG0 X500 Y0 Z400\n");
    let mut pos = [500.0, 0.0];
    for _ in 0..200 {
        let end = [
            500.0 + 40.0 * uniform(&mut rng) - 20.0,
            40.0 * uniform(&mut rng) - 20.0,
        ];
        let feed = [600, 1500, 3000, 6000][(4.0 * uniform(&mut rng)) as usize];
        let r = uniform(&mut rng);
        if r < 0.1 {
            let _ = writeln!(out, "G0 X{:.4} Y{:.4}", end[0], end[1]);
        } else if r < 0.5 {
            let _ = writeln!(out, "G1 X{:.4} Y{:.4} F{feed}", end[0], end[1]);
        } else {
            let chord = [end[0] - pos[0], end[1] - pos[1]];
            let len = chord[0].hypot(chord[1]).max(1e-12);
            let f = (3.0 * uniform(&mut rng) - 1.5) * len;
            let c = [
                0.5 * (pos[0] + end[0]) - chord[1] / len * f,
                0.5 * (pos[1] + end[1]) + chord[0] / len * f,
            ];
            let g = if uniform(&mut rng) < 0.5 { "G3" } else { "G2" };
            let _ = writeln!(
                out,
                "{g} X{:.4} Y{:.4} I{:.4} J{:.4} F{feed}",
                end[0],
                end[1],
                c[0] - pos[0],
                c[1] - pos[1]
            );
        }
        pos = end;
    }
    out
}

/// `n` tangent quarter circles, radius 1 → 6 mm, three decimals, F6000.
fn arcspiral(n: usize) -> String {
    let mut out = String::from("G21 G90 G17 G64 P0.01\n");
    let (cx, cy) = (500.0, 0.0);
    let mut phi: f64 = 0.0;
    let mut p = [cx + 1.0, cy];
    let _ = writeln!(out, "G0 X{:.3} Y{:.3} Z400", p[0], p[1]);
    for k in 0..n {
        let r = 1.0 + 5.0 * k as f64 / (n - 1) as f64;
        let c = [p[0] - r * phi.cos(), p[1] - r * phi.sin()];
        phi += std::f64::consts::FRAC_PI_2;
        let q = [c[0] + r * phi.cos(), c[1] + r * phi.sin()];
        let _ = writeln!(
            out,
            "G3 X{:.3} Y{:.3} I{:.3} J{:.3}{}",
            q[0],
            q[1],
            c[0] - p[0],
            c[1] - p[1],
            if k == 0 { " F6000" } else { "" }
        );
        p = q;
    }
    out
}

/// The benchmark programs by name.
fn benchmarks() -> Vec<(&'static str, String)> {
    vec![
        ("paper_p0.1", paper()),
        ("zigzag_0.2mm", zigzag()),
        ("torture", torture()),
        ("arcspiral", arcspiral(200)),
        ("corner_90_f30000", "G21 G90 G64 P0.1\nG0 X450 Y-50 Z400\nG1 X550 F30000\nY50\n".into()),
        ("rapid_between_feeds", "G21 G90 G64 P0.1\nG0 X450 Y0 Z400\nG1 X460 F300\nG0 X500\nG1 X510 F300\n".into()),
        ("out_and_back_f30000", "G21 G90 G64 P0.1\nG0 X450 Y0 Z400\nG1 X550 F30000\nX450\n".into()),
        ("short_segment_between_lines", "G21 G90 G64 P0.1\nG0 X400 Y0 Z400\nG1 X500 F6000\nX500.05\nX600 Y10\n".into()),
        ("arc_10um_between_lines", "G21 G90 G17 G64 P0.1\nG0 X400 Y0 Z400\nG1 X500 F6000\nG2 X500.01 Y0 I0.005 J0.1\nG1 X600 Y20\n".into()),
    ]
}

/// The program under `G61`: every `G64 P…` word replaced.
fn exact_stop(text: &str) -> String {
    text.split('\n')
        .map(|l| match l.find("G64") {
            Some(i) => {
                let rest = &l[i + 3..];
                let rest = rest.trim_start();
                let rest = rest.strip_prefix('P').map_or(rest, |r| {
                    r.trim_start_matches(|c: char| c.is_ascii_digit() || c == '.')
                });
                format!(
                    "{}G61{}{rest}",
                    &l[..i],
                    if rest.is_empty() { "" } else { " " }
                )
            }
            None => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Largest path jerk (m/s³) of the plan's Cartesian reference sampled every [`TS`]:
/// `|a(t_{k+1}) − a(t_k)| / TS`, and the time where it occurs.
fn worst_jerk(p: &Plan) -> (f64, f64) {
    let tr = &p.trajectory;
    let n = (tr.duration() / TS).ceil() as usize + 2;
    let mut prev = tr.sample(0.0).acceleration;
    let mut worst = (0.0f64, 0.0f64);
    for k in 1..=n {
        let t = k as f64 * TS;
        let a = tr.sample(t).acceleration;
        let j = (a - prev).norm() / TS;
        if j > worst.0 {
            worst = (j, t);
        }
        prev = a;
    }
    worst
}

fn options(jerk: f64) -> PlanOptions {
    PlanOptions {
        timing: TimingOptions {
            max_jerk: jerk,
            default_mode: PathMode::ExactStop,
            ..TimingOptions::default()
        },
        ts: 0.01,
        ..PlanOptions::default()
    }
}

/// Every benchmark program, under `G64` and under `G61`: path jerk ≤ 2× the setting.
#[test]
fn path_jerk_stays_within_twice_the_setting_on_every_benchmark() {
    let robot = Robot::irb140();
    let jerk = TimingOptions::default().max_jerk;
    let mut report = String::new();
    let mut bad = Vec::new();
    for (name, text) in benchmarks() {
        for (mode, t) in [("G64", text.clone()), ("G61", exact_stop(&text))] {
            let p =
                plan(&t, &robot, &options(jerk)).unwrap_or_else(|e| panic!("{name} {mode}: {e}"));
            let (j, at) = worst_jerk(&p);
            let _ = writeln!(
                report,
                "{name} {mode}: {:.3} s, jerk {j:.1} m/s³ at {at:.3} s",
                p.diagnostics.duration
            );
            if j > 2.0 * jerk {
                bad.push(format!("{name} {mode}"));
            }
        }
    }
    println!("{report}");
    assert!(bad.is_empty(), "{bad:?}\n{report}");
}
