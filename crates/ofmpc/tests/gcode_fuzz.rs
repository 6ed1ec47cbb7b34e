//! The reader never panics: random bytes, token soup from the G-code alphabet, and mutations of
//! the paper's program either parse or give a positioned error. Whatever parses also times
//! into a trajectory with finite samples, and every error points into the text.

use ofmpc::gcode::{parse, ParseOptions, PAPER_TABLE1};
use ofmpc::motion::{CartesianTrajectory, TimingOptions};
use proptest::prelude::*;

/// Parse; on success time and sample it; on failure check that the position is in the text.
fn exercise(text: &str) {
    match parse(text, &ParseOptions::default()) {
        Ok(program) => {
            assert!(program.start.iter().all(|x| x.is_finite()));
            let tr = CartesianTrajectory::new(&program, &TimingOptions::default())
                .expect("default options are valid");
            assert!(tr.duration().is_finite() && tr.duration() >= 0.0);
            for i in 0..=16 {
                let s = tr.sample(tr.duration() * (i as f64 / 16.0));
                assert!(s.position.iter().all(|x| x.is_finite()), "{text:?}");
                assert!(s.velocity.iter().all(|x| x.is_finite()));
                assert!(s.acceleration.iter().all(|x| x.is_finite()));
            }
        }
        Err(e) => {
            // Lines end at \n (with any carriage returns before it) or a lone \r (the reader's
            // rule).
            let unix = crlf_runs_to_lf(text);
            let lines: Vec<&str> = unix.split(['\n', '\r']).collect();
            if e.line > 0 {
                let line = lines.get(e.line - 1).expect("error line inside the text");
                assert!(
                    e.column >= 1 && e.column <= line.chars().count().max(1),
                    "column {} outside line {:?}",
                    e.column,
                    line
                );
            }
            assert!(!e.to_string().is_empty() && !e.hint.is_empty());
        }
    }
}

const TOKENS: &[&str] = &[
    "G0", "G00", "G1", "G01", "G2", "G02", "G3", "G03", "G4", "G04", "G10", "L2", "P1", "P7",
    "G17", "G18", "G19", "G20", "G21", "G54", "G55", "G59", "G90", "G91", "G91.1", "G64", "M2",
    "M30", "M3", "M98", "N10", "N010", "F100", "F0", "F-5", "S1000", "T1", "X", "Y", "Z", "I", "J",
    "K", "R", "X0", "Y0", "Z0", "X10", "Y-10", "Z400", "I-200", "J200", "K0", "R10", "R-10", "R0",
    "X630", "Y-200", "X1.5", "Y.5", "Z-0.", "I5", "J-5", "P0.5", "%", "(", ")", "(c)", ";", "#",
    "[", "/", "*", " ", " ", "\n", "\n", "\r\n", "\t", "1", ".", "-", "O",
];

fn token_soup() -> impl Strategy<Value = String> {
    prop::collection::vec(prop::sample::select(TOKENS), 0..80).prop_map(|t| t.concat())
}

/// A program that always starts from a valid point, followed by random soup: the reader gets
/// past the start and into the motion and arc code.
fn soup_after_start() -> impl Strategy<Value = String> {
    token_soup().prop_map(|s| format!("G0 X0 Y0 Z0\n{s}"))
}

#[derive(Debug, Clone)]
enum Edit {
    Delete(usize),
    Insert(usize, char),
    Replace(usize, char),
    SwapLines(usize, usize),
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    let alphabet = prop::sample::select(
        "GMNXYZIJKRFPLST0123456789.-+ ()%;#\nOo\u{b5}"
            .chars()
            .collect::<Vec<_>>(),
    );
    let edit = prop_oneof![
        any::<usize>().prop_map(Edit::Delete),
        (any::<usize>(), alphabet.clone()).prop_map(|(i, c)| Edit::Insert(i, c)),
        (any::<usize>(), alphabet).prop_map(|(i, c)| Edit::Replace(i, c)),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::SwapLines(a, b)),
    ];
    prop::collection::vec(edit, 1..8)
}

fn mutate(base: &str, edits: &[Edit]) -> String {
    let mut chars: Vec<char> = base.chars().collect();
    for e in edits {
        let n = chars.len().max(1);
        match *e {
            Edit::Delete(i) => {
                if !chars.is_empty() {
                    chars.remove(i % n);
                }
            }
            Edit::Insert(i, c) => chars.insert(i % (chars.len() + 1), c),
            Edit::Replace(i, c) => {
                if let Some(x) = chars.get_mut(i % n) {
                    *x = c;
                }
            }
            Edit::SwapLines(a, b) => {
                let text: String = chars.iter().collect();
                let mut lines: Vec<&str> = text.lines().collect();
                if !lines.is_empty() {
                    let (a, b) = (a % lines.len(), b % lines.len());
                    lines.swap(a, b);
                }
                chars = lines.join("\n").chars().collect();
            }
        }
    }
    chars.into_iter().collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        exercise(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn token_soup_never_panics(text in token_soup()) {
        exercise(&text);
    }

    #[test]
    fn token_soup_after_a_start_never_panics(text in soup_after_start()) {
        exercise(&text);
    }

    #[test]
    fn mutated_paper_program_never_panics(e in edits()) {
        exercise(&mutate(PAPER_TABLE1, &e));
    }

    #[test]
    fn mutated_g19_paper_program_never_panics(e in edits()) {
        exercise(&mutate(&PAPER_TABLE1.replace("N010 G17", "N010 G19"), &e));
    }
}

/// `text` with every run of carriage returns followed by a line feed replaced by the line feed.
fn crlf_runs_to_lf(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut pending = 0;
    for c in text.chars() {
        match c {
            '\r' => pending += 1,
            '\n' => {
                pending = 0;
                out.push('\n');
            }
            _ => {
                out.extend(std::iter::repeat_n('\r', pending));
                pending = 0;
                out.push(c);
            }
        }
    }
    out.extend(std::iter::repeat_n('\r', pending));
    out
}
