//! The actuator stage: the commanded torque against the drives' limits.

/// Watches the commanded torques against the drives' rated torques: the
/// largest ratio seen and the samples at a limit. (The plant's drives clamp
/// the torque they apply: [`super::PlantSettings::torque_limits`].)
///
/// Sized at construction; [`Actuator::account`] allocates nothing.
#[derive(Debug, Clone)]
pub struct Actuator {
    tau_max: Vec<f64>,
}

/// What [`Actuator::account`] saw in one commanded torque.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Loading {
    /// `max_i |τ_i| / τ_max,i` over the joints with a finite positive limit
    /// (0 when none has one).
    pub max_ratio: f64,
    /// Some joint is at its limit (ratio ≥ 1 − 10⁻⁹).
    pub saturated: bool,
}

impl Actuator {
    /// Drives with these rated torques (n; a non-finite or non-positive
    /// entry has no limit).
    pub fn new(tau_max: &[f64]) -> Self {
        Self {
            tau_max: tau_max.to_vec(),
        }
    }

    /// The drives of `robot` (their `effort` limits).
    pub fn for_robot(robot: &crate::robot::Robot) -> Self {
        let tau_max: Vec<f64> = robot.joints().iter().map(|j| j.limits.effort).collect();
        Self { tau_max }
    }

    /// How loaded the drives are by the commanded torque `tau` (n).
    pub fn account(&self, tau: &[f64]) -> Loading {
        let mut max_ratio: f64 = 0.0;
        let mut saturated = false;
        for (t, lim) in tau.iter().zip(&self.tau_max) {
            if lim.is_finite() && *lim > 0.0 {
                let r = t.abs() / lim;
                max_ratio = max_ratio.max(r);
                saturated |= r >= 1.0 - 1e-9;
            }
        }
        Loading {
            max_ratio,
            saturated,
        }
    }
}
