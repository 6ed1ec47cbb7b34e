//! Tool length offset (G43 H / G43.1 / G49) in the planned robot (issue #20 item 2): the
//! programmed points are the tool tip's (LinuxCNC's G43), the planner extends the TCP by the
//! tool length along the tool axis, and a change of length within a program is honoured.

mod common;

use common::gcode::assert_ends;
use nalgebra::{UnitQuaternion, Vector3};
use ofmpc::dynamics::{forward_kinematics, Workspace};
use ofmpc::gcode::{parse, MoveKind, ParseOptions, ToolTable};
use ofmpc::motion::{plan, start_position, tool_axis, Orientation, Plan, PlanOptions};
use ofmpc::robot::Robot;

/// A tool table with tool 1 100 mm long and tool 2 50 mm long.
fn table() -> ToolTable {
    ToolTable::parse("T1 P1 Z100 ;long\nT2 P2 Z50\n").unwrap()
}

/// Plans `body` for the IRB 140 with the part origin at the tip of tool 1 at the start pose
/// (so that the programmed points lie around the start pose's tip).
fn plan_with_tool(body: &str, orientation: Orientation) -> (Robot, Plan, Vector3<f64>) {
    let robot = Robot::irb140();
    let axis = tool_axis(&robot, orientation).unwrap();
    let origin = start_position(&robot).unwrap() + 0.1 * axis;
    let options = PlanOptions {
        parse: ParseOptions {
            origin: Some(origin.into()),
            tool_table: Some(table()),
            ..ParseOptions::default()
        },
        orientation,
        ..PlanOptions::default()
    };
    let planned = plan(body, &robot, &options).unwrap_or_else(|e| panic!("{e}\n{body}"));
    (robot, planned, axis)
}

/// The bare robot's TCP at every sample of the reference.
fn tcp_positions(robot: &Robot, planned: &Plan) -> Vec<Vector3<f64>> {
    let mut ws = Workspace::new(robot);
    let r = &planned.reference;
    (0..r.len())
        .map(|k| forward_kinematics(robot, &mut ws, r.q(k)).unwrap().pos)
        .collect()
}

/// Every programmed end point (with the tool length in force at its move) is reached by the
/// tip: some sample of the reference has FK(q) + L·a on it within 1e-6 m; and every sample's
/// FK(q) + tool_length·a is the Cartesian trajectory's point.
fn assert_tip_reaches_program(robot: &Robot, planned: &Plan, axis: Vector3<f64>) {
    let tcp = tcp_positions(robot, planned);
    let ts = planned.reference.ts();
    for (k, p) in tcp.iter().enumerate() {
        let want = planned.trajectory.sample(k as f64 * ts).position;
        let got = p + planned.tool_length * axis;
        assert!((got - want).norm() < 1e-6, "sample {k}: {got} vs {want}");
    }
    for m in &planned.program.moves {
        if let MoveKind::Path { segment, .. } = &m.kind {
            let end = segment.end();
            let best = tcp
                .iter()
                .map(|p| (p + m.tool_length * axis - end).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(
                best < 1e-6,
                "line {}: the tip misses {end} by {best} m",
                m.line
            );
        }
    }
}

#[test]
fn g43_h1_the_tip_reaches_the_programmed_points() {
    // Each move ends with a dwell so that samples land on the programmed point at rest.
    let body = "G21 G90 G61\nT1 M6 G43 H1\nG1 X0 Y0 Z0 F3000\nG4 P0.05\nX-40\nG4 P0.05\n\
                Y40\nG4 P0.05\nG2 X-40 Y-40 J-40\nG4 P0.05\nG0 Z-30\nG4 P0.05\n";
    let (robot, planned, axis) = plan_with_tool(body, Orientation::AtZero);
    assert_eq!(planned.tool_length, 0.1);
    // The IRB 140 at q = 0 holds its tool along base +x.
    assert!((axis - Vector3::x()).norm() < 1e-12);
    assert_tip_reaches_program(&robot, &planned, axis);
    // The reference starts at rest at the start pose (the first point is the start tip).
    let q0 = planned.reference.q(0);
    assert!(q0
        .iter()
        .zip(robot.start_q())
        .all(|(a, b)| (a - b).abs() < 1e-9));
    // Without G43 the same points are the TCP's: the joints differ (by 100 mm of reach).
    let bare = plan_with_tool(&body.replace("G43 H1", ""), Orientation::AtZero).1;
    assert_eq!(bare.tool_length, 0.0);
    let last = |p: &Plan| p.reference.q(p.reference.len() - 1).to_vec();
    let dq: f64 = last(&bare)
        .iter()
        .zip(last(&planned))
        .map(|(a, b)| (a - b).abs())
        .sum();
    assert!(dq > 0.05, "{dq}");
}

#[test]
fn a_change_of_tool_length_is_honoured() {
    // Tool 1 (100 mm) for two moves, then tool 2 (50 mm) after a tool change, then G49
    // (the bare TCP). The tool points down (LinuxCNC's −Z tool axis).
    let body = "G21 G90 G61\nT1 M6 G43 H1\nG1 X0 Y0 Z0 F3000\nG4 P0.05\nX-30\nG4 P0.05\n\
                T2 M6 G43 H2\nG1 Y30\nG4 P0.05\nZ20\nG4 P0.05\nG49\nG1 X0\nG4 P0.05\n";
    let down = UnitQuaternion::from_euler_angles(0.0, std::f64::consts::PI, 0.0);
    let (robot, planned, axis) = plan_with_tool(body, Orientation::Fixed(down));
    assert!((axis + Vector3::z()).norm() < 1e-12);
    assert_eq!(planned.tool_length, 0.1);
    let lengths: Vec<f64> = planned
        .program
        .moves
        .iter()
        .map(|m| m.tool_length)
        .collect();
    assert!(lengths.contains(&0.05) && lengths.contains(&0.0));
    assert_tip_reaches_program(&robot, &planned, axis);
}

#[test]
fn a_change_of_length_moves_the_current_point_as_linuxcnc() {
    // LinuxCNC (convert_tool_length_offset): G43 moves no axis; the tip's current Z is
    // the old one minus the length, so an incremental move or a move without Z keeps it.
    let p = common::gcode::ok("G0 X0 Y0 Z0\nG43.1 Z10\nG91 G1 X5 F100\nG90 G49\nG1 X0\n");
    assert_ends(&p, &[[5.0, 0.0, -10.0], [0.0, 0.0, 0.0]]);
    // G53 and G28 address the controlled point: the tip ends the length below.
    let p = common::gcode::ok("G0 X1 Y2 Z3\nG28.1\nG43.1 Z10\nG53 G0 Z0\nG28\n");
    assert_ends(&p, &[[1.0, 2.0, -10.0], [1.0, 2.0, -7.0]]);
    // #5422 (current Z in program coordinates) reads the tip's.
    let p = common::gcode::ok("G0 X0 Y0 Z0\nG43.1 Z10\nG1 X[#5422]\n");
    assert_ends(&p, &[[-10.0, 0.0, -10.0]]);
    // With a start position (the robot's TCP) the tip starts the length along the axis.
    let options = ParseOptions {
        start: Some(Vector3::new(0.5, 0.0, 0.6)),
        tool_axis: Some(Vector3::x()),
        tool_table: Some(table()),
        ..ParseOptions::default()
    };
    let p = parse("G43 H2\nG1 Z10 F100\n", &options).unwrap();
    assert!((p.start - Vector3::new(0.55, 0.0, 0.6)).norm() < 1e-15);
    assert_eq!(p.start_tool_length, 0.05);
    // A tool axis that is not a unit vector is refused.
    let bad = ParseOptions {
        tool_axis: Some(Vector3::new(0.0, 0.0, 2.0)),
        ..ParseOptions::default()
    };
    assert!(parse("G0 X0 Y0 Z0\n", &bad).is_err());
}

#[test]
fn g43_after_the_start_point_moves_the_tip_along_the_tcp_axis() {
    // The start point is set without a tool length; G43 then puts the tip 20 mm further
    // along the tool axis (the IRB 140 at q = 0: base +x) without moving a joint.
    let robot = Robot::irb140();
    let options = PlanOptions {
        parse: ParseOptions {
            tool_table: Some(ToolTable::parse("T1 P1 Z+20\n").unwrap()),
            ..ParseOptions::default()
        },
        ..PlanOptions::default()
    };
    let text = "G0 X500 Y0 Z600\nG43 H1\nG1 X510 F600\nG4 P0.05\nM30\n";
    let planned = plan(text, &robot, &options).unwrap_or_else(|e| panic!("{e}"));
    let tip = |m: usize| match &planned.program.moves[m].kind {
        MoveKind::Path { segment, .. } => segment.end(),
        MoveKind::Dwell { .. } => unreachable!(),
    };
    assert!((tip(0) - Vector3::new(0.51, 0.0, 0.6)).norm() < 1e-12);
    assert_tip_reaches_program(&robot, &planned, Vector3::x());
}
