//! # ofmpc — offset-free model predictive control of serial robots
//!
//! Pure computation, no printing. Data flow, one module per concept:
//! G-code text → [`gcode`] (moves made of [`geometry`] segments) → [`motion`] (corner blending, timing, joint
//! reference by IK; one entry point [`motion::plan`]) → [`control`] (the predictive
//! controllers on their robot model) → [`sim`] (the closed loop as public stages:
//! [`sim::Sensor`] → [`sim::SupervisedController`] (repair, [`sim::Supervisor`], the
//! controller with its observer) → [`sim::Actuator`] → [`sim::Plant`] (robot + payload) → [`sim::Recorder`], composed by
//! [`sim::ClosedLoop`]) → metrics.
//!
//! What most users need is re-exported here at the crate root: [`Robot`], [`Payload`],
//! [`plan`] and [`PlanOptions`], [`ControllerKind`], [`MpcSettings`] and [`BaselineSettings`], [`ControllerBuilder`]
//! (a controller that works as configured, or a typed refusal) and its [`Controller`],
//! [`Experiment`] (one run, judged), [`ClosedLoop`] and its settings.
//!
//! Equations are referenced as in the paper ("Predictive Control for Offset-Free
//! Motion of Industrial Articulated Robots"), e.g. *Eq. (39)*.
//!
//! The whole experiment of the paper's section IV, for one controller:
//!
//! ```
//! use ofmpc::control::{ControllerKind, MpcSettings};
//! use ofmpc::gcode::PAPER_TABLE1;
//! use ofmpc::motion::{plan, PlanOptions};
//! use ofmpc::robot::{Payload, Robot};
//! use ofmpc::sim::Experiment;
//!
//! let robot = Robot::irb140(); // built in, with its drives and its analytic IK parameters
//! // G-code → blended, timed path → joint reference (IK), sampled every 10 ms:
//! let plan = plan(PAPER_TABLE1, &robot, &PlanOptions::default())?;
//! let experiment = Experiment {
//!     robot, // the controller's model: it does not know the payload
//!     reference: plan.reference,
//!     mpc: MpcSettings::default(), // the paper's tuning
//!     plant: Default::default(),
//!     loop_settings: Default::default(), // 2 s hold after the path
//!     conditions: Default::default(),    // no pick-up, safety limit or fault
//!     baselines: Default::default(),     // the baselines' bandwidths (pid, ctc, dob-mpc)
//! };
//! let (_run, metrics) = experiment.run(ControllerKind::Second, &Payload::point_mass(0.25), &mut |_, _| {})?;
//! assert!(metrics.steady_joint_error_max_rad.iter().all(|e| *e < 1e-9)); // offset-free
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![doc = include_str!("../docs/embedding.md")]
#![warn(missing_docs)]
// Index loops mirror the equations' subscripts (H_ij, C_ij, q_i); iterator
// chains over several parallel arrays would read worse.
#![allow(clippy::needless_range_loop)]

/// The linear-algebra crate of the public API (its matrices and vectors
/// appear in signatures): use this re-export to get the same version.
pub use nalgebra;

/// The controllers' internal algorithms behind [`Controller`], for the workspace's own tests
/// and benchmarks that compare the object with them: not part of the API.
#[doc(hidden)]
pub use control::{new_controller, Algorithm};
pub use control::{
    BaselineSettings, BuildError, Controller, ControllerBuilder, ControllerKind, MpcSettings,
    StepError, StepInput, StepOutput, StepStatus,
};
pub use motion::{plan, JointReference, PlanError, PlanOptions};
pub use robot::{Payload, Robot};
pub use sim::{
    ClosedLoop, Experiment, ExperimentError, LoopSettings, Plant, PlantSettings, RunMetrics,
    RunOutcome, RunResult, SupervisedController,
};

pub mod analysis;
pub mod control;
pub mod dynamics;
pub mod gcode;
pub mod geometry;
pub mod ident;
// Inverse kinematics behind `robot::IkMethod` (the planner calls it): for the workspace's own
// tests, not part of the API.
#[doc(hidden)]
pub mod ik;
// Bounded, checked reading of input files and quoting of user text in messages, shared by the
// workspace's crates (CLI, scenario, Python): not part of the API.
#[doc(hidden)]
pub mod input;
mod linalg;
#[doc(hidden)]
pub use linalg::random;
pub mod motion;
pub mod robot;
pub mod sim;
pub mod spatial;
