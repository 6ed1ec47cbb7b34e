//! Motion planning: a G-code program → a blended, timed Cartesian path → the joint reference
//! the controllers follow. One entry point, [`plan`] (or [`plan_program`] for a parsed
//! program), assembles the pipeline:
//!
//! 1. [`crate::gcode::parse`]: program text → [`Program`] (start point, segments
//!    ([`crate::geometry::Segment`]), feeds, dwells, path modes `G61` / `G64 P…`);
//! 2. the path stage (`path/`, [`blend`]): under `G64` the corners between consecutive lines
//!    are rounded within the tolerance;
//! 3. the timing stage (`timing/`, [`CartesianTrajectory`]): `G61` moves rest to rest with
//!    the paper's septic law (`TimeLaw`), slowed down where a joint's speed or acceleration
//!    limit needs it ([`JointLimitedMove`]); `G64` runs time-optimally under the feed, path
//!    acceleration and jerk and every joint's speed and acceleration limit ([`Run`]);
//! 4. the joint reference (`reference/`, [`JointReference`]): inverse kinematics (analytic
//!    when the robot declares OPW parameters, else numeric) sampled every `Ts`, checked
//!    against the joint limits.
//!
//! `G61` (exact stop) is the default of programs that select neither mode, so that the
//! paper's Table I program runs exactly as published; `G64` without `P` rounds corners within
//! [`TimingOptions::blend_tolerance`] (0.1 mm).
//!
//! ```
//! use ofmpc::motion::{plan, PlanOptions};
//! use ofmpc::robot::Robot;
//!
//! let robot = Robot::irb140();
//! let program = "G21 G90 G64 P0.5\nG0 X500 Y-100 Z400\nG1 X600 F1200\nY0\nX500\nY-100\n";
//! let plan = plan(program, &robot, &PlanOptions::default())?;
//! let r = &plan.reference; // joint reference sampled every 10 ms
//! assert!(r.len() > 100);
//! // The square's corners are rounded within 0.5 mm (quintic blends, passed at the feed:
//! // their jerk-bounded speed is above 20 mm/s): the path never stops between them.
//! let mid = (r.len() / 4..3 * r.len() / 4).map(|k| r.qd(k).iter().map(|v| v.abs()).sum::<f64>());
//! assert!(mid.fold(f64::INFINITY, f64::min) > 1e-3);
//! # Ok::<(), ofmpc::motion::PlanError>(())
//! ```

mod error;
mod limits;
mod path;
mod reference;
mod timing;
mod tool;

pub use error::{PlanError, SampleCause};
pub(crate) use limits::values_per_sample;
#[doc(hidden)]
pub use limits::MAX_PLAN_VALUES;
pub use limits::{JointQuantity, Orientation, ReferenceError, ReferenceFailure};
#[doc(hidden)]
pub use path::blend::{blend, Geometry};
#[doc(hidden)]
pub use reference::build_reference;
pub use reference::JointReference;
pub(crate) use reference::StartTurn;
pub use timing::exact::JointLimitedMove;
pub use timing::timelaw::Profile;
pub use timing::topp::Run;
pub(crate) use timing::trajectory::TimedKind;
pub use timing::trajectory::{
    CartesianSample, CartesianTrajectory, TimingLimit, TimingOptions, TrajectoryError,
};
#[doc(hidden)]
pub use tool::tool_axis;

use crate::gcode::{parse, MoveKind, ParseOptions, PathMode, Program};
use crate::robot::Robot;
use limits::{JointMap, ARM_STRETCHED_RATIO};
use reference::{build_turning_reference, first_unreachable, sample_count};
use timing::topp::JointConstraints;
use timing::trajectory::LongCause;

/// Everything [`plan`] needs besides the program and the robot. Every field has the
/// library's default; the command line takes its defaults from here.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanOptions {
    /// How the program is read (work offset).
    pub parse: ParseOptions,
    /// Path limits, profile and path mode.
    pub timing: TimingOptions,
    /// Flange orientation along the path. Default: as at q = 0.
    pub orientation: Orientation,
    /// Sample period of the joint reference (s). Default 0.01 (the paper's).
    pub ts: f64,
}

impl Default for PlanOptions {
    fn default() -> Self {
        Self {
            parse: ParseOptions::default(),
            timing: TimingOptions::default(),
            orientation: Orientation::AtZero,
            ts: 0.01,
        }
    }
}

/// Numbers that describe a plan.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanDiagnostics {
    /// Duration of the path (s).
    pub duration: f64,
    /// Number of blended (`G64`) runs.
    pub runs: usize,
    /// Factor applied to the joint speed and acceleration limits by the last replan of the
    /// runs (1 when the first plan kept every sample within the limits).
    pub limit_scale: [f64; 2],
    /// Number of timing attempts.
    pub attempts: usize,
    /// Largest joint speed over the runs' samples, as a fraction of its limit.
    pub peak_speed_ratio: f64,
    /// Largest joint acceleration over the runs' samples, as a fraction of its limit.
    pub peak_accel_ratio: f64,
    /// The exact-stop (`G61`) moves a joint limit slowed down, with the cause.
    pub joint_limited: Vec<JointLimitedMove>,
    /// The turn of the joints in place before the first move, from a start pose that is
    /// singular for the path (`StartTurn`); `None` when the path starts without one.
    pub start_turn: Option<StartTurn>,
}

/// A planned program: the parsed program, the timed Cartesian path, the joint reference.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The program as read (its warnings included).
    pub program: Program,
    /// The timed Cartesian path.
    pub trajectory: CartesianTrajectory,
    /// The joint reference, sampled every `ts`.
    pub reference: JointReference,
    /// Diagnostics.
    pub diagnostics: PlanDiagnostics,
    /// Tool length (m) by which the plan extended the robot's TCP along its z axis (the
    /// program's `G43` length at its first path move; 0 without): the reference moves the
    /// TCP of [`Robot::with_tool_length`]`(tool_length)` along [`Plan::trajectory`].
    pub tool_length: f64,
}

/// Largest number of timing attempts of [`plan_program`] (the first and the replans with
/// scaled joint limits).
pub(crate) const MAX_TIMING_ATTEMPTS: usize = 6;

/// Parses `text` and plans it: see [`plan_program`].
///
/// A program whose first motion omits axes starts from the tool position of the robot's
/// start pose ([`Robot::start_q`]) unless `options.parse.start` gives another. A tool length
/// (`G43`) lies along the TCP's z axis ([`tool_axis`]) unless `options.parse.tool_axis`
/// gives another direction.
pub fn plan(text: &str, robot: &Robot, options: &PlanOptions) -> Result<Plan, PlanError> {
    let mut read = options.parse.clone();
    if read.start.is_none() {
        read.start = start_position(robot);
    }
    // A tool length (G43) lies along the TCP's z axis (the module `tool`).
    if read.tool_axis.is_none() {
        read.tool_axis = tool_axis(robot, options.orientation);
    }
    let program = parse(text, &read).map_err(PlanError::Program)?;
    plan_program(program, robot, options)
}

/// The joint reference of `trajectory`; where the robot's start pose is singular for it
/// ([`ReferenceFailure::StartSingular`]) and a turn of the joints in place cures that
/// ([`StartTurn`]), the trajectory delayed by the turn and the reference that turns first.
fn reference_turning_if_singular(
    robot: &Robot,
    trajectory: CartesianTrajectory,
    orientation: Orientation,
    ts: f64,
) -> Sampled {
    let error = match build_reference(robot, &trajectory, orientation, ts) {
        Ok(reference) => return Sampled::Reference(trajectory, reference, None),
        Err(error) => error,
    };
    let Some(turn) = StartTurn::curing(robot, &trajectory, orientation, ts, &error) else {
        let error = stretched_start(robot, orientation, error);
        return Sampled::failed(robot, &trajectory, orientation, ts, error);
    };
    let delayed = trajectory.delayed(turn.duration);
    match build_turning_reference(robot, &delayed, orientation, ts, Some(&turn)) {
        Ok(reference) => Sampled::Reference(delayed, reference, Some(turn)),
        Err(error) => Sampled::failed(robot, &delayed, orientation, ts, error),
    }
}

/// A singular start pose that no turn in place cures ([`StartTurn::curing`]) blamed on the
/// elbow when the start pose holds the arm almost stretched out (the position rows of its arm
/// joints' Jacobian near rank-deficient, `ARM_STRETCHED_RATIO`):
/// [`ReferenceFailure::StartStretched`], the tool leaving the reach; other errors unchanged.
fn stretched_start(
    robot: &Robot,
    orientation: Orientation,
    mut error: ReferenceError,
) -> ReferenceError {
    let ReferenceFailure::StartSingular {
        joint,
        name,
        speed,
        limit,
    } = &error.failure
    else {
        return error;
    };
    let stretched = JointMap::new(robot, orientation)
        .map(|mut map| map.arm_ratio(robot.start_q()) < ARM_STRETCHED_RATIO)
        .unwrap_or(false);
    if stretched {
        error.failure = ReferenceFailure::StartStretched {
            joint: *joint,
            name: name.clone(),
            speed: *speed,
            limit: *limit,
        };
    }
    error
}

/// Largest ratio of a sampled joint speed to its limit in an exact-stop (`G61`) move that is
/// cured by timing the program again under scaled limits: a peak between the time scaling's
/// grid points (issue 38: 2.200 rad/s against 2.175 on a 7-axis arm). A larger excess is a
/// jump or a singularity, reported as such.
const EXACT_STOP_RETIME_RATIO: f64 = 1.2;

/// The share of the limit a move or run timed again for a joint speed over it aims at
/// ([`plan_lines`]): 0.995 at the first two retimes, 0.97 at later ones. The numeric inverse
/// kinematics of a redundant arm drifts a little from sample to sample, and that part of the
/// sampled joint speed does not shrink with the scale (issue 38: a Panda's `G61` moves at
/// F15000 stayed 0.5 % over 2.175 rad/s through five retimes at 0.995, from scale 1 to 0.954);
/// a program that two retimes at 0.995 did not cure takes the wider margin. The first two keep
/// 0.995, so that a program cured by them is timed as before (`init robot`'s placement of the
/// paper's program on the Panda is chosen among such plans).
fn retime_margin(attempts: usize) -> f64 {
    if attempts <= 2 {
        0.995
    } else {
        0.97
    }
}

/// What sampling a timed path in joint space gave.
#[allow(clippy::large_enum_variant)]
enum Sampled {
    /// The trajectory (delayed by the start turn, if any), its reference and the turn.
    Reference(CartesianTrajectory, JointReference, Option<StartTurn>),
    /// A joint exceeds its speed limit by this ratio inside a blended run, or by a little in
    /// an exact-stop move ([`EXACT_STOP_RETIME_RATIO`]): timed again under scaled limits.
    RunTooFast(f64, PlanError),
    /// Another failure.
    Failed(PlanError),
}

impl Sampled {
    /// The failure `error` of `trajectory`'s reference. A joint's speed or range that fails
    /// where a later point of the path is out of the robot's reach is reported as that point
    /// ([`first_unreachable`]): the program does not fit, whatever its timing.
    fn failed(
        robot: &Robot,
        trajectory: &CartesianTrajectory,
        orientation: Orientation,
        ts: f64,
        error: ReferenceError,
    ) -> Self {
        let joints_failed = matches!(
            error.failure,
            ReferenceFailure::JointSpeed { .. }
                | ReferenceFailure::ReachEdge { .. }
                | ReferenceFailure::BranchJump { .. }
                | ReferenceFailure::StartSingular { .. }
                | ReferenceFailure::StartStretched { .. }
                | ReferenceFailure::BranchLimit { .. }
                | ReferenceFailure::SingularPass { .. }
        );
        if joints_failed {
            if let Some(out_of_reach) = first_unreachable(robot, trajectory, orientation, ts) {
                return Self::Failed(PlanError::Reference(out_of_reach));
            }
        }
        match error.failure {
            ReferenceFailure::JointSpeed { speed, limit, .. }
            | ReferenceFailure::ReachEdge { speed, limit, .. }
            | ReferenceFailure::BranchJump { speed, limit, .. }
                if trajectory.in_run(error.time) =>
            {
                Self::RunTooFast(speed / limit, PlanError::Reference(error))
            }
            // An exact-stop move whose sampled joint speed exceeds the limit by a little: the
            // time scaling's grid missed the peak (`timing/exact.rs`). Timed again under
            // scaled limits, the move is slowed down and listed as joint-limited (the G-code
            // tutorial's promise: slowed, with a warning), not refused.
            ReferenceFailure::JointSpeed { speed, limit, .. }
                if speed / limit <= EXACT_STOP_RETIME_RATIO =>
            {
                Self::RunTooFast(speed / limit, PlanError::Reference(error))
            }
            _ => Self::Failed(PlanError::Reference(error)),
        }
    }
}

/// The flange position (m, base frame) at the robot's start pose; `None` if it has none.
pub fn start_position(robot: &Robot) -> Option<nalgebra::Vector3<f64>> {
    let mut ws = crate::dynamics::Workspace::new(robot);
    crate::dynamics::forward_kinematics(robot, &mut ws, robot.start_q())
        .ok()
        .map(|t| t.pos)
}

/// Plans a parsed program for `robot`: blends and times it ([`CartesianTrajectory`]), maps
/// it to joint space and samples it every `options.ts` ([`JointReference`]).
///
/// Blended runs respect every joint's speed and acceleration limit on every sample of the
/// reference: the timing uses them, and if the sampled reference still exceeds one (the
/// jerk filter mixes neighbouring accelerations) the runs are timed again with the limits
/// scaled down, at most `MAX_TIMING_ATTEMPTS` (6) times. A `G61` move whose fastest law would
/// exceed a joint's speed or acceleration limit is slowed down uniformly until it keeps them
/// ([`JointLimitedMove`]); the moves so slowed are listed in
/// [`PlanDiagnostics::joint_limited`]. Before it allocates the reference the planner checks its
/// size against [`MAX_PLAN_VALUES`].
///
/// The program's points are the tool tip's: the robot's TCP is extended by the tool length
/// of the program's first path move, and moves under another length are planned for that
/// point ([`Plan::tool_length`]; the module `tool`). A program that changes its tool length
/// between moves should be read with [`crate::gcode::ParseOptions::tool_axis`] set to
/// [`tool_axis`] (as [`plan`] does).
pub fn plan_program(
    program: Program,
    robot: &Robot,
    options: &PlanOptions,
) -> Result<Plan, PlanError> {
    let columns = program.motion_columns.clone();
    plan_lines(program, robot, options).map_err(|e| with_column(e, &columns))
}

/// A failure at a program line with the column of that line's motion
/// ([`Program::motion_columns`]), where it names no column yet.
fn with_column(mut e: PlanError, columns: &[(usize, usize)]) -> PlanError {
    let reference = match &mut e {
        PlanError::Reference(r) | PlanError::Timing(TrajectoryError::Joint(r)) => r,
        _ => return e,
    };
    if reference.column == 0 {
        if let Some(&(_, c)) = columns.iter().find(|&&(l, _)| l == reference.line) {
            reference.column = c;
        }
    }
    e
}

/// [`plan_program`] without the columns of its errors.
fn plan_lines(program: Program, robot: &Robot, options: &PlanOptions) -> Result<Plan, PlanError> {
    let ts = options.ts;
    if !(ts.is_finite() && ts > 0.0) {
        return Err(PlanError::SamplePeriod(ts));
    }
    let tool_length = tool::reference_length(&program);
    let tooled = tool::tooled_robot(robot, tool_length, &program)?;
    let robot = tooled.as_ref().unwrap_or(robot);
    let (program, as_read) = at_tool_tip(program, robot, options.orientation, tool_length);
    let n = robot.dof();
    let has_runs = has_blended_runs(&program, options);
    let limits = RobotLimits::of(robot);
    let mut map = Some(joint_map(&program, robot, options)?);
    let mut scale = [1.0f64; 2];
    let mut attempts = 0;
    loop {
        attempts += 1;
        let trajectory = limits.time(&program, options, map.as_mut(), scale)?;
        check_sample_count(&trajectory, &program, options, n)?;
        let (trajectory, reference, start_turn) =
            match reference_turning_if_singular(robot, trajectory, options.orientation, ts) {
                Sampled::Reference(t, r, turn) => (t, r, turn),
                // A blended run's timing grid can miss a joint's peak speed near a
                // singularity, which the reference's samples show: timed again slower.
                Sampled::RunTooFast(ratio, _) if attempts < MAX_TIMING_ATTEMPTS => {
                    scale[0] *= retime_margin(attempts) / ratio;
                    continue;
                }
                Sampled::RunTooFast(_, e) | Sampled::Failed(e) => return Err(e),
            };
        // Worst joint speed and acceleration over the runs' samples, relative to the limits.
        let worst = if has_runs {
            limits.worst_in_runs(&trajectory, &reference, ts, n)
        } else {
            [(0.0f64, 0usize, 0usize); 2]
        };
        let ok = worst.iter().all(|w| w.0 <= 1.0 + 1e-9);
        if ok || attempts >= MAX_TIMING_ATTEMPTS {
            if !ok {
                return Err(limits.limit_error(worst, &reference, attempts));
            }
            let diagnostics = PlanDiagnostics::of(&trajectory, scale, attempts, worst, start_turn);
            return Ok(Plan {
                program: as_read.unwrap_or(program),
                trajectory,
                reference,
                diagnostics,
                tool_length,
            });
        }
        slow_down(&mut scale, worst);
    }
}

/// Scales down the speed and acceleration limit factors `scale` whose worst ratio over the
/// runs' samples exceeds 1, to just below the limit (0.995 of the ratio's inverse).
fn slow_down(scale: &mut [f64; 2], worst: [(f64, usize, usize); 2]) {
    for (s, w) in scale.iter_mut().zip(worst) {
        if w.0 > 1.0 {
            *s *= 0.995 / w.0;
        }
    }
}

/// The program with its moves under another tool length than `tool_length` planned for
/// that length's tip, and the program as read; the program itself and `None` when no move
/// needs it (the module `tool`).
fn at_tool_tip(
    program: Program,
    robot: &Robot,
    orientation: Orientation,
    tool_length: f64,
) -> (Program, Option<Program>) {
    let moved = tool_axis(robot, orientation)
        .and_then(|a| tool::controlled_program(&program, tool_length, a));
    match moved {
        Some(m) => (m, Some(program)),
        None => (program, None),
    }
}

impl PlanDiagnostics {
    /// The diagnostics of a plan accepted after `attempts` timings with the joint limits
    /// scaled by `scale`; `worst` is the worst speed and acceleration ratio over the runs.
    fn of(
        trajectory: &CartesianTrajectory,
        scale: [f64; 2],
        attempts: usize,
        worst: [(f64, usize, usize); 2],
        start_turn: Option<StartTurn>,
    ) -> Self {
        Self {
            duration: trajectory.duration(),
            runs: trajectory
                .segments()
                .iter()
                .filter(|s| matches!(s.kind, TimedKind::Run(_)))
                .count(),
            limit_scale: scale,
            attempts,
            peak_speed_ratio: worst[0].0,
            peak_accel_ratio: worst[1].0,
            joint_limited: trajectory.joint_limited().to_vec(),
            start_turn,
        }
    }
}

/// Whether the program has blended moves (`G64`, or the default path mode if it selects
/// none): only those are timed under the joint limits.
fn has_blended_runs(program: &Program, options: &PlanOptions) -> bool {
    program.moves.iter().any(|m| {
        matches!(&m.kind, MoveKind::Path { mode, .. }
            if matches!(mode.unwrap_or(options.timing.default_mode), PathMode::Blend { .. }))
    })
}

/// The map from flange positions to joints used by the timing of blended runs; its errors
/// are reported at the program's start point.
fn joint_map(
    program: &Program,
    robot: &Robot,
    options: &PlanOptions,
) -> Result<JointMap, PlanError> {
    JointMap::new(robot, options.orientation).map_err(|e| {
        PlanError::Reference(ReferenceError {
            line: program.start_line,
            column: program.motion_column(program.start_line).unwrap_or(0),
            time: 0.0,
            position: program.start.into(),
            failure: ReferenceFailure::Ik(e),
        })
    })
}

/// Checks the size of the reference against [`MAX_PLAN_VALUES`] before it is allocated;
/// the error names the likely cause ([`sample_cause`]).
fn check_sample_count(
    trajectory: &CartesianTrajectory,
    program: &Program,
    options: &PlanOptions,
    n: usize,
) -> Result<(), PlanError> {
    let count = sample_count(trajectory.duration(), options.ts) * values_per_sample(n) as f64;
    if count.is_nan() || count > MAX_PLAN_VALUES as f64 {
        return Err(PlanError::TooManySamples {
            cause: sample_cause(trajectory, program, options, n),
            count,
            limit: MAX_PLAN_VALUES,
        });
    }
    Ok(())
}

/// Why the reference would be too large: a sample period below the default that the
/// default would fit, else the longest piece's cause (dwell, feed, path limits).
fn sample_cause(
    trajectory: &CartesianTrajectory,
    program: &Program,
    options: &PlanOptions,
    n: usize,
) -> SampleCause {
    let at_default = sample_count(trajectory.duration(), PlanOptions::default().ts)
        * values_per_sample(n) as f64;
    if options.ts < PlanOptions::default().ts && at_default <= MAX_PLAN_VALUES as f64 {
        SampleCause::SamplePeriod
    } else {
        match trajectory.longest_piece(&options.timing, program) {
            Some((line, LongCause::Dwell)) => SampleCause::Dwell { line },
            Some((line, LongCause::Feed)) => SampleCause::Feed { line },
            Some((line, LongCause::PathSpeed)) => SampleCause::PathSpeed { line },
            Some((line, LongCause::PathAcceleration)) => SampleCause::PathAcceleration { line },
            None => SampleCause::SamplePeriod,
        }
    }
}

/// The robot's joint speed and acceleration limits, per joint.
struct RobotLimits {
    velocity: Vec<f64>,
    acceleration: Vec<f64>,
}

impl RobotLimits {
    /// The limits of `robot`'s joints.
    fn of(robot: &Robot) -> Self {
        let velocity: Vec<f64> = robot.joints().iter().map(|j| j.limits.velocity).collect();
        let acceleration: Vec<f64> = robot
            .joints()
            .iter()
            .map(|j| j.limits.acceleration)
            .collect();
        Self {
            velocity,
            acceleration,
        }
    }

    /// Times the program: blended runs (with a joint map) under the joint speed and
    /// acceleration limits scaled by `scale`, else under the path limits only.
    fn time(
        &self,
        program: &Program,
        options: &PlanOptions,
        map: Option<&mut JointMap>,
        scale: [f64; 2],
    ) -> Result<CartesianTrajectory, PlanError> {
        match map {
            Some(map) => {
                let mut jc = JointConstraints {
                    map,
                    velocity: self.velocity.iter().map(|v| v * scale[0]).collect(),
                    acceleration: self.acceleration.iter().map(|a| a * scale[1]).collect(),
                };
                CartesianTrajectory::plan(program, &options.timing, Some(&mut jc))
            }
            None => CartesianTrajectory::plan(program, &options.timing, None),
        }
        .map_err(PlanError::Timing)
    }

    /// The worst joint speed and acceleration ratios to the limits over the samples of the
    /// blended runs: `(ratio, joint, sample)` for speed, then acceleration.
    fn worst_in_runs(
        &self,
        trajectory: &CartesianTrajectory,
        reference: &JointReference,
        ts: f64,
        n: usize,
    ) -> [(f64, usize, usize); 2] {
        let mut worst = [(0.0f64, 0usize, 0usize); 2];
        for k in 0..reference.len() {
            if !trajectory.in_run(k as f64 * ts) {
                continue;
            }
            for i in 0..n {
                let rv = reference.qd(k)[i].abs() / self.velocity[i];
                let ra = reference.qdd(k)[i].abs() / self.acceleration[i];
                if rv > worst[0].0 {
                    worst[0] = (rv, i, k);
                }
                if ra > worst[1].0 {
                    worst[1] = (ra, i, k);
                }
            }
        }
        worst
    }

    /// The error for a reference that still exceeds a joint limit after the last attempt:
    /// the speed if it is exceeded, else the acceleration.
    fn limit_error(
        &self,
        worst: [(f64, usize, usize); 2],
        reference: &JointReference,
        attempts: usize,
    ) -> PlanError {
        let (q, (ratio, i, k)) = if worst[0].0 > 1.0 + 1e-9 {
            (JointQuantity::Speed, worst[0])
        } else {
            (JointQuantity::Acceleration, worst[1])
        };
        let limit = if q == JointQuantity::Speed {
            self.velocity[i]
        } else {
            self.acceleration[i]
        };
        PlanError::JointLimit {
            joint: i + 1,
            quantity: q,
            value: ratio * limit,
            limit,
            line: reference.line(k),
            attempts,
        }
    }
}
