//! Why the model of one sample cannot be used: its terms `H, C, g` ([`TermsError`], from
//! `mpc/model.rs`) or their zero-order-hold discretization ([`ZohError`], from `mpc/zoh.rs`).
//! A leaf: the step's failure ([`crate::control::StepError`]) names these causes without
//! importing the MPC engine that produces them.

/// Why the model terms of one sample cannot be used.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum TermsError {
    /// The robot model has another number of joints than the controller.
    #[error("the robot model has {got} joints but the controller was built for {expected}: build the controller with the model's dof()")]
    DofMismatch {
        /// Joints of the controller.
        expected: usize,
        /// Joints of the model.
        got: usize,
    },
    /// `H`, `C` or `g` returned by the robot model contain NaN or ±∞.
    #[error("the robot model returned a non-finite entry in {term}[{index}] (column-major): check the state passed to it and the model parameters")]
    NonFiniteTerm {
        /// `"H"`, `"C"` or `"g"`.
        term: &'static str,
        /// Column-major index of the first bad entry.
        index: usize,
    },
    /// A slice or matrix passed in has the wrong size.
    #[error("{what} has {got} entries but the model has {expected} joints (n for q, q̇, u, τ; n×n for H and C)")]
    WrongLength {
        /// Which argument.
        what: &'static str,
        /// Needed length (`n`, or `n·n` for matrices).
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// `H` is not symmetric positive definite (Cholesky pivot ≤ 0).
    #[error("the inertia matrix H is not positive definite (Cholesky pivot {pivot} = {value:e}): check the model's masses, inertias and armature")]
    InertiaNotPositiveDefinite {
        /// Index of the failing pivot.
        pivot: usize,
        /// The pivot value `H_jj − Σ L_jk²`.
        value: f64,
    },
}

/// Why a discretization failed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ZohError {
    /// `f0·Ts` has a non-finite entry or a norm too large to exponentiate.
    #[error("f0·Ts has 1-norm {norm:e}, which cannot be exponentiated (non-finite or above 2^60/4): check the model's Coriolis terms and the sampling period")]
    BadNorm {
        /// The 1-norm of `f0·Ts`.
        norm: f64,
    },
    /// `f0` (or an output matrix) has the wrong shape.
    #[error("a matrix has shape {got:?} but the discretization was built for n = {n} (f0 n×n, Ad 2n×2n, Bd 2n×n)")]
    WrongShape {
        /// Joints the `Zoh` was built for.
        n: usize,
        /// Shape of the given `f0`.
        got: (usize, usize),
    },
    /// The result overflowed.
    #[error("the zero-order-hold matrices overflowed (e^(f0·Ts) too large): the model is violently unstable over one sample")]
    Overflow,
}
