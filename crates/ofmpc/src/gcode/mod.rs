//! G-code reader: program text → start point and a list of moves in the robot base frame (SI).
//!
//! # Language
//!
//! A line holds words, a letter followed by a number (`G1`, `X-12.5`, `x.5`); letters are
//! case-insensitive and spaces are optional (`G1X10Y0`) and allowed between letter and number.
//! Comments run in parentheses `( … )` or from `;` to the end of the line. A line holding only
//! `%` delimits the program: the first opens it, a later one ends it. `N` labels must be the
//! first word; they are labels, not keys (repeats allowed). Each letter may appear once per
//! line, except `G` and `M` (one code per modal group).
//!
//! | word | meaning |
//! |---|---|
//! | `G00` | linear move at the path speed limit; a *planned* straight line like `G01` (not an uncoordinated rapid); ignores `F` |
//! | `G01` | linear move, at the modal feed `F` if one was given, else at the speed limit |
//! | `G02` / `G03` | clockwise / counter-clockwise arc (seen from the positive plane normal), centre by `I J K` offsets from the start point, or by `R` (`R < 0`: the long way, more than 180°); a move along the plane normal makes a helix; end = start with `I J K` is a full circle; an arc line without `X Y Z` is a full circle |
//! | `G04 P…` / `G04 X…` | dwell, in seconds (both `P` and `X` are seconds) |
//! | `G10 L2 Pn X Y Z R` | set the work offset of `G54 … G59` (`n = 1 … 6`) in the current units; always absolute; omitted axes keep their value; `R`: the system's rotation about Z in degrees (machine = Rz(R)·(program + G92) + offset, LinuxCNC's order; see `frames.rs`) |
//! | `G17` `G18` `G19` | arc plane XY (default), ZX, YZ |
//! | `G20` / `G21` | inch / millimetre (default) |
//! | `G54 … G59` | select a work offset (default `G54`); base-frame point = program point + offset |
//! | `G90` / `G91` | absolute (default) / incremental coordinates |
//! | `G91.1` | arc centres relative to the start point (the default and only mode) |
//! | `G40` `G80` `G94` | cancel / default modes: accepted, no effect |
//! | `G43 H…` `G43.1 Z…` `G49` | tool length offset: the points are the tip's; a change of length moves the current point along [`ParseOptions::tool_axis`] (LinuxCNC); the planner extends the TCP ([`crate::motion::plan_program`]) |
//! | `G61` `G61.1` | exact stop: every move runs rest to rest (the paper's septic law) |
//! | `G64 P…` / `G64` | blending: corners are rounded within `P` (program units) or the planner's default tolerance, the path does not stop at corners it can blend; see [`crate::motion`] |
//! | `F` | feed (mm/min or in/min, in the units active at each move): under `G61` the peak path speed of `G01 G02 G03` moves, under `G64` their cruise speed |
//! | `M02` `M30` | end of program; anything after it is ignored (with a warning) |
//! | other `M`, `S`, `T`, `O` | warning, no effect on the path |
//!
//! Modal motion: a line with only coordinates repeats the last `G00 … G03`.
//!
//! The first motion defines the start point, where the robot rests: it must be `G00`/`G01` in
//! absolute mode with all of `X`, `Y`, `Z`, and it produces no move.
//!
//! # Arcs
//!
//! Offsets use the plane's letters (`G17`: `I J`, `G18`: `K I`, `G19`: `J K`); the offset
//! along the plane normal must be 0 or absent. The start and end radii must agree within
//! `arc_tolerance` (0.002 mm in `G21`, 0.0002 in in `G20`, LinuxCNC's absolute tolerances;
//! no relative slack): beyond that the program is wrong and the reader says so, and if the
//! offsets would fit another plane it names it (the paper's Table I program has `G19` but
//! XY-plane offsets). Within the tolerance the arc keeps the start radius and ends on its
//! circle at the programmed end's angle; the next move starts exactly there (a shift of more
//! than 1 nm is reported as a warning).
//!
//! # Errors
//!
//! Anything the reader cannot honour is a [`GcodeError`] with the line and column (1-based),
//! the offending text and a hint. Harmless things are [`GcodeWarning`]s.
//!
//! The reader is written by hand: the `gcode` crate (0.6) stores values as `f32`, reports byte
//! spans and, by design, skips over malformed input, and it has no modal semantics.

mod arcs;
mod codes;
mod expr;
mod fanuc;
mod flow;
mod frames;
mod interpreter;
mod lexer;
mod modal;
mod predefined;
mod program;
mod text;
mod tools;

pub(crate) use flow::DEFAULT_MAX_STEPS;
use flow::{Runner, SourceLine};
use interpreter::Interpreter;
#[doc(hidden)]
pub use interpreter::{MAX_EVENTS, MAX_MESSAGE_BYTES, MAX_MOVES};
use lexer::lex_line;
pub use program::{
    GcodeError, GcodeErrorKind, GcodeWarning, Move, MoveKind, ParseOptions, PathMode, Program,
    ProgramEvent, ProgramMessage,
};
pub use tools::{ToolTable, ToolTableError};

/// The paper's Table I test program (section IV), corrected to `G17` and placed with a work
/// offset; see the comments in the file `examples/paper-table1.gcode` (the crate embeds its
/// byte-identical copy `crates/ofmpc/data/paper-table1.gcode`, so that the packaged crate is
/// self-contained).
pub const PAPER_TABLE1: &str = include_str!("../../data/paper-table1.gcode");

/// Parse a program text. See the module documentation for the language.
pub fn parse(text: &str, options: &ParseOptions) -> Result<Program, GcodeError> {
    let mut it = Interpreter::new(options)?;
    // A UTF-8 byte-order mark (Windows editors write one) is not part of the program.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let raw: Vec<&str> = lines(text).collect();
    // Read up to the closing `%` (a `%` after content); what follows is ignored text.
    let mut source = Vec::with_capacity(raw.len());
    let mut content = false;
    for (i, r) in raw.iter().enumerate() {
        let lexed = lex_line(r, i + 1);
        let percent = matches!(lexed, Ok(lexer::Lexed::Percent));
        let empty = matches!(&lexed, Ok(lexer::Lexed::Block(b)) if b.is_empty() && !b.delete);
        source.push(SourceLine {
            no: i + 1,
            raw: r,
            lexed,
        });
        if percent && content {
            break;
        }
        content |= !percent && !empty;
    }
    let mut runner = Runner::new(&source)?;
    let next = runner.run(&mut it, options.max_steps.unwrap_or(DEFAULT_MAX_STEPS))?;
    for (i, r) in raw.iter().enumerate().skip(next) {
        it.note_ignored(i + 1, r);
    }
    it.finish()
}

/// The lines of `text`, ended by `\n`, `\r\n` or a lone `\r` (old Mac, some controllers),
/// without their terminators. Carriage returns right before a `\n` belong to that line end:
/// `\r\r\n` (a CRLF file converted to CRLF again) ends one line, as vim, `wc -l`, GitHub and
/// LinuxCNC's reader count it (VS Code counts `\r` and `\r\n` apart, two lines); a `\r`
/// followed by anything else ends a line.
fn lines(text: &str) -> impl Iterator<Item = &str> {
    let mut rest = Some(text);
    std::iter::from_fn(move || {
        let t = rest?;
        match t.find(['\n', '\r']) {
            Some(i) => {
                let crs = t[i..].bytes().take_while(|&b| b == b'\r').count();
                let skip = if t[i + crs..].starts_with('\n') {
                    crs + 1
                } else {
                    1
                };
                rest = Some(&t[i + skip..]).filter(|r| !r.is_empty());
                Some(&t[..i])
            }
            None => {
                rest = None;
                (!t.is_empty()).then_some(t)
            }
        }
    })
}
