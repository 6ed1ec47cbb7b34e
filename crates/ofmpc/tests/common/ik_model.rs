//! Shared helpers of the ik_* integration tests: an independent IRB 140 model built
//! from the URDF joint origins and axes, a product-of-exponentials FK, a seeded RNG
//! and pose comparisons that do not use the library's own error functions.
// Limits are the URDF's literal 10-decimal values, not approximations of π.
#![allow(dead_code, clippy::approx_constant)]

use std::f64::consts::PI;

use nalgebra::{DMatrix, Isometry3, Matrix3, Matrix4, Translation3, Unit, UnitQuaternion, Vector3};
use ofmpc::ik::ForwardKinematics;

/// Joint origins (xyz, parent frame, rpy = 0) and axes of irb140.urdf, joints 1–6.
pub const URDF_ORIGINS: [[f64; 3]; 6] = [
    [0.0, 0.0, 0.0],
    [0.07, 0.0, 0.352],
    [0.0, 0.0, 0.36],
    [0.239, 0.0, 0.0],
    [0.141, 0.0, 0.0],
    [0.065, 0.0, 0.0],
];
/// Joint axes of irb140.urdf.
pub const URDF_AXES: [[f64; 3]; 6] = [
    [0.0, 0.0, 1.0],
    [0.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [1.0, 0.0, 0.0],
];
/// Joint limits of irb140.urdf (rad).
pub const LOWER: [f64; 6] = [
    -3.1415926536,
    -1.5707963268,
    -4.0142572796,
    -3.4906585040,
    -2.0071286398,
    -6.9813170080,
];
/// Joint limits of irb140.urdf (rad).
pub const UPPER: [f64; 6] = [
    3.1415926536,
    1.9198621772,
    0.8726646260,
    3.4906585040,
    2.0071286398,
    6.9813170080,
];

/// URDF rpy (roll, pitch, yaw) → rotation Rz(yaw)·Ry(pitch)·Rx(roll).
fn rpy(r: f64, p: f64, y: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), y)
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), p)
        * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), r)
}

/// Per joint: (axis, origin), both in the base frame.
pub type JointFrames = [(Vector3<f64>, Vector3<f64>); 6];

/// The IRB 140 as a generic serial chain composed joint by joint, URDF style, with
/// the analytic geometric Jacobian. Allocation-free.
pub struct UrdfChain;

impl UrdfChain {
    /// Flange pose and, per joint, (axis in base frame, joint origin in base frame).
    pub fn chain(&self, q: &[f64]) -> (Isometry3<f64>, JointFrames) {
        let mut t = Isometry3::identity();
        let mut joints = [(Vector3::zeros(), Vector3::zeros()); 6];
        for i in 0..6 {
            let o = URDF_ORIGINS[i];
            t *= Translation3::new(o[0], o[1], o[2]);
            let axis = Unit::new_normalize(Vector3::from(URDF_AXES[i]));
            joints[i] = (t.rotation * axis.into_inner(), t.translation.vector);
            t *= UnitQuaternion::from_axis_angle(&axis, q[i]);
        }
        t *= rpy(0.0, PI / 2.0, 0.0);
        (t, joints)
    }
}

impl ForwardKinematics for UrdfChain {
    fn dof(&self) -> usize {
        6
    }
    fn flange_pose(&mut self, q: &[f64]) -> Isometry3<f64> {
        self.chain(q).0
    }
    fn flange_jacobian(&mut self, q: &[f64], j: &mut DMatrix<f64>) {
        let (t, joints) = self.chain(q);
        let p = t.translation.vector;
        for (i, (z, o)) in joints.iter().enumerate() {
            let v = z.cross(&(p - o));
            for r in 0..3 {
                j[(r, i)] = v[r];
                j[(r + 3, i)] = z[r];
            }
        }
    }
}

/// Rodrigues: rotation by `t` about unit axis `w`.
fn rodrigues(w: &Vector3<f64>, t: f64) -> Matrix3<f64> {
    let k = w.cross_matrix();
    Matrix3::identity() + k * t.sin() + k * k * (1.0 - t.cos())
}

/// Product of exponentials T(q) = e^{[S1]q1}…e^{[S6]q6}·M with space screws of the
/// revolute joints taken from the URDF at q = 0 (all link frames parallel to the
/// base there): axis ω_i, point p_i = sum of the joint origins.
pub fn poe(q: &[f64; 6]) -> Matrix4<f64> {
    let mut t = Matrix4::<f64>::identity();
    let mut p = Vector3::zeros();
    for i in 0..6 {
        p += Vector3::from(URDF_ORIGINS[i]);
        let w = Vector3::from(URDF_AXES[i]);
        let r = rodrigues(&w, q[i]);
        let mut e = Matrix4::identity();
        e.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        e.fixed_view_mut::<3, 1>(0, 3)
            .copy_from(&((Matrix3::identity() - r) * p));
        t *= e;
    }
    let mut m = Matrix4::<f64>::identity();
    m.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&rodrigues(&Vector3::y(), PI / 2.0));
    m.fixed_view_mut::<3, 1>(0, 3).copy_from(&p);
    t * m
}

pub use super::rng;

/// SplitMix64 (the tests' one copy): a small deterministic generator for reproducible
/// random tests.
pub use rng::SplitMix64 as Rng;

impl Rng {
    /// Uniform joint vector inside the URDF limits shrunk by `margin` rad.
    pub fn joints_in_limits(&mut self, margin: f64) -> [f64; 6] {
        std::array::from_fn(|i| self.uniform(LOWER[i] + margin, UPPER[i] - margin))
    }
}

/// Rotation matrix of a pose.
pub fn rot(p: &Isometry3<f64>) -> Matrix3<f64> {
    p.rotation.to_rotation_matrix().into_inner()
}

/// Position distance (m) between two poses.
pub fn position_distance(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    (a.translation.vector - b.translation.vector).norm()
}

/// Rotation angle (rad) between two poses, from the matrices:
/// atan2(|vee(E − Eᵀ)|/2, (tr E − 1)/2) with E = R_aᵀ R_b.
pub fn rotation_distance(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    let e = rot(a).transpose() * rot(b);
    let v = Vector3::new(
        e[(2, 1)] - e[(1, 2)],
        e[(0, 2)] - e[(2, 0)],
        e[(1, 0)] - e[(0, 1)],
    );
    (0.5 * v.norm()).atan2(0.5 * (e.trace() - 1.0))
}

/// Largest |a_i − b_i| over joints after wrapping each difference to (−π, π].
pub fn max_angle_diff_mod_2pi(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| {
            let d = (x - y).rem_euclid(2.0 * PI);
            d.min(2.0 * PI - d)
        })
        .fold(0.0, f64::max)
}

/// Largest |a_i − b_i| over joints.
pub fn max_abs_diff(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}
