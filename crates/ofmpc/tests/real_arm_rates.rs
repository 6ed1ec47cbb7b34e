//! Issue 35, the real arm beyond the 10 ms preset: the payload identification
//! at 1 kHz (differences over a 10 ms window, the torque through the same
//! filter), the hold's judgement ("hunting": a hold whose measured joint error
//! moves by more than 2 encoder counts is not "ok"), and the test arm
//! (`tests/data/arm6.urdf`) with its own friction and 3 samples of delay
//! (`examples/test-arm.toml`). Short paths: each test runs in seconds in
//! release; the full presets' numbers are in docs/guide/real-arm.md.

mod common;

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::gcode::{parse, ParseOptions};
use ofmpc::motion::{build_reference, CartesianTrajectory, Orientation, TimingOptions};
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{Experiment, LoopSettings, PlantSettings, RunMetrics, RunStatus};

/// The paper's work offset and its two long straight moves and back
/// (about 2 s of motion in y, accelerations both ways).
const SHORT_IRB140: &str = "G21 G90\nG10 L2 P1 X150 Y0 Z-250\nG54 G17\n\
    G00 X630 Y0 Z400\nG00 X630 Y-200 Z400\nG00 X630 Y200 Z400\nG00 X630 Y0 Z400\nM30\n";

/// A drives file with Coulomb and viscous friction estimates `0.8 ×` the
/// plant's, for `robot`'s joints, on top of `base` (a drives file's text).
fn drives_with_friction(robot: &Robot, base: &str, coulomb: &[f64], viscous: &[f64]) -> Drives {
    let mut text = base.to_string();
    for (j, joint) in robot.joints().iter().enumerate() {
        let name = &joint.name;
        if !base.contains(&format!("[joints.{name}]")) {
            text += &format!("[joints.{name}]\n");
        }
        text = text.replacen(
            &format!("[joints.{name}]\n"),
            &format!(
                "[joints.{name}]\ncoulomb_nm = {}\nviscous_nms = {}\n",
                0.8 * coulomb[j],
                0.8 * viscous[j]
            ),
            1,
        );
    }
    Drives::from_toml_str(&text).unwrap()
}

/// The real arm's plant: `delay` samples, 20-bit encoders with encoder
/// velocity, friction, position noise 1e-6 rad, torque limits, a 0.2 ms
/// substep; the controllers' real-arm settings (`max_mass`: the bound).
fn real_arm(
    robot: Robot,
    program: &str,
    origin: Option<[f64; 3]>,
    ts: f64,
    delay: usize,
    friction: (&[f64], &[f64]),
    max_mass: f64,
) -> Experiment {
    let program = parse(
        program,
        &ParseOptions {
            origin,
            ..ParseOptions::default()
        },
    )
    .unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let reference = build_reference(&robot, &traj, Orientation::AtZero, ts).unwrap();
    Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc: MpcSettings {
            ts,
            horizon: if ts < 0.005 { 50 } else { 20 },
            torque_limits: true,
            friction_compensation: true,
            delay_compensation: true,
            max_payload_kg: max_mass,
            ..Default::default()
        },
        plant: PlantSettings {
            torque_limits: true,
            coulomb_friction: friction.0.to_vec(),
            viscous_friction: friction.1.to_vec(),
            encoder_counts: 1 << 20,
            velocity_from_encoder: true,
            position_noise: 1e-6,
            delay_samples: delay,
            substep: 2e-4,
            ..Default::default()
        },
        loop_settings: LoopSettings::default(),
        baselines: Default::default(),
    }
}

fn report(m: &RunMetrics) {
    eprintln!(
        "{}: {} RMS {:.4} steady {:.4} mm, est {:?}, hold p-p {:?} counts",
        m.name,
        m.status,
        m.cartesian_error_rms_mm,
        m.steady_cartesian_error_mm,
        m.payload_estimate_kg,
        m.hold_error_pp_counts
    );
}

const IRB_COULOMB: [f64; 6] = [5.0, 5.0, 3.0, 1.0, 1.0, 0.5];
const IRB_VISCOUS: [f64; 6] = [8.0, 8.0, 4.0, 1.0, 1.0, 0.5];

fn irb140_real_arm(ts: f64, delay: usize) -> Experiment {
    let mut robot = Robot::irb140();
    let drives = drives_with_friction(&robot, "", &IRB_COULOMB, &IRB_VISCOUS);
    robot.apply_drives(&drives).unwrap();
    real_arm(
        robot,
        SHORT_IRB140,
        None,
        ts,
        delay,
        (&IRB_COULOMB, &IRB_VISCOUS),
        9.0,
    )
}

fn run(exp: &Experiment, kind: ControllerKind, mass: f64) -> RunMetrics {
    let (_, m) = exp
        .run(kind, &Payload::point_mass(mass), &mut |_, _| {})
        .unwrap();
    report(&m);
    m
}

/// Completed (ok, or hunting within the bound), RMS and steady error (mm)
/// and the estimate (kg) within the bounds.
fn check(m: &RunMetrics, rms_mm: f64, steady_mm: f64, estimate: Option<(f64, f64)>) {
    assert!(
        matches!(m.status, RunStatus::Ok | RunStatus::Hunting),
        "{}: {}",
        m.name,
        m.reason
    );
    assert!(
        m.cartesian_error_rms_mm <= rms_mm,
        "{}: RMS {}",
        m.name,
        m.cartesian_error_rms_mm
    );
    assert!(
        m.steady_cartesian_error_mm <= steady_mm,
        "{}: steady {}",
        m.name,
        m.steady_cartesian_error_mm
    );
    if let Some((mass, tol)) = estimate {
        let est = m.payload_estimate_kg.unwrap();
        assert!((est - mass).abs() <= tol, "{}: estimate {est} kg", m.name);
    }
}

/// Measured (release): first-adaptive RMS 0.0035 mm, steady 0.0066 mm,
/// estimate 2.008 kg; ctc-adaptive 0.0042 / 0.0022 mm, 2.008 kg; both hold
/// within 4 encoder counts ("hunting" by the 2-count rule). Before (central
/// differences over 1 ms): 0.55 kg and the nominal fallback.
#[test]
fn the_payload_is_identified_at_1_khz_with_two_samples_of_delay() {
    let exp = irb140_real_arm(0.001, 2);
    for kind in [ControllerKind::FirstAdaptive, ControllerKind::CtcAdaptive] {
        let m = run(&exp, kind, 2.0);
        check(&m, 0.01, 0.014, Some((2.0, 0.1)));
        assert!(m.hold_error_pp_counts.unwrap() <= 8.0, "{}", m.name);
    }
}

/// Measured: first-adaptive at 10 ms with a sample of delay and friction
/// ends in a wrist limit cycle of 292 counts peak-to-peak (its steady
/// Cartesian error, 0.07 mm, was reported "ok" before); `first` on a plant
/// whose only effect is the encoder settles within 2 counts.
#[test]
fn a_hold_that_hunts_is_judged_and_one_that_settles_is_ok() {
    let hunts = run(
        &irb140_real_arm(0.01, 1),
        ControllerKind::FirstAdaptive,
        2.0,
    );
    assert_eq!(hunts.status, RunStatus::Hunting, "{}", hunts.reason);
    assert!(hunts.hold_error_pp_counts.unwrap() > 100.0);
    assert!(hunts.reason.contains("did not settle"), "{}", hunts.reason);
    assert!(hunts.steady_cartesian_error_mm.is_finite());
    let mut settled = irb140_real_arm(0.01, 0);
    settled.plant.coulomb_friction.clear();
    settled.plant.viscous_friction.clear();
    settled.plant.position_noise = 0.0;
    let settles = run(&settled, ControllerKind::First, 0.0);
    assert_eq!(settles.status, RunStatus::Ok, "{}", settles.reason);
    assert!(settles.hold_error_pp_counts.unwrap() <= 2.0);
    // The ideal plant: never judged.
    let mut ideal = settled;
    ideal.plant.encoder_counts = 0;
    ideal.plant.velocity_from_encoder = false;
    let m = run(&ideal, ControllerKind::First, 0.0);
    assert_eq!((m.status, m.hold_error_pp_counts), (RunStatus::Ok, None));
}

const ARM6_COULOMB: [f64; 6] = [3.0, 3.0, 2.0, 0.8, 0.8, 0.4];
const ARM6_VISCOUS: [f64; 6] = [4.0, 4.0, 2.0, 0.5, 0.5, 0.25];

fn test_arm() -> Experiment {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/");
    let mut robot =
        Robot::from_urdf_file(std::path::Path::new(&format!("{dir}arm6.urdf"))).unwrap();
    let base = std::fs::read_to_string(format!("{dir}arm6_drives.toml")).unwrap();
    let drives = drives_with_friction(&robot, &base, &ARM6_COULOMB, &ARM6_VISCOUS);
    robot.apply_drives(&drives).unwrap();
    let program = std::fs::read_to_string(format!("{dir}arc_yz.gcode")).unwrap();
    let mut exp = real_arm(
        robot,
        &program,
        Some([0.5, 0.11, 0.5]),
        0.01,
        3,
        (&ARM6_COULOMB, &ARM6_VISCOUS),
        7.5,
    );
    // As examples/test-arm.toml before its tuning (the preset as shipped is
    // checked in crates/ofmpc-scenario/tests/test_arm.rs).
    exp.mpc.observer_friction = true;
    exp.mpc.encoder_counts = 1_048_576.0;
    exp
}

/// Measured (release), RMS / steady mm, estimate kg at 0 / 2.5 / 5 kg:
/// ctc-adaptive 0.70 / 0.049, 0.05; 6.7 / 0.55, 2.497; 68 / 0.29, 5.005;
/// first-adaptive 0.68 / 1.01, 0.04; 12.8 / 0.57, 2.500; 58 / 0.29, 4.991;
/// every run "hunting" (35 to 1600 counts). The identification holds; the
/// loops do not settle with 30 ms of delay (docs/guide/real-arm.md). The
/// bounds are the measured numbers × 2.
#[test]
fn the_test_arm_with_three_samples_of_delay_at_0_half_and_rated_payload() {
    let exp = test_arm();
    for (kind, rms) in [
        (ControllerKind::CtcAdaptive, [0.70, 6.7, 68.0]),
        (ControllerKind::FirstAdaptive, [0.69, 12.9, 58.0]),
    ] {
        for (mass, rms) in [0.0, 2.5, 5.0].into_iter().zip(rms) {
            let m = run(&exp, kind, mass);
            // Within 10 % of the rated payload.
            check(&m, 2.0 * rms, 2.1, Some((mass, 0.5)));
        }
    }
}
