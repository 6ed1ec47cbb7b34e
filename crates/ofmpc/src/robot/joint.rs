//! One moving joint of a serial chain, its limits, and the check of a rigid body's
//! rotational inertia: the pieces the URDF reader builds a robot from.

use super::error::InertiaError;
use crate::spatial::{Inertia, Transform};
use nalgebra::{Matrix3, Vector3};

/// Kind of a moving joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about the joint axis (rad).
    Revolute,
    /// Translation along the joint axis (m).
    Prismatic,
}

/// Limits of one joint. Position limits may be infinite (continuous joints).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointLimits {
    /// Lower position limit (rad or m).
    pub lower: f64,
    /// Upper position limit (rad or m).
    pub upper: f64,
    /// Speed limit, symmetric (rad/s or m/s); infinite when unknown.
    pub velocity: f64,
    /// Torque or force limit, symmetric (N·m or N); infinite when unknown.
    pub effort: f64,
    /// Acceleration limit, symmetric (rad/s² or m/s²); infinite when unknown (URDF has
    /// none: it comes from a drives file). The motion planner keeps blended runs within it.
    pub acceleration: f64,
}

/// One moving joint and the rigid body it moves.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Joint name (URDF).
    pub name: String,
    /// Name of the link it moves (URDF child link).
    pub link: String,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Pose of the joint frame in the previous body's frame at q = 0 (fixed
    /// joints in between are folded in).
    pub placement: Transform,
    /// Unit joint axis in the joint frame.
    pub axis: Vector3<f64>,
    /// Inertia of the moved body in the joint frame, links rigidly attached
    /// through fixed joints included, payload excluded.
    pub body: Inertia,
    /// Position, speed and effort limits.
    pub limits: JointLimits,
    /// Reflected rotor inertia of the drive (kg·m²), added to `H[i][i]`.
    pub armature: f64,
    /// Coulomb friction estimate of the drive (N·m), for the controllers'
    /// friction compensation (the simulated plant has its own friction).
    pub coulomb_nm: f64,
    /// Viscous friction estimate of the drive (N·m·s/rad), likewise.
    pub viscous_nms: f64,
}

/// Checks a rotational inertia about the centre of mass: symmetric, principal
/// moments ≥ 0 and satisfying the triangle inequality.
pub(crate) fn check_inertia_tensor(i: &Matrix3<f64>) -> Result<(), InertiaError> {
    let asym = (i - i.transpose()).abs().max();
    let scale = i.abs().max().max(1e-300);
    if asym > 1e-9 * scale {
        return Err(InertiaError::NotSymmetric(asym));
    }
    let eig = i.symmetric_eigenvalues();
    let moments = [eig[0], eig[1], eig[2]];
    let tol = 1e-9 * scale;
    if eig.iter().any(|&e| e < -tol) {
        return Err(InertiaError::NegativeMoment(moments));
    }
    let (a, b, c) = (eig[0], eig[1], eig[2]);
    if a + b < c - tol || a + c < b - tol || b + c < a - tol {
        return Err(InertiaError::Triangle(moments));
    }
    Ok(())
}
