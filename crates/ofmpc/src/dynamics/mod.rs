//! Rigid-body algorithms for a serial [`Robot`]: `H(q) q̈ + C(q, q̇) q̇ + g(q) = τ`.
//!
//! One algorithm per file, Pinocchio's layout: the [`Robot`] is constant, a
//! [`Workspace`] sized once by [`Workspace::new`] receives the results, and no
//! algorithm allocates. Every entry point checks the lengths and finiteness of
//! its vectors and returns a [`ModelError`](crate::robot::ModelError) instead of panicking.
//!
//! | algorithm | file | result |
//! |---|---|---|
//! | forward kinematics | `kinematics.rs` | body poses, flange pose |
//! | geometric Jacobian | `kinematics.rs` | 6×n flange Jacobian |
//! | inverse dynamics (RNEA) | `rnea.rs` | τ |
//! | joint-space inertia (CRBA), Coriolis matrix, gravity | `terms.rs` | H, C, g |
//! | forward dynamics (Cholesky of H) | `forward.rs` | q̈ |

mod forward;
pub(crate) mod friction;
mod kinematics;
mod rnea;
mod terms;
mod workspace;

pub use forward::forward_dynamics;
#[doc(hidden)]
pub use forward::{kinetic_energy, potential_energy};
pub use kinematics::{flange_jacobian, forward_kinematics};
pub use rnea::rnea;
pub use terms::{coriolis_matrix, crba, gravity, joint_space_terms};
pub use workspace::Workspace;

pub(crate) use kinematics::local_axis;

/// Runs RNEA (`ws.tau`, `ws.local`) without checks and returns the last
/// body's spatial velocity and acceleration (gravity included), in its frame:
/// what the payload regressor of [`crate::ident`] needs.
pub(crate) fn rnea_unchecked_parts(
    robot: &Robot,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> (crate::spatial::Motion, crate::spatial::Motion) {
    rnea::rnea_unchecked(robot, ws, q, qd, qdd);
    let last = robot.dof() - 1;
    (ws.v[last], ws.a[last])
}

use crate::robot::Robot;
use nalgebra::{DMatrix, DVector};

/// What a controller or a simulator needs of a robot model: the terms of the
/// Lagrange form `H(q) q̈ + C(q, q̇) q̇ + g(q) = τ` (Eq. (1)–(5) of the paper).
///
/// Implementations must not allocate in [`JointSpaceDynamics::terms`]: it is
/// called inside the real-time control step.
pub trait JointSpaceDynamics {
    /// Number of joints `n` (degrees of freedom).
    fn dof(&self) -> usize;
    /// Writes the joint-space inertia `H(q)` (n×n, including the drives'
    /// armature), the Coriolis matrix `C(q, q̇)` (n×n, Christoffel-consistent:
    /// `Ḣ − 2C` skew-symmetric) and gravity `g(q)` (n) into the given buffers,
    /// which the caller has sized n×n, n×n and n.
    fn terms(
        &mut self,
        q: &[f64],
        qd: &[f64],
        h: &mut DMatrix<f64>,
        c: &mut DMatrix<f64>,
        g: &mut DVector<f64>,
    );

    /// The rigid-body model behind these terms, when there is one: adaptive
    /// controllers identify the payload with it and update its payload
    /// ([`Robot::set_payload`]). `None` by default.
    fn robot_dynamics_mut(&mut self) -> Option<&mut RobotDynamics> {
        None
    }
}

/// A robot together with its workspace: the object a controller or a
/// simulator owns.
#[derive(Debug, Clone)]
pub struct RobotDynamics {
    robot: Robot,
    ws: Workspace,
}

impl RobotDynamics {
    /// Sizes a workspace for `robot`.
    pub fn new(robot: Robot) -> Self {
        let ws = Workspace::new(&robot);
        Self { robot, ws }
    }
    /// The robot.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }
    /// The robot, to change its payload or gravity (the workspace stays valid:
    /// the number of joints cannot change).
    pub fn robot_mut(&mut self) -> &mut Robot {
        &mut self.robot
    }
    /// The robot and the workspace, to call the algorithms directly.
    pub fn parts(&mut self) -> (&Robot, &mut Workspace) {
        (&self.robot, &mut self.ws)
    }
}

impl JointSpaceDynamics for RobotDynamics {
    fn dof(&self) -> usize {
        self.robot.dof()
    }
    fn robot_dynamics_mut(&mut self) -> Option<&mut RobotDynamics> {
        Some(self)
    }
    /// On a wrong length or non-finite input, writes NaN everywhere so that the
    /// caller's own finiteness check reports it.
    fn terms(
        &mut self,
        q: &[f64],
        qd: &[f64],
        h: &mut DMatrix<f64>,
        c: &mut DMatrix<f64>,
        g: &mut DVector<f64>,
    ) {
        match joint_space_terms(&self.robot, &mut self.ws, q, qd) {
            Ok(())
                if h.shape() == self.ws.h.shape()
                    && c.shape() == self.ws.c.shape()
                    && g.len() == self.ws.g.len() =>
            {
                h.copy_from(&self.ws.h);
                c.copy_from(&self.ws.c);
                g.copy_from(&self.ws.g);
            }
            _ => {
                h.fill(f64::NAN);
                c.fill(f64::NAN);
                g.fill(f64::NAN);
            }
        }
    }
}

impl crate::ik::ForwardKinematics for RobotDynamics {
    fn dof(&self) -> usize {
        self.robot.dof()
    }
    /// NaN pose on a wrong length or non-finite `q`.
    fn flange_pose(&mut self, q: &[f64]) -> nalgebra::Isometry3<f64> {
        match forward_kinematics(&self.robot, &mut self.ws, q) {
            Ok(f) => f.to_isometry(),
            Err(_) => nalgebra::Isometry3::from_parts(
                nalgebra::Translation3::new(f64::NAN, f64::NAN, f64::NAN),
                nalgebra::UnitQuaternion::identity(),
            ),
        }
    }
    fn flange_jacobian(&mut self, q: &[f64], j: &mut DMatrix<f64>) {
        match flange_jacobian(&self.robot, &mut self.ws, q) {
            Ok(jac) if jac.shape() == j.shape() => j.copy_from(jac),
            _ => j.fill(f64::NAN),
        }
    }
}
