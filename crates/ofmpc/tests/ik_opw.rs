//! Closed-form OPW kinematics of the IRB 140 against the URDF and PARAMETERS.md.
// The test poses are PARAMETERS.md's 9-decimal values (e.g. 0.707106781).
#![allow(clippy::approx_constant)]

mod common;
use common::ik_model as ik_common;
use common::robots as robot_common;

use std::f64::consts::PI;

use ik_common::*;
use nalgebra::{Isometry3, Matrix3, Vector3};
use ofmpc::ik::OpwParameters;

#[test]
fn forward_matches_parameter_test_poses() {
    let opw = OpwParameters::irb140();
    for (k, (q, p, r)) in robot_common::parameter_poses().into_iter().enumerate() {
        let pose = opw.forward(&q);
        let dp = (pose.translation.vector - Vector3::from(p)).amax();
        let dr = (rot(&pose) - Matrix3::from_row_slice(&r)).amax();
        // The table gives 9 decimals.
        assert!(
            dp < 1e-9 && dr < 1e-9,
            "P{k}: position {dp:e}, rotation {dr:e}"
        );
    }
}

#[test]
fn forward_matches_urdf_chain_and_product_of_exponentials() {
    let opw = OpwParameters::irb140();
    let mut rng = Rng::new(1);
    for _ in 0..1000 {
        // Beyond the limits too: the formulas must hold for every angle.
        let q: [f64; 6] = std::array::from_fn(|_| rng.uniform(-7.0, 7.0));
        let pose = opw.forward(&q);
        let (chain, _) = UrdfChain.chain(&q);
        let t = poe(&q);
        let pos = pose.translation.vector;
        assert!(position_distance(&pose, &chain) < 1e-12, "q {q:?}");
        assert!((rot(&pose) - rot(&chain)).amax() < 1e-12, "q {q:?}");
        assert!((pos - t.fixed_view::<3, 1>(0, 3)).amax() < 1e-12, "q {q:?}");
        assert!(
            (rot(&pose) - t.fixed_view::<3, 3>(0, 0)).amax() < 1e-12,
            "q {q:?}"
        );
    }
}

/// Every solution reproduces the pose; one of them equals q modulo 2π.
fn check_round_trip(opw: &OpwParameters, q: &[f64; 6], q_tol: f64) {
    let pose = opw.forward(q);
    let sols = opw.inverse(&pose);
    assert!(!sols.is_empty(), "no solution for q {q:?}");
    for s in sols.as_slice() {
        let back = opw.forward(s);
        assert!(position_distance(&back, &pose) < 1e-9, "q {q:?}, sol {s:?}");
        assert!(rotation_distance(&back, &pose) < 1e-9, "q {q:?}, sol {s:?}");
        assert!(s.iter().all(|x| x.abs() <= PI), "not wrapped: {s:?}");
    }
    let closest = sols
        .as_slice()
        .iter()
        .map(|s| max_angle_diff_mod_2pi(s, q))
        .fold(f64::INFINITY, f64::min);
    assert!(
        closest < q_tol,
        "q {q:?} not among solutions (closest {closest:e})"
    );
}

#[test]
fn inverse_round_trip_for_random_joints_within_limits() {
    let opw = OpwParameters::irb140();
    let mut rng = Rng::new(2);
    for _ in 0..2000 {
        check_round_trip(&opw, &rng.joints_in_limits(0.0), 1e-9);
    }
}

#[test]
fn inverse_gives_eight_distinct_solutions_for_a_generic_pose() {
    let opw = OpwParameters::irb140();
    // A pose close to the base: the back-bent shoulder branch reaches it too.
    let q = [0.3, -0.2, -0.4, 0.5, 0.7, -0.2];
    let sols = opw.inverse(&opw.forward(&q));
    assert_eq!(sols.len(), 8);
    let s = sols.as_slice();
    for i in 0..8 {
        for j in 0..i {
            assert!(
                max_angle_diff_mod_2pi(&s[i], &s[j]) > 1e-3,
                "duplicates {i} {j}"
            );
        }
    }
}

#[test]
fn inverse_at_singular_and_boundary_configurations() {
    let opw = OpwParameters::irb140();
    // Wrist centre on axis 1 (shoulder singularity): 0.360·0 + 0.380·sin θ3 = −0.070.
    let t3 = -(0.070f64 / 0.380).asin();
    // (q, tolerance on recovering q). At the reach boundary (arm stretched) the
    // elbow angle is acos(1 − δ) with δ ~ 1e-16 from rounding, so the pose fixes
    // q2, q3 only to ≈ √(2·1e-16) ≈ 1.5e-8 rad (the pose error is second order).
    let cases = [
        ([0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 1e-9),       // wrist straight
        ([0.4, 0.3, -0.6, 1.2, 0.0, -0.7], 1e-9),     // wrist singular, q4 + q6 only
        ([0.2, 0.1, -PI / 2.0, 0.4, 0.5, 0.3], 1e-7), // arm stretched (reach boundary)
        ([0.7, 0.0, t3 - PI / 2.0, 0.3, 0.9, 0.1], 1e-9), // shoulder singular
    ];
    for (q, q_tol) in cases {
        let pose = opw.forward(&q);
        let sols = opw.inverse(&pose);
        assert!(!sols.is_empty(), "{q:?}");
        for s in sols.as_slice() {
            let back = opw.forward(s);
            assert!(position_distance(&back, &pose) < 1e-9, "{q:?} -> {s:?}");
            assert!(rotation_distance(&back, &pose) < 1e-9, "{q:?} -> {s:?}");
        }
        // With the exact q as hint, the hinted inverse returns q itself.
        let near = opw.inverse_near(&pose, &q);
        let closest = near
            .as_slice()
            .iter()
            .map(|s| max_angle_diff_mod_2pi(s, &q))
            .fold(f64::INFINITY, f64::min);
        assert!(closest < q_tol, "{q:?}: closest {closest:e}");
    }
}

#[test]
fn unreachable_pose_has_no_solution_and_reports_the_excess() {
    let opw = OpwParameters::irb140();
    let pose = Isometry3::translation(1.5, 0.0, 0.712) * opw.forward(&[0.0; 6]).rotation;
    let sols = opw.inverse(&pose);
    assert!(sols.is_empty());
    // Flange z = base x, so the wrist centre is at x = 1.5 − 0.065 = 1.435 m,
    // z = 0.712: |(1.435 − 0.070, 0.712 − 0.352)| − (0.360 + 0.380).
    let expected = (1.365f64).hypot(0.36) - 0.74;
    assert!((sols.reach_excess() - expected).abs() < 1e-12);
}

#[test]
fn tool_transform_is_applied_consistently() {
    let mut opw = OpwParameters::irb140();
    let tool = Isometry3::new(
        Vector3::new(0.01, -0.02, 0.15),
        Vector3::new(0.1, 0.4, -0.3),
    );
    let plain = opw;
    opw.tool = tool;
    let mut rng = Rng::new(3);
    for _ in 0..200 {
        let q = rng.joints_in_limits(0.0);
        let expected = plain.forward(&q) * tool;
        let got = opw.forward(&q);
        assert!(position_distance(&got, &expected) < 1e-14);
        assert!(rotation_distance(&got, &expected) < 1e-14);
        check_round_trip(&opw, &q, 1e-9);
    }
}

#[test]
fn other_opw_geometries_round_trip() {
    // KUKA KR 6 R700 sixx (opw_kinematics example): a2 ≠ 0, negative signs.
    let kuka = OpwParameters {
        a1: 0.025,
        a2: -0.035,
        b: 0.0,
        c1: 0.400,
        c2: 0.315,
        c3: 0.365,
        c4: 0.080,
        offsets: [0.0, -PI / 2.0, 0.0, 0.0, 0.0, 0.0],
        signs: [-1.0, 1.0, 1.0, -1.0, 1.0, -1.0],
        tool: Isometry3::identity(),
    };
    // Synthetic arm with a lateral offset b.
    let lateral = OpwParameters {
        b: 0.05,
        a2: 0.02,
        ..OpwParameters::irb140()
    };
    let mut rng = Rng::new(4);
    for opw in [kuka, lateral] {
        opw.validate().unwrap();
        for _ in 0..500 {
            let q: [f64; 6] = std::array::from_fn(|_| rng.uniform(-PI, PI));
            check_round_trip(&opw, &q, 1e-8);
        }
    }
}
