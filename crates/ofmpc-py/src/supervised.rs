//! `ofmpc.SupervisedController`: the controller behind its guard
//! ([`ofmpc::sim::SupervisedController`]: measurement repair, plausibility,
//! safety limit, divergence rule and safe stop), stepped from Python, with the
//! command a position or velocity interface is sent — the controller's, or the
//! stop law's braking trajectory during a safe stop.

use crate::arrays::{array1, fill_shaped};
use crate::controller::{build, output_mode};
use crate::errors::to_py;
use crate::robot::PyRobot;
use numpy::PyArray1;
use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::sim::{
    LoopSettings, SafetySettings, SupervisedController, SupervisedInput, SupervisedStatus,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Mutex;

/// The library's supervised controller and the arrays of one step's arguments.
#[pyclass(name = "SupervisedController", module = "ofmpc")]
pub struct PySupervised {
    /// In a `Mutex` only to make the class `Sync`: reached by `get_mut`, without locking.
    inner: Mutex<SupervisedController>,
    dof: usize,
    horizon: usize,
    ts: f64,
    x: Vec<f64>,
    w: Vec<f64>,
    preview: Vec<f64>,
    /// The last step's status; None before the first step.
    status: Option<SupervisedStatus>,
    /// The drives' applied torque given to `set_applied_torque` (n).
    applied: Vec<f64>,
}

/// The name of a status in Python.
fn status_name(s: SupervisedStatus) -> &'static str {
    match s {
        SupervisedStatus::Controlled => "controlled",
        SupervisedStatus::RepairedMeasurement => "repaired_measurement",
        SupervisedStatus::Stopping => "stopping",
        SupervisedStatus::Stopped => "stopped",
        SupervisedStatus::Diverged => "diverged",
        _ => "non_finite_error",
    }
}

#[pymethods]
impl PySupervised {
    #[new]
    #[pyo3(signature = (kind, robot, ts=0.01, horizon=10, output="torque", output_lead_s=None,
        safe_stop=true, plausibility_check=false, max_joint_error_rad=None, delay_samples=0,
        output_smoothing_s=None, output_cycle_s=None, output_smoothing_step_s=None, **weights))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        kind: &str,
        robot: &PyRobot,
        ts: f64,
        horizon: usize,
        output: &str,
        output_lead_s: Option<f64>,
        safe_stop: bool,
        plausibility_check: bool,
        max_joint_error_rad: Option<f64>,
        delay_samples: usize,
        output_smoothing_s: Option<f64>,
        output_cycle_s: Option<f64>,
        output_smoothing_step_s: Option<f64>,
        weights: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let kind: ControllerKind = kind.parse().map_err(to_py)?;
        let settings = MpcSettings {
            ts,
            horizon,
            output: output_mode(output)?,
            output_lead_s,
            output_smoothing_s,
            output_cycle_s,
            output_smoothing_step_s,
            ..MpcSettings::default()
        };
        let controller = build(kind, robot, settings, weights)?;
        let rules = LoopSettings {
            safe_stop,
            plausibility_check,
            ..LoopSettings::default()
        }
        .supervisor(&SafetySettings {
            max_joint_error_rad,
        });
        let inner =
            SupervisedController::new(controller, robot.robot(), rules, delay_samples, true)
                .map_err(to_py)?;
        let (dof, horizon) = (inner.controller().dof(), inner.controller().horizon());
        Ok(Self {
            ts: inner.controller().settings().ts,
            inner: Mutex::new(inner),
            dof,
            horizon,
            x: vec![0.0; 2 * dof],
            w: vec![0.0; dof],
            preview: vec![0.0; horizon * dof],
            status: None,
            applied: vec![0.0; dof],
        })
    }

    /// Number of joints n.
    #[getter]
    fn dof(&self) -> usize {
        self.dof
    }
    /// Prediction horizon N.
    #[getter]
    fn horizon(&self) -> usize {
        self.horizon
    }
    /// Sampling period Ts (s).
    #[getter]
    fn ts(&self) -> f64 {
        self.ts
    }

    /// What the last step did: "controlled", "repaired_measurement", "stopping", "stopped",
    /// "diverged" (no stop law: stop the robot) or "non_finite_error"; None before the first.
    #[getter]
    fn last_status(&self) -> Option<&'static str> {
        self.status.map(status_name)
    }

    /// With output="position_velocity" or "velocity": the last step's command as a dict
    /// {"q_command", "qd_command", "qdd_command", "tau_command"} (n,) each — the controller's
    /// (its torque feed-forward: the identified payload's torque, see
    /// `Controller.set_applied_torque`; zeros during a stop), predicted
    /// output_lead_s ahead, while it controls; during a safe stop ("stopping", "stopped") the
    /// stop law's braking trajectory output_lead_s ahead, decelerating to rest and then
    /// holding (send it: the controller's last command is a moving target). None before the
    /// first step or with a torque output.
    #[getter]
    fn last_command<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let inner = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        if self.status.is_none() || inner.controller().settings().output.is_torque() {
            return Ok(None);
        }
        let (q, qd, qdd) = inner.command();
        let d = PyDict::new(py);
        d.set_item("q_command", array1(py, q))?;
        d.set_item("qd_command", array1(py, qd))?;
        d.set_item("qdd_command", array1(py, qdd))?;
        d.set_item("tau_command", array1(py, inner.command_torque()))?;
        Ok(Some(d))
    }

    /// The torque the drives applied over the period that just ended (n,), for the
    /// controller's identification through an interface that reports it (as
    /// `Controller.set_applied_torque`); call it before `step`.
    fn set_applied_torque(&mut self, tau: &Bound<'_, PyAny>) -> PyResult<()> {
        fill_shaped("tau", tau, &[("(dof,)", &[self.dof])], &mut self.applied)?;
        let inner = self.inner.get_mut().unwrap_or_else(|e| e.into_inner());
        inner.set_applied_torque(&self.applied).map_err(to_py)
    }

    /// Starts a run at the reading x0 = [q; q̇] (2n,): no stop in progress.
    fn reset(&mut self, x0: &Bound<'_, PyAny>) -> PyResult<()> {
        fill_shaped("x0", x0, &[("(2·dof,)", &[2 * self.dof])], &mut self.x)?;
        self.status = None;
        let inner = self.inner.get_mut().unwrap_or_else(|e| e.into_inner());
        inner.reset(&self.x).map_err(to_py)
    }

    /// One supervised sample at time t (s): raw reading x (2n,; NaN where a value was lost),
    /// reference w_k (n,), preview ((N, n) or (N·n,)) → the torque (n,): the controller's, or
    /// the stop law's during a safe stop (`last_status` says which). Raises `OfmpcError` for
    /// an argument of another shape and for a failed step no stop law takes over.
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        x: &Bound<'py, PyAny>,
        w_k: &Bound<'py, PyAny>,
        preview: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (n, h) = (self.dof, self.horizon);
        fill_shaped("x", x, &[("(2·dof,)", &[2 * n])], &mut self.x)?;
        fill_shaped("w_k", w_k, &[("(dof,)", &[n])], &mut self.w)?;
        fill_shaped(
            "preview",
            preview,
            &[("(horizon, dof)", &[h, n]), ("(horizon·dof,)", &[h * n])],
            &mut self.preview,
        )?;
        let inner = self.inner.get_mut().unwrap_or_else(|e| e.into_inner());
        let input = SupervisedInput {
            t,
            x: &self.x,
            w_k: &self.w,
            preview: &self.preview,
            truth: None,
        };
        let out = inner.step(&input).map_err(to_py)?;
        self.status = Some(out.status);
        Ok(array1(py, &out.tau))
    }

    fn __repr__(&self) -> String {
        let c = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        format!(
            "SupervisedController({:?}, dof={}, horizon={}, ts={})",
            c.controller().kind().name(),
            self.dof,
            self.horizon,
            self.ts
        )
    }
}
