//! Corner blending under `G64 P<tol>`: consecutive moves are joined by curvature-continuous
//! (G2) quintic blends (`path/g2blend.rs`) that leave the programmed path by at most
//! the tolerance, so the path need not stop there and its curvature never steps.
//!
//! A corner between two straight lines with unit directions `u₁`, `u₂` turns by
//! `θ = acos(u₁·u₂)`. It is replaced by the quintic from `d` before the corner to `d` after
//! it with zero end curvatures, whose midpoint (its farthest point from the lines) lies
//! `d · 2 sin(θ/2) cos(θ/2) (1/2 − (5/16) α cos(θ/2))` from them (`α` the scale of its end
//! derivatives, 1 or 1.4, whichever allows the higher speed); `d` is set so that this is
//! 0.98 `tol`, and capped at half of each line, so that neighbouring blends never overlap.
//! (Until issue 26 these corners were circular arcs, LinuxCNC's circular blend, whose
//! curvature `1/R` steps at the tangent points: the path acceleration stepped there.)
//!
//! Joins that are already tangent-continuous (angle below [`TANGENT_ANGLE`]) are passed
//! without a stop, and so are near-tangent joins (below [`NEAR_TANGENT_ANGLE`], such as the
//! kinks that three-decimal CAM output leaves between arcs) when the move allows a
//! deviation (`P` > 0): the path keeps its programmed points there, except where the
//! curvature jumps enough to step the centripetal acceleration (a line into an arc): that
//! jump is spread by a quintic blend within the tolerance too. Corners that involve an arc
//! (G02/G03) are rounded by a quintic from a point of the incoming move to a point of the
//! outgoing one, each at the tangent distance `d` of a circular corner of the same angle
//! (capped at half of each move), shortened until the blend keeps within the tolerance of the
//! moves it replaces. The path stops at a tolerance of 0 and at reversals.

use super::g2blend::{blend_deviation, QuinticBlend, SegmentPart};
use crate::geometry::Segment;
use nalgebra::Vector3;

/// The corner arc and the angles that classify a corner are path geometry
/// ([`crate::geometry::corner`]); re-exported here where the blending uses them.
use crate::geometry::corner::{CornerArc, REVERSAL_ANGLE, TANGENT_ANGLE};

/// Angle (rad) below which a join is passed without a stop when its tolerance is positive:
/// 0.05°, a direction change of under 0.1 % of the speed (rounding of CAM output, LinuxCNC's
/// naive-CAM joins); larger kinks between lines are blended, others stop.
pub const NEAR_TANGENT_ANGLE: f64 = 0.05 * std::f64::consts::PI / 180.0;

/// The geometry of one piece of a blended path.
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry {
    /// A programmed move, or the part of a line that the blends leave.
    Segment(Segment),
    /// A corner blend.
    Corner(CornerArc),
    /// The part of an arc that the blends of its corners leave.
    Part(SegmentPart),
    /// A curvature-continuous blend of a corner that involves an arc.
    Curve(QuinticBlend),
}

impl Geometry {
    /// Length (m).
    pub fn length(&self) -> f64 {
        match self {
            Geometry::Segment(s) => s.length(),
            Geometry::Corner(c) => c.length(),
            Geometry::Part(p) => p.length,
            Geometry::Curve(c) => c.length(),
        }
    }
    /// Point at arc length `s`.
    pub fn point(&self, s: f64) -> Vector3<f64> {
        match self {
            Geometry::Segment(g) => g.point(s),
            Geometry::Corner(c) => c.point(s),
            Geometry::Part(p) => p.point(s),
            Geometry::Curve(c) => c.point(s),
        }
    }
    /// Unit tangent at arc length `s`.
    pub fn tangent(&self, s: f64) -> Vector3<f64> {
        match self {
            Geometry::Segment(g) => g.tangent(s),
            Geometry::Corner(c) => c.tangent(s),
            Geometry::Part(p) => p.tangent(s),
            Geometry::Curve(c) => c.tangent(s),
        }
    }
    /// Curvature vector at arc length `s`.
    pub fn curvature(&self, s: f64) -> Vector3<f64> {
        match self {
            Geometry::Segment(g) => g.curvature(s),
            Geometry::Corner(c) => c.curvature(s),
            Geometry::Part(p) => p.curvature(s),
            Geometry::Curve(c) => c.curvature(s),
        }
    }
}

impl Geometry {
    /// Largest curvature (1/m) and largest `|dk/ds|` (1/m², the rate of change of the
    /// curvature vector along the arc length) over the piece: zero on a line; `κ` and `κ²`
    /// on a circle (`κ` times the turning rate of the curvature vector on a helix, from its
    /// curvature vectors 1/16 of the piece apart); over the table of a quintic blend
    /// ([`QuinticBlend::max_curvature_rate`]).
    pub fn curvature_bounds(&self) -> (f64, f64) {
        let segment = match self {
            Geometry::Segment(s) | Geometry::Part(SegmentPart { segment: s, .. }) => s,
            Geometry::Corner(c) => return (1.0 / c.radius, 1.0 / (c.radius * c.radius)),
            Geometry::Curve(c) => return (c.max_curvature(), c.max_curvature_rate()),
        };
        match segment {
            Segment::Line { .. } => (0.0, 0.0),
            Segment::Arc { .. } => {
                let len = segment.length();
                let k0 = segment.curvature(0.0);
                let h = (len / 16.0).max(1e-12);
                let rate = (segment.curvature(h) - k0).norm() / h;
                (k0.norm(), rate)
            }
        }
    }
}

/// One piece of a blended path.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// Geometry.
    pub geometry: Geometry,
    /// Cruise speed (m/s): the move's feed, or the smaller of both feeds on a blend.
    pub feed: f64,
    /// Source line (a blend belongs to the move that enters the corner).
    pub line: usize,
    /// Arc length (m) of the piece's start along the run.
    pub start: f64,
    /// The path must be at rest at the end of this piece (an unblended corner).
    pub stop_after: bool,
}

/// One programmed move of a run, as input to [`blend`].
#[derive(Debug, Clone, PartialEq)]
pub struct RunMove {
    /// Geometry.
    pub segment: Segment,
    /// Cruise speed (m/s).
    pub feed: f64,
    /// Corner tolerance (m) at the end of this move.
    pub tolerance: f64,
    /// Source line.
    pub line: usize,
}

/// Rounds the corners of a sequence of consecutive moves (see the module documentation).
/// The run starts and ends at rest; pieces come out in path order with their start arc
/// lengths.
pub fn blend(moves: &[RunMove]) -> Vec<Piece> {
    blend_within(moves, None)
}

/// [`blend`], but a corner whose blend would be a near-stop (slower than a tenth of the
/// feed) and slower than a stop under the path acceleration `max_accel` and jerk `max_jerk`
/// stops instead.
///
/// The timing (`timing/topp.rs`) holds a blend's speed `v_c = min(F, √(a R))`
/// (feed, centripetal limit on the radius `R`) over about `±1.1 T_j v_c` around it,
/// `T_j = 2a/j` (its jerk filter), which costs about `2.2 T_j (1 − v_c/F)` against cruising;
/// a stop costs one more filter window, `T_j`, and the deceleration from `v_c` to rest,
/// `v_c / a`. Only a blend below [`MIN_BLEND_SPEED_SHARE`] of the feed is traded for a stop
/// when that is cheaper: above it the path keeps moving, as a CNC's `G64` does (issue 38: the
/// 90° corners of a square at F12000, P0.5 stopped, their 44 mm/s blends estimated 45 ms slower
/// each than a stop). The estimate takes the filter's wide window `2a/j`; where the timing
/// filters a run over `a/j` (`timing/topp.rs`) a kept blend costs about half as much, so the
/// estimate errs towards keeping the stop, as before.
pub fn blend_timed(moves: &[RunMove], max_accel: f64, max_jerk: f64) -> Vec<Piece> {
    blend_within(moves, Some((max_accel, max_jerk)))
}

/// Share of the feed at or above which a corner's blend is always kept under `G64`
/// ([`blend_timed`]): below it the blend is a near-stop, and a stop is taken where faster.
pub const MIN_BLEND_SPEED_SHARE: f64 = 0.1;

/// Whether the corner blend `curve` between moves of feeds `f1`, `f2` is a near-stop that is
/// slower than stopping (see [`blend_timed`]): its speed is also held within the jerk bound of
/// its curvature change, `ṡ³ |dk/ds| ≤ TURN_JERK_SHARE · j` (`timing/topp.rs`).
fn stop_is_faster(curve: &QuinticBlend, f1: f64, f2: f64, max_accel: f64, max_jerk: f64) -> bool {
    let feed = f1.min(f2);
    let v_c = feed.min(turn_speed(curve, max_accel, max_jerk));
    let t_j = 2.0 * max_accel / max_jerk;
    let extra = 2.2 * t_j * (1.0 - v_c / feed) - (t_j + v_c / max_accel);
    extra > 0.0 && (v_c < MIN_BLEND_SPEED_SHARE * feed || extra > MAX_BLEND_EXTRA_S)
}

/// Most time (s) a kept `G64` blend of at least [`MIN_BLEND_SPEED_SHARE`] of the feed may
/// cost over a stop at its corner (estimated as in [`blend_timed`]): a CNC keeps moving
/// through a corner it can pass within the tolerance, but a blend much slower than a stop
/// is traded for one, so that a blended program stays near time-optimal.
pub const MAX_BLEND_EXTRA_S: f64 = 0.06;

/// Share of the jerk setting that the turning of the path's curvature vector may take,
/// `ṡ³ |dk/ds|` (the rest of the Cartesian jerk `s⃛ t + 3 ṡ s̈ κ n + ṡ³ dk/ds` is the
/// tangential jerk, within the setting, and `3 ṡ s̈ κ`, small where the speed is held at this
/// bound). Issue 26 bounds the Cartesian jerk by twice the setting: where the speed is held by
/// this bound the tangential jerk is zero, and where the speed changes the two add as vectors
/// at an angle; 1.25 keeps every benchmark program within 2× (worst 96 m/s³ at the setting
/// 50, `tests/motion_jerk.rs`) while the three-decimal kinks of CAM output (0.005 rad over
/// 0.2 mm) still pass at 0.044 m/s instead of 0.041 m/s at 1.0 (the zigzag pocket's
/// TOPP-RA bound needs ≥ 1.2).
pub const TURN_JERK_SHARE: f64 = 1.25;

/// The blend of a corner that involves an arc ([`QuinticBlend`] from the incoming move at
/// `d` before its end to the outgoing one at `d` after its start), `d` shortened (×0.7, at
/// most 30 times) until the blend keeps within the incoming move's tolerance of the path it
/// replaces; `None` if none does.
fn arc_corner(a: &RunMove, b: &RunMove, d: f64) -> Option<(f64, QuinticBlend)> {
    g2_corner(a, b, d, 1.0)
}

/// [`arc_corner`] with the quintic's end derivatives scaled by `alpha`
/// ([`QuinticBlend::with_tangent_scale`]).
fn g2_corner(a: &RunMove, b: &RunMove, d: f64, alpha: f64) -> Option<(f64, QuinticBlend)> {
    let (sa, sb) = (&a.segment, &b.segment);
    let la = sa.length();
    let mut d = d;
    for _ in 0..30 {
        if d.is_nan() || d <= 1e-9 {
            return None;
        }
        let (s0, s1) = (la - d, d);
        let c = QuinticBlend::with_tangent_scale(
            sa.point(s0),
            sa.tangent(s0),
            sa.curvature(s0),
            sb.point(s1),
            sb.tangent(s1),
            sb.curvature(s1),
            alpha,
        );
        if let Some(c) = c {
            let deviation = if is_line(sa) && is_line(sb) {
                lines_deviation(&c, sa.end(), sa.tangent(0.0), sb.tangent(0.0), d)
            } else {
                blend_deviation(&c, sa, d, sb, d)
            };
            if deviation <= a.tolerance {
                return Some((d, c));
            }
        }
        d *= 0.7;
    }
    None
}

/// The blend of a corner between two lines, of half turning angle `half`: the quintic with
/// end derivatives scaled by [`LINE_TANGENT_SCALE`] as long as the tolerance allows (its
/// midpoint 0.98 `P` from the lines, [`line_corner_distance`]), or if that is longer than
/// `cap` allows (half of each line), the one scaled by 1, capped.
fn line_corner(
    a: &RunMove,
    b: &RunMove,
    half: f64,
    cap: impl Fn(f64) -> f64,
) -> Option<(f64, QuinticBlend)> {
    // Bounded by the tolerance, the scale 1.4 allows the higher speed (a quarter of the
    // largest `|dk/ds|` at a 90° corner); at a length fixed by the lines, 1 does.
    let d = 0.98 * a.tolerance / line_corner_distance(half, LINE_TANGENT_SCALE);
    if cap(d) >= d {
        g2_corner(a, b, d, LINE_TANGENT_SCALE)
    } else {
        let d = 0.98 * a.tolerance / line_corner_distance(half, 1.0);
        g2_corner(a, b, cap(d), 1.0)
    }
}

/// The highest speed through `curve` under the centripetal limit `√(a/κ)` and the jerk of
/// its curvature change, `ṡ³ |dk/ds| ≤ TURN_JERK_SHARE · j`.
fn turn_speed(curve: &QuinticBlend, max_accel: f64, max_jerk: f64) -> f64 {
    let radius = 1.0 / curve.max_curvature().max(1e-300);
    let rate = curve.max_curvature_rate();
    let v_turn = if rate > 0.0 {
        (TURN_JERK_SHARE * max_jerk / rate).cbrt()
    } else {
        f64::INFINITY
    };
    (max_accel * radius).sqrt().min(v_turn)
}

/// Path acceleration (m/s²) and jerk (m/s³) of the untimed [`blend`]: the defaults of
/// [`crate::motion::TimingOptions`].
const DEFAULT_ACCEL: f64 = 2.5;
const DEFAULT_JERK: f64 = 50.0;

/// Largest distance from `blend` (33 points evenly spaced in its parameter) to the two lines it replaces: from
/// `corner − d u₁` to the corner and on to `corner + d u₂` (what [`blend_deviation`] computes
/// for any moves, without following the lines by 64 chords).
fn lines_deviation(
    blend: &QuinticBlend,
    corner: Vector3<f64>,
    u1: Vector3<f64>,
    u2: Vector3<f64>,
    d: f64,
) -> f64 {
    let to_line = |p: &Vector3<f64>, dir: &Vector3<f64>, from: f64| {
        let t = ((p - corner).dot(dir)).clamp(from, from + d);
        (p - (corner + dir * t)).norm()
    };
    (0..=32)
        .map(|i| {
            let p = blend.point_at_parameter(i as f64 / 32.0);
            to_line(&p, &u1, -d).min(to_line(&p, &u2, 0.0))
        })
        .fold(0.0, f64::max)
}

/// Whether `s` is a straight line.
fn is_line(s: &Segment) -> bool {
    matches!(s, Segment::Line { .. })
}

/// Scale of the end derivatives of a blend between two lines
/// ([`QuinticBlend::with_tangent_scale`]).
const LINE_TANGENT_SCALE: f64 = 1.4;

/// Distance from the lines to the midpoint of the quintic blend of their corner
/// ([`QuinticBlend`] with zero end curvatures and end derivatives `α |P₁ − P₀|`, from `d`
/// before the corner to `d` after it), per unit of `d`, for the half turning angle `h`:
/// `2 sin h cos h (1/2 − (5/16) α cos h)`.
///
/// The quintic Hermite basis at `u = 1/2` weighs both end points `1/2` and the end
/// derivatives `±5/32`; with `P₀ = C − d t₀`, `P₁ = C + d t₁`, `λ = α |P₁ − P₀| = 2 α d cos h`,
/// the midpoint is `C + (t₁ − t₀) d (1/2 − (5/16) α cos h)`, `|t₁ − t₀| = 2 sin h`, on the
/// bisector inside the corner, `cos h` times that from either line. The midpoint is where
/// the blend is farthest from the lines (to within a few per cent at sharp corners; the
/// blend is then checked against the tolerance, [`arc_corner`]).
fn line_corner_distance(h: f64, alpha: f64) -> f64 {
    2.0 * h.sin() * h.cos() * (0.5 - 5.0 / 16.0 * alpha * h.cos())
}

/// Time (s) over which a step of the centripetal acceleration at a tangent join is read
/// as jerk: the 1 ms sample period at which issue 26 measures the path jerk.
const JUMP_READ_TIME: f64 = 1e-3;

/// The blend of a tangent join whose curvature jumps by `Δκ` so that, at the speed `v` the
/// moves allow there (their feeds and the centripetal limit `√(a/κ)` of both sides), the
/// centripetal acceleration steps by more than half the jerk bound over [`JUMP_READ_TIME`]:
/// `v² Δκ > j · 1 ms / 2` (1.25 m/s² where the paper's path enters its 200 mm arcs at
/// 0.5 m/s; a spiral of tangent arcs whose radius grows by 5 µm per quarter turn steps by
/// 0.0125 m/s² and is left as it is). Only when the move allows a deviation: a
/// [`QuinticBlend`] from `d` before the join to `d` after it,
/// `d` first `2 √(6 P / Δκ)` (a transition of length `L` that ramps the curvature by `Δκ`
/// shifts the path by about `Δκ L²/24`, as a clothoid does), capped at half of each move,
/// then shortened until within the tolerance ([`arc_corner`]).
fn curvature_jump_blend(
    a: &RunMove,
    b: &RunMove,
    limits: (f64, f64),
) -> Option<(f64, QuinticBlend)> {
    if a.tolerance <= 0.0 {
        return None;
    }
    let (a_max, j_max) = limits;
    let (sa, sb) = (&a.segment, &b.segment);
    let (ka, kb) = (sa.curvature(sa.length()), sb.curvature(0.0));
    let jump = (ka - kb).norm();
    let kappa = ka.norm().max(kb.norm());
    let mut v2 = a.feed.min(b.feed).powi(2);
    if kappa > 0.0 {
        v2 = v2.min(a_max / kappa);
    }
    if jump.is_nan() || v2 * jump <= 0.5 * j_max * JUMP_READ_TIME {
        return None;
    }
    let d = (2.0 * (6.0 * a.tolerance / jump).sqrt())
        .min(sa.length() / 2.0)
        .min(sb.length() / 2.0);
    arc_corner(a, b, d)
}

/// The corner after each move: its tangent distance (0: no blend), whether the path stops
/// there, and the curvature-continuous blend of a corner that involves an arc.
type Corners = (Vec<f64>, Vec<bool>, Vec<Option<QuinticBlend>>);

/// Decides every corner of `moves` (see [`blend`] and [`blend_timed`]).
fn corners(moves: &[RunMove], timed: Option<(f64, f64)>) -> Corners {
    let m = moves.len();
    // Tangent distance at the corner after move k (0: no blend).
    let mut d = vec![0.0; m];
    let mut stop = vec![false; m];
    // The curvature-continuous blend of a corner that involves an arc.
    let mut curve: Vec<Option<QuinticBlend>> = vec![None; m];
    for k in 0..m.saturating_sub(1) {
        let (a, b) = (&moves[k], &moves[k + 1]);
        let u1 = a.segment.tangent(a.segment.length());
        let u2 = b.segment.tangent(0.0);
        let theta = u1.dot(&u2).clamp(-1.0, 1.0).acos();
        if theta < TANGENT_ANGLE || (theta < NEAR_TANGENT_ANGLE && a.tolerance > 0.0) {
            // A tangent join where the curvature jumps (a line into an arc): the jump is
            // spread over a curvature-continuous blend within the tolerance.
            let limits = timed.unwrap_or((DEFAULT_ACCEL, DEFAULT_JERK));
            if let Some((dk, c)) = curvature_jump_blend(a, b, limits) {
                d[k] = dk;
                curve[k] = Some(c);
            }
            continue;
        }
        let both_lines = is_line(&a.segment) && is_line(&b.segment);
        if theta > REVERSAL_ANGLE || a.tolerance <= 0.0 {
            stop[k] = true;
            continue;
        }
        let half = theta / 2.0;
        let cap = |d: f64| {
            d.min(a.segment.length() / 2.0)
                .min(b.segment.length() / 2.0)
        };
        let candidate = if both_lines {
            line_corner(a, b, half, cap)
        } else {
            // From the tangent distance of a circular blend of the same angle.
            let d_arc = a.tolerance / (1.0 / half.cos() - 1.0) * half.tan();
            arc_corner(a, b, cap(d_arc))
        };
        let Some((dk, c)) = candidate else {
            stop[k] = true;
            continue;
        };
        let slow =
            timed.is_some_and(|(a_max, j_max)| stop_is_faster(&c, a.feed, b.feed, a_max, j_max));
        if !slow {
            curve[k] = Some(c);
        }
        if dk > 1e-12 && !slow {
            d[k] = dk;
        } else {
            stop[k] = true;
        }
    }
    (d, stop, curve)
}

fn blend_within(moves: &[RunMove], timed: Option<(f64, f64)>) -> Vec<Piece> {
    let m = moves.len();
    let (d, stop, mut curve) = corners(moves, timed);
    let mut pieces: Vec<Piece> = Vec::with_capacity(2 * m);
    let push =
        |pieces: &mut Vec<Piece>, geometry: Geometry, feed: f64, line: usize, stop_after: bool| {
            let start = pieces.last().map_or(0.0, |p| p.start + p.geometry.length());
            pieces.push(Piece {
                geometry,
                feed,
                line,
                start,
                stop_after,
            });
        };
    for k in 0..m {
        let mv = &moves[k];
        let d_in = if k > 0 { d[k - 1] } else { 0.0 };
        let d_out = d[k];
        match &mv.segment {
            Segment::Line { a, b } if d_in > 0.0 || d_out > 0.0 => {
                let u = (b - a).normalize();
                let (p0, p1) = (a + u * d_in, b - u * d_out);
                if (p1 - p0).dot(&u) > 1e-9 {
                    push(
                        &mut pieces,
                        Geometry::Segment(Segment::line(p0, p1)),
                        mv.feed,
                        mv.line,
                        false,
                    );
                }
            }
            seg if d_in > 0.0 || d_out > 0.0 => {
                let length = seg.length() - d_in - d_out;
                if length > 1e-9 {
                    let part = SegmentPart {
                        segment: seg.clone(),
                        from: d_in,
                        length,
                    };
                    push(&mut pieces, Geometry::Part(part), mv.feed, mv.line, false);
                }
            }
            seg => push(
                &mut pieces,
                Geometry::Segment(seg.clone()),
                mv.feed,
                mv.line,
                stop[k],
            ),
        }
        if let Some(c) = curve[k].take() {
            let feed = mv.feed.min(moves[k + 1].feed);
            push(&mut pieces, Geometry::Curve(c), feed, mv.line, false);
        } else if d_out > 0.0 {
            let next = &moves[k + 1];
            let u1 = mv.segment.tangent(mv.segment.length());
            let u2 = next.segment.tangent(0.0);
            if let Some(c) = CornerArc::new(mv.segment.end(), u1, u2, d_out) {
                push(
                    &mut pieces,
                    Geometry::Corner(c),
                    mv.feed.min(next.feed),
                    mv.line,
                    false,
                );
            }
        } else if stop[k] {
            if let Some(last) = pieces.last_mut() {
                last.stop_after = true;
            }
        }
    }
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    fn dist_to_segment(p: Vector3<f64>, a: Vector3<f64>, b: Vector3<f64>) -> f64 {
        let u = b - a;
        let t = ((p - a).dot(&u) / u.norm_squared()).clamp(0.0, 1.0);
        (p - (a + u * t)).norm()
    }

    fn line_move(a: Vector3<f64>, b: Vector3<f64>, tol: f64) -> RunMove {
        RunMove {
            segment: Segment::line(a, b),
            feed: 0.1,
            tolerance: tol,
            line: 1,
        }
    }

    /// The blended path is continuous with a continuous tangent and curvature (issue 26:
    /// line corners are quintic G2 blends), the blend keeps within the tolerance of the lines
    /// (dense scan) and uses it (0.98 P, or half a line when that is shorter).
    #[test]
    fn square_corner_within_tolerance_and_tangent_continuous() {
        for (tol, turn) in [(0.5e-3, 90f64), (0.05e-3, 30.0), (1e-3, 150.0), (2e-3, 5.0)] {
            let t = turn.to_radians();
            let a = v(0.0, 0.0, 0.0);
            let c = v(0.1, 0.0, 0.0);
            let b = c + v(t.cos(), t.sin(), 0.3 * t.sin()).normalize() * 0.1;
            let pieces = blend(&[line_move(a, c, tol), line_move(c, b, tol)]);
            assert_eq!(pieces.len(), 3, "{turn}");
            let mut worst: f64 = 0.0;
            for w in pieces.windows(2) {
                let (p, q) = (&w[0], &w[1]);
                let l = p.geometry.length();
                assert!((p.geometry.point(l) - q.geometry.point(0.0)).norm() < 1e-15);
                assert!((p.geometry.tangent(l) - q.geometry.tangent(0.0)).norm() < 1e-12);
                let (k0, k1) = (p.geometry.curvature(l), q.geometry.curvature(0.0));
                assert!((k0 - k1).norm() < 1e-6 * pieces[1].geometry.curvature_bounds().0);
                assert!((q.start - (p.start + l)).abs() < 1e-15);
            }
            let arc = &pieces[1].geometry;
            for i in 0..=1000 {
                let s = arc.length() * i as f64 / 1000.0;
                worst = worst.max(dist_to_segment(arc.point(s), a, c).min(dist_to_segment(
                    arc.point(s),
                    c,
                    b,
                )));
                // Finite-difference tangent and curvature.
                let h = arc.length() * 1e-5;
                let fd = (arc.point(s + h) - arc.point(s - h)) / (2.0 * h);
                if s > h && s < arc.length() - h {
                    assert!((fd - arc.tangent(s)).norm() < 1e-5);
                    let fdk = (arc.tangent(s + h) - arc.tangent(s - h)) / (2.0 * h);
                    let kmax = arc.curvature_bounds().0;
                    assert!((fdk - arc.curvature(s)).norm() < 1e-3 * kmax, "{turn} {s}");
                }
            }
            // Off the polygon by at most the tolerance, and the tolerance is used (LinuxCNC's
            // meaning of P), unless half a line is shorter than the blend needs (here at 5°).
            assert!(worst <= tol * (1.0 + 1e-9), "{turn}: {worst} > {tol}");
            let start = pieces[1].geometry.point(0.0);
            let capped = ((start - c).norm() - 0.05).abs() < 1e-12;
            assert!(capped || worst >= 0.9 * tol, "{turn}: {worst} vs {tol}");
        }
    }

    #[test]
    fn tangent_joins_pass_and_arcs_and_reversals_stop() {
        let a = v(0.0, 0.0, 0.0);
        let b = v(0.1, 0.0, 0.0);
        let c = v(0.2, 0.0, 0.0);
        let p = blend(&[line_move(a, b, 1e-3), line_move(b, c, 1e-3)]);
        assert_eq!(p.len(), 2);
        assert!(p.iter().all(|q| !q.stop_after));
        let p = blend(&[line_move(a, b, 1e-3), line_move(b, a, 1e-3)]);
        assert!(p[0].stop_after && p.len() == 2);
        let p = blend(&[line_move(a, b, 0.0), line_move(b, v(0.1, 0.1, 0.0), 0.0)]);
        assert!(p[0].stop_after && p.len() == 2, "zero tolerance stops");
    }

    /// A line into an arc and an arc into an arc (issue 26: these corners stopped): each
    /// corner is rounded by one curvature-continuous piece; position, tangent and curvature
    /// are continuous at every join, and the path stays within the tolerance of the moves.
    #[test]
    fn arc_corners_are_blended_curvature_continuously_within_tolerance() {
        use crate::geometry::segment::{ArcDirection, Plane};
        let tol = 1e-4;
        let a = v(0.0, 0.0, 0.0);
        let b = v(0.05, 0.0, 0.0);
        // An arc of radius 20 mm leaving b at 45° to the line, then an arc turning back.
        let c1 = b + v(-1.0, 1.0, 0.0).normalize() * 0.02;
        let rot = |p: Vector3<f64>, c: Vector3<f64>, ang: f64| {
            let d = p - c;
            c + v(
                d.x * ang.cos() - d.y * ang.sin(),
                d.x * ang.sin() + d.y * ang.cos(),
                0.0,
            )
        };
        let p1 = rot(b, c1, 0.6);
        let arc1 = Segment::arc(b, c1, p1, Plane::XY, ArcDirection::CounterClockwise).unwrap();
        // The second arc turns the other way from p1, with a 30° kink.
        let t1 = arc1.tangent(arc1.length());
        let kink = rot(t1, v(0.0, 0.0, 0.0), -0.5);
        let n = v(kink.y, -kink.x, 0.0); // right of the direction: clockwise centre
        let c2 = p1 + n * 0.015;
        let p2 = rot(p1, c2, -0.8);
        let arc2 = Segment::arc(p1, c2, p2, Plane::XY, ArcDirection::Clockwise).unwrap();
        let moves = [
            RunMove {
                segment: Segment::line(a, b),
                feed: 0.1,
                tolerance: tol,
                line: 1,
            },
            RunMove {
                segment: arc1.clone(),
                feed: 0.1,
                tolerance: tol,
                line: 2,
            },
            RunMove {
                segment: arc2.clone(),
                feed: 0.1,
                tolerance: tol,
                line: 3,
            },
        ];
        let pieces = blend(&moves);
        let curves = pieces
            .iter()
            .filter(|p| matches!(p.geometry, Geometry::Curve(_)))
            .count();
        assert_eq!(curves, 2, "{pieces:?}");
        assert!(pieces
            .iter()
            .all(|p| !p.stop_after || std::ptr::eq(p, pieces.last().unwrap())));
        for w in pieces.windows(2) {
            let (p, q) = (&w[0], &w[1]);
            let l = p.geometry.length();
            assert!((p.geometry.point(l) - q.geometry.point(0.0)).norm() < 1e-12);
            assert!((p.geometry.tangent(l) - q.geometry.tangent(0.0)).norm() < 1e-9);
            let (k0, k1) = (p.geometry.curvature(l), q.geometry.curvature(0.0));
            assert!(
                (k0 - k1).norm() < 1e-6 * k0.norm().max(k1.norm()).max(1.0),
                "{k0} {k1}"
            );
            assert!((q.start - (p.start + l)).abs() < 1e-12);
        }
        let poly: Vec<Vector3<f64>> = moves
            .iter()
            .flat_map(|m| {
                let l = m.segment.length();
                (0..=2000).map(move |i| m.segment.point(l * i as f64 / 2000.0))
            })
            .collect();
        for p in &pieces {
            let l = p.geometry.length();
            for i in 0..=200 {
                let x = p.geometry.point(l * i as f64 / 200.0);
                let d = poly
                    .windows(2)
                    .map(|w| dist_to_segment(x, w[0], w[1]))
                    .fold(f64::INFINITY, f64::min);
                assert!(d <= tol * (1.0 + 1e-6), "{d}");
            }
        }
    }
}
