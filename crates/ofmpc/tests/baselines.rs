//! The baseline controllers (issue #21) against the issue's targets: the
//! paper's path on the IRB 140 (0.5 m/s, 2.5 m/s², septic law, N = 10,
//! Ts = 10 ms, noise-free) with RMS no worse than 1.5× the independent
//! implementation's table, offset-free (steady joint error ≤ 1e-9 rad), and
//! the same on the 6-axis test arm (up to 1 kg for the fixed-gain ones,
//! 6 kg for ctc-adaptive); torque limits respected with the
//! integrators' anti-windup.

mod common;

use common::experiment::{experiment, run, steady};
use nalgebra::{DMatrix, DVector};
use ofmpc::control::DEFAULT_CTC_BANDWIDTH;
use ofmpc::control::{triple_pole_inertia_ratio_range, ControllerKind};
use ofmpc::dynamics::{JointSpaceDynamics, RobotDynamics};
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{PlantSettings, RunMetrics, RunStatus};

fn assert_offset_free(m: &RunMetrics) {
    assert_eq!(m.status, RunStatus::Ok, "{}: {}", m.name, m.reason);
    assert!(steady(m) <= 1e-9, "{}: steady {:e} rad", m.name, steady(m));
}

/// The issue's table (Cartesian RMS, mm, independent implementation) at
/// 1 kg and 6 kg.
const TABLE: [(ControllerKind, [f64; 2]); 3] = [
    (ControllerKind::Pid, [0.065, 0.22]),
    (ControllerKind::Ctc, [0.0057, 0.053]),
    (ControllerKind::DobMpc, [0.0082, 0.077]),
];

#[test]
fn baselines_meet_the_issue_table_on_the_paper_path() {
    let exp = experiment(Robot::irb140(), PAPER_TABLE1, None);
    for (kind, want) in TABLE {
        for (mass, table) in [1.0, 6.0].into_iter().zip(want) {
            let m = run(&exp, kind, mass);
            assert_offset_free(&m);
            assert!(
                m.cartesian_error_rms_mm <= 1.5 * table,
                "{}: RMS {} mm, table {table} mm",
                m.name,
                m.cartesian_error_rms_mm
            );
        }
    }
    // Adaptive against adaptive: the identified payload leaves the computed
    // torque nearly exact.
    let m = run(&exp, ControllerKind::CtcAdaptive, 6.0);
    assert_offset_free(&m);
    assert!(
        m.cartesian_error_rms_mm <= 0.001,
        "{}",
        m.cartesian_error_rms_mm
    );
    let est = m.payload_estimate_kg.unwrap();
    assert!((est - 6.0).abs() < 0.05, "{est}");
}

#[test]
fn baselines_carry_the_payload_range_on_the_test_arm() {
    let mut robot = Robot::from_urdf_str(include_str!("data/arm6.urdf")).unwrap();
    let d = Drives::from_toml_str(include_str!("data/arm6_drives.toml")).unwrap();
    robot.apply_drives(&d).unwrap();
    let exp = experiment(
        robot,
        include_str!("data/arc_yz.gcode"),
        Some([0.5, 0.11, 0.5]),
    );
    // Offset-free up to 1 kg. Heavier, the payload's inertia on the three
    // parallel pitch axes (shoulder_lift, elbow, wrist_1) raises the
    // plant/model inertia ratio beyond what the sampled triple pole tolerates
    // (measured: steady 2e-8 to 1e-6 rad at 2 kg, ctc and dob-mpc diverge at
    // 4 kg, joint 4; the Jury bound below); the identified model of
    // ctc-adaptive carries 6 kg.
    for kind in ControllerKind::BASELINES {
        for mass in [0.0, 1.0] {
            assert_offset_free(&run(&exp, kind, mass));
        }
    }
    let m = run(&exp, ControllerKind::CtcAdaptive, 6.0);
    assert_offset_free(&m);
    assert!(
        m.cartesian_error_rms_mm <= 0.001,
        "{}",
        m.cartesian_error_rms_mm
    );
}

/// `H(q)` of `robot` carrying a point mass `mass` at the flange.
fn inertia(robot: &Robot, q: &[f64], mass: f64) -> DMatrix<f64> {
    let mut r = robot.clone();
    r.set_payload(Some(Payload::point_mass(mass))).unwrap();
    let n = r.dof();
    let (mut h, mut c, mut g) = (
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
        DVector::zeros(n),
    );
    RobotDynamics::new(r).terms(q, &vec![0.0; n], &mut h, &mut c, &mut g);
    h
}

/// The largest generalized eigenvalue `λmax(Ĥ⁻¹H)`: the inertia ratio the
/// computed-torque loop sees along its worst direction (control::baseline).
fn worst_inertia_ratio(nominal: &DMatrix<f64>, actual: &DMatrix<f64>) -> f64 {
    let l_inv = nominal
        .clone()
        .cholesky()
        .unwrap()
        .l()
        .try_inverse()
        .unwrap();
    (&l_inv * actual * l_inv.transpose())
        .symmetric_eigenvalues()
        .max()
}

/// Why the fixed-gain computed torque loses the test arm at 4 kg: the
/// largest generalized eigenvalue of `Ĥ⁻¹H` at the start pose against the
/// sampled triple pole's Jury bound (2.83 at 150 rad/s, Ts = 10 ms).
#[test]
fn ctc_on_the_test_arm_is_stable_where_the_jury_bound_says() {
    let mut robot = Robot::from_urdf_str(include_str!("data/arm6.urdf")).unwrap();
    let d = Drives::from_toml_str(include_str!("data/arm6_drives.toml")).unwrap();
    robot.apply_drives(&d).unwrap();
    let exp = experiment(
        robot,
        include_str!("data/arc_yz.gcode"),
        Some([0.5, 0.11, 0.5]),
    );
    let q0 = exp.reference.q(0).to_vec();
    let nominal = inertia(&exp.robot, &q0, 0.0);
    let (_, r_max) = triple_pole_inertia_ratio_range(DEFAULT_CTC_BANDWIDTH, exp.mpc.ts);
    assert!((r_max - 2.83).abs() < 0.01, "{r_max}");
    // Measured: the ratios grow linearly with the mass (1 + m λmax(J Ĥ⁻¹ Jᵀ)).
    for (mass, want) in [(1.0, 1.656), (2.0, 2.313), (4.0, 3.626), (6.0, 4.938)] {
        let r = worst_inertia_ratio(&nominal, &inertia(&exp.robot, &q0, mass));
        assert!((r - want).abs() < 0.01, "{mass} kg: ratio {r}");
        let m = run(&exp, ControllerKind::Ctc, mass);
        if r < 0.9 * r_max {
            assert_eq!(m.status, RunStatus::Ok, "{mass} kg: {}", m.reason);
        } else {
            assert!(r > 1.1 * r_max);
            assert_eq!(m.status, RunStatus::Diverged, "{mass} kg: {}", m.reason);
        }
    }
    // The IRB 140 at its 6 kg stays inside the bound.
    let irb = experiment(Robot::irb140(), PAPER_TABLE1, None);
    let q0 = irb.reference.q(0).to_vec();
    let r = worst_inertia_ratio(
        &inertia(&irb.robot, &q0, 0.0),
        &inertia(&irb.robot, &q0, 6.0),
    );
    assert!(r < 0.8 * r_max, "{r}");
}

#[test]
fn baselines_respect_torque_limits_and_do_not_wind_up() {
    // Joint 1 limited at 26 N·m (the path asks 26.4 at 0.25 kg), limits in
    // the plant and the controllers: clipped, and offset-free afterwards.
    let mut robot = Robot::irb140();
    robot
        .apply_drives(&Drives::from_toml_str("[joints.joint_1]\nmax_torque_nm = 26.0\n").unwrap())
        .unwrap();
    let mut exp = experiment(robot, PAPER_TABLE1, None);
    exp.mpc.torque_limits = true;
    exp.plant = PlantSettings {
        torque_limits: true,
        ..Default::default()
    };
    for kind in ControllerKind::BASELINES {
        let m = run(&exp, kind, 0.25);
        assert_offset_free(&m);
        assert!(
            m.torque_max_nm[0] <= 26.0 + 1e-9,
            "{}: {:?}",
            m.name,
            m.torque_max_nm
        );
    }
}
