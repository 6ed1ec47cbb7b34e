//! Modal codes of issue #20: G92 family, G52, G53, G28/G30, G10 L20, G43, G90.1, canned
//! cycles, G64 Q, G93/G95, polar words. End points are checked against values worked out by
//! hand from LinuxCNC's documented semantics.

use nalgebra::Vector3;
mod common;

use common::gcode::{assert_ends, ends, ok};
use ofmpc::gcode::{parse, MoveKind, ParseOptions, Program};

#[test]
fn g92_family_g52_and_g53() {
    let p = ok("G0 X10 Y10 Z10\nG92 X0 Y0\nG1 X1 Y1\nG92.2\nG1 X1 Y1\nG92.3\nG1 X2\nG92.1\nG1 X3\nG52 X100\nG1 X1\nG53 G1 X5\nG1 Y0\n");
    assert_ends(
        &p,
        &[
            [11.0, 11.0, 10.0],
            [1.0, 1.0, 10.0],
            [12.0, 1.0, 10.0],
            [3.0, 1.0, 10.0],
            [101.0, 1.0, 10.0],
            [5.0, 1.0, 10.0],
            [5.0, 0.0, 10.0],
        ],
    );
}

#[test]
fn g28_g30_and_g10_l20() {
    let p = ok("G0 X1 Y2 Z3\nG28.1\nG1 X5\nG28 Z10\nG30\nG10 L20 P1 X0\nG1 Y7\nG0 X0\n");
    // G28 Z10: through Z10, then Z of the stored point; G30 (nothing stored): machine zero.
    assert_ends(
        &p,
        &[
            [5.0, 2.0, 3.0],
            [5.0, 2.0, 10.0],
            [5.0, 2.0, 3.0],
            [0.0, 0.0, 0.0],
            [0.0, 7.0, 0.0],
        ],
    );
    let p = ok("G0 X0 Y0 Z0\nG10 L20 P1 X0\nG0 X1\n");
    assert_ends(&p, &[[1.0, 0.0, 0.0]]);
}

#[test]
fn tool_length_is_kept_for_the_tcp() {
    let p = ok("G0 X0 Y0 Z0\nG43.1 Z12.5\nG1 Z1\n");
    assert!((p.tool_length - 0.0125).abs() < 1e-15);
    assert_ends(&p, &[[0.0, 0.0, 1.0]]);
    assert_eq!(
        ok("G0 X0 Y0 Z0\nG43.1 Z12.5\nG49\nG1 Z1\n").tool_length,
        0.0
    );
}

#[test]
fn absolute_arc_centres() {
    let a = ok("G0 X10 Y0 Z0\nG90.1 G3 X0 Y10 I0 J0\n");
    let b = ok("G0 X10 Y0 Z0\nG3 X0 Y10 I-10 J0\n");
    assert_eq!(a.moves, b.moves);
}

#[test]
fn drilling_cycles() {
    // G81 with G99 (retract to R) at two holes, then G98 G83 pecking with Q.
    let p = ok("G0 X0 Y0 Z10\nG99 G81 X1 Y1 R2 Z-3 F60\nX2\nG80\nG98 G83 X5 Y5 R2 Z-3 Q2\n");
    assert_ends(
        &p,
        &[
            // Above R: XY first at the current Z, then down to R.
            [1.0, 1.0, 10.0],
            [1.0, 1.0, 2.0],
            [1.0, 1.0, -3.0],
            [1.0, 1.0, 2.0],
            [2.0, 1.0, 2.0],
            [2.0, 1.0, -3.0],
            [2.0, 1.0, 2.0],
            [5.0, 5.0, 2.0],
            [5.0, 5.0, 0.0],
            [5.0, 5.0, 2.0],
            [5.0, 5.0, 0.254],
            [5.0, 5.0, -2.0],
            [5.0, 5.0, 2.0],
            [5.0, 5.0, -1.746],
            [5.0, 5.0, -3.0],
            // G98: back to the Z where the cycle began (2, the R plane of the G81 retract).
            [5.0, 5.0, 2.0],
        ],
    );
    // G91 with L: the X step repeats.
    let p = ok("G0 X0 Y0 Z5\nG91 G81 X10 R-3 Z-2 L3 F100\n");
    let xs: Vec<f64> = ends(&p).iter().map(|e| e[0]).collect();
    assert_eq!(
        xs,
        [10.0, 10.0, 10.0, 10.0, 20.0, 20.0, 20.0, 30.0, 30.0, 30.0]
    );
}

#[test]
fn g64_q_merges_collinear_moves_within_q() {
    let p =
        ok("G0 X0 Y0 Z0\nG64 P0.1 Q0.01\nG1 X1 Y0.001 F600\nG1 X2 Y0\nG1 X3 Y0.005\nG1 X3 Y1\n");
    assert_ends(&p, &[[3.0, 0.005, 0.0], [3.0, 1.0, 0.0]]);
    // Without Q nothing is merged.
    let p = ok("G0 X0 Y0 Z0\nG64 P0.1\nG1 X1 Y0.001 F600\nG1 X2 Y0\n");
    assert_eq!(p.moves.len(), 2);
}

#[test]
fn feed_modes_and_polar_words() {
    let feed = |p: &Program| match &p.moves[0].kind {
        MoveKind::Path { feed, .. } => feed.unwrap(),
        MoveKind::Dwell { .. } => unreachable!(),
    };
    // G93: F2 = the move takes 1/2 min; 30 mm in 30 s is 1 mm/s.
    let p = ok("G0 X0 Y0 Z0\nG93 G1 X30 F2\n");
    assert!((feed(&p) - 1e-3).abs() < 1e-15);
    // G95: 0.1 mm/rev at S600 = 60 mm/min.
    let p = ok("G0 X0 Y0 Z0 S600\nG95 G1 X30 F0.1\n");
    assert!((feed(&p) - 1e-3).abs() < 1e-15);
    let p = ok("G0 X0 Y0 Z0\nG1 @10 ^90 F100\nG91 G1 @1 ^0\n");
    let e = ends(&p);
    assert!((Vector3::from(e[0]) - Vector3::new(0.0, 10.0, 0.0)).norm() < 1e-12);
    assert!((Vector3::from(e[1]) - Vector3::new(1.0, 10.0, 0.0)).norm() < 1e-12);
}

#[test]
fn origin_with_another_work_offset_is_named() {
    let opts = ParseOptions::with_origin(Some([0.5, 0.0, 0.3]));
    let p = parse("G55\nG0 X0 Y0 Z0\nG1 X1\n", &opts).unwrap();
    assert!(
        p.warnings[0].message.contains("G55 selected"),
        "{:?}",
        p.warnings
    );
}
