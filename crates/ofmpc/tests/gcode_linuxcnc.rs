//! LinuxCNC's dialect where its interpreter tests (tests/interp) and its programs (nc_files)
//! found the reader refusing with a wrong cause (issue #20): EXISTS with axes kept at 0,
//! G64 … R, computed O-word labels, `#<_value>` and the other predefined parameters. The
//! programs are the project's own; the expected values follow LinuxCNC's documentation
//! ("G-code overview: predefined named parameters", "O codes: indirection", "G64").

mod common;

use common::gcode::{assert_ends, fail, ok};
use ofmpc::gcode::{GcodeErrorKind, MoveKind};

#[test]
fn exists_reads_with_axes_kept_at_zero() {
    // EXISTS of a set and an unset name, of valid and invalid parameter numbers; A0 keeps
    // the A axis where it starts and is read (LinuxCNC's tests/interp/exists does this).
    let p = ok("#<a> = 9\nG0 X0 Y0 Z0\n#1 = 2\n#2 = 99999\n\
         G0 X EXISTS[#<a>] Y EXISTS[#<b>] Z EXISTS[##1] A EXISTS[#<b>]\n\
         G0 X EXISTS[##2] B0 C0\nG91 G0 Y1 A0 U0 V0 W0\nM2\n");
    assert_ends(&p, &[[1.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 1.0, 1.0]]);
    // An axis that would move is refused by name, at its word.
    let e = fail("G0 X0 Y0 Z0\nG1 X1 A90\n");
    assert_eq!(
        (e.line, e.column, e.kind),
        (2, 7, GcodeErrorKind::Unsupported)
    );
    assert!(e.to_string().contains("moves the A axis"), "{e}");
    let e = fail("G0 X0 Y0 Z0\nG1 X1 W-2\n");
    assert!(e.to_string().contains("moves the W axis"), "{e}");
}

#[test]
fn g64_r_planner_selection_is_read_and_named_in_a_warning() {
    let p = ok("G0 X0 Y0 Z0\nG64 P1 R0.5\nG64 P1 Q0.5 R0\nG64\nG1 X1 F100\n");
    let r: Vec<_> = p
        .warnings
        .iter()
        .filter(|w| w.message.contains("planner selection"))
        .collect();
    assert_eq!(r.len(), 2, "{:?}", p.warnings);
    assert_eq!((r[0].line, r[0].column), (2, 8));
    // R of an arc on a G64 line stays the arc's radius.
    let p = ok("G0 X0 Y0 Z0\nG64 P0.1 G2 X2 Y0 R1 F100\n");
    assert!(p.warnings.iter().all(|w| !w.message.contains("planner")));
    assert!(matches!(
        p.moves[0].kind,
        MoveKind::Path {
            segment: ofmpc::geometry::Segment::Arc { .. },
            ..
        }
    ));
}

#[test]
fn computed_o_word_labels_call_the_subroutine_they_name() {
    let text = "\
o100 sub
  G1 X[#<_x> + 1] F100
o100 endsub
o200 sub
  G1 Y2
o200 endsub
o<side> sub
  G1 Z3
o<side> endsub
G0 X0 Y0 Z0
#2 = 10
o[#2 * 10] call
#<n> = 200
o#<n> call
#3 = 2
o[#3 * 50] call
M2
";
    assert_ends(
        &ok(text),
        &[[1.0, 0.0, 0.0], [1.0, 2.0, 0.0], [2.0, 2.0, 0.0]],
    );
    // Not a whole number; no such subroutine; a computed label on a sub.
    let e = fail("G0 X0 Y0 Z0\no[1.5] call\n");
    assert_eq!(
        (e.line, e.column, e.kind),
        (2, 1, GcodeErrorKind::InvalidValue)
    );
    assert!(e.to_string().contains("not a whole number"), "{e}");
    let e = fail("G0 X0 Y0 Z0\n#1 = 7\no#1 call\n");
    assert!(e.to_string().contains("o7 call (o#1 is o7)"), "{e}");
    let e = fail("#1 = 7\no#1 sub\no#1 endsub\n");
    assert_eq!(e.kind, GcodeErrorKind::Unsupported);
    assert!(e.to_string().contains("computed O-word label"), "{e}");
}

#[test]
fn value_holds_the_last_return_value_and_is_zero_before_any_call() {
    // LinuxCNC: #<_value> is 0 before any call; `return [v]` / `endsub [v]` set it to v and
    // #<_value_returned> to 1; a return without a value sets both to 0.
    let text = "\
o1 sub
  o2 if [#1 GT 0]
    o1 return [#1 * 123]
  o2 endif
  o3 if [#1 LT 0]
    o1 return
  o3 endif
o1 endsub [4712]
G0 X#<_value> Y#<_value_returned> Z0
o1 call [2]
G0 X#<_value> Y#<_value_returned>
o1 call [-1]
G0 X#<_value> Y#<_value_returned>
o1 call [0]
G0 X#<_value> Y#<_value_returned>
M2
";
    assert_ends(
        &ok(text),
        &[[246.0, 1.0, 0.0], [0.0, 0.0, 0.0], [4712.0, 1.0, 0.0]],
    );
}

#[test]
fn predefined_parameters_follow_the_modal_state() {
    // Position (#<_x>, #5420 in program coordinates; #<_abs_x> in machine ones), units,
    // distance mode, coordinate system (#5220, #<_coord_system>), call level and line.
    let text = "\
G10 L2 P2 X100
G0 X1 Y2 Z3
G55
G0 X5
G0 X#<_x> Y#<_abs_x> Z#5420
G0 X#5220 Y#<_coord_system> Z#<_metric>
G20 G91
G90 G0 X#<_imperial> Y#<_incremental> Z[#<_line> / 10]
o1 sub
  G0 X[#<_call_level> * 2]
o1 endsub
o1 call
M2
";
    // Each parameter is read before its line runs (G90 on line 8 comes after G91's
    // #<_incremental> = 1 is read); inches from line 8 on.
    let inch = 25.4;
    assert_ends(
        &ok(text),
        &[
            [105.0, 2.0, 3.0],
            [105.0, 105.0, 5.0],
            [102.0, 550.0, 1.0],
            [100.0 + inch, inch, 0.8 * inch],
            [100.0 + 2.0 * inch, inch, 0.8 * inch],
        ],
    );
    // Setting a predefined parameter is refused, naming it.
    let e = fail("#<_x> = 1\nG0 X0 Y0 Z0\n");
    assert_eq!(
        (e.line, e.column, e.kind),
        (1, 1, GcodeErrorKind::InvalidValue)
    );
    assert!(
        e.to_string().contains("#<_x> is a predefined parameter"),
        "{e}"
    );
    let e = fail("#5220 = 2\nG0 X0 Y0 Z0\n");
    assert!(
        e.to_string().contains("#5220 is a predefined parameter"),
        "{e}"
    );
    // Parameters outside the kept ranges stay free (#5070: probe result, #5599: debug).
    ok("#5070 = 1\n#5599 = 1\nG0 X#5070 Y0 Z0\n");
}

#[test]
fn corpus_constructs_read_or_are_refused_by_their_own_name() {
    // G04 uses no axis words: a motion may follow it on its line; the dwell comes first.
    let p = ok("G0 X0 Y0 Z0\nG4 P0.5 G0 X1 Y1 M3 $0 S1000\nM52 P1\nM19 R90 Q2 $0\nM2\n");
    assert!(matches!(p.moves[0].kind, MoveKind::Dwell { seconds } if seconds == 0.5));
    assert_ends(&p, &[[1.0, 1.0, 0.0]]);
    let m3 = p.events.iter().find(|e| e.code == "M3").expect("M3 event");
    assert_eq!(m3.words, vec![('$', 0.0)]);
    assert!(p
        .events
        .iter()
        .any(|e| e.code == "M52" && e.words == vec![('P', 1.0)]));
    // Each refusal names its construct, at its column.
    let cases: [(&str, usize, &str); 5] = [
        (
            "G0 X0 Y0 Z0\nF#<_hal[plasmac.cut-feed-rate]>\n",
            1,
            "reads a HAL pin",
        ),
        (
            "G0 X0 Y0 Z0\nG0 Z#<_ini[probe]z_max>\n",
            4,
            "reads LinuxCNC's INI file",
        ),
        (
            "G0 X0 Y0 Z0\nG91 G38.2 Z-10 F100\n",
            5,
            "G38.2 (straight probe)",
        ),
        (
            "G0 X0 Y0 Z0\nO<g20sub> callsub\n",
            11,
            "unknown O-word keyword `callsub`",
        ),
        ("gsw_meta:51\nG0 X0 Y0 Z0\n", 1, "`gsw_meta` is not G-code"),
    ];
    for (text, col, what) in cases {
        let e = fail(text);
        assert!(e.to_string().contains(what), "{e}");
        assert_eq!(e.column, col, "{e}");
    }
}

/// A program point `p` (mm) of a system with offset `o` rotated by `deg` about Z, as the
/// machine point (mm): `Rz(deg)·(p + g92) + o` (LinuxCNC's emccanon.cc, written here
/// independently of the reader).
fn machine(p: [f64; 3], g92: [f64; 3], o: [f64; 3], deg: f64) -> [f64; 3] {
    let (s, c) = deg.to_radians().sin_cos();
    let (x, y) = (p[0] + g92[0], p[1] + g92[1]);
    [
        c * x - s * y + o[0],
        s * x + c * y + o[1],
        p[2] + g92[2] + o[2],
    ]
}

#[test]
fn g10_l2_r_rotates_the_xy_plane_of_the_system_about_its_origin() {
    // R0 is no rotation; R45 rotates the programmed XY before the offset is added.
    let p = ok("G10 L2 P1 X1 R0\nG0 X0 Y0 Z0\nM2\n");
    assert!((p.start.x - 1e-3).abs() < 1e-15);
    let o = [10.0, 20.0, 5.0];
    let p = ok("G10 L2 P1 X10 Y20 Z5 R45\nG0 X0 Y0 Z0\nG1 X4 F100\nY3\nG91 X1 Y1\nG90 Z2\nM2\n");
    let want = [
        [4.0, 0.0, 0.0],
        [4.0, 3.0, 0.0],
        [5.0, 4.0, 0.0],
        [5.0, 4.0, 2.0],
    ]
    .map(|q| machine(q, [0.0; 3], o, 45.0));
    assert_ends(&p, &want);
    assert!((p.start - nalgebra::Vector3::new(10.0, 20.0, 5.0) * 1e-3).norm() < 1e-15);
    // G92 is added to the program point before the rotation: G92 X0 Y0 at program (4, 0)
    // makes g92 = (4, 0), so X1 Y0 is program (5, 0).
    let p = ok("G10 L2 P2 X10 R90\nG55 G0 X4 Y0 Z0\nG92 X0 Y0\nG1 X1 F100\nM2\n");
    let want = [machine(
        [1.0, 0.0, 0.0],
        [4.0, 0.0, 0.0],
        [10.0, 0.0, 0.0],
        90.0,
    )];
    assert_ends(&p, &want);
    // Arcs turn with the system: a half circle from program (0, 0) about (5, 0).
    let p = ok("G10 L2 P1 R30\nG0 X0 Y0 Z0\nG2 X10 Y0 I5 J0 F100\nM2\n");
    assert_ends(&p, &[machine([10.0, 0.0, 0.0], [0.0; 3], [0.0; 3], 30.0)]);
    let p = ok("G10 L2 P1 R30\nG90.1 G0 X0 Y0 Z0\nG3 X10 Y0 I5 J0 F100\nM2\n");
    assert_ends(&p, &[machine([10.0, 0.0, 0.0], [0.0; 3], [0.0; 3], 30.0)]);
    // G53 moves in machine coordinates, unrotated; #5230 holds the rotation and #5420/#5421
    // read the position back in the rotated system.
    let p = ok("G10 L2 P1 R90\nG0 X0 Y0 Z0\nG53 G0 X2 Y0\n(DEBUG, #5230 #5420 #5421)\nM2\n");
    assert_ends(&p, &[[2.0, 0.0, 0.0]]);
    assert_eq!(p.messages[0].text, "90.000000 0.000000 -2.000000");
}

#[test]
fn g10_l20_in_a_rotated_system_makes_the_current_point_read_as_given() {
    // LinuxCNC's tests/interp g10-l20 scenario, written anew: in a system rotated by 45°,
    // G10 L20 X-1 makes the current point (machine 0, 0) read X = -1; G1 X0 then moves
    // one unit along the rotated X axis.
    let p =
        ok("G10 L2 P1 R45\nG0 G53 X0 Y0 Z0\nG10 L20 P1 X-1\n(DEBUG, #5420 #5421)\nG1 X0 F60\nM2\n");
    assert_eq!(p.messages[0].text, "-1.000000 0.000000");
    let h = 0.5_f64.sqrt();
    assert_ends(&p, &[[h, h, 0.0]]);
    // Arcs in G18/G19 of a rotated system leave the plane: refused by name.
    let e = fail("G10 L2 P1 R45\nG0 X0 Y0 Z0\nG18 G2 X2 Z0 I1 K0\n");
    assert_eq!((e.line, e.kind), (3, GcodeErrorKind::Unsupported));
    assert!(e.to_string().contains("rotated coordinate system"), "{e}");
}

#[test]
fn a_program_name_o_word_alone_on_its_line_is_read_as_a_title() {
    // LinuxCNC reads `O<name>` alone on a line as the program's name, like `O42`.
    let p = ok("%\n(title)\nO<MyProgram> (the name)\nG0 X1 Y2 Z3\nG1 X2 F100\nM30\n%\n");
    assert_ends(&p, &[[2.0, 2.0, 3.0]]);
    assert!(
        p.warnings
            .iter()
            .any(|w| w.line == 3 && w.message.contains("o<myprogram> (program name) ignored")),
        "{:?}",
        p.warnings
    );
    // With a word after it, it is still an O-word without a keyword.
    let e = fail("O<name> G0 X0 Y0 Z0\n");
    assert!(e.to_string().contains("without a keyword"), "{e}");
}

#[test]
fn debug_and_print_formats_set_the_decimals_of_the_values_after_them() {
    // LinuxCNC's convert_param_comment: %lf by default, %d no decimals, %f four, %.Nf N;
    // a format holds for the rest of the comment; another % is kept.
    let p = ok("#<v> = 2.718281828\n#1 = 0.5\n(DEBUG, a #<v> %d#<v> b #1)\n(PRINT, %.2f#<v> and #1, 50%)\n(DEBUG, %f#<v>)\nG0 X0 Y0 Z0\nM2\n");
    let texts: Vec<&str> = p.messages.iter().map(|m| m.text.as_str()).collect();
    assert_eq!(texts, ["a 2.718282 3 b 0", "2.72 and 0.50, 50%", "2.7183"]);
}
