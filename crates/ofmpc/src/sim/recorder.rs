//! The recorder stage: what a run keeps of each sample.

use super::actuator::Loading;
use super::metrics::Record;

/// One sample as recorded: the true state measured at `t`, the torque the
/// drives applied over `[t, t + Ts)`, the reference and the flange.
#[derive(Debug, Clone, Copy)]
pub struct Sample<'a> {
    /// Path time (s).
    pub t: f64,
    /// True joint positions (n).
    pub q: &'a [f64],
    /// True joint velocities (n).
    pub qd: &'a [f64],
    /// Torque the drives applied (n).
    pub tau: &'a [f64],
    /// Joint reference `w_k` (n).
    pub w: &'a [f64],
    /// Flange position of the reference (m).
    pub flange_ref: [f64; 3],
    /// Flange position (m).
    pub flange: [f64; 3],
    /// Time of the controller's (or the stop law's) step (µs).
    pub step_us: f64,
    /// The controller's payload estimate (kg), if it identifies one.
    pub payload_mass_est: Option<f64>,
}

/// Fills a [`Record`] sample by sample. Sized at construction for the
/// run's samples: recording within that size allocates nothing.
#[derive(Debug, Clone)]
pub struct Recorder {
    record: Record,
    measured: bool,
}

impl Recorder {
    /// A record of `n` joints with room for `capacity` samples; `measured`:
    /// also record the readings the controller's side got
    /// ([`Self::reading`]); `payload_estimate`: room for a payload estimate
    /// per sample.
    pub fn new(n: usize, capacity: usize, measured: bool, payload_estimate: bool) -> Self {
        let mut record = Record::with_capacity(n, capacity);
        if payload_estimate {
            record.payload_mass_est.reserve(capacity);
        }
        if measured {
            record.q_meas.reserve(capacity * n);
            record.qd_meas.reserve(capacity * n);
        }
        Self { record, measured }
    }

    /// The reading as delivered by the sensor, before any repair (2n);
    /// kept only for a recorder built with `measured`.
    pub fn reading(&mut self, x: &[f64]) {
        if self.measured {
            let n = self.record.n;
            self.record.q_meas.extend_from_slice(&x[..n]);
            self.record.qd_meas.extend_from_slice(&x[n..2 * n]);
        }
    }

    /// Counts a sample whose reading was replaced or rejected.
    pub fn fault(&mut self, fault: bool) {
        self.record.faults += usize::from(fault);
    }

    /// Accounts the drives' loading of one sample.
    pub fn loading(&mut self, loading: Loading) {
        let r = &mut self.record;
        r.max_torque_ratio = r.max_torque_ratio.max(loading.max_ratio);
        r.saturated_samples += usize::from(loading.saturated);
    }

    /// Appends one sample.
    pub fn push(&mut self, s: &Sample<'_>) {
        let r = &mut self.record;
        r.t.push(s.t);
        r.q.extend_from_slice(s.q);
        r.qd.extend_from_slice(s.qd);
        r.tau.extend_from_slice(s.tau);
        r.q_ref.extend_from_slice(s.w);
        r.flange_ref.push(s.flange_ref);
        r.step_us.push(s.step_us);
        r.flange.push(s.flange);
        if let Some(m) = s.payload_mass_est {
            r.payload_mass_est.push(m);
        }
    }

    /// What was recorded so far.
    pub fn record(&self) -> &Record {
        &self.record
    }

    /// The record.
    pub fn into_record(self) -> Record {
        self.record
    }
}
