//! Issue 35 at 1 kHz: the settings of `examples/real-arm-1khz.toml` (Ts = 1 ms,
//! horizon 50, two samples of delay, 20-bit encoders with encoder velocity,
//! friction known 20 % low, 1e-6 rad noise, torque limits on the first 5
//! torques, every link's inertial parameters 10 % off, `q_du = 3e-3`, the
//! wrist's stiff hold 0.1, the model centred at 3 kg) on a short path: the
//! paper's work offset, two long moves in y and back (about 2 s of motion).
//! And the stiff hold with the structured solver: the same torques as the
//! dense one.
//!
//! Measured on this short path (release): every run "ok" (the hold within 2
//! encoder counts); RMS / steady (mm) at 0 / 6 kg: first-adaptive
//! 0.0133 / 0.0016, 0.0108 / 0.0025; second-adaptive 0.0029 / 0.0023,
//! 0.0070 / 0.0024; ctc-adaptive 0.0051 / 0.0018, 0.0021 / 0.0023; dob-mpc
//! (its payload fitted at rest) 0.0098 / 0.0012, 0.0097 / 0.0019 (before the
//! fit 0.0153 / 0.0015, 0.0188 / 0.0016); estimates 0.03–0.20 and 5.47–6.15 kg.
//! The stiff hold's peers (`first`, 2 kg, 10 ms): dense and structured RMS
//! 0.0285 mm, steady 0.0011 mm; without the factor 0.0014 mm.
//! The whole preset's numbers are in docs/guide/real-arm.md.

mod common;

use ofmpc::control::{BaselineSettings, ControllerKind, MpcSettings, Solver, Weight};
use ofmpc::gcode::{parse, ParseOptions};
use ofmpc::motion::{build_reference, CartesianTrajectory, Orientation, TimingOptions};
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{Experiment, LoopSettings, PlantSettings, RunMetrics, RunStatus};

const SHORT_IRB140: &str = "G21 G90\nG10 L2 P1 X150 Y0 Z-250\nG54 G17\n\
    G00 X630 Y0 Z400\nG00 X630 Y-200 Z400\nG00 X630 Y200 Z400\nG00 X630 Y0 Z400\nM30\n";

const COULOMB: [f64; 6] = [5.0, 5.0, 3.0, 1.0, 1.0, 0.5];
const VISCOUS: [f64; 6] = [8.0, 8.0, 4.0, 1.0, 1.0, 0.5];

/// The IRB 140 with the drives' friction estimates 20 % below the plant's.
fn robot() -> Robot {
    let mut robot = Robot::irb140();
    let text: String = (0..6)
        .map(|j| {
            format!(
                "[joints.joint_{}]\ncoulomb_nm = {}\nviscous_nms = {}\n",
                j + 1,
                0.8 * COULOMB[j],
                0.8 * VISCOUS[j]
            )
        })
        .collect();
    robot
        .apply_drives(&Drives::from_toml_str(&text).unwrap())
        .unwrap();
    robot
}

/// The short path at `ts` with friction in the plant and its compensation.
fn experiment(ts: f64, mpc: MpcSettings, plant: PlantSettings) -> Experiment {
    let robot = robot();
    let program = parse(SHORT_IRB140, &ParseOptions::default()).unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let reference = build_reference(&robot, &traj, Orientation::AtZero, ts).unwrap();
    Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc: MpcSettings {
            ts,
            torque_limits: true,
            friction_compensation: true,
            ..mpc
        },
        plant: PlantSettings {
            torque_limits: true,
            coulomb_friction: COULOMB.to_vec(),
            viscous_friction: VISCOUS.to_vec(),
            substep: 2e-4,
            ..plant
        },
        loop_settings: LoopSettings::default(),
        // As the preset: dob-mpc identifies its payload at rest (the other
        // kinds do not read it).
        baselines: BaselineSettings {
            dob_identify_at_rest: true,
            ..Default::default()
        },
    }
}

/// `examples/real-arm-1khz.toml` on the short path.
fn preset() -> Experiment {
    experiment(
        0.001,
        MpcSettings {
            horizon: 50,
            solver: Solver::Structured,
            constraint_horizon: Some(5),
            delay_compensation: true,
            observer_friction: true,
            friction_creep: true,
            q_du: Weight::Scalar(3e-3),
            hold_q_du_scale: Weight::Diagonal(vec![1.0, 1.0, 1.0, 0.1, 0.1, 0.1]),
            model_payload_kg: 3.0,
            max_payload_kg: 9.0,
            payload_com_max_m: 0.2,
            ..Default::default()
        },
        PlantSettings {
            encoder_counts: 1 << 20,
            velocity_from_encoder: true,
            delay_samples: 2,
            position_noise: 1e-6,
            inertia_error: 0.1,
            ..Default::default()
        },
    )
}

fn run(exp: &Experiment, kind: ControllerKind, mass: f64) -> RunMetrics {
    let (_, m) = exp
        .run(kind, &Payload::point_mass(mass), &mut |_, _| {})
        .unwrap();
    eprintln!(
        "{}: {} RMS {:.4} steady {:.4} mm, est {:?}, hold p-p {:?} counts",
        m.name,
        m.status,
        m.cartesian_error_rms_mm,
        m.steady_cartesian_error_mm,
        m.payload_estimate_kg,
        m.hold_error_pp_counts
    );
    m
}

/// Issue 35's targets at 1 kHz, as reached: "ok" (the hold within 2 encoder
/// counts), steady ≤ 0.005 mm (target 0.01; measured ≤ 0.0025), RMS ≤ 0.05 mm
/// (target 0.1; measured ≤ 0.019), the estimate within 10 % of the rated 6 kg
/// (dob-mpc's from its hold at rest, `dob_identify_at_rest`).
#[test]
fn the_offset_free_kinds_hold_at_1_khz_at_0_and_rated_payload() {
    let exp = preset();
    for mass in [0.0, 6.0] {
        for kind in [
            ControllerKind::FirstAdaptive,
            ControllerKind::SecondAdaptive,
            ControllerKind::CtcAdaptive,
            ControllerKind::DobMpc,
        ] {
            let m = run(&exp, kind, mass);
            assert_eq!(m.status, RunStatus::Ok, "{}: {}", m.name, m.reason);
            // Counts as a ratio of the error to one count: 2 to rounding.
            assert!(m.hold_error_pp_counts.unwrap() <= 2.0 + 1e-6, "{}", m.name);
            assert!(m.steady_cartesian_error_mm <= 0.005, "{}", m.name);
            assert!(m.cartesian_error_rms_mm <= 0.05, "{}", m.name);
            if kind.is_adaptive() || kind == ControllerKind::DobMpc {
                let est = m.payload_estimate_kg.unwrap();
                assert!((est - mass).abs() <= 0.6, "{}: estimate {est} kg", m.name);
            }
        }
    }
}

/// The stiff hold (`hold_q_du_scale`) with the structured solver: the same
/// run as with the dense one (the two solvers give the same `ΔU` to
/// rounding), and not the run without the factor (the gate fires: the
/// wrist rests and creeps on the path's hold). Ts = 10 ms, horizon 10,
/// friction only (no quantization to amplify the rounding).
#[test]
fn the_stiff_hold_is_the_same_with_both_solvers() {
    let settings = |solver, scale: f64| MpcSettings {
        horizon: 10,
        solver,
        q_du: Weight::Scalar(1e-4),
        hold_q_du_scale: Weight::Diagonal(vec![1.0, 1.0, 1.0, scale, scale, scale]),
        ..Default::default()
    };
    let metrics = |solver, scale| {
        let exp = experiment(0.01, settings(solver, scale), PlantSettings::default());
        run(&exp, ControllerKind::First, 2.0)
    };
    let dense = metrics(Solver::DenseQr, 0.01);
    let structured = metrics(Solver::Structured, 0.01);
    let unscaled = metrics(Solver::Structured, 1.0);
    let close = |a: &RunMetrics, b: &RunMetrics, tol: f64| {
        a.steady_joint_error_max_rad
            .iter()
            .zip(&b.steady_joint_error_max_rad)
            .chain(a.joint_error_rms_rad.iter().zip(&b.joint_error_rms_rad))
            .all(|(x, y)| (x - y).abs() <= tol * x.abs().max(y.abs()).max(1e-12))
    };
    assert!(
        close(&dense, &structured, 1e-6),
        "{dense:?}\n{structured:?}"
    );
    assert!(
        !close(&structured, &unscaled, 1e-3),
        "the factor changed nothing"
    );
}
