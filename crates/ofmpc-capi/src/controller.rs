//! The controller handle: wraps [`ofmpc::Controller`].

use crate::ffi::*;
use crate::robot::ofmpc_robot;
use crate::settings::{build_controller, kind, Settings};
use ofmpc::{Controller, StepError, StepInput, StepOutput, StepStatus};
use std::ffi::c_char;
use std::mem::size_of;

/// A built controller (any kind: the paper's three, the adaptive variants,
/// the baselines). Opaque; `Send`: one thread at a time.
pub struct ofmpc_controller(pub(crate) Controller);

/// One sample's measurement and reference (borrowed by the call).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ofmpc_step_input {
    /// `sizeof(ofmpc_step_input)`.
    pub size: usize,
    /// Measured state `[q; q̇]`, 2n values.
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

/// The numerical outcome of a step (the library's `StepStatus`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ofmpc_step_status {
    /// The algorithm's optimum.
    OFMPC_STEP_SOLVED = 0,
    /// The torque-limit QP stopped at its iteration cap: feasible, not optimal.
    OFMPC_STEP_QP_ITERATION_CAP = 1,
    /// The step failed numerically: `tau` holds the last torque; begin a safe stop.
    OFMPC_STEP_HELD_LAST_TORQUE = 2,
}

/// What a step computed. The caller owns `tau` (n doubles) and sets `size`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ofmpc_step_output {
    /// `sizeof(ofmpc_step_output)`: fields past it are not written.
    pub size: usize,
    /// The torque to apply (n values, written by the step).
    pub tau: *mut f64,
    /// Length of `tau`.
    pub tau_len: usize,
    /// Numerical outcome.
    pub status: ofmpc_step_status,
    /// Active-set iterations of the torque-limit QP (0 without limits).
    pub qp_iterations: u32,
    /// Minimum of the cost `J_min` (Eq. (42)).
    pub cost: f64,
    /// `max|R_ii| / min|R_ii|` of the least-squares factor.
    pub r_diag_ratio: f64,
    /// The payload mass the model carries (kg); NaN for kinds that do not identify it.
    pub payload_estimate_kg: f64,
    /// Wall time of the step (ns).
    pub solve_time_ns: u64,
    /// Doublings of the ZOH discretization.
    pub zoh_squarings: u32,
    /// With a position or velocity output (`[mpc] output`): the joint
    /// positions the controller's model predicted one lead time ahead (n
    /// values; rad). Written when `size` covers the command fields and the
    /// pointer is not NULL (NULL: not asked for); zeros with a torque output.
    pub q_command: *mut f64,
    /// The predicted joint velocities one lead time ahead (n values; rad/s),
    /// as `q_command`.
    pub qd_command: *mut f64,
    /// The predicted joint accelerations one lead time ahead (n values;
    /// rad/s²: the feed-forward of the interface's joint loop), as
    /// `q_command`.
    pub qdd_command: *mut f64,
    /// Length of each non-NULL command array (n).
    pub command_len: usize,
    /// With a position or velocity output and an adaptive kind given the
    /// drives' applied torque (`ofmpc_controller_set_applied_torque`):
    /// the torque feed-forward for an interface that adds one to its own
    /// joint loop, the identified payload's torque along the command (n
    /// values; N·m; zeros otherwise), as `q_command` (length
    /// `command_len`). Written when `size` covers it.
    pub tau_command: *mut f64,
}

/// The size of the first version of [`ofmpc_step_output`]: fields appended
/// later are written only when the caller's `size` covers them.
pub(crate) const STEP_OUTPUT_V1: usize = std::mem::offset_of!(ofmpc_step_output, q_command);
/// The size with the predicted command (issue 37): `q_command` … `command_len`.
pub(crate) const STEP_OUTPUT_V2: usize = std::mem::offset_of!(ofmpc_step_output, tau_command);
/// The size with the command's torque feed-forward: `tau_command`.
pub(crate) const STEP_OUTPUT_V3: usize = size_of::<ofmpc_step_output>();
/// The size of the first version of [`ofmpc_step_input`].
pub(crate) const STEP_INPUT_V1: usize = size_of::<ofmpc_step_input>();

/// Builds the controller `kind_name` ("usual", "first", "second",
/// "first-adaptive", "second-adaptive", "pid", "ctc", "ctc-adaptive",
/// "dob-mpc") for `robot` from `settings_toml` (the scenario's `[mpc]`,
/// `[baselines]` and `[plant]` tables; NULL: the paper's tuning).
/// `OFMPC_BUILD` when it cannot work as configured.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_controller_new(
    robot: *const ofmpc_robot,
    kind_name: *const c_char,
    settings_toml: *const c_char,
    out: *mut *mut ofmpc_controller,
) -> ofmpc_status {
    boundary(|| {
        let robot = unsafe { arg(robot, "robot") }?;
        let kind = kind(unsafe { text(kind_name, "kind_name") }?)?;
        let settings = Settings::parse(unsafe { opt_text(settings_toml, "settings_toml") }?)?;
        if out.is_null() {
            return Err(null("out"));
        }
        let c = build_controller(&robot.0, kind, &settings)?;
        unsafe { give(out, ofmpc_controller(c)) };
        Ok(())
    })
}

/// Starts a run at the measured state `x0 = [q; q̇]` (2n values).
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_controller_reset(
    c: *mut ofmpc_controller,
    x0: *const f64,
    x0_len: usize,
) -> ofmpc_status {
    boundary(|| {
        let c = &mut unsafe { arg_mut(c, "controller") }?.0;
        let x0 = unsafe { slice(x0, x0_len, 2 * c.dof(), "x0") }?;
        c.reset(x0).map_err(step_failure)
    })
}

/// One control step: allocates nothing, takes no lock. `OFMPC_OK` with the
/// numerical outcome in `out->status`; on bad input (sizes, non-finite
/// values, not reset) another status and nothing written.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_controller_step(
    c: *mut ofmpc_controller,
    input: *const ofmpc_step_input,
    out: *mut ofmpc_step_output,
) -> ofmpc_status {
    boundary(|| {
        #[cfg(test)]
        crate::ffi::maybe_panic();
        let c = &mut unsafe { arg_mut(c, "controller") }?.0;
        let input = unsafe { arg(input, "input") }?;
        let out = unsafe { arg_mut(out, "out") }?;
        let n = c.dof();
        check_record(out.size, STEP_OUTPUT_V1, "ofmpc_step_output")?;
        let tau = unsafe { slice_mut(out.tau, out.tau_len, n, "out->tau") }?;
        check_command(out, n)?;
        let result = {
            let (x, w, preview) = unsafe { step_slices(input, n, c.horizon()) }?;
            c.step(&StepInput { x, w_k: w, preview })
                .map_err(step_failure)?
        };
        write_output(result, tau, out);
        unsafe { write_command(result, out) };
        Ok(())
    })
}

/// The torque the drives applied over the period that just ended (`tau`,
/// n values, N·m), for an interface that closes its own joint loop and
/// reports it: call it before [`ofmpc_controller_step`]. The adaptive kinds
/// then identify their payload from it also through a position or velocity
/// output, and `out->tau_command` carries the payload as a torque
/// feed-forward; the other kinds ignore it. Allocates nothing.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_controller_set_applied_torque(
    c: *mut ofmpc_controller,
    tau: *const f64,
    tau_len: usize,
) -> ofmpc_status {
    boundary(|| {
        let c = &mut unsafe { arg_mut(c, "controller") }?.0;
        let tau = unsafe { slice(tau, tau_len, c.dof(), "tau") }?;
        c.set_applied_torque(tau).map_err(step_failure)
    })
}

/// The record's command arrays, checked before the step (nothing is
/// written on a refusal): when its `size` covers them, every non-NULL one
/// has `command_len = n`.
fn check_command(out: &ofmpc_step_output, n: usize) -> Result<(), Failure> {
    // An older record: the command fields are not there to read.
    let covered = out.size >= STEP_OUTPUT_V2;
    let arrays = [out.q_command, out.qd_command, out.qdd_command];
    check_command_arrays(covered, &arrays, out.command_len, n, "out->command_len")?;
    let covered = out.size >= STEP_OUTPUT_V3;
    check_command_arrays(
        covered,
        &[out.tau_command],
        out.command_len,
        n,
        "out->command_len",
    )
}

/// Command arrays `arrays` of `len` values each: when the record covers
/// them (`covered`), every non-NULL one must hold the robot's `n` joints
/// (`what` names the length field in the refusal).
pub(crate) fn check_command_arrays(
    covered: bool,
    arrays: &[*mut f64],
    len: usize,
    n: usize,
    what: &str,
) -> Result<(), Failure> {
    let asked = covered && arrays.iter().any(|p| !p.is_null());
    if asked && len != n {
        return Err(Failure::new(
            ofmpc_status::OFMPC_SIZE_MISMATCH,
            format!("{what} is {len} but the robot has {n} joints"),
        ));
    }
    Ok(())
}

/// The predicted command into the record's non-NULL command arrays, when
/// its `size` covers them ([`check_command`] checked their length).
unsafe fn write_command(o: &StepOutput, out: &mut ofmpc_step_output) {
    let arrays = [out.q_command, out.qd_command, out.qdd_command];
    let command = [&o.q_command[..], &o.qd_command, &o.qdd_command];
    // SAFETY: checked by `check_command`.
    unsafe { write_command_arrays(out.size >= STEP_OUTPUT_V2, &arrays, &command) };
    let covered = out.size >= STEP_OUTPUT_V3;
    // SAFETY: checked by `check_command`.
    unsafe { write_command_arrays(covered, &[out.tau_command], &[&o.tau_command]) };
}

/// `command` (position, velocity, acceleration) into the non-NULL ones of
/// `arrays` when the record covers them.
///
/// # Safety
/// Every non-NULL array holds `command[i].len()` writable values
/// ([`check_command_arrays`]).
pub(crate) unsafe fn write_command_arrays(covered: bool, arrays: &[*mut f64], command: &[&[f64]]) {
    if !covered {
        return;
    }
    for (&p, src) in arrays.iter().zip(command) {
        if !p.is_null() {
            // SAFETY: the caller gave `command_len = n` writable values.
            unsafe { std::slice::from_raw_parts_mut(p, src.len()) }.copy_from_slice(src);
        }
    }
}

/// The state, the reference and the preview of a step.
pub(crate) type StepSlices<'a> = (&'a [f64], &'a [f64], &'a [f64]);

/// The input record's arrays, checked (2n, n, N·n).
pub(crate) unsafe fn step_slices<'a>(
    input: &ofmpc_step_input,
    n: usize,
    horizon: usize,
) -> Result<StepSlices<'a>, Failure> {
    check_record(input.size, STEP_INPUT_V1, "ofmpc_step_input")?;
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
    Ok((x, w, p))
}

/// The library's step output into the C record (`tau` is `out.tau`).
pub(crate) fn write_output(o: &StepOutput, tau: &mut [f64], out: &mut ofmpc_step_output) {
    tau.copy_from_slice(&o.tau);
    out.status = match o.status {
        StepStatus::Solved => ofmpc_step_status::OFMPC_STEP_SOLVED,
        StepStatus::QpIterationCap { .. } => ofmpc_step_status::OFMPC_STEP_QP_ITERATION_CAP,
        _ => ofmpc_step_status::OFMPC_STEP_HELD_LAST_TORQUE,
    };
    out.qp_iterations = o.qp_status.map_or(0, |q| q.iterations);
    out.cost = o.cost;
    out.r_diag_ratio = o.r_diag_ratio;
    out.payload_estimate_kg = o.payload_estimate.unwrap_or(f64::NAN);
    out.solve_time_ns = u64::try_from(o.solve_time.as_nanos()).unwrap_or(u64::MAX);
    out.zoh_squarings = o.zoh_squarings;
}

/// A step's refusal as a status and message (error path only).
#[cold]
pub(crate) fn step_failure(e: StepError) -> Failure {
    let status = match e {
        StepError::NotReset => ofmpc_status::OFMPC_NOT_RESET,
        StepError::WrongLength { .. } => ofmpc_status::OFMPC_SIZE_MISMATCH,
        _ => ofmpc_status::OFMPC_INVALID_ARG,
    };
    Failure::new(status, e.to_string())
}

/// The first-stage feedback law of the last successful step (issue 37,
/// `[mpc] gains = true`): `gain` = K (n × 2n doubles, row-major), `tau_ff`
/// = τ_k (n), `x_lin` = x_k (2n), so that between MPC samples a faster loop
/// can apply τ = tau_ff + K (x − x_lin); zeros before the first step.
/// `OFMPC_INVALID_ARG` when the controller was built without gains (nothing
/// written); allocates nothing.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_controller_gains(
    c: *const ofmpc_controller,
    gain: *mut f64,
    gain_len: usize,
    tau_ff: *mut f64,
    tau_ff_len: usize,
    x_lin: *mut f64,
    x_lin_len: usize,
) -> ofmpc_status {
    boundary(|| {
        let c = &unsafe { arg(c, "controller") }?.0;
        let n = c.dof();
        let o = c.output();
        if o.gain.is_empty() {
            return Err(Failure::new(
                ofmpc_status::OFMPC_INVALID_ARG,
                "no gains: build the controller with [mpc] gains = true".to_string(),
            ));
        }
        let k = unsafe { slice_mut(gain, gain_len, 2 * n * n, "gain") }?;
        let t = unsafe { slice_mut(tau_ff, tau_ff_len, n, "tau_ff") }?;
        let x = unsafe { slice_mut(x_lin, x_lin_len, 2 * n, "x_lin") }?;
        k.copy_from_slice(&o.gain);
        t.copy_from_slice(&o.tau_ff);
        x.copy_from_slice(&o.x_lin);
        Ok(())
    })
}

/// Number of joints n (0 for NULL).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_controller_dof(c: *const ofmpc_controller) -> usize {
    query(0, || unsafe { c.as_ref() }.map(|c| c.0.dof()))
}

/// Prediction horizon N (the preview holds N·n values; 0 for NULL).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_controller_horizon(c: *const ofmpc_controller) -> usize {
    query(0, || unsafe { c.as_ref() }.map(|c| c.0.horizon()))
}

/// Sampling period Ts (s; 0 for NULL).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_controller_ts(c: *const ofmpc_controller) -> f64 {
    query(0.0, || unsafe { c.as_ref() }.map(|c| c.0.settings().ts))
}

/// Frees a controller (NULL: nothing).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_controller_free(c: *mut ofmpc_controller) {
    let _ = boundary(|| {
        unsafe { take(c) };
        Ok(())
    });
}
