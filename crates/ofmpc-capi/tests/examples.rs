//! The C and C++ examples, compiled with the system's gcc and g++ under
//! AddressSanitizer against the static library, run on the paper's scenario:
//! their Cartesian RMS and steady errors equal `ofmpc run`'s metrics for the
//! same scenario file to 1e-12 relative. Fails (never skips) without gcc/g++.

use ofmpc_scenario::{run_metrics, Scenario, ScenarioFile};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The folder cargo built this test's copy of the library in
/// (target/<profile>/deps: `cargo test` does not copy it up to target/<profile>).
fn lib_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test path");
    let dir = exe.parent().expect("deps folder").to_path_buf();
    assert!(
        dir.join("libofmpc_capi.a").is_file(),
        "{} has no libofmpc_capi.a: build the crate first (cargo build -p ofmpc-capi)",
        dir.display()
    );
    dir
}

/// Compiles `source` with `compiler` (gcc or g++) under ASAN into `out`.
fn compile(compiler: &str, std: &str, source: &str, out: &Path) {
    let lib = lib_dir();
    let status = Command::new(compiler)
        .arg(std)
        .args(["-O1", "-g", "-Wall", "-Wextra", "-Werror", "-fsanitize=address"])
        .arg("-fno-omit-frame-pointer")
        .arg("-I")
        .arg(crate_dir().join("include"))
        .arg(crate_dir().join("examples").join(source))
        .arg(lib.join("libofmpc_capi.a"))
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(out)
        .status()
        .unwrap_or_else(|e| {
            panic!("{compiler} is needed to build the C/C++ examples (apt-get install {compiler}): {e}")
        });
    assert!(status.success(), "{compiler} failed on {source}");
}

/// Runs an example on the paper's scenario; its "key value" lines by label.
fn run(exe: &Path) -> HashMap<String, f64> {
    let scenario = crate_dir().join("examples/paper.toml");
    let gcode = crate_dir().join("../../examples/paper-table1.gcode");
    let out = Command::new(exe)
        .arg(&scenario)
        .arg(&gcode)
        .args(["second", "0.25"])
        .env(
            "ASAN_OPTIONS",
            "detect_leaks=1:abort_on_error=0:exitcode=23",
        )
        .output()
        .expect("the example runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{} failed ({}):\n{stdout}\n{}",
        exe.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
        .lines()
        .filter_map(|l| {
            let (key, value) = l.rsplit_once(' ')?;
            Some((key.to_string(), value.parse().ok()?))
        })
        .collect()
}

/// `ofmpc run`'s metrics of the paper scenario (the CLI's code path).
fn reference() -> ofmpc::RunMetrics {
    let file = ScenarioFile::from_file(&crate_dir().join("examples/paper.toml")).expect("scenario");
    let scenario = Scenario::resolve(&file).expect("resolves");
    let mut runs = run_metrics(&scenario).expect("runs");
    assert_eq!(runs.len(), 1);
    runs.remove(0)
}

fn close(label: &str, got: f64, want: f64) {
    let rel = (got - want).abs() / want.abs().max(f64::MIN_POSITIVE);
    assert!(
        rel <= 1e-12,
        "{label}: {got} vs ofmpc run's {want} (relative {rel:e})"
    );
}

fn compare(prefix: &str, got: &HashMap<String, f64>, m: &ofmpc::RunMetrics) {
    let value = |k: &str| {
        *got.get(&format!("{prefix}{k}"))
            .unwrap_or_else(|| panic!("no {prefix}{k} in the output: {got:?}"))
    };
    let steady_joint = m
        .steady_joint_error_max_rad
        .iter()
        .fold(0.0_f64, |a, b| a.max(*b));
    close(
        "cartesian_error_rms_mm",
        value("cartesian_error_rms_mm"),
        m.cartesian_error_rms_mm,
    );
    close(
        "cartesian_error_max_mm",
        value("cartesian_error_max_mm"),
        m.cartesian_error_max_mm,
    );
    close(
        "steady_cartesian_error_mm",
        value("steady_cartesian_error_mm"),
        m.steady_cartesian_error_mm,
    );
    close(
        "steady_joint_error_max_rad",
        value("steady_joint_error_max_rad"),
        steady_joint,
    );
    assert!(value("step_us_p50") > 0.0 && value("step_us_p99") >= value("step_us_p50"));
}

#[test]
fn the_c_and_cpp_examples_reproduce_ofmpc_run_under_asan() {
    let dir = std::env::temp_dir().join(format!("ofmpc-capi-examples-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (c, cpp) = (dir.join("paper_loop"), dir.join("paper_loop_cpp"));
    compile("gcc", "-std=c11", "paper_loop.c", &c);
    compile("g++", "-std=c++17", "paper_loop.cpp", &cpp);
    let m = reference();
    assert!(m.cartesian_error_rms_mm > 0.0 && m.steady_cartesian_error_mm > 0.0);
    compare("", &run(&c), &m);
    let out = run(&cpp);
    compare("direct ", &out, &m);
    compare("ros2 ", &out, &m);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The C++ wrapper's gains getter and its step with the predicted command
/// (issue 37; `examples/gains_and_command.cpp`), under ASAN.
#[test]
fn the_cpp_wrapper_gives_the_gains_and_the_command() {
    let dir = std::env::temp_dir().join(format!("ofmpc-gains-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exe = dir.join("gains_and_command");
    compile("g++", "-std=c++17", "gains_and_command.cpp", &exe);
    let out = Command::new(&exe)
        .env(
            "ASAN_OPTIONS",
            "detect_leaks=1:abort_on_error=0:exitcode=23",
        )
        .output()
        .expect("the example runs");
    assert!(
        out.status.success(),
        "{} failed ({}):\n{}\n{}",
        exe.display(),
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The C++ wrapper's supervised step with the command (issue 37;
/// `examples/supervised_stop.cpp`), under ASAN: an encoder slip at 3 s on
/// the paper's path passes the safety limit, and the command through the
/// wrapper is the stop law's braking trajectory — it never speeds up, ends
/// below 1e-6 rad/s with the status `STOPPED`, where the controller's last
/// command moved at over 0.1 rad/s.
#[test]
fn the_cpp_wrapper_commands_a_braking_position_during_a_safe_stop() {
    let dir = std::env::temp_dir().join(format!("ofmpc-stop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exe = dir.join("supervised_stop");
    compile("g++", "-std=c++17", "supervised_stop.cpp", &exe);
    let out = Command::new(&exe)
        .arg(crate_dir().join("../../examples/paper-table1.gcode"))
        .env(
            "ASAN_OPTIONS",
            "detect_leaks=1:abort_on_error=0:exitcode=23",
        )
        .output()
        .expect("the example runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{} failed ({}):\n{stdout}\n{}",
        exe.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("stop at 3."), "{stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}
