//! The joint reference the controllers follow: `w_k = q_ref(k Ts)`, sampled
//! once before the run, with its preview `w_{k+1..k+N}` (the last value held
//! past the end of the path), its velocity and acceleration, and the flange
//! position it corresponds to.
//!
//! [`build_reference`] maps a timed Cartesian path to joint space by inverse
//! kinematics: analytic (OPW) when the robot declares its OPW parameters
//! ([`Robot::opw_parameters`], the built-in IRB 140 does), analytic (UR family) when its
//! joint axes are of that geometry ([`Robot::ur_kinematics`]), else numeric: damped
//! least squares from the previous sample (continuation: one branch along the path), and
//! for the first sample, or when that fails, from the start pose
//! ([`Robot::start_q`]), the limits' centre and a low-discrepancy set ([`RobustIk`]).

use super::limits::{Ik, JointMap};
use super::timing::trajectory::CartesianTrajectory;
use crate::ik::ForwardKinematics;
use crate::robot::Robot;
use nalgebra::Vector3;

use super::limits::{
    values_per_sample, Orientation, ReferenceError, ReferenceFailure, LEAVING_REACH, LEAVING_START,
    MAX_PLAN_VALUES, REACH_EDGE_RATIO, START_POSE_TOLERANCE,
};
use crate::ik::IkError;

/// Number of samples at period `ts` of a path of `duration` seconds (samples at 0, ts, …
/// up to and including the end).
pub(crate) fn sample_count(duration: f64, ts: f64) -> f64 {
    (duration / ts - 1e-9).ceil().max(0.0) + 1.0
}

/// Maps the timed path to joint space, sampled every `ts` seconds from t = 0
/// to the end of the path, with constant flange `orientation`.
///
/// Checks every sample: reachable, within the joint limits, and each joint's
/// step within its speed limit times `ts`. The first sample takes the
/// solution closest to the start pose ([`Robot::start_q`], within limits); each later
/// one the solution closest to the previous sample. Where the path's first sample is the
/// start pose's tool pose (within `START_POSE_TOLERANCE`; a program starts there), it is
/// the start pose itself: the run's initial state is then the start pose even where the
/// inverse kinematics would pick another configuration of that tool pose (a redundant arm,
/// a singular wrist). Where they differ, the first sample is the inverse kinematics' solution
/// nearest to the start pose. Refuses, before allocating, a path that
/// needs more than [`MAX_PLAN_VALUES`] values.
pub fn build_reference(
    robot: &Robot,
    trajectory: &CartesianTrajectory,
    orientation: Orientation,
    ts: f64,
) -> Result<JointReference, ReferenceError> {
    build_turning_reference(robot, trajectory, orientation, ts, None)
}

/// [`build_reference`], with the joints following `turn` over its duration (the trajectory
/// holds its start point meanwhile: [`CartesianTrajectory::delayed`]) and the path solved
/// from its end pose after it.
pub(crate) fn build_turning_reference(
    robot: &Robot,
    trajectory: &CartesianTrajectory,
    orientation: Orientation,
    ts: f64,
    turn: Option<&StartTurn>,
) -> Result<JointReference, ReferenceError> {
    let n = robot.dof();
    let start = trajectory.start();
    let fail = |line: usize, time: f64, p: Vector3<f64>, failure| ReferenceError {
        line,
        column: 0,
        time,
        position: [p.x, p.y, p.z],
        failure,
    };
    let first_line = trajectory.start_line();
    if !(ts.is_finite() && ts > 0.0) {
        return Err(fail(
            first_line,
            0.0,
            start,
            ReferenceFailure::SamplePeriod(ts),
        ));
    }
    let count = sample_count(trajectory.duration(), ts);
    let values = count * values_per_sample(n) as f64;
    if values.is_nan() || values > MAX_PLAN_VALUES as f64 {
        return Err(fail(
            first_line,
            0.0,
            start,
            ReferenceFailure::TooManySamples {
                count: values,
                limit: MAX_PLAN_VALUES,
            },
        ));
    }
    let steps = count as usize;
    let mut map = JointMap::new(robot, orientation)
        .map_err(|e| fail(first_line, 0.0, start, ReferenceFailure::Ik(e)))?;
    let mut q = Vec::with_capacity(steps * n);
    let mut position: Vec<[f64; 3]> = Vec::with_capacity(steps);
    let mut lines = Vec::with_capacity(steps);
    let mut prev = vec![0.0; n];
    let mut jac = nalgebra::DMatrix::zeros(6, n);
    let mut exact_qd = Vec::with_capacity(if n == 6 { steps * n } else { 0 });
    let mut exact_ok = true;
    // Whether the run starts at the robot's start pose (see [`ReferenceFailure::StartSingular`]).
    let mut from_start_pose = false;
    for k in 0..steps {
        let t = (k as f64 * ts).min(trajectory.duration());
        let sample = trajectory.sample(t);
        let p = sample.position;
        if let Some(turn) = turn.filter(|turn| t <= turn.duration) {
            // The joints turn in place; the path starts from the turn's end.
            let (q_t, qd_t) = turn.state(t);
            from_start_pose = true;
            map.set_state(&q_t);
            if n == 6 && exact_ok {
                exact_qd.extend_from_slice(&qd_t);
            }
            q.extend_from_slice(&q_t);
            position.push([p.x, p.y, p.z]);
            lines.push(sample.line);
            prev.copy_from_slice(&q_t);
            continue;
        }
        let (line, moved) = (point_line(trajectory, k, sample.line), (p - start).norm());
        let mut sol = map
            .solve(&p)
            .map_err(|e| fail(line, t, p, reach_failure(e, from_start_pose, moved)))?
            .to_vec();
        if k == 0 {
            if let Some(start) = map.keep_start_pose(&p) {
                sol.copy_from_slice(start);
            }
            from_start_pose = sol
                .iter()
                .zip(robot.start_q())
                .all(|(a, b)| (a - b).abs() <= START_POSE_TOLERANCE);
        }
        if k > 0 {
            // Blended runs are timed at the joint speed limits, which the mean speed over a
            // step may exceed by rounding: 1 % slack there (a jump to another arm
            // configuration is far larger; the planner checks the exact speeds itself).
            let slack = if trajectory.in_run(t) { 1.01 } else { 1.0 };
            let leaving_start = from_start_pose && moved <= LEAVING_START;
            let from = position.last().map_or(start, |x| Vector3::from(*x));
            step_within_speed_limits(&mut map, &from, &p, &prev, &sol, ts, slack, leaving_start)
                .map_err(|failure| fail(sample.line, t, p, failure))?;
        }
        // Exact joint velocity where the Jacobian is square and regular:
        // J(q) q̇ = [ṗ; ω] with ω = 0 (constant orientation).
        if n == 6 && exact_ok {
            match map.velocity(&sample.velocity, &mut jac) {
                Some(v) => exact_qd.extend(v),
                None => exact_ok = false,
            }
        }
        q.extend_from_slice(&sol);
        position.push([p.x, p.y, p.z]);
        lines.push(sample.line);
        prev.copy_from_slice(&sol);
    }
    // At least one sample (steps ≥ 1), sizes consistent: cannot fail.
    let mut r = JointReference::from_samples(n, ts, q, position, lines)
        .ok_or_else(|| fail(first_line, 0.0, start, ReferenceFailure::SamplePeriod(ts)))?;
    if n == 6 && exact_ok && exact_qd.len() == r.qd.len() {
        r.qd = exact_qd;
    }
    Ok(r)
}

/// A turn of the joints in place before the path starts, the tool holding still: from a
/// singular start pose ([`ReferenceFailure::StartSingular`], e.g. the IRB 140's q = 0 with
/// joints 4 and 6 on one axis) to the configuration of the same tool pose on the branch the
/// path leaves by, so that the joints need no jump when the tool starts to move.
///
/// The joints move on the straight line from [`StartTurn::from`] to [`StartTurn::to`] with
/// the quintic rest-to-rest law `s(τ) = 10τ³ − 15τ⁴ + 6τ⁵`, `τ = t / T` (peak speed
/// `15/8 · Δ/T`, peak acceleration `10/√3 · Δ/T²`; Biagiotti & Melchiorri, *Trajectory
/// Planning for Automatic Machines and Robots*, 2008, §2.1.5), `T` the shortest duration
/// that keeps every joint within its speed and acceleration limits, rounded up to a whole
/// number of samples. Every point of the line is checked to keep the start's tool pose.
#[derive(Debug, Clone, PartialEq)]
pub struct StartTurn {
    /// The robot's start pose (rad).
    pub from: Vec<f64>,
    /// The same tool pose on the branch the path leaves by (rad).
    pub to: Vec<f64>,
    /// Duration `T` (s); the program's path starts after it.
    pub duration: f64,
    /// The joints' names.
    pub names: Vec<String>,
}

/// How far (m, rad) the tool may move during a [`StartTurn`]: it must hold still.
pub const START_TURN_TOLERANCE: f64 = 1e-9;

impl StartTurn {
    /// Joint positions and velocities at time `t ∈ [0, T]` of the turn.
    pub fn state(&self, t: f64) -> (Vec<f64>, Vec<f64>) {
        let tau = (t / self.duration).clamp(0.0, 1.0);
        let s = tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
        let ds = 30.0 * tau * tau * (1.0 - tau) * (1.0 - tau) / self.duration;
        let q = self
            .from
            .iter()
            .zip(&self.to)
            .map(|(a, b)| a + (b - a) * s)
            .collect();
        let qd = self
            .from
            .iter()
            .zip(&self.to)
            .map(|(a, b)| (b - a) * ds)
            .collect();
        (q, qd)
    }

    /// The turn that cures a [`ReferenceFailure::StartSingular`] `error` of the reference of
    /// `trajectory`: `None` for another failure, or when the branch the path leaves by has no
    /// configuration of the start's tool pose joined to the start pose by a straight line of
    /// that tool pose (within [`START_TURN_TOLERANCE`]).
    pub(crate) fn curing(
        robot: &Robot,
        trajectory: &CartesianTrajectory,
        orientation: Orientation,
        ts: f64,
        error: &ReferenceError,
    ) -> Option<Self> {
        if !matches!(error.failure, ReferenceFailure::StartSingular { .. }) {
            return None;
        }
        let mut map = JointMap::new(robot, orientation).ok()?;
        let from = robot.start_q().to_vec();
        // The branch the path leaves by: the solution where the joints jumped, nearest to
        // the start pose; then the start's tool pose on that branch (at a wrist singularity
        // the closed forms keep the free joint at its hint).
        let leaving = map
            .solve(&trajectory.sample(error.time).position)
            .ok()?
            .to_vec();
        map.set_state(&leaving);
        let to = map.solve(&trajectory.start()).ok()?.to_vec();
        let still = map.fk.flange_pose(&from);
        let holds = (0..=32).all(|i| {
            let s = f64::from(i) / 32.0;
            let q: Vec<f64> = from.iter().zip(&to).map(|(a, b)| a + (b - a) * s).collect();
            let pose = map.fk.flange_pose(&q);
            (pose.translation.vector - still.translation.vector).norm() <= START_TURN_TOLERANCE
                && pose.rotation.angle_to(&still.rotation) <= START_TURN_TOLERANCE
        });
        let within = robot
            .joints()
            .iter()
            .zip(&to)
            .all(|(j, v)| *v >= j.limits.lower && *v <= j.limits.upper);
        if !(holds && within) {
            return None;
        }
        let duration = robot
            .joints()
            .iter()
            .zip(from.iter().zip(&to))
            .map(|(j, (a, b))| {
                let d = (b - a).abs();
                let by_speed = 15.0 / 8.0 * d / j.limits.velocity;
                let by_accel = (10.0 / 3f64.sqrt() * d / j.limits.acceleration).sqrt();
                by_speed.max(by_accel)
            })
            .fold(0.0, f64::max);
        if !(duration.is_finite() && duration > 0.0) {
            return None;
        }
        let duration = (duration / ts - 1e-9).ceil() * ts;
        let names = robot.joints().iter().map(|j| j.name.clone()).collect();
        Some(Self {
            from,
            to,
            duration,
            names,
        })
    }
}

impl std::fmt::Display for StartTurn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the robot's start pose is singular for this path: before the first move, the joints turn in place \
             for {:.3} s, the tool holding still (",
            self.duration
        )?;
        let mut first = true;
        for (i, (a, b)) in self.from.iter().zip(&self.to).enumerate() {
            if (b - a).abs() > START_POSE_TOLERANCE {
                let name = self.names.get(i).map_or("", String::as_str);
                let sep = if first { "" } else { ", " };
                write!(
                    f,
                    "{sep}joint {} ({name}) by {:.1}°",
                    i + 1,
                    (b - a).to_degrees()
                )?;
                first = false;
            }
        }
        write!(f, "); start from a non-singular pose to avoid it")
    }
}

/// Distance (m) the tool moves between the points [`first_unreachable`] checks: 0.1 mm, so
/// that a short move past the edge of the reach is found (a 1 mm move from a stretched arm).
const REACH_CHECK_STEP: f64 = 1e-4;

/// The first sample of `trajectory` (every `ts`, checked where the tool moved by
/// [`REACH_CHECK_STEP`] since the last check, and the last sample) whose pose no arm configuration within the joint limits reaches: the
/// closed-form inverse kinematics (OPW, UR) solved afresh from the start pose. `None` when
/// every checked sample is in reach, or for a robot without a closed form (a numeric solver
/// failing from one start proves nothing).
pub(crate) fn first_unreachable(
    robot: &Robot,
    trajectory: &CartesianTrajectory,
    orientation: Orientation,
    ts: f64,
) -> Option<ReferenceError> {
    let mut map = JointMap::new(robot, orientation).ok()?;
    if matches!(map.ik, Ik::Numeric(_)) {
        return None;
    }
    let steps = sample_count(trajectory.duration(), ts);
    let mut last: Option<Vector3<f64>> = None;
    (0..steps as usize).find_map(|k| {
        let t = (k as f64 * ts).min(trajectory.duration());
        let sample = trajectory.sample(t);
        let p = sample.position;
        let end = k + 1 == steps as usize;
        if !end && last.is_some_and(|l| (p - l).norm() < REACH_CHECK_STEP) {
            return None;
        }
        last = Some(p);
        map.reset();
        match map.solve(&p) {
            Err(failure @ ReferenceFailure::Ik(_)) => Some(ReferenceError {
                line: point_line(trajectory, k, sample.line),
                column: 0,
                time: t,
                position: [p.x, p.y, p.z],
                failure,
            }),
            _ => None,
        }
    })
}

/// Checks the step from `prev` (at `from`) to `sol` (at flange position `p`) against every
/// joint's speed limit times `slack`; the failure names its cause ([`speed_failure`]).
#[allow(clippy::too_many_arguments)]
fn step_within_speed_limits(
    map: &mut JointMap,
    from: &Vector3<f64>,
    p: &Vector3<f64>,
    prev: &[f64],
    sol: &[f64],
    ts: f64,
    slack: f64,
    leaving_start: bool,
) -> Result<(), ReferenceFailure> {
    let too_fast = map.robot.joints().iter().enumerate().find_map(|(i, j)| {
        let speed = (sol[i] - prev[i]).abs() / ts;
        (speed > j.limits.velocity * slack)
            .then(|| (i + 1, j.name.clone(), speed, j.limits.velocity))
    });
    let Some((joint, name, speed, limit)) = too_fast else {
        return Ok(());
    };
    if let Some(failure) = map.branch_limit(p, prev) {
        return Err(failure);
    }
    Err(speed_failure(
        map,
        (from, p),
        (prev, sol),
        (joint, name, speed, limit),
        leaving_start,
    ))
}

/// The cause of a joint's speed over its limit on the step from `prev` (at `from`) to `sol`
/// (at `to`), in this order: the edge of the reach (the position rows of the Jacobian near
/// rank-deficient, [`REACH_EDGE_RATIO`]), a singular start pose (`leaving_start`), a jump to
/// another arm configuration ([`JointMap::jumps`]), or the speed itself.
fn speed_failure(
    map: &mut JointMap,
    (from, to): (&Vector3<f64>, &Vector3<f64>),
    (prev, sol): (&[f64], &[f64]),
    (joint, name, speed, limit): (usize, String, f64, f64),
    leaving_start: bool,
) -> ReferenceFailure {
    if map.position_ratio(prev) < REACH_EDGE_RATIO {
        return ReferenceFailure::ReachEdge {
            joint,
            name,
            speed,
            limit,
        };
    }
    if leaving_start {
        return ReferenceFailure::StartSingular {
            joint,
            name,
            speed,
            limit,
        };
    }
    if map.jumps(from, to, prev, sol, joint - 1) {
        return ReferenceFailure::BranchJump {
            joint,
            name,
            step: (sol[joint - 1] - prev[joint - 1]).abs(),
            speed,
            limit,
        };
    }
    ReferenceFailure::JointSpeed {
        joint,
        name,
        speed,
        limit,
    }
}

/// The program line of sample `k` (its own line `line`): the start point (`k = 0`) is the
/// target of the motion that set it (issue 38: an unreachable point from line 2 was reported at
/// line 3, the first move after it).
fn point_line(trajectory: &CartesianTrajectory, k: usize, line: usize) -> usize {
    if k == 0 {
        trajectory.start_line()
    } else {
        line
    }
}

/// A point out of reach `failure` at `moved` (m) from the start point: blamed on the start
/// pose ([`ReferenceFailure::StartAtReach`]) when the run started there and the point lies
/// within [`LEAVING_REACH`] of it.
fn reach_failure(failure: ReferenceFailure, from_start_pose: bool, moved: f64) -> ReferenceFailure {
    match failure {
        ReferenceFailure::Ik(IkError::Unreachable { excess, .. })
            if from_start_pose && moved <= LEAVING_REACH =>
        {
            ReferenceFailure::StartAtReach { excess, moved }
        }
        other => other,
    }
}

/// A joint reference sampled at `ts`. Vectors are stored row-major (`k·n + i`).
#[derive(Debug, Clone, PartialEq)]
pub struct JointReference {
    n: usize,
    ts: f64,
    q: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
    position: Vec<[f64; 3]>,
    line: Vec<usize>,
}

impl JointReference {
    /// A reference from its samples: `q` (K·n values), the flange positions
    /// (K) and the program line of each sample (K). Velocities and
    /// accelerations are central differences of `q` (zero at the ends, where
    /// the path is at rest). [`build_reference`] replaces the velocities by
    /// the exact `J(q)⁻¹ ṗ` for six-joint robots.
    ///
    /// Returns `None` when the sizes disagree, `K = 0` or `ts ≤ 0`.
    pub fn from_samples(
        n: usize,
        ts: f64,
        q: Vec<f64>,
        position: Vec<[f64; 3]>,
        line: Vec<usize>,
    ) -> Option<Self> {
        let k = position.len();
        if n == 0 || k == 0 || q.len() != k * n || line.len() != k || !(ts > 0.0 && ts.is_finite())
        {
            return None;
        }
        let mut qd = vec![0.0; k * n];
        let mut qdd = vec![0.0; k * n];
        for s in 1..k.saturating_sub(1) {
            for i in 0..n {
                let (a, b, c) = (q[(s - 1) * n + i], q[s * n + i], q[(s + 1) * n + i]);
                qd[s * n + i] = (c - a) / (2.0 * ts);
                qdd[s * n + i] = (c - 2.0 * b + a) / (ts * ts);
            }
        }
        Some(Self {
            n,
            ts,
            q,
            qd,
            qdd,
            position,
            line,
        })
    }
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.n
    }
    /// Sample period (s).
    pub fn ts(&self) -> f64 {
        self.ts
    }
    /// Number of samples K (the path; the hold is not included).
    pub fn len(&self) -> usize {
        self.position.len()
    }
    /// Always false: a reference has at least one sample.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }
    /// Duration of the path (s): `(K − 1) Ts`.
    pub fn duration(&self) -> f64 {
        (self.len() - 1) as f64 * self.ts
    }
    fn clamp(&self, k: usize) -> usize {
        k.min(self.len() - 1)
    }
    /// `w_k` (n values); past the end, the last sample.
    pub fn q(&self, k: usize) -> &[f64] {
        let k = self.clamp(k);
        &self.q[k * self.n..(k + 1) * self.n]
    }
    /// Reference velocity at sample `k` (n values); past the end, the last
    /// sample's (the path ends at rest: zero).
    pub fn qd(&self, k: usize) -> &[f64] {
        let k = self.clamp(k);
        &self.qd[k * self.n..(k + 1) * self.n]
    }
    /// Reference acceleration at sample `k` (n values); past the end, the
    /// last sample's (zero).
    pub fn qdd(&self, k: usize) -> &[f64] {
        let k = self.clamp(k);
        &self.qdd[k * self.n..(k + 1) * self.n]
    }
    /// Flange position of the reference at sample `k` (m, base frame).
    pub fn position(&self, k: usize) -> [f64; 3] {
        self.position[self.clamp(k)]
    }
    /// Program line of sample `k`.
    pub fn line(&self, k: usize) -> usize {
        self.line[self.clamp(k)]
    }
    /// Writes the preview `w_{k+1}, …, w_{k+N}` into `out` (N·n values, `N =
    /// out.len() / n`), holding the last value past the end. Allocation-free.
    pub fn preview(&self, k: usize, horizon: usize, out: &mut [f64]) {
        let n = self.n;
        for j in 0..horizon.min(out.len() / n) {
            out[j * n..(j + 1) * n].copy_from_slice(self.q(k + 1 + j));
        }
    }
    /// All samples of `q`, row-major.
    pub fn q_all(&self) -> &[f64] {
        &self.q
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preview_holds_the_last_value_and_differences_are_exact_for_parabolas() {
        let ts = 0.1;
        let k = 11;
        let q: Vec<f64> = (0..k)
            .flat_map(|s| {
                let t = s as f64 * ts;
                [t * t, -t]
            })
            .collect();
        let r = JointReference::from_samples(2, ts, q, vec![[0.0; 3]; k], vec![1; k]).unwrap();
        assert!(
            (r.qd(5)[0] - 1.0).abs() < 1e-12
                && (r.qdd(5)[0] - 2.0).abs() < 1e-9
                && (r.qd(5)[1] + 1.0).abs() < 1e-12
        );
        let mut p = vec![0.0; 6];
        r.preview(9, 3, &mut p);
        assert_eq!(&p[0..2], r.q(10));
        assert_eq!(&p[2..4], r.q(10));
        assert_eq!(&p[4..6], r.q(10));
        assert!((r.duration() - 1.0).abs() < 1e-12);
        assert!(
            JointReference::from_samples(2, ts, vec![0.0; 3], vec![[0.0; 3]; 2], vec![1; 2])
                .is_none()
        );
    }
}
