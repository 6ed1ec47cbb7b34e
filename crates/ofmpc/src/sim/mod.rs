//! Closed-loop simulation: the plant (nonlinear robot with an unknown payload)
//! and, later, the loop that runs a controller against it.

mod plant;

pub use plant::{Plant, PlantSettings};
