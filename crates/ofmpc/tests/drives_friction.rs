//! Friction compensation (#11 item 2) on the paper's path, 0.25 kg: the
//! plant has 1 N·m Coulomb friction on every joint, the controller's drives
//! file says 0.8 N·m (20 % off). The compensation adds the estimate at the
//! reference's velocity to the torque.
//!
//! Measured (probe `drives_probe friction` / `friction-comp`): usual RMS
//! 0.151 → 0.082 mm, first steady 2.7e-8 → 6.3e-9 mm, second RMS 0.0198 →
//! 0.0180 mm; the second's steady hunting in the hold (≈ 0.05 mm) is NOT
//! removed by it (the 0.001 mm target is open).

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::gcode::{parse, ParseOptions, PAPER_TABLE1};
use ofmpc::motion::reference::{build_reference, Orientation};
use ofmpc::motion::trajectory::{CartesianTrajectory, TimingOptions};
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{Experiment, LoopSettings, PlantSettings, RunMetrics};

fn run(kind: ControllerKind, compensate: bool) -> RunMetrics {
    let mut robot = Robot::irb140();
    let text: String = (1..=6)
        .map(|j| format!("[joints.joint_{j}]\ncoulomb_nm = 0.8\nviscous_nms = 0.0\n"))
        .collect();
    robot
        .apply_drives(&Drives::from_toml_str(&text).unwrap())
        .unwrap();
    let program = parse(PAPER_TABLE1, &ParseOptions::default()).unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let reference = build_reference(&robot, &traj, Orientation::AtZero, 0.01).unwrap();
    let exp = Experiment {
        robot,
        reference,
        mpc: MpcSettings {
            friction_compensation: compensate,
            ..Default::default()
        },
        plant: PlantSettings {
            coulomb_friction: vec![1.0],
            ..Default::default()
        },
        loop_settings: LoopSettings::default(),
    };
    let (r, m) = exp
        .run(kind, &Payload::point_mass(0.25), &mut |_, _| {})
        .unwrap();
    assert!(r.outcome.is_completed(), "{kind}: {}", r.outcome);
    assert!(r
        .record
        .tau
        .iter()
        .chain(&r.record.q)
        .all(|v| v.is_finite()));
    m
}

#[test]
fn compensation_helps_tracking_and_the_first_algorithm_is_no_worse() {
    let (u0, u1) = (
        run(ControllerKind::Usual, false),
        run(ControllerKind::Usual, true),
    );
    assert!(
        u1.cartesian_error_rms_mm < 0.7 * u0.cartesian_error_rms_mm,
        "usual RMS {} → {}",
        u0.cartesian_error_rms_mm,
        u1.cartesian_error_rms_mm
    );
    let (f0, f1) = (
        run(ControllerKind::First, false),
        run(ControllerKind::First, true),
    );
    assert!(f1.cartesian_error_rms_mm <= f0.cartesian_error_rms_mm * 1.001);
    assert!(f1.steady_cartesian_error_mm <= f0.steady_cartesian_error_mm.max(1e-9));
    let (s0, s1) = (
        run(ControllerKind::Second, false),
        run(ControllerKind::Second, true),
    );
    assert!(s1.cartesian_error_rms_mm < s0.cartesian_error_rms_mm);
}
