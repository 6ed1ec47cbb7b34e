//! A program's output has a budget as well as its lines (issue #36): moves, events and
//! message bytes are counted as the program grows, and a program past one is refused with
//! an error naming the limit and the line, quickly (no abort on memory).

use ofmpc::gcode::{parse, ParseOptions, MAX_EVENTS, MAX_MESSAGE_BYTES, MAX_MOVES};

fn refused(text: &str) -> String {
    parse(text, &ParseOptions::default())
        .unwrap_err()
        .to_string()
}

#[test]
fn peck_cycles_with_a_tiny_q_stop_at_the_move_budget() {
    for code in ["G83", "G73"] {
        let e = refused(&format!(
            "G21 G90 G0 X0 Y0 Z10\n{code} X0 Y0 Z-100000 R1 Q0.0001 F100\nM30\n"
        ));
        assert!(
            e.contains(&format!(
                "more than {MAX_MOVES} moves (the limit) by line 2"
            )),
            "{code}: {e}"
        );
    }
}

#[test]
fn a_repeated_cycle_under_g91_stops_at_the_move_budget() {
    let e = refused("G21 G0 X0 Y0 Z10\nG91\nG81 X0.001 Y0 Z-1 R1 L1000000 F100\nM30\n");
    assert!(e.contains("moves (the limit) by line 3"), "{e}");
}

#[test]
fn loops_that_store_messages_or_events_stop_at_their_budgets() {
    let long = "x".repeat(20_000);
    let e = refused(&format!(
        "G21 G0 X0 Y0 Z0\n#1=0\no1 while [#1 LT 2000000]\n(PRINT,{long})\n#1=[#1+1]\no1 endwhile\nM30\n"
    ));
    assert!(
        e.contains(&format!(
            "more than {} MB of messages",
            MAX_MESSAGE_BYTES >> 20
        )),
        "{e}"
    );
    assert!(
        e.len() < 1000,
        "the error quotes little of the line: {} bytes",
        e.len()
    );
    let e = refused(
        "G21 G0 X0 Y0 Z0\n#1=0\no1 while [#1 LT 2000000]\nM3 S1000\n#1=[#1+1]\no1 endwhile\nM30\n",
    );
    assert!(e.contains(&format!("more than {MAX_EVENTS} events")), "{e}");
}

#[test]
fn the_repeat_cap_and_the_step_limit_say_what_they_are() {
    let e = refused("G21 G0 X0 Y0 Z10\nG81 X0 Y0 Z-1 R1 L999999999 F100\nM30\n");
    assert!(e.contains("from 0 to 1000000 (the limit)"), "{e}");
    let options = ParseOptions {
        max_steps: Some(1000),
        ..ParseOptions::default()
    };
    let e = parse(
        "G21 G0 X0 Y0 Z0\n#1=0\no1 while [#1 LT 3000]\n#1=[#1+1]\no1 endwhile\nM30\n",
        &options,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("the limit on executed lines") && e.contains("or repeats more than that"),
        "{e}"
    );
}

/// LinuxCNC's canned-cycle checks (issue #36): R below the hole's bottom is refused ("R less
/// than Z in cycle"), as is a negative dwell P on G82/G89 (as G4 P-1).
#[test]
fn canned_cycles_refuse_r_below_the_bottom_and_a_negative_dwell() {
    let e = refused("G21 G90 G0 X0 Y0 Z20\nG81 X0 Y0 Z5 R-5 F100\nM30\n");
    assert!(e.contains("R is below the hole's bottom"), "{e}");
    for code in ["G82", "G89"] {
        let e = refused(&format!(
            "G21 G90 G0 X0 Y0 Z20\n{code} X0 Y0 Z-5 R2 P-1 F100\nM30\n"
        ));
        assert!(e.contains("negative dwell time P"), "{code}: {e}");
    }
    // R above the bottom, P ≥ 0: accepted.
    let p = parse(
        "G21 G90 G0 X0 Y0 Z20\nG89 X0 Y0 Z-5 R2 P0.5 F100\nM30\n",
        &ParseOptions::default(),
    )
    .unwrap();
    assert!(!p.moves.is_empty());
}

/// With a tool table, `T1 M6` chooses the length `G43` takes: no "ignored" warning for T or
/// M6 (issue #36); without one they still have no effect and are warned.
#[test]
fn t_and_m6_are_not_called_ignored_when_a_tool_table_gives_their_length() {
    let text = "T1 M6\nG21 G0 X0 Y0 Z0\nG43\nG1 Z1 F100\nM30\n";
    let options = ParseOptions {
        tool_table: Some(ofmpc::gcode::ToolTable::parse("T1 P1 Z10\n").unwrap()),
        ..ParseOptions::default()
    };
    let p = parse(text, &options).unwrap();
    assert!((p.tool_length - 0.01).abs() < 1e-15);
    assert!(
        p.warnings.iter().all(|w| !w.message.contains("ignored")),
        "{:?}",
        p.warnings
    );
    let p = parse("T1 M6\nG21 G0 X0 Y0 Z0\nM30\n", &ParseOptions::default()).unwrap();
    assert!(p
        .warnings
        .iter()
        .any(|w| w.message.contains("T1 (tool) ignored")));
}
