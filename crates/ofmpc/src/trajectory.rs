//! Timed Cartesian reference: a parsed [`Program`] with a rest-to-rest [`TimeLaw`] on every
//! segment (section IV of the paper: "time parameterized with 5th order polynomial of
//! acceleration").
//!
//! Each path segment starts and ends at rest, so velocity and acceleration are continuous
//! (zero) at every join; with [`Profile::Septic`] the jerk is too. Dwells hold the position.
//! Orientation is not handled here (it is constant in the paper's experiments).
//!
//! [`CartesianTrajectory::sample`] allocates nothing and is meant to be called every control
//! step.

use crate::gcode::{MoveKind, Program};
use crate::path::Segment;
use crate::timelaw::{Profile, TimeLaw};
use nalgebra::Vector3;

/// Limits and profile used to time a program.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimingOptions {
    /// Rest-to-rest profile of every segment. Default: [`Profile::Septic`] (the paper's).
    pub profile: Profile,
    /// Peak path speed (m/s) of moves without an `F` word. Default 0.5.
    pub max_speed: f64,
    /// Peak path (tangential) acceleration (m/s²) of every move, also those with `F`.
    /// Default 2.5.
    pub max_accel: f64,
}

impl Default for TimingOptions {
    fn default() -> Self {
        TimingOptions {
            profile: Profile::Septic,
            max_speed: 0.5,
            max_accel: 2.5,
        }
    }
}

/// Why a trajectory could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrajectoryError {
    /// A timing limit is not a positive finite number.
    #[error("TimingOptions::{name} must be positive and finite, got {value} (give it in SI units: m/s or m/s²)")]
    InvalidLimit {
        /// Field name.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A move of the program carries an invalid feed or dwell (not produced by
    /// [`crate::gcode::parse`]; possible for hand-built programs).
    #[error("the move from program line {line} has an invalid {what} ({value}): it must be positive and finite")]
    InvalidMove {
        /// Source line of the move.
        line: usize,
        /// "feed" or "dwell time".
        what: &'static str,
        /// The value.
        value: f64,
    },
}

/// What a timed segment does.
#[derive(Debug, Clone, PartialEq)]
pub enum TimedKind {
    /// Travel along `segment` with arc length `law.eval(t − start_time).s`.
    Path {
        /// Geometry.
        segment: Segment,
        /// Time law over the segment's length.
        law: TimeLaw,
    },
    /// Hold `position`.
    Dwell {
        /// Held point (m).
        position: Vector3<f64>,
    },
}

/// One timed piece of the trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct TimedSegment {
    /// What happens.
    pub kind: TimedKind,
    /// Start time (s) from the start of the program.
    pub start_time: f64,
    /// End time (s).
    pub end_time: f64,
    /// Source line of the program block.
    pub line: usize,
}

/// The reference at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CartesianSample {
    /// Position (m, base frame).
    pub position: Vector3<f64>,
    /// Velocity (m/s).
    pub velocity: Vector3<f64>,
    /// Acceleration (m/s²): tangential plus centripetal.
    pub acceleration: Vector3<f64>,
    /// Index into [`CartesianTrajectory::segments`] of the active piece (clamped to the first
    /// before the start and the last after the end); `None` if the program has no moves.
    pub segment: Option<usize>,
    /// Source line of the active piece (the start line if there is none).
    pub line: usize,
}

/// A program timed with rest-to-rest laws.
#[derive(Debug, Clone, PartialEq)]
pub struct CartesianTrajectory {
    start: Vector3<f64>,
    start_line: usize,
    segments: Vec<TimedSegment>,
    duration: f64,
}

impl CartesianTrajectory {
    /// Time every move of `program`.
    ///
    /// Each path move takes the shortest duration whose peak path speed stays within its
    /// feed (`F`, overriding `max_speed` for that move) or else `max_speed`, and whose peak
    /// path acceleration stays within `max_accel` ([`Profile::min_duration`]).
    pub fn new(program: &Program, options: &TimingOptions) -> Result<Self, TrajectoryError> {
        for (name, value) in [
            ("max_speed", options.max_speed),
            ("max_accel", options.max_accel),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(TrajectoryError::InvalidLimit { name, value });
            }
        }
        let mut segments = Vec::with_capacity(program.moves.len());
        let mut t = 0.0;
        let mut pos = program.start;
        for m in &program.moves {
            let (kind, dt) = match &m.kind {
                MoveKind::Path { segment, feed } => {
                    let speed = match feed {
                        Some(f) if !(f.is_finite() && *f > 0.0) => {
                            return Err(TrajectoryError::InvalidMove {
                                line: m.line,
                                what: "feed",
                                value: *f,
                            })
                        }
                        Some(f) => *f,
                        None => options.max_speed,
                    };
                    let law = TimeLaw::fastest(
                        options.profile,
                        segment.length(),
                        speed,
                        options.max_accel,
                    );
                    pos = segment.end();
                    let dt = law.duration;
                    (
                        TimedKind::Path {
                            segment: segment.clone(),
                            law,
                        },
                        dt,
                    )
                }
                MoveKind::Dwell { seconds } => {
                    if !(seconds.is_finite() && *seconds > 0.0) {
                        return Err(TrajectoryError::InvalidMove {
                            line: m.line,
                            what: "dwell time",
                            value: *seconds,
                        });
                    }
                    (TimedKind::Dwell { position: pos }, *seconds)
                }
            };
            segments.push(TimedSegment {
                kind,
                start_time: t,
                end_time: t + dt,
                line: m.line,
            });
            t += dt;
        }
        Ok(CartesianTrajectory {
            start: program.start,
            start_line: program.start_line,
            segments,
            duration: t,
        })
    }

    /// Total duration (s).
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Start point (m), where the robot rests before `t = 0`.
    pub fn start(&self) -> Vector3<f64> {
        self.start
    }

    /// End point (m), held after [`Self::duration`].
    pub fn end(&self) -> Vector3<f64> {
        self.segments
            .last()
            .map_or(self.start, |s| piece_state(s, s.end_time).0)
    }

    /// The timed pieces, in order.
    pub fn segments(&self) -> &[TimedSegment] {
        &self.segments
    }

    /// The reference at time `t` (s). Before 0 (or NaN): the start point at rest; after the
    /// end: the last point at rest.
    pub fn sample(&self, t: f64) -> CartesianSample {
        let rest = |position, segment, line| CartesianSample {
            position,
            velocity: Vector3::zeros(),
            acceleration: Vector3::zeros(),
            segment,
            line,
        };
        let Some(last) = self.segments.len().checked_sub(1) else {
            return rest(self.start, None, self.start_line);
        };
        if t.is_nan() || t <= 0.0 {
            let line = self.segments.first().map_or(self.start_line, |s| s.line);
            return rest(self.start, Some(0), line);
        }
        // First piece that ends at or after t.
        let k = self.segments.partition_point(|s| s.end_time < t).min(last);
        let Some(piece) = self.segments.get(k) else {
            return rest(self.start, None, self.start_line);
        };
        let (position, velocity, acceleration) = piece_state(piece, t);
        CartesianSample {
            position,
            velocity,
            acceleration,
            segment: Some(k),
            line: piece.line,
        }
    }
}

/// Position, velocity and acceleration of `piece` at absolute time `t` (clamped to the piece).
fn piece_state(piece: &TimedSegment, t: f64) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    match &piece.kind {
        TimedKind::Dwell { position } => (*position, Vector3::zeros(), Vector3::zeros()),
        TimedKind::Path { segment, law } => {
            let st = law.eval(t - piece.start_time);
            let tangent = segment.tangent(st.s);
            (
                segment.point(st.s),
                tangent * st.speed,
                tangent * st.accel + segment.curvature(st.s) * (st.speed * st.speed),
            )
        }
    }
}
