//! G-code reader: the paper's program, language features, arc geometry, and every error case
//! (line, column, and a hint that names the fix).

mod common;

use common::gcode::{fail, ok};
use nalgebra::Vector3;
use ofmpc::gcode::{
    parse, GcodeError, GcodeErrorKind, MoveKind, ParseOptions, Program, PAPER_TABLE1,
};
use ofmpc::geometry::{Plane, Segment};
use std::f64::consts::PI;

/// Asserts position and kind, and that the rendered message contains every `needle`.
fn check(e: &GcodeError, line: usize, column: usize, kind: GcodeErrorKind, needles: &[&str]) {
    let shown = e.to_string();
    assert_eq!((e.line, e.column, e.kind), (line, column, kind), "{shown}");
    for n in needles {
        assert!(shown.contains(n), "`{shown}` does not mention `{n}`");
    }
    assert!(!e.hint.is_empty(), "no hint in {shown}");
    assert!(shown.starts_with(&format!("line {line}, column {column}: ")));
}

fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
    Vector3::new(x, y, z)
}

fn segments(p: &Program) -> Vec<Segment> {
    p.moves
        .iter()
        .filter_map(|m| match &m.kind {
            MoveKind::Path { segment, .. } => Some(segment.clone()),
            MoveKind::Dwell { .. } => None,
        })
        .collect()
}

/// Every sampled point of an arc lies at its radius from the axis.
fn assert_on_circle(seg: &Segment, centre_uv: (f64, f64), r: f64) {
    let Segment::Arc { plane, .. } = seg else {
        panic!("not an arc: {seg:?}")
    };
    let (u, w, _) = plane.axes();
    for i in 0..=200 {
        let p = seg.point(seg.length() * i as f64 / 200.0);
        let d = (p[u] - centre_uv.0).hypot(p[w] - centre_uv.1);
        assert!(
            (d - r).abs() < 1e-12,
            "point {p} at {d} from the centre, not {r}"
        );
    }
}

fn sweep(seg: &Segment) -> f64 {
    match seg {
        Segment::Arc { sweep, .. } => *sweep,
        Segment::Line { .. } => panic!("not an arc"),
    }
}

// ------------------------------------------------------------------------------------------
// The paper's program

#[test]
fn paper_program_with_g17_and_offset() {
    let p = ok(PAPER_TABLE1);
    assert!(p.warnings.is_empty(), "{:?}", p.warnings);
    // Offset (150, 0, -250) mm: the start point X630 Y-200 Z400 lies at (0.780, -0.200, 0.150).
    assert!((p.start - v(0.780, -0.200, 0.150)).norm() < 1e-15);
    let line_of = |label: &str| {
        PAPER_TABLE1
            .lines()
            .position(|l| l.starts_with(label))
            .map(|i| i + 1)
    };
    assert_eq!(Some(p.start_line), line_of("N020"));
    // The first G00 is the start point; then 2 lines, 3 arcs, 3 lines.
    let segs = segments(&p);
    assert_eq!(segs.len(), 8);
    let kinds: Vec<bool> = segs
        .iter()
        .map(|s| matches!(s, Segment::Arc { .. }))
        .collect();
    assert_eq!(kinds, [false, false, true, true, true, false, false, false]);
    let ends = [
        v(0.780, 0.200, 0.150),
        v(0.780, 0.0, 0.150),
        v(0.580, -0.200, 0.150),
        v(0.580, 0.200, 0.150),
        v(0.780, 0.0, 0.150),
        v(0.780, -0.200, 0.150),
        v(0.780, 0.200, 0.150),
        v(0.780, 0.0, 0.150),
    ];
    let mut prev = p.start;
    for (seg, end) in segs.iter().zip(ends) {
        assert_eq!(seg.start(), prev, "segments must join exactly");
        assert!((seg.end() - end).norm() < 1e-12, "{} vs {end}", seg.end());
        prev = seg.end();
    }
    // The arcs: clockwise about (580, 0) mm, radius 200 mm, one full turn in all.
    let total: f64 = segs[2..5].iter().map(sweep).sum();
    assert!((total + 2.0 * PI).abs() < 1e-12, "total sweep {total}");
    for s in &segs[2..5] {
        assert!(sweep(s) < 0.0);
        assert_on_circle(s, (0.580, 0.0), 0.200);
    }
    // Source lines follow the labels (N010 appears twice: the last move is the second one).
    let labels = ["N030", "N040", "N050", "N060", "N070", "N080", "N090"];
    for (m, label) in p.moves.iter().zip(labels) {
        assert_eq!(Some(m.line), line_of(label));
    }
    let lines: Vec<&str> = PAPER_TABLE1.lines().collect();
    let last_n010 = lines
        .iter()
        .rposition(|l| l.starts_with("N010"))
        .map(|i| i + 1);
    assert_eq!(p.moves.last().map(|m| m.line), last_n010);
    assert!(p
        .moves
        .iter()
        .all(|m| matches!(m.kind, MoveKind::Path { feed: None, .. })));
}

/// The paper's Table I exactly as printed (with digits for the OCR's letter O).
const PAPER_G19: &str = "N010 G19
N020 G00 X630 Y-200 Z400
N030 G00 X630 Y200 Z400
N040 G00 X630 Y0 Z400
N050 G02 X430 Y-200 Z400 I-200 J0 K0
N060 G02 X430 Y200 Z400 I0 J200 K0
N070 G02 X630 Y0 Z400 I0 J-200 K0
N080 G00 X630 Y-200 Z400
N090 G00 X630 Y200 Z400
N010 G00 X630 Y0 Z400
";

#[test]
fn paper_program_with_g19_is_rejected_with_the_g17_hint() {
    let e = fail(PAPER_G19);
    check(
        &e,
        5,
        6,
        GcodeErrorKind::Arc,
        &[
            "radius is zero in the YZ plane (G19)",
            "the I/J offsets fit the XY plane (G17): did you mean G17 instead of G19?",
            "N050 G02",
        ],
    );
    // With G17 the same text parses, in the base frame (no offset).
    let p = ok(&PAPER_G19.replace("G19", "G17"));
    assert!((p.start - v(0.630, -0.200, 0.400)).norm() < 1e-15);
    assert_eq!(segments(&p).len(), 8);
}

#[test]
fn paper_ocr_letter_o_gets_a_hint() {
    let e = fail("N020 G00 X630 Y0 Z400\nN050 G02 X430 Y-200 Z400 I-200 JO K0\n");
    check(
        &e,
        2,
        32,
        GcodeErrorKind::Syntax,
        &["J has no number", "JO", "write J0"],
    );
}

// ------------------------------------------------------------------------------------------
// Language features

#[test]
fn lexical_forms_parse() {
    let p = ok("%\r\n\
        ( header comment )\r\n\
        n1 g21 g90 ; lower case, comment after semicolon\r\n\
        N2G0X10Y20Z30(packed words)\r\n\
        N2 G 1 X 11.5 ; repeated label, spaces inside words\r\n\
        N3 X+12. Y20.25 Z.5\r\n\
        %\r\n");
    assert!((p.start - v(0.010, 0.020, 0.030)).norm() < 1e-15);
    let s = segments(&p);
    assert_eq!(s.len(), 2);
    assert!((s[0].end() - v(0.0115, 0.020, 0.030)).norm() < 1e-15);
    assert!((s[1].end() - v(0.012, 0.02025, 0.0005)).norm() < 1e-15);
    assert_eq!(p.moves[1].line, 6);
}

#[test]
fn units_distance_modes_and_feeds() {
    let p = ok("G20 G90 G0 X1 Y2 Z3\n\
        G1 X2 F60\n\
        G91 Y-1\n\
        G21 G0 Z10\n\
        G1 X-5\n");
    let i = 0.0254;
    assert!((p.start - v(i, 2.0 * i, 3.0 * i)).norm() < 1e-15);
    let s = segments(&p);
    assert!((s[0].end() - v(2.0 * i, 2.0 * i, 3.0 * i)).norm() < 1e-15);
    assert!((s[1].end() - v(2.0 * i, i, 3.0 * i)).norm() < 1e-15);
    assert!((s[2].end() - v(2.0 * i, i, 3.0 * i + 0.010)).norm() < 1e-15);
    assert!((s[3].end() - v(2.0 * i - 0.005, i, 3.0 * i + 0.010)).norm() < 1e-15);
    let feeds: Vec<Option<f64>> = p
        .moves
        .iter()
        .map(|m| match m.kind {
            MoveKind::Path { feed, .. } => feed,
            MoveKind::Dwell { .. } => panic!(),
        })
        .collect();
    // F60 in/min = 0.0254 m/s; modal; G00 ignores it; after G21 it reads 60 mm/min.
    let f = feeds
        .iter()
        .map(|f| f.map(|f| f * 60.0))
        .collect::<Vec<_>>();
    assert!((f[0].unwrap() - 60.0 * i).abs() < 1e-15);
    assert!((f[1].unwrap() - 60.0 * i).abs() < 1e-15);
    assert_eq!(f[2], None);
    assert!((f[3].unwrap() - 0.060).abs() < 1e-15);
}

#[test]
fn modal_motion_repeats_the_last_mode() {
    let p = ok("G0 X0 Y0 Z0\nG2 X20 Y0 I10\nX0 Y0 I-10\nG1 X5\nY5\n");
    let s = segments(&p);
    assert_eq!(s.len(), 4);
    assert!(matches!(s[0], Segment::Arc { .. }) && matches!(s[1], Segment::Arc { .. }));
    assert!((sweep(&s[0]) + PI).abs() < 1e-12 && (sweep(&s[1]) + PI).abs() < 1e-12);
    assert!(matches!(s[3], Segment::Line { .. }));
    assert!((s[3].end() - v(0.005, 0.005, 0.0)).norm() < 1e-15);
    // A mode word alone sets the mode without moving.
    let p = ok("G0 X0 Y0 Z0\nG1\nX1\n");
    assert_eq!(p.moves.len(), 1);
}

#[test]
fn dwell() {
    let p = ok("G0 X0 Y0 Z0\nG4 P0.5\nG04 X2\nG4 P0\n");
    let d: Vec<f64> = p
        .moves
        .iter()
        .map(|m| match m.kind {
            MoveKind::Dwell { seconds } => seconds,
            MoveKind::Path { .. } => panic!(),
        })
        .collect();
    assert_eq!(d, [0.5, 2.0]);
}

#[test]
fn work_offsets_and_origin_option() {
    // G10 L2 P2 sets G55; switching frames mid-program keeps omitted axes where they are.
    let p = ok("G10 L2 P2 X100 Y-50 Z10\nG55 G0 X1 Y2 Z3\nG54 X0\nG10 L2 P1 Y7\nG1 Y0\n");
    assert!((p.start - v(0.101, -0.048, 0.013)).norm() < 1e-15);
    let s = segments(&p);
    assert!((s[0].end() - v(0.0, -0.048, 0.013)).norm() < 1e-15);
    assert!((s[1].end() - v(0.0, 0.007, 0.013)).norm() < 1e-15);

    let opts = ParseOptions {
        origin: Some([0.5, 0.1, -0.2]),
        ..ParseOptions::default()
    };
    let p = parse("G0 X10 Y0 Z0\n", &opts).unwrap();
    assert!((p.start - v(0.510, 0.1, -0.2)).norm() < 1e-15);
    assert!(p.warnings.is_empty());
    // A program that sets its own G54 offset wins over the option, with a warning; omitted
    // axes of that offset are zero, not taken from the option.
    let p = parse("G10 L2 P1 X150\nG0 X10 Y0 Z0\n", &opts).unwrap();
    assert!((p.start - v(0.160, 0.0, 0.0)).norm() < 1e-15);
    assert_eq!(p.warnings.len(), 1);
    assert!(p.warnings[0].message.contains("origin"));
    // G10 is absolute even in G91.
    let p = ok("G91 G10 L2 P1 X1\nG90 G0 X0 Y0 Z0\n");
    assert!((p.start - v(0.001, 0.0, 0.0)).norm() < 1e-15);
}

#[test]
fn warnings_for_harmless_words_and_text_after_the_end() {
    let p = ok(
        "O1000\nG0 X0 Y0 Z0 S1000 M03\nT1 M6\nG1 X1 G64\nM05 M30\nG1 X5 (ignored)\n@@@ garbage\n",
    );
    let at: Vec<(usize, usize)> = p.warnings.iter().map(|w| (w.line, w.column)).collect();
    assert_eq!(
        at,
        [(1, 1), (2, 13), (2, 19), (3, 1), (3, 4), (5, 1), (6, 1)]
    );
    assert!(p.warnings[6].message.contains("ignored"));
    assert_eq!(p.moves.len(), 1);
    assert!(p.warnings[6].to_string().starts_with("line 6, column 1: "));
}

#[test]
fn zero_length_moves_are_skipped_with_a_warning() {
    let p = ok("G0 X1 Y1 Z1\nG1 X1\nG91 X0 Y0\n");
    assert!(p.moves.is_empty());
    assert_eq!(p.warnings.len(), 2);
    assert_eq!(p.end(), p.start);
}

// ------------------------------------------------------------------------------------------
// Arcs

#[test]
fn arcs_in_every_plane_end_exactly_and_turn_the_right_way() {
    // Quarter arcs of radius 10 mm about the origin, in each plane, G02 and G03.
    let cases = [
        ("G17", "X10 Y0 Z0", "X0 Y10", "I-10 J0", Plane::XY),
        ("G18", "X0 Y0 Z10", "X10 Z0", "K-10 I0", Plane::ZX),
        ("G19", "X0 Y10 Z0", "Y0 Z10", "J-10 K0", Plane::YZ),
    ];
    for (g, start, end, ijk, plane) in cases {
        for (code, sign) in [("G03", 1.0), ("G02", -1.0)] {
            let p = ok(&format!("{g} G0 {start}\n{code} {end} {ijk}\n"));
            let s = segments(&p);
            let seg = &s[0];
            let (u, w, n) = plane.axes();
            let mut expect_end = Vector3::zeros();
            expect_end[w] = 0.010;
            assert!(
                (seg.end() - expect_end).norm() < 1e-12,
                "{g} {code}: {}",
                seg.end()
            );
            assert_on_circle(seg, (0.0, 0.0), 0.010);
            // Counter-clockwise = a quarter turn, clockwise = three quarters.
            let expect = if sign > 0.0 { PI / 2.0 } else { -1.5 * PI };
            assert!((sweep(seg) - expect).abs() < 1e-12, "{g} {code}");
            // The turning sense about the plane's positive normal.
            let mut normal = Vector3::zeros();
            normal[n] = 1.0;
            let r = seg.point(0.001);
            let turn = r.cross(&seg.tangent(0.001)).dot(&normal);
            assert!(turn * sign > 0.0, "{g} {code}");
            let _ = u;
        }
    }
}

#[test]
fn helix_and_full_circles() {
    // Half a turn rising 5 mm.
    let p = ok("G0 X10 Y0 Z0\nG3 X-10 Y0 Z5 I-10 J0\n");
    let s = &segments(&p)[0];
    assert!((s.end() - v(-0.010, 0.0, 0.005)).norm() < 1e-12);
    assert!((s.length() - (0.010 * PI).hypot(0.005)).abs() < 1e-15);
    assert_on_circle(s, (0.0, 0.0), 0.010);
    for i in 0..=10 {
        let z = s.point(s.length() * i as f64 / 10.0).z;
        assert!((z - 0.0005 * i as f64).abs() < 1e-15);
    }
    // Full circle, with explicit end = start and with no end at all.
    for text in [
        "G0 X10 Y0 Z0\nG2 X10 Y0 I-10 J0\n",
        "G0 X10 Y0 Z0\nG2 I-10\n",
    ] {
        let p = ok(text);
        let s = &segments(&p)[0];
        assert!((sweep(s) + 2.0 * PI).abs() < 1e-15);
        assert!((s.end() - v(0.010, 0.0, 0.0)).norm() < 1e-12);
        assert_on_circle(s, (0.0, 0.0), 0.010);
    }
    // A full helical turn.
    let p = ok("G0 X10 Y0 Z0\nG3 Z-3 I-10\n");
    let s = &segments(&p)[0];
    assert!((sweep(s) - 2.0 * PI).abs() < 1e-15);
    assert!((s.end() - v(0.010, 0.0, -0.003)).norm() < 1e-12);
}

#[test]
fn r_arcs_short_and_long() {
    // From (0,0) to (10,10) with |R| = 10: centres (10,0) or (0,10).
    for (code, r, expect_sweep, centre) in [
        ("G2", "R10", -PI / 2.0, (0.010, 0.0)),
        ("G2", "R-10", -1.5 * PI, (0.0, 0.010)),
        ("G3", "R10", PI / 2.0, (0.0, 0.010)),
        ("G3", "R-10", 1.5 * PI, (0.010, 0.0)),
    ] {
        let p = ok(&format!("G0 X0 Y0 Z0\n{code} X10 Y10 {r}\n"));
        let s = &segments(&p)[0];
        assert!(
            (sweep(s) - expect_sweep).abs() < 1e-12,
            "{code} {r}: {}",
            sweep(s)
        );
        assert!((s.end() - v(0.010, 0.010, 0.0)).norm() < 1e-12);
        assert_on_circle(s, centre, 0.010);
    }
    // Semicircle: |R| exactly half the chord; and a radius a hair short of it.
    for r in ["R5", "R4.9995"] {
        let p = ok(&format!("G0 X0 Y0 Z0\nG2 X10 Y0 {r}\n"));
        let s = &segments(&p)[0];
        assert!((sweep(s) + PI).abs() < 1e-9, "{r}: {}", sweep(s));
        assert!((s.end() - v(0.010, 0.0, 0.0)).norm() < 1e-12);
    }
    // Inch R, arc in G18 with a helix along Y.
    let p = ok("G20 G18 G0 X1 Y0 Z0\nG3 X0 Z1 Y0.5 R1\n");
    let s = &segments(&p)[0];
    assert!((sweep(s) - PI / 2.0).abs() < 1e-12);
    assert!((s.end() - v(0.0, 0.0127, 0.0254)).norm() < 1e-12);
}

#[test]
fn small_radius_mismatch_within_tolerance_is_accepted() {
    // End radius 10.001 mm vs start radius 10 mm: within 0.002 mm.
    let p = ok("G0 X10 Y0 Z0\nG3 X0 Y10.001 I-10 J0\nG1 X-5\n");
    let s = segments(&p);
    assert_on_circle(&s[0], (0.0, 0.0), 0.010);
    assert_eq!(
        s[1].start(),
        s[0].end(),
        "the next move starts where the arc ends"
    );
    assert!((s[0].end() - v(0.0, 0.010, 0.0)).norm() < 1e-12);
    assert_eq!(p.warnings.len(), 1);
    assert!(
        p.warnings[0].message.contains("0.001000 mm"),
        "{}",
        p.warnings[0]
    );
    // 0.003 mm is too much.
    let e = fail("G0 X10 Y0 Z0\nG3 X0 Y10.003 I-10 J0\n");
    check(
        &e,
        2,
        1,
        GcodeErrorKind::Arc,
        &["radii differ", "10.0000 mm vs 10.0030 mm"],
    );
}

// ------------------------------------------------------------------------------------------
// Errors

const START: &str = "G0 X0 Y0 Z0\n";

fn fail_after_start(body: &str) -> GcodeError {
    fail(&format!("{START}{body}"))
}

#[test]
fn syntax_errors() {
    use GcodeErrorKind::*;
    check(
        &fail_after_start("G1 X1.2.3\n"),
        2,
        4,
        Syntax,
        &["`1.2.3` does not parse", "X1.2.3", "one point"],
    );
    check(
        &fail_after_start("G1 X Y1\n"),
        2,
        4,
        Syntax,
        &["X has no number", "write a number after X"],
    );
    check(
        &fail_after_start("G1 X-\n"),
        2,
        4,
        Syntax,
        &["X has no number"],
    );
    check(
        &fail_after_start("G1 X1 (open comment\n"),
        2,
        7,
        Syntax,
        &["unclosed comment", "close the comment"],
    );
    // Issue #20: parameters, block delete and expressions are read now (gcode_language.rs).
    let p = ok(&format!("{START}#1=5\nG1 X#1\n/G1 X9\nG1 Y[1+2]\n"));
    assert!((p.end() - v(0.005, 0.003, 0.0)).norm() < 1e-15);
    check(
        &fail_after_start("G1 X1 %\n"),
        2,
        7,
        Syntax,
        &["`%` inside a line", "alone on its line"],
    );
    check(
        &fail_after_start("G1 X1 ) \n"),
        2,
        7,
        Syntax,
        &["`)` without `(`"],
    );
    check(
        &fail_after_start("G1 X1 µ\n"),
        2,
        7,
        Syntax,
        &["unexpected character", "`µ`"],
    );
    check(
        &fail_after_start("G1 Xé1\n"),
        2,
        4,
        Syntax,
        &["X has no number"],
    );
    let huge = format!("G1 X{}\n", "9".repeat(400));
    check(
        &fail_after_start(&huge),
        2,
        4,
        InvalidValue,
        &["out of range"],
    );
}

#[test]
fn word_errors() {
    use GcodeErrorKind::*;
    check(
        &fail_after_start("G6 X1\n"),
        2,
        1,
        UnknownCode,
        &["unknown G code G6", "supported: G00"],
    );
    check(
        &fail_after_start("G1.5 X1\n"),
        2,
        1,
        UnknownCode,
        &["unknown G code"],
    );
    check(
        &fail_after_start("G41 D1\n"),
        2,
        1,
        Unsupported,
        &["G41/G42 cutter radius compensation", "tool centre path"],
    );
    check(
        &fail_after_start("G96 S100\n"),
        2,
        1,
        Unsupported,
        &["G96", "G97"],
    );
    check(
        &fail_after_start("G5.2 X1 Y1 P1\n"),
        2,
        1,
        Unsupported,
        &["G5.2 (spline or NURBS)", "lines and arcs"],
    );
    check(
        &fail_after_start("G1 X1 A90\n"),
        2,
        7,
        Unsupported,
        &["rotary axis word A", "orientation is constant"],
    );
    check(
        &fail_after_start("G1 X1 E0.5\n"),
        2,
        7,
        Unsupported,
        &["E (extruder)", "3D-printer"],
    );
    check(
        &fail_after_start("G1 X1 Q2\n"),
        2,
        7,
        Unsupported,
        &["word Q is not supported", "supported letters"],
    );
    check(
        // M98 is read since issue #20's third round: a call of a missing subprogram.
        &fail_after_start("M98 P100\n"),
        2,
        1,
        Unsupported,
        &["no subprogram O100", "O100 on its own line … M99"],
    );
    check(
        &fail_after_start("G1 X1 X2\n"),
        2,
        7,
        Duplicate,
        &["X given twice", "(first as X1)", "once per line"],
    );
    check(
        &fail_after_start("G0 G1 X1\n"),
        2,
        4,
        Duplicate,
        &["G0 and G1 on one line", "keep one"],
    );
    check(
        &fail_after_start("G20 G21\n"),
        2,
        5,
        Duplicate,
        &["G20 and G21"],
    );
    check(
        &fail_after_start("G1 N5 X1\n"),
        2,
        4,
        Syntax,
        &["N label must be the first word"],
    );
    check(
        &fail_after_start("N-5 G1 X1\n"),
        2,
        1,
        InvalidValue,
        &["non-negative integer"],
    );
    check(
        &fail_after_start("G1 X1 F0\n"),
        2,
        7,
        InvalidValue,
        &["feed must be positive", "mm/min"],
    );
    check(
        &fail_after_start("G1 X1 F-100\n"),
        2,
        7,
        InvalidValue,
        &["feed must be positive"],
    );
}

#[test]
fn command_errors() {
    use GcodeErrorKind::*;
    check(
        &fail("X1 Y2 Z3\n"),
        1,
        1,
        Conflict,
        &["without a motion mode", "add G00 or G01"],
    );
    check(
        &fail_after_start("G1 X1 I5\n"),
        2,
        7,
        Conflict,
        &["I is only used by arcs", "G02 or G03"],
    );
    check(
        &fail_after_start("G1 X1 P2\n"),
        2,
        7,
        Conflict,
        &["P is only used by G04"],
    );
    check(
        &fail_after_start("G1 X1 L2\n"),
        2,
        7,
        Conflict,
        &["L is only used by G10 L2"],
    );
    check(
        &fail_after_start("G2 X1 Y1 I1 P2\n"),
        2,
        13,
        Conflict,
        &["P is only used by G04", "each turn"],
    );
    check(
        &fail_after_start("G4\n"),
        2,
        1,
        Missing,
        &["G04 without a time", "G04 P0.5"],
    );
    check(
        &fail_after_start("G4 P1 X1\n"),
        2,
        7,
        Conflict,
        &["both P and X", "once"],
    );
    check(
        &fail_after_start("G4 P-1\n"),
        2,
        4,
        InvalidValue,
        &["negative dwell"],
    );
    check(
        &fail_after_start("G4 P1 Y1\n"),
        2,
        7,
        Conflict,
        &["Y is not used by G04", "P (or X) seconds"],
    );
    // G10 and a motion both use the axis words: refused. (G04 uses none: `G4 P1 G1 X1`
    // dwells, then moves, as in LinuxCNC; see gcode_linuxcnc.rs.)
    check(
        &fail_after_start("G10 L2 P1 G1 X0\n"),
        2,
        11,
        Conflict,
        &["G10 and G1 on one line", "own line"],
    );
    check(
        &fail_after_start("G10 P1 X0\n"),
        2,
        1,
        Missing,
        &["G10 without L", "G10 L2 P1"],
    );
    check(
        &fail_after_start("G10 L1 P1 Z0\n"),
        2,
        5,
        Unsupported,
        &["G10 L1", "only G10 L2 / L20"],
    );
    check(
        &fail_after_start("G10 L2 X0\n"),
        2,
        1,
        Missing,
        &["without P", "P1..P6"],
    );
    check(
        &fail_after_start("G10 L2 P7 X0\n"),
        2,
        8,
        InvalidValue,
        &["P1..P6"],
    );
    // R of G10 L2 is LinuxCNC's rotation of the coordinate system (read, issue #20); with
    // L20 LinuxCNC refuses it, and so does the reader.
    check(
        &fail_after_start("G10 L20 P1 X0 R5\n"),
        2,
        15,
        Conflict,
        &["R is not allowed in G10 L20", "G10 L2 Pn R"],
    );
}

#[test]
fn start_point_errors() {
    use GcodeErrorKind::*;
    check(
        &fail("G0 X630 Y-200\n"),
        1,
        1,
        StartPoint,
        &["must give X, Y and Z (missing: Z)", "all three"],
    );
    check(&fail("G1 Z5\n"), 1, 1, StartPoint, &["missing: X, Y"]);
    check(
        &fail("G2 X1 Y1 Z0 I1\n"),
        1,
        1,
        StartPoint,
        &["first motion is an arc", "G00 X.. Y.. Z.."],
    );
    check(
        &fail("G91 G0 X1 Y1 Z1\n"),
        1,
        5,
        StartPoint,
        &["incremental (G91)", "absolute coordinates (G90)"],
    );
    check(
        &fail("G4 P1\nG0 X0 Y0 Z0\n"),
        1,
        1,
        StartPoint,
        &["dwell before the start point"],
    );
    let e = fail("(only a comment)\nG21 G90\nM30\n");
    assert_eq!((e.line, e.kind), (0, NoMotion));
    assert!(
        e.to_string().starts_with("the program has no motion"),
        "{e}"
    );
    assert_eq!(fail("").kind, NoMotion);
    let e = parse(
        START,
        &ParseOptions {
            origin: Some([f64::NAN, 0.0, 0.0]),
            ..ParseOptions::default()
        },
    )
    .unwrap_err();
    assert_eq!(e.kind, InvalidOption);
    assert!(e
        .to_string()
        .contains("origin (work offset) must be finite"));
    assert!(!e.to_string().contains("::"), "{e}");
}

#[test]
fn arc_errors() {
    use GcodeErrorKind::*;
    check(
        &fail_after_start("G2 X0 Y0 R10\n"),
        2,
        1,
        Arc,
        &[
            "zero-length arc",
            "give the centre with I/J/K",
            "R cannot describe a full circle",
        ],
    );
    check(
        &fail_after_start("G2 X10 Y0 R0\n"),
        2,
        11,
        Arc,
        &["R is zero"],
    );
    check(
        &fail_after_start("G2 X10 Y0 R4\n"),
        2,
        11,
        Arc,
        &[
            "|R| = 4.0000 mm is less than half the chord (5.0000 mm)",
            "increase R",
        ],
    );
    check(
        &fail_after_start("G2 X10 Y0 I0 J0\n"),
        2,
        1,
        Arc,
        &["radius is zero in the XY plane (G17)"],
    );
    check(
        &fail_after_start("G2 X10 Y0 I3\n"),
        2,
        1,
        Arc,
        &[
            "radii differ",
            "3.0000 mm vs 7.0000 mm",
            "check the end point",
        ],
    );
    check(
        &fail_after_start("G2 X10 Y0 K5\n"),
        2,
        1,
        Arc,
        &["needs the centre offsets I/J (or R)"],
    );
    check(
        &fail_after_start("G2 X10 Y0 R5 I5\n"),
        2,
        14,
        Conflict,
        &["both R and I/J/K", "either by R or by I/J/K"],
    );
    check(
        &fail_after_start("G2 X10 Y0 Z1 I5 K3\n"),
        2,
        1,
        Arc,
        &["K offset lies along the normal of the XY plane", "remove K"],
    );
    // Offsets I5 K1 also describe a valid ZX arc (centre Z1 X5, both radii √26 mm).
    check(
        &fail_after_start("G2 X10 Y0 I5 K1\n"),
        2,
        1,
        Arc,
        &[
            "K offset lies along the normal",
            "did you mean G18 instead of G17?",
        ],
    );
    // An XZ arc programmed under G17: in XY its end radius is 0; in ZX (centre Z0 X5) both
    // radii are 5 mm.
    check(
        &fail_after_start("G2 X5 Z5 I5 K0\n"),
        2,
        1,
        Arc,
        &[
            "radii differ",
            "the K/I offsets fit the ZX plane (G18): did you mean G18 instead of G17?",
        ],
    );
    // A YZ arc under G18 (centre Y5 Z5, radii √50 mm): the hint names G19.
    check(
        &fail_after_start("G18 G2 Y10 Z10 J5 K5\n"),
        2,
        5,
        Arc,
        &["did you mean G19 instead of G18?"],
    );
    // Modal motion: the error points at the first coordinate word.
    check(
        &fail_after_start("G2 X10 Y0 I5\n  Y10 Z10 J5 K5\n"),
        3,
        3,
        Arc,
        &[
            "K offset lies along the normal",
            "did you mean G19 instead of G17?",
        ],
    );
}

#[test]
fn display_format() {
    let e = fail_after_start("G1 X1 X2\n");
    assert_eq!(
        e.to_string(),
        "line 2, column 7: X given twice on one line (first as X1) in `X2` \
         (give each letter once per line; split the line in two)"
    );
}

#[test]
fn exponent_notation_nested_comments_bom_and_cr_line_ends() {
    use GcodeErrorKind::*;
    // Exponent notation: named as such, with the decimal number to write.
    let e = fail("G0 X0 Y0 Z0\nG1 X1e300\n");
    check(
        &e,
        2,
        4,
        Syntax,
        &["exponent notation is not G-code", "1e300"],
    );
    assert!(!e.to_string().contains("extruder"), "{e}");
    let e = fail("G0 X0 Y0 Z0\nG1 X2.5E-3 Y1\n");
    check(&e, 2, 4, Syntax, &["exponent notation", "X0.0025"]);
    // A nested comment is named, at the inner `(`.
    let e = fail("G0 X0 Y0 Z0\nG1 X1 ( a ( b ) c )\n");
    check(&e, 2, 11, Syntax, &["nested comment"]);
    // A UTF-8 byte-order mark at the start is accepted.
    let p = ok("\u{feff}G0 X1 Y2 Z3\nG1 X4\n");
    assert!((p.start - v(0.001, 0.002, 0.003)).norm() < 1e-15);
    assert_eq!(p.moves.len(), 1);
    // CR-only line ends: lines are counted (an error on the third line says line 3).
    let p = ok("G0 X0 Y0 Z0\rG1 X1\rG1 X2\r");
    assert_eq!(p.moves.len(), 2);
    assert_eq!(p.moves[1].line, 3);
    let e = fail("G0 X0 Y0 Z0\rG1 X1\rG1 Q2\r");
    assert_eq!(e.line, 3, "{e}");
    // Mixed CR LF and LF count the same.
    let p = ok("G0 X0 Y0 Z0\r\nG1 X1\nG1 X2\r\n");
    assert_eq!(p.moves[1].line, 3);
}

#[test]
fn path_modes_g61_and_g64_with_tolerance() {
    use ofmpc::gcode::PathMode;
    let modes = |p: &Program| -> Vec<Option<PathMode>> {
        p.moves
            .iter()
            .filter_map(|m| match &m.kind {
                MoveKind::Path { mode, .. } => Some(*mode),
                MoveKind::Dwell { .. } => None,
            })
            .collect()
    };
    let p =
        ok("G0 X0 Y0 Z0\nG1 X1\nG64 P0.05\nG1 X2\nG64\nG1 X3\nG61\nG1 X4\nG20 G64 P0.01 G1 X5\n");
    assert_eq!(
        modes(&p),
        [
            None,
            Some(PathMode::Blend {
                tolerance: Some(0.05e-3)
            }),
            Some(PathMode::Blend { tolerance: None }),
            Some(PathMode::ExactStop),
            Some(PathMode::Blend {
                tolerance: Some(0.01 * 0.0254)
            }),
        ]
    );
    assert!(p.warnings.is_empty(), "{:?}", p.warnings);
    // A negative tolerance is an error; P elsewhere still says what it is for.
    check(
        &fail("G0 X0 Y0 Z0\nG64 P-1\n"),
        2,
        5,
        GcodeErrorKind::InvalidValue,
        &["tolerance"],
    );
    let e = fail("G0 X0 Y0 Z0\nG1 X1 P0.1\n");
    assert!(e.to_string().contains("G64"), "{e}");
}
