//! Forward kinematics and the geometric Jacobian.

use super::workspace::{check, check_ws, finite_result, Workspace};
use crate::robot::{JointKind, ModelError, Robot};
use crate::spatial::{axis_angle, Motion, Transform};
use nalgebra::DMatrix;

/// The motion of joint `i` at position `qi`: pose of the body in the joint frame.
#[inline]
pub(crate) fn joint_transform(robot: &Robot, i: usize, qi: f64) -> Transform {
    let j = &robot.joints()[i];
    let motion = match j.kind {
        JointKind::Revolute => Transform {
            rot: axis_angle(&j.axis, qi),
            pos: nalgebra::Vector3::zeros(),
        },
        JointKind::Prismatic => Transform {
            rot: nalgebra::Matrix3::identity(),
            pos: j.axis * qi,
        },
    };
    j.placement.compose(&motion)
}

/// The joint's motion subspace in its body frame (ω, v).
#[inline]
pub(crate) fn local_axis(robot: &Robot, i: usize) -> Motion {
    let j = &robot.joints()[i];
    match j.kind {
        JointKind::Revolute => Motion {
            ang: j.axis,
            lin: nalgebra::Vector3::zeros(),
        },
        JointKind::Prismatic => Motion {
            ang: nalgebra::Vector3::zeros(),
            lin: j.axis,
        },
    }
}

/// Fills `ws.local`, `ws.poses`, `ws.s` (joint axes in the base frame) and
/// `ws.flange` without checking `q`.
pub(crate) fn fk_unchecked(robot: &Robot, ws: &mut Workspace, q: &[f64]) {
    let mut parent = Transform::identity();
    for i in 0..robot.dof() {
        let local = joint_transform(robot, i, q[i]);
        let pose = parent.compose(&local);
        ws.local[i] = local;
        ws.poses[i] = pose;
        let s = local_axis(robot, i);
        let ang = pose.rot * s.ang;
        let lin = pose.rot * s.lin;
        // Motion vector of the joint at the base origin: v_O = p × ω + v.
        ws.s[i] = Motion {
            ang,
            lin: lin + pose.pos.cross(&ang),
        };
        parent = pose;
    }
    // The tool centre point (the flange unless a TCP is set; composed only then, so the
    // flange pose is bit for bit what it was before TCPs).
    ws.flange = if robot.tcp_is_identity() {
        parent.compose(robot.flange_offset())
    } else {
        parent.compose(&robot.tool_offset())
    };
}

/// Forward kinematics: the pose of every body (`ws.poses`, base frame) and of
/// the flange (`ws.flange`, returned) — the tool centre point when the robot has one
/// ([`Robot::tcp`]).
pub fn forward_kinematics<'w>(
    robot: &Robot,
    ws: &'w mut Workspace,
    q: &[f64],
) -> Result<&'w Transform, ModelError> {
    check_ws(robot, ws)?;
    check(robot, "q", q)?;
    fk_unchecked(robot, ws, q);
    Ok(&ws.flange)
}

/// The geometric Jacobian of the flange (the tool centre point when set), 6×n (`ws.jacobian`): `[ṗ; ω] = J q̇`,
/// with ṗ the velocity of the flange origin and ω the angular velocity, both in
/// the base frame. Also runs forward kinematics.
pub fn flange_jacobian<'w>(
    robot: &Robot,
    ws: &'w mut Workspace,
    q: &[f64],
) -> Result<&'w DMatrix<f64>, ModelError> {
    check_ws(robot, ws)?;
    check(robot, "q", q)?;
    fk_unchecked(robot, ws, q);
    let p = ws.flange.pos;
    for i in 0..robot.dof() {
        let s = ws.s[i];
        // Velocity of the flange point: v_O + ω × p.
        let lin = s.lin + s.ang.cross(&p);
        for r in 0..3 {
            ws.jacobian[(r, i)] = lin[r];
            ws.jacobian[(r + 3, i)] = s.ang[r];
        }
    }
    finite_result("J", ws.jacobian.as_slice())?;
    Ok(&ws.jacobian)
}
