//! The baselines a control engineer compares against, behind the same
//! [`Algorithm`](crate::control::algorithm::Algorithm) as the paper's
//! controllers: the shared joint law and its gains ([`baseline`]), joint PID
//! with gravity compensation ([`pid`]), computed torque ([`ctc`]) and the
//! disturbance-observer MPC ([`dob_mpc`]).

pub(crate) mod baseline;
pub(crate) mod ctc;
pub(crate) mod dob_mpc;
pub(crate) mod pid;
pub(crate) mod rest_identification;
