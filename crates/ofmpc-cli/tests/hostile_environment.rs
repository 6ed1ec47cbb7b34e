//! The `ofmpc` binary against a hostile environment: closed pipes, repeated runs,
//! devices and links where files go, inputs in the output folder, conflicts at the final move,
//! signals, concurrent runs, relative paths, earlier results, bad option values. Each test checks
//! the exit status, the message and the file system before and after.

mod bin;
mod signals;
use bin::*;

use serde_json::Value;
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Exit status 2, no panic, and the message on stderr.
fn fails_in(cwd: &Path, args: &[&str]) -> String {
    let o = ofmpc_in(cwd, args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "ofmpc {args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

fn ok_in(cwd: &Path, args: &[&str]) -> Output {
    let o = ofmpc_in(cwd, args);
    assert!(o.status.success(), "ofmpc {args:?}: {}", stderr(&o));
    o
}

/// Every entry under `dir` (recursive, hidden ones too) with its content (files), `<dir>`,
/// `-> target` (links) or `<other>`: a snapshot to compare before and after.
fn snapshot(dir: &Path) -> BTreeMap<String, String> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, String>) {
        let Ok(entries) = fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            let rel = p.strip_prefix(root).unwrap().display().to_string();
            let t = e.file_type().unwrap();
            if t.is_symlink() {
                out.insert(rel, format!("-> {}", fs::read_link(&p).unwrap().display()));
            } else if t.is_dir() {
                out.insert(rel, "<dir>".into());
                walk(root, &p, out);
            } else if t.is_file() {
                let bytes = fs::read(&p).unwrap();
                out.insert(rel, String::from_utf8_lossy(&bytes).into_owned());
            } else {
                out.insert(rel, "<other>".into());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Hidden names the output layer uses (stages, temporaries, lock) found under `dir`.
fn hidden_leftovers(dir: &Path) -> Vec<String> {
    snapshot(dir)
        .into_keys()
        .filter(|k| k.split('/').any(|c| c.starts_with(".ofmpc")))
        .collect()
}

/// A quick scenario: one controller, the given masses, a short hold.
fn quick_scenario(dir: &Path, name: &str, extra: &str) -> PathBuf {
    let p = dir.join(name);
    fs::write(
        &p,
        format!(
            "# my scenario, with a comment that must survive\ncontrollers = [\"usual\"]\n{extra}\n\
             [simulation]\nhold_s = 0.2\nsteady_window_s = 0.1\n"
        ),
    )
    .unwrap();
    p
}

fn metrics_names(out: &Path) -> Vec<String> {
    let m: Value =
        serde_json::from_str(&fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    m["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["name"].as_str().unwrap().to_string())
        .collect()
}

/// Item 1: a closed stdout ends the command quietly with status 0 (like ripgrep), no panic.
/// The pipe's read end is closed before the command starts (it belonged to a process that has
/// exited), so the first write fails with EPIPE every time.
#[test]
fn closed_stdout_stops_quietly() {
    let tmp = tempfile::tempdir().unwrap();
    let closed_pipe = || {
        let mut reader = Command::new(BIN)
            .arg("--version")
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .spawn()
            .unwrap();
        let w = reader.stdin.take().unwrap();
        assert!(reader.wait().unwrap().success());
        Stdio::from(w)
    };
    let out = tmp.path().join("o");
    for args in [
        vec!["--help"],
        vec!["reproduce", "--help"],
        vec!["inspect", "robot"],
        vec!["inspect", "dynamics", "--q", "0,0,0,0,0,0"],
        vec!["trajectory", "paper", "--ts", "0.05"],
        vec![
            "reproduce",
            "--payload",
            "0",
            "--out",
            out.to_str().unwrap(),
        ],
    ] {
        let o = Command::new(BIN)
            .args(&args)
            .current_dir(tmp.path())
            .stdin(Stdio::null())
            .stdout(closed_pipe())
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?} printed: {err}");
    }
    // The run's files were complete before the summary was printed.
    assert_eq!(metrics_names(&out).len(), 3);
    assert!(tmp.path().join("ofmpc-out/reference.csv").is_file());
    assert!(hidden_leftovers(tmp.path()).is_empty());
}

/// Item 9: repeated payloads (also -0 and 0) and controllers run once, with a warning; the
/// written scenario lists each once.
#[test]
fn repeated_payloads_and_controllers_run_once() {
    let tmp = tempfile::tempdir().unwrap();
    let s = quick_scenario(
        tmp.path(),
        "s.toml",
        "[payload]\nmasses_kg = [-0.0, 0.0, 0.25, 0.25]",
    );
    let text = fs::read_to_string(&s)
        .unwrap()
        .replace("[\"usual\"]", "[\"usual\", \"second\", \"usual\"]");
    fs::write(&s, text).unwrap();
    let out = tmp.path().join("o");
    let o = ok_in(
        tmp.path(),
        &["run", s.to_str().unwrap(), "--out", out.to_str().unwrap()],
    );
    let err = stderr(&o);
    assert!(
        err.contains("warning: the payload 0 kg is listed more than once"),
        "{err}"
    );
    assert!(
        err.contains("payload 0.25 kg is listed more than once"),
        "{err}"
    );
    assert!(err.contains("\"usual\" is listed more than once"), "{err}");
    let mut names = metrics_names(&out);
    names.sort();
    assert_eq!(
        names,
        ["second_m0", "second_m0.25", "usual_m0", "usual_m0.25"]
    );
    assert!(!out.join("usual_m-0").exists());
    let written: toml::Value =
        toml::from_str(&fs::read_to_string(out.join("scenario.toml")).unwrap()).unwrap();
    assert_eq!(
        written["payload"]["masses_kg"].as_array().unwrap(),
        &[toml::Value::Float(0.0), toml::Value::Float(0.25)]
    );
    assert_eq!(written["controllers"].as_array().unwrap().len(), 2);
}

/// Item 10: a device, FIFO, socket, folder or symbolic link where a file goes is refused before
/// anything is written; nothing is created beside it.
#[test]
fn special_files_at_the_output_path_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // A character device (readable by anyone; as root the old code replaced it).
    let e = fails_in(d, &["trajectory", "paper", "--out", "/dev/null"]);
    assert!(
        e.contains("/dev/null is a character device") && e.contains("nothing was written"),
        "{e}"
    );
    use std::os::unix::fs::FileTypeExt;
    assert!(fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
    assert!(fs::read_dir("/dev")
        .unwrap()
        .flatten()
        .all(|e| !e.file_name().to_string_lossy().starts_with(".ofmpc")));

    // A FIFO (a writer would block forever), a socket, a folder, a symbolic link.
    let fifo = d.join("fifo.csv");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let _sock = std::os::unix::net::UnixListener::bind(d.join("sock.csv")).unwrap();
    fs::create_dir(d.join("dir.csv")).unwrap();
    fs::write(d.join("elsewhere.csv"), "precious").unwrap();
    std::os::unix::fs::symlink(d.join("elsewhere.csv"), d.join("link.csv")).unwrap();
    let before = snapshot(d);
    for (name, what) in [
        ("fifo.csv", "is a named pipe (FIFO)"),
        ("sock.csv", "is a socket"),
        ("dir.csv", "is a folder"),
        ("link.csv", "is a symbolic link to"),
    ] {
        let out = d.join(name);
        let e = fails_in(d, &["trajectory", "paper", "--out", out.to_str().unwrap()]);
        assert!(e.contains(name) && e.contains(what), "{name}: {e}");
        assert_eq!(snapshot(d), before, "{name}");
    }
    // The same for a run folder and for a file of the run.
    let out = d.join("o");
    fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(d.join("elsewhere.csv"), out.join("metrics.json")).unwrap();
    let before = snapshot(d);
    let e = fails_in(d, &["reproduce", "--out", out.to_str().unwrap()]);
    assert!(e.contains("metrics.json is a symbolic link"), "{e}");
    assert_eq!(snapshot(d), before);
    let e = fails_in(
        d,
        &[
            "reproduce",
            "--out",
            d.join("elsewhere.csv").to_str().unwrap(),
        ],
    );
    assert!(e.contains("is a file, not a folder"), "{e}");
    assert_eq!(snapshot(d), before);
    // An output folder given as a symbolic link to a folder: followed, and said so.
    fs::create_dir(d.join("real_out")).unwrap();
    std::os::unix::fs::symlink(d.join("real_out"), d.join("out_link")).unwrap();
    let o = ok_in(
        d,
        &[
            "trajectory",
            "paper",
            "--ts",
            "0.05",
            "--out",
            "out_link/r.csv",
        ],
    );
    let err = stderr(&o);
    assert!(
        err.contains("out_link is a symbolic link to") && err.contains("real_out"),
        "{err}"
    );
    assert!(d.join("real_out/r.csv").is_file());
    assert!(fs::symlink_metadata(d.join("out_link"))
        .unwrap()
        .file_type()
        .is_symlink());
}

/// Item 11: the outputs never replace an input of the same run.
#[test]
fn inputs_are_never_overwritten() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let s = quick_scenario(d, "scenario.toml", "");
    let before = snapshot(d);
    let e = fails_in(d, &["run", "scenario.toml", "--out", "."]);
    assert!(
        e.contains("scenario.toml is the scenario file of this run") && e.contains("never"),
        "{e}"
    );
    assert_eq!(snapshot(d), before);
    assert!(fs::read_to_string(&s).unwrap().contains("# my scenario"));

    let g = d.join("p.gcode");
    fs::write(&g, ofmpc::gcode::PAPER_TABLE1).unwrap();
    let before = snapshot(d);
    let e = fails_in(d, &["trajectory", "p.gcode", "--out", "p.gcode"]);
    assert!(e.contains("p.gcode is the program of this run"), "{e}");
    assert_eq!(snapshot(d), before);
    // The program given as a scenario's input, in the output folder under an output's name.
    fs::write(d.join("metrics.json"), ofmpc::gcode::PAPER_TABLE1).unwrap();
    let s2 = quick_scenario(d, "s2.toml", "[program]\nfile = \"metrics.json\"");
    let before = snapshot(d);
    let e = fails_in(d, &["run", s2.to_str().unwrap(), "--out", "."]);
    assert!(e.contains("metrics.json is the program of this run"), "{e}");
    assert_eq!(snapshot(d), before);
}

/// Item 12: every destination is checked before the first move; on a conflict nothing moves
/// and nothing is computed.
#[test]
fn a_conflict_moves_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o");
    fs::create_dir(&out).unwrap();
    fs::write(out.join("usual_m0"), "a file where a run folder goes").unwrap();
    fs::create_dir(out.join("report.html")).unwrap();
    let before = snapshot(tmp.path());
    let e = fails_in(tmp.path(), &["reproduce", "--out", out.to_str().unwrap()]);
    assert!(
        e.contains("usual_m0 is a file, where this run writes a folder")
            && e.contains("report.html is a folder, where this run writes a file"),
        "{e}"
    );
    assert_eq!(snapshot(tmp.path()), before);
}

/// Waits (bounded, generously) until `cond` holds; panics with `what` otherwise.
fn wait_for(what: &str, mut cond: impl FnMut() -> bool) {
    let deadline = Instant::now() + Duration::from_secs(120);
    while !cond() {
        assert!(Instant::now() < deadline, "gave up waiting for {what}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A long run (a payload sweep) into `out`, started in the background.
fn long_run(cwd: &Path, out: &Path) -> Child {
    signals::with_default_signals(&mut Command::new(BIN))
        .args([
            "reproduce",
            "--payload",
            "0,0.25,0.5,1,2,4,0.1,0.2,0.3,0.4",
            "--out",
            out.to_str().unwrap(),
        ])
        .current_dir(cwd)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn kill(child: &Child, sig: &str) {
    assert!(Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .unwrap()
        .success());
}

/// Items 13 and 14: a second run into a busy folder fails at once and names the first; SIGINT
/// and SIGTERM remove the stage and the lock (and a folder the run created) and exit 130 / 143.
#[test]
fn concurrent_runs_and_signals() {
    let tmp = tempfile::tempdir().unwrap();
    for (sig, code) in [("-INT", 130), ("-TERM", 143)] {
        let out = tmp.path().join(format!("o{code}"));
        let first = long_run(tmp.path(), &out);
        wait_for("the stage folder", || {
            hidden_leftovers(&out)
                .iter()
                .any(|n| n.starts_with(".ofmpc-stage-"))
        });
        let lock = fs::read_to_string(out.join(".ofmpc-lock")).unwrap();
        assert_eq!(lock.trim(), first.id().to_string());
        let e = fails_in(tmp.path(), &["reproduce", "--out", out.to_str().unwrap()]);
        assert!(
            e.contains(&format!("in use by process {}", first.id())),
            "{e}"
        );
        kill(&first, sig);
        let o = first.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(code), "{}", stderr(&o));
        assert!(!out.exists(), "{:?}", snapshot(&out));
    }
    // Into a folder that existed: it stays, with exactly its old content.
    let out = tmp.path().join("kept");
    fs::create_dir(&out).unwrap();
    fs::write(out.join("notes.txt"), "mine").unwrap();
    let before = snapshot(&out);
    let run = long_run(tmp.path(), &out);
    wait_for("the lock", || out.join(".ofmpc-lock").exists());
    kill(&run, "-TERM");
    assert_eq!(run.wait_with_output().unwrap().status.code(), Some(143));
    assert_eq!(snapshot(&out), before);
}

/// Item 13: stale stages and locks of dead processes are removed by the next run (with a note);
/// a lock held by a live process is respected.
#[test]
fn stale_stages_and_locks_are_removed() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o");
    fs::create_dir(&out).unwrap();
    let mut dead = Command::new(BIN)
        .arg("--version")
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let dead_pid = dead.id();
    dead.wait().unwrap();
    let stage = out.join(format!(".ofmpc-stage-{dead_pid}-0"));
    fs::create_dir_all(stage.join("usual_m0")).unwrap();
    fs::write(stage.join("usual_m0/timeseries.csv"), vec![b'x'; 1 << 20]).unwrap();
    fs::write(
        out.join(format!(".ofmpc-tmp-{dead_pid}-3-metrics.json")),
        "{",
    )
    .unwrap();
    fs::write(out.join(".ofmpc-lock"), format!("{dead_pid}\n")).unwrap();
    // A stage of a live process (this test) is not touched.
    let live = out.join(format!(".ofmpc-stage-{}-0", std::process::id()));
    fs::create_dir(&live).unwrap();
    let s = quick_scenario(tmp.path(), "s.toml", "[payload]\nmasses_kg = [0.0]");
    let o = ok_in(
        tmp.path(),
        &["run", s.to_str().unwrap(), "--out", out.to_str().unwrap()],
    );
    let err = stderr(&o);
    assert!(
        err.contains("note: removed") && err.contains(&format!(".ofmpc-stage-{dead_pid}-0")),
        "{err}"
    );
    assert_eq!(
        hidden_leftovers(&out),
        [format!(".ofmpc-stage-{}-0", std::process::id())]
    );
    assert_eq!(metrics_names(&out), ["usual_m0"]);

    // A lock of a live process: refused, named, nothing changes.
    fs::write(out.join(".ofmpc-lock"), format!("{}\n", std::process::id())).unwrap();
    let before = snapshot(tmp.path());
    let e = fails_in(
        tmp.path(),
        &["run", s.to_str().unwrap(), "--out", out.to_str().unwrap()],
    );
    assert!(
        e.contains(&format!("in use by process {}", std::process::id())),
        "{e}"
    );
    assert_eq!(snapshot(tmp.path()), before);
}

/// Item 15: paths in a scenario are relative to the scenario file, and the written scenario
/// re-runs from any working directory.
#[test]
fn written_scenario_reruns_from_anywhere() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    fs::create_dir_all(d.join("ex")).unwrap();
    fs::create_dir_all(d.join("elsewhere/deeper")).unwrap();
    fs::write(d.join("ex/p.gcode"), ofmpc::gcode::PAPER_TABLE1).unwrap();
    ok_in(
        d,
        &[
            "reproduce",
            "--program",
            "ex/p.gcode",
            "--payload",
            "0",
            "--out",
            "rt",
        ],
    );
    let again = ok_in(
        &d.join("elsewhere/deeper"),
        &["run", "../../rt/scenario.toml", "--out", "again"],
    );
    assert!(again.status.success());
    assert_eq!(
        metrics_names(&d.join("elsewhere/deeper/again")),
        metrics_names(&d.join("rt"))
    );
    // A scenario next to its program and robot (a model path without .urdf), run from elsewhere.
    let robots = Path::new(env!("CARGO_MANIFEST_DIR")).join("../ofmpc/robots/irb140");
    fs::create_dir_all(d.join("proj")).unwrap();
    fs::copy(robots.join("irb140.urdf"), d.join("proj/arm.model")).unwrap();
    fs::copy(robots.join("drives.toml"), d.join("proj/drives.toml")).unwrap();
    fs::copy(d.join("ex/p.gcode"), d.join("proj/p.gcode")).unwrap();
    quick_scenario(
        &d.join("proj"),
        "s.toml",
        "[robot]\nmodel = \"arm.model\"\ndrives = \"drives.toml\"\n[payload]\nmasses_kg = [0.0]\n\
         [program]\nfile = \"p.gcode\"",
    );
    ok_in(
        &d.join("elsewhere"),
        &["run", "../proj/s.toml", "--out", "o"],
    );
    ok_in(
        &d.join("elsewhere/deeper"),
        &["run", "../o/scenario.toml", "--out", "o2"],
    );
    assert_eq!(metrics_names(&d.join("elsewhere/deeper/o2")), ["usual_m0"]);
}

/// Item 16: results of an earlier run in the folder are named in a warning; metrics.json lists
/// only this run.
#[test]
fn earlier_results_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o");
    fs::create_dir_all(out.join("first_m1")).unwrap();
    fs::write(out.join("first_m1/timeseries.csv"), "t\n").unwrap();
    fs::write(out.join("joint_errors_m1.png"), "old").unwrap();
    fs::write(out.join("payload_sweep.svg"), "old").unwrap();
    fs::write(out.join("my_notes.txt"), "mine").unwrap();
    let s = quick_scenario(tmp.path(), "s.toml", "[payload]\nmasses_kg = [0.0]");
    let o = ok_in(
        tmp.path(),
        &["run", s.to_str().unwrap(), "--out", out.to_str().unwrap()],
    );
    let err = stderr(&o);
    assert!(
        err.contains("results of an earlier run")
            && err.contains("first_m1/, joint_errors_m1.png, payload_sweep.svg")
            && !err.contains("my_notes"),
        "{err}"
    );
    assert_eq!(metrics_names(&out), ["usual_m0"]);
    let report = fs::read_to_string(out.join("report.html")).unwrap();
    assert!(!report.contains("first_m1") && !report.contains("joint_errors_m1."));
    assert_eq!(
        fs::read_to_string(out.join("my_notes.txt")).unwrap(),
        "mine"
    );
}

/// Item 17 (part): option values name what they need; `trajectory` has a default --out.
#[test]
fn option_messages_and_trajectory_default_out() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let e = fails_in(d, &["trajectory", "paper", "--origin", "1,2"]);
    assert!(
        e.contains("--origin has 2 values but needs 3") && e.contains("x,y,z in mm"),
        "{e}"
    );
    assert!(!e.contains("joints"), "{e}");
    let e = fails_in(d, &["trajectory", "paper", "--rpy", "0"]);
    assert!(
        e.contains("--rpy has 1 value but needs 3: roll,pitch,yaw"),
        "{e}"
    );
    assert!(snapshot(d).is_empty());
    let help = String::from_utf8_lossy(&ok_in(d, &["trajectory", "--help"]).stdout).into_owned();
    assert!(
        help.contains("[default: ofmpc-out/reference.csv]"),
        "{help}"
    );
    ok_in(d, &["trajectory", "paper", "--ts", "0.05"]);
    let mut names: Vec<String> = snapshot(d).into_keys().collect();
    names.sort();
    assert_eq!(
        names,
        [
            "ofmpc-out",
            "ofmpc-out/reference.csv",
            "ofmpc-out/reference_cartesian.png",
            "ofmpc-out/reference_cartesian.svg",
            "ofmpc-out/reference_path.png",
            "ofmpc-out/reference_path.svg",
            "ofmpc-out/reference_speed.png",
            "ofmpc-out/reference_speed.svg"
        ]
    );
}

/// Item 20 (units): `--help` of the commands that write CSV states the columns' SI units.
#[test]
fn help_states_csv_units() {
    let tmp = tempfile::tempdir().unwrap();
    for cmd in ["run", "reproduce"] {
        let help =
            String::from_utf8_lossy(&ok_in(tmp.path(), &[cmd, "--help"]).stdout).into_owned();
        for unit in ["t (s)", "(rad)", "(rad/s", "(N·m", "flange position (m"] {
            assert!(help.contains(unit), "{cmd} --help lacks {unit}: {help}");
        }
    }
    let help =
        String::from_utf8_lossy(&ok_in(tmp.path(), &["trajectory", "--help"]).stdout).into_owned();
    for unit in ["t in s", "x,y,z in m", "q in rad", "qd in rad/s"] {
        assert!(help.contains(unit), "trajectory --help lacks {unit}");
    }
}
