//! Closed-form kinematics of the Universal Robots family: six revolute joints, axes 2, 3
//! and 4 parallel, axes 5 and 6 intersecting (UR3/5/10/16 and their e-Series, and any arm
//! of that geometry).
//!
//! The standard closed form (K. P. Hawkins, "Analytic inverse kinematics for the Universal
//! Robots UR-5/UR-10 arms", Georgia Tech tech. report, 2013; ROS-Industrial
//! `ur_kinematics/src/ur_kin.cpp`) is written for the UR's Denavit–Hartenberg frames. Here
//! the same chain of steps is derived on the product-of-exponentials model
//! `T(q) = e^{ξ̂1 q1} ⋯ e^{ξ̂6 q6} M` (R. M. Murray, Z. Li, S. S. Sastry, *A Mathematical
//! Introduction to Robotic Manipulation*, 1994, eq. 3.26) read off the robot's own joint
//! axes at q = 0, so that no DH convention, base or tool frame has to be matched: a URDF
//! as ROS-Industrial or example-robot-data ship it is solved as it is, with any tool
//! centre point.
//!
//! With `u` the direction of axes 2–4 and `P` the point where axes 5 and 6 meet:
//!
//! 1. q1: joints 2–5 leave `P`'s component along `R1·u` unchanged (rotations about axes
//!    parallel to `u`, and about axes through `P`), so `(Rot(w1, q1)·u)·(P − p1) = const`:
//!    `A cos q1 + B sin q1 = C`, two shoulder branches (Hawkins eq. for θ1).
//! 2. q5: likewise `(R1·u)·z6 = u·Rot(w5, q5)·w6` for the target's axis-6 direction
//!    `z6`: two wrist branches (Hawkins' θ5 = ±acos).
//! 3. q6: `Rot(w6, q6)·k = Rot(w5, q5)ᵀ·u` with `k = R_M·R_Tᵀ·R1·u` (Paden–Kahan
//!    subproblem 1, Murray et al. §3.3.2); free in the wrist singularity (axis 6 ∥ u),
//!    where it keeps the hint's value.
//! 4. q2, q3, q4: the planar three-link problem left (Paden–Kahan subproblems 3 and 1 in
//!    the plane ⟂ u), two elbow branches; q4 from the remaining rotation about u.
//!
//! Up to 8 solutions (2 × 2 × 2). Each is polished by at most [`NEWTON_STEPS`] Newton
//! steps on the exact forward kinematics (URDF angles such as `1.57079632679` make the
//! axes parallel only to 1e-11; the closed form is then exact to that, the polish to
//! rounding) and kept only if it reproduces the pose within [`ACCEPT_TOLERANCE`].

use nalgebra::{Isometry3, Matrix3, Matrix6, Rotation3, UnitQuaternion, Vector3, Vector6};

use super::opw::wrap_angle;
use super::solutions::Solutions;
use super::solver::{ClosedFormBranches, ClosedFormKinematics, ClosedFormSolver};
use super::{pose_is_finite, rotation_log};

/// Largest angle (rad) between two axes that the detection still calls parallel, and
/// largest distance (m) between axes 5 and 6 that it calls intersecting.
pub const DETECT_TOLERANCE: f64 = 1e-9;

/// Newton steps that polish each closed-form solution on the exact kinematics.
pub const NEWTON_STEPS: usize = 4;

/// A polished solution is kept when its position error (m) plus orientation error (rad)
/// is at most this.
pub const ACCEPT_TOLERANCE: f64 = 1e-7;

/// Relative slack of the `acos` arguments: a pose on the boundary of the workspace (arm
/// stretched) is still solved.
const REACH_SLACK: f64 = 1e-10;

/// Wrist singularity band: when the component of `k` perpendicular to axis 6 is at most
/// this (axis 6 nearly parallel to axes 2–4), q6 keeps the hint's value.
const WRIST_SINGULAR: f64 = 1e-7;

/// The kinematics of a UR-type arm: joint axes at q = 0 in the base frame, the tool pose
/// at q = 0, and the constants of the closed form. Built by [`UrKinematics::detect`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UrKinematics {
    /// Unit axis directions at q = 0 (base frame).
    w: [Vector3<f64>; 6],
    /// A point on each axis at q = 0 (base frame).
    p: [Vector3<f64>; 6],
    /// Tool rotation and position at q = 0.
    m_rot: Matrix3<f64>,
    m_pos: Vector3<f64>,
    /// Direction of axes 2–4 (= w2) and the signs of w3, w4 along it.
    u: Vector3<f64>,
    sign: [f64; 3],
    /// Two unit vectors spanning the plane ⟂ u, `e1 × e2 = u`.
    e1: Vector3<f64>,
    e2: Vector3<f64>,
    /// The intersection of axes 5 and 6 in the tool frame.
    wrist_in_tool: Vector3<f64>,
    /// Axis 6 in the tool frame.
    axis6_in_tool: Vector3<f64>,
    /// `u·(P − p1)` at q = 0: the constant of step 1.
    lateral: f64,
}

/// All closed-form solutions of one pose: up to 8 joint vectors, no allocation.
pub type UrSolutions = Solutions;

/// Rotation by `angle` about the unit `axis` (Rodrigues).
fn rot(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(*axis), angle).into_inner()
}

/// The angles θ with `(Rot(w, θ)·a)·b = c` (Rodrigues: `A cos θ + B sin θ + C0 = c`);
/// `Err(excess)` when none (excess in the units of `a·b`), `Ok([θ, θ])` at a double root.
fn rotate_to_dot(
    w: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: f64,
) -> Result<[f64; 2], f64> {
    let c0 = w.dot(a) * w.dot(b);
    let ca = a.dot(b) - c0;
    let cb = w.cross(a).dot(b);
    two_angles(ca, cb, c - c0)
}

/// The angles θ with `A cos θ + B sin θ = C`: `atan2(B, A) ± acos(C/√(A²+B²))`.
fn two_angles(a: f64, b: f64, c: f64) -> Result<[f64; 2], f64> {
    let r = a.hypot(b);
    if r == 0.0 {
        return Err(c.abs());
    }
    let x = c / r;
    if x.abs() > 1.0 + REACH_SLACK {
        return Err(c.abs() - r);
    }
    let phi = b.atan2(a);
    let d = x.clamp(-1.0, 1.0).acos();
    Ok([phi + d, phi - d])
}

/// Signed angle from `a` to `b` about the unit `w` (both projected onto the plane ⟂ w):
/// Paden–Kahan subproblem 1. `None` when a projection is (nearly) zero.
fn angle_about(w: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>, floor: f64) -> Option<f64> {
    let a = a - w * w.dot(a);
    let b = b - w * w.dot(b);
    if a.norm() <= floor || b.norm() <= floor {
        return None;
    }
    Some(w.dot(&a.cross(&b)).atan2(a.dot(&b)))
}

/// Closest points of two lines: the distance between lines (p, a) and (q, b) and the
/// midpoint of the common perpendicular (`None` when parallel).
pub(crate) fn line_intersection(
    p: &Vector3<f64>,
    a: &Vector3<f64>,
    q: &Vector3<f64>,
    b: &Vector3<f64>,
) -> Option<(f64, Vector3<f64>)> {
    let n = a.cross(b);
    let nn = n.norm_squared();
    if nn <= 1e-12 {
        return None;
    }
    let d = q - p;
    let s = d.cross(b).dot(&n) / nn;
    let t = d.cross(a).dot(&n) / nn;
    let x = p + a * s;
    let y = q + b * t;
    Some(((x - y).norm(), 0.5 * (x + y)))
}

impl UrKinematics {
    /// The UR kinematics of a six-revolute-joint chain given by its axes at q = 0
    /// (`axes` unit or not, `points` on them, base frame) and its tool pose at q = 0, or
    /// `None` when the chain is not of that family: axes 2, 3, 4 parallel (within
    /// [`DETECT_TOLERANCE`]) and pairwise distinct, axis 1 not parallel to them, axes 5 and
    /// 6 intersecting and neither parallel to the other nor axis 5 to axes 2–4.
    pub fn detect(
        axes: &[Vector3<f64>; 6],
        points: &[Vector3<f64>; 6],
        tool: &Isometry3<f64>,
    ) -> Option<Self> {
        let finite = axes
            .iter()
            .chain(points)
            .all(|v| v.iter().all(|x| x.is_finite()));
        if !finite || !pose_is_finite(tool) || axes.iter().any(|a| a.norm() < 1e-12) {
            return None;
        }
        let w: [Vector3<f64>; 6] = std::array::from_fn(|i| axes[i].normalize());
        let u = w[1];
        let parallel = |a: &Vector3<f64>| a.cross(&u).norm() <= DETECT_TOLERANCE;
        if !(parallel(&w[2]) && parallel(&w[3])) {
            return None;
        }
        let off_axis = |a: &Vector3<f64>| a.cross(&u).norm() > 1e-6;
        if !off_axis(&w[0]) || !off_axis(&w[4]) || w[4].cross(&w[5]).norm() <= 1e-6 {
            return None;
        }
        let (gap, wrist) = line_intersection(&points[4], &w[4], &points[5], &w[5])?;
        if gap > DETECT_TOLERANCE {
            return None;
        }
        // Distinct parallel axes 2, 3, 4 (else the planar problem degenerates).
        let perp = |v: Vector3<f64>| v - u * u.dot(&v);
        if perp(points[2] - points[1]).norm() < 1e-6 || perp(points[3] - points[2]).norm() < 1e-6 {
            return None;
        }
        let e1 = u.cross(&w[0]).normalize();
        let e2 = u.cross(&e1);
        let m_rot = tool.rotation.to_rotation_matrix().into_inner();
        let m_pos = tool.translation.vector;
        Some(Self {
            w,
            p: *points,
            m_rot,
            m_pos,
            u,
            sign: [1.0, w[2].dot(&u).signum(), w[3].dot(&u).signum()],
            e1,
            e2,
            wrist_in_tool: m_rot.transpose() * (wrist - m_pos),
            axis6_in_tool: m_rot.transpose() * w[5],
            lateral: u.dot(&(wrist - points[0])),
        })
    }

    /// Tool pose at joint positions `q` (product of exponentials).
    pub fn forward(&self, q: &[f64; 6]) -> Isometry3<f64> {
        let (r, t) = self.forward_matrix(q, None);
        Isometry3::from_parts(
            t.into(),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
        )
    }

    /// Tool rotation and position at `q`; with `jac`, also the geometric Jacobian
    /// (rows: linear velocity of the tool point, angular velocity; base frame).
    fn forward_matrix(
        &self,
        q: &[f64; 6],
        jac: Option<&mut Matrix6<f64>>,
    ) -> (Matrix3<f64>, Vector3<f64>) {
        let mut r = Matrix3::identity();
        let mut t = Vector3::zeros();
        let mut axes = [(Vector3::zeros(), Vector3::zeros()); 6];
        for i in 0..6 {
            axes[i] = (r * self.w[i], r * self.p[i] + t);
            let ri = rot(&self.w[i], q[i]);
            // e^{ξ̂θ}: x ↦ Rᵢ(x − pᵢ) + pᵢ.
            t += r * (self.p[i] - ri * self.p[i]);
            r *= ri;
        }
        let tool = t + r * self.m_pos;
        if let Some(j) = jac {
            for (i, (w, p)) in axes.iter().enumerate() {
                let lin = w.cross(&(tool - p));
                for k in 0..3 {
                    j[(k, i)] = lin[k];
                    j[(k + 3, i)] = w[k];
                }
            }
        }
        (r * self.m_rot, tool)
    }

    /// Position (m) and orientation (rad) error of `q` against the target.
    fn error(
        &self,
        q: &[f64; 6],
        rt: &Matrix3<f64>,
        pt: &Vector3<f64>,
        jac: Option<&mut Matrix6<f64>>,
    ) -> Vector6<f64> {
        let (r, p) = self.forward_matrix(q, jac);
        let dr = rotation_log(&UnitQuaternion::from_rotation_matrix(
            &Rotation3::from_matrix_unchecked(rt * r.transpose()),
        ));
        let dp = pt - p;
        Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z)
    }

    /// Newton steps on the exact kinematics; the polished solution and its error
    /// (position + orientation).
    fn polish(&self, mut q: [f64; 6], rt: &Matrix3<f64>, pt: &Vector3<f64>) -> ([f64; 6], f64) {
        let mut jac = Matrix6::zeros();
        let mut e = self.error(&q, rt, pt, Some(&mut jac));
        let size = |e: &Vector6<f64>| e.fixed_rows::<3>(0).norm() + e.fixed_rows::<3>(3).norm();
        let mut err = size(&e);
        for _ in 0..NEWTON_STEPS {
            if err <= 1e-15 {
                break;
            }
            let Some(dq) = jac.lu().solve(&e) else { break };
            let trial: [f64; 6] = std::array::from_fn(|i| q[i] + dq[i]);
            let mut j2 = Matrix6::zeros();
            let e2 = self.error(&trial, rt, pt, Some(&mut j2));
            let err2 = size(&e2);
            if err2.is_nan() || err2 >= err {
                break;
            }
            (q, e, err, jac) = (trial, e2, err2, j2);
        }
        (q, err)
    }

    /// All closed-form solutions of `pose` (the tool frame of [`UrKinematics::detect`] in
    /// the base frame), polished and checked; each joint wrapped to (−π, π]. In the wrist
    /// singularity q6 is 0; see [`UrKinematics::inverse_near`].
    pub fn inverse(&self, pose: &Isometry3<f64>) -> UrSolutions {
        self.inverse_near(pose, &[0.0; 6])
    }

    /// Like [`UrKinematics::inverse`], with q6 (and q1 at the shoulder singularity, the
    /// wrist point on axis 1) taken from `hint` where the pose leaves it free.
    pub fn inverse_near(&self, pose: &Isometry3<f64>, hint: &[f64; 6]) -> UrSolutions {
        let mut out = UrSolutions::empty(());
        if !pose_is_finite(pose) || !hint.iter().all(|x| x.is_finite()) {
            return out;
        }
        let rt = pose.rotation.to_rotation_matrix().into_inner();
        let pt = pose.translation.vector;
        let wrist = pt + rt * self.wrist_in_tool;
        let z6 = rt * self.axis6_in_tool;
        // Step 1: (Rot(w1, q1)·u)·(P − p1) = lateral.
        let v = wrist - self.p[0];
        let shoulders = match rotate_to_dot(&self.w[0], &self.u, &v, self.lateral) {
            Ok(s) => s,
            Err(_) if (v - self.w[0] * self.w[0].dot(&v)).norm() <= 1e-9 => [hint[0]; 2],
            Err(excess) => {
                out.reach_excess = excess;
                return out;
            }
        };
        let mut excess = f64::INFINITY;
        for (k1, &q1) in shoulders.iter().enumerate() {
            if k1 == 1 && shoulders[1] == shoulders[0] {
                break;
            }
            let r1 = rot(&self.w[0], q1);
            let u1 = r1 * self.u;
            // Step 2: u·Rot(w5, q5)·w6 = (R1·u)·z6.
            let Ok(wrists) = rotate_to_dot(&self.w[4], &self.w[5], &self.u, u1.dot(&z6)) else {
                excess = excess.min(0.0);
                continue;
            };
            for &q5 in &wrists {
                let r5 = rot(&self.w[4], q5);
                // Step 3: Rot(w6, q6)·k = R5ᵀ·u.
                let k = self.m_rot * rt.transpose() * u1;
                let q6 = angle_about(&self.w[5], &k, &(r5.transpose() * self.u), WRIST_SINGULAR)
                    .unwrap_or(hint[5]);
                if let Some(e) = self.push_arm(&mut out, [q1, q5, q6], &rt, &pt) {
                    excess = excess.min(e);
                }
            }
        }
        out.reach_excess = if out.count > 0 { 0.0 } else { excess };
        out
    }

    /// Step 4 for known q1, q5, q6: the two elbow branches of q2, q3 and their q4,
    /// polished and pushed. Returns the planar reach excess when out of reach.
    fn push_arm(
        &self,
        out: &mut UrSolutions,
        [q1, q5, q6]: [f64; 3],
        rt: &Matrix3<f64>,
        pt: &Vector3<f64>,
    ) -> Option<f64> {
        let screw = |i: usize, q: f64| {
            let r = rot(&self.w[i], q);
            (r, self.p[i] - r * self.p[i])
        };
        // G = e^{−ξ̂1q1}·T·M⁻¹·e^{−ξ̂6q6}·e^{−ξ̂5q5} = e^{ξ̂2q2}·e^{ξ̂3q3}·e^{ξ̂4q4}.
        let (r1, t1) = screw(0, q1);
        let (r5, t5) = screw(4, q5);
        let (r6, t6) = screw(5, q6);
        // T·M⁻¹.
        let rtm = rt * self.m_rot.transpose();
        let ptm = pt - rtm * self.m_pos;
        // e^{−ξ̂1q1}·(T·M⁻¹): R1ᵀ(x − t1).
        let (ga, gb) = (r1.transpose() * rtm, r1.transpose() * (ptm - t1));
        // ·e^{−ξ̂6q6}: x ↦ R6ᵀ(x − t6).
        let (ga, gb) = (ga * r6.transpose(), gb - ga * r6.transpose() * t6);
        let (g_rot, g_pos) = (ga * r5.transpose(), gb - ga * r5.transpose() * t5);
        let target = g_rot * self.p[3] + g_pos;
        let plane = |x: Vector3<f64>| (self.e1.dot(&x), self.e2.dot(&x));
        let a = plane(self.p[2] - self.p[1]);
        let b = plane(self.p[3] - self.p[2]);
        let t = plane(target - self.p[1]);
        let delta2 = t.0 * t.0 + t.1 * t.1;
        let (la2, lb2) = (a.0 * a.0 + a.1 * a.1, b.0 * b.0 + b.1 * b.1);
        // |a + Rot(φ3)·b|² = δ²: (a·b) cos φ3 − (a×b) sin φ3 = (δ² − |a|² − |b|²)/2.
        let cross = a.0 * b.1 - a.1 * b.0;
        let rhs = 0.5 * (delta2 - la2 - lb2);
        let elbows = match two_angles(a.0 * b.0 + a.1 * b.1, -cross, rhs) {
            Ok(e) => e,
            Err(_) => {
                let d = delta2.sqrt();
                let (la, lb) = (la2.sqrt(), lb2.sqrt());
                return Some((d - (la + lb)).max((la - lb).abs() - d));
            }
        };
        let total = self
            .e1
            .cross(&(g_rot * self.e1))
            .dot(&self.u)
            .atan2(self.e1.dot(&(g_rot * self.e1)));
        for (ke, &phi3) in elbows.iter().enumerate() {
            if ke == 1 && elbows[1] == elbows[0] {
                break;
            }
            let (s, c) = phi3.sin_cos();
            let x = (a.0 + c * b.0 - s * b.1, a.1 + s * b.0 + c * b.1);
            let phi2 = t.1.atan2(t.0) - x.1.atan2(x.0);
            let phi4 = total - phi2 - phi3;
            let q = [
                q1,
                phi2 * self.sign[0],
                phi3 * self.sign[1],
                phi4 * self.sign[2],
                q5,
                q6,
            ];
            let q: [f64; 6] = std::array::from_fn(|i| wrap_angle(q[i]));
            let (q, err) = self.polish(q, rt, pt);
            if err <= ACCEPT_TOLERANCE {
                out.push(std::array::from_fn(|i| wrap_angle(q[i])));
            }
        }
        None
    }
}

/// Sequential inverse kinematics of a UR-type arm: for each pose, the solution nearest to
/// the previous sample (weighted joint distance) among all closed-form solutions and their
/// 2π-equivalents inside the joint limits (`ClosedFormSolver`, as [`super::IkSolver`]
/// for OPW arms; `ClosedFormSolver::kinematics` gives the `UrKinematics`).
/// Allocation-free.
pub type UrSolver = ClosedFormSolver<UrKinematics>;

impl ClosedFormKinematics for UrKinematics {
    fn branches(&self, pose: &Isometry3<f64>, hint: &[f64; 6]) -> ClosedFormBranches {
        let s = self.inverse_near(pose, hint);
        ClosedFormBranches::new(s.as_slice(), s.reach_excess().max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_angles_solves_the_trigonometric_equation() {
        for &(a, b, c) in &[(1.0, 2.0, 0.5), (-0.3, 0.7, -0.2), (2.0, 0.0, 2.0)] {
            let [x, y] = two_angles(a, b, c).unwrap();
            for t in [x, y] {
                assert!((a * t.cos() + b * t.sin() - c).abs() < 1e-14);
            }
        }
        assert!(two_angles(1.0, 1.0, 2.0).is_err());
    }

    #[test]
    fn lines_meet_where_they_cross() {
        let (d, x) = line_intersection(
            &Vector3::new(1.0, 0.0, 0.0),
            &Vector3::new(0.0, 1.0, 0.0),
            &Vector3::new(0.0, 2.0, 0.5),
            &Vector3::new(1.0, 0.0, 0.0),
        )
        .unwrap();
        assert!((d - 0.5).abs() < 1e-15);
        assert!((x - Vector3::new(1.0, 2.0, 0.25)).norm() < 1e-15);
    }
}
