//! The payload's inertial parameters and their linear regressor.
//!
//! A rigid payload fixed to the flange is described by ten numbers, its
//! spatial inertia about the flange origin in flange axes (Atkinson, An &
//! Hollerbach 1986; Khalil & Dombre, *Modeling, Identification and Control of
//! Robots*, §12.3):
//!
//! `π = [m, h_x, h_y, h_z, I_xx, I_xy, I_xz, I_yy, I_yz, I_zz]`,
//!
//! with `h = m c` the first moment and `I` the rotational inertia about the
//! flange origin. The wrench the flange exerts on the payload is
//! `f = I(π) a + v ×* I(π) v` (`v`, `a`: the flange's spatial velocity and
//! acceleration, gravity included as an upward base acceleration), linear in
//! `π`: `f = Y(v, a) π` with `Y` the 6×10 body regressor. Mapped to the
//! joints by the flange Jacobian, `τ_payload = Jᵀ Y π` (an n×10 regressor).
//! Column `k` of `Y` is `f` evaluated for the unit parameter vector `e_k`,
//! so the regressor is exactly the payload's share of inverse dynamics
//! (tested against RNEA with and without a payload).

use crate::dynamics::{local_axis, rnea_unchecked_parts, Workspace};
use crate::robot::{Payload, Robot};
use crate::spatial::{skew, Force, Inertia, Motion};
use nalgebra::{Matrix3, Matrix4, SVector, Vector3};

/// Number of inertial parameters of a rigid body.
pub const NUM_PARAMS: usize = 10;

/// The ten inertial parameters `π` (see the module doc), flange frame.
pub type PayloadParams = SVector<f64, NUM_PARAMS>;

/// `π` of a payload (mass, centre of mass and inertia about it, flange frame).
pub fn params_of(p: &Payload) -> PayloadParams {
    let i = Inertia::from_com(p.mass, p.com, p.inertia);
    params_of_inertia(&i)
}

/// `π` of a spatial inertia expressed about the flange origin.
pub fn params_of_inertia(i: &Inertia) -> PayloadParams {
    let o = &i.i_o;
    PayloadParams::from_column_slice(&[
        i.mass,
        i.h.x,
        i.h.y,
        i.h.z,
        o[(0, 0)],
        o[(0, 1)],
        o[(0, 2)],
        o[(1, 1)],
        o[(1, 2)],
        o[(2, 2)],
    ])
}

/// The spatial inertia of `π` (flange frame, about its origin).
pub fn inertia_of(pi: &PayloadParams) -> Inertia {
    Inertia {
        mass: pi[0],
        h: Vector3::new(pi[1], pi[2], pi[3]),
        i_o: Matrix3::new(
            pi[4], pi[5], pi[6], //
            pi[5], pi[7], pi[8], //
            pi[6], pi[8], pi[9],
        ),
    }
}

/// The payload of `π`: mass, centre of mass `h/m` and the inertia about it.
/// A mass below `1e-9` kg (or a non-finite `π`) is no payload (`None`).
///
/// The inertia about the centre of mass is cleaned so that it passes
/// [`Payload::validate`] whatever the round-off: principal moments clipped
/// at 0, the largest at most the sum of the two others, then all three raised
/// by `1e-9` of their sum (+1e-12 kg·m²). For a physically consistent `π`
/// this changes the inertia by about 1e-9 relative.
pub fn payload_of(pi: &PayloadParams) -> Option<Payload> {
    let i = inertia_of(pi);
    if !pi.iter().all(|v| v.is_finite()) || i.mass <= 1e-9 {
        return None;
    }
    let com = i.h / i.mass;
    let cx = skew(&com);
    let i_com = i.i_o + cx * cx * i.mass;
    let eig = nalgebra::SymmetricEigen::new((i_com + i_com.transpose()) * 0.5);
    let mut d = eig.eigenvalues.map(|l| l.max(0.0));
    let (imax, _) = d.argmax();
    let others = d.sum() - d[imax];
    d[imax] = d[imax].min(others);
    let floor = 1e-9 * d.sum() + 1e-12;
    d.add_scalar_mut(floor);
    let r = eig.eigenvectors;
    let inertia = r * Matrix3::from_diagonal(&d) * r.transpose();
    Some(Payload {
        mass: i.mass,
        com,
        inertia: (inertia + inertia.transpose()) * 0.5,
    })
}

/// The pseudo-inertia matrix `J(π) = [[Σ, h], [hᵀ, m]]`, `Σ = ½ tr(I) 1 − I`
/// (Wensing, Kim & Slotine, "Linear matrix inequalities for physically
/// consistent inertial parameter identification", RA-L 2018). `π` is the
/// inertia of some mass distribution (mass ≥ 0, inertia about the centre of
/// mass positive semi-definite and obeying the triangle inequalities) iff
/// `J ⪰ 0`.
pub fn pseudo_inertia(pi: &PayloadParams) -> Matrix4<f64> {
    let i = inertia_of(pi);
    let sigma = Matrix3::identity() * (0.5 * i.i_o.trace()) - i.i_o;
    let mut j = Matrix4::zeros();
    j.fixed_view_mut::<3, 3>(0, 0).copy_from(&sigma);
    j.fixed_view_mut::<3, 1>(0, 3).copy_from(&i.h);
    j.fixed_view_mut::<1, 3>(3, 0).copy_from(&i.h.transpose());
    j[(3, 3)] = i.mass;
    j
}

/// `π` of a pseudo-inertia matrix (inverse of [`pseudo_inertia`]:
/// `I = tr(Σ) 1 − Σ`).
pub fn params_of_pseudo_inertia(j: &Matrix4<f64>) -> PayloadParams {
    let sigma: Matrix3<f64> = j.fixed_view::<3, 3>(0, 0).into_owned();
    let sigma = (sigma + sigma.transpose()) * 0.5;
    let i_o = Matrix3::identity() * sigma.trace() - sigma;
    let h = (j.fixed_view::<3, 1>(0, 3) + j.fixed_view::<1, 3>(3, 0).transpose()) * 0.5;
    params_of_inertia(&Inertia {
        mass: j[(3, 3)],
        h,
        i_o,
    })
}

/// The wrench `f = I(π) a + v ×* I(π) v` for the unit parameter vector `e_k`.
#[inline]
fn unit_wrench(k: usize, v: &Motion, a: &Motion) -> Force {
    let mut e = PayloadParams::zeros();
    e[k] = 1.0;
    let i = inertia_of(&e);
    i.apply(a) + v.cross_force(&i.apply(v))
}

/// The joint-space payload regressor `Y_q` (n×10, row-major into `rows`):
/// `τ_payload(q, q̇, q̈) = Y_q π` for any payload `π` rigidly fixed to the
/// flange. Also leaves in `ws.tau` the inverse dynamics `τ(q, q̇, q̈)` of
/// `robot` as it is (its own payload included), so that `ws.tau − Y_q π̂` is
/// the robot without payload when `π̂` is its payload.
///
/// `q`, `qd`, `qdd` must have `n` finite values and `rows` `n` entries (the
/// caller checks; nothing is allocated).
pub fn joint_regressor(
    robot: &Robot,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    rows: &mut [[f64; NUM_PARAMS]],
) {
    let n = robot.dof();
    let (v_last, a_last) = rnea_unchecked_parts(robot, ws, q, qd, qdd);
    let flange = robot.flange_offset();
    let v = flange.motion_to_child(&v_last);
    let a = flange.motion_to_child(&a_last);
    for k in 0..NUM_PARAMS {
        // The wrench in the flange frame, then in the last body's frame and
        // down the chain as in RNEA's backward pass.
        let mut f = flange.force_to_parent(&unit_wrench(k, &v, &a));
        for i in (0..n).rev() {
            rows[i][k] = local_axis(robot, i).dot(&f);
            if i > 0 {
                f = ws.local[i].force_to_parent(&f);
            }
        }
    }
}
