//! The library's typed errors and run outcomes reach the CLI's
//! user as the scenario's words, with exit statuses that scripts can rely on
//! (0 ok or diverged, 1 some run failed, 2 nothing was run).

mod bin;
use bin::*;

use serde_json::Value;
use std::path::Path;

fn scenario(dir: &Path, body: &str) -> String {
    let p = dir.join("s.toml");
    std::fs::write(&p, body).unwrap();
    p.display().to_string()
}

/// A hold of 1e6 s and a substep of 1e-300 are rejected
/// before anything is allocated or integrated, naming the key, the count and
/// the limit.
#[test]
fn absurd_sample_counts_and_substeps_are_rejected_up_front() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let s = scenario(
        tmp.path(),
        "[simulation]\nhold_s = 1e6\nsteady_window_s = 0.5\n",
    );
    let o = ofmpc(&["run", &s, "--out", out.to_str().unwrap()]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("hold_s") && e.contains("100000000") && e.contains("limit"),
        "{e}"
    );
    assert!(!out.exists());
    for (substep, needle) in [
        ("1e-300", "whole number"),
        ("1e-9", "whole number"),
        ("0.003", "e.g. 3.333e-3"),
    ] {
        let s = scenario(tmp.path(), &format!("[plant]\nsubstep = {substep}\n"));
        let o = ofmpc(&["run", &s, "--out", out.to_str().unwrap()]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{e}");
        assert!(
            e.contains("[plant] substep") && e.contains(needle),
            "{substep}: {e}"
        );
    }
    assert!(!out.exists());
}

/// A non-finite result is an error, not `null` with exit 0.
#[test]
fn inspect_dynamics_refuses_overflowing_results() {
    let o = ofmpc(&[
        "inspect",
        "dynamics",
        "--q",
        "0,0,0,0,0,0",
        "--qd",
        "1e160,0,0,0,0,0",
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("not finite"), "{e}");
    assert!(o.stdout.is_empty());
}

/// An absurd payload is blamed on the payload, a tiny one gets a
/// bounded folder name.
#[test]
fn payload_messages_and_names() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o");
    let o = ofmpc(&[
        "reproduce",
        "--payload",
        "1e20",
        "--out",
        out.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("payload") && e.contains("1e20") && !e.contains("inertials"),
        "{e}"
    );
    let s = scenario(tmp.path(), "controllers = [\"first\"]\n[payload]\nmasses_kg = [1e-300]\n[simulation]\nhold_s = 0.5\nsteady_window_s = 0.5\n");
    let o = ofmpc(&["run", &s, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("first_m1e-300").join("timeseries.csv").is_file());
}

/// A run that fails numerically is "failed" with a reason, its
/// missing metrics are null (never 0), the others keep their results, and the
/// exit status is 1; a diverged run is a result (status 0).
#[test]
fn failed_and_diverged_runs_are_typed_in_metrics_and_exit_status() {
    let tmp = tempfile::tempdir().unwrap();
    // 6 kg unknown: the second algorithm diverges with the paper's tuning.
    let base = "controllers = [\"usual\", \"second\"]\n[payload]\nmasses_kg = [6.0]\n[simulation]\nhold_s = 0.5\nsteady_window_s = 0.5\n";
    let out = tmp.path().join("diverged");
    let s = scenario(tmp.path(), base);
    let o = ofmpc(&["run", &s, "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let m: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    let runs = m["runs"].as_array().unwrap();
    let by = |name: &str| runs.iter().find(|r| r["name"] == name).unwrap().clone();
    let usual = by("usual_m6");
    assert_eq!(usual["status"], "ok");
    assert!(usual["reason"].as_str().unwrap().contains("completed"));
    let second = by("second_m6");
    assert_eq!(second["status"], "diverged");
    assert_eq!(second["diverged"], true);
    assert!(second["reason"]
        .as_str()
        .unwrap()
        .contains("divergence threshold"));
    assert!(second["steady_cartesian_error_mm"].is_null());
    assert!(second["cartesian_error_rms_mm"].as_f64().unwrap() > 0.0);

    // The same without a divergence threshold: the state grows until the
    // plant's integration fails.
    let out = tmp.path().join("failed");
    let s = scenario(
        tmp.path(),
        &base.replace(
            "hold_s = 0.5",
            "hold_s = 0.5\ndivergence_threshold_rad = 1e300",
        ),
    );
    let o = ofmpc(&["run", &s, "--out", out.to_str().unwrap()]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("second_m6") && e.contains("failed"), "{e}");
    let m: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    let runs = m["runs"].as_array().unwrap();
    let second = runs.iter().find(|r| r["name"] == "second_m6").unwrap();
    assert_eq!(second["status"], "failed", "{second}");
    assert_eq!(second["diverged"], false);
    assert!(second["stopped_at_s"].as_f64().unwrap() > 0.0);
    assert!(second["steady_cartesian_error_mm"].is_null());
    assert!(second["steady_joint_error_max_rad"]
        .as_array()
        .unwrap()
        .iter()
        .all(Value::is_null));
    let usual = runs.iter().find(|r| r["name"] == "usual_m6").unwrap();
    assert_eq!(usual["status"], "ok");
}
