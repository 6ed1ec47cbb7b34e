//! Analyses of the closed loop that need no full run: the stability of the
//! controllers near rest against an inertia mismatch ([`stability`]).

pub mod stability;

pub use stability::{
    alpha_interval, alpha_interval_by_perturbation, closed_loop_matrix, inertia_ratio_range,
    max_payload, simulated_growth, spectral_radius, LinearizedLoop, StabilityError,
    StabilityOptions,
};
