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
//! [`Fault`], [`MeasurementFaults`], [`FaultSchedule`]).

mod actuator;
mod closed_loop;
mod conditions;
mod estimator;
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
mod settings_error;
mod state;
mod supervised;
mod supervisor;

pub use actuator::{Actuator, Loading};
pub use estimator::Estimator;
pub use faults::{
    at_or_after, sample_at, Fault, FaultSchedule, LossSchedule, MeasurementFaults,
    TIME_MATCH_TOLERANCE,
};
pub use horizon::{HorizonRecorder, HorizonSampling, PredictedHorizons};
pub use recorder::{Record, Recorder, Sample};
pub use repair::MeasurementGuard;
pub use sensor::Sensor;
pub use settings_error::LoopSettingsError;
pub use state::JointState;
pub use supervised::{
    SupervisedController, SupervisedError, SupervisedInput, SupervisedOutput, SupervisedStatus,
};

pub use closed_loop::{
    record_columns, records_measurement, run_closed_loop, run_closed_loop_with, ClosedLoop,
    LoopSettings, RunEvents, RunResult, MAX_IDENTIFICATION_S, SAFE_STOP_RECORD_S,
};
pub use conditions::{RunConditions, SafetySettings};
pub use experiment::{kind_name, mass_label, run_name, Experiment, OBSERVER_POLE};
pub use metrics::{compute as compute_metrics, quantile, RunMetrics, StepTime};
pub use outcome::{
    ExperimentError, RunFailure, RunOutcome, RunStatus, FAILED_STOP_SPEED, MAX_RECORD_VALUES,
};
pub use plant::{
    check_plant_model, FrictionKind, NoiseKind, Plant, PlantError, PlantSettings,
    PlantSettingsError, DEFAULT_STRIBECK_VELOCITY, MAX_DELAY_SAMPLES, MAX_SUBSTEPS,
};
pub use supervisor::{
    DivergenceRule, Inspection, Plausibility, SafeStop, StopReason, Stopping, Supervisor,
    SupervisorSettings, BRAKE_TIME, FROZEN_SAMPLES, GROWTH_CEILING_RAD, GROWTH_FACTOR,
    GROWTH_WINDOW_S, MAX_REJECTED, MOVING_STEP_RAD, REST_SPEED,
};
