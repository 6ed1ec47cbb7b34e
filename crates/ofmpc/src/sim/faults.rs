//! The one home of a run's faults: the plant's own ([`Fault`], a scenario's
//! `[plant] faults`: encoder glitch and dropout, torque drop), the
//! measurement channel's ([`MeasurementFaults`], `[faults]`: lost samples),
//! and their schedule ([`FaultSchedule`]).
//!
//! Events of a run at path times are matched to control samples by one rule.
//!
//! A scenario gives times in seconds; the loop runs on sample indices
//! `k` (`t_k = k·Ts`, `k = 0` the path's first sample). Every timed event of
//! the loop — a lost measurement, a fault of the plant ([`FaultSchedule`]),
//! the payload pick-up — is converted once, when its stage is built, by
//! [`sample_at`]: the event belongs to the first sample at or after its time,
//! with a tolerance of `10⁻⁹·Ts` for times that are whole multiples of `Ts`
//! up to rounding (`0.1 + 0.2` s at `Ts = 0.1` s is sample 3).

use super::settings_error::LoopSettingsError;
use serde::{Deserialize, Serialize};

/// Relative tolerance (of `Ts`) when a time is matched to a sample.
pub const TIME_MATCH_TOLERANCE: f64 = 1e-9;

/// Whether time `t` is at or after the event time `at`, within
/// [`TIME_MATCH_TOLERANCE`]` · ts`: the one comparison every timed event of
/// the loop is matched by (`t ≥ at − 10⁻⁹·ts`).
#[inline]
pub fn at_or_after(t: f64, at: f64, ts: f64) -> bool {
    t >= at - TIME_MATCH_TOLERANCE * ts
}

/// The first sample `k` whose time `k·ts` is at or after `t − 10⁻⁹·ts`
/// (`TIME_MATCH_TOLERANCE`). `t` must be finite and `ts > 0`; negative
/// times give sample 0.
///
/// Exactly the comparison `k as f64 * ts >= t − 1e-9 * ts` the loop makes
/// per sample, solved once (the estimate from the division is corrected by
/// that very comparison, so rounding cannot move the result).
pub fn sample_at(t: f64, ts: f64) -> usize {
    let threshold = t - TIME_MATCH_TOLERANCE * ts;
    if threshold.is_nan() || threshold <= 0.0 {
        return 0;
    }
    let estimate = (threshold / ts).ceil();
    if estimate.is_nan() || estimate >= usize::MAX as f64 {
        return usize::MAX;
    }
    let mut k = estimate as usize;
    while k > 0 && at_or_after((k - 1) as f64 * ts, t, ts) {
        k -= 1;
    }
    while !at_or_after(k as f64 * ts, t, ts) {
        k += 1;
    }
    k
}

/// The one schedule of a run's faults: each fault, given at a path time
/// (and a duration), as the half-open range of samples `[from, to)` it
/// covers, matched by [`sample_at`] once, when the stage that applies it is
/// built. Both kinds of fault use it: the measurement faults of a scenario's
/// `[faults]` ([`Self::new`], the [`super::Sensor`]'s lost samples) and the
/// plant's own faults of `[plant] faults` ([`Self::for_plant`], applied by
/// the [`super::Plant`]), so that a fault at `t` hits the same path sample
/// whichever stage applies it, with or without a pre-roll before the path.
///
/// Built before the loop (allocates); the queries allocate nothing.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FaultSchedule {
    ranges: Vec<(usize, usize)>,
}

/// The measurement faults' `FaultSchedule` (its former name, kept).
pub type LossSchedule = FaultSchedule;

/// The samples a fault at `t` covers when it lasts one sample:
/// `[sample_at(t), sample_at(t + ts))` (`t_k < t + ts − ε`).
fn one_sample(t: f64, ts: f64) -> (usize, usize) {
    (sample_at(t, ts), sample_at(t + ts, ts))
}

impl FaultSchedule {
    /// The schedule of the measurement faults `faults` at the control period
    /// `ts` (the faults are checked by [`super::RunConditions::validate`]):
    /// a NaN at `t` is the one sample [`sample_at`]`(t)`, a dropout `[a, b)`
    /// is the samples `[sample_at(a), sample_at(b))`. [`Self::lost`] tells
    /// whether a sample is lost.
    pub fn new(faults: &MeasurementFaults, ts: f64) -> Self {
        let nan = faults.nan_at_s.iter().map(|&t| one_sample(t, ts));
        let dropout = faults
            .dropout_s
            .iter()
            .map(|&[a, b]| (sample_at(a, ts), sample_at(b, ts)));
        // Ranges that hold no sample stay: the faults were asked for (the
        // sensor then still learns the model's missing acceleration).
        Self {
            ranges: nan.chain(dropout).collect(),
        }
    }

    /// The schedule of the plant's faults at the control period `ts`, one
    /// range per fault in their order (checked by
    /// [`super::PlantSettings::validate`]): an encoder glitch at `t` is the
    /// one sample [`sample_at`]`(t)` (as a NaN of [`Self::new`]), a fault
    /// lasting `d` covers `[sample_at(t), sample_at(t + d))` (as a dropout).
    pub fn for_plant(faults: &[Fault], ts: f64) -> Self {
        let mut s = Self {
            ranges: vec![(0, 0); faults.len()],
        };
        s.reschedule(faults, ts);
        s
    }

    /// [`Self::for_plant`] again at another period, in place (the same
    /// faults: allocates nothing).
    pub(crate) fn reschedule(&mut self, faults: &[Fault], ts: f64) {
        for (r, f) in self.ranges.iter_mut().zip(faults) {
            let (t, _, d) = f.span();
            *r = match f {
                Fault::EncoderGlitch { .. } => one_sample(t, ts),
                _ => (sample_at(t, ts), sample_at(t + d, ts)),
            };
        }
    }

    /// No fault is scheduled.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Whether any fault covers sample `k`: for the measurement faults
    /// ([`Self::new`]), whether the measurement of sample `k` is lost.
    pub fn lost(&self, k: usize) -> bool {
        self.ranges.iter().any(|&(a, b)| k >= a && k < b)
    }

    /// The samples `[from, to)` of fault `index` (in the order the faults
    /// were given); `None` past the last fault.
    pub fn range(&self, index: usize) -> Option<(usize, usize)> {
        self.ranges.get(index).copied()
    }

    /// Whether fault `index` covers sample `k`.
    pub fn active(&self, index: usize, k: usize) -> bool {
        self.range(index).is_some_and(|(a, b)| k >= a && k < b)
    }
}

/// An injected fault of one joint, from path time `t` on (`t = 0`: the
/// path's first sample, after any pre-roll at rest), matched to samples as
/// every timed event of a run (`super::FaultSchedule::for_plant`,
/// [`super::sample_at`]). In TOML:
/// `faults = [{ kind = "encoder_glitch", t = 2.0, joint = 6, offset_rad = 0.01 }]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
#[non_exhaustive]
pub enum Fault {
    /// The measured position is off by `offset_rad` on one sample (the
    /// first measurement at or after `t`).
    EncoderGlitch {
        /// Time (s).
        t: f64,
        /// Joint, 1-based.
        joint: usize,
        /// Offset (rad).
        offset_rad: f64,
    },
    /// The joint's measurement (position and velocity) is frozen at its last
    /// value for `duration_s`.
    EncoderDropout {
        /// Time (s).
        t: f64,
        /// Joint, 1-based.
        joint: usize,
        /// Duration (s).
        duration_s: f64,
    },
    /// The drive delivers `fraction` of the commanded torque for `duration_s`.
    TorqueDrop {
        /// Time (s).
        t: f64,
        /// Joint, 1-based.
        joint: usize,
        /// Delivered fraction, in [0, 1].
        fraction: f64,
        /// Duration (s).
        duration_s: f64,
    },
}

impl Fault {
    /// Start time, 0-based joint and duration (0 for a glitch).
    pub(super) fn span(&self) -> (f64, usize, f64) {
        match *self {
            Fault::EncoderGlitch { t, joint, .. } => (t, joint.wrapping_sub(1), 0.0),
            Fault::EncoderDropout {
                t,
                joint,
                duration_s,
            }
            | Fault::TorqueDrop {
                t,
                joint,
                duration_s,
                ..
            } => (t, joint.wrapping_sub(1), duration_s),
        }
    }
}

/// Faults of the measurement channel, at path times: at the sample at (or
/// first after) each `nan_at_s` the measurement is NaN; in each
/// `dropout_s = [from, to)` no measurement arrives (it reads as NaN). The
/// loop then hands the controller a model prediction
/// (the supervisor module) and counts the fault.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MeasurementFaults {
    /// Times of single invalid (NaN) measurements (s).
    pub nan_at_s: Vec<f64>,
    /// Intervals without measurements, `[from, to)` (s).
    pub dropout_s: Vec<[f64; 2]>,
}

impl MeasurementFaults {
    /// No fault.
    pub fn is_empty(&self) -> bool {
        self.nan_at_s.is_empty() && self.dropout_s.is_empty()
    }

    /// Whether the measurement of the sample at `t` (period `ts`) is lost.
    pub fn lost_at(&self, t: f64, ts: f64) -> bool {
        let within = |from: f64, to: f64| at_or_after(t, from, ts) && !at_or_after(t, to, ts);
        self.nan_at_s.iter().any(|&f| within(f, f + ts))
            || self.dropout_s.iter().any(|&[from, to]| within(from, to))
    }

    /// Checks the times: finite, `≥ 0`, dropouts `from < to`.
    pub fn validate(&self) -> Result<(), LoopSettingsError> {
        if let Some((index, &value)) = self
            .nan_at_s
            .iter()
            .enumerate()
            .find(|(_, t)| !(t.is_finite() && **t >= 0.0))
        {
            return Err(LoopSettingsError::FaultTime { index, value });
        }
        if let Some((index, &[from, to])) = self
            .dropout_s
            .iter()
            .enumerate()
            .find(|(_, [a, b])| !(a.is_finite() && b.is_finite() && *a >= 0.0 && a < b))
        {
            return Err(LoopSettingsError::DropoutInterval { index, from, to });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule against the per-sample comparison it replaces, on times near
    /// sample boundaries and on rounding-prone sums.
    #[test]
    fn sample_at_is_the_per_sample_comparison() {
        for &ts in &[1e-3, 0.01, 0.1, 0.3, 1.0 / 3.0] {
            for i in 0..2000 {
                for t in [
                    i as f64 * ts,
                    i as f64 * ts * (1.0 + 1e-12),
                    i as f64 * ts * (1.0 - 1e-12),
                    i as f64 * 0.0137,
                    0.1 * i as f64 + 0.2,
                ] {
                    let brute = (0..)
                        .find(|&k| k as f64 * ts >= t - TIME_MATCH_TOLERANCE * ts)
                        .unwrap();
                    assert_eq!(sample_at(t, ts), brute, "t = {t}, ts = {ts}");
                }
            }
        }
        assert_eq!(sample_at(-1.0, 0.01), 0);
        assert_eq!(sample_at(0.1 + 0.2, 0.1), 3);
    }

    /// The schedule equals the per-sample test it replaces
    /// ([`MeasurementFaults::lost_at`]).
    #[test]
    fn schedule_matches_lost_at() {
        let faults = MeasurementFaults {
            nan_at_s: vec![0.0, 0.3, 1.0 / 3.0, 2.0],
            dropout_s: vec![[0.5, 0.55], [0.7, 0.7001], [1.2, 1.5]],
        };
        for &ts in &[1e-3, 0.01, 0.1] {
            let s = LossSchedule::new(&faults, ts);
            for k in 0..3000 {
                assert_eq!(
                    s.lost(k),
                    faults.lost_at(k as f64 * ts, ts),
                    "k = {k}, ts = {ts}"
                );
            }
        }
    }

    /// The plant's faults are scheduled by the measurement faults' rule: a
    /// glitch as a NaN at its time, a fault with a duration as a dropout
    /// over it (brute force: the per-sample comparison of
    /// [`MeasurementFaults::lost_at`]).
    #[test]
    fn plant_faults_follow_the_measurement_faults_rule() {
        for &ts in &[1e-3, 0.01, 0.1] {
            for &(t, d) in &[
                (0.0, 0.0),
                (0.3, 0.05),
                (1.0 / 3.0, 0.1),
                (2.0, 0.5),
                (1.203, 0.0),
            ] {
                let faults = [
                    Fault::EncoderGlitch {
                        t,
                        joint: 1,
                        offset_rad: 0.01,
                    },
                    Fault::EncoderDropout {
                        t,
                        joint: 2,
                        duration_s: d,
                    },
                    Fault::TorqueDrop {
                        t,
                        joint: 3,
                        fraction: 0.5,
                        duration_s: d,
                    },
                ];
                let s = FaultSchedule::for_plant(&faults, ts);
                let nan = MeasurementFaults {
                    nan_at_s: vec![t],
                    dropout_s: Vec::new(),
                };
                let dropout = MeasurementFaults {
                    nan_at_s: Vec::new(),
                    dropout_s: vec![[t, t + d]],
                };
                for k in 0..3000 {
                    let tk = k as f64 * ts;
                    assert_eq!(s.active(0, k), nan.lost_at(tk, ts), "glitch k = {k}");
                    assert_eq!(s.active(1, k), dropout.lost_at(tk, ts), "k = {k}");
                    assert_eq!(s.active(2, k), dropout.lost_at(tk, ts), "k = {k}");
                }
                assert!(!s.active(3, 0));
            }
        }
    }
}
