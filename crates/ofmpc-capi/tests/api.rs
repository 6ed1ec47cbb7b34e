//! The C API called as C calls it: `*_step` allocates nothing (a counting
//! global allocator, the calling thread only), statuses and messages for bad
//! input, outputs written only on success.

use ofmpc_capi::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ffi::CStr;
use std::mem::size_of;
use std::ptr::{null, null_mut};

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

struct Counting;

// SAFETY: forwards to the system allocator; counting touches a thread-local Cell.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.realloc(p, l, n) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

fn ok(st: ofmpc_status) {
    assert_eq!(st, ofmpc_status::OFMPC_OK, "{}", last_error());
}

fn last_error() -> String {
    unsafe { CStr::from_ptr(ofmpc_last_error()) }
        .to_string_lossy()
        .into_owned()
}

const SETTINGS: &CStr = c"[mpc]\nhorizon = 10\n";

struct Setup {
    robot: *mut ofmpc_robot,
    ctrl: *mut ofmpc_controller,
    sup: *mut ofmpc_supervised,
    plan: *mut ofmpc_plan,
    sim: *mut ofmpc_sim,
}

fn setup() -> Setup {
    let mut s = Setup {
        robot: null_mut(),
        ctrl: null_mut(),
        sup: null_mut(),
        plan: null_mut(),
        sim: null_mut(),
    };
    let gcode = std::ffi::CString::new(ofmpc::gcode::PAPER_TABLE1).unwrap();
    unsafe {
        ok(ofmpc_robot_new_builtin(c"irb140".as_ptr(), &mut s.robot));
        ok(ofmpc_controller_new(
            s.robot,
            c"second".as_ptr(),
            SETTINGS.as_ptr(),
            &mut s.ctrl,
        ));
        ok(ofmpc_supervised_new(
            s.robot,
            c"second".as_ptr(),
            SETTINGS.as_ptr(),
            &mut s.sup,
        ));
        ok(ofmpc_plan_new(s.robot, gcode.as_ptr(), 0.01, &mut s.plan));
        ok(ofmpc_sim_new(
            s.robot,
            s.plan,
            SETTINGS.as_ptr(),
            0.25,
            &mut s.sim,
        ));
    }
    s
}

impl Drop for Setup {
    fn drop(&mut self) {
        unsafe {
            ofmpc_sim_free(self.sim);
            ofmpc_plan_free(self.plan);
            ofmpc_supervised_free(self.sup);
            ofmpc_controller_free(self.ctrl);
            ofmpc_robot_free(self.robot);
        }
    }
}

fn output(tau: &mut [f64]) -> ofmpc_step_output {
    ofmpc_step_output {
        size: size_of::<ofmpc_step_output>(),
        tau: tau.as_mut_ptr(),
        tau_len: tau.len(),
        status: ofmpc_step_status::OFMPC_STEP_SOLVED,
        qp_iterations: 0,
        cost: -1.0,
        r_diag_ratio: 0.0,
        payload_estimate_kg: 0.0,
        solve_time_ns: 0,
        zoh_squarings: 0,
        q_command: null_mut(),
        qd_command: null_mut(),
        qdd_command: null_mut(),
        command_len: 0,
        tau_command: null_mut(),
    }
}

fn telemetry() -> ofmpc_step_telemetry {
    ofmpc_step_telemetry {
        size: size_of::<ofmpc_step_telemetry>(),
        model_time_ns: 0,
        solve_time_ns: 0,
        total_time_ns: 0,
        qp_iterations: 7,
        active_constraints: 7,
        budget_slack_us: 0.0,
        fallback: ofmpc_fallback_level::OFMPC_FALLBACK_HOLD,
        budget_hit: 1,
    }
}

fn input(x: &[f64], w: &[f64], p: &[f64]) -> ofmpc_step_input {
    ofmpc_step_input {
        size: size_of::<ofmpc_step_input>(),
        x: x.as_ptr(),
        x_len: x.len(),
        w: w.as_ptr(),
        w_len: w.len(),
        preview: p.as_ptr(),
        preview_len: p.len(),
    }
}

#[test]
fn a_closed_loop_through_the_c_api_allocates_nothing_per_sample() {
    let s = setup();
    let (n, h) = (6, 10);
    let (mut x, mut w, mut p, mut tau, mut tau_s) = (
        vec![0.0; 2 * n],
        vec![0.0; n],
        vec![0.0; h * n],
        vec![0.0; n],
        vec![0.0; n],
    );
    let mut out = output(&mut tau);
    let mut sout = ofmpc_supervised_output {
        size: size_of::<ofmpc_supervised_output>(),
        tau: tau_s.as_mut_ptr(),
        tau_len: n,
        status: ofmpc_supervised_status::OFMPC_SUPERVISED_DIVERGED,
        step_status: ofmpc_step_status::OFMPC_STEP_HELD_LAST_TORQUE,
        q_command: null_mut(),
        qd_command: null_mut(),
        qdd_command: null_mut(),
        command_len: 0,
        tau_command: null_mut(),
    };
    let samples = unsafe { ofmpc_sim_samples(s.sim) };
    assert!(samples > 1000, "{samples}");
    unsafe {
        ok(ofmpc_sim_read(s.sim, x.as_mut_ptr(), 2 * n));
        ok(ofmpc_controller_reset(s.ctrl, x.as_ptr(), 2 * n));
        ok(ofmpc_supervised_reset(s.sup, x.as_ptr(), 2 * n));
    }
    let (mut tel, mut stel) = (telemetry(), telemetry());
    let before = allocations();
    let mut max_diff = 0.0_f64;
    for k in 0..samples {
        unsafe {
            ok(ofmpc_sim_read(s.sim, x.as_mut_ptr(), 2 * n));
            ok(ofmpc_plan_reference(s.plan, k, w.as_mut_ptr(), n));
            ok(ofmpc_plan_preview(s.plan, k, h, p.as_mut_ptr(), h * n));
            let inp = input(&x, &w, &p);
            ok(ofmpc_controller_step(s.ctrl, &inp, &mut out));
            let sin = ofmpc_supervised_input {
                size: size_of::<ofmpc_supervised_input>(),
                t: k as f64 * 0.01,
                x: x.as_ptr(),
                x_len: x.len(),
                w: w.as_ptr(),
                w_len: n,
                preview: p.as_ptr(),
                preview_len: p.len(),
            };
            ok(ofmpc_supervised_step(s.sup, &sin, &mut sout));
            ok(ofmpc_controller_telemetry(s.ctrl, &mut tel));
            ok(ofmpc_supervised_telemetry(s.sup, &mut stel));
            ok(ofmpc_sim_apply(s.sim, tau.as_ptr(), n, 1.0));
        }
        // The step's telemetry: no limits, no budget, the optimum.
        for t in [&tel, &stel] {
            assert!(t.model_time_ns > 0 && t.model_time_ns <= t.solve_time_ns);
            assert!(t.solve_time_ns <= t.total_time_ns);
            assert_eq!((t.qp_iterations, t.active_constraints), (0, 0));
            assert!(t.budget_slack_us.is_nan() && t.budget_hit == 0);
            assert_eq!(t.fallback, ofmpc_fallback_level::OFMPC_FALLBACK_NONE);
        }
        assert_eq!(tel.total_time_ns as u128, out.solve_time_ns as u128);
        assert_eq!(out.status, ofmpc_step_status::OFMPC_STEP_SOLVED);
        assert_eq!(
            sout.status,
            ofmpc_supervised_status::OFMPC_SUPERVISED_CONTROLLED
        );
        max_diff = tau
            .iter()
            .zip(&tau_s)
            .fold(max_diff, |m, (a, b)| m.max((a - b).abs()));
    }
    assert_eq!(
        allocations() - before,
        0,
        "allocations in {samples} samples"
    );
    // The supervised controller on the same readings gives the same torques.
    assert_eq!(max_diff, 0.0);
    let mut m = metrics();
    unsafe { ok(ofmpc_sim_metrics(s.sim, &mut m)) };
    assert_eq!(m.samples, samples);
    assert!(m.steady_joint_error_max_rad < 1e-9, "{m:?}"); // offset-free
    assert!(
        m.cartesian_error_rms_mm > 0.0 && m.cartesian_error_rms_mm < 0.1,
        "{m:?}"
    );
    // Past the end: OFMPC_END, and nothing written.
    x.fill(7.0);
    let st = unsafe { ofmpc_sim_read(s.sim, x.as_mut_ptr(), 2 * n) };
    assert_eq!(st, ofmpc_status::OFMPC_END);
    assert!(x.iter().all(|v| *v == 7.0));
}

fn metrics() -> ofmpc_metrics {
    ofmpc_metrics {
        size: size_of::<ofmpc_metrics>(),
        samples: 0,
        cartesian_error_rms_mm: 0.0,
        cartesian_error_max_mm: 0.0,
        steady_cartesian_error_mm: 0.0,
        steady_joint_error_max_rad: 0.0,
        joint_error_rms_max_rad: 0.0,
        step_time_median_us: 0.0,
        step_time_max_us: 0.0,
    }
}

#[test]
fn bad_input_gets_a_status_and_a_message_and_writes_nothing() {
    let s = setup();
    let n = 6;
    let x = vec![0.0; 2 * n];
    let w = vec![0.0; n];
    let p = vec![0.0; 10 * n];
    let mut tau = vec![5.0; n];
    let mut out = output(&mut tau);
    unsafe {
        // Before reset.
        let st = ofmpc_controller_step(s.ctrl, &input(&x, &w, &p), &mut out);
        assert_eq!(st, ofmpc_status::OFMPC_NOT_RESET);
        assert!(last_error().contains("reset"), "{}", last_error());
        ok(ofmpc_controller_reset(s.ctrl, x.as_ptr(), 2 * n));
        // A preview of the wrong length.
        let st = ofmpc_controller_step(s.ctrl, &input(&x, &w, &p[1..]), &mut out);
        assert_eq!(st, ofmpc_status::OFMPC_SIZE_MISMATCH);
        assert!(
            last_error().contains("input->preview has 59 values but 60"),
            "{}",
            last_error()
        );
        // NaN in the state.
        let mut bad = x.clone();
        bad[3] = f64::NAN;
        let st = ofmpc_controller_step(s.ctrl, &input(&bad, &w, &p), &mut out);
        assert_eq!(st, ofmpc_status::OFMPC_INVALID_ARG);
        assert!(last_error().contains("x[3]"), "{}", last_error());
        // NULL handle, NULL output, a record too small.
        let st = ofmpc_controller_step(null_mut(), &input(&x, &w, &p), &mut out);
        assert_eq!(st, ofmpc_status::OFMPC_NULL_ARG);
        assert!(last_error().contains("controller is NULL"));
        let st = ofmpc_controller_step(s.ctrl, &input(&x, &w, &p), null_mut());
        assert_eq!(st, ofmpc_status::OFMPC_NULL_ARG);
        out.size = 8;
        let st = ofmpc_controller_step(s.ctrl, &input(&x, &w, &p), &mut out);
        assert_eq!(st, ofmpc_status::OFMPC_SIZE_MISMATCH);
        assert!(
            last_error().contains("sizeof(ofmpc_step_output)"),
            "{}",
            last_error()
        );
        // The telemetry getter: NULL handle or record, a record too small.
        let mut t = telemetry();
        let st = ofmpc_controller_telemetry(std::ptr::null(), &mut t);
        assert_eq!(st, ofmpc_status::OFMPC_NULL_ARG);
        let st = ofmpc_controller_telemetry(s.ctrl, null_mut());
        assert_eq!(st, ofmpc_status::OFMPC_NULL_ARG);
        t.size = 8;
        let st = ofmpc_controller_telemetry(s.ctrl, &mut t);
        assert_eq!(st, ofmpc_status::OFMPC_SIZE_MISMATCH);
        assert!(last_error().contains("sizeof(ofmpc_step_telemetry)"));
        assert_eq!((t.qp_iterations, t.budget_hit), (7, 1), "written on error");
    }
    assert!(
        tau.iter().all(|t| *t == 5.0),
        "outputs written only on success"
    );
    assert_eq!(out.cost, -1.0);
    // The message getter copies and truncates.
    let mut buf = [1 as std::ffi::c_char; 8];
    let need = unsafe { ofmpc_last_error_message(buf.as_mut_ptr(), buf.len()) };
    assert_eq!(need, last_error().len() + 1);
    assert_eq!(buf[7], 0);
}

#[test]
fn builds_that_cannot_work_are_refused_with_where_and_what() {
    let mut robot = null_mut();
    let mut c = null_mut();
    unsafe {
        ok(ofmpc_robot_new_builtin(c"irb140".as_ptr(), &mut robot));
        let st = ofmpc_controller_new(robot, c"third".as_ptr(), null(), &mut c);
        assert_eq!(st, ofmpc_status::OFMPC_INVALID_ARG);
        assert!(last_error().contains("third"), "{}", last_error());
        let st = ofmpc_controller_new(
            robot,
            c"second".as_ptr(),
            c"[mpc]\nhorizon = \"ten\"\n".as_ptr(),
            &mut c,
        );
        assert_eq!(st, ofmpc_status::OFMPC_PARSE);
        let e = last_error();
        assert!(e.contains("line 2") && e.contains("horizon"), "{e}");
        let st = ofmpc_controller_new(
            robot,
            c"second".as_ptr(),
            c"[mpc]\nhorizon = 0\n".as_ptr(),
            &mut c,
        );
        assert_eq!(st, ofmpc_status::OFMPC_BUILD, "{}", last_error());
        let st = ofmpc_controller_new(robot, c"second".as_ptr(), c"[mcp]\n".as_ptr(), &mut c);
        assert_eq!(st, ofmpc_status::OFMPC_PARSE);
        assert!(last_error().contains("mcp"), "{}", last_error());
        assert!(c.is_null(), "no handle on failure");
        let st = ofmpc_robot_new_builtin(c"irb9999".as_ptr(), &mut robot);
        assert_eq!(st, ofmpc_status::OFMPC_INVALID_ARG);
        ofmpc_robot_free(robot);
    }
}

#[test]
fn a_robot_from_urdf_text_or_file_with_its_drives() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../ofmpc/robots/irb140");
    let urdf_path = dir.join("irb140.urdf");
    let drives_path = dir.join("drives.toml");
    let urdf = std::ffi::CString::new(std::fs::read_to_string(&urdf_path).unwrap()).unwrap();
    let drives = std::ffi::CString::new(std::fs::read_to_string(&drives_path).unwrap()).unwrap();
    let (mut a, mut b, mut c) = (null_mut(), null_mut(), null_mut());
    let up = std::ffi::CString::new(urdf_path.to_str().unwrap()).unwrap();
    let dp = std::ffi::CString::new(drives_path.to_str().unwrap()).unwrap();
    unsafe {
        ok(ofmpc_robot_new_urdf(urdf.as_ptr(), drives.as_ptr(), &mut a));
        ok(ofmpc_robot_new_urdf_file(up.as_ptr(), dp.as_ptr(), &mut b));
        assert_eq!((ofmpc_robot_dof(a), ofmpc_robot_dof(b)), (6, 6));
        // A controller builds on either.
        ok(ofmpc_controller_new(b, c"second".as_ptr(), null(), &mut c));
        assert_eq!(ofmpc_controller_dof(c), 6);
        ofmpc_controller_free(c);
        let mut d = null_mut();
        let st = ofmpc_robot_new_urdf(c"<robot name=\"x\"><link".as_ptr(), null(), &mut d);
        assert_eq!(st, ofmpc_status::OFMPC_PARSE, "{}", last_error());
        assert!(d.is_null());
        let st = ofmpc_robot_new_urdf(
            urdf.as_ptr(),
            c"[joint_1]\narmature = \"x\"\n".as_ptr(),
            &mut d,
        );
        assert_eq!(st, ofmpc_status::OFMPC_PARSE);
        assert!(last_error().contains("drives TOML"), "{}", last_error());
        let st = ofmpc_robot_new_urdf_file(c"/nonexistent/robot.urdf".as_ptr(), null(), &mut d);
        assert_eq!(st, ofmpc_status::OFMPC_PARSE);
        assert!(
            last_error().contains("/nonexistent/robot.urdf"),
            "{}",
            last_error()
        );
        ofmpc_robot_free(a);
        ofmpc_robot_free(b);
    }
}

/// `kind` with a position/velocity output 40 ms ahead, built twice: in Rust
/// on `robot` (the IRB 140), and through the C API on the built-in IRB 140
/// from the same settings as TOML (its robot and controller handles).
fn position_output_pair(
    robot: &ofmpc::robot::Robot,
    kind: ofmpc::ControllerKind,
) -> (ofmpc::Controller, *mut ofmpc_robot, *mut ofmpc_controller) {
    let toml = c"[mpc]\noutput = \"position_velocity\"\noutput_lead_s = 0.04\n";
    let settings = ofmpc::control::MpcSettings {
        output: ofmpc::control::OutputMode::PositionVelocity,
        output_lead_s: Some(0.04),
        ..Default::default()
    };
    let rust = ofmpc::ControllerBuilder::new(kind, robot)
        .settings(settings)
        .build()
        .unwrap();
    let name = std::ffi::CString::new(kind.name()).unwrap();
    let (mut r, mut c) = (null_mut(), null_mut());
    unsafe {
        ok(ofmpc_robot_new_builtin(c"irb140".as_ptr(), &mut r));
        ok(ofmpc_controller_new(
            r,
            name.as_ptr(),
            toml.as_ptr(),
            &mut c,
        ));
    }
    (rust, r, c)
}

/// The output mode through the C API (issue 37): `[mpc] output` in the
/// settings TOML just works, and the step's record carries the predicted
/// command, equal to the Rust controller's for the same input; a record
/// of the first version (its `size`) is written as before, a wrong
/// `command_len` is refused with nothing written.
#[test]
fn the_predicted_command_through_the_c_api() {
    let robot = ofmpc::robot::Robot::irb140();
    let (mut rust, r, c) = position_output_pair(&robot, ofmpc::ControllerKind::Second);
    let x0 = [0.1, 0.4, -0.2, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let w = [0.12, 0.41, -0.19, 0.01, 0.5, 0.0];
    let preview: Vec<f64> = (0..10).flat_map(|_| w).collect();
    rust.reset(&x0).unwrap();
    unsafe { ok(ofmpc_controller_reset(c, x0.as_ptr(), x0.len())) };
    let expected = rust
        .step(&ofmpc::StepInput {
            x: &x0,
            w_k: &w,
            preview: &preview,
        })
        .unwrap()
        .clone();
    assert!(expected.q_command.iter().any(|q| *q != 0.0));
    let mut tau = [0.0; 6];
    let (mut q, mut qd, mut qdd) = ([9.0; 6], [9.0; 6], [9.0; 6]);
    let mut out = output(&mut tau);
    // A wrong length: refused, nothing written.
    out.q_command = q.as_mut_ptr();
    out.command_len = 5;
    let st = unsafe { ofmpc_controller_step(c, &input(&x0, &w, &preview), &mut out) };
    assert_eq!(st, ofmpc_status::OFMPC_SIZE_MISMATCH, "{}", last_error());
    assert_eq!((tau, q), ([0.0; 6], [9.0; 6]));
    out.command_len = 6;
    out.qd_command = qd.as_mut_ptr();
    out.qdd_command = qdd.as_mut_ptr();
    unsafe {
        ok(ofmpc_controller_step(
            c,
            &input(&x0, &w, &preview),
            &mut out,
        ))
    };
    assert_eq!(&q[..], &expected.q_command[..]);
    assert_eq!(&qd[..], &expected.qd_command[..]);
    assert_eq!(&qdd[..], &expected.qdd_command[..]);
    assert_eq!(&tau[..], &expected.tau[..]);
    // A first-version record (its size ends before the command): the command
    // fields are neither read nor written.
    let mut q1 = [9.0; 6];
    let mut out = output(&mut tau);
    out.size = std::mem::offset_of!(ofmpc_step_output, q_command);
    out.q_command = q1.as_mut_ptr();
    out.command_len = 1;
    unsafe {
        ok(ofmpc_controller_step(
            c,
            &input(&x0, &w, &preview),
            &mut out,
        ))
    };
    assert_eq!(q1, [9.0; 6]);
    unsafe {
        ofmpc_controller_free(c);
        ofmpc_robot_free(r);
    }
}

/// The drives' applied torque through the C API (issue 37): second-adaptive
/// with a position output, given the torque a loaded arm at rest is held
/// with, identifies the payload and writes the command's torque
/// feed-forward, equal to the Rust controller's for the same inputs, bit for
/// bit; a record that ends before `tau_command` is served without it; a
/// report of the wrong length is refused.
#[test]
fn the_applied_torque_and_the_torque_feed_forward_through_the_c_api() {
    let robot = ofmpc::robot::Robot::irb140();
    let (mut rust, r, c) = position_output_pair(&robot, ofmpc::ControllerKind::SecondAdaptive);
    let w = [0.1, 0.4, -0.2, 0.0, 0.5, 0.0];
    let x0: Vec<f64> = w.iter().copied().chain([0.0; 6]).collect();
    let preview: Vec<f64> = (0..10).flat_map(|_| w).collect();
    let mut loaded = robot.clone();
    loaded
        .set_payload(Some(ofmpc::robot::Payload::point_mass(2.0)))
        .unwrap();
    let mut ws = ofmpc::dynamics::Workspace::new(&loaded);
    let held = ofmpc::dynamics::rnea(&loaded, &mut ws, &w, &[0.0; 6], &[0.0; 6])
        .unwrap()
        .as_slice()
        .to_vec();
    rust.reset(&x0).unwrap();
    unsafe { ok(ofmpc_controller_reset(c, x0.as_ptr(), x0.len())) };
    let st = unsafe { ofmpc_controller_set_applied_torque(c, held.as_ptr(), 5) };
    assert_eq!(st, ofmpc_status::OFMPC_SIZE_MISMATCH, "{}", last_error());
    let mut tau = [0.0; 6];
    let mut ff = [9.0; 6];
    for k in 0..30 {
        rust.set_applied_torque(&held).unwrap();
        let expected = rust
            .step(&ofmpc::StepInput {
                x: &x0,
                w_k: &w,
                preview: &preview,
            })
            .unwrap()
            .clone();
        let mut out = output(&mut tau);
        out.tau_command = ff.as_mut_ptr();
        out.command_len = 6;
        if k == 29 {
            // A record of the version before `tau_command`: not written.
            out.size = std::mem::offset_of!(ofmpc_step_output, tau_command);
            ff = [9.0; 6];
        }
        unsafe {
            ok(ofmpc_controller_set_applied_torque(c, held.as_ptr(), 6));
            ok(ofmpc_controller_step(
                c,
                &input(&x0, &w, &preview),
                &mut out,
            ));
        }
        assert_eq!(&tau[..], &expected.tau[..]);
        if k == 29 {
            assert_eq!(ff, [9.0; 6]);
        } else {
            assert_eq!(&ff[..], &expected.tau_command[..], "step {k}");
        }
        if k == 28 {
            // The payload's gravity reaches the feed-forward.
            assert!(ff[1].abs() > 1.0, "{ff:?}");
        }
    }
    unsafe {
        ofmpc_controller_free(c);
        ofmpc_robot_free(r);
    }
}

/// The first-stage gains through the C API (issue 37 item 5): `[mpc] gains =
/// true` in the settings TOML, `ofmpc_controller_gains` returns the Rust
/// controller's law for the same input (no allocation); without gains, and
/// for a kind that cannot have them, a status and a message.
#[test]
fn the_first_stage_gains_through_the_c_api() {
    let robot = ofmpc::robot::Robot::irb140();
    let settings = ofmpc::control::MpcSettings {
        gains: true,
        ..Default::default()
    };
    let mut rust = ofmpc::ControllerBuilder::new(ofmpc::ControllerKind::Second, &robot)
        .settings(settings)
        .build()
        .unwrap();
    let (mut r, mut c, mut plain, mut pid) = (null_mut(), null_mut(), null_mut(), null_mut());
    unsafe {
        ok(ofmpc_robot_new_builtin(c"irb140".as_ptr(), &mut r));
        let gains = c"[mpc]\ngains = true\n";
        ok(ofmpc_controller_new(
            r,
            c"second".as_ptr(),
            gains.as_ptr(),
            &mut c,
        ));
        ok(ofmpc_controller_new(
            r,
            c"second".as_ptr(),
            null(),
            &mut plain,
        ));
        let st = ofmpc_controller_new(r, c"pid".as_ptr(), gains.as_ptr(), &mut pid);
        assert_eq!(st, ofmpc_status::OFMPC_BUILD);
        assert!(
            last_error().contains("first-stage gains"),
            "{}",
            last_error()
        );
    }
    let x0 = [0.1, 0.4, -0.2, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let w = [0.12, 0.41, -0.19, 0.01, 0.5, 0.0];
    let preview: Vec<f64> = (0..10).flat_map(|_| w).collect();
    rust.reset(&x0).unwrap();
    let expected = rust
        .step(&ofmpc::StepInput {
            x: &x0,
            w_k: &w,
            preview: &preview,
        })
        .unwrap()
        .clone();
    let mut tau = [0.0; 6];
    let (mut k, mut tff, mut xl) = ([0.0; 72], [0.0; 6], [0.0; 12]);
    unsafe {
        ok(ofmpc_controller_reset(c, x0.as_ptr(), x0.len()));
        ok(ofmpc_controller_step(
            c,
            &input(&x0, &w, &preview),
            &mut output(&mut tau),
        ));
        let before = allocations();
        ok(ofmpc_controller_gains(
            c,
            k.as_mut_ptr(),
            72,
            tff.as_mut_ptr(),
            6,
            xl.as_mut_ptr(),
            12,
        ));
        assert_eq!(allocations(), before);
        let st = ofmpc_controller_gains(
            plain,
            k.as_mut_ptr(),
            72,
            tff.as_mut_ptr(),
            6,
            xl.as_mut_ptr(),
            12,
        );
        assert_eq!(st, ofmpc_status::OFMPC_INVALID_ARG);
        assert!(last_error().contains("gains = true"), "{}", last_error());
        let st = ofmpc_controller_gains(
            c,
            k.as_mut_ptr(),
            71,
            tff.as_mut_ptr(),
            6,
            xl.as_mut_ptr(),
            12,
        );
        assert_eq!(st, ofmpc_status::OFMPC_SIZE_MISMATCH);
    }
    assert_eq!(&k[..], &expected.gain[..]);
    assert!(k.iter().any(|v| *v != 0.0));
    assert_eq!(&tff[..], &expected.tau[..]);
    assert_eq!(&xl[..], &x0[..]);
    unsafe {
        ofmpc_controller_free(c);
        ofmpc_controller_free(plain);
        ofmpc_robot_free(r);
    }
}

/// The largest `|v_i|`.
fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// The supervised controller's command through the C API (issue 37), in a
/// position-interface run: the simulated `abb-egm` interface (4 ms cycle,
/// 40 ms lag) takes `q_command`/`qd_command`/`qdd_command` from
/// `ofmpc_supervised_step`, an 8 kg load picked up at 3 s passes the
/// safety limit (1.5 mrad) at speed, and the safe stop's command — the stop
/// law's braking trajectory one lead ahead — decelerates to rest and holds:
/// its speed falls from the stop's first sample on, every later command
/// moves less than the one before (to within 1e-9 rad/s), it ends below
/// 1e-6 rad/s and the arm itself at rest (< 1e-3 rad/s). The controller's
/// last command, which a position interface would otherwise keep
/// streaming, was moving (> 0.1 rad/s). Measured: the stop begins at
/// 3.02 s; the controller's last command moved at 0.61 rad/s, the stop's
/// first at 0.14 rad/s (40 ms into a 30 ms braking law), its last at
/// 2e-15 rad/s, the arm at 1e-13 rad/s. A record of the first version
/// (size before `q_command`) is still served, and a wrong `command_len` is
/// refused with nothing written. Allocation-free throughout.
#[test]
fn a_safe_stop_commands_a_braking_position_through_the_c_api() {
    use ofmpc::sim::{Plant, PlantSettings, Servo, ServoProfile, ServoSettings};
    let toml = c"[mpc]\nq_du = 1e-3\noutput = \"position_velocity\"\noutput_lead_s = 0.04\n\
        [simulation]\nsafe_stop = true\n[safety]\nmax_joint_error_rad = 1.5e-3\n";
    let gcode = std::ffi::CString::new(ofmpc::gcode::PAPER_TABLE1).unwrap();
    let ts = 0.01;
    let (mut robot, mut sup, mut plan) = (null_mut(), null_mut(), null_mut());
    unsafe {
        ok(ofmpc_robot_new_builtin(c"irb140".as_ptr(), &mut robot));
        ok(ofmpc_supervised_new(
            robot,
            c"second".as_ptr(),
            toml.as_ptr(),
            &mut sup,
        ));
        ok(ofmpc_plan_new(robot, gcode.as_ptr(), ts, &mut plan));
    }
    let (n, h) = unsafe { (ofmpc_supervised_dof(sup), ofmpc_supervised_horizon(sup)) };
    let model = ofmpc::Robot::irb140();
    let servo_settings = ServoSettings::profile(ServoProfile::AbbEgm);
    let settings = PlantSettings {
        servo: Some(servo_settings.clone()),
        ..Default::default()
    };
    let substep = settings.substep;
    let mut w = vec![0.0; n];
    unsafe { ok(ofmpc_plan_reference(plan, 0, w.as_mut_ptr(), n)) };
    let mut plant = Plant::with_period(model.clone(), settings, &w, ts).unwrap();
    let mut servo = Servo::new(&servo_settings, &model, ts, substep).unwrap();
    servo.start(&w).unwrap();
    let (mut x, mut p, mut tau) = (vec![0.0; 2 * n], vec![0.0; h * n], vec![0.0; n]);
    let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut out = ofmpc_supervised_output {
        size: size_of::<ofmpc_supervised_output>(),
        tau: tau.as_mut_ptr(),
        tau_len: n,
        status: ofmpc_supervised_status::OFMPC_SUPERVISED_DIVERGED,
        step_status: ofmpc_step_status::OFMPC_STEP_HELD_LAST_TORQUE,
        q_command: q.as_mut_ptr(),
        qd_command: qd.as_mut_ptr(),
        qdd_command: qdd.as_mut_ptr(),
        command_len: n,
        tau_command: null_mut(),
    };
    let read = |plant: &Plant, x: &mut [f64]| {
        x[..n].copy_from_slice(plant.q());
        x[n..].copy_from_slice(plant.qd());
    };
    read(&plant, &mut x);
    unsafe { ok(ofmpc_supervised_reset(sup, x.as_ptr(), 2 * n)) };
    let samples = unsafe { ofmpc_plan_len(plan) } + 200;
    let pick_up = (3.0 / ts) as usize;
    // Per sample: the status and the command's speed.
    let mut log = Vec::with_capacity(samples);
    let (mut stale_speed, mut allocated) = (f64::NAN, 0);
    for k in 0..samples {
        if k == pick_up {
            let load = ofmpc::Payload::point_mass(8.0);
            plant.set_payload(Some(load)).unwrap();
        }
        read(&plant, &mut x);
        let kr = k.min(unsafe { ofmpc_plan_len(plan) } - 1);
        unsafe {
            ok(ofmpc_plan_reference(plan, kr, w.as_mut_ptr(), n));
            ok(ofmpc_plan_preview(plan, kr, h, p.as_mut_ptr(), h * n));
            let sin = ofmpc_supervised_input {
                size: size_of::<ofmpc_supervised_input>(),
                t: k as f64 * ts,
                x: x.as_ptr(),
                x_len: x.len(),
                w: w.as_ptr(),
                w_len: n,
                preview: p.as_ptr(),
                preview_len: p.len(),
            };
            let before = allocations();
            ok(ofmpc_supervised_step(sup, &sin, &mut out));
            allocated += allocations() - before;
        }
        let controlled = out.status == ofmpc_supervised_status::OFMPC_SUPERVISED_CONTROLLED;
        if controlled {
            stale_speed = max_abs(&qd);
        }
        servo.receive(&tau, &q, &qd, &qdd, false);
        plant
            .advance_with(&mut |i, q, qd, tau| {
                servo.drive(i, q, qd, tau, substep).unwrap();
                Ok(())
            })
            .unwrap();
        log.push((out.status, max_abs(&qd)));
    }
    assert_eq!(allocated, 0, "allocations in {samples} steps");
    assert_braked_to_rest(&log, pick_up, stale_speed);
    assert!(
        max_abs(plant.qd()) < 1e-3,
        "the arm moves at {:?}",
        plant.qd()
    );
    check_command_record_versions(sup, &x, &w, &p, samples as f64 * ts);
    unsafe {
        ofmpc_plan_free(plan);
        ofmpc_supervised_free(sup);
        ofmpc_robot_free(robot);
    }
}

/// One more sample of `sup` (a position output) with a first-version
/// record (its size ends before the command): served, the command arrays
/// untouched; then a wrong `command_len`: refused, nothing written.
fn check_command_record_versions(
    sup: *mut ofmpc_supervised,
    x: &[f64],
    w: &[f64],
    p: &[f64],
    t: f64,
) {
    let n = w.len();
    let (mut tau, mut q, mut qd, mut qdd) =
        (vec![-7.0; n], vec![-7.0; n], vec![0.0; n], vec![0.0; n]);
    let sin = ofmpc_supervised_input {
        size: size_of::<ofmpc_supervised_input>(),
        t,
        x: x.as_ptr(),
        x_len: x.len(),
        w: w.as_ptr(),
        w_len: n,
        preview: p.as_ptr(),
        preview_len: p.len(),
    };
    let mut out = ofmpc_supervised_output {
        size: std::mem::offset_of!(ofmpc_supervised_output, q_command),
        tau: tau.as_mut_ptr(),
        tau_len: n,
        status: ofmpc_supervised_status::OFMPC_SUPERVISED_DIVERGED,
        step_status: ofmpc_step_status::OFMPC_STEP_HELD_LAST_TORQUE,
        q_command: q.as_mut_ptr(),
        qd_command: qd.as_mut_ptr(),
        qdd_command: qdd.as_mut_ptr(),
        command_len: n,
        tau_command: null_mut(),
    };
    unsafe { ok(ofmpc_supervised_step(sup, &sin, &mut out)) };
    assert!(q.iter().all(|v| *v == -7.0), "{q:?}");
    out.size = size_of::<ofmpc_supervised_output>();
    out.command_len = n - 1;
    tau.fill(-7.0);
    let st = unsafe { ofmpc_supervised_step(sup, &sin, &mut out) };
    assert_eq!(st, ofmpc_status::OFMPC_SIZE_MISMATCH);
    assert!(
        last_error().contains("out->command_len"),
        "{}",
        last_error()
    );
    assert!(tau.iter().chain(&q).all(|v| *v == -7.0));
}

/// The command's speed per sample of a run (`log`: status, speed) braked to
/// rest in a safe stop that began after sample `after`: slower than the
/// controller's last command (`stale`, which moved), never faster than the
/// sample before (to 1e-9 rad/s), below 1e-6 rad/s at the end, `STOPPED`.
fn assert_braked_to_rest(log: &[(ofmpc_supervised_status, f64)], after: usize, stale_speed: f64) {
    let k0 = log
        .iter()
        .position(|(s, ..)| *s == ofmpc_supervised_status::OFMPC_SUPERVISED_STOPPING)
        .expect("the safety limit brought no stop");
    assert!(
        k0 > after,
        "stopped at sample {k0}, before the load at {after}"
    );
    assert!(
        stale_speed > 0.1,
        "the controller's last command moved at {stale_speed} rad/s"
    );
    let speeds: Vec<f64> = log[k0..].iter().map(|(_, v)| *v).collect();
    for (j, pair) in speeds.windows(2).enumerate() {
        assert!(pair[1] <= pair[0] + 1e-9, "sample {}: {pair:?}", k0 + j);
    }
    assert!(speeds[0] < stale_speed, "{} vs {stale_speed}", speeds[0]);
    let last = *speeds.last().unwrap();
    assert!(last < 1e-6, "the command still moves at {last} rad/s");
    assert_eq!(
        log.last().unwrap().0,
        ofmpc_supervised_status::OFMPC_SUPERVISED_STOPPED
    );
}
