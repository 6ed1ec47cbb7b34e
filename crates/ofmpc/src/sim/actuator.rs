//! The actuator stage: what happens between the commanded and the applied
//! torque.
//!
//! [`Actuator::apply`] turns the controller's command into the torque the
//! drives deliver over the period: clamped to the drives' rated torques when
//! the plant's settings ask for it (`[plant] torque_limits`), then
//! scaled by a torque-drop fault of a scenario's `[plant] faults` over its
//! path samples. It also meters how loaded the drives are by the command
//! ([`Loading`]).
//!
//! Friction stays in the plant ([`super::Plant`]): it depends on the joint
//! velocity inside the integration's substeps (`F(q̇)` at each RK4 stage), so
//! taking it out of the integrator would evaluate it once per period and
//! change the physics (and every run's numbers); the actuator holds the
//! torque constant over the period (zero-order hold), as the drives do.

use super::faults::{Fault, FaultSchedule};
use crate::robot::{ModelError, Robot};

/// The drives between the controller and the plant. Sized at construction;
/// [`Actuator::apply`] and [`Actuator::account`] allocate nothing.
#[derive(Debug, Clone)]
pub struct Actuator {
    tau_max: Vec<f64>,
    /// Clamp the command to `tau_max` (finite entries).
    saturate: bool,
    /// The plant's faults (the torque drops act here) and their path samples.
    faults: Vec<Fault>,
    schedule: FaultSchedule,
    /// The torque applied over the last period (n).
    applied: Vec<f64>,
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
    /// entry has no limit) that deliver the command as it is (no clamp, no
    /// fault): a meter of the load.
    pub fn new(tau_max: &[f64]) -> Self {
        Self {
            tau_max: tau_max.to_vec(),
            saturate: false,
            faults: Vec::new(),
            schedule: FaultSchedule::default(),
            applied: vec![0.0; tau_max.len()],
        }
    }

    /// The drives of `robot` (their `effort` limits), delivering the
    /// command as it is: [`Self::new`].
    pub fn for_robot(robot: &Robot) -> Self {
        let tau_max: Vec<f64> = robot.joints().iter().map(|j| j.limits.effort).collect();
        Self::new(&tau_max)
    }

    /// The drives of `robot`, clamping the command to their rated torques
    /// when `torque_limits`, with the torque drops among `faults` (a
    /// scenario's `[plant] faults`; the other kinds act elsewhere, a drop on
    /// a joint the robot lacks is ignored), run at the control period `ts`
    /// (s): the faults are matched to its samples once. The plant's settings
    /// give both ([`PlantSettings::actuator`](super::PlantSettings::actuator)).
    pub fn with_faults(robot: &Robot, torque_limits: bool, faults: &[Fault], ts: f64) -> Self {
        let mut a = Self::for_robot(robot);
        a.saturate = torque_limits;
        a.faults = faults.to_vec();
        a.schedule = FaultSchedule::for_plant(faults, ts);
        a
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

    /// The torque the drives deliver over the period whose path sample is
    /// `path_sample` (`None` before the path: no fault yet) for the command
    /// `commanded` (n): `clamp(τ_c, −τ_max, τ_max)` with torque limits, times
    /// the delivered fraction of a torque drop covering the sample. Also
    /// [`Self::applied`]. A command of another length or not finite is an
    /// error (the plant's check of a torque: nothing is applied).
    pub fn apply(
        &mut self,
        commanded: &[f64],
        path_sample: Option<usize>,
    ) -> Result<&[f64], ModelError> {
        check_torque(commanded, self.applied.len())?;
        for ((a, t), lim) in self.applied.iter_mut().zip(commanded).zip(&self.tau_max) {
            *a = if self.saturate && lim.is_finite() {
                t.clamp(-lim, *lim)
            } else {
                *t
            };
        }
        if let Some(k) = path_sample {
            for (index, f) in self.faults.iter().enumerate() {
                if let Fault::TorqueDrop {
                    joint, fraction, ..
                } = *f
                {
                    let joint = self.applied.get_mut(joint.wrapping_sub(1));
                    if let Some(a) = joint.filter(|_| self.schedule.active(index, k)) {
                        *a *= fraction;
                    }
                }
            }
        }
        Ok(&self.applied)
    }

    /// The torque applied over the last period (n).
    pub fn applied(&self) -> &[f64] {
        &self.applied
    }
}

/// The plant's check of a torque (`Robot::check_vector("tau", …)`): `n`
/// finite values.
fn check_torque(tau: &[f64], n: usize) -> Result<(), ModelError> {
    if tau.len() != n {
        return Err(ModelError::Dimension {
            what: "tau".to_string(),
            expected: n,
            got: tau.len(),
        });
    }
    if let Some((index, x)) = tau.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(ModelError::NonFinite {
            what: "tau".to_string(),
            index,
            value: *x,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{Plant, PlantSettings};

    /// With torque limits the command is clamped to the drives' rated
    /// torques (IRB 140: 290, 500, …, 16 N·m), and the plant integrates what
    /// the actuator applied; a non-finite command is refused.
    #[test]
    fn torque_saturation() {
        let robot = Robot::irb140();
        let s = PlantSettings {
            torque_limits: true,
            ..Default::default()
        };
        let mut a = s.actuator(&robot, 0.01);
        let mut p = Plant::with_period(robot, s, &[0.0; 6], 0.01).unwrap();
        let applied = a.apply(&[1e4, -1e4, 0.0, 0.0, 0.0, 100.0], None).unwrap();
        assert_eq!(applied[0], 290.0);
        assert_eq!(applied[1], -500.0);
        assert_eq!(applied[5], 16.0);
        p.advance(a.applied()).unwrap();
        assert_eq!(p.applied_torque(), a.applied());
        assert!(a.apply(&[f64::NAN; 6], None).is_err());
        assert!(a.apply(&[0.0; 5], None).is_err());
        let loading = a.account(&[1e4, 0.0, 0.0, 0.0, 0.0, 0.0]);
        assert!(loading.saturated && loading.max_ratio > 30.0);
    }

    /// A torque drop delivers its fraction over its path samples only (at
    /// 0.05 s for 0.03 s at 10 ms: samples 5, 6, 7), and never before the
    /// path.
    #[test]
    fn a_torque_drop_acts_over_its_samples() {
        let robot = Robot::irb140();
        let s = PlantSettings {
            faults: vec![Fault::TorqueDrop {
                t: 0.05,
                joint: 2,
                fraction: 0.25,
                duration_s: 0.03,
            }],
            ..Default::default()
        };
        let mut a = s.actuator(&robot, 0.01);
        for k in 0..10 {
            let dropped = (5..8).contains(&k);
            let applied = a.apply(&[2.0; 6], Some(k)).unwrap();
            assert_eq!(applied[1], if dropped { 0.5 } else { 2.0 }, "k = {k}");
            assert_eq!(applied[0], 2.0);
        }
        assert_eq!(a.apply(&[2.0; 6], None).unwrap()[1], 2.0);
    }
}
