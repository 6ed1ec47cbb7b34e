//! Joint limits of exact-stop (`G61`) moves: the move's rest-to-rest law is slowed down
//! uniformly until no joint exceeds its speed or acceleration limit.
//!
//! Along a law `s(t) = L σ(t/T)` (see [`TimeLaw`]) and a joint path `q(s)`
//! (inverse kinematics), the chain rule gives
//!
//! `q̇_j = q'_j(s) L σ'(τ) / T`, `q̈_j = (q'_j(s) L σ''(τ) + q''_j(s) L² σ'(τ)²) / T²`,
//!
//! so the joint speeds scale with `1/T` and the joint accelerations with `1/T²`. The shortest
//! duration that keeps joint `j` within its speed limit `v_j` and acceleration limit `A_j` is
//! therefore `T_v = max_τ |q'_j L σ'| / v_j` and `T_a = √(max_τ |q'_j L σ'' + q''_j L² σ'²| / A_j)`
//! (time scaling, e.g. Hollerbach 1984, "Dynamic scaling of manipulator trajectories").
//! A move whose fastest law already keeps the limits is left exactly as it is.

use super::timelaw::{ProfileValue, TimeLaw};
use super::topp::JointConstraints;
use crate::geometry::Segment;
use crate::motion::limits::JointQuantity;

/// Samples of `τ` per move at which the joint speed and acceleration are evaluated.
const TAU_SAMPLES: usize = 512;

/// Largest joint step (rad) between neighbouring fine points ([`fine_peaks`]) that is still
/// one branch of the inverse kinematics; a larger one is a configuration jump, left to the
/// reference's check.
const BRANCH_JUMP: f64 = 0.5;

/// A `G61` move slowed down by a joint limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointLimitedMove {
    /// Program line of the move.
    pub line: usize,
    /// The limiting joint, 1-based.
    pub joint: usize,
    /// Which of its limits.
    pub quantity: JointQuantity,
    /// The move's duration over its fastest duration under the path limits (> 1).
    pub factor: f64,
}

impl std::fmt::Display for JointLimitedMove {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the exact-stop move on program line {} is slowed down {:.3}× to keep joint {}'s {} limit",
            self.line, self.factor, self.joint, self.quantity
        )
    }
}

/// Joint positions at `m + 1` equally spaced points of `segment`, row-major; `None` if the
/// inverse kinematics fails (the reference builder reports it). A large step between two
/// points (a joint turning fast near a singularity, or a jump of branch) is resolved by
/// [`fine_peaks`].
fn joint_grid(segment: &Segment, m: usize, jc: &mut JointConstraints<'_>) -> Option<Vec<f64>> {
    let nj = jc.velocity.len();
    let len = segment.length();
    let mut q: Vec<f64> = Vec::with_capacity((m + 1) * nj);
    for i in 0..=m {
        let sol = jc
            .map
            .solve(&segment.point(len * i as f64 / m as f64))
            .ok()?;
        q.extend_from_slice(sol);
    }
    Some(q)
}

/// `q'` and `q''` at the grid points (spacing `h`): central differences inside, second-order
/// one-sided ones at the ends.
fn derivatives(q: &[f64], m: usize, nj: usize, h: f64) -> (Vec<f64>, Vec<f64>) {
    let at = |i: usize, j: usize| q[i * nj + j];
    let mut d1 = vec![0.0; (m + 1) * nj];
    let mut d2 = vec![0.0; (m + 1) * nj];
    for i in 0..=m {
        let c = i.clamp(1, m - 1);
        for j in 0..nj {
            let (y0, y1, y2) = (at(c - 1, j), at(c, j), at(c + 1, j));
            let second = (y0 - 2.0 * y1 + y2) / (h * h);
            let first = (y2 - y0) / (2.0 * h) + second * (i as f64 - c as f64) * h;
            d1[i * nj + j] = first;
            d2[i * nj + j] = second;
        }
    }
    (d1, d2)
}

/// A joint step (rad) between neighbouring grid points above which the interval is sampled
/// again finely ([`fine_peaks`]): near a singularity a joint turns within a fraction of the
/// grid spacing, and the grid's differences miss its peak speed.
const STEEP_STEP: f64 = 0.01;

/// Largest joint step (rad) between the fine points of a steep interval.
const FINE_STEP: f64 = 1e-3;

/// The grid intervals (`i` from point `i` to `i + 1`) in which a joint steps by more than
/// [`STEEP_STEP`].
fn steep_intervals(q: &[f64], m: usize, nj: usize) -> impl Iterator<Item = usize> + '_ {
    (0..m)
        .filter(move |&i| (0..nj).any(|j| (q[(i + 1) * nj + j] - q[i * nj + j]).abs() > STEEP_STEP))
}

/// `τ ∈ [0, 1]` at which the normalized law reaches `x ∈ [0, 1]` of the length (bisection:
/// `σ` increases).
fn tau_at(law: &TimeLaw, x: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..48 {
        let mid = 0.5 * (lo + hi);
        if law.profile.eval(mid).s < x {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The durations the speed and acceleration limits need on grid interval `i` of `segment`,
/// with the joint path sampled finely there (joint steps of at most [`FINE_STEP`], central
/// differences) and the law evaluated where it passes each fine point; `None` if the inverse
/// kinematics fails or jumps branch.
fn fine_peaks(
    segment: &Segment,
    law: &TimeLaw,
    q: &[f64],
    i: usize,
    m: usize,
    jc: &mut JointConstraints<'_>,
) -> Option<Peaks> {
    let nj = jc.velocity.len();
    let len = segment.length();
    let step = (0..nj)
        .map(|j| (q[(i + 1) * nj + j] - q[i * nj + j]).abs())
        .fold(0.0, f64::max);
    let k = ((step / FINE_STEP).ceil() as usize).clamp(2, 1024);
    let h = len / (m * k) as f64;
    let s0 = len * i as f64 / m as f64;
    // Points s0 + l h for l = −1 ..= k + 1, solved from grid point i along the path.
    jc.map.set_state(&q[i * nj..(i + 1) * nj]);
    let mut fine: Vec<f64> = Vec::with_capacity((k + 3) * nj);
    for l in -1..=(k as i64 + 1) {
        let s = (s0 + l as f64 * h).clamp(0.0, len);
        let sol = jc.map.solve(&segment.point(s)).ok()?;
        if let Some(last) = fine.len().checked_sub(nj).map(|a| &fine[a..]) {
            if (0..nj).any(|j| (sol[j] - last[j]).abs() > BRANCH_JUMP) {
                return None;
            }
        }
        fine.extend_from_slice(sol);
    }
    let mut peaks = Peaks::default();
    for l in 1..=k + 1 {
        let s = s0 + (l as f64 - 1.0) * h;
        if !(0.0..=len).contains(&s) || l == 1 && i == 0 || l == k + 1 && i + 1 == m {
            continue; // the ends of the segment: the grid's one-sided differences cover them
        }
        let p = law.profile.eval(tau_at(law, s / len));
        for j in 0..nj {
            let (y0, y1, y2) = (
                fine[(l - 1) * nj + j],
                fine[l * nj + j],
                fine[(l + 1) * nj + j],
            );
            let dq = (y2 - y0) / (2.0 * h);
            let ddq = (y0 - 2.0 * y1 + y2) / (h * h);
            peaks.add(j, dq, ddq, &p, len, jc);
        }
    }
    Some(peaks)
}

/// The largest durations the joints' speed and acceleration limits need, with the joint
/// (0-based) that needs each.
#[derive(Debug, Clone, Copy, Default)]
struct Peaks {
    speed: (f64, usize),
    accel: (f64, usize),
}

impl Peaks {
    /// Joint `j` with `q' = dq`, `q'' = ddq` (per metre of path) where the law is at `p` on a
    /// move of length `len`: `T_v = |q' L σ'| / v`, `T_a = √(|q' L σ'' + q'' L² σ'²| / A)`.
    fn add(
        &mut self,
        j: usize,
        dq: f64,
        ddq: f64,
        p: &ProfileValue,
        len: f64,
        jc: &JointConstraints<'_>,
    ) {
        let tv = (dq * len * p.ds).abs() / jc.velocity[j];
        let ta =
            ((dq * len * p.dds + ddq * len * len * p.ds * p.ds).abs() / jc.acceleration[j]).sqrt();
        if tv > self.speed.0 {
            self.speed = (tv, j);
        }
        if ta > self.accel.0 {
            self.accel = (ta, j);
        }
    }

    /// The larger of each.
    fn merge(&mut self, other: Peaks) {
        if other.speed.0 > self.speed.0 {
            self.speed = other.speed;
        }
        if other.accel.0 > self.accel.0 {
            self.accel = other.accel;
        }
    }
}

/// The duration of `law` on `segment` stretched so that every joint keeps its speed and
/// acceleration limit (see the module documentation), and the limit that binds; `None` when
/// the law already keeps them (or the joint path cannot be evaluated).
pub(crate) fn joint_limited_duration(
    segment: &Segment,
    law: &TimeLaw,
    jc: &mut JointConstraints<'_>,
) -> Option<(f64, usize, JointQuantity)> {
    let len = segment.length();
    if !(len > 0.0 && law.duration > 0.0) {
        return None;
    }
    let nj = jc.velocity.len();
    let m = ((len / 5e-4).ceil() as usize).clamp(32, 512);
    let q = joint_grid(segment, m, jc)?;
    let (d1, d2) = derivatives(&q, m, nj, len / m as f64);
    let mut peaks = Peaks::default();
    for k in 0..=TAU_SAMPLES {
        let p = law.profile.eval(k as f64 / TAU_SAMPLES as f64);
        let x = (p.s * m as f64).clamp(0.0, m as f64);
        let i = (x.floor() as usize).min(m - 1);
        let w = x - i as f64;
        for j in 0..nj {
            let lerp = |d: &[f64]| d[i * nj + j] * (1.0 - w) + d[(i + 1) * nj + j] * w;
            peaks.add(j, lerp(&d1), lerp(&d2), &p, len, jc);
        }
    }
    let fine: Option<Vec<Peaks>> = steep_intervals(&q, m, nj)
        .map(|i| fine_peaks(segment, law, &q, i, m, jc))
        .collect();
    // The next move is solved from this one's end.
    jc.map.set_state(&q[m * nj..]);
    for f in fine? {
        peaks.merge(f);
    }
    let (t_v, t_a) = (peaks.speed, peaks.accel);
    let (t, j, quantity) = if t_v.0 >= t_a.0 {
        (t_v.0, t_v.1, JointQuantity::Speed)
    } else {
        (t_a.0, t_a.1, JointQuantity::Acceleration)
    };
    (t.is_finite() && t > law.duration).then_some((t, j + 1, quantity))
}
