//! Inverse kinematics that finds every reachable pose: damped least squares
//! ([`NumericIk`]) from a deterministic set of starts, with a posture objective for
//! redundant arms.
//!
//! A single damped-least-squares run converges to the solution whose basin holds its
//! seed; from a bad seed it stalls on a joint limit or in a local minimum of the pose
//! error. [`RobustIk::solve`] therefore tries, in this order and until one converges:
//!
//! 1. the caller's seed (along a path: the previous sample, so that the path stays on
//!    one branch: continuation);
//! 2. the start pose (the robot's `start_q`);
//! 3. the centre of the joint limits;
//! 4. [`RobustIkSettings::halton_starts`] points of the Halton low-discrepancy sequence
//!    (bases 2, 3, 5, 7, …: J. H. Halton, Numer. Math. 2, 1960) spread over the limits
//!    (an unbounded joint over [−π, π]).
//!
//! The order is fixed, so the result is a function of the inputs alone.
//!
//! Redundant arms (more than six joints): once a start has converged, the self-motion is
//! used to bring the arm towards the start pose: steps `δ = −(I − J⁺J)·k·(q − q_start)`
//! in the null space of the Jacobian (Liégeois 1977; Siciliano et al., *Robotics*,
//! eq. 3.54), each followed by a damped-least-squares polish back onto the pose, accepted
//! only when the distance to the start pose decreases. A fresh solve takes up to
//! [`RobustIkSettings::posture_steps`] such steps; a continuation (the seed, the previous
//! sample, converged) one step of [`RobustIkSettings::continuation_gain`], so that a path
//! moves smoothly and does not drift along the self-motion.

use nalgebra::{DMatrix, Isometry3};

use super::{pose_error, ForwardKinematics, IkError, NumericIk, NumericIkSettings};

/// Settings of [`RobustIk`]; defaults in each field's doc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobustIkSettings {
    /// The damped-least-squares run of each start. Default [`NumericIkSettings::default`].
    pub numeric: NumericIkSettings,
    /// Number of Halton starts after the seed, the start pose and the limits' centre.
    /// Default 96.
    pub halton_starts: usize,
    /// Null-space steps towards the start pose for redundant arms (0: none). Default 20.
    pub posture_steps: usize,
    /// Gain `k` of the null-space step (fraction of the distance per step). Default 0.5.
    pub posture_gain: f64,
    /// Gain of the one null-space step of a continuation (the seed converged: along a
    /// path). Default 0.01.
    pub continuation_gain: f64,
}

impl Default for RobustIkSettings {
    fn default() -> Self {
        Self {
            numeric: NumericIkSettings::default(),
            halton_starts: 96,
            posture_steps: 20,
            posture_gain: 0.5,
            continuation_gain: 0.01,
        }
    }
}

/// What a converged [`RobustIk::solve`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobustIkReport {
    /// Index of the start that converged: 0 the seed, 1 the start pose, 2 the limits'
    /// centre, 3.. the Halton points.
    pub start: usize,
    /// Final position error (m).
    pub position_error: f64,
    /// Final orientation error (rad).
    pub orientation_error: f64,
}

/// Multi-start damped-least-squares IK within joint limits (see the module docs).
/// Buffers are sized in [`RobustIk::new`]; [`RobustIk::solve`] allocates nothing.
#[derive(Debug, Clone)]
pub struct RobustIk {
    n: usize,
    numeric: NumericIk,
    settings: RobustIkSettings,
    lower: Vec<f64>,
    upper: Vec<f64>,
    start_q: Vec<f64>,
    /// Start pose, limits' centre, Halton points: `(2 + halton_starts)·n` values.
    starts: Vec<f64>,
    q: Vec<f64>,
    trial: Vec<f64>,
    best: Vec<f64>,
    jac: DMatrix<f64>,
    jjt: DMatrix<f64>,
    y: Vec<f64>,
}

/// The first `n` primes (the Halton bases).
fn primes(n: usize) -> Vec<u64> {
    let mut p: Vec<u64> = Vec::with_capacity(n);
    let mut c = 2u64;
    while p.len() < n {
        if p.iter().all(|d| !c.is_multiple_of(*d)) {
            p.push(c);
        }
        c += 1;
    }
    p
}

/// The radical inverse of `i` in base `b`: the `i`-th Halton coordinate, in [0, 1).
fn radical_inverse(mut i: u64, b: u64) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= b as f64;
        r += f * (i % b) as f64;
        i /= b;
    }
    r
}

/// A joint's range for spreading starts: the limits, an infinite side at ±π.
fn spread_range(lo: f64, hi: f64) -> (f64, f64) {
    let l = if lo.is_finite() {
        lo
    } else {
        -std::f64::consts::PI
    };
    let h = if hi.is_finite() {
        hi
    } else {
        std::f64::consts::PI
    };
    if l <= h {
        (l, h)
    } else {
        (lo.max(-1e6), hi.min(1e6))
    }
}

impl RobustIk {
    /// IK for `n` joints within `lower`/`upper` (rad or m; ±∞ for an unbounded side),
    /// with `start_q` the start pose (the second start and the posture of redundant
    /// arms). Errors as [`NumericIk::new`], and for a `start_q` of another length or not
    /// finite.
    pub fn new(
        n: usize,
        lower: &[f64],
        upper: &[f64],
        start_q: &[f64],
        settings: RobustIkSettings,
    ) -> Result<Self, IkError> {
        let numeric = NumericIk::new(n, lower, upper, settings.numeric)?;
        if start_q.len() != n {
            return Err(IkError::DimensionMismatch {
                what: "start pose",
                expected: n,
                got: start_q.len(),
            });
        }
        if !start_q.iter().all(|x| x.is_finite()) {
            return Err(IkError::NonFinite { what: "start pose" });
        }
        for (name, value) in [
            ("posture_gain", settings.posture_gain),
            ("continuation_gain", settings.continuation_gain),
        ] {
            if !(value.is_finite() && value > 0.0 && value <= 1.0) {
                return Err(IkError::InvalidParameter {
                    name,
                    value,
                    requirement: "must be in (0, 1]",
                });
            }
        }
        let m = 2 + settings.halton_starts;
        let mut starts = Vec::with_capacity(m * n);
        starts.extend(
            start_q
                .iter()
                .zip(lower.iter().zip(upper))
                .map(|(&s, (&l, &h))| s.clamp(l, h)),
        );
        starts.extend(lower.iter().zip(upper).map(|(&l, &h)| {
            let (a, b) = spread_range(l, h);
            0.5 * (a + b)
        }));
        let bases = primes(n);
        for k in 0..settings.halton_starts {
            for i in 0..n {
                let (a, b) = spread_range(lower[i], upper[i]);
                // Index k + 1: the sequence's first point (all zeros) is a corner.
                starts.push(a + (b - a) * radical_inverse(k as u64 + 1, bases[i]));
            }
        }
        Ok(Self {
            n,
            numeric,
            settings,
            lower: lower.to_vec(),
            upper: upper.to_vec(),
            start_q: start_q.to_vec(),
            starts,
            q: vec![0.0; n],
            trial: vec![0.0; n],
            best: vec![0.0; n],
            jac: DMatrix::zeros(6, n),
            jjt: DMatrix::zeros(6, 6),
            y: vec![0.0; 6],
        })
    }

    /// The settings in use.
    pub fn settings(&self) -> &RobustIkSettings {
        &self.settings
    }

    /// The start pose.
    pub fn start_q(&self) -> &[f64] {
        &self.start_q
    }

    /// Solves `target` for `q`: in, the seed (e.g. the previous sample along a path, or
    /// the start pose); out, the solution. The seed is tried first, then the start pose,
    /// the limits' centre and the Halton points (module docs); the first that converges
    /// wins. On a redundant arm the solution is then moved towards the start pose along
    /// the self-motion.
    ///
    /// Errors: [`IkError::DimensionMismatch`], [`IkError::NonFinite`] as
    /// [`NumericIk::solve`] (`q` unchanged); [`IkError::NoSolution`] when no start
    /// converges (`q` then holds the best iterate; the error names a joint at its limit
    /// there, if any).
    pub fn solve<F: ForwardKinematics + ?Sized>(
        &mut self,
        fk: &mut F,
        target: &Isometry3<f64>,
        q: &mut [f64],
    ) -> Result<RobustIkReport, IkError> {
        let n = self.n;
        let starts = 1 + self.starts.len() / n;
        let mut best_cost = f64::INFINITY;
        let mut best_err = (f64::INFINITY, f64::INFINITY);
        for s in 0..starts {
            if s == 0 {
                self.q.copy_from_slice(q);
            } else {
                self.q.copy_from_slice(&self.starts[(s - 1) * n..s * n]);
            }
            let result = self.numeric.solve(fk, target, &mut self.q);
            match result {
                Ok(r) => {
                    let mut report = RobustIkReport {
                        start: s,
                        position_error: r.position_error,
                        orientation_error: r.orientation_error,
                    };
                    if n > 6 {
                        // A fresh solve goes to the posture optimum; a continuation (the
                        // seed converged) takes one small step towards it, so that a path
                        // moves smoothly along the self-motion.
                        let (steps, gain) = if s == 0 {
                            (
                                self.settings.posture_steps.min(1),
                                self.settings.continuation_gain,
                            )
                        } else {
                            (self.settings.posture_steps, self.settings.posture_gain)
                        };
                        self.posture(fk, target, &mut report, steps, gain)?;
                    }
                    q.copy_from_slice(&self.q);
                    return Ok(report);
                }
                Err(IkError::NotConverged {
                    position_error,
                    orientation_error,
                    ..
                }) => {
                    let cost = position_error.powi(2) + orientation_error.powi(2);
                    if cost < best_cost {
                        best_cost = cost;
                        best_err = (position_error, orientation_error);
                        self.best.copy_from_slice(&self.q);
                    }
                }
                Err(e) => return Err(e),
            }
        }
        q.copy_from_slice(&self.best);
        Err(self.no_solution(starts, best_err))
    }

    /// The error when no start converged: the best iterate's remaining error and the
    /// joint of it that sits on a limit (the most likely obstacle), if any.
    fn no_solution(&self, starts: usize, (pe, oe): (f64, f64)) -> IkError {
        let at_limit = (0..self.n).find_map(|i| {
            let v = self.best[i];
            let (l, u) = (self.lower[i], self.upper[i]);
            let tol = 1e-9 * (1.0 + v.abs());
            ((v - l).abs() <= tol || (u - v).abs() <= tol).then_some(IkLimitHit {
                joint: i + 1,
                value: v,
                lower: l,
                upper: u,
            })
        });
        IkError::NoSolution {
            starts,
            position_error: pe,
            orientation_error: oe,
            at_limit,
        }
    }

    /// One step of the posture pull in `self.trial`: `q + δ` clamped into the limits, with
    /// `z = −k (q − q_start)` and `δ = z − Jᵀ (J Jᵀ + μI)⁻¹ J z` (`self.jac` holds `J`);
    /// `false` when `J Jᵀ + μI` cannot be factored.
    fn null_space_trial(&mut self, k: f64) -> bool {
        let n = self.n;
        // z = −k (q − q_start); δ = z − Jᵀ (J Jᵀ + μI)⁻¹ J z: the null-space projection.
        for i in 0..n {
            self.trial[i] = -k * (self.q[i] - self.start_q[i]);
        }
        for r in 0..6 {
            for c in 0..6 {
                self.jjt[(r, c)] = (0..n).map(|i| self.jac[(r, i)] * self.jac[(c, i)]).sum();
            }
        }
        // Tikhonov μ: the projection stays bounded near singularities.
        let mu = 1e-12 * (1.0 + self.jjt.trace());
        for r in 0..6 {
            self.jjt[(r, r)] += mu;
            self.y[r] = (0..n).map(|c| self.jac[(r, c)] * self.trial[c]).sum();
        }
        if crate::linalg::cholesky_in_place(6, 6, self.jjt.as_mut_slice()).is_err() {
            return false;
        }
        crate::linalg::cholesky_solve_in_place(6, 6, self.jjt.as_slice(), &mut self.y);
        for c in 0..n {
            let back: f64 = (0..6).map(|r| self.jac[(r, c)] * self.y[r]).sum();
            self.trial[c] = (self.q[c] + self.trial[c] - back).clamp(self.lower[c], self.upper[c]);
        }
        true
    }

    /// Null-space steps towards the start pose (module docs), each polished back onto the
    /// pose and kept only if it converged nearer to the start pose. `self.q` holds a
    /// converged solution on entry and on exit.
    fn posture<F: ForwardKinematics + ?Sized>(
        &mut self,
        fk: &mut F,
        target: &Isometry3<f64>,
        report: &mut RobustIkReport,
        steps: usize,
        k: f64,
    ) -> Result<(), IkError> {
        let dist =
            |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum() };
        let mut d = dist(&self.q, &self.start_q);
        for _ in 0..steps {
            if d <= 1e-24 {
                break;
            }
            fk.flange_jacobian(&self.q, &mut self.jac);
            if !self.null_space_trial(k) {
                break;
            }
            let mut cand = std::mem::take(&mut self.trial);
            let polished = self.numeric.solve(fk, target, &mut cand);
            let nd = dist(&cand, &self.start_q);
            match polished {
                Ok(r) if nd < d * (1.0 - 1e-6) => {
                    self.q.copy_from_slice(&cand);
                    d = nd;
                    report.position_error = r.position_error;
                    report.orientation_error = r.orientation_error;
                    self.trial = cand;
                }
                _ => {
                    self.trial = cand;
                    break;
                }
            }
        }
        let (ep, er) = pose_error(target, &fk.flange_pose(&self.q));
        report.position_error = ep.norm();
        report.orientation_error = er.norm();
        Ok(())
    }
}

/// A joint found at its limit (1-based joint number, value, range).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkLimitHit {
    /// Joint number, 1-based.
    pub joint: usize,
    /// Its value (rad or m).
    pub value: f64,
    /// Lower limit.
    pub lower: f64,
    /// Upper limit.
    pub upper: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halton_points_are_the_radical_inverses() {
        assert_eq!(primes(5), vec![2, 3, 5, 7, 11]);
        assert_eq!(radical_inverse(1, 2), 0.5);
        assert_eq!(radical_inverse(3, 2), 0.75);
        assert!((radical_inverse(5, 3) - (2.0 / 3.0 + 1.0 / 9.0)).abs() < 1e-15);
    }
}
