//! The step telemetry ([`ofmpc::StepTelemetry`]) through the C API: a getter
//! per controller handle, filled from the last step, allocation-free.

use crate::controller::ofmpc_controller;
use crate::ffi::*;
use crate::supervised::ofmpc_supervised;
use ofmpc::control::{FallbackLevel, StepTelemetry};
use std::mem::size_of;

/// Which answer a step returned (the library's `FallbackLevel`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ofmpc_fallback_level {
    /// The algorithm's optimum.
    OFMPC_FALLBACK_NONE = 0,
    /// The torque-limit QP stopped early (iteration cap or step budget): its
    /// best feasible answer so far.
    OFMPC_FALLBACK_BEST_FEASIBLE = 1,
    /// The step budget ran out before the QP could iterate: the last plan,
    /// one sample on.
    OFMPC_FALLBACK_SHIFTED_PLAN = 2,
    /// A numerical failure: the last torque held.
    OFMPC_FALLBACK_HOLD = 3,
}

/// Telemetry of the last step. The caller sets `size`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ofmpc_step_telemetry {
    /// `sizeof(ofmpc_step_telemetry)`: fields past it are not written.
    pub size: usize,
    /// Time on the model: terms, ZOH, prediction matrices (ns; 0 for the
    /// baselines).
    pub model_time_ns: u64,
    /// Time of the algorithm's step (ns).
    pub solve_time_ns: u64,
    /// Wall time of the whole step call (ns).
    pub total_time_ns: u64,
    /// Active-set iterations of the torque-limit QP (0 when it did not run).
    pub qp_iterations: u32,
    /// Box constraints active at the QP's answer.
    pub active_constraints: u32,
    /// Budget left at the end of the step (µs; negative: over); NaN without
    /// `[mpc] step_budget_us`.
    pub budget_slack_us: f64,
    /// Which answer the step returned.
    pub fallback: ofmpc_fallback_level,
    /// 1 when the step budget ran out in the QP, else 0.
    pub budget_hit: u8,
}

/// The size of the first version of [`ofmpc_step_telemetry`].
const TELEMETRY_V1: usize = size_of::<ofmpc_step_telemetry>();

fn ns(d: std::time::Duration) -> u64 {
    u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
}

/// The library's telemetry into the C record.
fn write(t: &StepTelemetry, out: &mut ofmpc_step_telemetry) -> Res {
    check_record(out.size, TELEMETRY_V1, "ofmpc_step_telemetry")?;
    out.model_time_ns = ns(t.model_time);
    out.solve_time_ns = ns(t.solve_time);
    out.total_time_ns = ns(t.total_time);
    out.qp_iterations = t.qp_iterations;
    out.active_constraints = t.active_constraints;
    out.budget_slack_us = t.budget_slack_us.unwrap_or(f64::NAN);
    out.fallback = match t.fallback {
        FallbackLevel::None => ofmpc_fallback_level::OFMPC_FALLBACK_NONE,
        FallbackLevel::BestFeasible => ofmpc_fallback_level::OFMPC_FALLBACK_BEST_FEASIBLE,
        FallbackLevel::ShiftedPlan => ofmpc_fallback_level::OFMPC_FALLBACK_SHIFTED_PLAN,
        _ => ofmpc_fallback_level::OFMPC_FALLBACK_HOLD,
    };
    out.budget_hit = u8::from(t.budget_hit);
    Ok(())
}

/// The telemetry of the controller's last step (zeros before the first).
/// Allocates nothing; `OFMPC_NULL_ARG` / `OFMPC_INVALID_ARG` (size) and
/// nothing written otherwise.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_controller_telemetry(
    c: *const ofmpc_controller,
    out: *mut ofmpc_step_telemetry,
) -> ofmpc_status {
    boundary(|| {
        let c = &unsafe { arg(c, "controller") }?.0;
        let out = unsafe { arg_mut(out, "out") }?;
        write(&c.output().telemetry, out)
    })
}

/// The telemetry of the guarded controller's last step (its last call of
/// the controller: during a safe stop the stop law runs instead).
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_supervised_telemetry(
    s: *const ofmpc_supervised,
    out: *mut ofmpc_step_telemetry,
) -> ofmpc_status {
    boundary(|| {
        let s = &unsafe { arg(s, "supervised") }?.0;
        let out = unsafe { arg_mut(out, "out") }?;
        write(&s.diagnostics().telemetry, out)
    })
}
