//! Closed-loop simulation: the plant (nonlinear robot with an unknown payload)
//! and, later, the loop that runs a controller against it.

mod closed_loop;
mod experiment;
mod metrics;
mod plant;

pub use closed_loop::{run_closed_loop, LoopSettings, RunResult};
pub use experiment::{kind_name, run_name, Experiment};
pub use metrics::{compute as compute_metrics, quantile, Record, RunMetrics, StepTime};
pub use plant::{Plant, PlantSettings};
