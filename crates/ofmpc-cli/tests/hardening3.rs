//! The `ofmpc` binary against the third round of hostile cases (issue #22): each test checks the
//! exit status, the message and the file system before and after.

mod bin;
use bin::*;

use std::collections::BTreeMap;
use std::fs;
use std::path::Path;
use std::process::{Command, Stdio};

/// Every file under `dir` (recursive, hidden ones too) with its bytes; folders as `<dir>`.
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        let Ok(entries) = fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            let rel = p.strip_prefix(root).unwrap().display().to_string();
            let t = e.file_type().unwrap();
            if t.is_dir() {
                out.insert(rel, b"<dir>".to_vec());
                walk(root, &p, out);
            } else if t.is_symlink() {
                out.insert(rel, b"<link>".to_vec());
            } else {
                out.insert(rel, fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Exit status 2, no panic; returns stderr.
fn fails_in(cwd: &Path, args: &[&str]) -> String {
    let o = ofmpc_in(cwd, args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "ofmpc {args:?}: {err}");
    err
}

/// A G-code program: one short move.
const PROGRAM: &str = "G21 G90\nG0 X500 Y0 Z600\nG1 X510 F3000\nM30\n";

/// Item 2: `tune --out` never replaces its own program, and a figure that cannot be written
/// changes nothing (the scenario file is not replaced first); `analyze` likewise.
#[test]
fn tune_and_analyze_use_the_staged_checked_output() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    fs::write(d.join("p.gcode"), PROGRAM).unwrap();
    // --out is the program.
    let before = snapshot(d);
    let e = fails_in(
        d,
        &[
            "tune",
            "--payload-range",
            "0,1",
            "--controllers",
            "second",
            "--program",
            "p.gcode",
            "--out",
            "p.gcode",
        ],
    );
    assert!(e.contains("is the program of this run"), "{e}");
    assert_eq!(snapshot(d), before);
    // An earlier scenario stays when the figure cannot go where it should (a folder is there).
    fs::write(d.join("t.toml"), "# mine\n").unwrap();
    fs::create_dir(d.join("t_tradeoff.png")).unwrap();
    let before = snapshot(d);
    let e = fails_in(
        d,
        &[
            "tune",
            "--payload-range",
            "0,1",
            "--controllers",
            "second",
            "--program",
            "p.gcode",
            "--out",
            "t.toml",
        ],
    );
    assert!(e.contains("t_tradeoff.png is a folder"), "{e}");
    assert_eq!(snapshot(d), before);
    // analyze: the program in the output folder under the figure's name is never replaced.
    fs::write(d.join("stability.svg"), PROGRAM).unwrap();
    let before = snapshot(d);
    let e = fails_in(
        d,
        &[
            "analyze",
            "stability",
            "--controllers",
            "second",
            "--program",
            "stability.svg",
            "--out",
            ".",
        ],
    );
    assert!(e.contains("is the program of this run"), "{e}");
    assert_eq!(snapshot(d), before);
}

/// A pipe whose reader has gone: every write to it fails with EPIPE.
fn closed_pipe() -> Stdio {
    let mut reader = Command::new(BIN)
        .arg("--version")
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let w = reader.stdin.take().unwrap();
    assert!(reader.wait().unwrap().success());
    Stdio::from(w)
}

/// Item 4: `analyze stability | true` and `tune | true` end quietly with status 0, their files
/// written.
#[test]
fn analyze_and_tune_into_a_closed_pipe_stop_quietly() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    fs::write(d.join("p.gcode"), PROGRAM).unwrap();
    for args in [
        vec![
            "analyze",
            "stability",
            "--controllers",
            "second",
            "--program",
            "p.gcode",
            "--out",
            "a",
        ],
        vec![
            "tune",
            "--payload-range",
            "0,1",
            "--controllers",
            "second",
            "--program",
            "p.gcode",
            "--out",
            "t.toml",
        ],
    ] {
        let o = Command::new(BIN)
            .args(&args)
            .current_dir(d)
            .stdin(Stdio::null())
            .stdout(closed_pipe())
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
    }
    assert!(d.join("a/stability.png").is_file());
    assert!(d.join("t.toml").is_file() && d.join("t_tradeoff.svg").is_file());
    let hidden: Vec<String> = snapshot(d)
        .into_keys()
        .filter(|k| k.contains(".ofmpc"))
        .collect();
    assert!(hidden.is_empty(), "{hidden:?}");
}
