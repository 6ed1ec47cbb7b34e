//! Forward dynamics `q̈ = H⁻¹ (τ − C q̇ − g)`, and the robot's energy.

use super::rnea::rnea_unchecked;
use super::terms::crba;
use super::{check, check_ws, finite_result, Workspace};
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
    // In-place Cholesky H = L Lᵀ (lower triangle of ws.chol).
    for j in 0..n {
        let mut d = ws.h[(j, j)];
        for k in 0..j {
            d -= ws.chol[(j, k)] * ws.chol[(j, k)];
        }
        if d <= 0.0 || !d.is_finite() {
            return Err(ModelError::NotPositiveDefinite {
                joint: j,
                pivot: d,
                with_payload: robot.payload().is_some_and(|p| p.mass > 0.0),
            });
        }
        let l = d.sqrt();
        ws.chol[(j, j)] = l;
        for i in j + 1..n {
            let mut s = ws.h[(i, j)];
            for k in 0..j {
                s -= ws.chol[(i, k)] * ws.chol[(j, k)];
            }
            ws.chol[(i, j)] = s / l;
        }
    }
    // Solve L y = b, then Lᵀ x = y, in ws.qdd.
    for i in 0..n {
        let mut s = ws.qdd[i];
        for k in 0..i {
            s -= ws.chol[(i, k)] * ws.qdd[k];
        }
        ws.qdd[i] = s / ws.chol[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = ws.qdd[i];
        for k in i + 1..n {
            s -= ws.chol[(k, i)] * ws.qdd[k];
        }
        ws.qdd[i] = s / ws.chol[(i, i)];
    }
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
    super::forward_kinematics(robot, ws, q)?;
    let g = robot.gravity();
    Ok((0..robot.dof())
        .map(|k| {
            let b = robot.body_inertia(k);
            let c = ws.poses[k].apply_point(&b.com());
            -b.mass * g.dot(&c)
        })
        .sum())
}
