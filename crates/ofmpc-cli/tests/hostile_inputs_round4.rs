//! Hostile inputs, fourth round (issue #36): input files that are named pipes, devices or
//! folders are refused by kind without waiting; XML nested without bound and robots of
//! absurd dimension are refused with the limit named, never a stack overflow or an abort.
//! Large inputs are generated here. Each case asserts the exit status (2), that the command
//! ends within a generous time limit (the point is "no hang": 60 s), and the message.

mod bin;
use bin::*;

use std::fs;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The time a hostile case may take on a loaded machine before it counts as a hang.
const LIMIT: Duration = Duration::from_secs(60);

/// Runs `ofmpc args` in `cwd`; kills it past [`LIMIT`]. Asserts exit status 2 (never a
/// signal or a panic) and returns standard error.
fn refused_in(cwd: &Path, args: &[&str]) -> String {
    let mut child = Command::new(BIN)
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run ofmpc");
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if start.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("ofmpc {args:?} still running after {LIMIT:?}: a hang");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = child.wait_with_output().unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "ofmpc {args:?}: {e}");
    e
}

/// A named pipe with no writer at `p`.
#[cfg(unix)]
fn fifo(p: &Path) {
    assert!(Command::new("mkfifo").arg(p).status().unwrap().success());
}

/// Every reader opens without blocking: a FIFO given as a program, a scenario, a URDF, a
/// drives file or a tool table is refused at once, saying it is a named pipe.
#[cfg(unix)]
#[test]
fn a_fifo_is_refused_by_every_reader() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    for n in ["p.ngc", "s.toml", "r.urdf", "drives.toml", "t.tbl"] {
        fifo(&d.join(n));
    }
    fs::write(d.join("ok.ngc"), "G21 G90\nG0 X500 Y0 Z600\nM30\n").unwrap();
    let urdf = Path::new(env!("CARGO_MANIFEST_DIR")).join("../ofmpc/robots/irb140/irb140.urdf");
    let urdf = urdf.to_str().unwrap();
    let cases: [&[&str]; 6] = [
        &["trajectory", "p.ngc"],
        &["inspect", "program", "p.ngc"],
        &["run", "s.toml"],
        &["inspect", "robot", "--robot", "r.urdf"],
        &[
            "inspect",
            "robot",
            "--robot",
            urdf,
            "--drives",
            "drives.toml",
        ],
        &["inspect", "program", "ok.ngc", "--tool-table", "t.tbl"],
    ];
    for args in cases {
        let e = refused_in(d, args);
        assert!(
            e.contains("it is a named pipe (FIFO), not a regular file"),
            "{args:?}: {e}"
        );
    }
    let e = refused_in(d, &["inspect", "robot", "--robot", "r.urdf"]);
    assert!(e.contains("r.urdf") && e.contains("given as a URDF"), "{e}");
    // A folder is said to be one.
    fs::create_dir(d.join("dir.urdf")).unwrap();
    let e = refused_in(d, &["inspect", "robot", "--robot", "dir.urdf"]);
    assert!(e.contains("it is a folder"), "{e}");
}

/// A URDF of 30 000 (and 300 000) nested unknown elements: refused with the depth limit, the
/// line and the column, not a stack overflow.
#[test]
fn deeply_nested_urdf_is_refused_with_the_limit() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    for levels in [30_000, 300_000] {
        let text = format!(
            "<robot name=\"x\">\n{}{}</robot>\n",
            "<a>".repeat(levels),
            "</a>".repeat(levels)
        );
        fs::write(d.join("deep.urdf"), text).unwrap();
        for args in [
            &["inspect", "robot", "--robot", "deep.urdf"][..],
            &["inspect", "dynamics", "--robot", "deep.urdf", "--q", "0"][..],
        ] {
            let e = refused_in(d, args);
            assert!(
                e.contains("line 2, column 766: elements nested more than 256 deep (the limit"),
                "{e}"
            );
        }
    }
}

/// A 20 000-joint URDF: `inspect dynamics` refuses it before allocating its n×n matrices
/// (3.2 GB each), naming the limit.
#[test]
fn a_robot_of_absurd_dimension_is_refused_before_allocating() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let mut s = String::from("<robot name=\"big\"><link name=\"l0\"/>\n");
    for i in 0..20_000 {
        s += &format!(
            "<link name=\"l{}\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" \
             izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link><joint name=\"j{i}\" \
             type=\"revolute\"><parent link=\"l{i}\"/><child link=\"l{}\"/><axis xyz=\"0 0 1\"/>\
             <limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n",
            i + 1,
            i + 1
        );
    }
    s += "</robot>\n";
    fs::write(d.join("big.urdf"), s).unwrap();
    let e = refused_in(
        d,
        &["inspect", "dynamics", "--robot", "big.urdf", "--q", "0"],
    );
    assert!(
        e.contains("the chain has 20000 moving joints, more than the limit of 1000"),
        "{e}"
    );
}

/// Two `init robot` at once into one folder, 50 times: one complete set of one robot (its
/// drives file and its scenario) and a refusal, never a mix of the two robots' files.
#[test]
fn concurrent_inits_never_mix_their_files() {
    let tmp = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR"));
    let a = data.join("../ofmpc/robots/irb140/irb140.urdf");
    let b = data.join("tests/data/mesh_arm/urdf/mesh_arm.urdf");
    for i in 0..50 {
        let out = tmp.path().join(format!("o{i}"));
        let spawn = |urdf: &Path| {
            Command::new(BIN)
                .args(["init", "robot"])
                .arg(urdf)
                .arg("--out")
                .arg(&out)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        };
        let (ca, cb) = (spawn(&a), spawn(&b));
        let (oa, ob) = (
            ca.wait_with_output().unwrap(),
            cb.wait_with_output().unwrap(),
        );
        let codes = [oa.status.code(), ob.status.code()];
        let wins = codes.iter().filter(|c| **c == Some(0)).count();
        assert!(
            wins >= 1 && codes.iter().all(|c| matches!(c, Some(0) | Some(2))),
            "try {i}: {codes:?} {} {}",
            stderr(&oa),
            stderr(&ob)
        );
        assert_eq!(wins, 1, "try {i}: both said they wrote");
        let drives = fs::read_to_string(out.join("drives.toml")).unwrap();
        let scenario = fs::read_to_string(out.join("scenario.toml")).unwrap();
        let from_a = drives.contains("irb140.urdf");
        assert_eq!(
            from_a,
            scenario.contains("irb140.urdf"),
            "try {i}: a mixed folder"
        );
        assert_eq!(
            !from_a,
            scenario.contains("mesh_arm.urdf"),
            "try {i}: a mixed folder"
        );
        let names: Vec<_> = fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(names.len(), 3, "try {i}: {names:?}"); // drives.toml, scenario.toml, program.gcode
    }
}
