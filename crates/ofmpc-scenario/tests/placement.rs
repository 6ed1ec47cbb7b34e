//! `place_paper_program` (issue 38): for each public arm the repository ships, the paper's
//! program placed for the arm resolves (reach, joint limits, timing within the joints' speed
//! limits), from a start pose inside the limits, without a hand-chosen pose.

use ofmpc_scenario::{place_paper_program, Scenario, ScenarioFile};
use std::path::PathBuf;

fn robot_file(rel: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../ofmpc/tests/data/robots")
        .join(rel)
        .display()
        .to_string()
}

/// The arm's scenario as `init robot` writes it: model, tip; no drives (the URDF's limits).
fn base(rel: &str, tip: Option<&str>) -> ScenarioFile {
    let mut f = ScenarioFile::default();
    f.robot.model = robot_file(rel);
    f.robot.tip = tip.map(str::to_string);
    f
}

#[test]
fn every_public_arm_gets_a_placement_that_resolves() {
    let arms = [
        ("ur/ur3_robot.urdf", None),
        ("ur/ur5_robot.urdf", None),
        ("ur/ur10_robot.urdf", None),
        ("panda/panda.urdf", Some("panda_hand")),
        ("iiwa/model.urdf", None),
        ("kinova/kinova.urdf", None),
        ("lwr/kuka.urdf", None),
        ("z1/z1.urdf", None),
    ];
    let mut failures = Vec::new();
    for (rel, tip) in arms {
        let f = base(rel, tip);
        match place_paper_program(&f) {
            Ok(p) => {
                let mut g = f.clone();
                g.robot.start_q = Some(p.start_q.clone());
                g.timing.max_speed_m_s = p.max_speed_m_s;
                let s = Scenario::resolve_program(&g, "placed".into(), &p.program)
                    .unwrap_or_else(|e| panic!("{rel}: the placement does not resolve: {e}"));
                eprintln!(
                    "{rel}: q0 {:?}, offset {:?} mm, {} m/s, {:.1} s, title {:?}",
                    p.start_q,
                    p.offset_mm,
                    p.max_speed_m_s,
                    s.experiment.reference.duration(),
                    s.file.title
                );
                let robot = &s.experiment.robot;
                for (j, q) in p.start_q.iter().enumerate() {
                    let (lo, hi) = (robot.lower_limits()[j], robot.upper_limits()[j]);
                    assert!(
                        *q > lo && *q < hi,
                        "{rel}: joint {j} at {q} outside [{lo}, {hi}]"
                    );
                }
            }
            Err(e) => failures.push(format!("{rel}: {e}")),
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The Panda's URDF gives `<dynamics>` and `<safety_controller>` on each of its 7 joints: one
/// warning line per kind (not 14), each naming the 7 joints.
#[test]
fn urdf_warnings_come_one_line_per_kind() {
    let chain = ofmpc::robot::ChainOptions {
        tip: Some("panda_hand".into()),
        tcp: None,
    };
    let path = robot_file("panda/panda.urdf");
    let robot =
        ofmpc::robot::Robot::from_urdf_file_with(std::path::Path::new(&path), &chain).unwrap();
    let raw = robot.warnings().len();
    let (_, lines) = ofmpc_scenario::load_robot_with(&path, None, &chain).unwrap();
    assert!(raw >= 14, "{raw} warnings from the library");
    assert_eq!(lines.len(), 2, "{lines:#?}");
    assert!(lines.iter().all(|l| l.contains("7 joints")), "{lines:#?}");
}
