//! Divergence is growth (issue #19 item 5): an unstable run still ends
//! "diverged" at about the time the threshold rule stopped it, while a
//! stable controller with a large steady offset (the usual MPC under a heavy
//! payload its model does not know, well inside its stability margin)
//! completes and reports its offset.

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::gcode::{parse, ParseOptions, PAPER_TABLE1};
use ofmpc::motion::{build_reference, Orientation};
use ofmpc::motion::{CartesianTrajectory, TimingOptions};
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{DivergenceRule, Experiment, LoopSettings, RunOutcome, RunStatus};

fn experiment(robot: Robot, rule: DivergenceRule) -> Experiment {
    let program = parse(PAPER_TABLE1, &ParseOptions::default()).unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let reference = build_reference(&robot, &traj, Orientation::AtZero, 0.01).unwrap();
    Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc: MpcSettings::default(),
        plant: Default::default(),
        loop_settings: LoopSettings {
            divergence: rule,
            ..Default::default()
        },
        baselines: Default::default(),
    }
}

fn arm6() -> Robot {
    let mut r = Robot::from_urdf_str(include_str!("data/arm6.urdf")).unwrap();
    let d = Drives::from_toml_str(include_str!("data/arm6_drives.toml")).unwrap();
    r.apply_drives(&d).unwrap();
    r
}

fn outcome(exp: &Experiment, kind: ControllerKind, mass: f64) -> RunOutcome {
    exp.run(kind, &Payload::point_mass(mass), &mut |_, _| {})
        .unwrap()
        .0
        .outcome
}

/// README: with the paper's tuning the second algorithm diverges at 2 and
/// 6 kg and the first at 6 kg; the growth rule stops them within 0.05 s of
/// the threshold rule (the samples of their exponential growth).
#[test]
fn the_paper_s_unstable_runs_still_diverge_at_about_the_same_time() {
    let growth = experiment(Robot::irb140(), DivergenceRule::Growth);
    let threshold = experiment(Robot::irb140(), DivergenceRule::Threshold);
    for (kind, mass) in [
        (ControllerKind::Second, 2.0),
        (ControllerKind::First, 6.0),
        (ControllerKind::Second, 6.0),
    ] {
        let g = outcome(&growth, kind, mass);
        let t = outcome(&threshold, kind, mass);
        let (RunOutcome::Diverged { t: tg, rule, .. }, RunOutcome::Diverged { t: tt, .. }) =
            (&g, &t)
        else {
            panic!("{kind} at {mass} kg: growth {g}, threshold {t}");
        };
        assert_eq!(*rule, DivergenceRule::Growth);
        assert!(
            (tg - tt).abs() <= 0.05 + 1e-9,
            "{kind} at {mass} kg: {tg} s against {tt} s"
        );
        assert!(g.to_string().contains("growing"), "{g}");
    }
}

/// The usual MPC on the test arm is stable to about 157 kg (`ofmpc analyze
/// stability`); at 70 and 120 kg its steady offset is above the 0.2 rad
/// threshold (120 kg: the first sag reaches 0.55 rad within 0.35 s).
/// The threshold rule calls that "diverged"; the growth rule lets it
/// complete and report the offset.
#[test]
fn a_stable_run_with_a_large_offset_completes_and_reports_it() {
    for mass in [70.0, 120.0] {
        stable_with_offset(mass);
    }
}

fn stable_with_offset(mass: f64) {
    let t = outcome(
        &experiment(arm6(), DivergenceRule::Threshold),
        ControllerKind::Usual,
        mass,
    );
    assert!(matches!(t, RunOutcome::Diverged { .. }), "{t}");
    let exp = experiment(arm6(), DivergenceRule::Growth);
    let (r, m) = exp
        .run(
            ControllerKind::Usual,
            &Payload::point_mass(mass),
            &mut |_, _| {},
        )
        .unwrap();
    assert_eq!(m.status, RunStatus::Ok, "{}", r.outcome);
    let steady = m
        .steady_joint_error_max_rad
        .iter()
        .copied()
        .fold(0.0, f64::max);
    assert!(steady > 0.2 && steady < 0.5, "steady offset {steady}");
    // Bounded: the largest error is the first sag, not a growth.
    let peak = m.joint_error_max_rad.iter().copied().fold(0.0, f64::max);
    assert!(peak < 0.6, "peak {peak}");
}

/// A scenario that writes `divergence_threshold_rad` keeps the threshold
/// rule; one that does not (or says `divergence = "growth"`) gets growth;
/// the settings written back read the same.
#[test]
fn the_rule_follows_what_the_file_says() {
    let read = |text: &str| -> LoopSettings { toml::from_str(text).unwrap() };
    assert_eq!(read("").divergence, DivergenceRule::Growth);
    let explicit = read("divergence_threshold_rad = 3.0");
    assert_eq!(explicit.divergence, DivergenceRule::Threshold);
    assert_eq!(explicit.divergence_threshold_rad, 3.0);
    let both = read("divergence_threshold_rad = 0.3\ndivergence = \"growth\"");
    assert_eq!(both.divergence, DivergenceRule::Growth);
    for s in [read(""), explicit, both] {
        let again = read(&toml::to_string(&s).unwrap());
        assert_eq!(again, s);
    }
    assert!(toml::from_str::<LoopSettings>("divergence = \"grow\"").is_err());
    assert!(toml::from_str::<LoopSettings>("unknown = 1").is_err());
}
