//! Choice among the analytic solutions: closest to the previous sample, inside the
//! joint limits, continuous through singularities. One solver, [`ClosedFormSolver`], over
//! any closed form ([`ClosedFormKinematics`]): [`IkSolver`] for OPW arms and
//! [`super::UrSolver`] for the UR family.

use std::f64::consts::PI;

use nalgebra::Isometry3;

use super::opw::OpwParameters;
use super::solutions::Solutions;
use super::{pose_is_finite, IkError};

/// Joint values may exceed a limit by this much (rad) and still count as inside:
/// rounding in the inverse must not reject a target that sits exactly on a limit.
/// The value is returned as computed, not clamped.
pub const LIMIT_TOLERANCE: f64 = 1e-9;

const TWO_PI: f64 = 2.0 * PI;

/// What [`ClosedFormSolver`] needs of a closed-form kinematics: every branch of a pose,
/// with the joints the pose leaves free (at a singularity) taken from a hint. Implemented
/// by [`OpwParameters`] (OPW arms) and [`super::UrKinematics`] (the UR family, in ur.rs).
pub trait ClosedFormKinematics {
    /// Checks the kinematics' constants ([`ClosedFormSolver::new`] calls it).
    fn validate(&self) -> Result<(), IkError> {
        Ok(())
    }

    /// All branches of `pose` (up to 8, each joint wrapped to (−π, π] unless taken from
    /// the finite `hint`), and the distance (m) by which the pose misses the workspace
    /// when there is none. Allocation-free.
    fn branches(&self, pose: &Isometry3<f64>, hint: &[f64; 6]) -> ClosedFormBranches;
}

/// The branches of one pose ([`ClosedFormKinematics::branches`]): up to 8 joint vectors
/// and the reach excess, no allocation ([`Solutions::new`]).
pub type ClosedFormBranches = Solutions;

impl ClosedFormKinematics for OpwParameters {
    fn validate(&self) -> Result<(), IkError> {
        OpwParameters::validate(self)
    }

    fn branches(&self, pose: &Isometry3<f64>, hint: &[f64; 6]) -> ClosedFormBranches {
        let s = self.inverse_near(pose, hint);
        ClosedFormBranches::new(s.as_slice(), s.reach_excess())
    }
}

/// Sequential inverse kinematics of an arm with a closed form ([`ClosedFormKinematics`]):
/// for each pose, the solution with the smallest weighted joint distance
/// `Σ w_i (q_i − q_prev,i)²` to the previous sample among all closed-form branches and
/// all their 2π-equivalents that respect the joint limits (joints 4 and 6 of the IRB 140
/// travel ±200° and ±400°, so the equivalent matters).
///
/// Singularities: the kinematics keep the joints a pose leaves free at the hint, the
/// previous sample. For OPW arms ([`IkSolver`]): inside the wrist singularity band
/// (`|sin q5| ≤` [`super::opw::WRIST_SINGULAR_SIN`]) only q4 + q6 is determined by the
/// pose; q4 stays at its previous value and the rest goes into q6, as long as that costs
/// at most [`super::opw::SINGULAR_ORIENTATION_TOLERANCE`] rad of orientation. The
/// shoulder singularity (wrist centre on axis 1) keeps q1 likewise. See
/// [`OpwParameters::inverse_near`] and [`super::UrKinematics::inverse_near`].
///
/// Allocation-free; [`ClosedFormSolver::solve`] may be called per control step.
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedFormSolver<K> {
    kin: K,
    lower: [f64; 6],
    upper: [f64; 6],
    weights: [f64; 6],
    previous: [f64; 6],
}

/// The closed-form solver of OPW arms (ortho-parallel, spherical wrist).
pub type IkSolver = ClosedFormSolver<OpwParameters>;

/// Nearest 2π-equivalent of `value` to `reference` inside `[lower, upper]` (with
/// [`LIMIT_TOLERANCE`]); `Err((v, violation))` with the least-violating equivalent if
/// none lies inside.
fn nearest_equivalent(
    value: f64,
    reference: f64,
    lower: f64,
    upper: f64,
) -> Result<f64, (f64, f64)> {
    let lo = lower - LIMIT_TOLERANCE;
    let hi = upper + LIMIT_TOLERANCE;
    let k_lo = ((lo - value) / TWO_PI).ceil();
    let k_hi = ((hi - value) / TWO_PI).floor();
    if k_lo <= k_hi {
        let k = ((reference - value) / TWO_PI).round().clamp(k_lo, k_hi);
        Ok(value + TWO_PI * k)
    } else {
        // value + 2π·k_lo lies above the range, value + 2π·(k_lo − 1) below it.
        let above = value + TWO_PI * k_lo;
        let below = above - TWO_PI;
        let (va, vb) = (above - upper, lower - below);
        Err(if va <= vb { (above, va) } else { (below, vb) })
    }
}

impl<K: ClosedFormKinematics> ClosedFormSolver<K> {
    /// Solver with joint limits `lower`/`upper` (rad, finite), unit weights, and previous
    /// sample q = 0 (the calibration position) until [`ClosedFormSolver::set_previous`]
    /// is called. Errors: the kinematics' own check, [`IkError::InvalidLimits`].
    pub fn new(kin: K, lower: [f64; 6], upper: [f64; 6]) -> Result<Self, IkError> {
        kin.validate()?;
        for (i, (&l, &u)) in lower.iter().zip(&upper).enumerate() {
            if !(l.is_finite() && u.is_finite() && l <= u) {
                return Err(IkError::InvalidLimits {
                    joint: i + 1,
                    lower: l,
                    upper: u,
                });
            }
        }
        Ok(Self {
            kin,
            lower,
            upper,
            weights: [1.0; 6],
            previous: [0.0; 6],
        })
    }

    /// Sets the joint weights of the distance (all must be finite and > 0).
    pub fn with_weights(mut self, weights: [f64; 6]) -> Result<Self, IkError> {
        if let Some(&w) = weights.iter().find(|w| !(w.is_finite() && **w > 0.0)) {
            return Err(IkError::InvalidParameter {
                name: "weights",
                value: w,
                requirement: "every joint weight must be finite and positive",
            });
        }
        self.weights = weights;
        Ok(self)
    }

    /// The kinematics.
    pub fn kinematics(&self) -> &K {
        &self.kin
    }

    /// Lower joint limits (rad).
    pub fn lower(&self) -> &[f64; 6] {
        &self.lower
    }

    /// Upper joint limits (rad).
    pub fn upper(&self) -> &[f64; 6] {
        &self.upper
    }

    /// The previous sample that the next [`ClosedFormSolver::solve`] stays close to.
    pub fn previous(&self) -> &[f64; 6] {
        &self.previous
    }

    /// Sets the previous sample (e.g. the robot's measured start position).
    pub fn set_previous(&mut self, q: &[f64; 6]) -> Result<(), IkError> {
        if !q.iter().all(|x| x.is_finite()) {
            return Err(IkError::NonFinite {
                what: "previous joint position",
            });
        }
        self.previous = *q;
        Ok(())
    }

    /// Solves `pose` near the stored previous sample and, on success, stores the
    /// result as the new previous sample (on error it is left unchanged).
    pub fn solve(&mut self, pose: &Isometry3<f64>) -> Result<[f64; 6], IkError> {
        let q = self.solve_near(pose, &self.previous)?;
        self.previous = q;
        Ok(q)
    }

    /// Solution of `pose` (the kinematics' end frame in the base frame) closest to
    /// `previous` within the joint limits. Errors: [`IkError::NonFinite`] for NaN/∞
    /// input, [`IkError::Unreachable`] when no configuration reaches the pose,
    /// [`IkError::JointLimit`] (the least-violating configuration, summed violation)
    /// when all of them leave the limits.
    pub fn solve_near(
        &self,
        pose: &Isometry3<f64>,
        previous: &[f64; 6],
    ) -> Result<[f64; 6], IkError> {
        check_inputs(pose, previous)?;
        let sols = self.kin.branches(pose, previous);
        choose_branch(
            sols.as_slice(),
            sols.reach_excess(),
            pose,
            previous,
            (&self.lower, &self.upper),
            &self.weights,
        )
    }
}

impl ClosedFormSolver<OpwParameters> {
    /// ABB IRB 140 with the data-sheet joint limits of the project URDF
    /// (±180°, −90…110°, −230…50°, ±200°, ±115°, ±400°).
    pub fn irb140() -> Self {
        let d = |x: f64| x.to_radians();
        Self {
            kin: OpwParameters::irb140(),
            lower: [
                d(-180.0),
                d(-90.0),
                d(-230.0),
                d(-200.0),
                d(-115.0),
                d(-400.0),
            ],
            upper: [d(180.0), d(110.0), d(50.0), d(200.0), d(115.0), d(400.0)],
            weights: [1.0; 6],
            previous: [0.0; 6],
        }
    }

    /// The kinematic parameters.
    pub fn parameters(&self) -> &OpwParameters {
        &self.kin
    }
}

/// The inputs of a closed-form solver's `solve_near`: a finite target pose and previous
/// sample, else [`IkError::NonFinite`] naming which.
pub(crate) fn check_inputs(pose: &Isometry3<f64>, previous: &[f64; 6]) -> Result<(), IkError> {
    if !pose_is_finite(pose) {
        return Err(IkError::NonFinite {
            what: "target pose",
        });
    }
    if !previous.iter().all(|x| x.is_finite()) {
        return Err(IkError::NonFinite {
            what: "previous joint position",
        });
    }
    Ok(())
}

/// A closed-form solver's answer among its branches `sols` ([`nearest_within_limits`]):
/// the one nearest `previous` within the limits; else [`IkError::JointLimit`] for the
/// least-violating one, or [`IkError::Unreachable`] with the reach `excess` (m) when there
/// is no branch. Shared by the OPW and the UR solvers.
pub(crate) fn choose_branch(
    sols: &[[f64; 6]],
    excess: f64,
    pose: &Isometry3<f64>,
    previous: &[f64; 6],
    (lower, upper): (&[f64; 6], &[f64; 6]),
    weights: &[f64; 6],
) -> Result<[f64; 6], IkError> {
    match nearest_within_limits(sols, previous, lower, upper, weights) {
        LimitChoice::Inside(q) => Ok(q),
        LimitChoice::Outside { joint, value } => Err(IkError::JointLimit {
            joint: joint + 1,
            value,
            lower: lower[joint],
            upper: upper[joint],
        }),
        LimitChoice::None => {
            let p = pose.translation.vector;
            Err(IkError::Unreachable {
                position: [p.x, p.y, p.z],
                excess,
            })
        }
    }
}

/// What [`nearest_within_limits`] found.
pub(crate) enum LimitChoice {
    /// The nearest solution inside the limits.
    Inside([f64; 6]),
    /// Every solution leaves the limits: the least-violating one's worst joint (0-based)
    /// and the value it would need.
    Outside { joint: usize, value: f64 },
    /// No solution at all.
    None,
}

/// Among `sols` and their 2π-equivalents inside `[lower, upper]`, the one with the smallest
/// weighted distance `Σ wᵢ (qᵢ − previousᵢ)²` to `previous`.
pub(crate) fn nearest_within_limits(
    sols: &[[f64; 6]],
    previous: &[f64; 6],
    lower: &[f64; 6],
    upper: &[f64; 6],
    weights: &[f64; 6],
) -> LimitChoice {
    let mut best: Option<(f64, [f64; 6])> = None;
    // (summed violation, joint index, value) of the least-violating solution.
    let mut least: Option<(f64, usize, f64)> = None;
    for sol in sols {
        let mut cand = [0.0; 6];
        let mut cost = 0.0;
        let mut violation = 0.0;
        let mut worst: (f64, usize, f64) = (-1.0, 0, 0.0);
        for i in 0..6 {
            match nearest_equivalent(sol[i], previous[i], lower[i], upper[i]) {
                Ok(v) => {
                    cand[i] = v;
                    cost += weights[i] * (v - previous[i]).powi(2);
                }
                Err((v, viol)) => {
                    violation += viol;
                    if viol > worst.0 {
                        worst = (viol, i, v);
                    }
                }
            }
        }
        if violation == 0.0 {
            if !matches!(best, Some((c, _)) if c <= cost) {
                best = Some((cost, cand));
            }
        } else if !matches!(least, Some((v, _, _)) if v <= violation) {
            least = Some((violation, worst.1, worst.2));
        }
    }
    match (best, least) {
        (Some((_, q)), _) => LimitChoice::Inside(q),
        (None, Some((_, joint, value))) => LimitChoice::Outside { joint, value },
        (None, None) => LimitChoice::None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_equivalent_picks_closest_inside_limits() {
        let (l, u) = (-400f64.to_radians(), 400f64.to_radians());
        // 0.1 near reference 6.3 → 0.1 + 2π.
        let v = nearest_equivalent(0.1, 6.3, l, u).unwrap();
        assert!((v - (0.1 + TWO_PI)).abs() < 1e-15);
        // Reference far beyond the range: clamp to the largest equivalent in range.
        let v = nearest_equivalent(0.1, 100.0, l, u).unwrap();
        assert!((v - (0.1 + TWO_PI)).abs() < 1e-15);
        // Brute force over k.
        for &(x, r) in &[(3.0, -3.0), (-3.1, 3.0), (1.0, 1.0), (-0.5, -6.0)] {
            let v = nearest_equivalent(x, r, l, u).unwrap();
            let brute = (-3..=3)
                .map(|k| x + TWO_PI * f64::from(k))
                .filter(|y| *y >= l && *y <= u)
                .min_by(|a, b| (a - r).abs().total_cmp(&(b - r).abs()))
                .unwrap();
            assert_eq!(v, brute);
        }
    }

    #[test]
    fn nearest_equivalent_reports_least_violation() {
        // Range [-1, 1]: 2.0 violates by 1.0, its equivalent 2 − 2π by 3.28.
        let (v, viol) = nearest_equivalent(2.0, 0.0, -1.0, 1.0).unwrap_err();
        assert_eq!((v, viol), (2.0, 1.0));
        let (v, viol) = nearest_equivalent(-2.5, 0.0, -1.0, 1.0).unwrap_err();
        assert_eq!((v, viol), (-2.5, 1.5));
        // Exactly on the limit (plus rounding) is inside.
        assert!(nearest_equivalent(1.0 + 1e-12, 0.0, -1.0, 1.0).is_ok());
    }

    #[test]
    fn new_rejects_inverted_limits_and_bad_weights() {
        let p = OpwParameters::irb140();
        let mut lo = [-1.0; 6];
        let hi = [1.0; 6];
        lo[4] = 2.0;
        assert!(matches!(
            IkSolver::new(p, lo, hi),
            Err(IkError::InvalidLimits { joint: 5, .. })
        ));
        let s = IkSolver::new(p, [-1.0; 6], hi).unwrap();
        assert!(matches!(
            s.with_weights([1.0, 1.0, 0.0, 1.0, 1.0, 1.0]),
            Err(IkError::InvalidParameter {
                name: "weights",
                ..
            })
        ));
    }
}
