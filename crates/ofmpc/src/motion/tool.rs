//! The tool length offset of a program (`G43 H…`, `G43.1 Z…`, `G49`) in the planned robot.
//!
//! LinuxCNC's meaning (its G-code reference, "G43 Tool Length Offset", and
//! `convert_tool_length_offset` in `interp_convert.cc`): the programmed point is the tool
//! tip; the controlled point lies the tool length `L` back along the tool axis, and a change
//! of `L` moves no axis. The reader ([`crate::gcode`]) gives every move the tip's points and
//! the length `L_m` in force ([`crate::gcode::Move::tool_length`]). The planner follows one
//! point of the robot: the TCP moved `L_ref` along its z axis, the tool axis
//! ([`Robot::with_tool_length`]), with `L_ref` the length at the first path move. The
//! orientation is constant along the path, so the tool axis `a` (base frame) is too, and a
//! move planned under `L_m ≠ L_ref` is its tip path moved by `−(L_m − L_ref)·a`: the point
//! `L_ref` along the axis lies there when the tip of the `L_m` tool is on the programmed
//! point.

use super::error::PlanError;
use super::limits::Orientation;
use crate::gcode::{GcodeError, GcodeErrorKind, MoveKind, Program};
use crate::geometry::Segment;
use crate::robot::Robot;
use nalgebra::Vector3;

/// The tool axis (unit, base frame) along a planned path: the z axis of the TCP at the
/// path's constant orientation (the start pose's for [`Orientation::AtZero`]); `None` when
/// the forward kinematics of the start pose fail.
pub fn tool_axis(robot: &Robot, orientation: Orientation) -> Option<Vector3<f64>> {
    let rot = match orientation {
        Orientation::Fixed(r) => r.to_rotation_matrix().into_inner(),
        Orientation::AtZero => {
            let mut ws = crate::dynamics::Workspace::new(robot);
            crate::dynamics::forward_kinematics(robot, &mut ws, robot.start_q())
                .ok()?
                .rot
        }
    };
    let a = rot.column(2).into_owned();
    a.iter().all(|v| v.is_finite()).then_some(a)
}

/// The tool length the plan extends the TCP by: the one in force at the first path move
/// (at the start point when there is none).
pub(super) fn reference_length(program: &Program) -> f64 {
    program
        .moves
        .iter()
        .find(|m| matches!(m.kind, MoveKind::Path { .. }))
        .map_or(program.start_tool_length, |m| m.tool_length)
}

/// `robot` with its TCP extended by the tool length `length` (itself when 0).
pub(super) fn tooled_robot(
    robot: &Robot,
    length: f64,
    program: &Program,
) -> Result<Option<Robot>, PlanError> {
    if length == 0.0 {
        return Ok(None);
    }
    robot.with_tool_length(length).map(Some).map_err(|e| {
        PlanError::Program(GcodeError {
            line: program.start_line,
            column: 1,
            kind: GcodeErrorKind::InvalidValue,
            text: String::new(),
            message: format!(
                "the tool length {:.6} mm cannot extend the TCP: {e}",
                length * 1e3
            ),
            hint: "check the tool length (G43 H…, G43.1 Z…) and the tool table".into(),
        })
    })
}

/// The program's points moved to the point `l_ref` along the tool axis `axis`: every move
/// (and the start) planned under another length moves by `−(L_m − l_ref)·axis`; `None`
/// when every move has the length `l_ref` (the program's points are already that point's).
pub(super) fn controlled_program(
    program: &Program,
    l_ref: f64,
    axis: Vector3<f64>,
) -> Option<Program> {
    let same =
        program.start_tool_length == l_ref && program.moves.iter().all(|m| m.tool_length == l_ref);
    if same {
        return None;
    }
    let mut p = program.clone();
    p.start -= (p.start_tool_length - l_ref) * axis;
    for m in &mut p.moves {
        let d = -(m.tool_length - l_ref) * axis;
        if let MoveKind::Path { segment, .. } = &mut m.kind {
            translate(segment, d);
        }
    }
    Some(p)
}

/// Moves `segment` by `d`.
fn translate(segment: &mut Segment, d: Vector3<f64>) {
    match segment {
        Segment::Line { a, b } => {
            *a += d;
            *b += d;
        }
        Segment::Arc { center, .. } => *center += d,
    }
}
