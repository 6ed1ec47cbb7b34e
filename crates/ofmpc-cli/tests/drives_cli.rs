//! Issue #11 at the CLI: the `[faults]` and `[safety]` tables, metrics.json's
//! `faults`, `saturated_samples` and `max_torque_ratio`, timeseries.csv's
//! true state beside `q_meas`/`qd_meas`, the report's drives section, and
//! bad values named by their keys.

mod bin;
use bin::*;

use std::path::Path;

fn scenario(dir: &Path, body: &str) -> String {
    let p = dir.join("s.toml");
    std::fs::write(&p, body).unwrap();
    p.display().to_string()
}

fn rows(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (header, rows)
}

#[test]
fn faults_and_safety_tables_reach_metrics_timeseries_and_report() {
    let tmp = tempfile::tempdir().unwrap();
    let s = scenario(
        tmp.path(),
        r#"
title = "faults"
controllers = ["second"]
[payload]
masses_kg = [0.25]
[faults]
nan_at_s = [1.0, 3.0]
dropout_s = [[2.0, 2.1]]
[safety]
max_joint_error_rad = 0.1
"#,
    );
    let out = tmp.path().join("out");
    ok(&["run", &s, "--out", out.to_str().unwrap()]);
    let m = metrics(&out);
    let r = run(&m, "second_m0.25");
    assert_eq!(r["status"], "ok");
    assert_eq!(r["faults"], 12);
    assert_eq!(r["saturated_samples"], 0);
    let ratio = r["max_torque_ratio"].as_f64().unwrap();
    assert!(ratio > 0.0 && ratio < 1.0, "{ratio}");
    let (header, data) = rows(&out.join("second_m0.25/timeseries.csv"));
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (q1, qm1, qdm6) = (col("q1"), col("q_meas1"), col("qd_meas6"));
    assert_eq!(qdm6, header.len() - 1, "q_meas/qd_meas come last");
    let lost: Vec<&str> = data
        .iter()
        .filter(|r| r[qm1] == "NaN")
        .map(|r| r[0].as_str())
        .collect();
    assert_eq!(lost.len(), 12);
    assert_eq!((lost[0], lost[11]), ("1", "3"));
    // NaN is allowed in the measurement columns only.
    for r in &data {
        for (i, v) in r.iter().enumerate() {
            if i < col("q_meas1") {
                assert!(v.parse::<f64>().unwrap().is_finite(), "{} = {v}", header[i]);
            }
        }
        assert!(r[q1].parse::<f64>().is_ok());
    }
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(report.contains("Drives, sensors and faults"));
    // The effective scenario keeps the tables.
    let eff = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
    assert!(
        eff.contains("[faults]") && eff.contains("nan_at_s = [1.0, 3.0]"),
        "{eff}"
    );
    assert!(eff.contains("max_joint_error_rad = 0.1"), "{eff}");
}

#[test]
fn an_ideal_measurement_adds_no_columns() {
    let tmp = tempfile::tempdir().unwrap();
    let s = scenario(
        tmp.path(),
        "controllers = [\"first\"]\n[payload]\nmasses_kg = [0.0]\n[simulation]\nhold_s = 0.5\n",
    );
    let out = tmp.path().join("out");
    ok(&["run", &s, "--out", out.to_str().unwrap()]);
    let (header, _) = rows(&out.join("first_m0/timeseries.csv"));
    assert!(!header.iter().any(|h| h.contains("meas")), "{header:?}");
    let m = metrics(&out);
    assert_eq!(run(&m, "first_m0")["faults"], 0);
}

#[test]
fn bad_fault_and_safety_values_name_their_keys() {
    let tmp = tempfile::tempdir().unwrap();
    for (body, key) in [
        (
            "[faults]\nnan_at_s = [1.0, -2.0]\n",
            "[faults] nan_at_s[1] = -2",
        ),
        (
            "[faults]\ndropout_s = [[3.0, 2.0]]\n",
            "[faults] dropout_s[0] = [3, 2]",
        ),
        (
            "[safety]\nmax_joint_error_rad = -0.1\n",
            "[safety] max_joint_error_rad = -0.1",
        ),
        ("[faults]\nnan_at = [1.0]\n", "nan_at"),
    ] {
        let s = scenario(tmp.path(), body);
        let o = ofmpc(&["run", &s, "--out", tmp.path().join("o").to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{body}");
        let e = stderr(&o);
        assert!(e.contains(key), "{body}: {e}");
    }
}

/// The safety limit at the CLI: a run that would diverge ends "stopped", the
/// summary says so (not "ok"), and the process exits 0 (the run did what it
/// was told).
#[test]
fn a_stopped_run_is_reported_as_stopped() {
    let tmp = tempfile::tempdir().unwrap();
    let s = scenario(
        tmp.path(),
        "controllers = [\"second\"]\n[payload]\nmasses_kg = [6.0]\n[plant]\ntorque_limits = true\n[safety]\nmax_joint_error_rad = 0.05\n",
    );
    let out = tmp.path().join("out");
    let stdout = ok(&["run", &s, "--out", out.to_str().unwrap()]);
    assert!(stdout.contains("STOPPED at"), "{stdout}");
    let m = metrics(&out);
    let r = run(&m, "second_m6");
    assert_eq!(r["status"], "stopped");
    assert!(
        r["reason"].as_str().unwrap().contains("safety limit"),
        "{}",
        r["reason"]
    );
    // The controller asked for more than the limits before the stop (no
    // limits in the controller here): the counter is of the commanded torque.
    assert!(r["max_torque_ratio"].as_f64().unwrap() > 1.0);
}

/// The three example scenarios of issue #11 run as shipped and show what
/// their comments promise.
#[test]
fn the_drive_examples_run_and_meet_their_targets() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let tmp = tempfile::tempdir().unwrap();
    let go = |name: &str| {
        let out = tmp.path().join(name);
        let file = examples.join(format!("{name}.toml"));
        ok(&[
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let report = std::fs::read_to_string(out.join("report.html")).unwrap();
        assert!(report.contains("Drives, sensors and faults"), "{name}");
        metrics(&out)
    };
    let m = go("drives-saturation");
    for name in ["usual_m0.25", "first_m0.25", "second_m0.25"] {
        let r = run(&m, name);
        assert_eq!(r["status"], "ok", "{name}");
        assert!(
            r["max_torque_ratio"].as_f64().unwrap() <= 1.0 + 1e-9,
            "{name}"
        );
        assert!(r["saturated_samples"].as_u64().unwrap() > 0, "{name}");
    }
    let m = go("drives-friction");
    let second = run(&m, "second_m0.25")["steady_cartesian_error_mm"]
        .as_f64()
        .unwrap();
    assert!(second <= 1e-3, "second steady {second} mm");
    let m = go("drives-faults");
    for name in ["first_m0.25", "second_m0.25"] {
        assert_eq!(run(&m, name)["faults"], 12, "{name}");
        assert_eq!(run(&m, name)["status"], "ok", "{name}");
    }
    assert_eq!(run(&m, "second_m6")["status"], "stopped");
}

/// A plant substep too coarse for its Coulomb friction is warned about, with
/// a substep that resolves it.
#[test]
fn a_coarse_substep_under_friction_is_warned_about() {
    let tmp = tempfile::tempdir().unwrap();
    let s = scenario(
        tmp.path(),
        "controllers = [\"first\"]\n[payload]\nmasses_kg = [0.0]\n[simulation]\nhold_s = 0.3\nsteady_window_s = 0.3\n[plant]\ncoulomb_friction = [1.0]\n",
    );
    let o = ofmpc(&["run", &s, "--out", tmp.path().join("o").to_str().unwrap()]);
    assert!(o.status.success());
    let e = stderr(&o);
    assert!(e.contains("[plant] substep = 0.001 s is coarser"), "{e}");
    assert!(e.contains("use substep = 2.000e-4 s"), "{e}");
}

/// Settings that would silently do nothing are warned about: an observer's
/// friction model without an observer, friction compensation without
/// friction estimates.
#[test]
fn settings_without_effect_are_warned_about() {
    let tmp = tempfile::tempdir().unwrap();
    let zero: String = (1..=6)
        .map(|j| format!("[joints.joint_{j}]\ncoulomb_nm = 0.0\nviscous_nms = 0.0\n"))
        .collect();
    std::fs::write(tmp.path().join("zero.toml"), zero).unwrap();
    let s = scenario(
        tmp.path(),
        "controllers = [\"first\"]\n[robot]\ndrives = \"zero.toml\"\n[payload]\nmasses_kg = [0.0]\n\
         [simulation]\nhold_s = 0.3\nsteady_window_s = 0.3\n\
         [mpc]\nobserver_friction = true\nfriction_compensation = true\n",
    );
    let o = ofmpc(&["run", &s, "--out", tmp.path().join("o").to_str().unwrap()]);
    assert!(o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("observer_friction = true without an observer"),
        "{e}"
    );
    assert!(e.contains("give no friction estimate"), "{e}");
}
