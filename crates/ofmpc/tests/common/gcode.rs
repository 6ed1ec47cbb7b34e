//! The G-code tests' helpers: read a program that must read, or must be refused, and
//! compare the end points of its path moves.

use ofmpc::gcode::{parse, GcodeError, MoveKind, ParseOptions, Program};

/// Reads `text` with the default options; panics with the error and the program otherwise.
pub fn ok(text: &str) -> Program {
    parse(text, &ParseOptions::default())
        .unwrap_or_else(|e| panic!("unexpected error: {e}\n{text}"))
}

/// The error reading `text` gives; panics when it reads.
pub fn fail(text: &str) -> GcodeError {
    match parse(text, &ParseOptions::default()) {
        Ok(p) => panic!("expected an error, got {p:?}\n{text}"),
        Err(e) => e,
    }
}

/// End points of the path moves (dwells left out), in mm.
pub fn ends(p: &Program) -> Vec<[f64; 3]> {
    p.moves
        .iter()
        .filter_map(|m| match &m.kind {
            MoveKind::Path { segment, .. } => {
                let e = segment.end() * 1e3;
                Some([e.x, e.y, e.z])
            }
            MoveKind::Dwell { .. } => None,
        })
        .collect()
}

/// Whether two lists of points are the same to 1e-9 mm.
pub fn close(a: &[[f64; 3]], b: &[[f64; 3]]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(p, q)| (0..3).all(|k| (p[k] - q[k]).abs() < 1e-9))
}

/// Asserts that the path's end points are `want` (mm, to 1e-9).
pub fn assert_ends(p: &Program, want: &[[f64; 3]]) {
    let got = ends(p);
    assert!(close(&got, want), "got {got:?}\nwant {want:?}");
}
