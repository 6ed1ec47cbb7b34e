//! The loop's telemetry: per sample, the controller's QP iterations, model
//! time and fallback level and the loop's own iteration time (sized at the
//! start of the run: recording allocates nothing), and their summary in
//! `metrics.json` ([`TelemetryMetrics`], computed by
//! [`telemetry_metrics`](crate::sim::telemetry_metrics)).

use serde::Serialize;

use crate::control::{FallbackLevel, QpStatus, StepOutput};

/// Per-sample telemetry of a run, beside the [`super::Record`].
#[derive(Debug, Clone, Default)]
pub struct LoopTelemetry {
    /// Active-set iterations of the torque-limit QP per sample (0: it did
    /// not run).
    pub qp_iterations: Vec<f64>,
    /// Time the controller spent on its model per sample (µs; 0 when the
    /// controller does not time it).
    pub model_us: Vec<f64>,
    /// Wall time of each whole loop iteration (µs): sensor, controller,
    /// actuator, plant and record. In a real-time loop this is the time it
    /// needs of its period.
    pub loop_us: Vec<f64>,
    /// Wall time of the controller's own step per sample
    /// ([`crate::control::StepTelemetry::total_time`], µs; 0 when the loop
    /// did not step it).
    pub controller_us: Vec<f64>,
    /// Steps per [`FallbackLevel`] (indexed by [`FallbackLevel::index`]).
    pub fallback_steps: [usize; 4],
    /// Steps that ran out of their step budget.
    pub budget_hits: usize,
}

/// One sample's telemetry, as the loop hands it to the recorder.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TelemetrySample {
    /// What the QP did (`None`: no QP).
    pub qp: Option<QpStatus>,
    /// The step budget ran out.
    pub budget_hit: bool,
    /// The controller's model time (µs).
    pub model_us: f64,
    /// The controller's whole step (µs).
    pub total_us: f64,
    /// Which answer the step returned.
    pub fallback: FallbackLevel,
}

impl TelemetrySample {
    /// What the controller's last step did, from its output (`None`: the
    /// loop did not step the controller this sample, e.g. during a safe
    /// stop).
    pub fn of(step: Option<&StepOutput>) -> Self {
        let Some(out) = step else {
            return Self {
                qp: None,
                budget_hit: false,
                model_us: 0.0,
                total_us: 0.0,
                fallback: FallbackLevel::None,
            };
        };
        let t = &out.telemetry;
        let held = t.fallback == FallbackLevel::Hold;
        Self {
            qp: out.qp_status.filter(|_| !held),
            budget_hit: t.budget_hit,
            model_us: t.model_time.as_secs_f64() * 1e6,
            total_us: t.total_time.as_secs_f64() * 1e6,
            fallback: t.fallback,
        }
    }
}

impl LoopTelemetry {
    /// Room for `capacity` samples.
    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            qp_iterations: Vec::with_capacity(capacity),
            model_us: Vec::with_capacity(capacity),
            loop_us: Vec::with_capacity(capacity),
            controller_us: Vec::with_capacity(capacity),
            ..Self::default()
        }
    }

    /// Appends one controller step.
    pub(crate) fn push(&mut self, s: &TelemetrySample) {
        self.budget_hits += usize::from(s.budget_hit);
        self.qp_iterations
            .push(s.qp.map_or(0.0, |q| f64::from(q.iterations)));
        self.model_us.push(s.model_us);
        self.controller_us.push(s.total_us);
        self.fallback_steps[s.fallback.index()] += 1;
    }

    /// Appends one loop iteration's wall time (µs).
    pub fn push_loop(&mut self, us: f64) {
        self.loop_us.push(us);
    }
}

/// Median, 99th percentile and maximum of a per-sample quantity (NaN, shown
/// as `null`, when nothing was recorded).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Percentiles {
    /// Median.
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Maximum.
    pub max: f64,
}

impl Default for Percentiles {
    fn default() -> Self {
        Self {
            p50: f64::NAN,
            p99: f64::NAN,
            max: f64::NAN,
        }
    }
}

/// Steps per fallback level, as in `metrics.json`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct FallbackCounts {
    /// The optimum.
    pub none: usize,
    /// The QP's best feasible answer (iteration cap or budget).
    pub best_feasible: usize,
    /// The previous plan, shifted.
    pub shifted_plan: usize,
    /// The last torque held.
    pub hold: usize,
}

/// The telemetry summary of a run (`metrics.json`'s `telemetry`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct TelemetryMetrics {
    /// QP iterations per step.
    pub qp_iterations: Percentiles,
    /// The controller's model time per step (µs).
    pub model_time_us: Percentiles,
    /// The controller's own step time (µs; without the loop's guard and
    /// recording, which `step_time_us` includes).
    pub controller_time_us: Percentiles,
    /// Wall time of one whole loop iteration (µs).
    pub loop_time_us: Percentiles,
    /// Loop iterations longer than the sampling period.
    pub loop_deadline_misses: usize,
    /// Steps per fallback level.
    pub fallback_steps: FallbackCounts,
    /// Steps that ran out of their step budget.
    pub budget_hits: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_counts_levels_and_misses() {
        let mut t = LoopTelemetry::with_capacity(4);
        for (i, level) in FallbackLevel::ALL.iter().enumerate() {
            t.push(&TelemetrySample {
                qp: Some(QpStatus {
                    iterations: i as u32,
                    ..QpStatus::default()
                }),
                model_us: 1.0,
                total_us: 2.0,
                budget_hit: false,
                fallback: *level,
            });
            t.push_loop(if i == 3 { 2000.0 } else { 10.0 });
        }
        let m = crate::sim::metrics::telemetry_metrics(&t, 1e-3);
        assert_eq!(m.qp_iterations.max, 3.0);
        assert_eq!(m.loop_deadline_misses, 1);
        assert_eq!(
            m.fallback_steps,
            FallbackCounts {
                none: 1,
                best_feasible: 1,
                shifted_plan: 1,
                hold: 1
            }
        );
        assert_eq!(m.loop_time_us.max, 2000.0);
    }
}
