//! `ofmpc.plan`: G-code → timed Cartesian path → joint reference (IK), over
//! `ofmpc::gcode`, `ofmpc::trajectory` and `ofmpc::reference`.

use crate::arrays::{array1, array2};
use crate::errors::to_py;
use crate::robot::PyRobot;
use nalgebra::UnitQuaternion;
use numpy::{PyArray1, PyArray2};
use ofmpc::control::MAX_HORIZON;
use ofmpc::gcode::{ParseOptions, PAPER_TABLE1};
use ofmpc::motion::Profile;
use ofmpc::motion::{plan as motion_plan, JointReference, Orientation, PlanOptions, TimingOptions};
use pyo3::prelude::*;

/// A joint reference w_k sampled every `ts` seconds along a program.
#[pyclass(name = "Reference", module = "ofmpc", frozen)]
pub struct PyReference {
    pub(crate) reference: JointReference,
    warnings: Vec<String>,
}

impl PyReference {
    fn rows<'py>(
        &self,
        py: Python<'py>,
        row: impl Fn(usize) -> Vec<f64>,
        cols: usize,
    ) -> Bound<'py, PyArray2<f64>> {
        let k = self.reference.len();
        array2(py, k, cols, (0..k).flat_map(row).collect())
    }
}

#[pymethods]
impl PyReference {
    /// Sample times (K,), s.
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let ts = self.reference.ts();
        let t: Vec<f64> = (0..self.reference.len()).map(|k| k as f64 * ts).collect();
        array1(py, &t)
    }
    /// Joint positions w_k (K, n), rad.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.rows(py, |k| self.reference.q(k).to_vec(), self.reference.dof())
    }
    /// Joint velocities (K, n), rad/s.
    #[getter]
    fn qd<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.rows(py, |k| self.reference.qd(k).to_vec(), self.reference.dof())
    }
    /// Joint accelerations (K, n), rad/s².
    #[getter]
    fn qdd<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.rows(py, |k| self.reference.qdd(k).to_vec(), self.reference.dof())
    }
    /// Flange position of the reference (K, 3), m, base frame.
    #[getter]
    fn cartesian<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.rows(py, |k| self.reference.position(k).to_vec(), 3)
    }
    /// Program line of each sample (K,).
    #[getter]
    fn lines(&self) -> Vec<usize> {
        (0..self.reference.len())
            .map(|k| self.reference.line(k))
            .collect()
    }
    /// Sample period (s).
    #[getter]
    fn ts(&self) -> f64 {
        self.reference.ts()
    }
    /// Number of joints n.
    #[getter]
    fn dof(&self) -> usize {
        self.reference.dof()
    }
    /// Duration of the path, (K − 1)·ts (s).
    #[getter]
    fn duration(&self) -> f64 {
        self.reference.duration()
    }
    /// The program reader's warnings (things it ignored).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }
    /// w_k (n,); past the end, the last sample.
    fn w<'py>(&self, py: Python<'py>, k: usize) -> Bound<'py, PyArray1<f64>> {
        array1(py, self.reference.q(k))
    }
    /// The preview w_{k+1}, …, w_{k+N} as an (N, n) array, the last sample held past the end.
    /// `horizon` is bounded like a controller's (at most `MAX_HORIZON` = 1000 samples).
    fn preview<'py>(
        &self,
        py: Python<'py>,
        k: usize,
        horizon: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        if horizon > MAX_HORIZON {
            return Err(to_py(format!(
                "preview horizon = {horizon}: at most {MAX_HORIZON} samples (the controllers' \
                 limit, ofmpc's MAX_HORIZON)"
            )));
        }
        let n = self.reference.dof();
        let mut out = vec![0.0; horizon * n];
        // Past the end every sample is the last: k beyond it reads the same and cannot overflow.
        self.reference
            .preview(k.min(self.reference.len()), horizon, &mut out);
        Ok(array2(py, horizon, n, out))
    }
    fn __len__(&self) -> usize {
        self.reference.len()
    }
    fn __repr__(&self) -> String {
        format!(
            "Reference(K={}, n={}, ts={}, duration={:.3} s)",
            self.reference.len(),
            self.reference.dof(),
            self.reference.ts(),
            self.reference.duration()
        )
    }
}

/// The time law named `profile` (`"septic"`/`"paper"` or `"quintic"`, any case).
fn profile_named(profile: &str) -> PyResult<Profile> {
    match profile.to_ascii_lowercase().as_str() {
        "septic" | "paper" => Ok(Profile::Septic),
        "quintic" => Ok(Profile::Quintic),
        other => Err(to_py(format!(
            "profile {other:?}: use \"septic\" (the paper's) or \"quintic\""
        ))),
    }
}

/// Plans a program (`text`; `None`: the paper's Table I program) for `robot`.
/// `name` prefixes error messages (the file name).
#[pyfunction]
#[pyo3(name = "_plan", signature = (text, name, robot, ts, origin_mm, profile, max_speed, max_accel, rpy_deg))]
#[allow(clippy::too_many_arguments)]
pub fn plan(
    py: Python<'_>,
    text: Option<String>,
    name: String,
    robot: &PyRobot,
    ts: f64,
    origin_mm: Option<(f64, f64, f64)>,
    profile: &str,
    max_speed: f64,
    max_accel: f64,
    rpy_deg: Option<(f64, f64, f64)>,
) -> PyResult<PyReference> {
    let profile = profile_named(profile)?;
    let robot = robot.robot().clone();
    let text = text.unwrap_or_else(|| PAPER_TABLE1.to_string());
    // Ctrl-C answered at once (issue #36).
    crate::run::answering_signals(py, move || {
        let orientation = match rpy_deg {
            None => Orientation::AtZero,
            Some((r, p, y)) => Orientation::Fixed(UnitQuaternion::from_euler_angles(
                r.to_radians(),
                p.to_radians(),
                y.to_radians(),
            )),
        };
        let options = PlanOptions {
            parse: ParseOptions {
                origin: origin_mm.map(|(x, y, z)| [x * 1e-3, y * 1e-3, z * 1e-3]),
                ..ParseOptions::default()
            },
            timing: TimingOptions {
                profile,
                max_speed,
                max_accel,
                ..TimingOptions::default()
            },
            orientation,
            ts,
        };
        // The library's one planning entry point (parse, blend, time, IK).
        let planned =
            motion_plan(&text, &robot, &options).map_err(|e| to_py(format!("{name}: {e}")))?;
        let (program, reference) = (planned.program, planned.reference);
        Ok(PyReference {
            reference,
            warnings: program
                .warnings
                .iter()
                .map(|w| format!("{name}: {w}"))
                .collect(),
        })
    })
}

/// Reads a program (`text`) as `ofmpc inspect program` does; returns its JSON text.
/// `start_mm`: the tool position before the program (default machine zero), or the start
/// pose of `robot`; `tool_table`: the path of a tool table (LinuxCNC's .tbl) for G43 H.
#[pyfunction]
#[pyo3(name = "_read_program", signature = (text, name, origin_mm, robot, tool_table=None))]
pub fn read_program(
    py: Python<'_>,
    text: Option<String>,
    name: String,
    origin_mm: Option<(f64, f64, f64)>,
    robot: Option<&PyRobot>,
    tool_table: Option<std::path::PathBuf>,
) -> PyResult<String> {
    let text = text.unwrap_or_else(|| PAPER_TABLE1.to_string());
    let tool_table = tool_table
        .map(|p| ofmpc_scenario::read_tool_table(&p, "tool_table"))
        .transpose()
        .map_err(to_py)?;
    let robot = robot.map(|r| r.robot().clone());
    crate::run::answering_signals(py, move || {
        let start = match &robot {
            Some(r) => ofmpc::motion::start_position(r)
                .ok_or_else(|| to_py("the robot's start pose has no tool position".to_string()))?,
            None => nalgebra::Vector3::zeros(),
        };
        // A G43 tool length lies along the robot's TCP z axis (LinuxCNC's −Z without one).
        let tool_axis = robot
            .as_ref()
            .and_then(|r| ofmpc::motion::tool_axis(r, Orientation::AtZero));
        let options = ParseOptions {
            origin: origin_mm.map(|(x, y, z)| [x * 1e-3, y * 1e-3, z * 1e-3]),
            start: Some(start),
            tool_axis,
            tool_table,
            ..ParseOptions::default()
        };
        let program =
            ofmpc::gcode::parse(&text, &options).map_err(|e| to_py(format!("{name}: {e}")))?;
        serde_json::to_string(&ofmpc_scenario::program_json_with_tool_axis(
            &program, start, tool_axis,
        ))
        .map_err(|e| to_py(e.to_string()))
    })
}
