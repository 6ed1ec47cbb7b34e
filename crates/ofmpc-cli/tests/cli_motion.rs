//! `ofmpc trajectory` with the motion planner: G61 against G64 on a corner program through
//! the CSV contract (`t,x,y,z,q1..qn,qd1..qdn`), and clear errors that name the flag.

mod bin;
use bin::*;

use std::path::Path;

fn csv(path: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect()
}

/// Slowest flange speed (m/s) over the samples within `radius` of `corner` (from the CSV's
/// x, y, z by central differences).
fn slowest_near(rows: &[Vec<f64>], corner: [f64; 3], radius: f64) -> f64 {
    (1..rows.len() - 1)
        .filter(|&k| {
            let d: f64 = (0..3).map(|c| (rows[k][1 + c] - corner[c]).powi(2)).sum();
            d.sqrt() < radius
        })
        .map(|k| {
            let d: f64 = (0..3)
                .map(|c| (rows[k + 1][1 + c] - rows[k - 1][1 + c]).powi(2))
                .sum();
            d.sqrt() / (rows[k + 1][0] - rows[k - 1][0])
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn g64_keeps_moving_through_the_corners_that_g61_stops_at() {
    let dir = tempfile::tempdir().unwrap();
    let program = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/corners.gcode");
    let run = |mode: &[&str], out: &str| {
        let csv_path = dir.path().join(out);
        let mut args = vec!["trajectory", program.to_str().unwrap(), "--ts", "0.005"];
        args.extend_from_slice(mode);
        args.extend_from_slice(&["--out", csv_path.to_str().unwrap()]);
        let o = ofmpc(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        csv(&csv_path)
    };
    let exact = run(&["--mode", "G61"], "g61.csv");
    let blended = run(&["--mode", "G64", "--tolerance", "0.5"], "g64.csv");
    assert!(dir.path().join("g64_speed.png").is_file());
    for corner in [[0.55, -0.05, 0.4], [0.55, 0.05, 0.4], [0.45, 0.05, 0.4]] {
        let ve = slowest_near(&exact, corner, 0.002);
        let vb = slowest_near(&blended, corner, 0.002);
        assert!(ve < 1e-3, "G61 passes {corner:?} at {ve} m/s");
        assert!(vb > 0.01, "G64 slows to {vb} m/s at {corner:?}");
    }
    let (te, tb) = (exact.last().unwrap()[0], blended.last().unwrap()[0]);
    assert!(tb < 0.8 * te, "G64 {tb} s vs G61 {te} s");
    eprintln!("corners.gcode: G61 {te:.3} s, G64 P0.5 {tb:.3} s");
}

#[test]
fn sample_count_errors_name_the_flag_or_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("p.gcode");
    std::fs::write(&g, "G0 X500 Y0 Z400\nG1 X600 F0.0001\n").unwrap();
    let out = dir.path().join("x.csv");
    let fails = |extra: &[&str], file: &Path| {
        let mut args = vec!["trajectory", file.to_str().unwrap()];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", out.to_str().unwrap()]);
        let o = ofmpc(&args);
        assert!(!o.status.success());
        let e = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!e.contains("panicked") && !e.contains("::"), "{e}");
        assert!(!out.exists(), "no output for a failed plan");
        e
    };
    let e = fails(&[], &g);
    assert!(e.contains("program line 2") && e.contains("feed"), "{e}");
    std::fs::write(&g, "G0 X500 Y0 Z400\nG1 X600\n").unwrap();
    let e = fails(&["--ts", "1e-9"], &g);
    assert!(e.contains("--ts") && e.contains("sample period"), "{e}");
    let e = fails(&["--accel", "1e-12"], &g);
    assert!(e.contains("--accel"), "{e}");
    let e = fails(&["--speed", "0"], &g);
    assert!(e.contains("--speed"), "{e}");
}

#[test]
fn the_command_line_and_scenario_defaults_are_the_librarys() {
    use clap::Parser;
    use ofmpc::motion::{PlanOptions, TimingOptions};
    use ofmpc_cli::cli::{Cli, Command as Cmd};
    use ofmpc_scenario::{parse_mode, parse_profile, ScenarioFile};
    let cli = Cli::parse_from(["ofmpc", "trajectory", "paper", "--out", "x.csv"]);
    let Cmd::Trajectory(a) = cli.command else {
        panic!("not the trajectory command")
    };
    let (d, p) = (TimingOptions::default(), PlanOptions::default());
    assert_eq!(parse_profile(&a.profile).unwrap(), d.profile);
    assert_eq!(parse_mode(&a.mode, "--mode").unwrap(), d.default_mode);
    assert_eq!(
        (a.speed, a.accel, a.jerk, a.ts),
        (d.max_speed, d.max_accel, d.max_jerk, p.ts)
    );
    assert!((a.tolerance * 1e-3 - d.blend_tolerance).abs() < 1e-15);
    let s = ScenarioFile::default().timing;
    assert_eq!(parse_profile(&s.profile).unwrap(), d.profile);
    assert_eq!(parse_mode(&s.mode, "mode").unwrap(), d.default_mode);
    assert_eq!(
        (s.max_speed_m_s, s.max_accel_m_s2, s.max_jerk_m_s3),
        (d.max_speed, d.max_accel, d.max_jerk)
    );
    assert!((s.tolerance_mm * 1e-3 - d.blend_tolerance).abs() < 1e-15);
}

#[test]
fn inspect_robot_shows_the_joint_acceleration_limits_of_the_drives() {
    let o = ofmpc(&["inspect", "robot"]);
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let acc: Vec<f64> = (0..6)
        .map(|i| v["joints"][i]["max_accel"].as_f64().unwrap())
        .collect();
    assert_eq!(acc, [13.0, 18.0, 32.0, 160.0, 180.0, 160.0]);
}

#[test]
fn scenario_planning_errors_name_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let s = dir.path().join("s.toml");
    std::fs::write(&s, "[timing]\nmax_accel_m_s2 = 1e-12\n").unwrap();
    let out = dir.path().join("o");
    let o = ofmpc(&["run", s.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("[timing] max_accel_m_s2") && e.contains("path acceleration limit"),
        "{e}"
    );
    assert!(!out.exists());
    std::fs::write(&s, "[timing]\nmode = \"G65\"\n").unwrap();
    let o = ofmpc(&["run", s.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("[timing] mode") && e.contains("G64"),
        "{e}"
    );
}
