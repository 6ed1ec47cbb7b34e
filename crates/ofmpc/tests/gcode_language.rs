//! rs274ngc language of the reader (issue #20): parameters, expressions, O-word control flow,
//! events, messages, the start from the tool position, the step limit.

use nalgebra::Vector3;
mod common;

use common::gcode::{close, ends, ok};
use ofmpc::gcode::{parse, GcodeErrorKind, ParseOptions};

#[test]
fn expressions_follow_the_dialect() {
    // Each X is checked against the value computed here independently.
    let cases: [(&str, f64); 14] = [
        ("[1 + 2 * 3]", 7.0),
        ("[2 ** 3 ** 2]", 64.0), // left to right, as LinuxCNC
        ("[7 MOD 3]", 1.0),
        ("[-7 MOD 3]", 2.0),
        ("[1 + 2 EQ 3]", 1.0),
        ("[1 LT 2 AND 3 GT 4]", 0.0),
        ("[1 OR 0 XOR 1]", 0.0),
        ("SIN[30]", 0.5),
        ("ATAN[1]/[1]", 45.0),
        ("SQRT[16] + 0", 4.0),
        ("[ROUND[2.5] + FIX[-1.5] + FUP[1.2]]", 3.0 - 2.0 + 2.0),
        ("[ABS[-3] * EXP[0] + LN[1]]", 3.0),
        ("-[2]", -2.0),
        ("[ACOS[0] - ASIN[1] + COS[60] * TAN[45]]", 0.5),
    ];
    for (e, want) in cases {
        // "SQRT[16] + 0" after a letter reads only SQRT[16]: a word's value is one real value.
        let e = e.trim_end_matches(" + 0");
        let p = ok(&format!("G0 X0 Y0 Z0\nG1 X{e} Y1\n"));
        let got = ends(&p)[0][0];
        assert!((got - want).abs() < 1e-9, "{e}: {got} vs {want}");
    }
}

#[test]
fn numbered_and_named_parameters() {
    let p = ok("#1 = 5\n#1 = 7 #2 = #1\n#<_g> = [#1 + #2]\n#<l> = 1\n#3 = 1\nG0 X#2 Y#<_g> Z#<l>\nG1 X##3\n");
    assert!(close(&ends(&p), &[[7.0, 12.0, 1.0]]), "{:?}", ends(&p));
    assert!((p.start - Vector3::new(5e-3, 12e-3, 1e-3)).norm() < 1e-15);
    let e = parse("G0 X#<nope> Y0 Z0\n", &ParseOptions::default()).unwrap_err();
    assert_eq!(
        (e.line, e.column, e.kind),
        (1, 4, GcodeErrorKind::InvalidValue)
    );
    assert!(e.to_string().contains("#<nope>"), "{e}");
    let e = parse("G0 X[1/0] Y0 Z0\n", &ParseOptions::default()).unwrap_err();
    assert!(e.to_string().contains("division by zero"), "{e}");
}

#[test]
fn subroutines_loops_and_conditions() {
    let text = "\
o<square> sub
  G1 X#1 Y0
  G1 X#1 Y#1
  G1 X0 Y#1
  G1 X0 Y0
o<square> endsub
G0 X0 Y0 Z0
#1 = 99
o<square> call [2]
#10 = 0
o100 while [#10 LT 3]
  #10 = [#10 + 1]
  o101 if [#10 EQ 2]
    o100 continue
  o101 elseif [#10 EQ 3]
    G1 Z3
  o101 else
    G1 Z1
  o101 endif
o100 endwhile
o102 repeat [2]
  G91 G1 X1
o102 endrepeat
G90
o103 do
  G1 Y#1
  o103 break
o103 while [1]
M2
G1 X1000
";
    let p = ok(text);
    let want = [
        [2.0, 0.0, 0.0],
        [2.0, 2.0, 0.0],
        [0.0, 2.0, 0.0],
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, 3.0],
        [1.0, 0.0, 3.0],
        [2.0, 0.0, 3.0],
        [2.0, 99.0, 3.0],
    ];
    assert!(close(&ends(&p), &want), "{:?}", ends(&p));
    // The caller's #1 came back after the call; the text after M2 is ignored.
    assert!(p
        .warnings
        .iter()
        .any(|w| w.message.contains("after the end")));
}

#[test]
fn an_endless_loop_ends_with_an_error_naming_it() {
    let text = "G0 X0 Y0 Z0\no7 while [1]\n#1 = [#1 + 1]\no7 endwhile\n";
    let opts = ParseOptions {
        max_steps: Some(10_000),
        ..ParseOptions::default()
    };
    let e = parse(text, &opts).unwrap_err();
    assert_eq!((e.line, e.kind), (2, GcodeErrorKind::InvalidValue));
    assert!(e.to_string().contains("o7 while"), "{e}");
    // With the default limit too (the limit, not a clock, ends it).
    let e = parse(text, &ParseOptions::default()).unwrap_err();
    assert!(e.to_string().contains("the loop o7 while (line 2)"), "{e}");
}

#[test]
fn structure_errors_name_the_statements() {
    let e = parse("o1 while [1]\no2 endwhile\n", &ParseOptions::default()).unwrap_err();
    assert!(
        e.to_string().contains("does not close o1 while (line 1)"),
        "{e}"
    );
    let e = parse("o1 if [1]\nG0 X0 Y0 Z0\n", &ParseOptions::default()).unwrap_err();
    assert!(e.to_string().contains("never closed"), "{e}");
    let e = parse("o<x> call\n", &ParseOptions::default()).unwrap_err();
    assert_eq!(e.kind, GcodeErrorKind::Unsupported);
    assert!(e.to_string().contains("in this file"), "{e}");
}

#[test]
fn a_syntax_error_on_an_opening_or_closing_line_is_reported_at_that_line() {
    // The opener cannot be read: the error is its own (line 1), not "endif without its
    // opening statement" at the closer (line 3).
    for (text, col) in [
        ("G0 X0 Y0 Z0\no1 if [1e3 GT 2]\nG0 X1\no1 endif\nM2\n", 9),
        (
            "G0 X0 Y0 Z0\no1 while [0] junk\nG0 X1\no1 endwhile\nM2\n",
            14,
        ),
        ("G0 X0 Y0 Z0\no100 sub X5\nG0 X1\no100 endsub\nM2\n", 6),
        (
            "G0 X0 Y0 Z0\nN10 o1 if [1e3 GT 2]\nG0 X1\no1 endif\nM2\n",
            13,
        ),
    ] {
        let e = parse(text, &ParseOptions::default()).unwrap_err();
        assert_eq!((e.line, e.column), (2, col), "{text:?}: {e}");
        assert!(!e.to_string().contains("opening statement"), "{e}");
    }
    // The closer cannot be read: reported at the closer, not "never closed" at the opener.
    let e = parse(
        "o1 if [1]\nG0 X0 Y0 Z0\no1 endif junk\nM2\n",
        &ParseOptions::default(),
    )
    .unwrap_err();
    assert_eq!(e.line, 3, "{e}");
    assert!(!e.to_string().contains("never closed"), "{e}");
}

#[test]
fn m_codes_s_and_t_are_events_and_comments_are_messages() {
    let p = ok("G0 X0 Y0 Z0 S1000 M3\n(MSG, hello)\n#<d> = 2\n(DEBUG, d=#<d> one=#1)\nM62 P1\nG1 X1\nM66 P0 L0 E1 Q2\nM67 E0 Q50\nT2 M6\nM30\n");
    let codes: Vec<(&str, usize, usize)> = p
        .events
        .iter()
        .map(|e| (e.code.as_str(), e.line, e.after_moves))
        .collect();
    assert_eq!(
        codes,
        [
            ("S", 1, 0),
            ("M3", 1, 0),
            ("M62", 5, 0),
            ("M66", 7, 1),
            ("M67", 8, 1),
            ("T", 9, 1),
            ("M6", 9, 1),
            ("M30", 10, 1)
        ]
    );
    assert_eq!(
        p.events[3].words,
        [('P', 0.0), ('E', 1.0), ('L', 0.0), ('Q', 2.0)]
    );
    let m: Vec<(&str, &str)> = p
        .messages
        .iter()
        .map(|m| (m.kind, m.text.as_str()))
        .collect();
    assert_eq!(m, [("MSG", "hello"), ("DEBUG", "d=2.000000 one=0.000000")]);
}

#[test]
fn the_first_move_starts_from_the_tool_position_when_given() {
    let start = Vector3::new(0.5, 0.1, 0.3);
    let opts = ParseOptions {
        start: Some(start),
        ..ParseOptions::default()
    };
    let p = parse("G21 G90\nG0 Z5\nG1 X10 Y10\n", &opts).unwrap();
    assert_eq!((p.start, p.start_line), (start, 2));
    let e = ends(&p);
    assert!(
        close(&e, &[[500.0, 100.0, 5.0], [10.0, 10.0, 5.0]]),
        "{e:?}"
    );
    // A first move with X, Y and Z still sets the start (as without the option).
    let p = parse("G0 X1 Y2 Z3\nG1 X4\n", &opts).unwrap();
    assert_eq!(p, ok("G0 X1 Y2 Z3\nG1 X4\n"));
}

#[test]
fn invisible_characters_are_shown_escaped() {
    let e = parse("G0 X0 Y0 Z0\nG1\u{200b} X1\n", &ParseOptions::default()).unwrap_err();
    let shown = e.to_string();
    assert!(
        shown.contains("\\u{200b}") && shown.contains("invisible"),
        "{shown}"
    );
    assert!(!shown.contains('\u{200b}'), "{shown}");
}
