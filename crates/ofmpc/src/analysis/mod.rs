//! Analyses of the closed loop that need no full run: the stability of the
//! controllers near rest against an inertia mismatch (`stability`).

pub(crate) mod stability;

pub use stability::{
    inertia_ratio_range, max_payload, StabilityError, StabilityOptions, StabilityProblem,
};
