//! Helpers of the inverse-kinematics tests: pose distances and random joint vectors
//! (with [`super::rng`]).
#![allow(dead_code)]

use nalgebra::Isometry3;
use ofmpc::robot::Robot;
use std::f64::consts::PI;

/// Position (m) and orientation (rad) distance between two poses, computed from the
/// rotation matrices (angle = acos((tr R − 1)/2), through atan2 for accuracy).
pub fn distance(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let dp = (a.translation.vector - b.translation.vector).norm();
    let r = (a.rotation.inverse() * b.rotation).to_rotation_matrix();
    let m = r.matrix();
    let s = 0.5
        * nalgebra::Vector3::new(
            m[(2, 1)] - m[(1, 2)],
            m[(0, 2)] - m[(2, 0)],
            m[(1, 0)] - m[(0, 1)],
        )
        .norm();
    let c = 0.5 * (m.trace() - 1.0);
    (dp, s.atan2(c))
}

/// A random pose of a 6-joint arm within its limits (clipped to ±π).
pub fn random_q(robot: &Robot, rng: &mut super::rng::SplitMix64) -> [f64; 6] {
    let j = robot.joints();
    std::array::from_fn(|i| rng.uniform(j[i].limits.lower.max(-PI), j[i].limits.upper.min(PI)))
}

/// The joint limits of a 6-joint arm as arrays.
pub fn limits(robot: &Robot) -> ([f64; 6], [f64; 6]) {
    let (lo, up) = (robot.lower_limits(), robot.upper_limits());
    (
        std::array::from_fn(|i| lo[i]),
        std::array::from_fn(|i| up[i]),
    )
}

/// Same joint angle up to a multiple of 2π. The numeric solvers stop at a pose error of
/// about 1e-10; near a singularity (elbow stretched, wrist straight) that leaves joint
/// errors of 1e-6 rad, so the comparison allows 1e-4 rad (distinct branches differ by far
/// more away from singularities).
pub fn same_angle(a: f64, b: f64) -> bool {
    let d = (a - b).rem_euclid(2.0 * PI);
    d.min(2.0 * PI - d) < 1e-4
}
