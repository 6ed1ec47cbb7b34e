//! The solutions of one pose by a closed form, one type for every closed form
//! ([`super::OpwSolutions`], [`super::UrSolutions`], [`super::ClosedFormBranches`]).

use nalgebra::Vector3;

/// All closed-form solutions of one pose: up to 8 joint vectors and the distance by which
/// the pose misses the workspace, plus what a closed form tells besides (`X`: the OPW
/// form's wrist centre, [`Solutions::wrist_centre`]; nothing for the others). No
/// allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solutions<X = ()> {
    pub(super) solutions: [[f64; 6]; 8],
    pub(super) count: usize,
    pub(super) reach_excess: f64,
    pub(super) extra: X,
}

impl<X> Solutions<X> {
    /// No solution yet, the pose out of reach by +∞, with `extra`.
    pub(super) fn empty(extra: X) -> Self {
        Self {
            solutions: [[0.0; 6]; 8],
            count: 0,
            reach_excess: f64::INFINITY,
            extra,
        }
    }

    /// Adds `q` (ignored past the 8th).
    pub(super) fn push(&mut self, q: [f64; 6]) {
        if let Some(slot) = self.solutions.get_mut(self.count) {
            *slot = q;
            self.count += 1;
        }
    }

    /// The solutions (0 to 8), in user joint coordinates (each joint wrapped to
    /// (−π, π] unless the closed form took it from a hint).
    pub fn as_slice(&self) -> &[[f64; 6]] {
        &self.solutions[..self.count]
    }

    /// Number of solutions.
    pub fn len(&self) -> usize {
        self.count
    }

    /// True when the pose is out of reach (or not finite).
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Distance (m) by which the pose misses the workspace: 0 when solutions exist, +∞
    /// for a non-finite pose.
    pub fn reach_excess(&self) -> f64 {
        self.reach_excess
    }
}

impl Solutions {
    /// The first 8 of `solutions` and the reach excess (m; 0 when there are solutions).
    pub fn new(solutions: &[[f64; 6]], reach_excess: f64) -> Self {
        let mut out = Self::empty(());
        out.count = solutions.len().min(8);
        out.solutions[..out.count].copy_from_slice(&solutions[..out.count]);
        out.reach_excess = reach_excess;
        out
    }
}

impl Solutions<Vector3<f64>> {
    /// Wrist centre (m, base frame) of the requested pose (the OPW form).
    pub fn wrist_centre(&self) -> Vector3<f64> {
        self.extra
    }
}
