//! Issue 35: a plant that is not the model. The real-arm presets read as the issue specifies
//! them; `[plant] robot` / `drives` build the plant from its own files (relative to the
//! scenario), refuse a plant whose joints differ, and a heavier link is tracked offset-free
//! by the second algorithm on an ideal sensor; `inertia_error` is reported in the plant block;
//! the robustness study's output on a tiny grid.

use ofmpc::control::ControllerKind;
use ofmpc::robot::{Payload, IRB140_URDF};
use ofmpc::sim::RunStatus;
use ofmpc_scenario::robustness::{robustness, CellResult, RobustnessGrid};
use ofmpc_scenario::{plant_report, Scenario, ScenarioFile};
use std::path::{Path, PathBuf};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// A scratch folder removed at the end of the test.
struct Dir(PathBuf);

impl Dir {
    fn new(tag: &str) -> Self {
        let d = std::env::temp_dir().join(format!("ofmpc-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        Dir(d)
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[test]
fn the_real_arm_presets_are_as_specified() {
    for (name, ts, horizon, delay) in [
        ("real-arm.toml", 0.01, None, 1),
        ("real-arm-1khz.toml", 0.001, Some(50), 2),
    ] {
        let f = ScenarioFile::from_file(&examples().join(name)).unwrap();
        let p = &f.plant;
        assert_eq!(f.mpc.ts, ts, "{name}");
        if let Some(h) = horizon {
            assert_eq!(f.mpc.horizon, h, "{name}");
        }
        assert_eq!(p.delay_samples, delay, "{name}");
        assert_eq!(p.encoder_counts, 1 << 20);
        assert!(p.velocity_from_encoder && p.torque_limits);
        assert_eq!(p.coulomb_friction, [5.0, 5.0, 3.0, 1.0, 1.0, 0.5]);
        assert_eq!(p.viscous_friction, [8.0, 8.0, 4.0, 1.0, 1.0, 0.5]);
        assert_eq!((p.position_noise, p.inertia_error), (1e-6, 0.1));
        assert!(f.mpc.delay_compensation && f.mpc.friction_compensation && f.mpc.torque_limits);
        assert_eq!(f.payload.masses_kg, [0.0, 2.0, 6.0]);
        let names: Vec<&str> = f.controllers.iter().map(|k| k.name()).collect();
        assert_eq!(
            names,
            [
                "first",
                "second",
                "first-adaptive",
                "second-adaptive",
                "ctc-adaptive",
                "dob-mpc"
            ]
        );
        let s = Scenario::resolve(&f).unwrap();
        // The controllers' friction estimates are the plant's, 20 % below.
        for (i, j) in s.experiment.robot.joints().iter().enumerate() {
            assert!((j.coulomb_nm - 0.8 * p.coulomb_friction[i]).abs() < 1e-12);
            assert!((j.viscous_nms - 0.8 * p.viscous_friction[i]).abs() < 1e-12);
        }
        // The plant block reports one draw per link, ~10 % in size.
        let report = plant_report(&s).unwrap().unwrap();
        assert_eq!(report.links.len(), 6);
        let rms = (report
            .links
            .iter()
            .map(|l| l.error.mass.powi(2))
            .sum::<f64>()
            / 6.0)
            .sqrt();
        assert!((0.01..0.3).contains(&rms), "mass errors' RMS {rms}");
    }
}

/// `[plant] robot` from a URDF next to the scenario whose link 3 is 20 % heavier: the
/// second algorithm on an ideal sensor ends "ok" and offset-free (steady error below 1e-6
/// mm), while the run differs from the one against the nominal plant (the plant was used).
#[test]
fn a_heavier_plant_link_is_tracked_offset_free_by_second() {
    let dir = Dir::new("plant-robot");
    let heavy = IRB140_URDF.replacen("<mass value=\"16.5830\"/>", "<mass value=\"19.8996\"/>", 1);
    assert_ne!(heavy, IRB140_URDF);
    std::fs::write(dir.0.join("measured.urdf"), heavy).unwrap();
    let path = dir.0.join("s.toml");
    std::fs::write(
        &path,
        "controllers = [\"second\"]\n[payload]\nmasses_kg = [0.0]\n[plant]\nrobot = \"measured.urdf\"\n",
    )
    .unwrap();
    let f = ScenarioFile::from_file(&path).unwrap();
    assert_eq!(
        f.plant.robot.as_deref(),
        Some(dir.0.join("measured.urdf").as_path())
    );
    let s = Scenario::resolve(&f).unwrap();
    let plant = s.experiment.plant.model.as_ref().unwrap();
    let extra = plant.moving_mass() - s.experiment.robot.moving_mass();
    assert!((extra - (19.8996 - 16.5830)).abs() < 1e-9, "{extra}");
    let run = |e: &ofmpc::sim::Experiment| {
        e.run(
            ControllerKind::Second,
            &Payload::point_mass(0.0),
            &mut |_, _| {},
        )
        .unwrap()
        .1
    };
    let m = run(&s.experiment);
    assert_eq!(m.status, RunStatus::Ok);
    assert!(
        m.steady_cartesian_error_mm < 1e-6,
        "steady {}",
        m.steady_cartesian_error_mm
    );
    let mut nominal = s.experiment.clone();
    nominal.plant.model = None;
    let n = run(&nominal);
    assert!(
        (n.cartesian_error_rms_mm - m.cartesian_error_rms_mm).abs() > 1e-6,
        "{} vs {}",
        n.cartesian_error_rms_mm,
        m.cartesian_error_rms_mm
    );
    let report = plant_report(&s).unwrap().unwrap();
    assert!(report.links.is_empty() && report.robot.is_some());
}

#[test]
fn a_plant_robot_with_other_joints_is_refused_by_key() {
    let dir = Dir::new("plant-mismatch");
    let renamed = IRB140_URDF.replace("\"joint_6\"", "\"wrist_roll\"");
    std::fs::write(dir.0.join("other.urdf"), renamed).unwrap();
    let path = dir.0.join("s.toml");
    std::fs::write(&path, "[plant]\nrobot = \"other.urdf\"\n").unwrap();
    let e = Scenario::resolve(&ScenarioFile::from_file(&path).unwrap())
        .err()
        .expect("a plant with other joints must be refused")
        .to_string();
    assert!(
        e.contains("[plant] robot") && e.contains("wrist_roll") && e.contains("joint_6"),
        "{e}"
    );
}

#[test]
fn defaults_report_no_plant_block() {
    let s = Scenario::resolve(&ScenarioFile::default()).unwrap();
    assert_eq!(plant_report(&s).unwrap(), None);
    assert_eq!(s.experiment.plant.inertia_error, 0.0);
}

/// The study on a tiny grid: one cell per combination, every controller in every cell,
/// the summary's counts those of the cells, and the JSON's fields.
#[test]
fn robustness_output_on_a_tiny_grid() {
    let s = Scenario::resolve(&ScenarioFile::default()).unwrap();
    let grid = RobustnessGrid {
        delay_samples: vec![0, 1],
        encoder_bits: vec![0],
        friction_error: vec![0.2],
        inertia_error: vec![0.1],
        payload_kg: vec![0.0],
    };
    let kinds = [ControllerKind::First, ControllerKind::DobMpc];
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let r = robustness(&s, &kinds, &grid, 0.01, &|| {
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    })
    .unwrap();
    assert_eq!(calls.into_inner(), 4);
    assert_eq!(r.cells.len(), 4);
    assert_eq!(r.summary.len(), 2);
    for (k, sum) in kinds.iter().zip(&r.summary) {
        let mine: Vec<_> = r
            .cells
            .iter()
            .filter(|c| c.controller == k.name())
            .collect();
        assert_eq!(sum.cells, 2);
        // Completed: "ok" or "hunting" (a hold that did not settle holds nothing).
        let completed = |c: &CellResult| matches!(c.status, RunStatus::Ok | RunStatus::Hunting);
        let stable = mine.iter().filter(|c| completed(c)).count();
        assert_eq!(sum.stable, stable);
        assert_eq!(sum.holds, mine.iter().filter(|c| c.holds).count());
        for c in &mine {
            assert_eq!(
                c.holds,
                c.status == RunStatus::Ok && c.steady_mm.is_some_and(|s| s <= 0.01)
            );
            assert_eq!(c.rms_mm.is_some(), completed(c));
        }
    }
    // Without delay, on an ideal sensor, the first algorithm holds against a 10 % model error.
    let first_ideal = &r.cells[0];
    assert_eq!(
        (
            first_ideal.controller.as_str(),
            first_ideal.cell.delay_samples
        ),
        ("first", 0)
    );
    assert!(first_ideal.holds, "{first_ideal:?}");
    let json = serde_json::to_value(&r).unwrap();
    for key in ["grid", "steady_bound_mm", "summary", "cells"] {
        assert!(json.get(key).is_some(), "{key}");
    }
    let cell = &json["cells"][0];
    for key in [
        "controller",
        "delay_samples",
        "encoder_bits",
        "friction_error",
        "inertia_error",
        "payload_kg",
        "status",
        "rms_mm",
        "steady_mm",
        "holds",
    ] {
        assert!(cell.get(key).is_some(), "cell key {key}");
    }
}
