//! `ofmpc.Robot`: a robot model (URDF + drives + payload) and its rigid-body
//! algorithms, over `ofmpc::robot` and `ofmpc::dynamics`.

use crate::arrays::{array1, array2, matrix, vec_of, Matrix, Vector};
use crate::errors::to_py;
use nalgebra::{Matrix3, Vector3};
use numpy::{PyArray1, PyArray2};
use ofmpc::dynamics::{self, RobotDynamics};
use ofmpc::robot::{ChainOptions, Drives, Payload, Robot};
use pyo3::prelude::*;
use std::path::PathBuf;

/// A serial robot with its drives' armature and an optional payload at the flange.
#[pyclass(name = "Robot", module = "ofmpc")]
#[derive(Clone)]
pub struct PyRobot {
    pub(crate) dynamics: RobotDynamics,
}

impl PyRobot {
    pub(crate) fn robot(&self) -> &Robot {
        self.dynamics.robot()
    }
}

#[pymethods]
impl PyRobot {
    /// The built-in ABB IRB 140 with its drives (armature, torque and speed limits).
    #[staticmethod]
    fn irb140() -> Self {
        Self {
            dynamics: RobotDynamics::new(Robot::irb140()),
        }
    }

    /// A robot from a URDF file, with an optional drives file (TOML: armature and limits),
    /// the link that ends the chain (`tip`: joints beyond it or on other branches are held
    /// rigid), the tool centre point relative to the tip (`tcp`: a 4×4 homogeneous matrix,
    /// m) and the start pose (`start_q`, one value per joint within the limits).
    #[staticmethod]
    #[pyo3(signature = (path, drives=None, tip=None, tcp=None, start_q=None))]
    fn from_urdf(
        py: Python<'_>,
        path: PathBuf,
        drives: Option<PathBuf>,
        tip: Option<String>,
        tcp: Option<Matrix<'_>>,
        start_q: Option<Vector<'_>>,
    ) -> PyResult<Self> {
        let tcp = match tcp {
            None => None,
            Some(m) => {
                let a = m.as_array();
                if a.shape() != [4, 4] {
                    return Err(to_py(format!(
                        "tcp has shape {:?}: give a 4×4 homogeneous matrix (rotation, position in m)",
                        a.shape()
                    )));
                }
                Some(ofmpc::spatial::Transform {
                    rot: Matrix3::from_fn(|r, c| a[[r, c]]),
                    pos: Vector3::new(a[[0, 3]], a[[1, 3]], a[[2, 3]]),
                })
            }
        };
        let options = ChainOptions { tip, tcp };
        let start_q = start_q.map(|q| vec_of(&q));
        // The GIL released: a large URDF takes a while to read and check.
        let robot = py.detach(move || -> Result<Robot, String> {
            let mut robot =
                Robot::from_urdf_file_with(&path, &options).map_err(|e| e.to_string())?;
            if let Some(d) = drives {
                let drives = Drives::from_file(&d).map_err(|e| e.to_string())?;
                robot.apply_drives(&drives).map_err(|e| e.to_string())?;
            }
            if let Some(q) = start_q {
                robot.set_start_q(&q).map_err(|e| e.to_string())?;
            }
            Ok(robot)
        });
        Ok(Self {
            dynamics: RobotDynamics::new(robot.map_err(to_py)?),
        })
    }

    /// The link that ends the chain (the flange frame's link).
    #[getter]
    fn tip(&self) -> String {
        self.robot().flange_name().to_string()
    }

    /// The start pose (the IK's first seed and the initial state of a run).
    #[getter]
    fn start_q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, self.robot().start_q())
    }

    /// Number of joints n.
    #[getter]
    fn dof(&self) -> usize {
        self.robot().dof()
    }

    /// Robot name (URDF `<robot name>`).
    #[getter]
    fn name(&self) -> String {
        self.robot().name().to_string()
    }

    /// Joint names, base to tip.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.robot()
            .joints()
            .iter()
            .map(|j| j.name.clone())
            .collect()
    }

    /// Armature (reflected rotor inertia, kg·m²) of every joint.
    #[getter]
    fn armature<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, &self.robot().armature().collect::<Vec<_>>())
    }

    /// Gravity vector in the base frame (m/s²).
    #[getter]
    fn gravity_vector<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, self.robot().gravity().as_slice())
    }

    /// Payload at the flange as (mass_kg, com (3,), inertia (3, 3)), or None.
    #[getter]
    #[allow(clippy::type_complexity)]
    fn payload<'py>(
        &self,
        py: Python<'py>,
    ) -> Option<(f64, Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>)> {
        self.robot().payload().map(|p| {
            let inertia: Vec<f64> = (0..3)
                .flat_map(|i| (0..3).map(move |j| p.inertia[(i, j)]))
                .collect();
            (
                p.mass,
                array1(py, p.com.as_slice()),
                array2(py, 3, 3, inertia),
            )
        })
    }

    /// Attaches a rigid payload at the flange (replacing any previous one);
    /// `mass_kg = 0` removes it.
    #[pyo3(signature = (mass_kg, com=(0.0, 0.0, 0.0), inertia=None))]
    fn set_payload(
        &mut self,
        mass_kg: f64,
        com: (f64, f64, f64),
        inertia: Option<Matrix<'_>>,
    ) -> PyResult<()> {
        let inertia = match inertia {
            None => Matrix3::zeros(),
            Some(m) => {
                let a = m.as_array();
                if a.dim() != (3, 3) {
                    return Err(to_py(format!(
                        "payload inertia has shape {:?}: give a 3×3 matrix about the centre of mass",
                        a.dim()
                    )));
                }
                Matrix3::from_fn(|i, j| a[(i, j)])
            }
        };
        let payload = (mass_kg != 0.0 || inertia != Matrix3::zeros()).then_some(Payload {
            mass: mass_kg,
            com: Vector3::new(com.0, com.1, com.2),
            inertia,
        });
        self.dynamics
            .robot_mut()
            .set_payload(payload)
            .map_err(to_py)
    }

    /// Inverse dynamics τ = H(q) q̈ + C(q, q̇) q̇ + g(q) (RNEA, armature included), shape (n,).
    fn rnea<'py>(
        &mut self,
        py: Python<'py>,
        q: Vector<'_>,
        qd: Vector<'_>,
        qdd: Vector<'_>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (q, qd, qdd) = (vec_of(&q), vec_of(&qd), vec_of(&qdd));
        let (robot, ws) = self.dynamics.parts();
        let tau = py
            .detach(|| dynamics::rnea(robot, ws, &q, &qd, &qdd))
            .map_err(to_py)?;
        Ok(array1(py, tau.as_slice()))
    }

    /// Joint-space inertia matrix H(q) (CRBA, armature on the diagonal), shape (n, n).
    fn mass_matrix<'py>(
        &mut self,
        py: Python<'py>,
        q: Vector<'_>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let q = vec_of(&q);
        let (robot, ws) = self.dynamics.parts();
        let h = py.detach(|| dynamics::crba(robot, ws, &q)).map_err(to_py)?;
        Ok(matrix(py, h))
    }

    /// Coriolis matrix C(q, q̇) from Christoffel symbols (Ḣ − 2C skew-symmetric), shape (n, n).
    fn coriolis_matrix<'py>(
        &mut self,
        py: Python<'py>,
        q: Vector<'_>,
        qd: Vector<'_>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (q, qd) = (vec_of(&q), vec_of(&qd));
        let (robot, ws) = self.dynamics.parts();
        let c = py
            .detach(|| dynamics::coriolis_matrix(robot, ws, &q, &qd))
            .map_err(to_py)?;
        Ok(matrix(py, c))
    }

    /// Gravity torque g(q), shape (n,).
    fn gravity<'py>(
        &mut self,
        py: Python<'py>,
        q: Vector<'_>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let q = vec_of(&q);
        let (robot, ws) = self.dynamics.parts();
        let g = py
            .detach(|| dynamics::gravity(robot, ws, &q))
            .map_err(to_py)?;
        Ok(array1(py, g.as_slice()))
    }

    /// Flange pose in the base frame as a 4×4 homogeneous matrix (the tool centre point's
    /// when `from_urdf` was given a `tcp`).
    fn flange_pose<'py>(
        &mut self,
        py: Python<'py>,
        q: Vector<'_>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (robot, ws) = self.dynamics.parts();
        let f = dynamics::forward_kinematics(robot, ws, &vec_of(&q)).map_err(to_py)?;
        let mut m = nalgebra::DMatrix::<f64>::identity(4, 4);
        m.view_mut((0, 0), (3, 3)).copy_from(&f.rot);
        m.view_mut((0, 3), (3, 1)).copy_from(&f.pos);
        Ok(matrix(py, &m))
    }

    /// Geometric flange Jacobian (6, n): rows 0..3 linear velocity of the flange origin,
    /// rows 3..6 angular velocity, both in the base frame.
    fn flange_jacobian<'py>(
        &mut self,
        py: Python<'py>,
        q: Vector<'_>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let q = vec_of(&q);
        let (robot, ws) = self.dynamics.parts();
        let j = py
            .detach(|| dynamics::flange_jacobian(robot, ws, &q))
            .map_err(to_py)?;
        Ok(matrix(py, j))
    }

    /// Forward dynamics q̈ = H⁻¹(τ − C q̇ − g), shape (n,).
    fn forward_dynamics<'py>(
        &mut self,
        py: Python<'py>,
        q: Vector<'_>,
        qd: Vector<'_>,
        tau: Vector<'_>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (q, qd, tau) = (vec_of(&q), vec_of(&qd), vec_of(&tau));
        let (robot, ws) = self.dynamics.parts();
        let a = py
            .detach(|| dynamics::forward_dynamics(robot, ws, &q, &qd, &tau))
            .map_err(to_py)?;
        Ok(array1(py, a.as_slice()))
    }

    /// A copy of this robot.
    fn copy(&self) -> Self {
        self.clone()
    }

    fn __repr__(&self) -> String {
        let r = self.robot();
        format!(
            "Robot({:?}, dof={}, payload_kg={})",
            r.name(),
            r.dof(),
            r.payload().map_or(0.0, |p| p.mass)
        )
    }
}
