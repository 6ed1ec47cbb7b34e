//! Inverse kinematics: Cartesian flange pose → joint positions.
//!
//! The parts, one per file:
//!
//! - `opw`: the closed-form solver of Brandstötter, Hofbaur et al. (2014) for
//!   ortho-parallel arms with a spherical wrist (ABB, KUKA, Fanuc, Stäubli six-axis
//!   arms), with [`OpwParameters::irb140`] matching this project's URDF `flange` frame.
//!   It returns all (up to 8) solutions without allocating.
//! - `opw_detect`: [`OpwParameters::detect`] reads the OPW parameters off any
//!   six-revolute chain's joint axes (a URDF as ROS-Industrial ships it), or says it is
//!   not of that form.
//! - `solver`: `ClosedFormSolver` ([`IkSolver`] for OPW arms, [`UrSolver`] for the UR
//!   family) picks, from the analytic solutions and their
//!   2π-equivalents inside the joint limits, the one closest to the previous sample,
//!   and keeps the result continuous through the wrist singularity.
//! - `ur`: the closed form of the Universal Robots family (axes 2–4 parallel, axes 5
//!   and 6 intersecting; Hawkins 2013) on the product-of-exponentials model read off the
//!   robot's joint axes, up to 8 solutions, and [`UrSolver`], the nearest one within the
//!   limits.
//! - `numeric`: [`NumericIk`], damped least squares (Levenberg–Marquardt with
//!   adaptive damping) for any robot that implements [`ForwardKinematics`].
//!
//! Conventions: SI units and radians; poses are the flange frame expressed in the
//! robot base frame (`base_link`); rotation errors are measured with the SO(3) log
//! map ([`rotation_log`]) in the base frame.
//!
//! ```
//! use ofmpc::ik::{IkSolver, OpwParameters};
//!
//! let opw = OpwParameters::irb140();
//! let q = [0.3, -0.4, 0.5, 1.0, -0.6, 2.0];
//! let pose = opw.forward(&q); // URDF `flange` pose
//! assert!(!opw.inverse(&pose).is_empty()); // all configurations, no allocation
//!
//! let mut ik = IkSolver::irb140(); // data-sheet joint limits
//! ik.set_previous(&[0.31, -0.41, 0.5, 1.0, -0.6, 2.0])?; // e.g. the measured start
//! let sol = ik.solve(&pose)?; // closest to the previous sample
//! assert!(sol.iter().zip(&q).all(|(a, b)| (a - b).abs() < 1e-9));
//! # Ok::<(), ofmpc::ik::IkError>(())
//! ```

use nalgebra::{DMatrix, Isometry3, UnitQuaternion, Vector3};

pub(crate) mod numeric;
pub(crate) mod opw;
pub(crate) mod opw_detect;
pub(crate) mod robust;
mod solutions;
pub(crate) mod solver;
pub(crate) mod ur;

pub use numeric::{NumericIk, NumericIkSettings};
pub use opw::OpwParameters;
pub(crate) use robust::IkLimitHit;
pub use robust::{RobustIk, RobustIkSettings};
pub use solver::IkSolver;
pub(crate) use ur::UrKinematics;
pub use ur::UrSolver;

/// What the numeric IK needs of a robot model: flange pose and geometric Jacobian.
///
/// Implementations must not allocate in either method when the caller's buffers
/// are sized correctly: [`NumericIk::solve`] calls them once per iteration.
pub trait ForwardKinematics {
    /// Number of joints `n`.
    fn dof(&self) -> usize;
    /// Pose of the flange frame in the base frame at joint positions `q` (length `n`).
    fn flange_pose(&mut self, q: &[f64]) -> Isometry3<f64>;
    /// Writes the geometric Jacobian (6×n) at `q` into `j`, which the caller has
    /// sized 6×n: rows 0–2 map q̇ to the linear velocity of the flange origin, rows
    /// 3–5 to the angular velocity of the flange, both expressed in the base frame.
    fn flange_jacobian(&mut self, q: &[f64], j: &mut DMatrix<f64>);
}

/// Errors of the inverse kinematics. Each message says what to change.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IkError {
    /// No arm configuration reaches the pose: the wrist centre lies outside the
    /// reachable shell of the arm.
    #[error(
        "flange pose at ({:.4}, {:.4}, {:.4}) m is out of reach: its wrist centre lies \
         {:.2} mm outside the arm's workspace; move the target towards the robot \
         (e.g. change the work offset) or use a shorter tool",
        position[0], position[1], position[2], excess * 1e3
    )]
    Unreachable {
        /// Requested flange position in the base frame (m).
        position: [f64; 3],
        /// Distance (m) by which the wrist centre misses the reachable shell
        /// (smallest over the arm configurations).
        excess: f64,
    },
    /// Every configuration that reaches the pose violates a joint limit; the
    /// fields describe the least-violating one (its worst joint).
    #[error(
        "joint {joint} would have to be at {:.2}° but its range is {:.2}° … {:.2}° \
         (no arm configuration reaching this pose respects the joint limits); shift the \
         target (work offset) or change the tool orientation",
        value.to_degrees(), lower.to_degrees(), upper.to_degrees()
    )]
    JointLimit {
        /// Joint number, 1-based.
        joint: usize,
        /// Value the joint would need (rad), the 2π-equivalent nearest to its range.
        value: f64,
        /// Lower limit (rad).
        lower: f64,
        /// Upper limit (rad).
        upper: f64,
    },
    /// A pose, seed or parameter contained NaN or infinity.
    #[error("{what} contains NaN or infinite values; check the computation that produced it")]
    NonFinite {
        /// Which input was not finite.
        what: &'static str,
    },
    /// A joint's limits are not an interval (`lower > upper`) or not finite.
    #[error(
        "joint {joint} has invalid limits [{lower}, {upper}] rad; lower must be ≤ upper \
         and both finite"
    )]
    InvalidLimits {
        /// Joint number, 1-based.
        joint: usize,
        /// Given lower limit (rad).
        lower: f64,
        /// Given upper limit (rad).
        upper: f64,
    },
    /// A kinematic parameter or setting is out of its valid range.
    #[error("invalid IK parameter {name} = {value}: {requirement}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Given value.
        value: f64,
        /// What the value must satisfy.
        requirement: &'static str,
    },
    /// A slice or model has the wrong number of joints.
    #[error("{what} has {got} entries but the IK was built for {expected} joints")]
    DimensionMismatch {
        /// Which input.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// The numeric IK stopped before reaching its tolerances.
    #[error(
        "numeric IK did not converge after {iterations} iterations (remaining error \
         {:.3e} m, {:.3e} rad); the pose is probably unreachable or outside the joint \
         limits, or the seed is too far away — check the target or seed from a nearby \
         solution",
        position_error,
        orientation_error
    )]
    NotConverged {
        /// Iterations performed.
        iterations: usize,
        /// Remaining position error (m) of the best iterate.
        position_error: f64,
        /// Remaining orientation error (rad) of the best iterate.
        orientation_error: f64,
    },
    /// No start of the multi-start IK ([`RobustIk`]) converged: the pose is out of
    /// reach, or every configuration reaching it leaves a joint's limits.
    #[error(
        "no joint configuration within the limits reaches this pose (best of {starts} starts: \
         remaining error {:.3e} m, {:.3e} rad{}); move the target into the workspace \
         (work offset) or change the orientation",
        position_error,
        orientation_error,
        match at_limit {
            Some(h) => format!(
                "; there joint {} is at {:.2}°, on its limit of [{:.2}°, {:.2}°]",
                h.joint,
                h.value.to_degrees(),
                h.lower.to_degrees(),
                h.upper.to_degrees()
            ),
            None => String::new(),
        }
    )]
    NoSolution {
        /// Starts tried.
        starts: usize,
        /// Remaining position error (m) of the best iterate.
        position_error: f64,
        /// Remaining orientation error (rad) of the best iterate.
        orientation_error: f64,
        /// A joint of the best iterate on its limit, if any.
        at_limit: Option<IkLimitHit>,
    },
}

/// SO(3) log map of a unit quaternion: the rotation vector `θ·axis` with θ ∈ [0, π].
///
/// Accurate to machine precision for every angle (computed as `2·atan2(|v|, w)` on
/// the quaternion, not through `acos` of the trace, which loses half the digits
/// near θ = 0).
pub fn rotation_log(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let q = q.quaternion();
    let (w, v) = if q.w < 0.0 {
        (-q.w, -q.vector())
    } else {
        (q.w, q.vector().into_owned())
    };
    let n = v.norm();
    if n == 0.0 {
        return Vector3::zeros();
    }
    v * (2.0 * n.atan2(w) / n)
}

/// Pose error `[p_target − p; log(R_target·Rᵀ)]` (position in m, rotation vector in
/// rad, both in the base frame): the quantity the geometric Jacobian maps q̇ to.
pub(crate) fn pose_error(
    target: &Isometry3<f64>,
    pose: &Isometry3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let dp = target.translation.vector - pose.translation.vector;
    let dr = rotation_log(&(target.rotation * pose.rotation.inverse()));
    (dp, dr)
}

/// True when every number of the pose is finite.
pub(crate) fn pose_is_finite(pose: &Isometry3<f64>) -> bool {
    pose.translation.vector.iter().all(|x| x.is_finite())
        && pose.rotation.coords.iter().all(|x| x.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Unit;

    #[test]
    fn rotation_log_inverts_exp_over_all_angles() {
        let axis = Unit::new_normalize(Vector3::new(0.3, -0.5, 0.8));
        for &angle in &[
            0.0,
            1e-14,
            1e-10,
            1e-6,
            0.3,
            1.0,
            2.5,
            3.1,
            std::f64::consts::PI - 1e-5,
            std::f64::consts::PI - 1e-9,
        ] {
            let q = UnitQuaternion::from_axis_angle(&axis, angle);
            let w = rotation_log(&q);
            let expected = axis.into_inner() * angle;
            assert!(
                (w - expected).norm() <= 1e-15 * (1.0 + angle),
                "angle {angle}: {w:?} vs {expected:?}"
            );
        }
    }

    #[test]
    fn rotation_log_of_negated_quaternion_is_the_same_rotation() {
        let q = UnitQuaternion::from_euler_angles(0.2, -0.4, 1.1);
        let neg = UnitQuaternion::new_unchecked(-q.into_inner());
        assert!((rotation_log(&q) - rotation_log(&neg)).norm() < 1e-15);
    }

    #[test]
    fn pose_error_is_zero_for_equal_poses_and_detects_offsets() {
        let a = Isometry3::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.4, -0.2, 0.1));
        let (dp, dr) = pose_error(&a, &a);
        assert!(dp.norm() == 0.0 && dr.norm() < 1e-16);
        let rot = Vector3::new(0.0, 0.0, 1e-9);
        let target = Isometry3::from_parts(
            Vector3::new(0.1, 0.2, 0.3 + 1e-9).into(),
            UnitQuaternion::from_scaled_axis(rot),
        );
        let pose = Isometry3::translation(0.1, 0.2, 0.3);
        let (dp, dr) = pose_error(&target, &pose);
        assert!((dp - Vector3::new(0.0, 0.0, 1e-9)).norm() < 1e-15);
        assert!((dr - rot).norm() < 1e-23);
    }
}
