//! Payload identification: the regressor is the payload's share of inverse
//! dynamics, the projection keeps parameters physical, the RLS recovers a
//! payload from noise-free data.

mod common;
use common::robots as robot_common;

use nalgebra::{Matrix3, Vector3};
use ofmpc::dynamics::{rnea, RobotDynamics, Workspace};
use ofmpc::ident::{
    joint_regressor, params_of, payload_of, pseudo_inertia, PayloadEstimator, PayloadParams,
    PayloadRls, RlsSettings, NUM_PARAMS,
};
use ofmpc::robot::Payload;
use robot_common::{robots, Rng};

fn random_payload(rng: &mut Rng) -> Payload {
    // A box of random size and mass, rotated, off the flange centre.
    let m = rng.range(0.1, 8.0);
    let (a, b, c) = (
        rng.range(0.01, 0.3),
        rng.range(0.01, 0.3),
        rng.range(0.01, 0.3),
    );
    let d = Vector3::new(
        m / 12.0 * (b * b + c * c),
        m / 12.0 * (a * a + c * c),
        m / 12.0 * (a * a + b * b),
    );
    let axis = Vector3::new(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    );
    let r = nalgebra::Rotation3::from_scaled_axis(axis).into_inner();
    Payload {
        mass: m,
        com: Vector3::new(
            rng.range(-0.2, 0.2),
            rng.range(-0.2, 0.2),
            rng.range(-0.2, 0.2),
        ),
        inertia: r * Matrix3::from_diagonal(&d) * r.transpose(),
    }
}

#[test]
fn regressor_is_the_payloads_share_of_inverse_dynamics() {
    let mut rng = Rng(11);
    for (name, robot) in robots(&mut rng) {
        let n = robot.dof();
        let mut ws = Workspace::new(&robot);
        let mut rows = vec![[0.0; NUM_PARAMS]; n];
        for _ in 0..20 {
            let p = random_payload(&mut rng);
            let mut loaded = robot.clone();
            loaded.set_payload(Some(p)).unwrap();
            let q = rng.vec(n, -2.0, 2.0);
            let qd = rng.vec(n, -2.0, 2.0);
            let qdd = rng.vec(n, -5.0, 5.0);
            let tau0 = rnea(&robot, &mut ws, &q, &qd, &qdd).unwrap().clone();
            let tau1 = rnea(&loaded, &mut ws, &q, &qd, &qdd).unwrap().clone();
            joint_regressor(&robot, &mut ws, &q, &qd, &qdd, &mut rows);
            // Also leaves τ of the robot as it is in ws.tau.
            assert!((&ws.tau - &tau0).norm() < 1e-12);
            let pi = params_of(&p);
            let scale = tau1.norm().max(1.0);
            for i in 0..n {
                let yp: f64 = (0..NUM_PARAMS).map(|k| rows[i][k] * pi[k]).sum();
                let want = tau1[i] - tau0[i];
                assert!(
                    (yp - want).abs() < 1e-10 * scale,
                    "{name} joint {i}: Yπ = {yp}, RNEA difference {want}"
                );
            }
        }
    }
}

#[test]
fn params_round_trip_and_pseudo_inertia_marks_physical_sets() {
    let mut rng = Rng(3);
    for _ in 0..100 {
        let p = random_payload(&mut rng);
        let pi = params_of(&p);
        let back = payload_of(&pi).unwrap();
        assert!((back.mass - p.mass).abs() < 1e-12);
        assert!((back.com - p.com).norm() < 1e-12);
        assert!((back.inertia - p.inertia).norm() < 1e-8 * p.inertia.norm().max(1.0));
        let eig = pseudo_inertia(&pi).symmetric_eigenvalues();
        assert!(eig.min() > -1e-12, "{eig:?}");
    }
    // A negative mass, or a principal moment beyond the sum of the others:
    // not physical, the pseudo-inertia says so.
    let mut bad = params_of(&Payload::point_mass(1.0));
    bad[0] = -1.0;
    assert!(pseudo_inertia(&bad).symmetric_eigenvalues().min() < 0.0);
    let violates = Payload {
        mass: 1.0,
        com: Vector3::zeros(),
        inertia: Matrix3::from_diagonal(&Vector3::new(0.1, 0.1, 0.5)),
    };
    assert!(
        pseudo_inertia(&params_of(&violates))
            .symmetric_eigenvalues()
            .min()
            < 0.0
    );
}

#[test]
fn rls_projection_keeps_the_estimate_physical() {
    // Data that pull the mass negative and the inertia out of the set.
    let mut rls = PayloadRls::new(RlsSettings::default(), PayloadParams::zeros()).unwrap();
    let mut rng = Rng(5);
    for _ in 0..200 {
        let rows: Vec<[f64; NUM_PARAMS]> = (0..6)
            .map(|_| std::array::from_fn(|_| rng.range(-1.0, 1.0)))
            .collect();
        let y: Vec<f64> = rows.iter().map(|r| -3.0 * r[0] - 2.0 * r[9]).collect();
        assert!(rls.update(&rows, &y));
        let pi = rls.estimate();
        assert!(pi[0] >= 0.0);
        let eig = pseudo_inertia(pi).symmetric_eigenvalues();
        assert!(eig.min() > -1e-9 * eig.max().max(1.0), "{eig:?}");
    }
    // Non-finite data are skipped.
    let before = rls.estimate().clone_owned();
    let rows = vec![[f64::NAN; NUM_PARAMS]; 6];
    assert!(!rls.update(&rows, &[0.0; 6]));
    assert_eq!(*rls.estimate(), before);
}

#[test]
fn estimator_recovers_a_payload_from_exact_motion_data() {
    // Exact data from inverse dynamics along a smooth excitation: constant
    // torque over each period is emulated by integrating the loaded robot.
    use ofmpc::sim::{LossSchedule, Plant, PlantSettings, Sensor};
    let robot = ofmpc::robot::Robot::irb140();
    let n = robot.dof();
    let truth = Payload {
        mass: 3.0,
        com: Vector3::new(0.02, -0.01, 0.05),
        inertia: Matrix3::from_diagonal(&Vector3::new(0.01, 0.012, 0.008)),
    };
    let mut loaded = robot.clone();
    loaded.set_payload(Some(truth)).unwrap();
    let q0 = [0.1, 0.3, -0.2, 0.2, 0.8, 0.1];
    let ts = 0.01;
    let mut plant = Plant::with_period(loaded.clone(), PlantSettings::default(), &q0, ts).unwrap();
    let mut sensor = Sensor::ideal(n, ts, LossSchedule::default());
    let mut model = RobotDynamics::new(robot.clone());
    let mut est = PayloadEstimator::new(n, RlsSettings::default(), PayloadParams::zeros()).unwrap();
    let mut ws = Workspace::new(&loaded);
    let mut x_prev = vec![0.0; 2 * n];
    let mut x = vec![0.0; 2 * n];
    sensor.measure(&plant.state(), &mut x_prev).unwrap();
    for k in 0..400 {
        // Computed torque on the true model along sinusoids + a PD term.
        let t = k as f64 * ts;
        let mut qdd = vec![0.0; n];
        for i in 0..n {
            let w = 1.0 + 0.7 * i as f64;
            let qr = q0[i] + 0.3 * (w * t).sin();
            let qdr = 0.3 * w * (w * t).cos();
            qdd[i] = -0.3 * w * w * (w * t).sin()
                + 100.0 * (qr - x_prev[i])
                + 20.0 * (qdr - x_prev[n + i]);
        }
        let tau = rnea(&loaded, &mut ws, &x_prev[..n], &x_prev[n..], &qdd)
            .unwrap()
            .clone();
        plant.advance(tau.as_slice()).unwrap();
        sensor.measure(&plant.state(), &mut x).unwrap();
        assert!(est.update(&mut model, &x_prev, &x, tau.as_slice(), ts));
        // The controller's model follows the estimate.
        model
            .robot_mut()
            .set_payload(payload_of(est.rls().estimate()))
            .unwrap();
        x_prev.copy_from_slice(&x);
    }
    let pi = est.rls().estimate();
    let want = params_of(&truth);
    assert!((pi[0] - 3.0).abs() < 0.01 * 3.0, "mass {}", pi[0]);
    for k in 1..4 {
        assert!(
            (pi[k] - want[k]).abs() < 0.01,
            "first moment {k}: {} vs {}",
            pi[k],
            want[k]
        );
    }
}
