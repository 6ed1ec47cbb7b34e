//! Inverse dynamics by the recursive Newton–Euler algorithm (Featherstone,
//! *Rigid Body Dynamics Algorithms*, §5.3), in body frames.

use super::kinematics::{joint_transform, local_axis};
use super::workspace::{check, check_ws, finite_result, Workspace};
use crate::robot::{ModelError, Robot};
use crate::spatial::Motion;
use nalgebra::DVector;

/// Inverse dynamics `τ = H(q) q̈ + C(q, q̇) q̇ + g(q)`, armature included
/// (`τ_i += armature_i q̈_i`). Writes and returns `ws.tau` (n).
///
/// `rnea(q, q̇, 0)` is the vector of nonlinear effects `C q̇ + g`;
/// `rnea(q, 0, 0)` is `g`.
pub fn rnea<'w>(
    robot: &Robot,
    ws: &'w mut Workspace,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'w DVector<f64>, ModelError> {
    check_ws(robot, ws)?;
    check(robot, "q", q)?;
    check(robot, "qd", qd)?;
    check(robot, "qdd", qdd)?;
    rnea_unchecked(robot, ws, q, qd, qdd);
    finite_result("tau", ws.tau.as_slice())?;
    Ok(&ws.tau)
}

pub(crate) fn rnea_unchecked(
    robot: &Robot,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) {
    let n = robot.dof();
    // The base accelerates upwards at −gravity: gravity without a force field.
    let mut v_parent = Motion::zero();
    let mut a_parent = Motion {
        ang: nalgebra::Vector3::zeros(),
        lin: -robot.gravity(),
    };
    for i in 0..n {
        let x = joint_transform(robot, i, q[i]);
        let s = local_axis(robot, i);
        let vj = s.scale(qd[i]);
        let v = x.motion_to_child(&v_parent) + vj;
        let a = x.motion_to_child(&a_parent) + s.scale(qdd[i]) + v.cross_motion(&vj);
        let inertia = robot.body_inertia(i);
        ws.f[i] = inertia.apply(&a) + v.cross_force(&inertia.apply(&v));
        ws.local[i] = x;
        ws.v[i] = v;
        ws.a[i] = a;
        v_parent = v;
        a_parent = a;
    }
    for i in (0..n).rev() {
        let s = local_axis(robot, i);
        ws.tau[i] = s.dot(&ws.f[i]) + robot.joints()[i].armature * qdd[i];
        if i > 0 {
            let fp = ws.local[i].force_to_parent(&ws.f[i]);
            ws.f[i - 1] = ws.f[i - 1] + fp;
        }
    }
}
