//! Fanuc-style numbered subprograms (M98/M99) as LinuxCNC 2.9 reads them (issue #20): end
//! points worked out by hand from LinuxCNC's manual ("Fanuc-Style Numbered Programs") and
//! its interpreter's rules (interp_read.cc read_o, interp_o_word.cc execute_call).

mod common;

use common::gcode::{assert_ends, fail, ok};
use ofmpc::gcode::{parse, ParseOptions};

#[test]
fn m98_calls_the_numbered_subprogram_l_times() {
    let p = ok(
        "G21 G90 G0 X0 Y0 Z5\nM98 P100 L3\nM30\n\nO100 (drill step)\nG91 G1 X10 F600\nG90\nM99\n",
    );
    assert_ends(&p, &[[10.0, 0.0, 5.0], [20.0, 0.0, 5.0], [30.0, 0.0, 5.0]]);
    // Without L: once; L0: not at all; P may be an expression.
    let p = ok("G0 X0 Y0 Z0\nM98 P[50 * 2]\nM98 P100 L0\nM30\nO100\nG91 G1 Y1 F60\nM99\n");
    assert_ends(&p, &[[0.0, 1.0, 0.0]]);
}

#[test]
fn incremental_cycles_repeated_by_m98_keep_the_initial_level() {
    // LinuxCNC (convert_cycle_xy): in G91, R is relative to the initial level of the first
    // cycle line (cycle_il), which later cycle lines keep: R stays at 0.25 + 0.25.
    let p = ok("G21 G90 G0 X0 Y0 Z0.25\nM98 P1 L3\nM30\nO1\nG91 G99 G81 X1 Z-1 R0.25 F60\nM99\n");
    let mut want = vec![[0.0, 0.0, 0.5]];
    for x in [1.0, 2.0, 3.0] {
        want.extend([[x, 0.0, 0.5], [x, 0.0, -0.5], [x, 0.0, 0.5]]);
    }
    assert_ends(&p, &want);
}

#[test]
fn parameters_1_to_30_are_global_in_numbered_subprograms() {
    // M98 passes and restores nothing: the subprogram's #1 stays (an `o… call` restores it).
    let p = ok(
        "G0 X0 Y0 Z0\n#1 = 1\nM98 P7\nG1 X[#1] F60\no8 call\nG1 Y[#1]\nM30\n\
                O7\n#1 = [#1 + 4]\nM99\no8 sub\n#1 = 100\no8 endsub\n",
    );
    assert_ends(&p, &[[5.0, 0.0, 0.0], [5.0, 5.0, 0.0]]);
}

#[test]
fn the_first_subprogram_after_the_call_runs_and_calls_nest() {
    // O0002 and O2 are both number 2: the first one after the call is called.
    let p = ok("G0 X0 Y0 Z0\nM98 P0002\nM30\nO0002\nG1 X1 F60\nM99\nO2\nG1 X99\nM99\n");
    assert_ends(&p, &[[1.0, 0.0, 0.0]]);
    // O2 runs twice, calling O1 three times each: #1 counts 6.
    let p = ok("G0 X0 Y0 Z0\n#1 = 0\nM98 P2 L2\nG1 X[#1] F60\nM30\n\
                O2\nM98 P1 L3\nM99\nO1\n#1 = [#1 + 1]\nM99\n");
    assert_ends(&p, &[[6.0, 0.0, 0.0]]);
}

#[test]
fn m99_in_the_main_program_ends_it_with_a_warning() {
    let p = ok("G0 X0 Y0 Z0\nG1 X1 F60\nM99\nG1 X2\n");
    assert_ends(&p, &[[1.0, 0.0, 0.0]]);
    assert!(p
        .warnings
        .iter()
        .any(|w| w.line == 3 && w.message.contains("M99 in the main program")));
}

#[test]
fn wrong_uses_are_refused_with_their_cause() {
    let cases = [
        ("G0 X0 Y0 Z0\nM98\nM30\nO1\nM99\n", 2, "M98 without P"),
        ("G0 X0 Y0 Z0\nM98 P9\nM30\n", 2, "no subprogram O9"),
        ("G0 X0 Y0 Z0\nM98 P1.5\nM30\n", 2, "whole number"),
        (
            "G0 X0 Y0 Z0\nM98 P1\nM30\no1 sub\no1 endsub\n",
            2,
            "o1 call",
        ),
        ("G0 X0 Y0 Z0\no1 call\nM30\nO1\nM99\n", 2, "M98 P1"),
        (
            "G0 X0 Y0 Z0\no1 call\nM30\no1 sub\nM99\no1 endsub\n",
            5,
            "M99 inside an O-word subroutine",
        ),
        (
            "G0 X0 Y0 Z0\nM98 P1\nM30\no5 sub\nO1\nG1 X1 F60\no5 endsub\n",
            7,
            "with M99",
        ),
        (
            "G0 X0 Y0 Z0\nG1 X1 M98 P1\nM30\nO1\nM99\n",
            2,
            "on a line of its own",
        ),
    ];
    for (text, line, want) in cases {
        let e = fail(text);
        assert_eq!(e.line, line, "{e}\n{text}");
        assert!(e.to_string().contains(want), "{e}\n{text}");
    }
    // A subprogram that precedes its call is not found (LinuxCNC looks after the call).
    let e = fail("G0 X0 Y0 Z0\no1 if [0]\nO5\nM99\no1 endif\nM98 P5\nM30\n");
    assert!(e.to_string().contains("comes before the call"), "{e}");
}

#[test]
fn endless_repeats_end_at_the_step_limit() {
    let options = ParseOptions {
        max_steps: Some(10_000),
        ..ParseOptions::default()
    };
    let e = parse(
        "G0 X0 Y0 Z0\nM98 P1 L1000000000\nM30\nO1\nG91 G1 X0.001 F60\nM99\n",
        &options,
    )
    .unwrap_err();
    assert!(e.to_string().contains("does not end"), "{e}");
}
