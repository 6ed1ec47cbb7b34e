//! Buffers of the rigid-body algorithms, sized once per robot.

use crate::robot::{ModelError, Robot};
use crate::spatial::{Force, Inertia, Motion, Transform};
use nalgebra::{DMatrix, DVector};

/// Every buffer the algorithms of [`crate::dynamics`] write, sized once for a
/// robot (Pinocchio's `Data`). Results are public fields, named as in the
/// algorithms' docs; they hold the values of the last call.
#[derive(Debug, Clone)]
pub struct Workspace {
    /// Pose of each body (joint frame after its motion) in its parent body's frame.
    pub local: Vec<Transform>,
    /// Pose of each body in the base frame (after [`super::forward_kinematics`]).
    pub poses: Vec<Transform>,
    /// Flange pose in the base frame.
    pub flange: Transform,
    /// Geometric flange Jacobian, 6×n: rows 0..3 linear velocity of the flange
    /// origin, rows 3..6 angular velocity, both in the base frame.
    pub jacobian: DMatrix<f64>,
    /// Inverse dynamics result τ (n).
    pub tau: DVector<f64>,
    /// Joint-space inertia H (n×n), armature included.
    pub h: DMatrix<f64>,
    /// Coriolis matrix C (n×n).
    pub c: DMatrix<f64>,
    /// Gravity torque g (n).
    pub g: DVector<f64>,
    /// Forward dynamics result q̈ (n).
    pub qdd: DVector<f64>,
    /// Cholesky factor of H (lower triangle), from the last forward dynamics.
    pub chol: DMatrix<f64>,
    pub(crate) v: Vec<Motion>,
    pub(crate) a: Vec<Motion>,
    pub(crate) f: Vec<Force>,
    pub(crate) s: Vec<Motion>,
    pub(crate) sdot: Vec<Motion>,
    pub(crate) inertia: Vec<Inertia>,
    pub(crate) composite: Vec<Inertia>,
    pub(crate) ivel: Vec<Force>,
    pub(crate) zero: Vec<f64>,
}

impl Workspace {
    /// Sizes every buffer for `robot`.
    pub fn new(robot: &Robot) -> Self {
        let n = robot.dof();
        Self {
            local: vec![Transform::identity(); n],
            poses: vec![Transform::identity(); n],
            flange: Transform::identity(),
            jacobian: DMatrix::zeros(6, n),
            tau: DVector::zeros(n),
            h: DMatrix::zeros(n, n),
            c: DMatrix::zeros(n, n),
            g: DVector::zeros(n),
            qdd: DVector::zeros(n),
            chol: DMatrix::zeros(n, n),
            v: vec![Motion::zero(); n],
            a: vec![Motion::zero(); n],
            f: vec![Force::default(); n],
            s: vec![Motion::zero(); n],
            sdot: vec![Motion::zero(); n],
            inertia: vec![Inertia::zero(); n],
            composite: vec![Inertia::zero(); n],
            ivel: vec![Force::default(); n],
            zero: vec![0.0; n],
        }
    }
    /// Number of joints this workspace was sized for.
    pub fn dof(&self) -> usize {
        self.tau.len()
    }
    /// True when every buffer is sized for `n` joints (the public result
    /// fields could have been replaced by the caller).
    pub(crate) fn fits(&self, n: usize) -> bool {
        [
            self.local.len(),
            self.poses.len(),
            self.tau.len(),
            self.g.len(),
            self.qdd.len(),
            self.v.len(),
            self.a.len(),
            self.f.len(),
            self.s.len(),
            self.sdot.len(),
            self.inertia.len(),
            self.composite.len(),
            self.ivel.len(),
            self.zero.len(),
        ]
        .iter()
        .all(|&l| l == n)
            && self.jacobian.shape() == (6, n)
            && self.h.shape() == (n, n)
            && self.c.shape() == (n, n)
            && self.chol.shape() == (n, n)
    }
}

/// A vector must have one finite value per joint of `robot` ([`Robot::check_vector`]).
pub(crate) fn check(robot: &Robot, what: &str, v: &[f64]) -> Result<(), ModelError> {
    robot.check_vector(what, v)
}

/// The workspace must have been built for this robot's number of joints.
pub(crate) fn check_ws(robot: &Robot, ws: &Workspace) -> Result<(), ModelError> {
    if !ws.fits(robot.dof()) {
        return Err(ModelError::WorkspaceMismatch {
            workspace: ws.dof(),
            robot: robot.dof(),
        });
    }
    Ok(())
}

/// A result must be finite (inputs such as q̇ = 1e160 overflow it).
pub(crate) fn finite_result(what: &'static str, v: &[f64]) -> Result<(), ModelError> {
    match v.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(index) => Err(ModelError::NonFiniteResult {
            what,
            index,
            value: v[index],
        }),
    }
}
