//! Modal codes of issue #20: G92 family, G52, G53, G28/G30, G10 L20, G43, G90.1, canned
//! cycles, G64 Q, G93/G95, polar words. End points are checked against values worked out by
//! hand from LinuxCNC's documented semantics.

use nalgebra::Vector3;
mod common;

use common::gcode::{assert_ends, ends, ok};
use ofmpc::gcode::{parse, MoveKind, ParseOptions, Program, ToolTable};

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
fn g43_h_takes_the_length_from_the_tool_table() {
    let table = ToolTable::parse(
        "; LinuxCNC tool table\nT1 P1 Z+1.5 D0.25 ;comment\n\nT7 P3 X0.1 Z-20 D6 I0 J0 Q1 ;\nt12 p4 d3\n",
    )
    .unwrap();
    assert_eq!(table.len(), 3);
    assert_eq!(table.length(12), Some(0.0));
    let options = ParseOptions {
        tool_table: Some(table),
        ..ParseOptions::default()
    };
    let read = |text: &str| parse(text, &options);
    let length = |text: &str| read(text).unwrap().tool_length;
    assert!((length("G0 X0 Y0 Z0\nG43 H1\n") - 1.5e-3).abs() < 1e-15);
    assert!((length("G0 X0 Y0 Z0\nG43 H7\nG1 Z1 F100\n") + 0.02).abs() < 1e-15);
    // Without H: the tool in the spindle (T7 M6); H0 and G49: no length.
    assert!((length("T7 M6\nG0 X0 Y0 Z0\nG43\n") + 0.02).abs() < 1e-15);
    assert_eq!(length("G0 X0 Y0 Z0\nG43 H1\nG43 H0\n"), 0.0);
    assert_eq!(length("G0 X0 Y0 Z0\nG43 H1\nG49\n"), 0.0);
    // The length goes to the TCP, not to the points.
    assert_ends(
        &read("G0 X0 Y0 Z0\nG43 H7\nG1 Z1 F100\n").unwrap(),
        &[[0.0, 0.0, 1.0]],
    );
    let e = read("G0 X0 Y0 Z0\nG43 H3\n").unwrap_err();
    assert_eq!((e.line, e.column), (2, 5));
    assert!(
        e.to_string().contains("the tool table has no tool 3"),
        "{e}"
    );
    // Without a table, G43 H<n> is refused by name and says to give one.
    let e = common::gcode::fail("G0 X0 Y0 Z0\nG43 H1\n");
    assert!(e.to_string().contains("no tool table was given"), "{e}");
    assert!(e.to_string().contains("give a tool table"), "{e}");
    // A malformed table names its line and column.
    let e = ToolTable::parse("T1 Z1\nT2 Z1,5\n").unwrap_err();
    assert_eq!((e.line, e.column), (2, 4));
    let e = ToolTable::parse("T1 Z1\nP2 Z3\n").unwrap_err();
    assert!(e.to_string().contains("without T"), "{e}");
    // Issue #36: a tool listed twice, a word twice on a line and an absurd length are
    // refused with line and column (LinuxCNC keeps the first pocket silently); a BOM is
    // skipped.
    let e = ToolTable::parse("T1 Z1\nT1 Z3\n").unwrap_err();
    assert_eq!((e.line, e.column), (2, 1));
    assert!(
        e.to_string()
            .contains("tool 1 is listed twice (lines 1 and 2)"),
        "{e}"
    );
    let e = ToolTable::parse("T1 P1 Z10 Z20\n").unwrap_err();
    assert_eq!((e.line, e.column), (1, 11));
    assert!(e.to_string().contains("Z is given twice"), "{e}");
    let e = ToolTable::parse("T1 Z1e300\n").unwrap_err();
    assert_eq!((e.line, e.column), (1, 4));
    assert!(e.to_string().contains("past 10000 mm"), "{e}");
    let bom = ToolTable::parse("\u{feff}T1 P1 Z12.5\n").unwrap();
    assert_eq!(bom.length(1), Some(12.5e-3));
    let e =
        ToolTable::parse("TOOLNO POCKET LENGTH DIAMETER COMMENT\n1 1 0.5 0.1 mill\n").unwrap_err();
    assert!(e.to_string().contains("old tool table format"), "{e}");
    assert!(ToolTable::parse("T1 K3\n").is_err());
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

/// The G17 drilling of `program` with its axes permuted by `perm` (program axis k of the
/// G17 program becomes axis perm[k]): LinuxCNC's G18/G19 cycles drill along Y / X as G17
/// drills along Z.
fn permuted(points: &[[f64; 3]], perm: [usize; 3]) -> Vec<[f64; 3]> {
    points
        .iter()
        .map(|p| {
            let mut q = [0.0; 3];
            for k in 0..3 {
                q[perm[k]] = p[k];
            }
            q
        })
        .collect()
}

#[test]
fn drilling_cycles_in_g18_and_g19_are_the_g17_cycles_with_the_axes_permuted() {
    // G17: position X Y, depth Z. G18 (ZX plane): position Z X, depth Y. G19 (YZ plane):
    // position Y Z, depth X.
    let g17 = ok("G17 G0 X0 Y0 Z10\nG98 G83 X1 Y2 R2 Z-3 Q2 F60\nG91 G81 X1 Y1 R-1 Z-2 L2\n");
    let want = ends(&g17);
    let g18 = ok("G18 G0 Z0 X0 Y10\nG98 G83 Z1 X2 R2 Y-3 Q2 F60\nG91 G81 Z1 X1 R-1 Y-2 L2\n");
    assert_ends(&g18, &permuted(&want, [2, 0, 1]));
    let g19 = ok("G19 G0 Y0 Z0 X10\nG98 G83 Y1 Z2 R2 X-3 Q2 F60\nG91 G81 Y1 Z1 R-1 X-2 L2\n");
    assert_ends(&g19, &permuted(&want, [1, 2, 0]));
    // The depth word is the drilling axis's letter: a G18 cycle without Y names it.
    let e = common::gcode::fail("G18 G0 X0 Y10 Z0\nG81 X1 Z1 R2 F60\n");
    assert!(e.to_string().contains("G81 without R or Y"), "{e}");
}

#[test]
fn tapping_feeds_in_reverses_the_spindle_and_feeds_out_to_the_clear_plane() {
    // G84 (right hand, spindle M3) and G74 (left hand, M4): feed to the bottom, M5 and the
    // reverse direction, dwell P, feed out to the clear plane (G98: the initial Z), M5 and
    // the first direction again (LinuxCNC's convert_cycle_g74_g84).
    for (n, start, rev) in [(84, "M3", "M4"), (74, "M4", "M3")] {
        let p = ok(&format!(
            "{start} S500\nG0 X0 Y0 Z10\nG98 G{n} X1 Y1 R2 Z-3 P0.5 F60\nM5\n"
        ));
        assert_ends(
            &p,
            &[
                [1.0, 1.0, 10.0],
                [1.0, 1.0, 2.0],
                [1.0, 1.0, -3.0],
                [1.0, 1.0, 10.0],
            ],
        );
        let kinds: Vec<bool> = p
            .moves
            .iter()
            .map(|m| matches!(m.kind, MoveKind::Dwell { seconds } if seconds == 0.5))
            .collect();
        assert_eq!(kinds, [false, false, false, true, false]);
        let feeds: Vec<bool> = p
            .moves
            .iter()
            .filter_map(|m| match &m.kind {
                MoveKind::Path { feed, .. } => Some(feed.is_some()),
                MoveKind::Dwell { .. } => None,
            })
            .collect();
        assert_eq!(feeds, [false, false, true, true], "in and out at the feed");
        let events: Vec<(&str, usize)> = p
            .events
            .iter()
            .filter(|e| e.code.starts_with('M'))
            .map(|e| (e.code.as_str(), e.after_moves))
            .collect();
        assert_eq!(
            events,
            [
                (start, 0),
                ("M5", 3),
                (rev, 3),
                ("M5", 5),
                (start, 5),
                ("M5", 5)
            ]
        );
    }
    // Without the spindle turning the right way LinuxCNC refuses the cycle; so does the reader.
    let e = common::gcode::fail("G0 X0 Y0 Z10\nG84 X1 Y1 R2 Z-3 F60\n");
    assert!(
        e.to_string()
            .contains("needs the spindle turning clockwise"),
        "{e}"
    );
    let e = common::gcode::fail("M3 S100\nG0 X0 Y0 Z10\nG74 X1 Y1 R2 Z-3 F60\n");
    assert!(e.to_string().contains("M4"), "{e}");
}

#[test]
fn tapping_in_g18_and_g19_goes_where_linuxcnc_sends_it() {
    // LinuxCNC's convert_cycle_g74_g84 hands the plane's permuted coordinates to
    // cycle_feed, which permutes them again: in G18 the tap feeds to X = bottom,
    // Y = hole Z, Z = hole X; in G19 to X = hole Z, Y = bottom, Z = hole Y. The interpreter's
    // point stays the hole's (the next move's target), the next move starts at the tool.
    let tap_warnings = |p: &Program| {
        p.warnings
            .iter()
            .filter(|w| w.message.contains("follows LinuxCNC's interpreter"))
            .count()
    };
    let g18 = ok("G18 G21 M3 S100 F100\nG0 X0 Y20 Z0\nG84 X5 Z7 Y-10 R10\nG80\nG0 X0\n");
    assert_ends(
        &g18,
        &[
            [5.0, 20.0, 7.0],
            [5.0, 10.0, 7.0],
            [-10.0, 7.0, 5.0],
            [10.0, 7.0, 5.0],
            [0.0, 10.0, 7.0],
        ],
    );
    assert_eq!(tap_warnings(&g18), 1);
    let g19 = ok("G19 G21 M4 S100 F100\nG0 X20 Y0 Z0\nG74 Y5 Z7 X-10 R10\nY6\n");
    assert_ends(
        &g19,
        &[
            [20.0, 5.0, 7.0],
            [10.0, 5.0, 7.0],
            [7.0, -10.0, 5.0],
            [7.0, 10.0, 5.0],
            [10.0, 6.0, 7.0],
            [7.0, -10.0, 6.0],
            [7.0, 10.0, 6.0],
        ],
    );
    assert_eq!(tap_warnings(&g19), 1, "one warning a program");
    // The path stays connected: every move starts where the last one ended.
    for p in [&g18, &g19] {
        let segs: Vec<_> = p
            .moves
            .iter()
            .filter_map(|m| match &m.kind {
                MoveKind::Path { segment, .. } => Some(segment),
                MoveKind::Dwell { .. } => None,
            })
            .collect();
        for w in segs.windows(2) {
            assert!((w[0].end() - w[1].start()).norm() < 1e-15);
        }
    }
    // In G17 the tap goes into the hole, without a warning.
    assert_eq!(
        tap_warnings(&ok("M3 S1\nG0 X0 Y0 Z10\nG84 X1 Y1 R2 Z-3 F60\n")),
        0
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
