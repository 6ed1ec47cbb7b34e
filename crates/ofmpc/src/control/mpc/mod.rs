//! The paper's predictive controllers (Section III): the robot model at the
//! measured state ([`model`], Eq. (6)–(12)), its exact zero-order-hold
//! discretization ([`zoh`], Eq. (13)), the prediction matrices
//! ([`prediction`], Eq. (20)–(29)), the step skeleton they share ([`core`])
//! and the three algorithms: the usual MPC ([`usual`], Eq. (43)), the first
//! ([`first`], Eq. (32)/(37)) and second ([`second`], Eq. (34)/(39))
//! offset-free incremental algorithms, and the torque-limit step they share
//! ([`torque_limits`]). Their adaptive variants are one level up (`control/adaptive.rs`):
//! they also wrap the CTC baseline, which is built on this engine. The friction law near
//! rest for a real arm: [`creep`].

pub(crate) mod core;
pub(crate) mod creep;
pub(crate) mod first;
pub(crate) mod gains;
pub(crate) mod model;
pub(crate) mod prediction;
pub(crate) mod second;
pub(crate) mod torque_limits;
pub(crate) mod usual;
pub(crate) mod zoh;
