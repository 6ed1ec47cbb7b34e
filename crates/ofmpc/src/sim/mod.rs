//! Closed-loop simulation: the plant (nonlinear robot with an unknown payload),
//! the loop that runs a controller against it, the run's typed outcome and its
//! metrics.
//!
//! The loop is cut along physical roles, one file each: the [`Plant`]
//! (rigid-body and payload physics, friction inside its integration), the
//! [`Actuator`] (commanded → applied torque: saturation, torque drops), the
//! [`Sensor`] (true → measured state, from a plain [`JointState`]: encoders,
//! noise, delay, encoder faults, lost samples, repair), the [`Supervisor`]
//! (plausibility, safety limit, divergence, safe stop) and, for a real loop,
//! the controller behind that guard as one object, the
//! [`SupervisedController`]. The faults of a run have one home (`faults.rs`:
//! [`Fault`], [`MeasurementFaults`], `FaultSchedule`).

mod actuator;
mod closed_loop;
mod conditions;
mod experiment;
mod faults;
mod format;
mod horizon;
mod metrics;
mod outcome;
mod plant;
mod recorder;
mod repair;
mod sensor;
mod servo;
mod settings_error;
mod state;
mod supervised;
mod supervisor;
mod telemetry;

pub use actuator::Actuator;
#[doc(hidden)]
pub use faults::sample_at;
pub use faults::{Fault, LossSchedule, MeasurementFaults};
#[doc(hidden)]
pub use horizon::HorizonRecorder;
pub use horizon::{HorizonSampling, PredictedHorizons};
pub use recorder::{Record, Recorder, Sample};
pub use sensor::Sensor;
pub use servo::{
    LateSteps, OnLate, Servo, ServoProfile, ServoReport, ServoSettings, ServoSettingsError,
    ServoStatus,
};
pub use settings_error::LoopSettingsError;
pub use state::JointState;
pub use supervised::{
    SupervisedController, SupervisedError, SupervisedInput, SupervisedOutput, SupervisedStatus,
};

#[doc(hidden)]
pub use closed_loop::{records_measurement, run_closed_loop, run_closed_loop_with};
pub use closed_loop::{ClosedLoop, LoopSettings, RunResult};
pub use conditions::{RunConditions, SafetySettings};
pub use experiment::Experiment;
#[doc(hidden)]
pub use experiment::{kind_name, mass_label, run_name, OBSERVER_POLE};
#[doc(hidden)]
pub use metrics::{compute as compute_metrics, quantile};
pub use metrics::{RunMetrics, StepTime};
pub use outcome::{ExperimentError, RunFailure, RunOutcome, RunStatus};
#[doc(hidden)]
pub use plant::{check_plant_model, MAX_DELAY_SAMPLES, MAX_SUBSTEPS};
pub use plant::{FrictionKind, NoiseKind, Plant, PlantError, PlantSettings, PlantSettingsError};
pub use supervisor::{DivergenceRule, StopReason, SupervisorSettings};
#[doc(hidden)]
pub use supervisor::{Stopping, Supervisor, MAX_REJECTED};
#[doc(hidden)]
pub use telemetry::{FallbackCounts, LoopTelemetry, Percentiles, TelemetryMetrics};
