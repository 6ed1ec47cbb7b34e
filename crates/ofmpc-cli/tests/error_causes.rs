//! Planning errors in the CLI's words (issue 38 item 2): the UR5's stretched start pose names
//! `--start-q`, every error names the line and column of the motion, and a start point out
//! of reach is reported at its own line whatever the line endings.

mod bin;
use bin::*;

fn ur5() -> String {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../ofmpc/tests/data/robots/ur/ur5_robot.urdf")
        .display()
        .to_string()
}

#[test]
fn the_ur5_stretched_start_pose_names_start_q_and_a_bent_pose_plans() {
    let dir = tempfile::tempdir().unwrap();
    let program = dir.path().join("step.ngc");
    std::fs::write(&program, "G21 G91\nG1 X1 F600\n").unwrap();
    let out = dir.path().join("ref.csv");
    let (p, o, u) = (program.to_str().unwrap(), out.to_str().unwrap(), ur5());
    let e = fails(&["trajectory", p, "--robot", &u, "--out", o]);
    assert!(e.contains("program line 2, column 1"), "{e}");
    assert!(e.contains("start pose holds the arm stretched out"), "{e}");
    assert!(e.contains("--start-q"), "{e}");
    assert!(!e.contains("--origin"), "{e}");
    // The fix the message names works: a start pose with the elbow bent.
    ok(&[
        "trajectory",
        p,
        "--robot",
        &u,
        "--start-q=0,-1.57,1.57,-1.57,-1.57,0",
        "--out",
        o,
    ]);
}

#[test]
fn a_start_point_out_of_reach_is_reported_at_its_line_with_crcrlf_endings() {
    let dir = tempfile::tempdir().unwrap();
    let program = dir.path().join("far.ngc");
    std::fs::write(
        &program,
        "G21 G90\r\r\n  G0 X2000 Y0 Z400\r\r\nG1 X500 F600\r\r\n",
    )
    .unwrap();
    let out = dir.path().join("ref.csv");
    let e = fails(&[
        "trajectory",
        program.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(e.contains("program line 2, column 3 (t = 0.000 s)"), "{e}");
    assert!(e.contains("outside the arm's workspace"), "{e}");
}
