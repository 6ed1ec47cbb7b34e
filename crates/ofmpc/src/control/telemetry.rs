//! Per-step telemetry of the built [`Controller`](crate::control::Controller):
//! where the step's time went, what the torque-limit QP did and which
//! fallback the step took. A plain `Copy` record, written by every step
//! into [`StepOutput::telemetry`](crate::control::StepOutput::telemetry)
//! (three clock reads per step; nothing allocated).

use std::time::Duration;

/// Which answer a step returned, from the optimum down to the safe hold
/// (the order in which a step falls back).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum FallbackLevel {
    /// The algorithm's optimum (with torque limits, the QP's).
    #[default]
    None,
    /// The torque-limit QP stopped early (its iteration cap or the step
    /// budget): the best feasible answer found so far (with no iteration:
    /// the unconstrained torque clamped into the limits).
    BestFeasible,
    /// The step budget ran out before the QP could iterate: the last
    /// complete plan, one sample on (at most one such step in a row; the
    /// next solves the QP past its budget), within the limits.
    ShiftedPlan,
    /// The safe hold: the last torque held, on a numerical failure of the
    /// step ([`crate::control::StepStatus::HeldLastTorque`]).
    Hold,
}

impl FallbackLevel {
    /// Every level, in fallback order.
    pub const ALL: [FallbackLevel; 4] = [
        FallbackLevel::None,
        FallbackLevel::BestFeasible,
        FallbackLevel::ShiftedPlan,
        FallbackLevel::Hold,
    ];

    /// Position in [`FallbackLevel::ALL`] (0 = optimum).
    pub fn index(self) -> usize {
        match self {
            FallbackLevel::None => 0,
            FallbackLevel::BestFeasible => 1,
            FallbackLevel::ShiftedPlan => 2,
            FallbackLevel::Hold => 3,
        }
    }

    /// Short name (`"none"`, `"best_feasible"`, `"shifted_plan"`, `"hold"`).
    pub fn name(self) -> &'static str {
        match self {
            FallbackLevel::None => "none",
            FallbackLevel::BestFeasible => "best_feasible",
            FallbackLevel::ShiftedPlan => "shifted_plan",
            FallbackLevel::Hold => "hold",
        }
    }
}

/// Telemetry of one [`Controller::step`](crate::control::Controller::step).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepTelemetry {
    /// Time spent on the model: the robot's terms at the state, `f0`, the
    /// ZOH discretization and the prediction matrices (zero for the
    /// baselines, which do not time it).
    pub model_time: Duration,
    /// Time of the algorithm's step (model, solve, QP and torque), without
    /// the input checks and the observer.
    pub solve_time: Duration,
    /// Wall time of the whole call (checks, observer, algorithm, output);
    /// the same as [`StepOutput::solve_time`](crate::control::StepOutput::solve_time).
    pub total_time: Duration,
    /// Active-set iterations of the torque-limit QP (0 when it did not run).
    pub qp_iterations: u32,
    /// Box constraints active at the QP's answer (0 when it did not run).
    pub active_constraints: u32,
    /// Budget left at the end of the step (µs; negative: over budget),
    /// `None` without a step budget.
    pub budget_slack_us: Option<f64>,
    /// Which answer the step returned.
    pub fallback: FallbackLevel,
    /// The step budget ran out in the torque-limit QP (the answer is a
    /// fallback: [`FallbackLevel::BestFeasible`] or
    /// [`FallbackLevel::ShiftedPlan`]).
    pub budget_hit: bool,
}
