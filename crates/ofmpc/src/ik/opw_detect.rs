//! OPW parameters read off any six-revolute chain: [`OpwParameters::detect`].
//!
//! The OPW model (Brandstötter, Angerer, Hofbaur 2014, Fig. 1 and eq. 1; the parameter
//! conventions of ROS-Industrial `opw_kinematics`) is an ortho-parallel arm with a
//! spherical wrist in a fixed canonical pose: at θ = 0, axis 1 is the base z axis, axes 2
//! and 3 point along y in the arm plane at (a1, b, c1) and (a1, b, c1 + c2), axis 4 along z
//! through the wrist centre (a1 + a2, b, c1 + c2 + c3), axis 5 along y and axis 6 along z,
//! both through the wrist centre; the raw end frame sits at c4 along axis 6 with the base
//! orientation. A robot's zero pose is that pose turned by some θ⁰ (the joint offsets
//! `offsets = −θ⁰`), each joint axis possibly opposite to the model's (`signs`), and its
//! flange some constant frame `tool` in the raw end frame.
//!
//! So the parameters follow from the joint axes at q = 0 one joint at a time, each step
//! undoing the rotations found before it:
//!
//! 1. axis 1 must be the base z axis (the model has no base transform): `s1 = sign(w1·z)`;
//! 2. axis 2 ⟂ axis 1: θ1⁰ turns the model's y onto ±w2 (the sign keeping |θ1⁰| ≤ π/2);
//!    in that turned frame axis 2 crosses the arm plane at (a1, c1);
//! 3. axis 3 ∥ axis 2: c2 and θ2⁰ are the distance and direction from axis 2 to axis 3;
//! 4. axes 4, 5, 6 meet at the wrist centre C (b is its lateral coordinate); axis 4 ⟂ axis
//!    3 gives θ2⁰ + θ3⁰, and C seen from axis 3 in that direction gives c3 (along axis 4,
//!    the sign chosen so that c3 ≥ 0) and a2 (across it);
//! 5. θ4⁰ turns the model's y onto ±w5, θ5⁰ the model's z onto ±w6; c4 is the flange
//!    origin's distance from C along axis 6, θ6⁰ the flange's turn about axis 6, and
//!    `tool` the rest (identity for a flange that follows the ROS-I `tool0` convention).
//!
//! Every condition is checked within [`OPW_DETECT_TOLERANCE`], and the result is accepted
//! only if its closed-form forward kinematics reproduces the chain's (product of
//! exponentials, Murray, Li, Sastry 1994, eq. 3.26) within that tolerance at test poses.

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use super::opw::{ry, rz, wrap_angle, OpwParameters};
use super::pose_is_finite;
use super::ur::line_intersection;

/// Largest deviation the detection accepts: between directions (rad, as the sine of the
/// angle), between lines that must meet (m), and between the closed form's forward
/// kinematics and the chain's at the test poses (m and rad).
pub const OPW_DETECT_TOLERANCE: f64 = 1e-9;

/// +1 for `x ≥ 0`, else −1.
fn sign(x: f64) -> f64 {
    if x >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// The chain's flange pose at `q` (product of exponentials: axes `w` through `p` at q = 0,
/// flange `m` at q = 0; Murray, Li, Sastry 1994, eq. 3.26).
fn chain_forward(
    w: &[Vector3<f64>; 6],
    p: &[Vector3<f64>; 6],
    m: &Isometry3<f64>,
    q: &[f64; 6],
) -> Isometry3<f64> {
    let mut x = Isometry3::identity();
    for i in 0..6 {
        let r = UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_unchecked(w[i]), q[i]);
        // e^{ξ̂θ}: y ↦ R(y − p) + p.
        let t = p[i] - r * p[i];
        x *= Isometry3::from_parts(Translation3::from(t), r);
    }
    x * m
}

/// Position (m) and orientation (rad) distance of two poses.
fn pose_distance(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let dp = (a.translation.vector - b.translation.vector).norm();
    (dp, a.rotation.angle_to(&b.rotation))
}

/// The arm part of the parameters (steps 1–4 of the module text): the OPW lengths, the arm
/// rotation `rz(θ1⁰)·ry(θ2⁰ + θ3⁰)`, the wrist centre, the angles θ1⁰..θ3⁰ and the signs
/// of joints 1–4.
struct Arm {
    lengths: [f64; 6],
    rotation: Matrix3<f64>,
    centre: Vector3<f64>,
    theta: [f64; 3],
    signs: [f64; 4],
}

/// Steps 1–4: `None` when the chain is not an ortho-parallel arm with a spherical wrist.
fn arm(w: &[Vector3<f64>; 6], p: &[Vector3<f64>; 6]) -> Option<Arm> {
    let tol = OPW_DETECT_TOLERANCE;
    // 1. Axis 1 is the base z axis.
    if w[0].x.hypot(w[0].y) > tol || p[0].x.hypot(p[0].y) > tol {
        return None;
    }
    let s1 = sign(w[0].z);
    // 2. Axis 2 ⟂ axis 1; θ1⁰ turns y onto s2·w2.
    if w[1].z.abs() > tol {
        return None;
    }
    let s2 = sign(w[1].y);
    let t1 = (-s2 * w[1].x).atan2(s2 * w[1].y);
    let r1 = rz(t1);
    let local = |v: &Vector3<f64>| r1.transpose() * v;
    let (w3, w4) = (local(&w[2]), local(&w[3]));
    let (p2, p3) = (local(&p[1]), local(&p[2]));
    let (a1, c1) = (p2.x, p2.z);
    // 3. Axis 3 ∥ axis 2, at distance c2 in direction θ2⁰.
    if w3.x.hypot(w3.z) > tol {
        return None;
    }
    let s3 = sign(w3.y);
    let (dx, dz) = (p3.x - a1, p3.z - c1);
    let c2 = dx.hypot(dz);
    if c2 <= tol {
        return None;
    }
    let t2 = dx.atan2(dz);
    // 4. Axes 4, 5, 6 meet at C; axis 4 ⟂ axis 3.
    let (gap, centre) = line_intersection(&p[3], &w[3], &p[4], &w[4])?;
    let off6 = (centre - p[5]).cross(&w[5]).norm();
    if gap > tol || off6 > tol || w4.y.abs() > tol {
        return None;
    }
    let c = local(&centre);
    let (ex, ez) = (c.x - p3.x, c.z - p3.z);
    let s4 = sign(ex * w4.x + ez * w4.z);
    let t23 = (s4 * w4.x).atan2(s4 * w4.z);
    let (s23, c23) = t23.sin_cos();
    let c3 = ex * s23 + ez * c23;
    let a2 = ex * c23 - ez * s23;
    Some(Arm {
        lengths: [a1, a2, c.y, c1, c2, c3],
        rotation: r1 * ry(t23),
        centre,
        theta: [t1, t2, t23 - t2],
        signs: [s1, 1.0, s3, s4],
    })
}

impl OpwParameters {
    /// The OPW parameters of a chain of six revolute joints given by its axes at q = 0
    /// (`axes`, unit or not; `points` on them; base frame) and its flange pose at q = 0,
    /// or `None` when the chain is not an ortho-parallel arm with a spherical wrist whose
    /// axis 1 is the base z axis (within `OPW_DETECT_TOLERANCE`): axes 2 ∥ 3, both ⟂ 1,
    /// axis 4 ⟂ 3, axes 4, 5, 6 meeting in one point, 5 ⟂ 4 and 6 ⟂ 5 (Brandstötter et
    /// al. 2014). The derivation is in the module text; the result's
    /// [`OpwParameters::forward`] is the chain's flange pose (checked at test poses).
    pub fn detect(
        axes: &[Vector3<f64>; 6],
        points: &[Vector3<f64>; 6],
        flange: &Isometry3<f64>,
    ) -> Option<Self> {
        let finite = axes
            .iter()
            .chain(points)
            .all(|v| v.iter().all(|x| x.is_finite()));
        if !finite || !pose_is_finite(flange) || axes.iter().any(|a| a.norm() < 1e-12) {
            return None;
        }
        let tol = OPW_DETECT_TOLERANCE;
        let w: [Vector3<f64>; 6] = std::array::from_fn(|i| axes[i].normalize());
        let arm = arm(&w, points)?;
        // 5. θ4⁰ turns y onto s5·w5, θ5⁰ turns z onto s6·w6 (both ⟂ the axis before).
        let w5 = arm.rotation.transpose() * w[4];
        if w5.z.abs() > tol {
            return None;
        }
        let s5 = sign(w5.y);
        let t4 = (-s5 * w5.x).atan2(s5 * w5.y);
        let r4 = arm.rotation * rz(t4);
        let w6 = r4.transpose() * w[5];
        if w6.y.abs() > tol {
            return None;
        }
        let s6 = sign(w6.z);
        let t5 = (s6 * w6.x).atan2(s6 * w6.z);
        let r5 = r4 * ry(t5);
        let axis6 = r5.column(2).into_owned();
        let rf = flange.rotation.to_rotation_matrix().into_inner();
        let c4 = (flange.translation.vector - arm.centre).dot(&axis6);
        let m = r5.transpose() * rf;
        let t6 = m[(1, 0)].atan2(m[(0, 0)]);
        let raw = Isometry3::from_parts(
            Translation3::from(arm.centre + axis6 * c4),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r5 * rz(t6))),
        );
        let theta = [arm.theta[0], arm.theta[1], arm.theta[2], t4, t5, t6];
        let [a1, a2, b, c1, c2, c3] = arm.lengths;
        let [s1, s2, s3, s4] = arm.signs;
        let params = Self {
            a1,
            a2,
            b,
            c1,
            c2,
            c3,
            c4,
            offsets: std::array::from_fn(|i| wrap_angle(-theta[i])),
            signs: [s1, s2, s3, s4, s5, s6],
            tool: raw.inverse() * flange,
        };
        params.validate().ok()?;
        params.reproduces(&w, points, flange).then_some(params)
    }

    /// Whether [`OpwParameters::forward`] is the chain's flange pose within
    /// [`OPW_DETECT_TOLERANCE`] at q = 0, at ±π/2 on each joint alone and at a few poses
    /// that turn every joint.
    fn reproduces(
        &self,
        w: &[Vector3<f64>; 6],
        p: &[Vector3<f64>; 6],
        flange: &Isometry3<f64>,
    ) -> bool {
        let mixed = [
            [0.3, -0.7, 1.1, -2.1, 0.9, 2.7],
            [-2.5, 1.3, -0.4, 0.8, -1.6, -0.2],
            [1.9, 0.2, -1.8, 3.0, 2.2, -1.1],
        ];
        let single = (0..12).map(|k| {
            let mut q = [0.0; 6];
            q[k / 2] = if k % 2 == 0 { FRAC_PI_2 } else { -PI / 3.0 };
            q
        });
        std::iter::once([0.0; 6])
            .chain(single)
            .chain(mixed)
            .all(|q| {
                let (dp, dr) = pose_distance(&self.forward(&q), &chain_forward(w, p, flange, &q));
                dp <= OPW_DETECT_TOLERANCE && dr <= OPW_DETECT_TOLERANCE
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The axes, points and flange of an OPW arm at q = 0, from its own forward kinematics
    /// (joint i's axis and point from the poses with joint i turned).
    fn chain_of(opw: &OpwParameters) -> ([Vector3<f64>; 6], [Vector3<f64>; 6], Isometry3<f64>) {
        let q0 = [0.0; 6];
        let t: [f64; 6] = std::array::from_fn(|i| -opw.offsets[i]);
        let arm = rz(t[0]) * ry(t[1] + t[2]);
        let r4 = arm * rz(t[3]);
        let r5 = r4 * ry(t[4]);
        let dirs = [
            Vector3::z(),
            rz(t[0]) * Vector3::y(),
            rz(t[0]) * Vector3::y(),
            arm * Vector3::z(),
            r4 * Vector3::y(),
            r5 * Vector3::z(),
        ];
        let w: [Vector3<f64>; 6] = std::array::from_fn(|i| dirs[i] * opw.signs[i]);
        let (s1, c1) = t[0].sin_cos();
        let on_plane = |x: f64, z: f64| Vector3::new(x * c1 - opw.b * s1, x * s1 + opw.b * c1, z);
        let (s2, c2) = t[1].sin_cos();
        let raw = opw.forward(&q0) * opw.tool.inverse();
        let centre = raw.translation.vector - r5 * Vector3::z() * opw.c4;
        let p = [
            Vector3::zeros(),
            on_plane(opw.a1, opw.c1),
            on_plane(opw.a1 + opw.c2 * s2, opw.c1 + opw.c2 * c2),
            centre,
            centre,
            centre,
        ];
        (w, p, opw.forward(&q0))
    }

    #[test]
    fn detects_the_parameters_an_arm_was_built_from() {
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
        for opw in [OpwParameters::irb140(), kuka] {
            let (w, p, f) = chain_of(&opw);
            let d = OpwParameters::detect(&w, &p, &f).expect("an OPW chain");
            for q in [[0.0; 6], [0.4, -0.3, 1.2, 2.0, -0.7, 0.9]] {
                let (dp, dr) = pose_distance(&d.forward(&q), &opw.forward(&q));
                assert!(dp < 1e-12 && dr < 1e-12, "{dp:e} {dr:e}");
            }
        }
    }
}
