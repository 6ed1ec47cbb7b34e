//! Rigid-body dynamics of a serial robot: `H(q) q̈ + C(q, q̇) q̇ + g(q) = τ`.

use nalgebra::{DMatrix, DVector};

/// What a controller or a simulator needs of a robot model: the terms of the
/// Lagrange form `H(q) q̈ + C(q, q̇) q̇ + g(q) = τ` (Eq. (1)–(5) of the paper).
///
/// Implementations must not allocate in [`JointSpaceDynamics::terms`]: it is
/// called inside the real-time control step.
pub trait JointSpaceDynamics {
    /// Number of joints `n` (degrees of freedom).
    fn dof(&self) -> usize;
    /// Writes the joint-space inertia `H(q)` (n×n, including the drives'
    /// armature), the Coriolis matrix `C(q, q̇)` (n×n, Christoffel-consistent:
    /// `Ḣ − 2C` skew-symmetric) and gravity `g(q)` (n) into the given buffers,
    /// which the caller has sized n×n, n×n and n.
    fn terms(
        &mut self,
        q: &[f64],
        qd: &[f64],
        h: &mut DMatrix<f64>,
        c: &mut DMatrix<f64>,
        g: &mut DVector<f64>,
    );
}
