//! Running the `ofmpc` binary from the CLI tests: one copy of the helpers
//! every end-to-end test file uses.

#![allow(dead_code)]

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output, Stdio};

/// The binary under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_ofmpc");

/// Runs `ofmpc args` in `cwd` with no standard input.
pub fn ofmpc_in(cwd: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .output()
        .expect("run ofmpc")
}

/// Runs `ofmpc args` in the current directory with no standard input.
pub fn ofmpc(args: &[&str]) -> Output {
    ofmpc_in(Path::new("."), args)
}

/// Its standard error, which never reports a panic.
pub fn stderr(o: &Output) -> String {
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!e.contains("panicked"), "{e}");
    e
}

/// Runs and asserts success; returns standard output.
pub fn ok(args: &[&str]) -> String {
    let o = ofmpc(args);
    assert!(
        o.status.success(),
        "ofmpc {args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Runs and asserts failure without a panic; returns standard error.
pub fn fails(args: &[&str]) -> String {
    let o = ofmpc(args);
    assert!(!o.status.success(), "ofmpc {args:?} should fail");
    stderr(&o)
}

/// `dir/metrics.json`, parsed.
pub fn metrics(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap()).unwrap()
}

/// The run named `name` in a parsed metrics.json.
pub fn run<'a>(m: &'a Value, name: &str) -> &'a Value {
    m["runs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["name"] == name)
        .unwrap_or_else(|| panic!("no run {name}"))
}

/// The largest entry of a JSON array of numbers (0 for an empty one).
pub fn max_of(v: &Value) -> f64 {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .fold(0.0, f64::max)
}
