//! `ofmpc.Controller`: one controller, stepped from Python: a thin wrapper of
//! the library's one stepping object, [`ofmpc::control::Controller`] (built by
//! [`ControllerBuilder`]; it owns its model of the robot, its buffers and its
//! output).

use crate::arrays::{array1, array2, fill_shaped};
use crate::errors::to_py;
use crate::robot::PyRobot;
use numpy::PyArray1;
use ofmpc::control::{
    BaselineSettings, Controller, ControllerBuilder, ControllerKind, MpcSettings, OutputMode,
    Solver, StepError, StepInput, StepStatus, StepTelemetry, Weight,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Mutex;

/// The library's controller and the arrays of one step's arguments.
#[pyclass(name = "Controller", module = "ofmpc")]
pub struct PyController {
    /// In a `Mutex` only to make the class `Sync` (a Python requirement):
    /// `step` and `reset` take `&mut self` and reach it by `get_mut`, without locking.
    controller: Mutex<Controller>,
    kind: ControllerKind,
    dof: usize,
    horizon: usize,
    ts: f64,
    x: Vec<f64>,
    w: Vec<f64>,
    preview: Vec<f64>,
    /// Cost, `max|R_ii|/min|R_ii|` and ZOH doublings of the last successful step.
    info: Option<(f64, f64, u32)>,
    /// The telemetry of the last step (also a failed one's).
    telemetry: Option<StepTelemetry>,
    /// With `gains=True`: the first-stage gain law of the last successful step
    /// (`K` n×2n row-major, `tau_ff`, `x_lin`), copied into buffers sized at construction.
    gains: Option<(Vec<f64>, Vec<f64>, Vec<f64>)>,
    /// Whether `gains` holds a step's law (false before the first successful step).
    gains_set: bool,
    /// With a position or velocity `output`: the last successful step's predicted command
    /// (q, q̇, q̈ one lead time ahead, and the torque feed-forward), n values each, in buffers
    /// sized at construction; None with a torque output.
    command: Option<[Vec<f64>; 4]>,
    /// The drives' applied torque given to `set_applied_torque` (n).
    applied: Vec<f64>,
    /// Whether `command` holds a step's command (false before the first successful step).
    command_set: bool,
}

/// The keyword arguments of `Controller()` that are weights.
const WEIGHTS: [&str; 7] = [
    "q_yw",
    "q_dy",
    "q_du",
    "q_u",
    "pid_bandwidth",
    "ctc_bandwidth",
    "dob_observer_bandwidth",
];

/// Whether keyword `key` (a weight or `solver`) has an effect on a controller of `kind`: the
/// predictive weights and `solver` on the paper's controllers and dob-mpc, each baseline's
/// bandwidth on its own kind only (issue #36: `Controller("pid", q_yw=5)` was ignored).
fn applies(key: &str, kind: ControllerKind) -> bool {
    let predictive = !matches!(kind.base(), ControllerKind::Pid | ControllerKind::Ctc);
    match key {
        "pid_bandwidth" => kind == ControllerKind::Pid,
        "ctc_bandwidth" => kind.base() == ControllerKind::Ctc,
        "dob_observer_bandwidth" => kind == ControllerKind::DobMpc,
        _ => predictive,
    }
}

/// The keywords that apply to `kind`, for a message.
fn applying(kind: ControllerKind) -> String {
    let all = WEIGHTS.iter().copied().chain(["solver"]);
    let keys: Vec<&str> = all.filter(|k| applies(k, kind)).collect();
    keys.join(", ")
}

/// Reads `solver=`: `"dense-qr"`, `"structured"` or `"auto"` (the scenario's names).
fn solver(value: &Bound<'_, PyAny>) -> PyResult<Solver> {
    match value.extract::<String>().as_deref() {
        Ok("dense-qr") => Ok(Solver::DenseQr),
        Ok("structured") => Ok(Solver::Structured),
        Ok("auto") => Ok(Solver::Auto),
        _ => Err(to_py(format!(
            "solver={value}: give \"dense-qr\", \"structured\" or \"auto\""
        ))),
    }
}

/// Reads a weight: a number (times I) or one value per joint.
fn weight(name: &str, value: &Bound<'_, PyAny>) -> PyResult<Weight> {
    if let Ok(s) = value.extract::<f64>() {
        return Ok(Weight::Scalar(s));
    }
    value
        .extract::<Vec<f64>>()
        .map(Weight::Diagonal)
        .map_err(|_| {
            to_py(format!(
                "{name}={value}: give a number (times I) or one number per joint"
            ))
        })
}

/// The keyword arguments of `Controller(...)` (`solver`, the weights, the baselines'
/// bandwidths) into `settings` and `baselines`; a keyword that does not apply to `kind` or is
/// unknown is an error.
fn apply_keywords(
    kind: ControllerKind,
    w: &Bound<'_, PyDict>,
    settings: &mut MpcSettings,
    baselines: &mut BaselineSettings,
) -> PyResult<()> {
    for (key, value) in w.iter() {
        let key: String = key.extract()?;
        if (key == "solver" || WEIGHTS.contains(&key.as_str())) && !applies(&key, kind) {
            return Err(to_py(format!(
                "{key}= does not apply to a {:?} controller (it would be ignored): \
                 remove it; a {:?} controller takes ts, horizon and {}",
                kind.name(),
                kind.name(),
                applying(kind)
            )));
        }
        if key == "solver" {
            settings.solver = solver(&value)?;
            continue;
        }
        if !WEIGHTS.contains(&key.as_str()) {
            return Err(to_py(format!(
                "unknown weight or keyword argument {key:?}: Controller() takes ts, \
                 horizon, solver (\"dense-qr\", \"structured\" or \"auto\"), the weights \
                 q_yw, q_dy, q_du and q_u, and the baselines' bandwidths pid_bandwidth, \
                 ctc_bandwidth and dob_observer_bandwidth"
            )));
        }
        let wt = weight(&key, &value)?;
        match key.as_str() {
            "q_yw" => settings.q_yw = wt,
            "q_dy" => settings.q_dy = wt,
            "q_du" => settings.q_du = wt,
            "q_u" => settings.q_u = wt,
            // The baselines' bandwidths (rad/s): pid, ctc/ctc-adaptive, dob-mpc.
            "pid_bandwidth" => baselines.pid_bandwidth = wt,
            "ctc_bandwidth" => baselines.ctc_bandwidth = wt,
            "dob_observer_bandwidth" => baselines.dob_observer_bandwidth = wt,
            _ => {
                return Err(to_py(format!(
                    "unknown weight {key:?}: the weights are q_yw, q_dy, q_du and q_u, \
                     the baselines' bandwidths pid_bandwidth, ctc_bandwidth and \
                     dob_observer_bandwidth"
                )))
            }
        }
    }
    Ok(())
}

/// The output mode named `output` ("torque", "position_velocity", "velocity").
pub(crate) fn output_mode(output: &str) -> PyResult<OutputMode> {
    OutputMode::ALL
        .into_iter()
        .find(|m| m.name() == output)
        .ok_or_else(|| {
            to_py(format!(
                "output={output:?}: give \"torque\", \"position_velocity\" or \"velocity\""
            ))
        })
}

/// The controller `kind` for `robot` with `settings` and the keyword weights of
/// `Controller()` (applied to `settings` and to the baselines' gains).
pub(crate) fn build(
    kind: ControllerKind,
    robot: &PyRobot,
    mut settings: MpcSettings,
    weights: Option<&Bound<'_, PyDict>>,
) -> PyResult<Controller> {
    let mut baselines = BaselineSettings::default();
    if let Some(w) = weights {
        apply_keywords(kind, w, &mut settings, &mut baselines)?;
    }
    let mut builder = ControllerBuilder::new(kind, robot.robot()).settings(settings);
    if kind.is_baseline() {
        builder = builder.baselines(baselines);
    }
    // A settings error keeps its own message (`BuildError::Settings` is transparent).
    builder.build().map_err(to_py)
}

#[pymethods]
impl PyController {
    #[new]
    #[pyo3(signature = (kind, robot, ts=0.01, horizon=10, gains=false, output="torque", output_lead_s=None, output_smoothing_s=None, output_cycle_s=None, output_smoothing_step_s=None, **weights))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        kind: &str,
        robot: &PyRobot,
        ts: f64,
        horizon: usize,
        gains: bool,
        output: &str,
        output_lead_s: Option<f64>,
        output_smoothing_s: Option<f64>,
        output_cycle_s: Option<f64>,
        output_smoothing_step_s: Option<f64>,
        weights: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let kind: ControllerKind = kind.parse().map_err(to_py)?;
        let output = output_mode(output)?;
        let settings = MpcSettings {
            ts,
            horizon,
            gains,
            output,
            output_lead_s,
            output_smoothing_s,
            output_cycle_s,
            output_smoothing_step_s,
            ..MpcSettings::default()
        };
        let n = robot.robot().dof();
        let controller = build(kind, robot, settings, weights)?;
        Ok(Self {
            kind: controller.kind(),
            dof: controller.dof(),
            horizon: controller.horizon(),
            ts: controller.settings().ts,
            controller: Mutex::new(controller),
            x: vec![0.0; 2 * n],
            w: vec![0.0; n],
            preview: vec![0.0; horizon * n],
            info: None,
            telemetry: None,
            gains: gains.then(|| (vec![0.0; 2 * n * n], vec![0.0; n], vec![0.0; 2 * n])),
            gains_set: false,
            command: (!output.is_torque())
                .then(|| [vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]]),
            applied: vec![0.0; n],
            command_set: false,
        })
    }

    /// "usual", "first", "second", "first-adaptive", "second-adaptive",
    /// "pid", "ctc", "ctc-adaptive" or "dob-mpc".
    #[getter]
    fn kind(&self) -> &'static str {
        self.kind.name()
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
    /// The input u of the last successful step (n,); zero after reset.
    #[getter]
    fn input<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let c = self.controller.lock().unwrap_or_else(|e| e.into_inner());
        array1(py, c.input())
    }
    /// Diagnostics of the last successful step as a dict (cost, r_diag_ratio,
    /// zoh_squarings), or None before the first.
    #[getter]
    fn last_info<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.info
            .map(|(cost, r_diag_ratio, zoh_squarings)| {
                let d = PyDict::new(py);
                d.set_item("cost", cost)?;
                d.set_item("r_diag_ratio", r_diag_ratio)?;
                d.set_item("zoh_squarings", zoh_squarings)?;
                Ok(d)
            })
            .transpose()
    }

    /// Telemetry of the last step as a dict, or None before the first: "model_time_us",
    /// "solve_time_us", "total_time_us" (µs), "qp_iterations", "active_constraints",
    /// "budget_slack_us" (None without a step budget), "fallback" ("none", "best_feasible",
    /// "shifted_plan", "hold") and "budget_hit".
    #[getter]
    fn last_telemetry<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.telemetry
            .map(|t| {
                let us = |d: std::time::Duration| d.as_secs_f64() * 1e6;
                let d = PyDict::new(py);
                d.set_item("model_time_us", us(t.model_time))?;
                d.set_item("solve_time_us", us(t.solve_time))?;
                d.set_item("total_time_us", us(t.total_time))?;
                d.set_item("qp_iterations", t.qp_iterations)?;
                d.set_item("active_constraints", t.active_constraints)?;
                d.set_item("budget_slack_us", t.budget_slack_us)?;
                d.set_item("fallback", t.fallback.name())?;
                d.set_item("budget_hit", t.budget_hit)?;
                Ok(d)
            })
            .transpose()
    }

    /// With `gains=True`: the first-stage feedback law of the last successful step as a dict
    /// {"gain": K (n, 2n), "tau_ff": τ_k (n,), "x_lin": x_k (2n,)}, so that between MPC samples
    /// τ ≈ tau_ff + K (x − x_lin); None before the first step or with `gains=False`.
    #[getter]
    fn last_gains<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let n = self.dof;
        match &self.gains {
            Some((k, tau_ff, x_lin)) if self.gains_set => {
                let d = PyDict::new(py);
                d.set_item("gain", array2(py, n, 2 * n, k.clone()))?;
                d.set_item("tau_ff", array1(py, tau_ff))?;
                d.set_item("x_lin", array1(py, x_lin))?;
                Ok(Some(d))
            }
            _ => Ok(None),
        }
    }

    /// With output="position_velocity" or "velocity": the last successful step's command as a
    /// dict {"q_command", "qd_command", "qdd_command", "tau_command"} (n,) each: the positions,
    /// velocities and accelerations its model predicted output_lead_s ahead, and the torque
    /// feed-forward of an identified payload (zeros unless an adaptive kind is given
    /// `set_applied_torque`); None before the first step or with a torque output.
    #[getter]
    fn last_command<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.command
            .as_ref()
            .filter(|_| self.command_set)
            .map(|[q, qd, qdd, tau]| {
                let d = PyDict::new(py);
                d.set_item("q_command", array1(py, q))?;
                d.set_item("qd_command", array1(py, qd))?;
                d.set_item("qdd_command", array1(py, qdd))?;
                d.set_item("tau_command", array1(py, tau))?;
                Ok(d)
            })
            .transpose()
    }

    /// The torque the drives applied over the period that just ended (n,), for an interface
    /// that closes its own joint loop and reports it (UR RTDE's joint torques, KUKA FRI's
    /// measured torque): call it before `step`. The adaptive kinds then identify their payload
    /// from it also with output="position_velocity" or "velocity", and `last_command`'s
    /// "tau_command" carries it as a torque feed-forward; the other kinds ignore it. Raises
    /// `OfmpcError` for another shape or a value that is not finite.
    fn set_applied_torque(&mut self, tau: &Bound<'_, PyAny>) -> PyResult<()> {
        let n = self.dof;
        fill_shaped("tau", tau, &[("(dof,)", &[n])], &mut self.applied)?;
        self.controller
            .get_mut()
            .unwrap_or_else(|e| e.into_inner())
            .set_applied_torque(&self.applied)
            .map_err(to_py)
    }

    /// Starts a run at the measured state x0 = [q; q̇] (2n,). Required before the first
    /// `step` (a step before it raises `OfmpcError`: the controller's memory of the last input
    /// and output would otherwise be zeros, not the robot's state).
    fn reset(&mut self, x0: &Bound<'_, PyAny>) -> PyResult<()> {
        let n2 = 2 * self.dof;
        fill_shaped("x0", x0, &[("(2·dof,)", &[n2])], &mut self.x)?;
        self.info = None;
        self.telemetry = None;
        self.gains_set = false;
        self.command_set = false;
        self.controller
            .get_mut()
            .unwrap_or_else(|e| e.into_inner())
            .reset(&self.x)
            .map_err(to_py)
    }

    /// One control step: measured state x (2n,), current reference w_k (n,),
    /// preview w_{k+1..k+N} ((N, n) or (N·n,)) → torque τ_k (n,). Raises `OfmpcError` before
    /// the first `reset`, and for an argument of another shape (a transposed preview, a column
    /// `x`) or of a complex, datetime or string dtype, naming the argument.
    fn step<'py>(
        &mut self,
        py: Python<'py>,
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
        // The arguments first (an argument error names the argument whatever the state), then
        // the state: a controller never reset has no state to step from.
        let controller = self.controller.get_mut().unwrap_or_else(|e| e.into_inner());
        let input = StepInput {
            x: &self.x,
            w_k: &self.w,
            preview: &self.preview,
        };
        // The GIL released: a large robot's step may take long (other Python threads run).
        let out = match py.detach(move || controller.step(&input)) {
            Ok(out) => out,
            Err(StepError::NotReset) => {
                return Err(to_py(
                    "step before reset: call reset(x0) with the measured state [q, q̇] first",
                ))
            }
            Err(e) => return Err(to_py(e)),
        };
        self.telemetry = Some(out.telemetry);
        // A numerical failure raises (the controller holds its last torque and state).
        if let StepStatus::HeldLastTorque(failure) = out.status {
            return Err(to_py(failure));
        }
        self.info = Some((out.cost, out.r_diag_ratio, out.zoh_squarings));
        if let Some((k, tau_ff, x_lin)) = self.gains.as_mut() {
            k.copy_from_slice(&out.gain);
            tau_ff.copy_from_slice(&out.tau_ff);
            x_lin.copy_from_slice(&out.x_lin);
            self.gains_set = true;
        }
        if let Some([q, qd, qdd, tau]) = self.command.as_mut() {
            q.copy_from_slice(&out.q_command);
            qd.copy_from_slice(&out.qd_command);
            qdd.copy_from_slice(&out.qdd_command);
            tau.copy_from_slice(&out.tau_command);
            self.command_set = true;
        }
        Ok(array1(py, &out.tau))
    }

    fn __repr__(&self) -> String {
        format!(
            "Controller({:?}, dof={}, horizon={}, ts={})",
            self.kind(),
            self.dof(),
            self.horizon(),
            self.ts()
        )
    }
}
