//! The joint-space terms H(q), C(q, q̇), g(q), in the base frame.
//!
//! With the joint axes `S_j` and body velocities `v_k` as spatial vectors in
//! the base frame, `Ṡ_j = v_j ×ₘ S_j` and the composite inertias
//! `I^C_i = Σ_{k ≥ i} I_k`:
//!
//! - `H_ij = S_iᵀ I^C_{max(i,j)} S_j` (composite-rigid-body algorithm), plus
//!   the armature on the diagonal;
//! - `g_i = S_iᵀ I^C_i a_g`, with `a_g = (0, −gravity)`;
//! - `C = Σ_k J_kᵀ (I_k J̇_k + B_k J_k)` with
//!   `B_k = ½ (v_k ×* I_k − I_k v_k ×ₘ + (I_k v_k)⊼)` and `(f)⊼ w = w ×* f`
//!   (Echeandia & Wensing, "Numerical methods to compute the Coriolis matrix
//!   and Christoffel symbols for rigid-body systems", JCND 2021). Then
//!   `C q̇` is the Coriolis and centrifugal torque and `Ḣ − 2C` is
//!   skew-symmetric: C is the Christoffel-symbol matrix of the paper's
//!   `½ Ḣ + S` (docs/guide/paper-notes.md, "The model").

use super::kinematics::fk_unchecked;
use super::workspace::{check, check_ws, finite_result, Workspace};
use crate::robot::{ModelError, Robot};
use crate::spatial::{Force, Inertia, Motion};
use nalgebra::{DMatrix, DVector};

/// Base-frame inertias and composite inertias (`ws.inertia`, `ws.composite`).
fn composite_pass(robot: &Robot, ws: &mut Workspace) {
    let n = robot.dof();
    let mut acc = Inertia::zero();
    for i in (0..n).rev() {
        let world = robot.body_inertia(i).to_parent(&ws.poses[i]);
        ws.inertia[i] = world;
        acc = acc + world;
        ws.composite[i] = acc;
    }
}

fn fill_h(robot: &Robot, ws: &mut Workspace) {
    let n = robot.dof();
    for i in 0..n {
        for j in 0..=i {
            // H_ij = S_iᵀ I^C_i S_j for j ≤ i.
            let hij = ws.s[i].dot(&ws.composite[i].apply(&ws.s[j]));
            ws.h[(i, j)] = hij;
            ws.h[(j, i)] = hij;
        }
        ws.h[(i, i)] += robot.joints()[i].armature;
    }
}

fn fill_g(robot: &Robot, ws: &mut Workspace) {
    let ag = Motion {
        ang: nalgebra::Vector3::zeros(),
        lin: -robot.gravity(),
    };
    for i in 0..robot.dof() {
        ws.g[i] = ws.s[i].dot(&ws.composite[i].apply(&ag));
    }
}

/// `B_k w = ½ (v ×* (I w) − I (v ×ₘ w) + w ×* (I v))`.
#[inline]
fn b_apply(inertia: &Inertia, v: &Motion, iv: &Force, w: &Motion) -> Force {
    let a = v.cross_force(&inertia.apply(w));
    let b = inertia.apply(&v.cross_motion(w));
    let c = w.cross_force(iv);
    let sum = a - b + c;
    Force {
        ang: sum.ang * 0.5,
        lin: sum.lin * 0.5,
    }
}

fn fill_c(robot: &Robot, ws: &mut Workspace, qd: &[f64]) {
    let n = robot.dof();
    let mut v = Motion::zero();
    for k in 0..n {
        v = v + ws.s[k].scale(qd[k]);
        ws.v[k] = v;
        ws.sdot[k] = v.cross_motion(&ws.s[k]);
        ws.ivel[k] = ws.inertia[k].apply(&v);
    }
    for j in 0..n {
        // acc = Σ_{l ≥ i} B_l S_j, built from the tip down to i = j.
        let mut acc = Force::default();
        for i in (j..n).rev() {
            acc = acc + b_apply(&ws.inertia[i], &ws.v[i], &ws.ivel[i], &ws.s[j]);
            let f = ws.composite[i].apply(&ws.sdot[j]) + acc;
            ws.c[(i, j)] = ws.s[i].dot(&f);
            if i == j {
                for r in 0..j {
                    ws.c[(r, j)] = ws.s[r].dot(&f);
                }
            }
        }
    }
}

/// The joint-space inertia matrix `H(q)` (composite-rigid-body algorithm),
/// armature on the diagonal. Writes and returns `ws.h` (n×n, symmetric).
pub fn crba<'w>(
    robot: &Robot,
    ws: &'w mut Workspace,
    q: &[f64],
) -> Result<&'w DMatrix<f64>, ModelError> {
    check_ws(robot, ws)?;
    check(robot, "q", q)?;
    fk_unchecked(robot, ws, q);
    composite_pass(robot, ws);
    fill_h(robot, ws);
    finite_result("H", ws.h.as_slice())?;
    Ok(&ws.h)
}

/// The gravity torque `g(q)`. Writes and returns `ws.g` (n).
pub fn gravity<'w>(
    robot: &Robot,
    ws: &'w mut Workspace,
    q: &[f64],
) -> Result<&'w DVector<f64>, ModelError> {
    check_ws(robot, ws)?;
    check(robot, "q", q)?;
    fk_unchecked(robot, ws, q);
    composite_pass(robot, ws);
    fill_g(robot, ws);
    finite_result("g", ws.g.as_slice())?;
    Ok(&ws.g)
}

/// The Coriolis matrix `C(q, q̇)` built from Christoffel symbols (`Ḣ − 2C`
/// skew-symmetric, `C q̇` the Coriolis and centrifugal torque). Writes and
/// returns `ws.c` (n×n).
pub fn coriolis_matrix<'w>(
    robot: &Robot,
    ws: &'w mut Workspace,
    q: &[f64],
    qd: &[f64],
) -> Result<&'w DMatrix<f64>, ModelError> {
    check_ws(robot, ws)?;
    check(robot, "q", q)?;
    check(robot, "qd", qd)?;
    fk_unchecked(robot, ws, q);
    composite_pass(robot, ws);
    fill_c(robot, ws, qd);
    finite_result("C", ws.c.as_slice())?;
    Ok(&ws.c)
}

/// `H(q)`, `C(q, q̇)` and `g(q)` in one pass (`ws.h`, `ws.c`, `ws.g`): what the
/// controllers need at every sample.
pub fn joint_space_terms(
    robot: &Robot,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
) -> Result<(), ModelError> {
    check_ws(robot, ws)?;
    check(robot, "q", q)?;
    check(robot, "qd", qd)?;
    fk_unchecked(robot, ws, q);
    composite_pass(robot, ws);
    fill_h(robot, ws);
    fill_g(robot, ws);
    fill_c(robot, ws, qd);
    finite_result("H", ws.h.as_slice())?;
    finite_result("C", ws.c.as_slice())?;
    finite_result("g", ws.g.as_slice())?;
    Ok(())
}
