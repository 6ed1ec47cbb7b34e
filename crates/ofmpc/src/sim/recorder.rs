//! The recorder stage: what a run keeps of each sample.

use super::actuator::Loading;
use super::telemetry::{LoopTelemetry, TelemetrySample};

/// The recorded time series of one run. Row `k` holds the plant's true state
/// at `t_k`, what the controller was given as its measurement when that
/// differs (`q_meas`, `qd_meas`), and the torque applied over
/// `[t_k, t_k + Ts)`; vectors are stored row-major (`k·n + i`). Counters of
/// faults and saturation cover the whole run.
#[derive(Debug, Clone, Default)]
pub struct Record {
    /// Number of joints.
    pub n: usize,
    /// Sample times (s).
    pub t: Vec<f64>,
    /// True joint positions (rad).
    pub q: Vec<f64>,
    /// True joint velocities (rad/s).
    pub qd: Vec<f64>,
    /// The measured positions as they reached the controller (rad; NaN where
    /// the measurement was invalid or missing), when a measurement effect or
    /// fault is on; empty otherwise (the measurement is then `q`).
    pub q_meas: Vec<f64>,
    /// The measured velocities as they reached the controller (rad/s), as
    /// `q_meas`.
    pub qd_meas: Vec<f64>,
    /// Torque applied over the sample period (N·m), after saturation.
    pub tau: Vec<f64>,
    /// Joint reference w_k (rad).
    pub q_ref: Vec<f64>,
    /// True flange position (m, base frame).
    pub flange: Vec<[f64; 3]>,
    /// Reference flange position (m, base frame).
    pub flange_ref: Vec<[f64; 3]>,
    /// Wall time of each controller step (µs).
    pub step_us: Vec<f64>,
    /// The payload mass the controller's model carries after each step (kg),
    /// for controllers that identify it online; empty otherwise.
    pub payload_mass_est: Vec<f64>,
    /// Samples whose measurement was missing, invalid or implausible and
    /// was replaced by a prediction.
    pub faults: usize,
    /// Samples at which the commanded torque of some joint reached its
    /// limit (`|τ_i| ≥ (1 − 1e-9)·τmax_i`).
    pub saturated_samples: usize,
    /// Largest `|τ_i| / τmax_i` of the commanded torque over joints and
    /// samples (0 without finite limits).
    pub max_torque_ratio: f64,
    /// What the controller predicted over its horizon at some samples, when the loop was
    /// asked to record it ([`super::RunConditions::horizons`]); `None` otherwise.
    pub horizons: Option<super::horizon::PredictedHorizons>,
    /// What the servo interface saw (`[plant.servo]`); `None` without one.
    pub servo: Option<super::servo::ServoReport>,
    /// The loop's per-sample telemetry ([`LoopTelemetry`]).
    pub telemetry: LoopTelemetry,
}

impl Record {
    /// An empty record for `n` joints with room for `capacity` samples.
    pub fn with_capacity(n: usize, capacity: usize) -> Self {
        Self {
            n,
            t: Vec::with_capacity(capacity),
            q: Vec::with_capacity(capacity * n),
            qd: Vec::with_capacity(capacity * n),
            tau: Vec::with_capacity(capacity * n),
            q_ref: Vec::with_capacity(capacity * n),
            flange: Vec::with_capacity(capacity),
            flange_ref: Vec::with_capacity(capacity),
            step_us: Vec::with_capacity(capacity),
            payload_mass_est: Vec::new(),
            q_meas: Vec::new(),
            qd_meas: Vec::new(),
            faults: 0,
            saturated_samples: 0,
            max_torque_ratio: 0.0,
            horizons: None,
            servo: None,
            telemetry: LoopTelemetry::with_capacity(capacity),
        }
    }

    /// Whether the measurement the controller was given is recorded apart
    /// from the true state.
    pub fn has_measurement(&self) -> bool {
        !self.q_meas.is_empty()
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
    /// Joint error `w_k − q_k` of joint `i` at sample `k` (rad).
    pub fn joint_error(&self, k: usize, i: usize) -> f64 {
        self.q_ref[k * self.n + i] - self.q[k * self.n + i]
    }
    /// Cartesian error `p_ref − p` at sample `k` (m).
    pub fn cartesian_error(&self, k: usize) -> [f64; 3] {
        let (r, p) = (self.flange_ref[k], self.flange[k]);
        [r[0] - p[0], r[1] - p[1], r[2] - p[2]]
    }
}

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

    /// Appends one controller step's telemetry.
    pub(crate) fn telemetry(&mut self, s: &TelemetrySample) {
        self.record.telemetry.push(s);
    }

    /// Appends one loop iteration's wall time (µs).
    pub fn loop_time(&mut self, us: f64) {
        self.record.telemetry.push_loop(us);
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
