//! The scenario crate without the command: every example scenario resolves,
//! overrides meet the file's checks, and the closed loop's settings carry the
//! values of `[payload]`, `[safety]` and `[faults]`.

use ofmpc_scenario::{Override, Scenario, ScenarioError, ScenarioFile};
use std::path::Path;

fn examples() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

#[test]
fn every_example_scenario_resolves() {
    let mut n = 0;
    for entry in std::fs::read_dir(examples()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let file = ScenarioFile::from_file(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            Scenario::resolve(&file).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            n += 1;
        }
    }
    assert!(n >= 15, "{n} example scenarios");
}

#[test]
fn overrides_are_applied_before_the_files_checks() {
    let path = examples().join("probe-friction-comp.toml");
    let sets: Vec<Override> = ["mpc.horizon=12", "plant.substep=2e-4", "timing.mode=G64"]
        .iter()
        .map(|s| s.parse().unwrap())
        .collect();
    let f = ScenarioFile::from_file_with(&path, &sets).unwrap();
    assert_eq!(f.mpc.horizon, 12);
    assert_eq!(f.plant.substep, 2e-4);
    assert_eq!(f.timing.mode, "G64");
    // Untouched keys keep the file's values, its paths resolved against its folder.
    assert!(f.mpc.friction_compensation);
    assert!(f.robot.drives.as_deref().unwrap().is_absolute());

    let unknown: Override = "mpc.horizn=20".parse().unwrap();
    match ScenarioFile::from_file_with(&path, &[unknown]) {
        Err(ScenarioError::Override { key, message, .. }) => {
            assert_eq!(key, "mpc.horizn");
            assert!(message.contains("unknown field `horizn`"), "{message}");
        }
        other => panic!("{:?}", other.map(|_| ())),
    }
    assert!(matches!(
        "no-equals".parse::<Override>(),
        Err(ScenarioError::OverrideSyntax { .. })
    ));
    // The same overrides on a scenario built in code.
    let f = ScenarioFile::default().with_overrides(&sets).unwrap();
    assert_eq!((f.mpc.horizon, f.plant.substep), (12, 2e-4));
}

#[test]
fn run_conditions_carry_pick_up_safety_and_faults() {
    let text = "[payload]\npick_up_at_s = 1.5\n[safety]\nmax_joint_error_rad = 0.05\n\
                [faults]\nnan_at_s = [1.0]\ndropout_s = [[2.0, 2.1]]\n";
    let f: ScenarioFile = toml::from_str(text).unwrap();
    let s = f.run_conditions();
    assert_eq!(s.pick_up_at_s, Some(1.5));
    assert_eq!(s.safety.max_joint_error_rad, Some(0.05));
    assert_eq!(s.faults.nan_at_s, [1.0]);
    assert_eq!(s.faults.dropout_s, [[2.0, 2.1]]);
    assert!(f.records_measurement());
    assert!(!ScenarioFile::default().records_measurement());
}

#[test]
fn baselines_and_controller_shorthands() {
    use ofmpc::control::{ControllerKind, Weight};
    let f: ScenarioFile = toml::from_str(
        "controllers = [\"second\", \"baselines\"]\n[baselines]\nctc_bandwidth = [100, 100, 100, 120, 120, 120]\n",
    )
    .unwrap();
    let mut want = vec![ControllerKind::Second];
    want.extend(ControllerKind::BASELINES);
    assert_eq!(f.controllers, want);
    assert_eq!(f.baselines.pid_bandwidth, Weight::Scalar(60.0));
    let all: ScenarioFile = toml::from_str("controllers = [\"all\"]").unwrap();
    assert_eq!(all.controllers, ControllerKind::ALL.to_vec());
    assert!(toml::from_str::<ScenarioFile>("controllers = [\"pidd\"]").is_err());
    // The bandwidths reach the experiment (the run's controllers build with them); a bad one
    // names its key.
    let s = Scenario::resolve(&f).unwrap();
    assert_eq!(s.experiment.baselines, f.baselines);
    let mut bad = f.clone();
    bad.baselines.dob_observer_bandwidth = Weight::Scalar(0.0);
    let e = match Scenario::resolve(&bad) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("a zero bandwidth was accepted"),
    };
    assert!(
        e.contains("[baselines]") && e.contains("dob_observer_bandwidth"),
        "{e}"
    );
    // Written back only when set.
    let text = toml::to_string(&f).unwrap();
    assert!(text.contains("[baselines]"), "{text}");
    assert!(!toml::to_string(&ScenarioFile::default())
        .unwrap()
        .contains("[baselines]"));
}

/// Issue #22 item 13: events scheduled after the run's end (path + hold) are warned about,
/// naming the key; events within it are not.
#[test]
fn events_after_the_end_are_warned_about() {
    let text = "controllers = [\"usual\"]\n[payload]\nmasses_kg = [0.0]\npick_up_at_s = 1e6\n\
                [faults]\nnan_at_s = [1.0, 500.0]\ndropout_s = [[2.0, 2.1], [600.0, 601.0]]\n\
                [plant]\nfaults = [{ kind = \"torque_drop\", t = 700.0, joint = 1, fraction = 0.5, duration_s = 0.1 }, \
                { kind = \"encoder_glitch\", t = 1.0, joint = 2, offset_rad = 0.01 }]\n";
    let f: ScenarioFile = toml::from_str(text).unwrap();
    let s = Scenario::resolve(&f).unwrap();
    let late: Vec<&String> = s
        .warnings
        .iter()
        .filter(|w| w.contains("never happens"))
        .collect();
    assert_eq!(late.len(), 4, "{late:#?}");
    for key in [
        "[payload] pick_up_at_s = 1000000 s",
        "[faults] nan_at_s: 500 s",
        "[faults] dropout_s: [600, 601] s",
        "[plant] faults[0]: t = 700 s",
    ] {
        assert!(late.iter().any(|w| w.contains(key)), "{key} in {late:#?}");
    }
    // Within the run: no such warning.
    let f: ScenarioFile = toml::from_str("[payload]\npick_up_at_s = 1.5\n").unwrap();
    let s = Scenario::resolve(&f).unwrap();
    assert!(
        !s.warnings.iter().any(|w| w.contains("never happens")),
        "{:?}",
        s.warnings
    );
}

/// Issue #22 item 17: with a friction time constant far below what any substep resolves, the
/// warning does not suggest an impossible substep (it was "use substep = 2e-301 s"): it says
/// the finest allowed one and to raise `coulomb_velocity`. A model payload the robot cannot
/// carry names `[mpc] model_payload_kg`.
#[test]
fn friction_advice_is_possible_and_model_payload_names_its_key() {
    let text = "controllers = [\"usual\"]\n[payload]\nmasses_kg = [0.0]\n\
                [plant]\ncoulomb_friction = [1.0]\ncoulomb_velocity = 1e-300\n";
    let f: ScenarioFile = toml::from_str(text).unwrap();
    let s = Scenario::resolve(&f).unwrap();
    let w: Vec<&String> = s
        .warnings
        .iter()
        .filter(|w| w.contains("coarser than 4 time constants"))
        .collect();
    assert_eq!(w.len(), 1, "{:#?}", s.warnings);
    let finest = f.mpc.ts / ofmpc::sim::MAX_SUBSTEPS as f64;
    assert!(w[0].contains("raise [plant] coulomb_velocity"), "{}", w[0]);
    assert!(
        w[0].contains(&format!("substep = {finest:.3e} s")),
        "{}",
        w[0]
    );
    assert!(!w[0].contains("or smaller"), "{}", w[0]);
    let f: ScenarioFile = toml::from_str("[mpc]\nmodel_payload_kg = 1e6\n").unwrap();
    let e = Scenario::resolve(&f).err().expect("refused").to_string();
    assert!(
        e.starts_with("[mpc] model_payload_kg = 1000000: invalid payload"),
        "{e}"
    );
}

/// `[program] tool_table` (issue #20): a file relative to the scenario, read for `G43 H`;
/// a missing one is named with its key.
#[test]
fn program_tool_table_is_read_relative_to_the_scenario() {
    let dir = std::env::temp_dir().join(format!("ofmpc-tool-table-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let dir = Dir(dir);
    std::fs::write(
        dir.path().join("p.ngc"),
        "G0 X500 Y0 Z600\nG43 H1\nG1 X510 F600\nM30\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("t.tbl"), "T1 P1 Z+20 ;tool\n").unwrap();
    let path = dir.path().join("s.toml");
    std::fs::write(
        &path,
        "[program]\nfile = \"p.ngc\"\ntool_table = \"t.tbl\"\n",
    )
    .unwrap();
    let f = ScenarioFile::from_file(&path).unwrap();
    assert_eq!(f.program.tool_table, Some(dir.path().join("t.tbl")));
    // G43 H1 reads (without the table it is refused by name).
    Scenario::resolve(&f).unwrap();
    std::fs::write(&path, "[program]\nfile = \"p.ngc\"\n").unwrap();
    let e = Scenario::resolve(&ScenarioFile::from_file(&path).unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("no tool table was given"), "{e}");
    std::fs::write(
        &path,
        "[program]\nfile = \"p.ngc\"\ntool_table = \"none.tbl\"\n",
    )
    .unwrap();
    let f = ScenarioFile::from_file(&path).unwrap();
    let e = Scenario::resolve(&f).err().unwrap().to_string();
    assert!(
        e.contains("[program] tool_table") && e.contains("none.tbl"),
        "{e}"
    );
}

/// A scratch folder removed at the end of the test.
struct Dir(std::path::PathBuf);

impl Dir {
    fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Issue #23 item 3: `[baselines]` is the library's `BaselineSettings` as read, and the run's
/// controller builds with it. A scenario's `pid_bandwidth = 30` runs the PID whose torques
/// equal, bit for bit, those of the library's own pid built by `ControllerBuilder` with 30 rad/s in a
/// closed loop of its own (the same plant and reference), and differ from the default 60 rad/s.
#[test]
fn baselines_section_tunes_the_run_controller() {
    use ofmpc::control::{BaselineSettings, ControllerKind, Weight};
    use ofmpc::robot::Payload;
    use ofmpc::sim::{ClosedLoop, Plant};
    let text = "controllers = [\"pid\"]\n[payload]\nmasses_kg = [0.5]\n\
                [simulation]\nhold_s = 0.3\nsteady_window_s = 0.2\n[baselines]\npid_bandwidth = 30\n";
    let f: ScenarioFile = toml::from_str(text).unwrap();
    let s = Scenario::resolve(&f).unwrap();
    let exp = &s.experiment;
    let payload = Payload::point_mass(0.5);
    let torques = |e: &ofmpc::sim::Experiment| {
        let (run, _) = e
            .run(ControllerKind::Pid, &payload, &mut |_, _| {})
            .unwrap();
        run.record
            .tau
            .iter()
            .map(|t| t.to_bits())
            .collect::<Vec<_>>()
    };
    let scenario = torques(exp);

    let tuned = BaselineSettings {
        pid_bandwidth: Weight::Scalar(30.0),
        ..Default::default()
    };
    assert_eq!(exp.baselines, tuned);
    let n = exp.robot.dof();
    let pid = ofmpc::control::ControllerBuilder::new(ControllerKind::Pid, &exp.robot)
        .settings(exp.mpc.clone())
        .baselines(tuned.clone())
        .accept_ineffective_settings()
        .build()
        .unwrap();
    assert_eq!(pid.dof(), n);
    let mut plant_robot = exp.robot.clone();
    plant_robot.set_payload(Some(payload)).unwrap();
    let (q0, ts) = (exp.reference.q(0), exp.reference.ts());
    let mut plant = Plant::with_period(plant_robot, exp.plant.clone(), q0, ts).unwrap();
    let own =
        ClosedLoop::new(pid, &mut plant, &exp.reference, &exp.loop_settings).run(&mut |_, _| {});
    let own: Vec<u64> = own.record.tau.iter().map(|t| t.to_bits()).collect();
    assert!(!own.is_empty());
    assert_eq!(
        scenario, own,
        "the scenario's pid is the library's at 30 rad/s"
    );

    let mut default = f.clone();
    default.baselines = BaselineSettings::default();
    let default = Scenario::resolve(&default).unwrap();
    assert_ne!(
        scenario,
        torques(&default.experiment),
        "pid_bandwidth changed nothing"
    );
}

/// `[output] timeseries = "auto"` keeps a run within 12 MB and all runs together within
/// 48 MB (issue #38: `reproduce --compare` wrote 80 MB); "full" keeps every sample whatever
/// the number of runs; a single run's stride is unchanged.
#[test]
fn auto_time_series_share_a_total_budget() {
    use ofmpc_scenario::{
        OutputSection, TimeseriesOutput, AUTO_TIMESERIES_BYTES, AUTO_TIMESERIES_TOTAL_BYTES,
    };
    let auto = OutputSection::default();
    let (rows, per_row) = (2_000usize, 700u64); // 1.4 MB a run: the paper's path
    assert_eq!(auto.timeseries_stride(rows, per_row), Some(1));
    assert_eq!(auto.timeseries_stride_of(rows, per_row, 6), Some(1));
    for runs in [45usize, 100] {
        let stride = auto.timeseries_stride_of(rows, per_row, runs).unwrap();
        let total = runs as u64 * rows.div_ceil(stride) as u64 * per_row;
        assert!(
            total <= AUTO_TIMESERIES_TOTAL_BYTES + runs as u64 * per_row,
            "{runs}: {total}"
        );
        assert!(stride > 1, "{runs}");
    }
    // A 30-minute path (183 000 samples of 700 bytes) with 6 runs: ≤ 48 MB in all.
    let stride = auto.timeseries_stride_of(183_000, per_row, 6).unwrap();
    assert!(
        6 * 183_000u64.div_ceil(stride as u64) * per_row
            <= AUTO_TIMESERIES_TOTAL_BYTES + 6 * per_row
    );
    assert!(183_000u64.div_ceil(stride as u64) * per_row <= AUTO_TIMESERIES_BYTES + per_row);
    let full = OutputSection {
        timeseries: TimeseriesOutput::Full,
        stride: None,
    };
    assert_eq!(full.timeseries_stride_of(rows, per_row, 45), Some(1));
}
