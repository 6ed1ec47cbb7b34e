//! Timed Cartesian reference: a parsed [`Program`] timed move by move.
//!
//! Under `G61` (exact stop, the default) every path move runs rest to rest with a
//! [`TimeLaw`] (section IV of the paper: "time parameterized with 5th order polynomial of
//! acceleration"): velocity and acceleration are continuous (zero) at every join; with
//! [`Profile::Septic`] the jerk is too, and the move's feed is its peak speed. Consecutive
//! moves under `G64` form a *run*: their corners are blended (`path/blend.rs`) and
//! the run is timed as fast as the path and joint limits allow, with the feed as cruise
//! speed, from rest to rest (`timing/topp.rs`). Dwells hold the position.
//! Orientation is not handled here (it is constant in the paper's experiments).
//!
//! [`CartesianTrajectory::sample`] allocates nothing and is meant to be called every control
//! step.

use super::exact::{joint_limited_duration, JointLimitedMove};
use super::timelaw::{Profile, TimeLaw};
use super::topp::{time_run, JointConstraints, PathLimits, Run, RunError};
use crate::gcode::{MoveKind, PathMode, Program};
use crate::geometry::Segment;
use crate::motion::limits::{ReferenceError, MAX_PLAN_VALUES};
use crate::motion::path::blend::{blend_timed, RunMove};
use nalgebra::Vector3;

/// Limits, profile and path mode used to time a program.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimingOptions {
    /// Rest-to-rest profile of every `G61` move. Default: [`Profile::Septic`] (the paper's).
    pub profile: Profile,
    /// Path speed (m/s) of moves without an `F` word (`G00`, and `G01`–`G03` before any `F`):
    /// the peak speed under `G61`, the cruise speed under `G64`. Default 0.5.
    pub max_speed: f64,
    /// Path acceleration limit (m/s²) of every move, also those with `F`: tangential under
    /// `G61`; tangential and, separately, centripetal under `G64`. Default 2.5.
    pub max_accel: f64,
    /// Path jerk limit (m/s³) of `G64` runs (their tangential jerk; the Cartesian jerk,
    /// curvature terms included, stays within twice it), and the bound within twice which
    /// `G61` moves keep their Cartesian jerk. Default 50.
    pub max_jerk: f64,
    /// Corner tolerance (m) of `G64` without `P`. Default 0.1 mm.
    pub blend_tolerance: f64,
    /// Path mode of programs that select neither `G61` nor `G64` (until they do). Default:
    /// [`PathMode::ExactStop`], so that the paper's program runs as published.
    pub default_mode: PathMode,
}

impl Default for TimingOptions {
    fn default() -> Self {
        TimingOptions {
            profile: Profile::Septic,
            max_speed: 0.5,
            max_accel: 2.5,
            max_jerk: 50.0,
            blend_tolerance: 1e-4,
            default_mode: PathMode::ExactStop,
        }
    }
}

/// A timing limit of [`TimingOptions`], named in errors (the caller maps it to its own words).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum TimingLimit {
    /// The path speed limit (m/s).
    PathSpeed,
    /// The path acceleration limit (m/s²).
    PathAcceleration,
    /// The path jerk limit (m/s³).
    PathJerk,
    /// The default corner tolerance (m).
    BlendTolerance,
}

impl std::fmt::Display for TimingLimit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            TimingLimit::PathSpeed => "path speed limit (m/s)",
            TimingLimit::PathAcceleration => "path acceleration limit (m/s²)",
            TimingLimit::PathJerk => "path jerk limit (m/s³)",
            TimingLimit::BlendTolerance => "default corner tolerance (m)",
        })
    }
}

/// Why a trajectory could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TrajectoryError {
    /// A timing limit is not a positive finite number (the tolerance may be 0).
    #[error("the {limit} must be positive and finite, got {value}")]
    InvalidLimit {
        /// Which limit.
        limit: TimingLimit,
        /// The value given.
        value: f64,
    },
    /// A move of the program carries an invalid feed, dwell or tolerance (not produced by
    /// [`crate::gcode::parse`]; possible for hand-built programs).
    #[error("the move from program line {line} has an invalid {what} ({value}): it must be positive and finite")]
    InvalidMove {
        /// Source line of the move.
        line: usize,
        /// "feed", "dwell time" or "tolerance".
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// A blended run passes a pose the robot cannot take (joint-limited timing only).
    #[error("{0}")]
    Joint(ReferenceError),
    /// Timing a blended run would store more values than [`MAX_PLAN_VALUES`].
    #[error("timing the blended moves near program line {line} needs {count:.3e} values, above the limit of {limit}: the path is too slow for its length (a joint limit near a singularity, or a very small feed)")]
    TooManySamples {
        /// The slowest part's program line.
        line: usize,
        /// Values needed.
        count: f64,
        /// The limit.
        limit: usize,
    },
}

/// What a timed segment does.
#[derive(Debug, Clone, PartialEq)]
pub enum TimedKind {
    /// Travel along `segment` with arc length `law.eval(t − start_time).s` (`G61`).
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
    /// Consecutive `G64` moves, blended and timed together from rest to rest.
    Run(Box<Run>),
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
    /// Source line of the program block (the first move's, for a run).
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

/// A timed program.
#[derive(Debug, Clone, PartialEq)]
pub struct CartesianTrajectory {
    start: Vector3<f64>,
    start_line: usize,
    segments: Vec<TimedSegment>,
    duration: f64,
    joint_limited: Vec<JointLimitedMove>,
}

/// What a pending group of moves is.
enum Step<'a> {
    Exact(&'a Segment, f64),
    Dwell(f64),
}

/// The state [`CartesianTrajectory::plan`] builds: the timed segments so far, the time at
/// their end, and the blended moves collected for the next run.
struct Timeline {
    segments: Vec<TimedSegment>,
    t: f64,
    run: Vec<RunMove>,
    /// The exact-stop moves a joint limit slowed down (also those of a run timed as `G61`).
    joint_limited: Vec<JointLimitedMove>,
}

impl Timeline {
    /// Appends a segment lasting `dt` from the current time and advances the time.
    fn push(&mut self, kind: TimedKind, dt: f64, line: usize) {
        self.segments.push(TimedSegment {
            kind,
            start_time: self.t,
            end_time: self.t + dt,
            line,
        });
        self.t += dt;
    }

    /// Blends and times the collected run, if any ([`time_run`]), and appends it; or, when
    /// its moves timed as exact stops (`G61`, under the same joint limits) take less time,
    /// appends them so: a blended run is never slower than stopping at every move's end.
    fn flush(
        &mut self,
        options: &TimingOptions,
        mut joints: Option<&mut JointConstraints<'_>>,
    ) -> Result<(), TrajectoryError> {
        if self.run.is_empty() {
            return Ok(());
        }
        let line = self.run[0].line;
        let moves = std::mem::take(&mut self.run);
        let pieces = blend_timed(&moves, options.max_accel, options.max_jerk);
        // The joint map's state at the run's start, for the exact-stop alternative.
        let saved = joints.as_deref().map(|jc| jc.map.state().to_vec());
        let t = self.t;
        let timed = time_run(
            pieces,
            PathLimits {
                max_accel: options.max_accel,
                max_jerk: options.max_jerk,
            },
            joints.as_deref_mut(),
        )
        .map_err(|e| match e {
            RunError::Joint {
                line,
                position,
                failure,
            } => TrajectoryError::Joint(ReferenceError {
                line,
                column: 0,
                time: t,
                position: [position.x, position.y, position.z],
                failure,
            }),
            RunError::TooManySamples { count, line } => TrajectoryError::TooManySamples {
                line,
                count,
                limit: MAX_PLAN_VALUES,
            },
        })?;
        let dt = timed.duration();
        // The exact-stop laws without the joint limits are a lower bound of the alternative
        // (joint limits only stretch them): the joint-limited laws only when it is below.
        let lower: f64 = moves
            .iter()
            .map(|m| {
                TimeLaw::fastest(
                    options.profile,
                    m.segment.length(),
                    m.feed,
                    options.max_accel,
                )
                .duration
            })
            .sum();
        let exact = if lower < dt {
            if let (Some(jc), Some(q)) = (joints.as_deref_mut(), &saved) {
                jc.map.set_state(q);
            }
            exact_moves(&moves, options, joints)
        } else {
            Vec::new()
        };
        let exact_total: f64 = exact.iter().map(|e| e.law.duration).sum();
        if !exact.is_empty() && exact_total < dt {
            for e in exact {
                let dt = e.law.duration;
                if let Some(j) = e.limited {
                    self.joint_limited.push(j);
                }
                let kind = TimedKind::Path {
                    segment: e.segment,
                    law: e.law,
                };
                self.push(kind, dt, e.line);
            }
        } else {
            self.push(TimedKind::Run(Box::new(timed)), dt, line);
        }
        Ok(())
    }
}

/// The fastest rest-to-rest law of an exact-stop move within its speed and `max_accel`
/// ([`TimeLaw::fastest`]), lengthened where needed so that its Cartesian jerk stays within
/// twice `max_jerk` (issue 26).
///
/// Along a path of curvature `κ` the jerk is `s⃛ t + 3 ṡ s̈ κ n + ṡ³ dk/ds` (the derivative of
/// `ṡ t`, Frenet–Serret), `|dk/ds| = κ²` on a circle (`κ √(κ² + τ²)` on a helix, `κ`
/// times the turning rate of its curvature vector). With the profile's peak factors
/// `f_v`, `f_a`, `f_j` ([`Profile`]) the peaks of the three terms are `f_j L/T³`,
/// `3 f_v f_a L² κ/T³` and `(f_v L/T)³ |dk/ds|`; each is kept within a share of the bound,
/// `J`, `J/2` and `J/2`. A move whose fastest law keeps them is left exactly as it was (the
/// paper's program, whose moves are long, is unchanged).
fn exact_law(options: &TimingOptions, segment: &Segment, speed: f64) -> TimeLaw {
    let profile = options.profile;
    let len = segment.length();
    let mut law = TimeLaw::fastest(profile, len, speed, options.max_accel);
    let j = options.max_jerk;
    if !(len > 0.0 && law.duration > 0.0) {
        return law;
    }
    let (fv, fa, fj) = (
        profile.peak_velocity_factor(),
        profile.peak_acceleration_factor(),
        profile.peak_jerk_factor(),
    );
    let (kappa, rate) = match segment {
        Segment::Line { .. } => (0.0, 0.0),
        Segment::Arc { .. } => {
            let k = segment.curvature(0.0).norm();
            let h = (len / 8.0).clamp(1e-12, 1e-3);
            let rate = (segment.curvature(h) - segment.curvature(0.0)).norm() / h;
            (k, rate)
        }
    };
    let t_jerk = (fj * len / j).cbrt();
    let t_normal = (6.0 * fv * fa * len * len * kappa / j).cbrt();
    let t_turn = fv * len * (2.0 * rate / j).cbrt();
    let t = t_jerk.max(t_normal).max(t_turn);
    if t.is_finite() && t > law.duration {
        law.duration = t;
    }
    law
}

/// A move of a run timed as an exact stop.
struct ExactMove {
    segment: Segment,
    law: TimeLaw,
    line: usize,
    limited: Option<JointLimitedMove>,
}

/// The moves of a run timed each rest to rest as under `G61` (the fastest law within the
/// move's feed and `max_accel`, slowed down for the joint limits, [`joint_limited_duration`]).
fn exact_moves(
    moves: &[RunMove],
    options: &TimingOptions,
    mut joints: Option<&mut JointConstraints<'_>>,
) -> Vec<ExactMove> {
    moves
        .iter()
        .map(|m| {
            let mut law = exact_law(options, &m.segment, m.feed);
            let mut limited = None;
            if let Some(jc) = joints.as_deref_mut() {
                if let Some((t, joint, quantity)) = joint_limited_duration(&m.segment, &law, jc) {
                    limited = Some(JointLimitedMove {
                        line: m.line,
                        joint,
                        quantity,
                        factor: t / law.duration,
                    });
                    law.duration = t;
                }
            }
            ExactMove {
                segment: m.segment.clone(),
                law,
                line: m.line,
                limited,
            }
        })
        .collect()
}

impl CartesianTrajectory {
    /// Time every move of `program` under the path limits only (no joint limits; see
    /// [`crate::motion::plan`] for the planner that also respects the robot's joints).
    ///
    /// Each `G61` move takes the shortest duration whose peak path speed stays within its
    /// feed (`F`, overriding `max_speed` for that move) or else `max_speed`, and whose peak
    /// path acceleration stays within `max_accel` ([`Profile::min_duration`]).
    pub fn new(program: &Program, options: &TimingOptions) -> Result<Self, TrajectoryError> {
        Self::plan(program, options, None)
    }

    pub(crate) fn plan(
        program: &Program,
        options: &TimingOptions,
        mut joints: Option<&mut JointConstraints<'_>>,
    ) -> Result<Self, TrajectoryError> {
        Self::check_options(options)?;
        let mut timeline = Timeline {
            segments: Vec::with_capacity(program.moves.len()),
            t: 0.0,
            run: Vec::new(),
            joint_limited: Vec::new(),
        };
        let mut pos = program.start;
        if let Some(jc) = joints.as_deref_mut() {
            jc.map.reset();
        }
        for m in &program.moves {
            if let MoveKind::Path { segment, .. } = &m.kind {
                pos = segment.end();
            }
            let Some(step) = Self::move_step(m.line, &m.kind, options, &mut timeline.run)? else {
                continue;
            };
            timeline.flush(options, joints.as_deref_mut())?;
            let (mut kind, mut dt) = Self::time_step(step, options, pos);
            if let (Some(jc), TimedKind::Path { segment, law }) = (joints.as_deref_mut(), &mut kind)
            {
                if let Some((t, joint, quantity)) = joint_limited_duration(segment, law, jc) {
                    timeline.joint_limited.push(JointLimitedMove {
                        line: m.line,
                        joint,
                        quantity,
                        factor: t / law.duration,
                    });
                    law.duration = t;
                    dt = t;
                }
            }
            timeline.push(kind, dt, m.line);
        }
        timeline.flush(options, joints)?;
        Ok(CartesianTrajectory {
            start: program.start,
            start_line: program.start_line,
            segments: timeline.segments,
            duration: timeline.t,
            joint_limited: timeline.joint_limited,
        })
    }

    /// The exact-stop (`G61`) moves that a joint's speed or acceleration limit slowed down
    /// (empty when timed without joint limits, [`CartesianTrajectory::new`]).
    pub fn joint_limited(&self) -> &[JointLimitedMove] {
        &self.joint_limited
    }

    /// Checks the path limits (positive and finite) and the blend tolerance (non-negative
    /// and finite).
    fn check_options(options: &TimingOptions) -> Result<(), TrajectoryError> {
        for (limit, value) in [
            (TimingLimit::PathSpeed, options.max_speed),
            (TimingLimit::PathAcceleration, options.max_accel),
            (TimingLimit::PathJerk, options.max_jerk),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(TrajectoryError::InvalidLimit { limit, value });
            }
        }
        if !(options.blend_tolerance >= 0.0 && options.blend_tolerance.is_finite()) {
            return Err(TrajectoryError::InvalidLimit {
                limit: TimingLimit::BlendTolerance,
                value: options.blend_tolerance,
            });
        }
        Ok(())
    }

    /// Checks one program move (feed, blend tolerance, dwell time) and sorts it: a blended
    /// move joins `run` (`None`), an exact-stop move or a dwell is timed on its own.
    fn move_step<'a>(
        line: usize,
        kind: &'a MoveKind,
        options: &TimingOptions,
        run: &mut Vec<RunMove>,
    ) -> Result<Option<Step<'a>>, TrajectoryError> {
        let step = match kind {
            MoveKind::Path {
                segment,
                feed,
                mode,
            } => {
                let speed = match feed {
                    Some(f) if !(f.is_finite() && *f > 0.0) => {
                        return Err(TrajectoryError::InvalidMove {
                            line,
                            what: "feed",
                            value: *f,
                        })
                    }
                    Some(f) => *f,
                    None => options.max_speed,
                };
                match mode.unwrap_or(options.default_mode) {
                    PathMode::ExactStop => Step::Exact(segment, speed),
                    PathMode::Blend { tolerance } => {
                        let tolerance = tolerance.unwrap_or(options.blend_tolerance);
                        if !(tolerance >= 0.0 && tolerance.is_finite()) {
                            return Err(TrajectoryError::InvalidMove {
                                line,
                                what: "tolerance",
                                value: tolerance,
                            });
                        }
                        run.push(RunMove {
                            segment: segment.clone(),
                            feed: speed,
                            tolerance,
                            line,
                        });
                        return Ok(None);
                    }
                }
            }
            MoveKind::Dwell { seconds } => {
                if !(seconds.is_finite() && *seconds > 0.0) {
                    return Err(TrajectoryError::InvalidMove {
                        line,
                        what: "dwell time",
                        value: *seconds,
                    });
                }
                Step::Dwell(*seconds)
            }
        };
        Ok(Some(step))
    }

    /// Times an exact-stop move (the fastest time law within its speed and `max_accel`,
    /// [`TimeLaw::fastest`]) or a dwell at `pos`; returns the segment kind and duration.
    fn time_step(step: Step<'_>, options: &TimingOptions, pos: Vector3<f64>) -> (TimedKind, f64) {
        match step {
            Step::Exact(segment, speed) => {
                let law = exact_law(options, segment, speed);
                let dt = law.duration;
                (
                    TimedKind::Path {
                        segment: segment.clone(),
                        law,
                    },
                    dt,
                )
            }
            Step::Dwell(seconds) => (TimedKind::Dwell { position: pos }, seconds),
        }
    }

    /// The same trajectory after holding its start point for `hold` seconds (a leading
    /// dwell; every piece `hold` later): the time a `StartTurn`
    /// takes.
    pub(crate) fn delayed(mut self, hold: f64) -> Self {
        for s in &mut self.segments {
            s.start_time += hold;
            s.end_time += hold;
        }
        let line = self.segments.first().map_or(self.start_line, |s| s.line);
        self.segments.insert(
            0,
            TimedSegment {
                kind: TimedKind::Dwell {
                    position: self.start,
                },
                start_time: 0.0,
                end_time: hold,
                line,
            },
        );
        self.duration += hold;
        self
    }

    /// Total duration (s).
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Start point (m), where the robot rests before `t = 0`.
    pub fn start(&self) -> Vector3<f64> {
        self.start
    }

    /// Source line of the start point: the motion that set it (a point of the path at rest
    /// before `t = 0` belongs to that line, not to the first move after it).
    pub(crate) fn start_line(&self) -> usize {
        self.start_line
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

    /// Whether time `t` falls inside a blended (`G64`) run.
    pub fn in_run(&self, t: f64) -> bool {
        let k = self.segments.partition_point(|s| s.end_time < t);
        self.segments
            .get(k)
            .is_some_and(|s| matches!(s.kind, TimedKind::Run(_)) && t >= s.start_time)
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
        if let TimedKind::Run(run) = &piece.kind {
            let st = run.state(t - piece.start_time);
            return CartesianSample {
                position: st.position,
                velocity: st.velocity,
                acceleration: st.acceleration,
                segment: Some(k),
                line: st.line,
            };
        }
        let (position, velocity, acceleration) = piece_state(piece, t);
        CartesianSample {
            position,
            velocity,
            acceleration,
            segment: Some(k),
            line: piece.line,
        }
    }

    /// The piece and the reason that make the trajectory long: the line of the longest timed
    /// piece and what limits it.
    pub(crate) fn longest_piece(
        &self,
        options: &TimingOptions,
        program: &Program,
    ) -> Option<(usize, LongCause)> {
        let piece = self
            .segments
            .iter()
            .max_by(|a, b| (a.end_time - a.start_time).total_cmp(&(b.end_time - b.start_time)))?;
        let cause = match &piece.kind {
            TimedKind::Dwell { .. } => LongCause::Dwell,
            TimedKind::Run(_) => LongCause::Feed,
            TimedKind::Path { segment, law } => {
                let feed = program
                    .moves
                    .iter()
                    .find(|m| m.line == piece.line)
                    .and_then(|m| match &m.kind {
                        MoveKind::Path { feed, .. } => *feed,
                        MoveKind::Dwell { .. } => None,
                    });
                let speed = feed.unwrap_or(options.max_speed);
                let t_speed = law.profile.peak_velocity_factor() * segment.length() / speed;
                if t_speed >= law.duration * (1.0 - 1e-12) {
                    if feed.is_some() {
                        LongCause::Feed
                    } else {
                        LongCause::PathSpeed
                    }
                } else {
                    LongCause::PathAcceleration
                }
            }
        };
        Some((piece.line, cause))
    }
}

/// What makes the longest piece long.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LongCause {
    Dwell,
    Feed,
    PathSpeed,
    PathAcceleration,
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
        TimedKind::Run(run) => {
            let st = run.state(t - piece.start_time);
            (st.position, st.velocity, st.acceleration)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gcode::{parse, ParseOptions, PAPER_TABLE1};

    fn traj(text: &str, options: &TimingOptions) -> CartesianTrajectory {
        let program = parse(text, &ParseOptions::default()).unwrap();
        CartesianTrajectory::new(&program, options).unwrap()
    }

    /// Velocity and acceleration are the time derivatives of position and velocity (central
    /// differences), path speed and tangential acceleration stay within the limits, and the
    /// motion is continuous at every join (at rest there).
    fn check_consistency(tr: &CartesianTrajectory, speed_limits: &[f64], max_accel: f64) {
        let h = 1e-6;
        let n = 20_000;
        for i in 0..=n {
            let t = tr.duration() * i as f64 / n as f64;
            let s = tr.sample(t);
            let (a, b) = (tr.sample(t - h), tr.sample(t + h));
            let fd_v = (b.position - a.position) / (2.0 * h);
            let fd_a = (b.velocity - a.velocity) / (2.0 * h);
            assert!(
                (fd_v - s.velocity).norm() < 1e-7,
                "t {t}: v {} vs {fd_v}",
                s.velocity
            );
            assert!((fd_a - s.acceleration).norm() < 1e-5, "t {t}");
            let k = s.segment.unwrap();
            let speed = s.velocity.norm();
            assert!(speed <= speed_limits[k] * (1.0 + 1e-9), "t {t}: {speed}");
            if speed > 1e-9 {
                let tangential = s.acceleration.dot(&s.velocity) / speed;
                assert!(tangential.abs() <= max_accel * (1.0 + 1e-9), "t {t}");
            }
        }
        for (k, piece) in tr.segments().iter().enumerate() {
            for t in [piece.start_time, piece.end_time] {
                let s = tr.sample(t);
                assert!(
                    s.velocity.norm() < 1e-12 && s.acceleration.norm() < 1e-9,
                    "{k}"
                );
            }
            if let Some(next) = tr.segments().get(k + 1) {
                let end = piece_state(piece, piece.end_time).0;
                let start = piece_state(next, next.start_time).0;
                assert!(
                    (end - start).norm() < 1e-15,
                    "gap at join {k}: {}",
                    (end - start).norm()
                );
            }
        }
    }

    #[test]
    fn paper_program_is_continuous_and_within_limits() {
        for profile in [Profile::Septic, Profile::Quintic] {
            let opts = TimingOptions {
                profile,
                ..TimingOptions::default()
            };
            let tr = traj(PAPER_TABLE1, &opts);
            assert_eq!(tr.segments().len(), 8);
            let limits = vec![opts.max_speed; 8];
            check_consistency(&tr, &limits, opts.max_accel);
            // Duration: the sum of the shortest segment durations (lines 0.4, 0.2, 0.2, 0.4, 0.2 m;
            // arcs a quarter, a half and a quarter of a 0.2 m circle).
            let lengths = [
                0.4,
                0.2,
                0.1 * std::f64::consts::PI,
                0.2 * std::f64::consts::PI,
            ];
            let d = |l: f64| profile.min_duration(l, 0.5, 2.5);
            let expected =
                d(lengths[0]) * 2.0 + d(lengths[1]) * 3.0 + d(lengths[2]) * 2.0 + d(lengths[3]);
            assert!((tr.duration() - expected).abs() < 1e-12);
            assert!((tr.end() - Vector3::new(0.78, 0.0, 0.15)).norm() < 1e-15);
        }
    }

    #[test]
    fn feeds_override_the_speed_limit_and_dwells_hold() {
        // F6000 mm/min = 0.1 m/s; F60000 = 1 m/s (above max_speed, accel-limited here);
        // G00 ignores F.
        let text = "G0 X0 Y0 Z0\nG1 X100 F6000\nG4 P0.25\nG1 X500 F60000\nG0 X0\n";
        let opts = TimingOptions::default();
        let tr = traj(text, &opts);
        let limits = [0.1, f64::INFINITY, 1.0, 0.5];
        check_consistency(&tr, &limits, opts.max_accel);
        let segs = tr.segments();
        assert_eq!(segs.len(), 4);
        // First move speed-limited at 0.1 m/s: T = (35/16)·0.1/0.1.
        assert!((segs[0].end_time - 35.0 / 16.0).abs() < 1e-12);
        // The dwell holds the end of the first move for 0.25 s.
        assert!((segs[1].end_time - segs[1].start_time - 0.25).abs() < 1e-15);
        for f in [0.0, 0.3, 0.7, 1.0] {
            let s = tr.sample(segs[1].start_time + 0.25 * f);
            assert!((s.position - Vector3::new(0.1, 0.0, 0.0)).norm() < 1e-15);
            assert_eq!(s.velocity, Vector3::zeros());
        }
        // 0.4 m at 1 m/s peak would take 0.875 s, the accel limit needs √(7.51·0.4/2.5) s.
        let t2 = segs[2].end_time - segs[2].start_time;
        assert!((t2 - Profile::Septic.min_duration(0.4, 1.0, 2.5)).abs() < 1e-15);
        assert!(t2 > 35.0 / 16.0 * 0.4);
        let t3 = segs[3].end_time - segs[3].start_time;
        assert!((t3 - Profile::Septic.min_duration(0.5, 0.5, 2.5)).abs() < 1e-15);
    }

    #[test]
    fn sampling_outside_the_program() {
        let tr = traj("G0 X1 Y2 Z3\nG1 X10\n", &TimingOptions::default());
        let start = Vector3::new(0.001, 0.002, 0.003);
        let end = Vector3::new(0.010, 0.002, 0.003);
        for t in [-1.0, 0.0, f64::NAN, f64::NEG_INFINITY] {
            let s = tr.sample(t);
            assert_eq!(
                (s.position, s.velocity, s.segment, s.line),
                (start, Vector3::zeros(), Some(0), 2)
            );
        }
        for t in [tr.duration(), tr.duration() + 5.0, f64::INFINITY] {
            let s = tr.sample(t);
            assert!((s.position - end).norm() < 1e-18);
            assert_eq!(
                (s.velocity, s.acceleration),
                (Vector3::zeros(), Vector3::zeros())
            );
        }
        // A program that only sets its start point.
        let tr = traj("G0 X1 Y2 Z3\n", &TimingOptions::default());
        assert_eq!(tr.duration(), 0.0);
        let s = tr.sample(0.5);
        assert_eq!((s.position, s.segment, s.line), (start, None, 1));
        assert_eq!(tr.end(), start);
    }

    #[test]
    fn invalid_options_and_moves() {
        let p = parse(PAPER_TABLE1, &ParseOptions::default()).unwrap();
        for (speed, accel, name) in [
            (0.0, 1.0, TimingLimit::PathSpeed),
            (f64::NAN, 1.0, TimingLimit::PathSpeed),
            (1.0, -2.0, TimingLimit::PathAcceleration),
            (1.0, f64::INFINITY, TimingLimit::PathAcceleration),
        ] {
            let opts = TimingOptions {
                max_speed: speed,
                max_accel: accel,
                ..TimingOptions::default()
            };
            match CartesianTrajectory::new(&p, &opts) {
                Err(TrajectoryError::InvalidLimit { limit, .. }) => assert_eq!(limit, name),
                other => panic!("{other:?}"),
            }
        }
        let mut bad = p.clone();
        if let Some(MoveKind::Path { feed, .. }) = bad.moves.get_mut(0).map(|m| &mut m.kind) {
            *feed = Some(-1.0);
        }
        let e = CartesianTrajectory::new(&bad, &TimingOptions::default()).unwrap_err();
        assert!(e.to_string().contains("program line 17"), "{e}");
    }
}
