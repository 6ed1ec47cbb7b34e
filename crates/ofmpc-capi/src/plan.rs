//! The plan handle: a G-code text planned into a joint reference.

use crate::ffi::*;
use crate::robot::ofmpc_robot;
use crate::settings::chain;
use ofmpc::{plan, JointReference, PlanOptions};
use std::ffi::c_char;

/// A joint reference sampled every `ts` (s), with its preview. Opaque.
pub struct ofmpc_plan(pub(crate) JointReference);

/// Plans the G-code `gcode` for `robot` (blended, timed with the scenario's
/// default `[timing]`, mapped to joints by IK) sampled every `ts` seconds.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_plan_new(
    robot: *const ofmpc_robot,
    gcode: *const c_char,
    ts: f64,
    out: *mut *mut ofmpc_plan,
) -> ofmpc_status {
    boundary(|| {
        let robot = unsafe { arg(robot, "robot") }?;
        let gcode = unsafe { text(gcode, "gcode") }?;
        if out.is_null() {
            return Err(null("out"));
        }
        if !(ts.is_finite() && ts > 0.0) {
            return Err(Failure::new(
                ofmpc_status::OFMPC_INVALID_ARG,
                format!("ts = {ts}: the period must be a finite time > 0 s"),
            ));
        }
        let options = PlanOptions {
            ts,
            ..PlanOptions::default()
        };
        let planned = plan(gcode, &robot.0, &options).map_err(|e| {
            Failure::new(ofmpc_status::OFMPC_PARSE, format!("G-code: {}", chain(&e)))
        })?;
        unsafe { give(out, ofmpc_plan(planned.reference)) };
        Ok(())
    })
}

/// Number of samples of the path (0 for NULL).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_plan_len(plan: *const ofmpc_plan) -> usize {
    query(0, || unsafe { plan.as_ref() }.map(|p| p.0.len()))
}

/// Number of joints (0 for NULL).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_plan_dof(plan: *const ofmpc_plan) -> usize {
    query(0, || unsafe { plan.as_ref() }.map(|p| p.0.dof()))
}

/// Sampling period (s; 0 for NULL).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_plan_ts(plan: *const ofmpc_plan) -> f64 {
    query(0.0, || unsafe { plan.as_ref() }.map(|p| p.0.ts()))
}

/// The reference `w_k` (n values) into `w`; past the end, the last point.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_plan_reference(
    plan: *const ofmpc_plan,
    k: usize,
    w: *mut f64,
    w_len: usize,
) -> ofmpc_status {
    boundary(|| {
        let p = &unsafe { arg(plan, "plan") }?.0;
        let w = unsafe { slice_mut(w, w_len, p.dof(), "w") }?;
        w.copy_from_slice(p.q(k));
        Ok(())
    })
}

/// The preview `w_{k+1} … w_{k+N}` (N·n values, `horizon` = N) into
/// `preview`; past the end, the last point. Allocates nothing.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_plan_preview(
    plan: *const ofmpc_plan,
    k: usize,
    horizon: usize,
    preview: *mut f64,
    preview_len: usize,
) -> ofmpc_status {
    boundary(|| {
        let p = &unsafe { arg(plan, "plan") }?.0;
        let expected = horizon.saturating_mul(p.dof());
        let out = unsafe { slice_mut(preview, preview_len, expected, "preview") }?;
        p.preview(k, horizon, out);
        Ok(())
    })
}

/// Frees a plan (NULL: nothing).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_plan_free(plan: *mut ofmpc_plan) {
    let _ = boundary(|| {
        unsafe { take(plan) };
        Ok(())
    });
}
