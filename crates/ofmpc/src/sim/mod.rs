//! Closed-loop simulation: the plant (nonlinear robot with an unknown payload)
//! and, later, the loop that runs a controller against it.

mod metrics;
mod closed_loop;
mod plant;

pub use metrics::{compute as compute_metrics, quantile, Record, RunMetrics, StepTime};
pub use closed_loop::{run_closed_loop, LoopSettings, RunResult};
pub use plant::{Plant, PlantSettings};
