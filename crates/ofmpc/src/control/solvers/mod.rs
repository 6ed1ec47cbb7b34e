//! The numerical solvers behind the controllers: the stacked least-squares
//! problem by Householder QR ([`lsq`], with its AVX2 kernels), the
//! stage-wise square-root Riccati recursion ([`structured`]) on the
//! tracking rows ([`tracking`]), the torque-limit QP ([`constrained`]) and
//! the small dense kernels they share ([`dense`], [`simd`]).

pub(crate) mod constrained;
pub(crate) mod dense;
pub(crate) mod lsq;
pub(crate) mod simd;
pub(crate) mod structured;
pub(crate) mod tracking;
