//! The estimator stage: the state the controller acts on.

use crate::control::{StateObserver, StepFailure};
use crate::dynamics::JointSpaceDynamics;

/// Hands the controller the state it acts on: the observer's estimate
/// (updated from the reading, with the delay compensation the observer was
/// built with) when there is an observer, else the reading itself.
///
/// Sized at construction; [`Estimator::estimate`] allocates nothing.
#[derive(Debug)]
pub struct Estimator<'a> {
    observer: Option<&'a mut StateObserver>,
    x_est: Vec<f64>,
}

impl<'a> Estimator<'a> {
    /// An estimator for `n` joints, with `observer` or without one.
    pub fn new(n: usize, observer: Option<&'a mut StateObserver>) -> Self {
        Self {
            observer,
            x_est: vec![0.0; 2 * n],
        }
    }

    /// Starts a run from the reading `x0` (2n).
    pub fn reset(&mut self, x0: &[f64]) {
        self.x_est.copy_from_slice(x0);
        if let Some(o) = self.observer.as_deref_mut() {
            o.reset(x0);
        }
    }

    /// Whether there is an observer.
    pub fn has_observer(&self) -> bool {
        self.observer.is_some()
    }

    /// The state for the controller at this sample, from the reading `x`
    /// (2n): the observer's updated estimate, or `x`.
    pub fn estimate<'s>(
        &'s mut self,
        model: &mut dyn JointSpaceDynamics,
        x: &'s [f64],
    ) -> Result<&'s [f64], StepFailure> {
        match self.observer.as_deref_mut() {
            Some(o) => {
                self.x_est.copy_from_slice(o.update(model, x)?);
                Ok(&self.x_est)
            }
            None => Ok(x),
        }
    }

    /// The last estimate with an observer, else `x`: where a safe stop
    /// starts from.
    pub fn last<'s>(&'s self, x: &'s [f64]) -> &'s [f64] {
        if self.observer.is_some() {
            &self.x_est
        } else {
            x
        }
    }

    /// The torque applied at this sample (n), for the observer's
    /// prediction.
    pub fn record_torque(&mut self, tau: &[f64]) {
        if let Some(o) = self.observer.as_deref_mut() {
            o.record_torque(tau);
        }
    }
}
