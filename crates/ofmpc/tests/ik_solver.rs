//! IkSolver: choice of the closest solution within limits, continuity through the
//! wrist singularity, errors.

mod common;
use common::ik_model as ik_common;

use std::f64::consts::PI;

use ik_common::*;
use nalgebra::Isometry3;
use ofmpc::ik::{IkError, IkSolver, OpwParameters};

fn solver() -> IkSolver {
    IkSolver::new(OpwParameters::irb140(), LOWER, UPPER).unwrap()
}

#[test]
fn irb140_constructor_matches_urdf_limits() {
    let s = IkSolver::irb140();
    assert!(max_abs_diff(s.lower(), &LOWER) < 1e-10);
    assert!(max_abs_diff(s.upper(), &UPPER) < 1e-10);
}

#[test]
fn reproduces_q_from_a_nearby_previous_sample() {
    let s = solver();
    let opw = OpwParameters::irb140();
    let mut rng = Rng::new(10);
    let wrapped_distance = |a: &[f64; 6], b: &[f64; 6]| -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| {
                let d = (x - y).rem_euclid(2.0 * PI);
                d.min(2.0 * PI - d).powi(2)
            })
            .sum::<f64>()
            .sqrt()
    };
    let mut checked = 0;
    for _ in 0..2000 {
        let q = rng.joints_in_limits(0.05);
        let prev: [f64; 6] = std::array::from_fn(|i| q[i] + rng.uniform(-0.02, 0.02));
        let pose = opw.forward(&q);
        // q is the unique closest candidate when |prev − q| < ½·|q − s| for every
        // other solution s (any 2π-equivalent): triangle inequality. Near the elbow
        // or wrist singularity two solutions come closer than the perturbation.
        let step = prev
            .iter()
            .zip(&q)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        let separated = opw
            .inverse(&pose)
            .as_slice()
            .iter()
            .map(|sol| wrapped_distance(sol, &q))
            .filter(|d| *d > 1e-6)
            .all(|d| step < 0.5 * d);
        let got = s.solve_near(&pose, &prev).unwrap();
        if separated {
            // Exactly q, including the 2π-equivalent of joints 4 and 6 beyond ±180°.
            assert!(max_abs_diff(&got, &q) < 1e-9, "q {q:?} got {got:?}");
            checked += 1;
        }
    }
    assert!(checked > 1900, "only {checked} well-separated cases");
}

#[test]
fn choice_equals_brute_force_over_solutions_and_equivalents() {
    let opw = OpwParameters::irb140();
    let mut rng = Rng::new(11);
    for _ in 0..30 {
        let w: [f64; 6] = std::array::from_fn(|_| rng.uniform(0.1, 3.0));
        let s = solver().with_weights(w).unwrap();
        let pose = opw.forward(&rng.joints_in_limits(0.0));
        let prev = rng.joints_in_limits(0.0);
        let got = s.solve_near(&pose, &prev).unwrap();
        // Brute force: every analytic solution × every combination of 2πk, k ∈ −2..2.
        let mut best = (f64::INFINITY, [0.0; 6]);
        for sol in opw.inverse(&pose).as_slice() {
            for code in 0..5usize.pow(6) {
                let mut c = code;
                let mut cand = [0.0; 6];
                for i in 0..6 {
                    let k = (c % 5) as f64 - 2.0;
                    c /= 5;
                    cand[i] = sol[i] + 2.0 * PI * k;
                }
                if (0..6).any(|i| cand[i] < LOWER[i] - 1e-9 || cand[i] > UPPER[i] + 1e-9) {
                    continue;
                }
                let cost: f64 = (0..6).map(|i| w[i] * (cand[i] - prev[i]).powi(2)).sum();
                if cost < best.0 {
                    best = (cost, cand);
                }
            }
        }
        assert!(best.0.is_finite());
        assert!(
            max_abs_diff(&got, &best.1) < 1e-9,
            "got {got:?} brute {:?}",
            best.1
        );
    }
}

/// A smooth joint path with q5 = `q5_shift` at the middle sample (index n/2),
/// q6 travelling beyond +180°.
fn path(n: usize, q5_shift: f64) -> Vec<[f64; 6]> {
    (0..=n)
        .map(|k| {
            let t = k as f64 / n as f64;
            let wave = (2.0 * PI * t).sin();
            [
                -0.3 + 0.9 * t + 0.05 * wave,
                0.1 + 0.3 * t,
                -0.5 + 0.3 * t + 0.05 * wave,
                -0.5 + 3.3 * t,
                0.8 * (t - 0.5) + q5_shift,
                3.0 + 2.5 * t + 0.2 * wave,
            ]
        })
        .collect()
}

/// Runs the solver along the path; returns the largest q4/q6 step in the
/// redistribution samples (the singular sample and the one after it).
fn track(n: usize, q5_shift: f64) -> f64 {
    let opw = OpwParameters::irb140();
    let qs = path(n, q5_shift);
    let mut s = solver();
    s.set_previous(&qs[0]).unwrap();
    let mut max_step = [0.0f64; 6];
    for w in qs.windows(2) {
        for i in 0..6 {
            max_step[i] = max_step[i].max((w[1][i] - w[0][i]).abs());
        }
    }
    let mid = n / 2;
    let mut prev = qs[0];
    let mut redistribution_jump = 0.0f64;
    for (k, q) in qs.iter().enumerate() {
        let pose = opw.forward(q);
        let r = s.solve(&pose).unwrap();
        let back = opw.forward(&r);
        assert!(position_distance(&back, &pose) < 1e-9, "k {k}");
        assert!(rotation_distance(&back, &pose) < 1e-9, "k {k}");
        let singular = k == mid || k == mid + 1;
        if k > 0 {
            let q_prev = &qs[k - 1];
            for i in 0..6 {
                let step = (r[i] - prev[i]).abs();
                let path_step = (q[i] - q_prev[i]).abs();
                if singular && (i == 3 || i == 5) {
                    // q4 held, q6 takes the rest: at most two path steps of q4 + q6.
                    assert!(
                        step <= 2.0 * (max_step[3] + max_step[5]) + 1e-9,
                        "k {k} j {i}"
                    );
                    redistribution_jump = redistribution_jump.max(step);
                } else {
                    assert!(
                        step <= path_step + 1e-9,
                        "k {k} joint {} step {step:e}",
                        i + 1
                    );
                }
            }
            // q4 + q6 is what the pose determines: always continuous.
            let sum_step = ((r[3] + r[5]) - (prev[3] + prev[5])).abs();
            let path_sum = ((q[3] + q[5]) - (q_prev[3] + q_prev[5])).abs();
            assert!(sum_step <= path_sum + 1e-9, "k {k}");
        }
        if singular {
            if k == mid {
                assert_eq!(r[3], prev[3], "q4 must be held at the singular sample");
            }
            assert!(((r[3] + r[5]) - (q[3] + q[5])).abs() < 1e-9);
        } else {
            assert!(max_abs_diff(&r, q) < 1e-9, "k {k}: {r:?} vs {q:?}");
        }
        prev = r;
    }
    redistribution_jump
}

#[test]
fn path_through_wrist_singularity_is_tracked_continuously() {
    // Middle sample exactly at q5 = 0, and just inside the band (1e-9 rad).
    let coarse = track(2000, 0.0);
    track(2000, 1e-9);
    // Continuity: the redistribution jump shrinks with the path step.
    let fine = track(20000, 0.0);
    assert!(
        coarse > 0.0 && fine < coarse / 5.0,
        "coarse {coarse:e}, fine {fine:e}"
    );
}

#[test]
fn staying_in_the_wrist_singularity_holds_q4() {
    let opw = OpwParameters::irb140();
    let mut s = solver();
    let q0 = [0.2, 0.3, -0.4, 0.7, 0.0, -1.0];
    s.set_previous(&q0).unwrap();
    for k in 0..=500 {
        let t = k as f64 / 500.0;
        // q4 and q6 move, q5 stays 0: only q4 + q6 reaches the pose.
        let q = [
            0.2 + 0.3 * t,
            0.3,
            -0.4 + 0.2 * t,
            0.7 + 1.5 * t,
            0.0,
            -1.0 + 2.0 * t,
        ];
        let r = s.solve(&opw.forward(&q)).unwrap();
        assert_eq!(r[3], q0[3]);
        assert!(((r[3] + r[5]) - (q[3] + q[5])).abs() < 1e-9, "k {k}");
        for i in [0, 1, 2] {
            assert!((r[i] - q[i]).abs() < 1e-9);
        }
        assert!(r[4].abs() < 1e-9);
    }
}

#[test]
fn all_configurations_outside_limits_report_the_least_violating_joint() {
    let opw = OpwParameters::irb140();
    let mut lower = LOWER;
    let mut upper = UPPER;
    lower[0] = -0.5;
    upper[0] = 0.5;
    let s = IkSolver::new(opw, lower, upper).unwrap();
    // q1 = 1.0 for the front configurations, 1.0 − π for the back ones.
    let q = [1.0, 0.2, -0.1, 0.3, 0.4, 0.2];
    let err = s.solve_near(&opw.forward(&q), &[0.0; 6]).unwrap_err();
    match err {
        IkError::JointLimit {
            joint,
            value,
            lower,
            upper,
        } => {
            assert_eq!(joint, 1);
            assert!((value - 1.0).abs() < 1e-9);
            assert_eq!((lower, upper), (-0.5, 0.5));
        }
        other => panic!("expected JointLimit, got {other:?}"),
    }
    let msg = err.to_string();
    assert!(
        msg.contains("joint 1") && msg.contains("57.30°") && msg.contains("work offset"),
        "{msg}"
    );
}

#[test]
fn unreachable_pose_is_an_error_naming_the_position() {
    let mut s = solver();
    let before = *s.previous();
    let pose = Isometry3::translation(2.0, 0.5, 0.3);
    match s.solve(&pose) {
        Err(IkError::Unreachable { position, excess }) => {
            assert_eq!(position, [2.0, 0.5, 0.3]);
            assert!(excess > 1.0);
        }
        other => panic!("expected Unreachable, got {other:?}"),
    }
    assert_eq!(
        *s.previous(),
        before,
        "previous sample must survive an error"
    );
    let msg = s.solve(&pose).unwrap_err().to_string();
    assert!(
        msg.contains("(2.0000, 0.5000, 0.3000)") && msg.contains("work offset"),
        "{msg}"
    );
}

#[test]
fn non_finite_input_is_rejected() {
    let mut s = solver();
    let nan_pose = Isometry3::translation(f64::NAN, 0.0, 0.5);
    assert!(matches!(s.solve(&nan_pose), Err(IkError::NonFinite { .. })));
    let pose = OpwParameters::irb140().forward(&[0.1; 6]);
    let mut prev = [0.0; 6];
    prev[2] = f64::INFINITY;
    assert!(matches!(
        s.solve_near(&pose, &prev),
        Err(IkError::NonFinite { .. })
    ));
    assert!(matches!(
        s.set_previous(&prev),
        Err(IkError::NonFinite { .. })
    ));
}

#[test]
fn target_exactly_on_a_joint_limit_is_accepted() {
    let opw = OpwParameters::irb140();
    let s = solver();
    // q1 = +180° (the limit) and q6 = +400°.
    let q = [PI, 0.2, -0.3, 0.5, 0.6, 400f64.to_radians()];
    let prev = [3.0, 0.2, -0.3, 0.5, 0.6, 6.9];
    let got = s.solve_near(&opw.forward(&q), &prev).unwrap();
    assert!(max_abs_diff(&got, &q) < 1e-9, "{got:?}");
}
