//! Events of a run at path times, matched to control samples by one rule.
//!
//! A scenario gives times in seconds; the loop runs on sample indices
//! `k` (`t_k = k·Ts`). Every timed event of the loop — a lost measurement,
//! the payload pick-up — is converted once, when the loop is set up, by
//! [`sample_at`]: the event belongs to the first sample at or after its time,
//! with a tolerance of `10⁻⁹·Ts` for times that are whole multiples of `Ts`
//! up to rounding (`0.1 + 0.2` s at `Ts = 0.1` s is sample 3).

use super::conditions::MeasurementFaults;

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
/// ([`TIME_MATCH_TOLERANCE`]). `t` must be finite and `ts > 0`; negative
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

/// The samples whose measurement is lost, as half-open index ranges
/// `[from, to)`: a NaN at `t` is the one sample [`sample_at`]`(t)`, a
/// dropout `[a, b)` is the samples `[sample_at(a), sample_at(b))`.
/// Built before the loop (allocates); [`Self::lost`] allocates nothing.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LossSchedule {
    ranges: Vec<(usize, usize)>,
}

impl LossSchedule {
    /// The schedule of `faults` at the control period `ts` (the faults are
    /// checked by [`super::RunConditions::validate`]).
    pub fn new(faults: &MeasurementFaults, ts: f64) -> Self {
        let nan = faults.nan_at_s.iter().map(|&t| {
            let from = sample_at(t, ts);
            // `t_k < t + ts − ε`: the end is matched from `t + ts`.
            (from, sample_at(t + ts, ts))
        });
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

    /// No loss was asked for.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Whether the measurement of sample `k` is lost.
    pub fn lost(&self, k: usize) -> bool {
        self.ranges.iter().any(|&(a, b)| k >= a && k < b)
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
}
