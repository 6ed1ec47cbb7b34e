//! The `ofmpc` binary end to end: the paper's claims as numbers from
//! `metrics.json`, the time series contract (an independent replay), the
//! report in a real browser, and clear errors on bad input.

mod bin;
use bin::*;

use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{Plant, PlantSettings};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn parse_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// The paper's claims (section IV) on the IRB 140 and the paper's program,
/// with 0.25 kg and with 1 kg unknown to the controllers.
#[test]
fn reproduce_confirms_the_papers_claims_and_writes_every_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let stdout = ok(&[
        "reproduce",
        "--payload",
        "0,0.25,1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        stdout.contains("second_m0.25") && stdout.contains("9 runs"),
        "{stdout}"
    );
    let metrics: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    assert_eq!(metrics["runs"].as_array().unwrap().len(), 9);
    for m in ["0", "0.25", "1"] {
        let usual = run(&metrics, &format!("usual_m{m}"));
        let first = run(&metrics, &format!("first_m{m}"));
        let second = run(&metrics, &format!("second_m{m}"));
        for r in [usual, first, second] {
            assert_eq!(r["diverged"], false, "{r}");
            assert!(r["diverged_at_s"].is_null());
            for key in [
                "joint_error_rms_rad",
                "joint_error_max_rad",
                "steady_joint_error_max_rad",
                "torque_max_nm",
            ] {
                assert_eq!(r[key].as_array().unwrap().len(), 6, "{key}");
            }
            assert!(r["step_time_us"]["median"].as_f64().unwrap() > 0.0);
            assert!(r["wall_s"].as_f64().unwrap() > 0.0);
        }
        if m == "0" {
            // Exact model: all three track (sub-0.1 mm) and settle exactly.
            for r in [usual, first, second] {
                assert!(r["cartesian_error_max_mm"].as_f64().unwrap() < 0.1, "{r}");
                assert!(
                    r["steady_cartesian_error_mm"].as_f64().unwrap() < 1e-6,
                    "{r}"
                );
            }
        } else {
            // Usual MPC: a clear steady offset under the unknown payload.
            assert!(
                usual["steady_cartesian_error_mm"].as_f64().unwrap() > 0.05,
                "{usual}"
            );
            // Both incremental algorithms: no steady error.
            assert!(
                max_of(&first["steady_joint_error_max_rad"]) < 1e-6,
                "{first}"
            );
            assert!(
                max_of(&second["steady_joint_error_max_rad"]) < 1e-6,
                "{second}"
            );
            // The second algorithm has the smallest RMS Cartesian error.
            let rms = |r: &Value| r["cartesian_error_rms_mm"].as_f64().unwrap();
            assert!(
                rms(second) < rms(first) && rms(second) < rms(usual),
                "{} {} {}",
                rms(usual),
                rms(first),
                rms(second)
            );
        }
    }
    // The usual offset grows with the payload.
    let offset = |m: &str| {
        run(&metrics, &format!("usual_m{m}"))["steady_cartesian_error_mm"]
            .as_f64()
            .unwrap()
    };
    assert!(offset("1") > 3.0 * offset("0.25"));

    for f in [
        "report.html",
        "path.png",
        "path.svg",
        "joint_errors_m0.png",
        "joint_errors_m0.25.svg",
        "cartesian_errors_m1.png",
        "payload_sweep.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    for r in ["usual_m0", "second_m0.25", "first_m1"] {
        for f in [
            "timeseries.csv",
            "joints_torques.png",
            "joints_torques.svg",
            "cartesian_error.png",
            "cartesian_error.svg",
        ] {
            assert!(out.join(r).join(f).is_file(), "{r}/{f} missing");
        }
    }
    // No staging leftovers.
    for e in std::fs::read_dir(&out).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.starts_with('.'), "leftover {name}");
    }
    replay_matches_the_recorded_states(&out.join("second_m0.25/timeseries.csv"), 0.25);
    the_written_scenario_repeats_the_run(&out, &metrics);
    report_renders_in_chromium(&out.join("report.html"));
}

/// `ofmpc run OUT/scenario.toml` repeats the run: the same errors, bit for bit
/// (the simulation is deterministic; only timings differ).
fn the_written_scenario_repeats_the_run(out: &Path, metrics: &Value) {
    let again = out.parent().unwrap().join("again");
    ok(&[
        "run",
        out.join("scenario.toml").to_str().unwrap(),
        "--out",
        again.to_str().unwrap(),
    ]);
    let m2: Value =
        serde_json::from_str(&std::fs::read_to_string(again.join("metrics.json")).unwrap())
            .unwrap();
    let (a, b) = (
        metrics["runs"].as_array().unwrap(),
        m2["runs"].as_array().unwrap(),
    );
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        for key in [
            "name",
            "joint_error_rms_rad",
            "steady_joint_error_max_rad",
            "cartesian_error_rms_mm",
            "torque_max_nm",
        ] {
            assert_eq!(x[key], y[key], "{key} of {}", x["name"]);
        }
    }
}

/// An independent replay: from each row's state, apply its torque over one
/// period (Ts = t_1 − t_0), and compare with the next row's state. (A free
/// open-loop replay of 14 s would drift: the robot under recorded torques
/// amplifies round-off.)
fn replay_matches_the_recorded_states(csv: &Path, payload: f64) {
    let (header, rows) = parse_csv(csv);
    let mut expect = vec!["t".to_string()];
    for p in ["q", "qd", "tau", "qref", "e"] {
        expect.extend((1..=6).map(|i| format!("{p}{i}")));
    }
    expect.extend(["x", "y", "z", "xref", "yref", "zref", "ex", "ey", "ez"].map(String::from));
    assert_eq!(header, expect);
    let mut robot = Robot::irb140();
    robot
        .set_payload(Some(Payload::point_mass(payload)))
        .unwrap();
    let mut worst = 0.0f64;
    let ts = rows[1][0] - rows[0][0];
    let mut plant =
        Plant::with_period(robot, PlantSettings::default(), &rows[0][1..7], ts).unwrap();
    for k in 0..rows.len() - 1 {
        plant.set_state(&rows[k][1..7], &rows[k][7..13]).unwrap();
        plant.advance(&rows[k][13..19]).unwrap();
        for i in 0..6 {
            worst = worst.max((plant.q()[i] - rows[k + 1][1 + i]).abs());
            worst = worst.max((plant.qd()[i] - rows[k + 1][7 + i]).abs() * ts);
        }
    }
    assert!(
        worst < 1e-12,
        "replay drifts from the recorded states by {worst:e} rad"
    );
}

fn find_chromium() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::iter::once(PathBuf::from("/usr/bin"))
        .chain(std::env::split_paths(&path))
        .find_map(|d| {
            ["chromium", "chromium-browser", "google-chrome"]
                .iter()
                .map(|n| d.join(n))
                .find(|p| p.is_file())
        })
}

/// Opens the report in headless Chromium: every figure must have rendered
/// (the page's own check), and a screenshot must not be blank.
fn report_renders_in_chromium(report: &Path) {
    let Some(bin) = find_chromium() else {
        eprintln!("note: Chromium not installed; report.html not rendered (CI installs it)");
        return;
    };
    let profile = tempfile::tempdir().unwrap();
    let shot = profile.path().join("shot.png");
    let base = [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
    ];
    let go = |extra: &[String]| {
        let o = Command::new(&bin)
            .args(base)
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .args(extra)
            .arg(format!("file://{}", report.display()))
            .stdin(Stdio::null())
            .output()
            .expect("start chromium");
        assert!(
            o.status.success(),
            "chromium: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let dom = go(&["--virtual-time-budget=10000".into(), "--dump-dom".into()]);
    let at = dom
        .find("id=\"figure-check\"")
        .expect("the report has its figure check");
    let tag = &dom[dom[..at].rfind('<').unwrap()..at + dom[at..].find('>').unwrap()];
    let attr = |name: &str| -> usize {
        let k = format!("{name}=\"");
        let v = &tag[tag.find(&k).unwrap_or_else(|| panic!("{name} in {tag}")) + k.len()..];
        v[..v.find('"').unwrap()].parse().unwrap()
    };
    let figures = std::fs::read_to_string(report)
        .unwrap()
        .matches("<figure")
        .count();
    assert!(figures >= 10, "only {figures} figures in the report");
    assert_eq!(attr("data-total"), figures, "{tag}");
    assert_eq!(attr("data-ok"), figures, "not every figure rendered: {tag}");
    go(&[
        format!("--screenshot={}", shot.display()),
        "--window-size=1200,2400".into(),
    ]);
    let png = std::fs::read(&shot).expect("screenshot written");
    assert!(
        png.len() > 20_000,
        "screenshot suspiciously small ({} bytes)",
        png.len()
    );
}

#[test]
fn run_reads_the_annotated_example_scenario() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenario.toml");
    // The example, shortened to one controller and one payload for speed.
    let text = std::fs::read_to_string(&scenario).unwrap().replace(
        "controllers = [\"usual\", \"first\", \"second\"]",
        "controllers = [\"second\"]",
    );
    let text = text.replace("masses_kg = [0.0, 0.25]", "masses_kg = [0.5]");
    let path = dir.path().join("s.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.path().join("o");
    ok(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(out.join("second_m0.5/timeseries.csv").is_file());
}

#[test]
fn bad_input_gets_clear_errors_and_a_nonzero_exit() {
    let dir = tempfile::tempdir().unwrap();
    let s = dir.path().join("bad.toml");
    std::fs::write(&s, "[mpc]\nhorizon = 10\nq_yww = 1.0\n").unwrap();
    let e = fails(&[
        "run",
        s.to_str().unwrap(),
        "--out",
        dir.path().join("o").to_str().unwrap(),
    ]);
    assert!(
        e.contains("bad.toml") && e.contains("line 3") && e.contains("q_yww"),
        "{e}"
    );
    assert!(
        !dir.path().join("o").exists(),
        "no output directory for a failed run"
    );

    let g = dir.path().join("p.gcode");
    std::fs::write(
        &g,
        "G17\nG01 X700 Y0 Z300\nG02 X600 Y100 Z300 I-100 J0 Q5\n",
    )
    .unwrap();
    let e = fails(&[
        "reproduce",
        "--program",
        g.to_str().unwrap(),
        "--out",
        dir.path().join("o2").to_str().unwrap(),
    ]);
    assert!(e.contains("p.gcode") && e.contains("line 3"), "{e}");

    let e = fails(&[
        "reproduce",
        "--payload",
        "0,abc",
        "--out",
        dir.path().join("o3").to_str().unwrap(),
    ]);
    assert!(e.contains("--payload") && e.contains("abc"), "{e}");
    let e = fails(&[
        "reproduce",
        "--payload",
        "-1",
        "--out",
        dir.path().join("o4").to_str().unwrap(),
    ]);
    assert!(e.contains("mass"), "{e}");
    let e = fails(&["inspect", "dynamics", "--q", "0,0,0"]);
    assert!(e.contains("6 joints"), "{e}");
    let e = fails(&["inspect", "dynamics", "--robot", "nope.urdf", "--q", "0"]);
    assert!(e.contains("nope.urdf"), "{e}");
}

#[test]
fn inspect_dynamics_prints_the_documented_json() {
    let out = ok(&[
        "inspect",
        "dynamics",
        "--payload",
        "0.25",
        "--q",
        "0.1,-0.2,0.3,0.4,-0.5,0.6",
        "--qd",
        "0.1,0.2,0.3,0.4,0.5,0.6",
        "--qdd",
        "1,0,0,0,0,0",
    ]);
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["H"].as_array().unwrap().len(), 6);
    assert_eq!(v["H"][0].as_array().unwrap().len(), 6);
    assert_eq!(v["C"].as_array().unwrap().len(), 6);
    assert_eq!(v["g"].as_array().unwrap().len(), 6);
    assert_eq!(v["tau"].as_array().unwrap().len(), 6);
    assert_eq!(v["flange"]["position"].as_array().unwrap().len(), 3);
    assert_eq!(v["flange"]["rotation"].as_array().unwrap().len(), 3);
    // tau = H qdd + C qd + g with qdd = e1: column 0 of H plus C qd plus g.
    let qd = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
    for i in 0..6 {
        let h = v["H"][i][0].as_f64().unwrap();
        let cqd: f64 = (0..6).map(|j| v["C"][i][j].as_f64().unwrap() * qd[j]).sum();
        let g = v["g"][i].as_f64().unwrap();
        let tau = v["tau"][i].as_f64().unwrap();
        assert!(
            (h + cqd + g - tau).abs() < 1e-10 * tau.abs().max(1.0),
            "row {i}"
        );
    }
}

#[test]
fn trajectory_writes_the_reference_csv_and_figures() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("ref.csv");
    ok(&[
        "trajectory",
        "paper",
        "--ts",
        "0.02",
        "--profile",
        "quintic",
        "--out",
        csv.to_str().unwrap(),
    ]);
    let (header, rows) = parse_csv(&csv);
    let mut expect: Vec<String> = ["t", "x", "y", "z"].map(String::from).to_vec();
    expect.extend((1..=6).map(|i| format!("q{i}")));
    expect.extend((1..=6).map(|i| format!("qd{i}")));
    assert_eq!(header, expect);
    assert!(
        (rows[0][1] - 0.78).abs() < 1e-12
            && (rows[0][2] + 0.2).abs() < 1e-12
            && (rows[0][3] - 0.15).abs() < 1e-12
    );
    assert!((rows[1][0] - 0.02).abs() < 1e-15);
    for f in [
        "ref_path.png",
        "ref_path.svg",
        "ref_cartesian.png",
        "ref_cartesian.svg",
    ] {
        assert!(dir.path().join(f).is_file(), "{f} missing");
    }
    // Read in the base frame (no work offset), the paper's path is out of range:
    // the error names the program line, joint 3 and the work offset to use.
    let g = dir.path().join("base.gcode");
    std::fs::write(
        &g,
        ofmpc::gcode::PAPER_TABLE1.replace("G10 L2 P1 X150 Y0 Z-250", ""),
    )
    .unwrap();
    let e = fails(&[
        "trajectory",
        g.to_str().unwrap(),
        "--out",
        dir.path().join("x.csv").to_str().unwrap(),
    ]);
    assert!(
        e.contains("line") && e.contains("joint 3") && e.contains("work offset"),
        "{e}"
    );
    // --origin moves a program that sets no offset.
    let shifted = ofmpc::gcode::PAPER_TABLE1.replace("G10 L2 P1 X150 Y0 Z-250", "");
    std::fs::write(&g, shifted).unwrap();
    ok(&[
        "trajectory",
        g.to_str().unwrap(),
        "--origin",
        "150,0,-250",
        "--out",
        dir.path().join("y.csv").to_str().unwrap(),
    ]);
}

#[test]
fn inspect_robot_lists_joints_limits_and_drives() {
    let v: Value = serde_json::from_str(&ok(&["inspect", "robot"])).unwrap();
    assert_eq!(v["dof"], 6);
    assert_eq!(v["flange"]["frame"], "flange");
    assert!((v["moving_mass_kg"].as_f64().unwrap() - 71.882).abs() < 0.01);
    let j3 = &v["joints"][2];
    assert_eq!(j3["name"], "joint_3");
    assert!((j3["upper"].as_f64().unwrap() - 50f64.to_radians()).abs() < 1e-9);
    assert_eq!(j3["armature_kgm2"].as_f64().unwrap(), 0.5);
    assert_eq!(v["joints"][5]["max_effort"].as_f64().unwrap(), 16.0);
}

/// The inverse kinematics is chosen from the kinematics and named (issue #19): the
/// built-in IRB 140 and ROS-Industrial's IRB 2400 use the OPW closed form, with the
/// parameters read off the URDF (the IRB 2400's upper arm is 0.705 m, its forearm offset
/// a2 = −0.135 m as in ROS-Industrial `opw_kinematics`); a UR uses its own closed form.
#[test]
fn inspect_robot_names_the_closed_form_and_its_parameters() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../ofmpc/tests/data/robots");
    let v: Value = serde_json::from_str(&ok(&["inspect", "robot"])).unwrap();
    assert!(v["ik_solver"].as_str().unwrap().contains("OPW closed form"));
    assert_eq!(v["opw_parameters"]["c2_m"].as_f64().unwrap(), 0.36);
    let abb = data.join("abb/irb2400.urdf");
    let args = [
        "inspect",
        "robot",
        "--robot",
        abb.to_str().unwrap(),
        "--tip",
        "tool0",
    ];
    let v: Value = serde_json::from_str(&ok(&args)).unwrap();
    assert!(
        v["ik_solver"].as_str().unwrap().contains("OPW closed form"),
        "{v}"
    );
    let p = &v["opw_parameters"];
    assert!((p["c2_m"].as_f64().unwrap() - 0.705).abs() < 1e-12, "{p}");
    assert!((p["a2_m"].as_f64().unwrap() + 0.135).abs() < 1e-12, "{p}");
    let ur = data.join("ur/ur5_robot.urdf");
    let v: Value =
        serde_json::from_str(&ok(&["inspect", "robot", "--robot", ur.to_str().unwrap()])).unwrap();
    assert!(
        v["ik_solver"].as_str().unwrap().contains("UR closed form"),
        "{v}"
    );
    assert!(v["opw_parameters"].is_null());
}

/// `ofmpc init robot --tip`: the Panda (a hand with two prismatic fingers: a branched
/// tree) gets the tip panda_hand chosen without `--tip` and starts with it given; the written scenario
/// carries the tip and loads the 7-joint arm that `inspect robot --tip` describes.
#[test]
fn init_robot_with_a_tip_starts_a_branched_arm() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../ofmpc/tests/data/robots");
    let panda = data.join("panda/panda.urdf");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("panda");
    let p = panda.to_str().unwrap();
    let o = out.to_str().unwrap();
    // Without --tip, init chooses the branching link (panda_hand) itself.
    let auto = dir.path().join("panda-auto");
    ok(&["init", "robot", p, "--out", auto.to_str().unwrap()]);
    let chosen = std::fs::read_to_string(auto.join("scenario.toml")).unwrap();
    assert!(chosen.contains("panda_hand"), "{chosen}");
    ok(&["init", "robot", p, "--out", o, "--tip", "panda_hand"]);
    let scenario = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
    let file: toml::Value = toml::from_str(&scenario).unwrap();
    assert_eq!(
        file["robot"]["tip"].as_str(),
        Some("panda_hand"),
        "{scenario}"
    );
    let drives = std::fs::read_to_string(out.join("drives.toml")).unwrap();
    assert_eq!(drives.matches("[joints.").count(), 7, "{drives}");
    let v: Value = serde_json::from_str(&ok(&[
        "inspect",
        "robot",
        "--robot",
        p,
        "--tip",
        "panda_hand",
    ]))
    .unwrap();
    assert_eq!(v["dof"].as_u64(), Some(7), "{v}");
}

/// `ofmpc run FILE --set key=value`: the value as if written in the file. One quick run
/// (usual, one payload, a short hold set from the command line) that the written
/// `scenario.toml` reflects, and the file's checks and messages for what does not fit.
#[test]
fn run_set_overrides_a_key_with_the_files_checks() {
    let dir = tempfile::tempdir().unwrap();
    let s = dir.path().join("s.toml");
    std::fs::write(
        &s,
        "controllers = [\"usual\"]\n[payload]\nmasses_kg = [0.0]\n",
    )
    .unwrap();
    let out = dir.path().join("o");
    let (s, o) = (s.to_str().unwrap(), out.to_str().unwrap());
    ok(&[
        "run",
        s,
        "--set",
        "simulation.hold_s=0.2",
        "--set",
        "simulation.steady_window_s = 0.1",
        "--set",
        "title=set from the command line",
        "--set",
        "mpc.horizon=12",
        "--out",
        o,
    ]);
    let written: toml::Table =
        toml::from_str(&std::fs::read_to_string(out.join("scenario.toml")).unwrap()).unwrap();
    assert_eq!(written["title"].as_str(), Some("set from the command line"));
    assert_eq!(written["mpc"]["horizon"].as_integer(), Some(12));
    assert_eq!(written["simulation"]["hold_s"].as_float(), Some(0.2));

    // (arguments, what the message names); nothing is written for any of them.
    let bad: [(&[&str], &[&str]); 7] = [
        // An unknown key: the file's message (unknown field, the keys it knows).
        (
            &["--set", "mpc.horizn=20"],
            &["mpc.horizn=20", "unknown field `horizn`", "horizon"],
        ),
        (
            &["--set", "nosuch.key=1"],
            &["nosuch.key=1", "unknown field `nosuch`"],
        ),
        // A value of the wrong type.
        (
            &["--set", "simulation.hold_s=long"],
            &["simulation.hold_s=long", "invalid type", "long"],
        ),
        // A key below a value.
        (
            &["--set", "controllers.x=1"],
            &["controllers.x=1", "not a table"],
        ),
        (&["--set", "title.x=1"], &["title.x=1", "invalid type: map"]),
        // A value the library rejects: named by its scenario key, as in a file.
        (&["--set", "plant.substep=-1"], &["[plant] substep = -1"]),
        // Not key=value.
        (
            &["--set", "mpc.horizon"],
            &["--set", "mpc.horizon", "key=value"],
        ),
    ];
    for (args, names) in bad {
        let bad_out = dir.path().join("bad");
        let mut all = vec!["run", s];
        all.extend_from_slice(args);
        all.extend_from_slice(&["--out", bad_out.to_str().unwrap()]);
        let o = ofmpc(&all);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        for n in names {
            assert!(e.contains(n), "{args:?} should name {n}: {e}");
        }
        assert!(!bad_out.exists(), "{args:?}: no output for a failed run");
    }
}

/// `ofmpc reproduce --set`: applied after the options, with the same checks.
#[test]
fn reproduce_set_applies_after_the_options() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let o = ofmpc(&[
        "reproduce",
        "--controllers",
        "usual",
        "--payload",
        "0",
        "--set",
        "simulation.hold_s=-1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("[simulation] hold_s = -1"), "{e}");
    let e = fails(&[
        "reproduce",
        "--set",
        "controllers=[\"fourth\"]",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        e.contains("--set controllers=") && e.contains("fourth"),
        "{e}"
    );
    assert!(!out.exists());
}

#[test]
fn inspect_program_prints_the_moves_in_machine_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("p.ngc");
    std::fs::write(
        &f,
        "G21 G90\nG0 Z5 M3 S1000\n(MSG, cut)\nG10 L2 P2 X100\nG55 G1 X10 Y0 F600\nG81 X20 R2 Z-1\nG80\nM30\n",
    )
    .unwrap();
    let out = ok(&["inspect", "program", f.to_str().unwrap()]);
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["units"], "mm");
    let ends: Vec<Vec<f64>> = v["moves"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| serde_json::from_value(m["end"].clone()).unwrap())
        .collect();
    // From machine zero; G55's offset is added; the cycle expands to its moves.
    let want = [
        [0.0, 0.0, 5.0],
        [110.0, 0.0, 5.0],
        [120.0, 0.0, 5.0],
        [120.0, 0.0, 2.0],
        [120.0, 0.0, -1.0],
        [120.0, 0.0, 2.0],
    ];
    assert_eq!(ends.len(), want.len(), "{out}");
    for (a, b) in ends.iter().zip(want) {
        assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-9), "{a:?} vs {b:?}");
    }
    assert_eq!(v["moves"][1]["feed_mm_s"], 10.0);
    assert_eq!(v["events"][0]["code"], "S");
    assert_eq!(v["messages"][0]["text"], "cut");
    // With a robot the program starts from its start pose's tool position.
    let out = ok(&[
        "inspect",
        "program",
        f.to_str().unwrap(),
        "--robot",
        "irb140",
    ]);
    let v: Value = serde_json::from_str(&out).unwrap();
    assert!(v["start"][0].as_f64().unwrap() > 100.0, "{out}");
}

#[test]
fn g43_h_reads_with_a_tool_table_and_is_refused_without_one() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("p.ngc");
    std::fs::write(&f, "G0 X0 Y0 Z0\nG43 H2\nG1 Z1 F600\nM30\n").unwrap();
    let tbl = dir.path().join("tools.tbl");
    std::fs::write(&tbl, "T2 P2 Z+12.5 D3 ;drill\n").unwrap();
    let (f, tbl) = (f.to_str().unwrap(), tbl.to_str().unwrap());
    let e = fails(&["inspect", "program", f]);
    assert!(e.contains("no tool table was given"), "{e}");
    let out = ok(&["inspect", "program", f, "--tool-table", tbl]);
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["moves"].as_array().unwrap().len(), 1, "{out}");
    assert_eq!(v["tool_length_mm"], 12.5);
    // A malformed table is named with the option, its line and column.
    std::fs::write(dir.path().join("bad.tbl"), "T1 Z1\nT2 Z1,5\n").unwrap();
    let bad = dir.path().join("bad.tbl");
    let e = fails(&[
        "inspect",
        "program",
        f,
        "--tool-table",
        bad.to_str().unwrap(),
    ]);
    assert!(
        e.contains("--tool-table") && e.contains("line 2, column 4"),
        "{e}"
    );
}

/// With a baseline compared, the report's verdict (at the top) carries the recommendation of
/// "Controllers compared" (issue #38: it was only at the bottom of that section), and the
/// figure check says nothing to readers when every figure is drawn.
#[test]
fn the_verdict_carries_the_comparison_recommendation() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("r");
    let out_s = out.display().to_string();
    ok(&[
        "reproduce",
        "--controllers",
        "second,ctc",
        "--payload",
        "0,0.25",
        "--out",
        &out_s,
    ]);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    let verdict_at = html
        .find("Recommendation: Over the whole range 0–0.25 kg")
        .expect("in the verdict");
    let section_at = html.find("Controllers compared").unwrap();
    assert!(verdict_at < section_at, "the recommendation comes first");
    assert!(html.contains("choose it when the payload is not known"));
    assert!(
        !html.contains("figures rendered."),
        "no developer check for readers"
    );
}
