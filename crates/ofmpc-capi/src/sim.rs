//! The simulated plant for tests and examples: the plant (robot + payload)
//! behind its actuator and sensor stages, at the plan's period, recording
//! the run for the metrics `ofmpc run` writes.

use crate::ffi::*;
use crate::plan::ofmpc_plan;
use crate::robot::ofmpc_robot;
use crate::settings::{chain, Settings};
use ofmpc::sim::{
    compute_metrics, records_measurement, Actuator, LossSchedule, Plant, Recorder, RunOutcome,
    Sample, Sensor,
};
use ofmpc::{JointReference, Payload};
use std::mem::size_of;

/// A simulated robot along a plan. Opaque.
pub struct ofmpc_sim {
    plant: Plant,
    sensor: Sensor,
    actuator: Actuator,
    recorder: Recorder,
    reference: JointReference,
    steady_window_s: f64,
    payload_kg: f64,
    /// Next sample, samples in the run (path and hold).
    k: usize,
    total: usize,
    /// The reading of sample `k` (2n), the true state then (2n), its flange.
    x: Vec<f64>,
    x_true: Vec<f64>,
    flange: [f64; 3],
    /// Sample `k` was read and awaits its torque.
    pending: bool,
}

/// The metrics of a simulated run, as in `ofmpc run`'s metrics.json.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ofmpc_metrics {
    /// `sizeof(ofmpc_metrics)`: fields past it are not written.
    pub size: usize,
    /// Samples recorded.
    pub samples: usize,
    /// `cartesian_error_rms_mm`.
    pub cartesian_error_rms_mm: f64,
    /// `cartesian_error_max_mm`.
    pub cartesian_error_max_mm: f64,
    /// `steady_cartesian_error_mm`.
    pub steady_cartesian_error_mm: f64,
    /// Largest of `steady_joint_error_max_rad`.
    pub steady_joint_error_max_rad: f64,
    /// Largest of `joint_error_rms_rad`.
    pub joint_error_rms_max_rad: f64,
    /// `step_time_us.median` (of the step times passed to `ofmpc_sim_apply`).
    pub step_time_median_us: f64,
    /// `step_time_us.max`.
    pub step_time_max_us: f64,
}

const METRICS_V1: usize = size_of::<ofmpc_metrics>();

fn invalid(what: &str, e: &(dyn std::error::Error + 'static)) -> Failure {
    Failure::new(ofmpc_status::OFMPC_BUILD, format!("{what}: {}", chain(e)))
}

impl ofmpc_sim {
    /// The plant of `robot` carrying a point mass of `payload_kg` at the
    /// plan's first point, with the sensing, actuation and faults of `s`.
    fn new(
        robot: &ofmpc::Robot,
        plan: &JointReference,
        s: &Settings,
        payload_kg: f64,
    ) -> Result<Self, Failure> {
        let (n, ts) = (robot.dof(), plan.ts());
        let mut r = robot.clone();
        r.set_payload(Some(Payload::point_mass(payload_kg)))
            .map_err(|e| invalid("payload_kg", &e))?;
        let lost = LossSchedule::new(&s.faults, ts);
        let sensor = Sensor::new(&s.plant, n, ts, lost).map_err(|e| invalid("[plant]", &e))?;
        let mut plant = Plant::with_period(r, s.plant.clone(), plan.q(0), ts)
            .map_err(|e| invalid("[plant]", &e))?;
        let actuator = s.plant.actuator(plant.robot(), ts);
        let total = plan.len().saturating_add(s.simulation.hold_samples(ts));
        let measured = records_measurement(&s.plant, &s.faults);
        let mut sim = Self {
            recorder: Recorder::new(n, total, measured, false),
            reference: plan.clone(),
            steady_window_s: s.simulation.steady_window_s,
            payload_kg,
            k: 0,
            total,
            x: vec![0.0; 2 * n],
            x_true: vec![0.0; 2 * n],
            flange: plant.flange_position(),
            pending: false,
            sensor,
            actuator,
            plant,
        };
        sim.sensor
            .measure(&sim.plant.state(), &mut sim.x)
            .map_err(|e| invalid("the first reading", &e))?;
        Ok(sim)
    }

    /// The reading of the next sample (once per sample).
    fn read(&mut self) -> Res {
        if self.k >= self.total {
            return Err(Failure::new(
                ofmpc_status::OFMPC_END,
                "the run has no more samples",
            ));
        }
        if !self.pending {
            let n = self.x.len() / 2;
            self.sensor
                .read(&self.plant.state(), self.k, self.k > 0, &mut self.x)
                .map_err(|e| Failure::new(ofmpc_status::OFMPC_NUMERIC, e.to_string()))?;
            self.recorder.reading(&self.x);
            self.x_true[..n].copy_from_slice(self.plant.q());
            self.x_true[n..].copy_from_slice(self.plant.qd());
            self.flange = self.plant.flange_position();
            self.pending = true;
        }
        Ok(())
    }

    /// The torque `tau` of the sample read, over one period.
    fn apply(&mut self, tau: &[f64], step_us: f64) -> Res {
        if !self.pending {
            return Err(Failure::new(
                ofmpc_status::OFMPC_INVALID_ARG,
                "no reading awaits a torque: call ofmpc_sim_read first",
            ));
        }
        let numeric =
            |e: &dyn std::fmt::Display| Failure::new(ofmpc_status::OFMPC_NUMERIC, e.to_string());
        self.recorder.loading(self.actuator.account(tau));
        let applied = self
            .actuator
            .apply(tau, self.plant.state().path_sample)
            .map_err(|e| numeric(&e))?;
        self.plant.advance(applied).map_err(|e| numeric(&e))?;
        let (k, n) = (self.k, self.x.len() / 2);
        self.recorder.push(&Sample {
            t: k as f64 * self.reference.ts(),
            q: &self.x_true[..n],
            qd: &self.x_true[n..],
            tau: self.plant.applied_torque(),
            w: self.reference.q(k),
            flange_ref: self.reference.position(k),
            flange: self.flange,
            step_us,
            payload_mass_est: None,
        });
        self.k += 1;
        self.pending = false;
        Ok(())
    }
}

/// A simulated `robot` carrying a point mass of `payload_kg` (the
/// controller's model does not know it), at rest on `plan`'s first point,
/// with the `[plant]`, `[faults]` and `[simulation]` (hold_s,
/// steady_window_s) tables of `settings_toml` (NULL: ideal).
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_sim_new(
    robot: *const ofmpc_robot,
    plan: *const ofmpc_plan,
    settings_toml: *const std::ffi::c_char,
    payload_kg: f64,
    out: *mut *mut ofmpc_sim,
) -> ofmpc_status {
    boundary(|| {
        let robot = unsafe { arg(robot, "robot") }?;
        let plan = unsafe { arg(plan, "plan") }?;
        let s = Settings::parse(unsafe { opt_text(settings_toml, "settings_toml") }?)?;
        if out.is_null() {
            return Err(null("out"));
        }
        let sim = ofmpc_sim::new(&robot.0, &plan.0, &s, payload_kg)?;
        unsafe { give(out, sim) };
        Ok(())
    })
}

/// Samples of the run: the plan's and the hold's (0 for NULL).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_sim_samples(sim: *const ofmpc_sim) -> usize {
    query(0, || unsafe { sim.as_ref() }.map(|s| s.total))
}

/// The reading `[q; q̇]` (2n values) of the next sample into `x` (the same
/// reading again until `ofmpc_sim_apply`); `OFMPC_END` after the last.
/// Allocates nothing.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_sim_read(
    sim: *mut ofmpc_sim,
    x: *mut f64,
    x_len: usize,
) -> ofmpc_status {
    boundary(|| {
        let sim = unsafe { arg_mut(sim, "sim") }?;
        let x = unsafe { slice_mut(x, x_len, sim.x.len(), "x") }?;
        sim.read()?;
        x.copy_from_slice(&sim.x);
        Ok(())
    })
}

/// Applies the commanded torque `tau` (n values) through the drives over
/// one period and records the sample with the step's time `step_us` (µs).
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_sim_apply(
    sim: *mut ofmpc_sim,
    tau: *const f64,
    tau_len: usize,
    step_us: f64,
) -> ofmpc_status {
    boundary(|| {
        let sim = unsafe { arg_mut(sim, "sim") }?;
        let tau = unsafe { slice(tau, tau_len, sim.x.len() / 2, "tau") }?;
        sim.apply(tau, step_us)
    })
}

/// The metrics of the samples run so far, as `ofmpc run` computes them.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_sim_metrics(
    sim: *const ofmpc_sim,
    out: *mut ofmpc_metrics,
) -> ofmpc_status {
    boundary(|| {
        let sim = unsafe { arg(sim, "sim") }?;
        let out = unsafe { arg_mut(out, "out") }?;
        check_record(out.size, METRICS_V1, "ofmpc_metrics")?;
        let m = compute_metrics(
            "c-api",
            "c-api",
            sim.payload_kg,
            sim.recorder.record(),
            sim.steady_window_s,
            0.0,
            &RunOutcome::Completed,
        );
        let largest = |v: &[f64]| v.iter().fold(0.0_f64, |a, b| a.max(*b));
        out.samples = sim.recorder.record().len();
        out.cartesian_error_rms_mm = m.cartesian_error_rms_mm;
        out.cartesian_error_max_mm = m.cartesian_error_max_mm;
        out.steady_cartesian_error_mm = m.steady_cartesian_error_mm;
        out.steady_joint_error_max_rad = largest(&m.steady_joint_error_max_rad);
        out.joint_error_rms_max_rad = largest(&m.joint_error_rms_rad);
        out.step_time_median_us = m.step_time_us.median;
        out.step_time_max_us = m.step_time_us.max;
        Ok(())
    })
}

/// Frees a simulation (NULL: nothing).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_sim_free(sim: *mut ofmpc_sim) {
    let _ = boundary(|| {
        unsafe { take(sim) };
        Ok(())
    });
}
