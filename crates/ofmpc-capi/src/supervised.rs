//! The supervised controller handle: wraps
//! [`ofmpc::sim::SupervisedController`] (measurement repair, plausibility,
//! safety limit, divergence rule and safe stop around the controller).

use crate::controller::{check_command_arrays, ofmpc_step_status, write_command_arrays};
use crate::ffi::*;
use crate::robot::ofmpc_robot;
use crate::settings::{build_controller, kind, Settings};
use crate::step_failure;
use ofmpc::sim::{SupervisedController, SupervisedError, SupervisedInput, SupervisedStatus};
use ofmpc::StepStatus;
use std::ffi::c_char;
use std::mem::size_of;

/// The controller behind its guard, for a real loop. Opaque.
pub struct ofmpc_supervised(pub(crate) SupervisedController);

/// One sample's raw reading and reference (borrowed by the call).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ofmpc_supervised_input {
    /// `sizeof(ofmpc_supervised_input)`.
    pub size: usize,
    /// Time of the sample (s): stamps a stop.
    pub t: f64,
    /// Raw reading `[q; q̇]`, 2n values (NaN where a value was lost).
    pub x: *const f64,
    /// Length of `x`.
    pub x_len: usize,
    /// Current reference `w_k`, n values.
    pub w: *const f64,
    /// Length of `w`.
    pub w_len: usize,
    /// Preview `w_{k+1} … w_{k+N}`, N·n values.
    pub preview: *const f64,
    /// Length of `preview`.
    pub preview_len: usize,
}

/// What the supervised controller did at one sample.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ofmpc_supervised_status {
    /// The controller's torque, on the reading as it came.
    OFMPC_SUPERVISED_CONTROLLED = 0,
    /// The controller's torque, on a repaired reading.
    OFMPC_SUPERVISED_REPAIRED_MEASUREMENT = 1,
    /// A safe stop is in progress (the stop law's torque).
    OFMPC_SUPERVISED_STOPPING = 2,
    /// The stop law holds the robot at rest.
    OFMPC_SUPERVISED_STOPPED = 3,
    /// The error diverged and no stop law is set: stop the robot.
    OFMPC_SUPERVISED_DIVERGED = 4,
}

/// What a supervised step produced. The caller owns `tau` and sets `size`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ofmpc_supervised_output {
    /// `sizeof(ofmpc_supervised_output)`: fields past it are not written.
    pub size: usize,
    /// The torque to command (n values, written by the step).
    pub tau: *mut f64,
    /// Length of `tau`.
    pub tau_len: usize,
    /// What produced the torque.
    pub status: ofmpc_supervised_status,
    /// The outcome of the controller's last step.
    pub step_status: ofmpc_step_status,
    /// With a position or velocity output (`[mpc] output`): the joint
    /// positions to command (n values; rad) — the controller's, predicted
    /// one lead time ahead, while it controls; during a safe stop
    /// (`OFMPC_SUPERVISED_STOPPING`, `OFMPC_SUPERVISED_STOPPED`) the stop
    /// law's braking trajectory one lead time ahead, decelerating to rest
    /// and then holding (send it: the controller's last command would leave
    /// the drive following a stale, moving target). Written when `size`
    /// covers the command fields and the pointer is not NULL (NULL: not
    /// asked for); zeros with a torque output.
    pub q_command: *mut f64,
    /// The velocities to command (n values; rad/s), as `q_command`.
    pub qd_command: *mut f64,
    /// The accelerations to command (n values; rad/s²: the feed-forward of
    /// the interface's joint loop), as `q_command`.
    pub qdd_command: *mut f64,
    /// Length of each non-NULL command array (n).
    pub command_len: usize,
    /// The torque feed-forward to command (n values; N·m): the
    /// controller's (`ofmpc_step_output::tau_command`), zeros during a safe
    /// stop, as `q_command` (length `command_len`). Written when `size`
    /// covers it.
    pub tau_command: *mut f64,
}

const INPUT_V1: usize = size_of::<ofmpc_supervised_input>();
/// The size of the first version of [`ofmpc_supervised_output`]: fields
/// appended later are written only when the caller's `size` covers them.
const OUTPUT_V1: usize = std::mem::offset_of!(ofmpc_supervised_output, q_command);
/// The size with the command (issue 37): `q_command` … `command_len`.
const OUTPUT_V2: usize = std::mem::offset_of!(ofmpc_supervised_output, tau_command);
/// The size with the command's torque feed-forward: `tau_command`.
const OUTPUT_V3: usize = size_of::<ofmpc_supervised_output>();

/// Builds the controller `kind_name` for `robot` from `settings_toml` (as
/// [`crate::ofmpc_controller_new`]) behind its guard, whose rules come from
/// the same text's `[simulation]` (plausibility_check, safe_stop,
/// divergence) and `[safety]` tables, at `[plant] delay_samples`.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_supervised_new(
    robot: *const ofmpc_robot,
    kind_name: *const c_char,
    settings_toml: *const c_char,
    out: *mut *mut ofmpc_supervised,
) -> ofmpc_status {
    boundary(|| {
        let robot = unsafe { arg(robot, "robot") }?;
        let kind = kind(unsafe { text(kind_name, "kind_name") }?)?;
        let s = Settings::parse(unsafe { opt_text(settings_toml, "settings_toml") }?)?;
        if out.is_null() {
            return Err(null("out"));
        }
        let c = build_controller(&robot.0, kind, &s)?;
        let rules = s.simulation.supervisor(&s.safety);
        let sc = SupervisedController::new(c, &robot.0, rules, s.plant.delay_samples, true)
            .map_err(|e| Failure::new(ofmpc_status::OFMPC_BUILD, e.to_string()))?;
        unsafe { give(out, ofmpc_supervised(sc)) };
        Ok(())
    })
}

/// The torque the drives applied over the period that just ended (n
/// values), for the controller's identification through an interface that
/// reports it (as `ofmpc_controller_set_applied_torque`); call it
/// before [`ofmpc_supervised_step`]. Allocates nothing.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_supervised_set_applied_torque(
    s: *mut ofmpc_supervised,
    tau: *const f64,
    tau_len: usize,
) -> ofmpc_status {
    boundary(|| {
        let s = &mut unsafe { arg_mut(s, "supervised") }?.0;
        let tau = unsafe { slice(tau, tau_len, s.controller().dof(), "tau") }?;
        s.set_applied_torque(tau).map_err(step_failure)
    })
}

/// Starts a run at the reading `x0` (2n values): no stop in progress.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_supervised_reset(
    s: *mut ofmpc_supervised,
    x0: *const f64,
    x0_len: usize,
) -> ofmpc_status {
    boundary(|| {
        let s = &mut unsafe { arg_mut(s, "supervised") }?.0;
        let x0 = unsafe { slice(x0, x0_len, 2 * s.controller().dof(), "x0") }?;
        s.reset(x0).map_err(supervised_failure)
    })
}

/// One supervised sample: the torque into `out->tau` and, when asked for,
/// the position command into `out->q_command` … (the controller's, or the
/// stop law's braking trajectory during a safe stop). Allocates nothing,
/// takes no lock. Not `OFMPC_OK`
/// only for bad input or a failed step no stop law takes over
/// (`OFMPC_NUMERIC`: stop the robot).
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_supervised_step(
    s: *mut ofmpc_supervised,
    input: *const ofmpc_supervised_input,
    out: *mut ofmpc_supervised_output,
) -> ofmpc_status {
    boundary(|| {
        let s = &mut unsafe { arg_mut(s, "supervised") }?.0;
        let input = unsafe { arg(input, "input") }?;
        let out = unsafe { arg_mut(out, "out") }?;
        check_record(input.size, INPUT_V1, "ofmpc_supervised_input")?;
        check_record(out.size, OUTPUT_V1, "ofmpc_supervised_output")?;
        let (n, horizon) = (s.controller().dof(), s.controller().horizon());
        let tau = unsafe { slice_mut(out.tau, out.tau_len, n, "out->tau") }?;
        let commands = [out.q_command, out.qd_command, out.qdd_command];
        let covered = out.size >= OUTPUT_V2;
        check_command_arrays(covered, &commands, out.command_len, n, "out->command_len")?;
        let covered_tau = out.size >= OUTPUT_V3;
        let tau_command = [out.tau_command];
        check_command_arrays(
            covered_tau,
            &tau_command,
            out.command_len,
            n,
            "out->command_len",
        )?;
        let x = unsafe { slice(input.x, input.x_len, 2 * n, "input->x") }?;
        let w = unsafe { slice(input.w, input.w_len, n, "input->w") }?;
        let p = unsafe {
            slice(
                input.preview,
                input.preview_len,
                horizon * n,
                "input->preview",
            )
        }?;
        let input = SupervisedInput {
            t: input.t,
            x,
            w_k: w,
            preview: p,
            truth: None,
        };
        let result = s.step(&input).map_err(supervised_failure)?;
        tau.copy_from_slice(&result.tau);
        out.status = supervised_status(result.status);
        out.step_status = match s.diagnostics().status {
            StepStatus::Solved => ofmpc_step_status::OFMPC_STEP_SOLVED,
            StepStatus::QpIterationCap { .. } => ofmpc_step_status::OFMPC_STEP_QP_ITERATION_CAP,
            _ => ofmpc_step_status::OFMPC_STEP_HELD_LAST_TORQUE,
        };
        let (q, qd, qdd) = s.command();
        // SAFETY: `check_command_arrays` checked the arrays' length.
        unsafe { write_command_arrays(covered, &commands, &[q, qd, qdd]) };
        // SAFETY: as above.
        unsafe { write_command_arrays(covered_tau, &tau_command, &[s.command_torque()]) };
        Ok(())
    })
}

fn supervised_status(s: SupervisedStatus) -> ofmpc_supervised_status {
    use ofmpc_supervised_status::*;
    match s {
        SupervisedStatus::Controlled => OFMPC_SUPERVISED_CONTROLLED,
        SupervisedStatus::RepairedMeasurement => OFMPC_SUPERVISED_REPAIRED_MEASUREMENT,
        SupervisedStatus::Stopping => OFMPC_SUPERVISED_STOPPING,
        SupervisedStatus::Stopped => OFMPC_SUPERVISED_STOPPED,
        _ => OFMPC_SUPERVISED_DIVERGED,
    }
}

#[cold]
fn supervised_failure(e: SupervisedError) -> Failure {
    let status = match e {
        SupervisedError::InputLength { .. } => ofmpc_status::OFMPC_SIZE_MISMATCH,
        SupervisedError::Step(_) => ofmpc_status::OFMPC_NUMERIC,
        _ => ofmpc_status::OFMPC_INVALID_ARG,
    };
    Failure::new(status, e.to_string())
}

/// Number of joints n (0 for NULL).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_supervised_dof(s: *const ofmpc_supervised) -> usize {
    query(0, || unsafe { s.as_ref() }.map(|s| s.0.controller().dof()))
}

/// Prediction horizon N (0 for NULL).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_supervised_horizon(s: *const ofmpc_supervised) -> usize {
    query(0, || {
        unsafe { s.as_ref() }.map(|s| s.0.controller().horizon())
    })
}

/// Sampling period Ts (s; 0 for NULL).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_supervised_ts(s: *const ofmpc_supervised) -> f64 {
    query(0.0, || {
        unsafe { s.as_ref() }.map(|s| s.0.controller().settings().ts)
    })
}

/// Frees a supervised controller (NULL: nothing).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_supervised_free(s: *mut ofmpc_supervised) {
    let _ = boundary(|| {
        unsafe { take(s) };
        Ok(())
    });
}
