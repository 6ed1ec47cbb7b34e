//! Time-optimal timing of a blended run under path and joint limits (TOPP by reachability),
//! followed by a jerk-limiting filter.
//!
//! # Method
//!
//! The run (a blended path from rest to rest, `path/blend.rs`) is gridded in arc
//! length `s` (nodes at most [`GRID_STEP`] apart, at least two intervals per piece, every
//! piece boundary a node). With the state `x = ṡ²` and the control `u = s̈` (constant between
//! nodes, so `x_{i+1} = x_i + 2 Δs_i u_i`), each node has
//!
//! - a velocity limit `x ≤ x̄_i`: the cruise speed (feed) `x ≤ F²`, the centripetal
//!   acceleration `κ x ≤ a_max`, and each joint's speed `|q'_j(s)| √x ≤ v_j`, with
//!   `q'(s) = dq/ds` from the inverse kinematics at the nodes (finite differences);
//! - the velocity-dependent part of each joint's acceleration within its limit,
//!   `|q''_j(s)| x ≤ A_j` (conservative: the tangential acceleration could cancel it at one
//!   point, but not over a short blend sampled by a few nodes, nor after the filter);
//! - an admissible control interval `[u_lo(x), u_hi(x)]`: the tangential acceleration
//!   `|u| ≤ a_max` and each joint's acceleration `|q'_j u + q''_j x| ≤ A_j`
//!   (`q̈ = q' s̈ + q'' ṡ²`), linear in `(u, x)` as in TOPP-RA (Pham & Pham 2018);
//! - rest (`x = 0`) at the run's ends and at corners that cannot be blended.
//!
//! A backward pass computes the largest controllable state `k_i` (the largest `x ≤ x̄_i`
//! from which some admissible `u` reaches `[0, k_{i+1}]`; `u_lo` is convex and `u_hi`
//! concave in `x`, so the sets are intervals `[0, k_i]` found by bisection); a forward pass
//! takes the largest admissible step `x_{i+1} = min(k_{i+1}, x_i + 2Δs u_hi(x_i))`. This is
//! the time-optimal profile for the discretized problem, bang-bang in `s̈`.
//!
//! # Jerk limit
//!
//! Between stops the profile `ṡ(t)` is then averaged over a sliding window of
//! `T_j = 2 a / j_max` (a box filter, as in FIR-based interpolators of CNCs), `a` the
//! section's tangential acceleration limit: `a_max`, or less for a section too short to use
//! it (`(d j²/4)^{1/3}` for a rest-to-rest section of length `d`, which minimises its duration `2√(d/a) + 2a/j`). The filtered acceleration `(ṡ(t) − ṡ(t − T_j)) / T_j`
//! stays within `a`, its jerk `(s̈(t) − s̈(t − T_j)) / T_j` within `j_max`, the distance is
//! unchanged, each section still starts and ends at rest, and lasts `T_j` longer. Stops are
//! boundary conditions of their sections: nothing crosses them. The filtered speed stays
//! within every velocity limit because each limit is extended, before the passes, over the
//! distance the window spans at that limit's own speed (the erosion: see `eroded_limits`). The filter may
//! mix accelerations of neighbouring positions: the caller checks the joint accelerations of
//! the sampled reference and, if needed, replans with scaled limits ([`crate::motion::plan`]).
//!
//! A section that passes corners without stopping (a `G64` run) is filtered over `a / j`
//! instead where that keeps the jerk within `j_max` (the raw acceleration never changes by
//! more than `a` within one window, and the path's jerk stays within [`NARROW_PATH_JERK`]
//! `j_max`), with the limits eroded over half a window ([`NARROW_EROSION`]): the slow-downs
//! into a blend and the speed-ups out of it then take half as long, and the blend's speed is
//! held over half the distance around it (issue 38: a 200 mm square at F12000, `G64 P0.5`,
//! 5.118 s → 4.703 s against TOPP-RA's 4.217 s without a jerk limit, with the finer grid of
//! [`near_blend_step`]). Single moves between
//! stops (every move under `G61`) keep `2 a / j`.
//!
//! The joint derivatives `q'`, `q''` of a node come from the nodes of its own piece (the
//! path is smooth inside a piece); a node that joins two pieces keeps both one-sided values,
//! and both constrain it.

use crate::motion::limits::{JointMap, ReferenceFailure, MAX_PLAN_VALUES};
use crate::motion::path::blend::{Geometry, Piece, TURN_JERK_SHARE};
use nalgebra::Vector3;

/// Reach of the erosion in filter windows where the window is `2a/j` ([`eroded_limits`]):
/// every raw position of a window lies within one window's travel at the limit of the
/// filtered position, with a tenth more as margin.
const WIDE_EROSION: f64 = 1.1;

/// Reach of the erosion in filter windows where the window is `a/j` ([`choose_windows`]):
/// half a window's travel, with a tenth more as margin. A limit `v̄` held by the raw profile
/// over `r = v̄ T / 2` each side of a position `s_k` holds for the filtered profile at `s_k`:
/// the filtered position is the mean of the raw positions of its window, and a window that
/// reaches before `s_k − r` (after `s_k + r`) moves at most `v̄` from there, so its mean lies
/// before (after) `s_k`. The wide windows keep the older, wider reach so that the timing of
/// exact-stop moves (and the paper's reference) is unchanged.
const NARROW_EROSION: f64 = 0.55;

/// Largest path jerk, in shares of the jerk setting, of a section timed with the narrow window
/// ([`choose_windows`]): on a curve the tangential jerk adds to the jerk of the turning
/// (`3 ṡ s̈ κ`, `ṡ³ dk/ds`), where the wide window's monotone changes (at half the setting)
/// leave room; a section that would exceed this keeps the wide window. Issue 26 bounds the
/// path jerk by twice the setting (`tests/motion_jerk.rs`); 1.5 keeps a margin for the
/// reference's own sampling.
const NARROW_PATH_JERK: f64 = 1.5;

/// Largest node spacing of the grid (m).
pub const GRID_STEP: f64 = 1e-3;

/// Pieces shorter than this (m) get no grid nodes of their own (the interval that spans them
/// covers them): finite differences over tinier intervals would be noise.
pub const MIN_NODE_SPACING: f64 = 1e-5;

/// Largest number of grid nodes of one run; beyond it the spacing grows.
pub const MAX_GRID_NODES: usize = 2_000_000;

/// Time step (s) of the stored timing of a run.
pub const RUN_STEP: f64 = 1e-3;

/// Joint constraints of the timing: the map from flange positions to joints and the limits.
pub(crate) struct JointConstraints<'a> {
    pub(crate) map: &'a mut JointMap,
    /// Speed limits (rad/s), already scaled.
    pub(crate) velocity: Vec<f64>,
    /// Acceleration limits (rad/s²), already scaled.
    pub(crate) acceleration: Vec<f64>,
}

/// Path limits of the timing.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PathLimits {
    pub(crate) max_accel: f64,
    pub(crate) max_jerk: f64,
}

/// Why a run could not be timed.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum RunError {
    /// The inverse kinematics failed at a grid node.
    Joint {
        line: usize,
        position: Vector3<f64>,
        failure: ReferenceFailure,
    },
    /// The stored timing would exceed [`MAX_PLAN_VALUES`].
    TooManySamples { count: f64, line: usize },
}

/// A blended run with its timing: `s(t)` stored every `RUN_STEP`.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    pieces: Vec<Piece>,
    length: f64,
    /// Filtered arc length at `k h`.
    s: Vec<f64>,
    /// Filtered path speed at `k h`.
    v: Vec<f64>,
    step: f64,
}

/// State of a run at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunState {
    /// Position (m).
    pub position: Vector3<f64>,
    /// Velocity (m/s).
    pub velocity: Vector3<f64>,
    /// Acceleration (m/s²).
    pub acceleration: Vector3<f64>,
    /// Arc length along the run (m).
    pub s: f64,
    /// Path speed (m/s).
    pub speed: f64,
    /// Source line.
    pub line: usize,
}

impl Run {
    /// Duration (s).
    pub fn duration(&self) -> f64 {
        (self.s.len().saturating_sub(1)) as f64 * self.step
    }
    /// Length (m).
    pub fn length(&self) -> f64 {
        self.length
    }
    /// The blended pieces.
    pub fn pieces(&self) -> &[Piece] {
        &self.pieces
    }
    /// End point.
    pub fn end(&self) -> Vector3<f64> {
        self.pieces
            .last()
            .map_or_else(Vector3::zeros, |p| p.geometry.point(p.geometry.length()))
    }
    /// Start point.
    pub fn start(&self) -> Vector3<f64> {
        self.pieces
            .first()
            .map_or_else(Vector3::zeros, |p| p.geometry.point(0.0))
    }

    /// Arc length, speed and acceleration at time `t` (clamped): `s` and `ṡ` by cubic
    /// Hermite between the stored samples; `s̈` linear between the central differences of the
    /// stored speeds at the samples, `(ṡ_{k+1} − ṡ_{k−1}) / 2h` (continuous: the Hermite
    /// cubic's own second derivative jumps at every sample, which reads as a jerk of the order
    /// of the setting in 1 ms finite differences).
    fn path_state(&self, t: f64) -> (f64, f64, f64) {
        let last = self.s.len() - 1;
        if t.is_nan() || t <= 0.0 {
            return (self.s[0], 0.0, 0.0);
        }
        let x = t / self.step;
        if x >= last as f64 {
            return (self.s[last], 0.0, 0.0);
        }
        let k = (x.floor() as usize).min(last - 1);
        let tau = x - k as f64;
        let h = self.step;
        let (p0, p1, m0, m1) = (self.s[k], self.s[k + 1], self.v[k] * h, self.v[k + 1] * h);
        let t2 = tau * tau;
        let t3 = t2 * tau;
        let s = (2.0 * t3 - 3.0 * t2 + 1.0) * p0
            + (t3 - 2.0 * t2 + tau) * m0
            + (-2.0 * t3 + 3.0 * t2) * p1
            + (t3 - t2) * m1;
        let ds = (6.0 * t2 - 6.0 * tau) * p0
            + (3.0 * t2 - 4.0 * tau + 1.0) * m0
            + (-6.0 * t2 + 6.0 * tau) * p1
            + (3.0 * t2 - 2.0 * tau) * m1;
        let acc_at = |i: usize| {
            let lo = i.saturating_sub(1);
            let hi = (i + 1).min(last);
            (self.v[hi] - self.v[lo]) / ((hi - lo) as f64 * h)
        };
        let dds = (1.0 - tau) * acc_at(k) + tau * acc_at(k + 1);
        (s, ds / h, dds)
    }

    /// The run at time `t` since its start (clamped to the run).
    pub fn state(&self, t: f64) -> RunState {
        let (s, v, a) = self.path_state(t);
        let k = self
            .pieces
            .partition_point(|p| p.start <= s)
            .saturating_sub(1)
            .min(self.pieces.len() - 1);
        let p = &self.pieces[k];
        let local = s - p.start;
        let tangent = p.geometry.tangent(local);
        RunState {
            position: p.geometry.point(local),
            velocity: tangent * v,
            acceleration: tangent * a + p.geometry.curvature(local) * (v * v),
            s,
            speed: v,
            line: p.line,
        }
    }
}

/// Node data of the grid.
struct Node {
    s: f64,
    /// Velocity limit `x̄` (before erosion).
    xbar: f64,
    /// `q'` and `q''` per joint (empty without joint constraints); a node that joins two
    /// pieces holds both pieces' one-sided values, the entering piece's first (`2 n` values).
    dq: Vec<f64>,
    ddq: Vec<f64>,
    stop: bool,
    line: usize,
    /// Index of the piece this node ends or lies in.
    piece: usize,
    /// Tangential acceleration limit of the node's section (see [`section_accelerations`]).
    a: f64,
    /// Jerk filter window (s) of the node's section: `2 a / j`, or `a / j` where the section's
    /// raw profile allows it (see [`choose_windows`]).
    window: f64,
    /// Reach of the erosion per unit speed (s) in the node's section (see [`eroded_limits`]).
    erosion: f64,
}

/// Admissible `[u_lo, u_hi]` at node `n` and state `x` (`lo > hi` when none).
fn controls(n: &Node, x: f64, a_max: f64, acc: &[f64]) -> (f64, f64) {
    let (mut lo, mut hi) = (-a_max, a_max);
    for j in 0..n.dq.len() {
        let (c, e, a) = (n.dq[j], n.ddq[j] * x, acc[j % acc.len()]);
        if c.abs() > 1e-12 {
            let (b1, b2) = ((-a - e) / c, (a - e) / c);
            lo = lo.max(b1.min(b2));
            hi = hi.min(b1.max(b2));
        } else if e.abs() > a {
            return (1.0, -1.0);
        }
    }
    (lo, hi)
}

/// Largest `x ∈ [0, xmax]` with `pred(x)`, for a predicate true at 0 and on an interval.
fn bisect(xmax: f64, pred: impl Fn(f64) -> bool) -> f64 {
    if pred(xmax) {
        return xmax;
    }
    let (mut a, mut b) = (0.0, xmax);
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if pred(m) {
            a = m;
        } else {
            b = m;
        }
        if b - a <= 1e-12 * xmax {
            break;
        }
    }
    a
}

/// Times a blended run (see the module documentation).
pub(crate) fn time_run(
    pieces: Vec<Piece>,
    limits: PathLimits,
    joints: Option<&mut JointConstraints<'_>>,
) -> Result<Run, RunError> {
    let length = pieces.last().map_or(0.0, |p| p.start + p.geometry.length());
    let step = grid_step(&pieces);
    let mut nodes = grid_nodes(&pieces, step, limits);
    let a_max = limits.max_accel;
    let acc: Vec<f64> = joints
        .as_ref()
        .map_or_else(Vec::new, |j| j.acceleration.clone());
    let acc: &[f64] = &acc;
    if let Some(jc) = joints {
        joint_derivatives(&mut nodes, &pieces, jc)?;
    }
    section_accelerations(&mut nodes, a_max, limits.max_jerk);
    cap_by_acceleration(&mut nodes, acc);
    let x = choose_windows(&mut nodes, &pieces, acc, limits.max_jerk);
    let (s_out, v_out) = sample_run(&nodes, &x)?;
    Ok(Run {
        pieces,
        length,
        s: s_out,
        v: v_out,
        step: RUN_STEP,
    })
}

/// The tangential acceleration limit of each section between stops: `a_max`, or less where a
/// lower one makes the section shorter. The box filter over `T = 2a/j` adds `T` to the
/// section's duration, so a section that cannot use `a_max` is faster at a lower `a`: at rest
/// to rest over a length `d` and a speed limit `v`, the raw profile lasts `2√(d/a)` (no
/// cruise, `d < v²/a`) or `d/v + v/a` (with cruise), and the filtered one `T = 2a/j` longer.
/// The least duration is at `a = (d j²/4)^{1/3}` without cruise and `a = √(v j/2)` with it
/// (`v` the section's highest velocity limit); the best of these and `a_max` is taken. A
/// 0.05 mm section takes 38 ms instead of the 109 ms at `a_max` = 2.5 m/s², `j` = 50 m/s³;
/// a 20 mm section at F600 (10 mm/s) 2.04 s instead of 2.10 s.
fn section_accelerations(nodes: &mut [Node], a_max: f64, j_max: f64) {
    let nn = nodes.len();
    let mut start = 0;
    while start + 1 < nn {
        let mut end = start + 1;
        while end + 1 < nn && !nodes[end].stop {
            end += 1;
        }
        let d = nodes[end].s - nodes[start].s;
        let v = nodes[start..=end]
            .iter()
            .map(|n| n.xbar)
            .fold(0.0f64, f64::max)
            .sqrt();
        let a = section_acceleration(d, v, a_max, j_max);
        let window = 2.0 * a / j_max;
        for n in &mut nodes[start + 1..=end] {
            n.a = a;
            n.window = window;
            n.erosion = WIDE_EROSION * window;
        }
        if start == 0 {
            nodes[0].a = a;
            nodes[0].window = window;
            nodes[0].erosion = WIDE_EROSION * window;
        }
        start = end;
    }
}

/// The acceleration of [`section_accelerations`] for a section of length `d` (m) and
/// highest speed `v` (m/s): the best of `a_max`, `(d j²/4)^{1/3}` and `√(v j/2)` (each at
/// most `a_max`) by the filtered rest-to-rest duration.
fn section_acceleration(d: f64, v: f64, a_max: f64, j_max: f64) -> f64 {
    let duration = |a: f64| {
        let raw = if v.is_finite() && v > 0.0 && d >= v * v / a {
            d / v + v / a
        } else {
            2.0 * (d / a).sqrt()
        };
        raw + 2.0 * a / j_max
    };
    let floor = 1e-9 * a_max;
    [
        a_max,
        (d * j_max * j_max / 4.0).cbrt(),
        (v * j_max / 2.0).sqrt(),
    ]
    .into_iter()
    .filter(|a| a.is_finite())
    .map(|a| a.clamp(floor, a_max))
    .fold((a_max, duration(a_max)), |best, a| {
        let t = duration(a);
        if t < best.1 {
            (a, t)
        } else {
            best
        }
    })
    .0
}

/// Node spacing of the grid: [`GRID_STEP`], grown so the run has at most [`MAX_GRID_NODES`].
fn grid_step(pieces: &[Piece]) -> f64 {
    let total_nodes: f64 = pieces
        .iter()
        .map(|p| (p.geometry.length() / GRID_STEP).ceil().max(2.0))
        .sum();
    if total_nodes > MAX_GRID_NODES as f64 {
        GRID_STEP * total_nodes / MAX_GRID_NODES as f64
    } else {
        GRID_STEP
    }
}

/// Per piece: the speed² within which the turning of its curvature vector keeps the jerk
/// `ṡ³ |dk/ds|` within its share of the bound, and its largest curvature (a blend's peak
/// may fall between the nodes).
fn turn_bounds(pieces: &[Piece], limits: PathLimits) -> Vec<(f64, f64)> {
    pieces
        .iter()
        .map(|p| {
            let (kappa, rate) = p.geometry.curvature_bounds();
            let x_turn = if rate > 0.0 {
                (TURN_JERK_SHARE * limits.max_jerk / rate).powf(2.0 / 3.0)
            } else {
                f64::INFINITY
            };
            let curved = matches!(p.geometry, Geometry::Curve(_) | Geometry::Corner(_));
            (x_turn, if curved { kappa } else { 0.0 })
        })
        .collect()
}

/// The grid spacing on piece `p` for the run's spacing `step`.
fn piece_step(p: &Piece, step: f64, limits: PathLimits) -> f64 {
    // Slow pieces get a finer grid: the erosion of a limit reaches one node spacing
    // beyond `1.1 T_j v` ([`eroded_limits`]), so a 1 mm spacing would hold a 5 mm/s feed
    // 0.2 s longer at each change of feed; an eighth of the filter's reach at the feed
    // (`T_j = 2a/j` at most) keeps that within an eighth of the reach itself.
    let fine = (0.25 * limits.max_accel / limits.max_jerk * p.feed).max(4.0 * MIN_NODE_SPACING);
    if step <= GRID_STEP {
        step.min(fine)
    } else {
        step
    }
}

/// Share of a blend's filter reach (`a/j` times its speed bound) that the grid spacing of the
/// lines next to it keeps within ([`near_blend_step`]).
const NEAR_BLEND_SHARE: f64 = 0.1;

/// The grid spacing of piece `k` where it is a line next to a corner blend: a tenth of the
/// distance the narrow filter window covers at the blend's speed bound
/// ([`NEAR_BLEND_SHARE`]), so that the erosion around the blend, which reaches one node
/// spacing past its own reach (`eroded_limits`), holds the blend's speed only a little beyond
/// it (issue 38: a 1 mm spacing held the 44 mm/s of a square's corners up to 1 mm longer on
/// each side; the square 4.727 s → 4.703 s). Infinite elsewhere (finer grids on blends and arcs
/// resolve their limits more sharply and raised the torture program's path jerk to 103 m/s³,
/// over issue 26's bound of 100), and when the run's spacing is already coarser than
/// [`GRID_STEP`].
fn near_blend_step(
    pieces: &[Piece],
    bounds: &[(f64, f64)],
    k: usize,
    step: f64,
    limits: PathLimits,
) -> f64 {
    let line = matches!(
        &pieces[k].geometry,
        Geometry::Segment(crate::geometry::Segment::Line { .. })
    );
    if step > GRID_STEP || !line {
        return f64::INFINITY;
    }
    let speed = |i: usize| {
        let p = &pieces[i];
        if !matches!(p.geometry, Geometry::Curve(_) | Geometry::Corner(_)) {
            return f64::INFINITY;
        }
        let (x_turn, kappa) = bounds[i];
        let centripetal = if kappa > 0.0 {
            limits.max_accel / kappa
        } else {
            f64::INFINITY
        };
        p.feed.min(x_turn.min(centripetal).sqrt())
    };
    let v = (k.saturating_sub(1)..(k + 2).min(pieces.len()))
        .map(speed)
        .fold(f64::INFINITY, f64::min);
    if v.is_finite() {
        (NEAR_BLEND_SHARE * limits.max_accel / limits.max_jerk * v).max(4.0 * MIN_NODE_SPACING)
    } else {
        f64::INFINITY
    }
}

/// Grid nodes: piece boundaries and interior points at most `step` apart, with the path part
/// of the velocity limit, `x̄ = min(F², a_max / κ)` (feed and curvature of both pieces at a
/// boundary), and rest at the ends and after stopping pieces.
fn grid_nodes(pieces: &[Piece], step: f64, limits: PathLimits) -> Vec<Node> {
    let max_accel = limits.max_accel;
    let bounds = turn_bounds(pieces, limits);
    let mut nodes: Vec<Node> = Vec::new();
    for (k, p) in pieces.iter().enumerate() {
        let len = p.geometry.length();
        let last_piece = k + 1 == pieces.len();
        let tiny = len < MIN_NODE_SPACING;
        if tiny && !(p.stop_after || last_piece || k == 0) {
            continue;
        }
        let piece_step =
            piece_step(p, step, limits).min(near_blend_step(pieces, &bounds, k, step, limits));
        let m = if tiny {
            1
        } else {
            ((len / piece_step).ceil() as usize).max(2)
        };
        let first = if k == 0 { 0 } else { 1 };
        for i in first..=m {
            let local = len * i as f64 / m as f64;
            let at_end = i == m;
            let next = pieces.get(k + 1).filter(|_| at_end);
            let mut kappa = p.geometry.curvature(local).norm().max(bounds[k].1);
            let mut feed = p.feed;
            let mut x_turn = bounds[k].0;
            if let Some(nx) = next {
                kappa = kappa
                    .max(nx.geometry.curvature(0.0).norm())
                    .max(bounds[k + 1].1);
                feed = feed.min(nx.feed);
                x_turn = x_turn.min(bounds[k + 1].0);
            }
            if i == 0 {
                feed = feed.min(p.feed);
                if k > 0 {
                    x_turn = x_turn.min(bounds[k - 1].0);
                }
            }
            let mut xbar = (feed * feed).min(x_turn);
            if kappa > 0.0 {
                xbar = xbar.min(max_accel / kappa);
            }
            nodes.push(Node {
                s: p.start + local,
                xbar,
                dq: Vec::new(),
                ddq: Vec::new(),
                stop: (k == 0 && i == 0) || (at_end && (p.stop_after || next.is_none())),
                line: p.line,
                piece: k,
                a: max_accel,
                window: 2.0 * max_accel / limits.max_jerk,
                erosion: WIDE_EROSION * 2.0 * max_accel / limits.max_jerk,
            });
        }
    }
    nodes
}

/// Joint derivatives along `s`: `q'` and `q''` of every node from the inverse kinematics,
/// each from the nodes of its own piece only (the path is smooth inside a piece; its
/// curvature, and at a stop its tangent, jump between pieces, so a node that joins two pieces
/// keeps both one-sided values), and the joint speed limits `|q'_j| √x ≤ v_j` folded into `x̄`.
fn joint_derivatives(
    nodes: &mut [Node],
    pieces: &[Piece],
    jc: &mut JointConstraints<'_>,
) -> Result<(), RunError> {
    let q = joint_positions(nodes, pieces, jc)?;
    let nj = jc.velocity.len();
    let nn = nodes.len();
    // Node range of each node's piece: from the node before its first (the previous piece's
    // end, the piece's start point) to its last.
    let mut range_lo = vec![0usize; nn];
    let mut range_hi = vec![0usize; nn];
    let mut start = 0;
    while start < nn {
        let mut end = start;
        while end + 1 < nn && nodes[end + 1].piece == nodes[start].piece {
            end += 1;
        }
        let lo = start.saturating_sub(1);
        for i in start..=end {
            range_lo[i] = lo;
            range_hi[i] = end;
        }
        start = end + 1;
    }
    for i in 0..nn {
        let (mut dq, mut ddq) = finite_differences(nodes, &q, nj, i, range_lo[i], range_hi[i]);
        if i == range_hi[i] && i + 1 < nn {
            let (d1, d2) = finite_differences(nodes, &q, nj, i, i, range_hi[i + 1]);
            dq.extend(d1);
            ddq.extend(d2);
        }
        for (j, d) in dq.iter().enumerate() {
            if d.abs() > 0.0 {
                nodes[i].xbar = nodes[i].xbar.min((jc.velocity[j % nj] / d).powi(2));
            }
        }
        nodes[i].dq = dq;
        nodes[i].ddq = ddq;
    }
    Ok(())
}

/// Joint positions at the nodes (row-major, one row of `nj` joints per node) by the inverse
/// kinematics of the flange positions.
fn joint_positions(
    nodes: &[Node],
    pieces: &[Piece],
    jc: &mut JointConstraints<'_>,
) -> Result<Vec<f64>, RunError> {
    jc.map.reset();
    let nn = nodes.len();
    let nj = jc.velocity.len();
    let mut q = vec![0.0; nn * nj];
    for (i, node) in nodes.iter().enumerate() {
        let k = pieces
            .partition_point(|p| p.start <= node.s)
            .saturating_sub(1);
        let p = &pieces[k];
        let pos = p.geometry.point(node.s - p.start);
        let sol = jc.map.solve(&pos).map_err(|failure| RunError::Joint {
            line: node.line,
            position: pos,
            failure,
        })?;
        q[i * nj..(i + 1) * nj].copy_from_slice(sol);
    }
    Ok(q)
}

/// `q'` and `q''` of every joint at node `i` from the nodes `lo..=hi` only: three-point
/// finite differences on the non-uniform grid (the end nodes use their neighbour's stencil
/// extrapolated to second order; two nodes give a constant `q'` and `q'' = 0`).
fn finite_differences(
    nodes: &[Node],
    q: &[f64],
    nj: usize,
    i: usize,
    lo: usize,
    hi: usize,
) -> (Vec<f64>, Vec<f64>) {
    (0..nj)
        .map(|j| {
            let qa = |k: usize| q[k * nj + j];
            if hi < lo + 2 {
                let h = nodes[hi].s - nodes[lo].s;
                return if h > 0.0 {
                    ((qa(hi) - qa(lo)) / h, 0.0)
                } else {
                    (0.0, 0.0)
                };
            }
            let c = i.clamp(lo + 1, hi - 1);
            let (h1, h2) = (nodes[c].s - nodes[c - 1].s, nodes[c + 1].s - nodes[c].s);
            let (y0, y1, y2) = (qa(c - 1), qa(c), qa(c + 1));
            let d2 = 2.0 * (y0 / (h1 * (h1 + h2)) - y1 / (h1 * h2) + y2 / (h2 * (h1 + h2)));
            let d1c = -h2 / (h1 * (h1 + h2)) * y0
                + (h2 - h1) / (h1 * h2) * y1
                + h1 / (h2 * (h1 + h2)) * y2;
            (d1c + d2 * (nodes[i].s - nodes[c].s), d2)
        })
        .unzip()
}

/// Caps the velocity limits by acceleration feasibility: `|q''_j| x ≤ A_j` with `q''` the
/// largest of each node and its neighbours, then the largest `x` with a non-empty admissible
/// control interval.
fn cap_by_acceleration(nodes: &mut [Node], acc: &[f64]) {
    let nn = nodes.len();
    // Acceleration feasibility caps the velocity limit too. The velocity-dependent part of
    // each joint's acceleration alone must fit its limit, `|q''_j| x ≤ A_j`: cancelling it
    // with the tangential acceleration (`u = −q''x/q'`) holds at one node of the grid but not
    // over a blend a few nodes long, and not after the jerk filter.
    // `q''` from three nodes straddling a curvature jump (line → blend) is about half the
    // blend's: take the largest of each node and its neighbours.
    let nj = acc.len();
    // Largest |q''_j| of each node over its sides (one or two pieces).
    let own: Vec<f64> = nodes
        .iter()
        .flat_map(|n| {
            (0..nj).map(move |j| {
                n.ddq
                    .iter()
                    .skip(j)
                    .step_by(nj.max(1))
                    .fold(0.0f64, |m, d| m.max(d.abs()))
            })
        })
        .collect();
    for i in 0..nn {
        if nodes[i].ddq.is_empty() {
            continue;
        }
        let (lo, hi) = (i.saturating_sub(1), (i + 2).min(nn));
        for (j, a) in acc.iter().enumerate() {
            let d2 = (lo..hi).map(|k| own[k * nj + j]).fold(0.0, f64::max);
            if d2 > 0.0 {
                nodes[i].xbar = nodes[i].xbar.min(a / d2);
            }
        }
    }
    for node in nodes.iter_mut() {
        let n = &*node;
        let cap = bisect(n.xbar, |x| {
            let (lo, hi) = controls(n, x, n.a, acc);
            lo <= hi
        });
        node.xbar = cap;
    }
}

/// The velocity limits eroded for the jerk filter: each node's limit `x̄_i` also holds within
/// `T_j √x̄_i` of it (plus one grid step), inside its section between stops.
///
/// Why this suffices: the filtered speed at `t` is the mean of the raw speeds over
/// `[t − T_j, t]` and the filtered position lies among the raw positions of that window,
/// which span `T_j` times the filtered speed. Where the filtered speed first reaches the limit
/// `v̄` at its position `s_f`, every raw position of the window lies within `T_j v̄` of `s_f`,
/// where the eroded limit keeps the raw speed within `v̄`: so the mean cannot exceed it.
/// The reach is set by the slow limit itself (a 5 mm/s feed erodes 0.5 mm at
/// `T_j` = 0.1 s), not by the fast speeds around it.
fn eroded_limits(nodes: &[Node]) -> Vec<f64> {
    let nn = nodes.len();
    let mut out: Vec<f64> = nodes.iter().map(|n| n.xbar).collect();
    let mut start = 0;
    while start + 1 < nn {
        let mut end = start + 1;
        while end + 1 < nn && !nodes[end].stop {
            end += 1;
        }
        erode_section(nodes, nodes[end].erosion, start, end, &mut out);
        start = end;
    }
    out
}

/// [`eroded_limits`] over the nodes `i0..=i1`: a sweep each way with a min-heap of the limits
/// whose reach has not yet ended (lazy removal), O(n log n).
fn erode_section(nodes: &[Node], erosion: f64, i0: usize, i1: usize, out: &mut [f64]) {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let reach = |i: usize| {
        let spacing = if i < i1 {
            nodes[i + 1].s - nodes[i].s
        } else {
            0.0
        }
        .max(if i > i0 {
            nodes[i].s - nodes[i - 1].s
        } else {
            0.0
        });
        erosion * nodes[i].xbar.sqrt() + spacing
    };
    // Non-negative f64 order as their bit patterns.
    let key = |x: f64| x.max(0.0).to_bits();
    let mut heap: BinaryHeap<Reverse<(u64, usize)>> = BinaryHeap::new();
    // A stop is at rest whatever its limit (the next piece's curvature, say): it erodes
    // nothing, or the section would crawl into it.
    for i in i0..=i1 {
        if !nodes[i].stop {
            heap.push(Reverse((key(nodes[i].xbar), i)));
        }
        while let Some(Reverse((_, k))) = heap.peek() {
            if nodes[*k].s + reach(*k) < nodes[i].s {
                heap.pop();
            } else {
                break;
            }
        }
        if let Some(Reverse((_, k))) = heap.peek() {
            out[i] = out[i].min(nodes[*k].xbar);
        }
    }
    heap.clear();
    for i in (i0..=i1).rev() {
        if !nodes[i].stop {
            heap.push(Reverse((key(nodes[i].xbar), i)));
        }
        while let Some(Reverse((_, k))) = heap.peek() {
            if nodes[*k].s - reach(*k) > nodes[i].s {
                heap.pop();
            } else {
                break;
            }
        }
        if let Some(Reverse((_, k))) = heap.peek() {
            out[i] = out[i].min(nodes[*k].xbar);
        }
    }
}

/// Backward pass: the controllable sets `[0, k_i]`, `k_i` the largest `x ≤ x̄_i` (eroded)
/// with an admissible `u` such that `x + 2 Δs_i u_lo ≤ k_{i+1}`; zero at stops.
fn backward_pass(nodes: &[Node], eroded: &[f64], acc: &[f64]) -> Vec<f64> {
    let nn = nodes.len();
    let mut kset = vec![0.0; nn];
    for i in (0..nn.saturating_sub(1)).rev() {
        let n = &nodes[i];
        if n.stop {
            continue;
        }
        let d = nodes[i + 1].s - n.s;
        let knext = kset[i + 1];
        kset[i] = bisect(eroded[i], |x| {
            let (lo, hi) = controls(n, x, nodes[i + 1].a, acc);
            lo <= hi && x + 2.0 * d * lo <= knext
        });
    }
    kset
}

/// Forward pass: the largest admissible step `x_{i+1} = min(k_{i+1}, x_i + 2Δs u_hi(x_i))`
/// (kept slightly above zero except at stops).
fn forward_pass(nodes: &[Node], kset: &[f64], acc: &[f64]) -> Vec<f64> {
    let nn = nodes.len();
    let mut x = vec![0.0; nn];
    for i in 0..nn.saturating_sub(1) {
        let d = nodes[i + 1].s - nodes[i].s;
        let (_, hi) = controls(&nodes[i], x[i], nodes[i + 1].a, acc);
        x[i + 1] = kset[i + 1].min((x[i] + 2.0 * d * hi).max(0.0));
        if !nodes[i + 1].stop {
            x[i + 1] = x[i + 1].max(1e-12);
        }
    }
    x
}

/// The filter window of a section (its end node) in stored steps.
fn window_steps(end: &Node) -> usize {
    ((end.window / RUN_STEP).round() as usize).max(1)
}

/// The sections between stops as node ranges `(first, last)`.
fn section_ranges(nodes: &[Node]) -> Vec<(usize, usize)> {
    let mut bounds = vec![0];
    bounds.extend((1..nodes.len()).filter(|&i| nodes[i].stop));
    bounds.windows(2).map(|w| (w[0], w[1])).collect()
}

/// The velocity profile `x` of the nodes under their windows: erosion, then both passes.
fn profile(nodes: &[Node], acc: &[f64]) -> Vec<f64> {
    let eroded = eroded_limits(nodes);
    let kset = backward_pass(nodes, &eroded, acc);
    forward_pass(nodes, &kset, acc)
}

/// Chooses each section's filter window and returns the profile timed under them.
///
/// The box filter's jerk is `(s̈(t) − s̈(t − T)) / T` of the raw profile: the window
/// `T = 2a/j` bounds it whatever the raw acceleration does (from `−a` to `+a` at a dip), but
/// where the raw acceleration never changes by more than `a` within `a/j`, the window `a/j`
/// bounds it too, and the slow-downs into a blend and the speed-ups out of it (`−a` to a
/// hold, a hold to `+a`: each changes by `a`) are filtered twice as fast, and the limits
/// eroded half as far (issue 38: the corners of a square at F12000, P0.5). A section that
/// passes corners without stopping (it spans several pieces: a `G64` run) is timed with
/// `a/j` first and keeps it if its raw profile, sampled as the filter sees it, meets that
/// condition; every other section (a single move between stops, as every move under `G61`)
/// keeps `2a/j`.
fn choose_windows(nodes: &mut [Node], pieces: &[Piece], acc: &[f64], j_max: f64) -> Vec<f64> {
    let ranges = section_ranges(nodes);
    let mut tried = false;
    for &(i0, i1) in &ranges {
        if nodes[i0 + 1].piece != nodes[i1].piece {
            set_window(nodes, i0, i1, nodes[i1].a / j_max, true);
            tried = true;
        }
    }
    let x = profile(nodes, acc);
    if !tried {
        return x;
    }
    let times = node_times(nodes, &x);
    let mut failed = false;
    for &(i0, i1) in &ranges {
        let short = nodes[i1].window < 2.0 * nodes[i1].a / j_max;
        if short && !jerk_within(nodes, pieces, &x, &times, (i0, i1), j_max) {
            set_window(nodes, i0, i1, 2.0 * nodes[i1].a / j_max, false);
            failed = true;
        }
    }
    if failed {
        profile(nodes, acc)
    } else {
        x
    }
}

/// Sets the window of the section `i0..=i1` (its first node only for the run's first) and
/// its erosion: [`WIDE_EROSION`] windows for `2a/j`, [`NARROW_EROSION`] for `a/j`.
fn set_window(nodes: &mut [Node], i0: usize, i1: usize, window: f64, narrow: bool) {
    let first = if i0 == 0 { 0 } else { i0 + 1 };
    let share = if narrow { NARROW_EROSION } else { WIDE_EROSION };
    for n in &mut nodes[first..=i1] {
        n.window = window;
        n.erosion = share * window;
    }
}

/// Whether the box filter over the window of the section `i0..=i1` keeps the jerk of its
/// raw profile `x` within `j_max` and the path's jerk within [`NARROW_PATH_JERK`] `j_max`:
/// the raw accelerations (second differences of the stored samples, at rest before and
/// after) one window apart differ by at most `j_max` times it, and the Cartesian
/// acceleration `s̈ t + ṡ² k` of the filtered samples changes by at most that share of
/// `j_max` per step.
fn jerk_within(
    nodes: &[Node],
    pieces: &[Piece],
    x: &[f64],
    times: &[f64],
    (i0, i1): (usize, usize),
    j_max: f64,
) -> bool {
    let (raw, steps) = section_samples(nodes, x, times, i0, i1);
    let w = window_steps(&nodes[i1]);
    let h = RUN_STEP;
    let (s0, s1) = (nodes[i0].s, nodes[i1].s);
    let at = |k: isize| -> f64 {
        if k < 0 {
            s0
        } else if k as usize > steps {
            s1
        } else {
            raw[k as usize]
        }
    };
    let acc = |k: isize| (at(k + 1) - 2.0 * at(k) + at(k - 1)) / (h * h);
    let bound = j_max * w as f64 * h * (1.0 + 1e-6);
    let tangential =
        (0..=(steps + w) as isize).all(|k| (acc(k) - acc(k - w as isize)).abs() <= bound);
    tangential
        && path_jerk_within(
            pieces,
            &box_filter(&raw, steps, w, s0, s1),
            NARROW_PATH_JERK * j_max,
        )
}

/// Whether the Cartesian acceleration `s̈ t + ṡ² k` along the filtered samples `f` of the
/// arc length changes by at most `bound` times the step between samples.
fn path_jerk_within(pieces: &[Piece], f: &[f64], bound: f64) -> bool {
    let h = RUN_STEP;
    let accel = |k: usize| {
        let s = f[k];
        let v = (f[k + 1] - f[k - 1]) / (2.0 * h);
        let a = (f[k + 1] - 2.0 * f[k] + f[k - 1]) / (h * h);
        let i = pieces.partition_point(|p| p.start <= s).saturating_sub(1);
        let p = &pieces[i.min(pieces.len() - 1)];
        let local = s - p.start;
        p.geometry.tangent(local) * a + p.geometry.curvature(local) * (v * v)
    };
    let n = f.len();
    if n < 4 {
        return true;
    }
    let mut prev = accel(1);
    (2..n - 1).all(|k| {
        let a = accel(k);
        let ok = (a - prev).norm() <= bound * h;
        prev = a;
        ok
    })
}

/// The timing stored every [`RUN_STEP`]: for each section between stops, integrate the
/// profile `x`, sample it and box-filter it over `t_j`. Returns the filtered `s` and `ṡ`.
fn sample_run(nodes: &[Node], x: &[f64]) -> Result<(Vec<f64>, Vec<f64>), RunError> {
    let nn = nodes.len();
    // Filter window of the section ending at node `i1` (its `window`, in steps).
    let window = |i1: usize| window_steps(&nodes[i1]);
    let h = RUN_STEP;
    let mut bounds = vec![0];
    bounds.extend((1..nn).filter(|&i| nodes[i].stop));
    // Count the samples first (bounded allocation).
    let times = node_times(nodes, x);
    let count = sample_count(nodes, &times, &bounds, &window)?;
    let mut s_out: Vec<f64> = Vec::with_capacity(count as usize + 1);
    let mut v_out: Vec<f64> = Vec::with_capacity(count as usize + 1);
    s_out.push(0.0);
    v_out.push(0.0);
    for w in bounds.windows(2) {
        let (i0, i1) = (w[0], w[1]);
        let (raw, steps) = section_samples(nodes, x, &times, i0, i1);
        let window = window(i1);
        let filtered = box_filter(&raw, steps, window, nodes[i0].s, nodes[i1].s);
        let total = steps + window - 1;
        for k in 1..=total {
            s_out.push(filtered[k]);
            v_out.push(if k == total {
                0.0
            } else {
                (filtered[k + 1] - filtered[k - 1]) / (2.0 * h)
            });
        }
    }
    Ok((s_out, v_out))
}

/// Time at each node: `Δt_i = 2 Δs_i / (√x_i + √x_{i+1})` (constant `s̈` between nodes); an
/// interval at rest at both ends (a tiny piece between two stops) is crossed rest to rest at
/// `±a` (the section's limit), `Δt = 2 √(Δs / a)`.
fn node_times(nodes: &[Node], x: &[f64]) -> Vec<f64> {
    let nn = nodes.len();
    let mut times = vec![0.0; nn];
    for i in 0..nn - 1 {
        let d = nodes[i + 1].s - nodes[i].s;
        let v = x[i].sqrt() + x[i + 1].sqrt();
        times[i + 1] = times[i]
            + if v > 0.0 {
                2.0 * d / v
            } else {
                2.0 * (d.max(0.0) / nodes[i + 1].a).sqrt()
            };
    }
    times
}

/// Number of stored samples of the sections between `bounds` (filter tail included); an
/// error naming the slowest interval's line if the timing would exceed [`MAX_PLAN_VALUES`].
fn sample_count(
    nodes: &[Node],
    times: &[f64],
    bounds: &[usize],
    window: &impl Fn(usize) -> usize,
) -> Result<f64, RunError> {
    let nn = nodes.len();
    let h = RUN_STEP;
    let mut count = 0.0;
    for w in bounds.windows(2) {
        count += ((times[w[1]] - times[w[0]]) / h).ceil() + window(w[1]) as f64;
    }
    if count.is_nan() || 2.0 * count > MAX_PLAN_VALUES as f64 {
        let line = (0..nn - 1)
            .max_by(|&a, &b| (times[a + 1] - times[a]).total_cmp(&(times[b + 1] - times[b])))
            .map_or(0, |i| nodes[i].line);
        return Err(RunError::TooManySamples {
            count: 2.0 * count,
            line,
        });
    }
    Ok(count)
}

/// Unfiltered `s` at `k h` over the section from node `i0` to the stop `i1` (constant `s̈`
/// between nodes: `s = s_i + √x_i τ + u τ²/2`, `u = (x_{i+1} − x_i) / 2Δs`), ending exactly
/// at `s_{i1}`. Returns the samples and the number of steps.
fn section_samples(
    nodes: &[Node],
    x: &[f64],
    times: &[f64],
    i0: usize,
    i1: usize,
) -> (Vec<f64>, usize) {
    let h = RUN_STEP;
    let t0 = times[i0];
    let dur = times[i1] - t0;
    let steps = (dur / h).ceil() as usize;
    // Unfiltered s at k h.
    let mut raw = Vec::with_capacity(steps + 1);
    let mut iv = i0;
    for k in 0..=steps {
        let t = (k as f64 * h).min(dur) + t0;
        while iv + 1 < i1 && times[iv + 1] <= t {
            iv += 1;
        }
        let tau = t - times[iv];
        let d = nodes[iv + 1].s - nodes[iv].s;
        let s = if x[iv] > 0.0 || x[iv + 1] > 0.0 {
            let u = (x[iv + 1] - x[iv]) / (2.0 * d);
            nodes[iv].s + x[iv].sqrt() * tau + 0.5 * u * tau * tau
        } else {
            // Rest to rest at ±a over the interval's time `dt = 2 √(d / a)`.
            let dt = times[iv + 1] - times[iv];
            let a = if dt > 0.0 { 4.0 * d / (dt * dt) } else { 0.0 };
            let late = (dt - tau).max(0.0);
            if tau <= 0.5 * dt {
                nodes[iv].s + 0.5 * a * tau * tau
            } else {
                nodes[iv + 1].s - 0.5 * a * late * late
            }
        };
        raw.push(s.clamp(nodes[iv].s, nodes[iv + 1].s));
    }
    raw[steps] = nodes[i1].s;
    (raw, steps)
}

/// Box filter of one section: the mean of `raw[k − window + 1 ..= k]` for
/// `k = 0 ..= steps + window − 1` (`raw` before 0 = `s_start`, after `steps` = its end),
/// pinned to `s_start` and `s_end` at both ends.
fn box_filter(raw: &[f64], steps: usize, window: usize, s_start: f64, s_end: f64) -> Vec<f64> {
    // Box filter: mean of raw[k − window + 1 ..= k], raw before 0 = start, after = end.
    let get = |k: isize| -> f64 {
        if k < 0 {
            s_start
        } else {
            raw[(k as usize).min(steps)]
        }
    };
    let total = steps + window - 1;
    let mut sum: f64 = (0..window as isize).map(|j| get(-j)).sum();
    let mut filtered = Vec::with_capacity(total + 1);
    filtered.push(sum / window as f64);
    for k in 1..=total as isize {
        sum += get(k) - get(k - window as isize);
        filtered.push(sum / window as f64);
    }
    filtered[0] = s_start;
    filtered[total] = s_end;
    filtered
}

#[cfg(test)]
mod tests {
    use super::*;

    // Pseudo-random numbers in [0, 1).
    use crate::linalg::random::uniform as lcg;

    fn node(s: f64, xbar: f64, stop: bool) -> Node {
        Node {
            s,
            xbar,
            dq: Vec::new(),
            ddq: Vec::new(),
            stop,
            line: 1,
            piece: 0,
            a: 0.5,
            window: 0.05,
            erosion: 0.055,
        }
    }

    /// The eroded limits match a brute force: each node's limit holds within its reach, never
    /// across a stop, and a stop (at rest whatever its limit) erodes nothing.
    #[test]
    fn erosion_matches_brute_force_and_stops_at_stops() {
        let mut seed = 7;
        let n = 300;
        let mut nodes = vec![node(0.0, lcg(&mut seed), true)];
        for i in 1..n {
            let s = nodes[i - 1].s + 0.01 * lcg(&mut seed) + 1e-4;
            nodes.push(node(s, lcg(&mut seed), i == 150 || i == n - 1));
        }
        // Section acceleration 0.5 (node()), jerk 20: T_j = 2 · 0.5 / 20 = 0.05 s.
        let t_j = 0.05;
        let eroded = eroded_limits(&nodes);
        let section = |i: usize| usize::from(i > 150);
        for i in 0..n {
            let mut brute = nodes[i].xbar;
            for k in 0..n {
                let same = section(k) == section(i) && !nodes[k].stop;
                let sp = |a: usize, b: usize| (nodes[b].s - nodes[a].s).abs();
                let spacing = if k + 1 < n { sp(k, k + 1) } else { 0.0 }.max(if k > 0 {
                    sp(k - 1, k)
                } else {
                    0.0
                });
                let reach = 1.1 * t_j * nodes[k].xbar.sqrt() + spacing;
                if same && (nodes[k].s - nodes[i].s).abs() <= reach {
                    brute = brute.min(nodes[k].xbar);
                }
            }
            if i != 150 {
                assert_eq!(eroded[i], brute, "node {i}");
            }
            assert!(eroded[i] <= nodes[i].xbar);
        }
    }

    #[test]
    fn admissible_controls_respect_every_joint_and_bisection_finds_the_edge() {
        let node = Node {
            s: 0.0,
            xbar: 1.0,
            dq: vec![2.0, -1.0],
            ddq: vec![10.0, 0.0],
            stop: false,
            line: 1,
            piece: 0,
            a: 2.5,
            window: 0.1,
            erosion: 0.11,
        };
        let acc = [4.0, 3.0];
        let (lo, hi) = controls(&node, 0.1, 2.5, &acc);
        // Joint 1: |2u + 1| ≤ 4 → u ∈ [−2.5, 1.5]; joint 2: |u| ≤ 3; path: |u| ≤ 2.5.
        assert!((lo + 2.5).abs() < 1e-15 && (hi - 1.5).abs() < 1e-15);
        // Largest x with a non-empty interval: 2u + 10x ∈ [−4, 4] with u ≥ −2.5 → x ≤ 0.9.
        let x = bisect(1.0, |x| {
            let (l, h) = controls(&node, x, 2.5, &acc);
            l <= h
        });
        assert!((x - 0.9).abs() < 1e-9, "{x}");
    }
}
