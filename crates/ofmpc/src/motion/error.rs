//! Why a program could not be planned ([`PlanError`]), one leaf below its
//! users (mod.rs, tool.rs).

use super::limits::{JointQuantity, ReferenceError};
use super::timing::trajectory::TrajectoryError;
use crate::gcode::GcodeError;

/// What makes a plan too large to sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum SampleCause {
    /// The feed (`F`) of a move on this program line is too small for its length.
    Feed {
        /// Program line.
        line: usize,
    },
    /// The dwell (`G04`) on this program line is too long.
    Dwell {
        /// Program line.
        line: usize,
    },
    /// The path speed limit ([`super::TimingOptions::max_speed`]) is too small.
    PathSpeed {
        /// The slowest move's program line.
        line: usize,
    },
    /// The path acceleration limit is too small.
    PathAcceleration {
        /// The slowest move's program line.
        line: usize,
    },
    /// The sample period is too small for the path's duration.
    SamplePeriod,
}

impl std::fmt::Display for SampleCause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SampleCause::Feed { line } => {
                write!(f, "the feed of program line {line} is too small for its move")
            }
            SampleCause::Dwell { line } => write!(f, "the dwell of program line {line} is too long"),
            SampleCause::PathSpeed { line } => write!(
                f,
                "the path speed limit is too small (the slowest move is on program line {line})"
            ),
            SampleCause::PathAcceleration { line } => write!(
                f,
                "the path acceleration limit is too small (the slowest move is on program line {line})"
            ),
            SampleCause::SamplePeriod => f.write_str("the sample period is too small"),
        }
    }
}

/// Why a program could not be planned.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// The program text is wrong.
    #[error("{0}")]
    Program(GcodeError),
    /// The timing options or a move are invalid, or a blended run cannot be timed.
    #[error("{0}")]
    Timing(TrajectoryError),
    /// The path cannot be followed in joint space.
    #[error("{0}")]
    Reference(ReferenceError),
    /// The sample period is not positive and finite.
    #[error("the sample period must be positive and finite, got {0} s")]
    SamplePeriod(f64),
    /// The joint reference would need more values than [`super::MAX_PLAN_VALUES`]; nothing was
    /// allocated.
    #[error("the joint reference would need {count:.3e} values (samples × columns), above the limit of {limit}: {cause}")]
    TooManySamples {
        /// What makes it large.
        cause: SampleCause,
        /// Values needed.
        count: f64,
        /// The limit.
        limit: usize,
    },
    /// A blended run's reference still exceeds a joint limit after replanning with scaled
    /// limits.
    #[error("joint {joint} reaches {value:.3} at program line {line}, above its {quantity} limit {limit:.3}, after {attempts} timing attempts")]
    JointLimit {
        /// Joint number, 1-based.
        joint: usize,
        /// Which limit.
        quantity: JointQuantity,
        /// The value reached.
        value: f64,
        /// The limit.
        limit: f64,
        /// Program line.
        line: usize,
        /// Attempts made.
        attempts: usize,
    },
}
