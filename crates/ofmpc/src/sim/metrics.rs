//! What a closed-loop run is judged by: tracking errors (joint and
//! Cartesian), torques, step times, divergence.

use super::outcome::{RunOutcome, RunStatus};
use super::recorder::Record;
use super::telemetry::{FallbackCounts, LoopTelemetry, Percentiles, TelemetryMetrics};
use serde::Serialize;

/// Median, 99th percentile and maximum of the controller's step time (µs),
/// and how many steps missed their real-time deadline.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepTime {
    /// Median (µs).
    pub median: f64,
    /// 99th percentile (µs).
    pub p99: f64,
    /// Maximum (µs).
    pub max: f64,
    /// Steps that took longer than the sampling period `Ts` (the spacing of
    /// the record's sample times): each of them would have missed its
    /// deadline in a real-time loop.
    pub deadline_misses: usize,
}

/// Number of step times (µs) longer than the sampling period `ts` (s).
/// Zero when `ts` is not a finite positive number.
pub fn deadline_misses(step_us: &[f64], ts: f64) -> usize {
    if !(ts.is_finite() && ts > 0.0) {
        return 0;
    }
    let limit_us = ts * 1e6;
    step_us.iter().filter(|&&s| s > limit_us).count()
}

/// Summary of one run, as in `metrics.json`. A metric that does not exist
/// (nothing recorded, no steady window because the run stopped early) is NaN,
/// which serializes as `null`: never 0.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunMetrics {
    /// Run name (its folder): `<controller>_m<payload>`.
    pub name: String,
    /// The controller kind's name (`ControllerKind::name`): `"usual"`,
    /// `"first"`, `"second"`, `"first-adaptive"`, `"second-adaptive"`,
    /// `"pid"`, `"ctc"`, `"ctc-adaptive"` or `"dob-mpc"`.
    pub controller: String,
    /// Payload the controller does not know (kg).
    pub payload_kg: f64,
    /// RMS joint error per joint over the whole run (rad).
    pub joint_error_rms_rad: Vec<f64>,
    /// Maximum absolute joint error per joint (rad).
    pub joint_error_max_rad: Vec<f64>,
    /// Maximum absolute joint error per joint over the last 0.5 s of the hold (rad).
    pub steady_joint_error_max_rad: Vec<f64>,
    /// RMS of the Cartesian error norm (mm).
    pub cartesian_error_rms_mm: f64,
    /// Maximum Cartesian error norm (mm).
    pub cartesian_error_max_mm: f64,
    /// Maximum Cartesian error norm over the last 0.5 s of the hold (mm).
    pub steady_cartesian_error_mm: f64,
    /// RMS of the Cartesian error norm up to the stop (mm): for a run brought to a safe stop
    /// (status `stopped` or `failed_stop`) over the samples up to the stop's time, as the
    /// record goes on while the robot brakes and the reference does not wait (the error
    /// after the stop is not a tracking error); for every other run the same as
    /// [`Self::cartesian_error_rms_mm`] (its record ends at its end or its stop).
    pub cartesian_error_rms_to_stop_mm: f64,
    /// Maximum Cartesian error norm up to the stop (mm), as
    /// [`Self::cartesian_error_rms_to_stop_mm`].
    pub cartesian_error_max_to_stop_mm: f64,
    /// Maximum absolute torque per joint (N·m).
    pub torque_max_nm: Vec<f64>,
    /// Controller step time.
    pub step_time_us: StepTime,
    /// Wall time of the run (s).
    pub wall_s: f64,
    /// True when the run stopped because the joint error passed the threshold.
    pub diverged: bool,
    /// Time of the divergence (s), `None` when it did not diverge.
    pub diverged_at_s: Option<f64>,
    /// `"ok"`, `"diverged"`, `"failed"`, `"stopped"`, `"failed_stop"` or
    /// `"hunting"` ([`RunStatus`]).
    pub status: RunStatus,
    /// How the run ended, in words (the outcome's `Display`).
    pub reason: String,
    /// When the run was stopped early, diverged or failed (s).
    pub stopped_at_s: Option<f64>,
    /// The final payload mass identified online (kg); `None` (`null`) for
    /// controllers that do not identify it.
    pub payload_estimate_kg: Option<f64>,
    /// Samples whose measurement was missing, invalid or implausible (the
    /// controller ran on its prediction).
    pub faults: usize,
    /// Samples at which the commanded torque of some joint was at its limit.
    pub saturated_samples: usize,
    /// Largest `|τ_i| / τmax_i` of the commanded torque over joints and
    /// samples (0 without finite limits).
    pub max_torque_ratio: f64,
    /// Largest change of the applied torque between two samples,
    /// `max_{k,i} |τ_{k,i} − τ_{k−1,i}|` (N·m; NaN with fewer than two samples).
    pub torque_step_max_nm: f64,
    /// The hold's judgement on a plant with quantized encoders: the largest
    /// peak-to-peak, over the joints, of the measured joint error over the
    /// steady window, in encoder counts; above 2 the run is
    /// [`RunStatus::Hunting`] instead of `"ok"`. `None` (`null`) when not
    /// judged: no encoder quantization, or a run that did not complete.
    pub hold_error_pp_counts: Option<f64>,
    /// The largest joint error over the pre-roll at rest before the record
    /// starts (rad, over joints and samples at `t < 0`): an adaptive
    /// kind's identification or another kind's settling
    /// (`LoopSettings::settle_s`); 0 without a pre-roll.
    pub pre_roll_peak_joint_rad: f64,
    /// What the servo interface saw (`[plant.servo]`: cycles, missed
    /// cycles, the longest run of them, `"ok"` or `"watchdog_trip"`);
    /// absent without one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub servo: Option<super::servo::ServoReport>,
    /// The loop's telemetry: QP iterations, model and loop times (p50,
    /// p99, max), loop deadline misses, steps per fallback level, budget
    /// hits.
    pub telemetry: TelemetryMetrics,
}

/// A hold whose measured joint error moves by more than this many encoder
/// counts peak-to-peak over the steady window hunts ([`RunStatus::Hunting`]).
pub(crate) const HOLD_HUNTING_COUNTS: f64 = 2.0;

/// Rounding allowance of the judgement: a quantized measurement moves by a
/// whole number of counts, but `q_ref − q_meas` over radians carries the
/// rounding of the subtraction (2 counts came out 2.0000000000153, judged
/// "more than 2").
const HOLD_COUNTS_ROUNDING: f64 = 1e-6;

/// The largest peak-to-peak over the joints of the measured joint error
/// (`q_ref − q_meas`, the true `q` when no measurement was recorded) over the
/// record's last `steady_window` s, in counts of an encoder with
/// `encoder_counts` per turn; `None` without encoder or steady samples.
/// Samples whose measurement is missing (NaN) are left out.
pub(crate) fn hold_error_pp_counts(
    rec: &Record,
    steady_window: f64,
    encoder_counts: u64,
) -> Option<f64> {
    let (n, len) = (rec.n, rec.len());
    let t_end = *rec.t.last()?;
    if encoder_counts == 0 || n == 0 {
        return None;
    }
    let from = rec
        .t
        .iter()
        .position(|&t| t >= t_end - steady_window + 1e-9)?;
    let measured = rec.q_meas.len() == len * n;
    let count = std::f64::consts::TAU / encoder_counts as f64;
    (0..n)
        .map(|i| {
            let (lo, hi) = (from..len)
                .map(|k| {
                    let q = if measured {
                        rec.q_meas[k * n + i]
                    } else {
                        rec.q[k * n + i]
                    };
                    rec.q_ref[k * n + i] - q
                })
                .filter(|e| e.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), e| {
                    (lo.min(e), hi.max(e))
                });
            if hi >= lo {
                (hi - lo) / count
            } else {
                0.0
            }
        })
        .reduce(f64::max)
}

/// Judges the hold of a completed run on a plant with `encoder_counts`
/// (0: an ideal encoder, nothing judged): records the peak-to-peak in
/// [`RunMetrics::hold_error_pp_counts`] and turns `"ok"` into
/// [`RunStatus::Hunting`] above [`HOLD_HUNTING_COUNTS`], saying which
/// joint in [`RunMetrics::reason`].
pub(crate) fn judge_hold(
    m: &mut RunMetrics,
    rec: &Record,
    steady_window: f64,
    encoder_counts: u64,
) {
    if m.status != RunStatus::Ok {
        return;
    }
    m.hold_error_pp_counts = hold_error_pp_counts(rec, steady_window, encoder_counts);
    if let Some(pp) = m
        .hold_error_pp_counts
        .filter(|&pp| pp > HOLD_HUNTING_COUNTS + HOLD_COUNTS_ROUNDING)
    {
        m.status = RunStatus::Hunting;
        m.reason = format!(
            "{}, but the hold did not settle: the measured joint error moved by {pp:.1} \
             encoder counts peak-to-peak over the last {steady_window} s (more than \
             {HOLD_HUNTING_COUNTS})",
            m.reason
        );
    }
}

/// Median, 99th percentile and maximum of `v` (NaN when empty).
pub fn percentiles(v: &[f64]) -> Percentiles {
    Percentiles {
        p50: quantile(v, 0.5),
        p99: quantile(v, 0.99),
        max: v.iter().copied().fold(f64::NAN, f64::max),
    }
}

/// The telemetry summary of `t` for a loop of sampling period `ts` (s).
pub fn telemetry_metrics(t: &LoopTelemetry, ts: f64) -> TelemetryMetrics {
    let f = t.fallback_steps;
    TelemetryMetrics {
        qp_iterations: percentiles(&t.qp_iterations),
        model_time_us: percentiles(&t.model_us),
        controller_time_us: percentiles(&t.controller_us),
        loop_time_us: percentiles(&t.loop_us),
        loop_deadline_misses: deadline_misses(&t.loop_us, ts),
        fallback_steps: FallbackCounts {
            none: f[0],
            best_feasible: f[1],
            shifted_plan: f[2],
            hold: f[3],
        },
        budget_hits: t.budget_hits,
    }
}

/// The `p`-quantile (0..1) of `v` by linear interpolation (NaN when empty).
pub fn quantile(v: &[f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_by(f64::total_cmp);
    let pos = p.clamp(0.0, 1.0) * (s.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    s[lo] + (s[hi] - s[lo]) * (pos - lo as f64)
}

/// The sampling period of a record: the spacing of its first two sample
/// times (NaN with fewer than two samples).
fn sample_period(t: &[f64]) -> f64 {
    match t {
        [t0, t1, ..] => t1 - t0,
        _ => f64::NAN,
    }
}

/// Computes the metrics of a record. `steady_window` (s) is the final window
/// ("steady": the last 0.5 s of the hold).
pub fn compute(
    name: &str,
    controller: &str,
    payload_kg: f64,
    rec: &Record,
    steady_window: f64,
    wall_s: f64,
    outcome: &RunOutcome,
) -> RunMetrics {
    let n = rec.n;
    let len = rec.len();
    let t_end = rec.t.last().copied().unwrap_or(0.0);
    let steady_from = rec
        .t
        .iter()
        .position(|&t| t >= t_end - steady_window + 1e-9)
        .unwrap_or(len);
    // A safe stop: the samples after its time brake and hold (`*_to_stop_mm`).
    let to_stop = match outcome {
        RunOutcome::Stopped { t: stop, .. } => {
            rec.t.iter().position(|&t| t > stop + 1e-9).unwrap_or(len)
        }
        _ => len,
    };
    let (mut c_sq_stop, mut c_max_stop) = (0.0, 0.0f64);
    let mut rms = vec![0.0; n];
    let mut max = vec![0.0f64; n];
    let mut steady = vec![0.0f64; n];
    let mut tmax = vec![0.0f64; n];
    let (mut c_sq, mut c_max, mut c_steady) = (0.0, 0.0f64, 0.0f64);
    for k in 0..len {
        for i in 0..n {
            let e = rec.joint_error(k, i);
            rms[i] += e * e;
            max[i] = max[i].max(e.abs());
            if k >= steady_from {
                steady[i] = steady[i].max(e.abs());
            }
            tmax[i] = tmax[i].max(rec.tau[k * n + i].abs());
        }
        let c = rec.cartesian_error(k);
        let norm = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() * 1e3;
        c_sq += norm * norm;
        c_max = c_max.max(norm);
        if k < to_stop {
            c_sq_stop += norm * norm;
            c_max_stop = c_max_stop.max(norm);
        }
        if k >= steady_from {
            c_steady = c_steady.max(norm);
        }
    }
    let torque_step = (1..len)
        .flat_map(|k| (0..n).map(move |i| (k, i)))
        .map(|(k, i)| (rec.tau[k * n + i] - rec.tau[(k - 1) * n + i]).abs())
        .fold(if len < 2 { f64::NAN } else { 0.0 }, f64::max);
    let status = outcome.status();
    let stopped = status != RunStatus::Ok;
    // Nothing recorded: no metric exists.
    let recorded = |v: f64| if len == 0 { f64::NAN } else { v };
    let denom = len.max(1) as f64;
    let steady_or_nan = |v: f64| {
        if stopped || steady_from >= len {
            f64::NAN
        } else {
            v
        }
    };
    RunMetrics {
        name: name.to_string(),
        controller: controller.to_string(),
        payload_kg,
        joint_error_rms_rad: rms.iter().map(|s| recorded((s / denom).sqrt())).collect(),
        joint_error_max_rad: max.into_iter().map(recorded).collect(),
        steady_joint_error_max_rad: steady.into_iter().map(steady_or_nan).collect(),
        cartesian_error_rms_mm: recorded((c_sq / denom).sqrt()),
        cartesian_error_max_mm: recorded(c_max),
        steady_cartesian_error_mm: steady_or_nan(c_steady),
        cartesian_error_rms_to_stop_mm: if to_stop == 0 {
            f64::NAN
        } else {
            (c_sq_stop / to_stop as f64).sqrt()
        },
        cartesian_error_max_to_stop_mm: if to_stop == 0 { f64::NAN } else { c_max_stop },
        torque_max_nm: tmax.into_iter().map(recorded).collect(),
        step_time_us: StepTime {
            median: quantile(&rec.step_us, 0.5),
            p99: quantile(&rec.step_us, 0.99),
            max: rec.step_us.iter().copied().fold(f64::NAN, f64::max),
            deadline_misses: deadline_misses(&rec.step_us, sample_period(&rec.t)),
        },
        wall_s,
        diverged: status == RunStatus::Diverged,
        diverged_at_s: match outcome {
            RunOutcome::Diverged { t, .. } => Some(*t),
            _ => None,
        },
        status,
        reason: outcome.to_string(),
        stopped_at_s: outcome.stopped_at(),
        payload_estimate_kg: rec.payload_mass_est.last().copied(),
        faults: rec.faults,
        saturated_samples: rec.saturated_samples,
        max_torque_ratio: rec.max_torque_ratio,
        torque_step_max_nm: torque_step,
        hold_error_pp_counts: None,
        pre_roll_peak_joint_rad: 0.0,
        servo: rec.servo,
        telemetry: telemetry_metrics(&rec.telemetry, sample_period(&rec.t)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_of_a_known_record() {
        // One joint, error 1 rad for t < 1 s then 0.1 rad; Cartesian error 3-4-0 mm.
        let mut r = Record::with_capacity(1, 200);
        for k in 0..200 {
            let t = k as f64 * 0.01;
            r.t.push(t);
            r.q.push(0.0);
            r.qd.push(0.0);
            r.q_ref.push(if t < 1.0 { 1.0 } else { 0.1 });
            r.tau.push(-(k as f64));
            r.flange.push([0.0; 3]);
            r.flange_ref.push([0.003, 0.004, 0.0]);
            r.step_us.push(k as f64);
        }
        let m = compute("x", "first", 0.25, &r, 0.5, 1.0, &RunOutcome::Completed);
        let rms = ((100.0 * 1.0 + 100.0 * 0.01) / 200.0f64).sqrt();
        assert!((m.joint_error_rms_rad[0] - rms).abs() < 1e-12);
        assert_eq!(m.joint_error_max_rad[0], 1.0);
        assert!((m.steady_joint_error_max_rad[0] - 0.1).abs() < 1e-15);
        assert!((m.cartesian_error_rms_mm - 5.0).abs() < 1e-9);
        assert!((m.steady_cartesian_error_mm - 5.0).abs() < 1e-9);
        assert_eq!(m.torque_max_nm[0], 199.0);
        assert_eq!(m.torque_step_max_nm, 1.0);
        assert!((m.step_time_us.median - 99.5).abs() < 1e-12);
        assert_eq!(m.step_time_us.max, 199.0);
        // Ts = 10 ms = 10_000 µs: no step time of 0..199 µs misses it.
        assert_eq!(m.step_time_us.deadline_misses, 0);
        let outcome = RunOutcome::Diverged {
            t: 1.5,
            joint: 0,
            error_rad: 0.3,
            threshold_rad: 0.2,
            rule: crate::sim::DivergenceRule::Threshold,
        };
        let d = compute("x", "first", 0.25, &r, 0.5, 1.0, &outcome);
        assert!(d.diverged && d.steady_cartesian_error_mm.is_nan());
        assert_eq!(
            (d.status, d.diverged_at_s),
            (RunStatus::Diverged, Some(1.5))
        );
        assert!(d.reason.contains("joint 1"), "{}", d.reason);
        assert!(d.cartesian_error_rms_mm.is_finite());
        // A run that is not stopped safely: up to the stop is the whole record.
        for m in [&m, &d] {
            assert_eq!(m.cartesian_error_rms_to_stop_mm, m.cartesian_error_rms_mm);
            assert_eq!(m.cartesian_error_max_to_stop_mm, m.cartesian_error_max_mm);
        }
    }

    #[test]
    fn a_safe_stop_ends_the_error_statistics_at_its_time() {
        // Error 1 mm up to t = 0.5 s (the stop), 300 mm after (the robot brakes, the
        // reference goes on).
        let mut r = Record::with_capacity(1, 100);
        for k in 0..100 {
            let t = k as f64 * 0.01;
            r.t.push(t);
            r.q.push(0.0);
            r.qd.push(0.0);
            r.q_ref.push(0.0);
            r.tau.push(0.0);
            r.flange.push([0.0; 3]);
            r.flange_ref
                .push([if t <= 0.5 + 1e-12 { 0.001 } else { 0.3 }, 0.0, 0.0]);
            r.step_us.push(1.0);
        }
        let stopped = RunOutcome::Stopped {
            final_speed: 0.0,
            t: 0.5,
            reason: super::super::supervisor::StopReason::Diverged {
                joint: 0,
                error_rad: 0.3,
            },
            at_rest_after_s: Some(0.1),
            within_limits: true,
        };
        let m = compute("x", "first", 0.0, &r, 0.1, 1.0, &stopped);
        assert_eq!(m.status, RunStatus::Stopped);
        assert!((m.cartesian_error_max_to_stop_mm - 1.0).abs() < 1e-9);
        assert!((m.cartesian_error_rms_to_stop_mm - 1.0).abs() < 1e-9);
        // The whole record's statistics keep their meaning.
        assert!((m.cartesian_error_max_mm - 300.0).abs() < 1e-9);
        let rms = ((51.0 * 1.0 + 49.0 * 300.0 * 300.0) / 100.0f64).sqrt();
        assert!((m.cartesian_error_rms_mm - rms).abs() < 1e-9);
    }

    #[test]
    fn metrics_of_an_empty_record_do_not_exist() {
        let r = Record::with_capacity(2, 0);
        let outcome = RunOutcome::Failed {
            t: 0.0,
            cause: super::super::outcome::RunFailure::NonFiniteError { joint: 1 },
        };
        let m = compute("x", "second", 1.0, &r, 0.5, 0.0, &outcome);
        assert_eq!(m.status, RunStatus::Failed);
        assert!(!m.diverged && m.diverged_at_s.is_none());
        assert_eq!(m.stopped_at_s, Some(0.0));
        for v in [
            m.cartesian_error_rms_mm,
            m.cartesian_error_max_mm,
            m.steady_cartesian_error_mm,
        ] {
            assert!(v.is_nan(), "{v}");
        }
        for v in m
            .joint_error_rms_rad
            .iter()
            .chain(&m.joint_error_max_rad)
            .chain(&m.torque_max_nm)
        {
            assert!(v.is_nan(), "{v}");
        }
    }

    /// One joint held at rest for 1 s (Ts = 10 ms) whose measured error is
    /// `e(t)`; the metrics of the completed run on a 20-bit encoder.
    fn hold(e: impl Fn(f64) -> f64, encoder_counts: u64) -> RunMetrics {
        let mut r = Record::with_capacity(1, 100);
        for k in 0..100 {
            let t = k as f64 * 0.01;
            r.t.push(t);
            r.q.push(0.0);
            r.qd.push(0.0);
            r.q_meas.push(-e(t));
            r.qd_meas.push(0.0);
            r.q_ref.push(0.0);
            r.tau.push(0.0);
            r.flange.push([0.0; 3]);
            r.flange_ref.push([0.0; 3]);
            r.step_us.push(1.0);
        }
        let mut m = compute("x", "second", 2.0, &r, 0.5, 1.0, &RunOutcome::Completed);
        judge_hold(&mut m, &r, 0.5, encoder_counts);
        m
    }

    #[test]
    fn a_hold_that_hunts_or_drifts_is_not_ok_and_one_that_settles_is() {
        let count = std::f64::consts::TAU / 1_048_576.0;
        // A ±3-count limit cycle of 0.35 s (as the wrist's on the real-arm preset).
        let hunts = hold(
            |t| 3.0 * count * (t * std::f64::consts::TAU / 0.35).sin(),
            1 << 20,
        );
        assert_eq!(hunts.status, RunStatus::Hunting, "{}", hunts.reason);
        let pp = hunts.hold_error_pp_counts.unwrap();
        assert!(pp > 5.0 && pp <= 6.0, "{pp}");
        assert!(hunts.reason.contains("did not settle"), "{}", hunts.reason);
        // The steady metrics stay those of a completed run.
        assert!(hunts.steady_joint_error_max_rad[0].is_finite());
        // An error that grows by 3 counts over the steady window.
        let drifts = hold(|t| 6.0 * count * t, 1 << 20);
        assert_eq!(drifts.status, RunStatus::Hunting);
        // Settled within one count (a constant offset and quantization flicker): ok.
        let settles = hold(|t| count * (5.0 + f64::from(u8::from(t > 0.7))), 1 << 20);
        assert_eq!(settles.status, RunStatus::Ok, "{}", settles.reason);
        assert_eq!(settles.hold_error_pp_counts, Some(1.0));
        // Exactly 2 counts is the limit, still ok.
        let two = hold(|t| count * 2.0 * f64::from(u8::from(t > 0.9)), 1 << 20);
        assert_eq!(two.status, RunStatus::Ok);
        // ... also where the subtraction rounds (2 counts came out 2 + 1.5e-11).
        let off = hold(
            |t| 0.3 + count * 2.0 * f64::from(u8::from(t > 0.9)),
            1 << 20,
        );
        let pp = off.hold_error_pp_counts.unwrap();
        assert!((pp - 2.0).abs() < 1e-9, "{pp}");
        assert_eq!(off.status, RunStatus::Ok, "{}", off.reason);
        // Three counts still hunt.
        let three = hold(
            |t| 0.3 + count * 3.0 * f64::from(u8::from(t > 0.9)),
            1 << 20,
        );
        assert_eq!(three.status, RunStatus::Hunting);
        // No encoder (an ideal plant): not judged, whatever the hold does.
        let ideal = hold(|t| 1e-3 * (t * 40.0).sin(), 0);
        assert_eq!(
            (ideal.status, ideal.hold_error_pp_counts),
            (RunStatus::Ok, None)
        );
        // Coarser encoders: the same motion is within 2 counts of a 12-bit one.
        let coarse = hold(
            |t| 3.0 * count * (t * std::f64::consts::TAU / 0.35).sin(),
            1 << 12,
        );
        assert_eq!(coarse.status, RunStatus::Ok);
    }

    #[test]
    fn a_run_that_did_not_complete_is_not_judged() {
        let mut r = Record::with_capacity(1, 10);
        for k in 0..10 {
            r.t.push(k as f64 * 0.01);
            r.q.push(0.0);
            r.qd.push(0.0);
            r.q_ref.push(if k % 2 == 0 { 1.0 } else { -1.0 });
            r.tau.push(0.0);
            r.flange.push([0.0; 3]);
            r.flange_ref.push([0.0; 3]);
            r.step_us.push(1.0);
        }
        let outcome = RunOutcome::Diverged {
            t: 0.09,
            joint: 0,
            error_rad: 1.0,
            threshold_rad: 0.2,
            rule: crate::sim::DivergenceRule::Threshold,
        };
        let mut m = compute("x", "first", 0.0, &r, 0.05, 1.0, &outcome);
        judge_hold(&mut m, &r, 0.05, 1 << 20);
        assert_eq!(
            (m.status, m.hold_error_pp_counts),
            (RunStatus::Diverged, None)
        );
        // Without a measurement column the true position is judged.
        let mut m = compute("x", "first", 0.0, &r, 0.05, 1.0, &RunOutcome::Completed);
        judge_hold(&mut m, &r, 0.05, 1 << 20);
        assert_eq!(m.status, RunStatus::Hunting);
    }
}
