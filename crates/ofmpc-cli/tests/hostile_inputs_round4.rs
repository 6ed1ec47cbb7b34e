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
    let (code, e) = within_limit(cwd, args);
    assert_eq!(code, Some(2), "ofmpc {args:?}: {e}");
    e
}

/// Runs `ofmpc args` in `cwd` as [`refused_in`] does; asserts exit status 0 and returns
/// standard error (the warnings).
fn accepted_in(cwd: &Path, args: &[&str]) -> String {
    let (code, e) = within_limit(cwd, args);
    assert_eq!(code, Some(0), "ofmpc {args:?}: {e}");
    e
}

/// Runs `ofmpc args` in `cwd`, killed past [`LIMIT`] (a hang fails the test): the exit
/// status (`None` for a signal) and standard error.
fn within_limit(cwd: &Path, args: &[&str]) -> (Option<i32>, String) {
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
    (o.status.code(), stderr(&o))
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

/// Programs that expand without bound from a few lines (a tiny peck over 100 m, L1000000
/// under G91, a loop that prints 20 kB or records an M3 two million times, a loop of 300 000
/// moves): every command refuses them quickly, naming the limit and the line, never an
/// abort on memory.
#[test]
fn programs_that_expand_are_refused_with_the_limit_and_the_line() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let long = "x".repeat(19_900);
    let cases = [
        ("g83.ngc", "G21 G90\nG0 X0 Y0 Z5\nG83 X0 Y0 Z-100000 R1 Q0.0001\nM2\n".to_string(), 3, "250000 moves (the limit)"),
        ("g73.ngc", "G21 G90\nG0 X0 Y0 Z5\nG73 X0 Y0 Z-100000 R1 Q0.0001\nM2\n".to_string(), 3, "250000 moves (the limit)"),
        ("g81.ngc", "G21 G91\nG81 X0.001 Y0 Z-1 R1 L1000000\nM2\n".to_string(), 2, "250000 moves (the limit)"),
        ("print.ngc", format!("G0 X0 Y0 Z0\n#1=0\no1 while [#1 LT 2000000]\n(PRINT,{long})\n#1=[#1+1]\no1 endwhile\nM2\n"), 4, "16 MB of messages"),
        ("m3.ngc", "G0 X0 Y0 Z0\n#1=0\no1 while [#1 LT 2000000]\nM3 S1000\n#1=[#1+1]\no1 endwhile\nM2\n".to_string(), 4, "250000 events"),
        ("moves.ngc", "G21 G91\n#1=0\no1 while [#1 LT 300000]\nG1 X0.001 F1000\n#1=[#1+1]\no1 endwhile\nM2\n".to_string(), 4, "250000 moves (the limit)"),
    ];
    for (name, text, line, limit) in cases {
        fs::write(d.join(name), text).unwrap();
        for cmd in [
            vec!["inspect", "program", name],
            vec!["trajectory", name, "--out", "t/r.csv"],
        ] {
            let e = refused_in(d, &cmd);
            assert!(
                e.contains(&format!("{name}: line {line}, column 1:")) && e.contains(limit),
                "{cmd:?}: {e}"
            );
            assert!(e.len() < 1000, "{cmd:?}: {} bytes", e.len());
        }
    }
}

/// A syntax error on an O-word's opening line is reported at that line (it was reported at
/// the closer as "without its opening statement").
#[test]
fn a_syntax_error_on_an_o_word_opener_is_reported_at_its_line() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    for (opener, closer) in [
        ("o1 if [1e3 GT 2]", "o1 endif"),
        ("o1 while [0] junk", "o1 endwhile"),
        ("o100 sub X5", "o100 endsub"),
    ] {
        fs::write(
            d.join("p.ngc"),
            format!("G0 X0 Y0 Z0\n{opener}\nG0 X1\n{closer}\nM2\n"),
        )
        .unwrap();
        let e = refused_in(d, &["inspect", "program", "p.ngc"]);
        assert!(e.contains("p.ngc: line 2, column "), "{opener}: {e}");
        assert!(!e.contains("opening statement"), "{opener}: {e}");
    }
}

/// LinuxCNC's checks of canned cycles and tool tables: R below the hole's bottom, a negative
/// dwell, a tool listed twice, a word twice, an absurd length are refused with the line;
/// a byte-order mark is read past.
#[test]
fn cycle_and_tool_table_misreads_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let head = "G21 G90\nG10 L2 P1 X150 Y0 Z-250\nG54\nG0 X630 Y0 Z420\n";
    fs::write(
        d.join("r.ngc"),
        format!("{head}G81 X630 Y0 Z390 R380\nM2\n"),
    )
    .unwrap();
    let e = refused_in(d, &["trajectory", "r.ngc", "--out", "t/r.csv"]);
    assert!(
        e.contains("line 5") && e.contains("below the hole's bottom"),
        "{e}"
    );
    fs::write(
        d.join("p.ngc"),
        format!("{head}G89 X630 Y0 Z390 R400 P-1\nM2\n"),
    )
    .unwrap();
    let e = refused_in(d, &["trajectory", "p.ngc", "--out", "t/r.csv"]);
    assert!(e.contains("line 5") && e.contains("negative dwell"), "{e}");
    fs::write(
        d.join("t.ngc"),
        format!("{head}T1 M6\nG43 H1\nG1 X600 F1000\nM2\n"),
    )
    .unwrap();
    for (table, want) in [
        (
            "T1 P1 Z10\nT1 P1 Z20\n",
            "line 2, column 1: tool 1 is listed twice",
        ),
        ("T1 P1 Z10 Z20\n", "line 1, column 11: Z is given twice"),
        (
            "T1 P1 Z1e300\n",
            "line 1, column 7: a tool length past 10000 mm",
        ),
    ] {
        fs::write(d.join("t.tbl"), table).unwrap();
        let e = refused_in(
            d,
            &[
                "trajectory",
                "t.ngc",
                "--tool-table",
                "t.tbl",
                "--out",
                "t/r.csv",
            ],
        );
        assert!(e.contains(want) && !e.contains("inf"), "{table:?}: {e}");
    }
    fs::write(d.join("t.tbl"), "\u{feff}T1 P1 Z10\n").unwrap();
    accepted_in(
        d,
        &[
            "trajectory",
            "t.ngc",
            "--tool-table",
            "t.tbl",
            "--out",
            "t/r.csv",
        ],
    );
}

/// Values a reader cannot use are refused with short numbers: a tool centre point 1e300 mm
/// away, a 3 MB line of TOML (the message quotes a window of it); `--tip` of a link the
/// built-in robot has is named as one, with its links.
#[test]
fn absurd_values_are_refused_in_a_few_lines() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    fs::write(
        d.join("ok.ngc"),
        "G21 G90\nG10 L2 P1 X150 Y0 Z-250\nG54\nG0 X630 Y0 Z420\nG1 X600 F1000\nM2\n",
    )
    .unwrap();
    let e = refused_in(
        d,
        &[
            "trajectory",
            "ok.ngc",
            "--tcp",
            "1e300,0,0",
            "--out",
            "t/r.csv",
        ],
    );
    assert!(e.contains("within 10 m") && e.len() < 600, "{e}");
    fs::write(
        d.join("big.toml"),
        format!("title = \"{}\n", "a".repeat(3_000_000)),
    )
    .unwrap();
    let e = refused_in(d, &["run", "big.toml", "--out", "r"]);
    assert!(
        e.contains("big.toml: TOML parse error at line 1") && e.len() < 600,
        "{} bytes: {e}",
        e.len()
    );
    let e = refused_in(d, &["inspect", "robot", "--tip", "link_3"]);
    assert!(
        e.contains("is a link of the built-in robot") && e.contains("link_1, link_2, link_3"),
        "{e}"
    );
}

/// Meshes that cannot be drawn (non-finite or absurd coordinates, a NaN matrix, a 1e308
/// scale, 300 000 nested nodes, a named pipe, a folder, a device, paths leaving the package)
/// leave their link drawn as a capsule with a warning naming the link and the file; the run
/// completes (exit 0).
#[cfg(unix)]
#[test]
fn unreadable_meshes_become_capsules_with_a_warning() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mesh_arm");
    let arm = d.join("arm");
    fs::create_dir_all(arm.join("urdf")).unwrap();
    fs::create_dir_all(arm.join("meshes")).unwrap();
    for f in fs::read_dir(data.join("meshes")).unwrap() {
        let f = f.unwrap();
        fs::copy(f.path(), arm.join("meshes").join(f.file_name())).unwrap();
    }
    let m = arm.join("meshes");
    fs::write(
        m.join("inf.obj"),
        "v 0 0 0\nv inf 0 0\nv 0 NaN 0\nf 1 2 3\n",
    )
    .unwrap();
    fs::write(
        m.join("huge.obj"),
        "v 0 0 0\nv 1e38 0 0\nv 0 1e38 0\nf 1 2 3\n",
    )
    .unwrap();
    let nested = format!(
        "<?xml version=\"1.0\"?><COLLADA><library_visual_scenes><visual_scene>{}{}</visual_scene></library_visual_scenes></COLLADA>",
        "<node>".repeat(300_000),
        "</node>".repeat(300_000)
    );
    fs::write(m.join("nest.dae"), nested).unwrap();
    fifo(&m.join("fifo.stl"));
    fs::create_dir_all(m.join("folder.stl")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", m.join("zero.stl")).unwrap();
    let urdf = fs::read_to_string(data.join("urdf/mesh_arm.urdf")).unwrap();
    let one = "<visual><geometry><mesh filename=\"../meshes/link1.stl\"/></geometry><material name=\"blue\"/></visual>";
    assert!(urdf.contains(one));
    for bad in [
        "../meshes/inf.obj",
        "../meshes/huge.obj",
        "../meshes/nest.dae",
        "../meshes/fifo.stl",
        "../meshes/folder.stl",
        "../meshes/zero.stl",
        "package://arm/../../../../etc/passwd",
        "package:///etc/passwd",
    ] {
        let u = urdf.replace(one, &one.replace("../meshes/link1.stl", bad));
        fs::write(arm.join("urdf/bad.urdf"), u).unwrap();
        let scenario =
            format!(
            "controllers = [\"second\"]\n[robot]\nmodel = \"arm/urdf/bad.urdf\"\ndrives = {:?}\n\
             [payload]\nmasses_kg = [0.0]\n[simulation]\nhold_s = 0.2\nsteady_window_s = 0.1\n",
            data.join("../../../../ofmpc/robots/irb140/drives.toml").display().to_string()
        );
        fs::write(d.join("s.toml"), scenario).unwrap();
        let e = accepted_in(d, &["run", "s.toml", "--out", "r"]);
        let file = bad.rsplit('/').next().unwrap();
        assert!(
            e.contains("drawn as capsules") && e.contains("link_1") && e.contains(file),
            "{bad}: {e}"
        );
        assert!(e.len() < 2000, "{bad}: {} bytes", e.len());
        fs::remove_dir_all(d.join("r")).unwrap();
    }
}

/// `tune --words` for a baseline prints words, not the JSON (issue 36: the flag was ignored);
/// `--json` still prints the numbers.
#[test]
fn tune_words_for_a_baseline_prints_words() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let o = bin::ofmpc_in(
        d,
        &[
            "tune",
            "--payload-range",
            "0,0.25",
            "--controllers",
            "pid",
            "--words",
            "--out",
            "t.toml",
        ],
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        out.starts_with("Tuning pid for an unknown payload of 0–0.25 kg"),
        "{out}"
    );
    assert!(!out.trim_start().starts_with('{'), "{out}");
    let o = bin::ofmpc_in(
        d,
        &[
            "tune",
            "--payload-range",
            "0,0.25",
            "--controllers",
            "pid",
            "--json",
            "--out",
            "t2.toml",
        ],
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert!(v["bandwidth_rad_s"].as_f64().unwrap() > 0.0, "{v}");
}
