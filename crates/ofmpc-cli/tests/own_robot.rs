//! The README's own-robot steps, followed literally (issue 38): `init robot`, the `run` it
//! prints, the `inspect robot` it prints, `trajectory` and `reproduce` of a CAM-style program
//! with the start pose (`--start-q`), tip (`--tip`) and tool position (`--origin`) init
//! printed, on a UR arm (UR5) and a 7-axis arm with a hand (Panda). Every step exits 0 and the
//! reports are titled after the robot and program that ran.

mod bin;
use bin::*;
use std::path::{Path, PathBuf};

fn data(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(rel)
        .display()
        .to_string()
}

/// The value after `flag ` in init's output (up to the next `)` or white space).
fn printed(out: &str, flag: &str) -> String {
    let at = out
        .find(&format!("{flag} "))
        .unwrap_or_else(|| panic!("init printed no {flag}: {out}"));
    out[at + flag.len() + 1..]
        .split(|c: char| c == ')' || c.is_whitespace())
        .next()
        .unwrap()
        .to_string()
}

/// The printed command line after `next:` that starts with `ofmpc <command>`, as arguments.
fn next_command(out: &str, command: &str) -> Vec<String> {
    let next = out.split("next:").nth(1).expect("init printed next:");
    let line = next
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with(&format!("ofmpc {command}")))
        .unwrap_or_else(|| panic!("no `ofmpc {command}` after next: {out}"));
    line.split_whitespace().skip(1).map(String::from).collect()
}

fn title(report: &Path) -> String {
    let html = std::fs::read_to_string(report).unwrap();
    let at = html.find("<title>").unwrap() + "<title>".len();
    html[at..at + html[at..].find("</title>").unwrap()].replace("&#39;", "'")
}

fn step(cwd: &Path, args: &[String]) -> String {
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = ofmpc_in(cwd, &refs);
    assert!(
        o.status.success(),
        "ofmpc {}: exit {:?}\n{}",
        args.join(" "),
        o.status.code(),
        stderr(&o)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn follow_the_readme(urdf: &str, name: &str, tip: Option<&str>) {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<String>>();
    // ofmpc init robot my.urdf --out my
    let out = step(cwd, &s(&["init", "robot", urdf, "--out", "my"]));
    if let Some(t) = tip {
        assert!(
            out.contains(&format!("--tip {t}")),
            "init names the tip: {out}"
        );
    }
    // The command init printed: ofmpc run my/scenario.toml (--out my-run, as the README).
    let mut run = next_command(&out, "run");
    run.extend(s(&["--out", "my-run"]));
    step(cwd, &run);
    let t = title(&cwd.join("my-run/report.html"));
    assert!(t.contains(name) && t.contains("paper's path"), "{t}");
    assert!(!t.contains("ABB IRB 140"), "{t}");
    // The inspect command init printed (with the tip for a branched arm).
    step(cwd, &next_command(&out, "inspect"));
    // ofmpc trajectory my.gcode --robot my.urdf --drives my/drives.toml --start-q … --origin …
    let (q, origin) = (printed(&out, "--start-q"), printed(&out, "--origin"));
    let program = data("tests/data/cam_pocket.ngc");
    let tip_args: Vec<String> = tip.map(|t| s(&["--tip", t])).unwrap_or_default();
    let mut traj = s(&[
        "trajectory",
        &program,
        "--robot",
        urdf,
        "--drives",
        "my/drives.toml",
    ]);
    traj.extend(tip_args.clone());
    traj.extend([format!("--start-q={q}"), format!("--origin={origin}")]);
    traj.extend(s(&["--out", "traj/ref.csv"]));
    step(cwd, &traj);
    // ofmpc reproduce --robot my.urdf --set robot.drives=my/drives.toml --start-q … --program
    // my.gcode --origin … --payload 0,0.5
    let mut rep = s(&[
        "reproduce",
        "--robot",
        urdf,
        "--set",
        "robot.drives=my/drives.toml",
    ]);
    rep.extend(tip_args);
    rep.extend([format!("--start-q={q}"), format!("--origin={origin}")]);
    rep.extend(s(&[
        "--program",
        &program,
        "--payload",
        "0,0.5",
        "--out",
        "rep",
    ]));
    rep.extend(s(&["--controllers", "second"]));
    step(cwd, &rep);
    let t = title(&cwd.join("rep/report.html"));
    assert!(t.contains(name) && t.contains("cam_pocket.ngc"), "{t}");
    let scenario = std::fs::read_to_string(cwd.join("rep/scenario.toml")).unwrap();
    // The run's start pose is the one init printed (values as written: `0` printed, `0.0`
    // in the scenario).
    let line = scenario
        .lines()
        .find(|l| l.starts_with("start_q = ["))
        .unwrap_or_else(|| panic!("no start_q: {scenario}"));
    let written: Vec<f64> = line["start_q = [".len()..line.find(']').unwrap()]
        .split(',')
        .map(|v| v.trim().parse().unwrap())
        .collect();
    let given: Vec<f64> = q.split(',').map(|v| v.parse().unwrap()).collect();
    assert_eq!(written.len(), given.len(), "{scenario}");
    for (w, g) in written.iter().zip(&given) {
        assert!((w - g).abs() < 1e-9, "{line} against --start-q {q}");
    }
}

#[test]
fn the_readme_steps_run_on_a_ur5() {
    follow_the_readme(
        &data("../ofmpc/tests/data/robots/ur/ur5_robot.urdf"),
        "ur5",
        None,
    );
}

#[test]
fn the_readme_steps_run_on_a_panda_with_its_hand() {
    follow_the_readme(
        &data("../ofmpc/tests/data/robots/panda/panda.urdf"),
        "panda",
        Some("panda_hand"),
    );
}

/// The public arms with dynamics the repository ships (issue 38's "8 public arms": UR3, UR5,
/// UR10, Panda, iiwa, Kinova, LWR, Z1 — the UR5 and the Panda are the two README walks above,
/// which run init's printed `run` too; the six others here): `init robot` then its printed `run`
/// as printed (the three controllers, 0 and 0.5 kg), without a hand-chosen start pose: exits
/// 0, every run planned and simulated (a controller may diverge under the payload its model
/// does not know: a result, reported), the usual MPC without payload completes.
#[test]
fn every_public_arm_runs_after_init() {
    let arms = [
        "ur/ur3_robot.urdf",
        "ur/ur10_robot.urdf",
        "iiwa/model.urdf",
        "kinova/kinova.urdf",
        "lwr/kuka.urdf",
        "z1/z1.urdf",
    ];
    for rel in arms {
        let tmp = tempfile::tempdir().unwrap();
        let urdf: PathBuf = Path::new(&data("../ofmpc/tests/data/robots")).join(rel);
        let out = step(
            tmp.path(),
            &["init", "robot", &urdf.display().to_string(), "--out", "my"].map(String::from),
        );
        let mut run = next_command(&out, "run");
        run.extend(["--out", "r"].map(String::from));
        step(tmp.path(), &run);
        let m = metrics(&tmp.path().join("r"));
        assert_eq!(m["runs"].as_array().unwrap().len(), 6, "{rel}: {m}");
        assert_eq!(run_of(&m, "usual_m0")["status"], "ok", "{rel}: {m}");
    }
}

fn run_of<'a>(m: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    bin::run(m, name)
}
