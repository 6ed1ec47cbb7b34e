//! Forward dynamics `q̈ = H⁻¹ (τ − C q̇ − g)`, and the robot's energy.

use super::rnea::rnea_unchecked;
use super::terms::crba;
use super::workspace::{check, check_ws, finite_result, Workspace};
use crate::linalg::{cholesky_in_place, cholesky_solve_in_place};
use crate::robot::{ModelError, Robot};
use nalgebra::DVector;

/// Forward dynamics: the joint accelerations under torques `tau`, by RNEA for
/// the nonlinear effects and a Cholesky factorization of `H` (armature
/// included). Writes and returns `ws.qdd` (n); leaves the factor in `ws.chol`.
pub fn forward_dynamics<'w>(
    robot: &Robot,
    ws: &'w mut Workspace,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
) -> Result<&'w DVector<f64>, ModelError> {
    check_ws(robot, ws)?;
    check(robot, "q", q)?;
    check(robot, "qd", qd)?;
    check(robot, "tau", tau)?;
    let n = robot.dof();
    let zero = std::mem::take(&mut ws.zero);
    rnea_unchecked(robot, ws, q, qd, &zero);
    ws.zero = zero;
    for i in 0..n {
        ws.qdd[i] = tau[i] - ws.tau[i];
    }
    crba(robot, ws, q)?;
    // Cholesky H = L Lᵀ (lower triangle of ws.chol), then L Lᵀ q̈ = τ − h in ws.qdd.
    // Only the lower triangle is copied: the upper one of ws.chol stays as it was (zero).
    for j in 0..n {
        for i in j..n {
            ws.chol[(i, j)] = ws.h[(i, j)];
        }
    }
    if let Err(e) = cholesky_in_place(n, n, ws.chol.as_mut_slice()) {
        return Err(ModelError::NotPositiveDefinite {
            joint: e.pivot,
            pivot: e.value,
            with_payload: robot.payload().is_some_and(|p| p.mass > 0.0),
        });
    }
    cholesky_solve_in_place(n, n, ws.chol.as_slice(), ws.qdd.as_mut_slice());
    finite_result("qdd", ws.qdd.as_slice())?;
    Ok(&ws.qdd)
}

/// Kinetic energy `½ q̇ᵀ H(q) q̇` (armature included). Uses `ws.h`.
pub fn kinetic_energy(
    robot: &Robot,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
) -> Result<f64, ModelError> {
    check_ws(robot, ws)?;
    check(robot, "qd", qd)?;
    let h = crba(robot, ws, q)?;
    let v = DVector::from_column_slice(qd);
    Ok(0.5 * v.dot(&(h * &v)))
}

/// Potential energy in the gravity field, zero at the base origin:
/// `−Σ_k m_k gravityᵀ c_k`.
pub fn potential_energy(robot: &Robot, ws: &mut Workspace, q: &[f64]) -> Result<f64, ModelError> {
    super::kinematics::forward_kinematics(robot, ws, q)?;
    let g = robot.gravity();
    Ok((0..robot.dof())
        .map(|k| {
            let b = robot.body_inertia(k);
            let c = ws.poses[k].apply_point(&b.com());
            -b.mass * g.dot(&c)
        })
        .sum())
}
