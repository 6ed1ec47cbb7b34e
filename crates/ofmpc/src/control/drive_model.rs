//! What a controller knows about the drives: torque limits and friction
//! estimates per joint (from the drives file, [`crate::robot::Drives`]).

/// Which quantity of a [`DriveModel`] (defined next to the [`SettingsError`] that names it).
use crate::control::settings::DriveQuantity;
use crate::control::settings::SettingsError;
use crate::robot::Robot;

/// The drives as a controller models them, one entry per joint.
#[derive(Debug, Clone, PartialEq)]
pub struct DriveModel {
    /// Peak torque `τmax_i` (N·m), symmetric; `∞` for no limit.
    pub max_torque_nm: Vec<f64>,
    /// Coulomb friction estimate `F_c,i` (N·m).
    pub coulomb_nm: Vec<f64>,
    /// Viscous friction estimate `F_v,i` (N·m·s/rad).
    pub viscous_nms: Vec<f64>,
    /// Velocity scale `v_s` of the smoothed Coulomb friction
    /// `F_c tanh(q̇ / v_s)` (rad/s).
    pub coulomb_velocity_rad_s: f64,
}

use crate::dynamics::friction::DEFAULT_COULOMB_VELOCITY;

impl DriveModel {
    /// The robot's effort limits and its drives' friction estimates.
    pub fn from_robot(robot: &Robot) -> Self {
        let j = robot.joints();
        Self {
            max_torque_nm: j.iter().map(|j| j.limits.effort).collect(),
            coulomb_nm: j.iter().map(|j| j.coulomb_nm).collect(),
            viscous_nms: j.iter().map(|j| j.viscous_nms).collect(),
            coulomb_velocity_rad_s: DEFAULT_COULOMB_VELOCITY,
        }
    }

    /// Checks lengths (`n`) and values: limits `> 0` (or `∞`), friction finite
    /// and `≥ 0`, velocity scale finite and `> 0`.
    pub fn validate(&self, n: usize) -> Result<(), SettingsError> {
        for (what, v) in [
            (DriveQuantity::MaxTorque, &self.max_torque_nm),
            (DriveQuantity::Coulomb, &self.coulomb_nm),
            (DriveQuantity::Viscous, &self.viscous_nms),
        ] {
            if v.len() != n {
                return Err(SettingsError::DriveModelLength {
                    what,
                    expected: n,
                    got: v.len(),
                });
            }
            let bad = |x: f64| match what {
                DriveQuantity::MaxTorque => x.is_nan() || x <= 0.0,
                _ => !x.is_finite() || x < 0.0,
            };
            if let Some((index, &value)) = v.iter().enumerate().find(|(_, x)| bad(**x)) {
                return Err(SettingsError::DriveModelValue { what, index, value });
            }
        }
        let vs = self.coulomb_velocity_rad_s;
        if !(vs.is_finite() && vs > 0.0) {
            return Err(SettingsError::DriveModelValue {
                what: DriveQuantity::CoulombVelocity,
                index: 0,
                value: vs,
            });
        }
        Ok(())
    }

    /// The linear-like damping `d_i(q̇) = F_v + F_c tanh(q̇/v_s)/q̇` with
    /// `d_i q̇_i` = the friction torque (its limit `F_v + F_c/v_s` at rest;
    /// `crate::dynamics::friction::damping`).
    pub fn damping(&self, i: usize, v: f64) -> f64 {
        crate::dynamics::friction::damping(
            self.viscous_nms[i],
            self.coulomb_nm[i],
            self.coulomb_velocity_rad_s,
            v,
        )
    }
}
