//! # ofmpc-capi — the C API of ofmpc
//!
//! Opaque handles made by `*_new` and freed once by `*_free`:
//! [`ofmpc_robot`] (the built-in IRB 140, or a URDF with a drives file),
//! [`ofmpc_controller`] (wraps [`ofmpc::Controller`], built from the `[mpc]`
//! and `[baselines]` keys of a scenario as TOML text and a kind name),
//! [`ofmpc_supervised`] (wraps [`ofmpc::sim::SupervisedController`]),
//! [`ofmpc_plan`] (a G-code text planned into a joint reference with its
//! preview) and [`ofmpc_sim`] (the simulated plant behind its actuator and
//! sensor, recording the run for its metrics).
//!
//! Conventions (those of rustls-ffi and wasmtime):
//! - every fallible call returns an [`ofmpc_status`]; its outputs are
//!   written only on [`ofmpc_status::OFMPC_OK`]; the message of the last
//!   failure on the calling thread is [`ofmpc_last_error`];
//! - every export runs inside a panic boundary: a panic becomes
//!   [`ofmpc_status::OFMPC_PANIC`], it never unwinds into C;
//! - every pointer is checked for NULL, every array comes with its length;
//! - the `#[repr(C)]` in/out records begin with a `size` field, set by the
//!   caller to `sizeof` the record it was compiled with: fields appended by
//!   a later version are then neither read nor written;
//! - `const` handle = the call does not change it;
//! - the `*_step` functions allocate nothing and take no lock.
#![allow(non_camel_case_types)]
// The exports check every pointer before they read it; their safety
// contract is the C header's ("valid for its length, or NULL").
#![allow(clippy::missing_safety_doc)]

mod controller;
mod ffi;
mod plan;
mod robot;
mod settings;
mod sim;
mod supervised;
mod telemetry;

pub use controller::*;
pub use ffi::*;
pub use plan::*;
pub use robot::*;
pub use sim::*;
pub use supervised::*;
pub use telemetry::*;

#[cfg(test)]
mod tests {
    //! The panic boundary, with a panic hook compiled only in tests.
    use super::*;
    use std::ffi::CStr;

    #[test]
    fn a_panic_inside_an_export_becomes_the_panic_status_and_a_message() {
        let mut robot = std::ptr::null_mut();
        let mut c = std::ptr::null_mut();
        unsafe {
            assert_eq!(
                ofmpc_robot_new_builtin(c"irb140".as_ptr(), &mut robot),
                ofmpc_status::OFMPC_OK
            );
            let st = ofmpc_controller_new(robot, c"second".as_ptr(), std::ptr::null(), &mut c);
            assert_eq!(st, ofmpc_status::OFMPC_OK);
            let mut tau = [7.0; 6];
            let mut out = ofmpc_step_output {
                size: std::mem::size_of::<ofmpc_step_output>(),
                tau: tau.as_mut_ptr(),
                tau_len: 6,
                status: ofmpc_step_status::OFMPC_STEP_SOLVED,
                qp_iterations: 0,
                cost: 0.0,
                r_diag_ratio: 0.0,
                payload_estimate_kg: 0.0,
                solve_time_ns: 0,
                zoh_squarings: 0,
                q_command: std::ptr::null_mut(),
                qd_command: std::ptr::null_mut(),
                qdd_command: std::ptr::null_mut(),
                command_len: 0,
                tau_command: std::ptr::null_mut(),
            };
            let input = ofmpc_step_input {
                size: std::mem::size_of::<ofmpc_step_input>(),
                x: std::ptr::null(),
                x_len: 0,
                w: std::ptr::null(),
                w_len: 0,
                preview: std::ptr::null(),
                preview_len: 0,
            };
            let hook = std::panic::take_hook();
            std::panic::set_hook(Box::new(|_| {}));
            crate::ffi::panic_next();
            let st = ofmpc_controller_step(c, &input, &mut out);
            std::panic::set_hook(hook);
            assert_eq!(st, ofmpc_status::OFMPC_PANIC);
            let msg = CStr::from_ptr(ofmpc_last_error()).to_str().unwrap();
            assert!(msg.contains("deliberate test panic"), "{msg}");
            assert_eq!(tau, [7.0; 6], "nothing written on a panic");
            // The handle still works after the caught panic: the next call
            // refuses the empty input with a size error, not a panic.
            let st = ofmpc_controller_step(c, &input, &mut out);
            assert_eq!(st, ofmpc_status::OFMPC_SIZE_MISMATCH);
            ofmpc_controller_free(c);
            ofmpc_robot_free(robot);
        }
    }
}
