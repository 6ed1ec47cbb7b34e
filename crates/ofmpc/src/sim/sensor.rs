//! The sensor stage: the measurement as the controller's side receives it.
//!
//! The plant's own measurement effects (encoder quantization, noise, delay,
//! encoder faults: [`super::PlantSettings`]) happen inside
//! [`Plant::measure`]; this stage adds the loss of whole samples
//! ([`LossSchedule`]: NaN readings and dropouts) and stands in for a lost or
//! invalid reading with the model's prediction ([`MeasurementGuard`]), so
//! that everything after it sees finite numbers.

use super::faults::LossSchedule;
use super::plant::{Plant, PlantError};
use super::repair::MeasurementGuard;
use crate::dynamics::JointSpaceDynamics;

/// Reads the plant, loses the scheduled samples, repairs invalid readings.
/// Sized at construction; [`Sensor::read`] and [`Sensor::repair`] allocate
/// nothing.
#[derive(Debug, Clone)]
pub struct Sensor {
    lost: LossSchedule,
    guard: MeasurementGuard,
}

impl Sensor {
    /// A sensor for `n` joints read once per control period `ts` (s), whose
    /// readings are `delay_samples` old (the guard's prediction uses the
    /// torque of that sample), losing the samples of `lost` (scheduled at
    /// `ts`). Starts at rest at zero; call [`Self::reset`] with the first
    /// reading.
    pub fn new(n: usize, delay_samples: usize, lost: LossSchedule, ts: f64) -> Self {
        let track = !lost.is_empty();
        Self {
            guard: MeasurementGuard::new(&vec![0.0; 2 * n], delay_samples, track, ts),
            lost,
        }
    }

    /// Starts a run at rest at `x0` (2n values, the first reading).
    pub fn reset(&mut self, x0: &[f64]) {
        self.guard.reset(x0);
    }

    /// Whether samples can be lost (the readings then differ from the
    /// plant's state and are worth recording).
    pub fn loses_samples(&self) -> bool {
        !self.lost.is_empty()
    }

    /// The reading of sample `k` into `x` (2n): the plant's measurement, or
    /// NaN when the sample is lost. `fresh`: read the plant (`false` reuses
    /// what `x` holds, e.g. the reading the run started from).
    pub fn read(
        &mut self,
        plant: &mut Plant,
        k: usize,
        fresh: bool,
        x: &mut [f64],
    ) -> Result<(), PlantError> {
        if fresh {
            plant.measure(x)?;
        }
        if self.lost.lost(k) {
            x.fill(f64::NAN);
        }
        Ok(())
    }

    /// Replaces the non-finite entries of `x` by the model's prediction
    /// ([`MeasurementGuard::check`]); returns whether it did (a fault).
    pub fn repair(&mut self, model: &mut dyn JointSpaceDynamics, x: &mut [f64]) -> bool {
        self.guard.check(model, x)
    }

    /// The torque commanded at the current sample (n values), for the
    /// prediction of the samples to come.
    pub fn record_torque(&mut self, tau: &[f64]) {
        self.guard.record_torque(tau);
    }
}
