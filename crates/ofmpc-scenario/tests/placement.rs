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
