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
//! | `G10 L2 Pn X Y Z` | set the work offset of `G54 … G59` (`n = 1 … 6`) in the current units; always absolute; omitted axes keep their value |
//! | `G17` `G18` `G19` | arc plane XY (default), ZX, YZ |
//! | `G20` / `G21` | inch / millimetre (default) |
//! | `G54 … G59` | select a work offset (default `G54`); base-frame point = program point + offset |
//! | `G90` / `G91` | absolute (default) / incremental coordinates |
//! | `G91.1` | arc centres relative to the start point (the default and only mode) |
//! | `G40` `G49` `G80` `G94` | cancel / default modes: accepted, no effect |
//! | `G61` `G61.1` `G64` | blending modes: warning, every segment runs rest to rest anyway |
//! | `F` | feed (mm/min or in/min, in the units active at each move), the peak path speed of `G01 G02 G03` moves |
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
//! [`arc_tolerance`] (0.002 mm in `G21`, 0.0002 in in `G20`, LinuxCNC's absolute tolerances;
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

use crate::path::{ArcDirection, ArcError, Plane, Segment, CLOSED_ARC_TOLERANCE};
use nalgebra::Vector3;
use std::fmt;

/// The paper's Table I test program (section IV), corrected to `G17` and placed with a work
/// offset; see the comments in the file `examples/paper-table1.gcode`.
pub const PAPER_TABLE1: &str = include_str!("../../../examples/paper-table1.gcode");

/// Largest magnitude accepted for any number in a program.
pub const MAX_WORD_VALUE: f64 = 1e9;

/// Moves shorter than this (m) are skipped with a warning.
pub const MIN_MOVE_LENGTH: f64 = 1e-12;

/// Options of [`parse`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParseOptions {
    /// Initial `G54` work offset (m, base frame), used when the program does not set the G54
    /// offset itself with `G10 L2 P1`. `None`: zero.
    pub origin: Option<[f64; 3]>,
}

/// A parsed program: where the robot starts and what it does from there.
#[derive(Debug, Clone, PartialEq)]
pub struct Program {
    /// Start point (m, base frame): the target of the first motion; the robot rests there.
    pub start: Vector3<f64>,
    /// Source line (1-based) of the first motion.
    pub start_line: usize,
    /// Moves after the start point, in program order.
    pub moves: Vec<Move>,
    /// Harmless things the reader ignored.
    pub warnings: Vec<GcodeWarning>,
}

impl Program {
    /// Point where the program ends (the start point if it has no path moves).
    pub fn end(&self) -> Vector3<f64> {
        self.moves
            .iter()
            .rev()
            .find_map(|m| match &m.kind {
                MoveKind::Path { segment, .. } => Some(segment.end()),
                MoveKind::Dwell { .. } => None,
            })
            .unwrap_or(self.start)
    }
}

/// One move of a program.
#[derive(Debug, Clone, PartialEq)]
pub struct Move {
    /// Source line (1-based) of the block that commanded the move.
    pub line: usize,
    /// What the move does.
    pub kind: MoveKind,
}

/// The kinds of move.
#[derive(Debug, Clone, PartialEq)]
pub enum MoveKind {
    /// Travel along a path segment (base frame, m).
    Path {
        /// The geometry.
        segment: Segment,
        /// Peak path speed from the `F` word (m/s); `None` for `G00` and when no `F` was given
        /// (then the trajectory's speed limit applies).
        feed: Option<f64>,
    },
    /// Hold the position.
    Dwell {
        /// Duration (s), > 0.
        seconds: f64,
    },
}

/// A harmless thing the reader ignored.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GcodeWarning {
    /// Line (1-based).
    pub line: usize,
    /// Column (1-based, in characters).
    pub column: usize,
    /// What was ignored and why.
    pub message: String,
}

impl fmt::Display for GcodeWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "line {}, column {}: {}",
            self.line, self.column, self.message
        )
    }
}

/// Category of a [`GcodeError`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum GcodeErrorKind {
    /// Malformed text: unexpected character, missing or unparsable number, unclosed comment.
    Syntax,
    /// A G or M code that is not part of the language.
    UnknownCode,
    /// A known word or feature that this reader does not support.
    Unsupported,
    /// A letter given twice on one line, or two codes of one modal group.
    Duplicate,
    /// Words that do not go together or are not used by the line's command.
    Conflict,
    /// A command lacks a word it needs.
    Missing,
    /// A number outside its allowed range.
    InvalidValue,
    /// The first motion does not define a start point.
    StartPoint,
    /// Inconsistent arc geometry.
    Arc,
    /// The program contains no motion.
    NoMotion,
    /// Invalid [`ParseOptions`].
    InvalidOption,
}

/// An error in a program, with its position and a hint how to fix it.
///
/// `line == 0` means the error concerns the whole program or the options.
#[derive(Debug, Clone, PartialEq)]
pub struct GcodeError {
    /// Line (1-based).
    pub line: usize,
    /// Column (1-based, in characters).
    pub column: usize,
    /// Category.
    pub kind: GcodeErrorKind,
    /// The offending text (a word or the line).
    pub text: String,
    /// What is wrong.
    pub message: String,
    /// What to do.
    pub hint: String,
}

impl fmt::Display for GcodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "line {}, column {}: ", self.line, self.column)?;
        }
        write!(f, "{}", self.message)?;
        if !self.text.is_empty() {
            write!(f, " in `{}`", self.text)?;
        }
        if !self.hint.is_empty() {
            write!(f, " ({})", self.hint)?;
        }
        Ok(())
    }
}

impl std::error::Error for GcodeError {}

/// Radius tolerance of arcs (m): 0.002 mm for `G21`, 0.0002 in for `G20`.
pub fn arc_tolerance(inch: bool) -> f64 {
    if inch {
        0.0002 * 0.0254
    } else {
        0.002e-3
    }
}

/// Parse a program text. See the module documentation for the language.
pub fn parse(text: &str, options: &ParseOptions) -> Result<Program, GcodeError> {
    let mut it = Interpreter::new(options)?;
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        if it.ended {
            it.note_ignored(line_no, raw);
            continue;
        }
        match lex_line(raw, line_no)? {
            Lexed::Percent => {
                if it.seen_content {
                    it.ended = true;
                } else {
                    it.seen_content = true;
                }
            }
            Lexed::Words(words) if words.is_empty() => {}
            Lexed::Words(words) => {
                it.seen_content = true;
                it.line(line_no, raw, &words)?;
            }
        }
    }
    it.finish()
}

// ---------------------------------------------------------------------------------------------
// Lexer

/// One word of a line: an upper-case letter and its value.
#[derive(Debug, Clone)]
struct Word<'a> {
    letter: char,
    value: f64,
    /// 1-based column of the letter.
    col: usize,
    /// Source text of the word.
    text: &'a str,
}

enum Lexed<'a> {
    Percent,
    Words(Vec<Word<'a>>),
}

fn err(
    line: usize,
    column: usize,
    kind: GcodeErrorKind,
    text: &str,
    message: impl Into<String>,
    hint: impl Into<String>,
) -> GcodeError {
    GcodeError {
        line,
        column,
        kind,
        text: text.to_string(),
        message: message.into(),
        hint: hint.into(),
    }
}

fn lex_line(raw: &str, line: usize) -> Result<Lexed<'_>, GcodeError> {
    use GcodeErrorKind::Syntax;
    let chars: Vec<(usize, char)> = raw.char_indices().collect();
    let byte_at = |i: usize| chars.get(i).map_or(raw.len(), |&(b, _)| b);
    let mut words = Vec::new();
    let mut i = 0;
    let mut first_content = true;
    while let Some(&(_, c)) = chars.get(i) {
        let col = i + 1;
        if c == ' ' || c == '\t' || c == '\r' {
            i += 1;
            continue;
        }
        if c == '%' {
            if first_content {
                return Ok(Lexed::Percent);
            }
            return Err(err(
                line,
                col,
                Syntax,
                "%",
                "`%` inside a line",
                "`%` delimits the program and must stand alone on its line",
            ));
        }
        first_content = false;
        if c == ';' {
            break;
        }
        if c == '(' {
            match chars.iter().skip(i + 1).position(|&(_, ch)| ch == ')') {
                Some(k) => {
                    i += k + 2;
                    continue;
                }
                None => {
                    return Err(err(
                        line,
                        col,
                        Syntax,
                        &raw[byte_at(i)..],
                        "unclosed comment",
                        "close the comment with `)` on the same line",
                    ))
                }
            }
        }
        if c.is_ascii_alphabetic() {
            let letter = c.to_ascii_uppercase();
            let mut j = i + 1;
            while matches!(chars.get(j), Some(&(_, ' ' | '\t'))) {
                j += 1;
            }
            let num_start = j;
            if matches!(chars.get(j), Some(&(_, '+' | '-'))) {
                j += 1;
            }
            let digits_start = j;
            while matches!(chars.get(j), Some(&(_, ch)) if ch.is_ascii_digit() || ch == '.') {
                j += 1;
            }
            let text = &raw[byte_at(i)..byte_at(j)];
            if j == digits_start {
                let next = chars.get(j).map(|&(_, ch)| ch);
                let hint = if matches!(next, Some('O' | 'o')) {
                    format!("the letter O where the digit 0 was meant? write {letter}0")
                } else if next == Some('#') {
                    "parameters (`#`) are not supported: write plain numbers".to_string()
                } else if next == Some('[') {
                    "expressions (`[ ]`) are not supported: write plain numbers".to_string()
                } else {
                    format!("write a number after {letter}, e.g. {letter}10.5")
                };
                let shown = &raw[byte_at(i)..byte_at((j + 1).min(chars.len()))];
                return Err(err(
                    line,
                    col,
                    Syntax,
                    shown,
                    format!("{letter} has no number"),
                    hint,
                ));
            }
            let number = &raw[byte_at(num_start)..byte_at(j)];
            let value: f64 = number.parse().map_err(|_| {
                err(
                    line,
                    col,
                    Syntax,
                    text,
                    format!("the number `{number}` does not parse"),
                    "write a decimal number with at most one point, e.g. 12.5",
                )
            })?;
            if value.is_nan() || value.abs() > MAX_WORD_VALUE {
                return Err(err(
                    line,
                    col,
                    GcodeErrorKind::InvalidValue,
                    text,
                    "number out of range",
                    format!("numbers must not exceed {MAX_WORD_VALUE:e} in magnitude"),
                ));
            }
            words.push(Word {
                letter,
                value,
                col,
                text,
            });
            i = j;
            continue;
        }
        let (message, hint) = match c {
            '#' => ("parameters (`#`) are not supported", "write plain numbers"),
            '[' | ']' => (
                "expressions (`[ ]`) are not supported",
                "write plain numbers",
            ),
            '/' => (
                "block delete (`/`) is not supported",
                "remove the `/` (or the whole line)",
            ),
            '*' => ("checksums (`*`) are not supported", "remove the checksum"),
            ')' => ("`)` without `(`", "comments are written `(like this)`"),
            _ => (
                "unexpected character",
                "a line holds words such as G01 X10.5, comments in ( ) or after ;",
            ),
        };
        let end = byte_at(i + 1);
        return Err(err(line, col, Syntax, &raw[byte_at(i)..end], message, hint));
    }
    Ok(Lexed::Words(words))
}

// ---------------------------------------------------------------------------------------------
// Interpreter

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Motion {
    Rapid,
    Linear,
    Cw,
    Ccw,
}

impl Motion {
    fn code(self) -> &'static str {
        match self {
            Motion::Rapid => "G00",
            Motion::Linear => "G01",
            Motion::Cw => "G02",
            Motion::Ccw => "G03",
        }
    }
}

/// A recognised G code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum GCode {
    Motion(Motion),
    Dwell,
    SetOffset,
    Plane(Plane),
    Inch(bool),
    Wcs(usize),
    Absolute(bool),
    /// Accepted, no effect.
    NoOp,
    /// Accepted with a warning.
    Ignored(&'static str),
}

impl GCode {
    /// Modal group, for "two codes of one group on a line". Dwell and G10 share the
    /// non-modal group 0.
    fn group(self) -> u8 {
        match self {
            GCode::Motion(_) => 1,
            GCode::Dwell | GCode::SetOffset => 0,
            GCode::Plane(_) => 2,
            GCode::Inch(_) => 6,
            GCode::Wcs(_) => 12,
            GCode::Absolute(_) => 3,
            GCode::NoOp | GCode::Ignored(_) => 255,
        }
    }
}

fn classify_g(w: &Word<'_>, line: usize) -> Result<GCode, GcodeError> {
    let tenths = (w.value * 10.0).round();
    let unknown = || {
        err(
            line,
            w.col,
            GcodeErrorKind::UnknownCode,
            w.text,
            format!("unknown G code {}", w.text),
            "supported: G00 G01 G02 G03 G04 G10 G17 G18 G19 G20 G21 G54-G59 G90 G91",
        )
    };
    if (w.value * 10.0 - tenths).abs() > 1e-9 {
        return Err(unknown());
    }
    let unsupported = |message: &str, hint: &str| {
        err(
            line,
            w.col,
            GcodeErrorKind::Unsupported,
            w.text,
            message,
            hint,
        )
    };
    let code = tenths as i64;
    Ok(match code {
        0 => GCode::Motion(Motion::Rapid),
        10 => GCode::Motion(Motion::Linear),
        20 => GCode::Motion(Motion::Cw),
        30 => GCode::Motion(Motion::Ccw),
        40 => GCode::Dwell,
        100 => GCode::SetOffset,
        170 => GCode::Plane(Plane::XY),
        180 => GCode::Plane(Plane::ZX),
        190 => GCode::Plane(Plane::YZ),
        200 => GCode::Inch(true),
        210 => GCode::Inch(false),
        540 | 550 | 560 | 570 | 580 | 590 => GCode::Wcs(((code - 540) / 10) as usize),
        900 => GCode::Absolute(true),
        910 => GCode::Absolute(false),
        911 | 400 | 490 | 800 | 940 => GCode::NoOp,
        610 | 611 | 640 => {
            GCode::Ignored("path blending mode ignored: every segment runs rest to rest")
        }
        901 => {
            return Err(unsupported(
                "G90.1 (absolute arc centres) is not supported",
                "give I/J/K relative to the arc's start point (G91.1, the default)",
            ))
        }
        280 | 281 | 300 | 301 => {
            return Err(unsupported(
                "homing (G28/G30) is not supported",
                "program the position with G00 X Y Z",
            ))
        }
        920..=923 => {
            return Err(unsupported(
                "G92 offsets are not supported",
                "set a work offset with G10 L2 P1 X Y Z and select it with G54",
            ))
        }
        410 | 420 | 411 | 421 => {
            return Err(unsupported(
                "cutter radius compensation is not supported",
                "program the tool centre path",
            ))
        }
        430..=432 => {
            return Err(unsupported(
                "tool length compensation is not supported",
                "program the tool centre point; remove G43",
            ))
        }
        530 => {
            return Err(unsupported(
                "G53 (machine coordinates) is not supported",
                "use a work offset G54-G59",
            ))
        }
        930 | 950 => {
            return Err(unsupported(
                "only feed per minute (G94) is supported",
                "remove G93/G95 and give F in mm/min",
            ))
        }
        730 | 760 | 810..=890 => {
            return Err(unsupported(
                "canned cycles are not supported",
                "expand the cycle into G00/G01 moves",
            ))
        }
        _ => return Err(unknown()),
    })
}

/// Action of an M code.
enum MCode {
    End,
    Warn(String),
}

fn classify_m(w: &Word<'_>, line: usize) -> Result<MCode, GcodeError> {
    let v = w.value;
    if v == 2.0 || v == 30.0 {
        return Ok(MCode::End);
    }
    if v == 98.0 || v == 99.0 || v == 47.0 {
        return Err(err(
            line,
            w.col,
            GcodeErrorKind::Unsupported,
            w.text,
            "subprograms and program repeats (M98/M99/M47) are not supported",
            "write the moves out in full",
        ));
    }
    let what = match v as i64 {
        0 | 1 | 60 => "program pause",
        3..=5 => "spindle",
        6 => "tool change",
        7..=9 => "coolant",
        _ => "M code",
    };
    Ok(MCode::Warn(format!(
        "{} ({what}) ignored: no effect on the path",
        w.text
    )))
}

/// Letters that carry arguments (not G, M, N).
const ARG_LETTERS: &str = "FIJKLOPRSTXYZ";

fn letter_index(c: char) -> Option<usize> {
    ARG_LETTERS.find(c)
}

/// The argument words of one line, by letter.
struct Args<'l, 'w>([Option<&'l Word<'w>>; 13]);

impl<'l, 'w> Args<'l, 'w> {
    fn get(&self, c: char) -> Option<&'l Word<'w>> {
        letter_index(c).and_then(|k| self.0.get(k).copied().flatten())
    }
}

struct Interpreter {
    inch: bool,
    absolute: bool,
    plane: Plane,
    wcs: usize,
    /// Work offsets G54..G59 (m).
    offsets: [[f64; 3]; 6],
    /// The G54 offset still comes from `ParseOptions::origin`.
    p1_from_options: bool,
    origin_given: bool,
    motion: Option<Motion>,
    /// Modal feed as written (program units per minute).
    feed: Option<f64>,
    pos: Option<Vector3<f64>>,
    start: Vector3<f64>,
    start_line: usize,
    moves: Vec<Move>,
    warnings: Vec<GcodeWarning>,
    ended: bool,
    seen_content: bool,
    warned_ignored: bool,
}

impl Interpreter {
    fn new(options: &ParseOptions) -> Result<Self, GcodeError> {
        let mut offsets = [[0.0; 3]; 6];
        if let Some(o) = options.origin {
            if !o.iter().all(|x| x.is_finite()) {
                return Err(err(
                    0,
                    0,
                    GcodeErrorKind::InvalidOption,
                    "",
                    format!("ParseOptions::origin must be finite, got {o:?}"),
                    "give the part origin in metres",
                ));
            }
            offsets[0] = o;
        }
        Ok(Interpreter {
            inch: false,
            absolute: true,
            plane: Plane::XY,
            wcs: 0,
            offsets,
            p1_from_options: true,
            origin_given: options.origin.is_some(),
            motion: None,
            feed: None,
            pos: None,
            start: Vector3::zeros(),
            start_line: 0,
            moves: Vec::new(),
            warnings: Vec::new(),
            ended: false,
            seen_content: false,
            warned_ignored: false,
        })
    }

    fn scale(&self) -> f64 {
        if self.inch {
            0.0254
        } else {
            1e-3
        }
    }

    fn warn(&mut self, line: usize, column: usize, message: impl Into<String>) {
        self.warnings.push(GcodeWarning {
            line,
            column,
            message: message.into(),
        });
    }

    fn note_ignored(&mut self, line: usize, raw: &str) {
        let t = raw.trim_start();
        if self.warned_ignored || t.is_empty() || t.starts_with(['%', '(', ';']) {
            return;
        }
        self.warned_ignored = true;
        let col = raw.chars().take_while(|c| c.is_whitespace()).count() + 1;
        self.warn(
            line,
            col,
            "text after the end of the program (M02/M30/%) ignored",
        );
    }

    fn finish(self) -> Result<Program, GcodeError> {
        if self.pos.is_none() {
            return Err(err(
                0,
                0,
                GcodeErrorKind::NoMotion,
                "",
                "the program has no motion",
                "start with G00 X.. Y.. Z.., which sets the start point",
            ));
        }
        Ok(Program {
            start: self.start,
            start_line: self.start_line,
            moves: self.moves,
            warnings: self.warnings,
        })
    }

    fn line(&mut self, line: usize, raw: &str, words: &[Word<'_>]) -> Result<(), GcodeError> {
        use GcodeErrorKind::*;
        let line_text = raw.trim();
        // N label: first word, non-negative integer.
        for (i, w) in words.iter().enumerate() {
            if w.letter == 'N' {
                if i != 0 {
                    return Err(err(
                        line,
                        w.col,
                        Syntax,
                        w.text,
                        "an N label must be the first word of the line",
                        "move it to the front or remove it",
                    ));
                }
                if w.value < 0.0 || w.value.fract() != 0.0 {
                    return Err(err(
                        line,
                        w.col,
                        InvalidValue,
                        w.text,
                        "an N label must be a non-negative integer",
                        "write e.g. N010",
                    ));
                }
            }
        }
        // Sort words.
        let mut gcodes: Vec<(GCode, &Word<'_>)> = Vec::new();
        let mut mcodes: Vec<(MCode, &Word<'_>)> = Vec::new();
        let mut args: [Option<&Word<'_>>; 13] = [None; 13];
        for w in words {
            match w.letter {
                'N' => {}
                'G' => {
                    let g = classify_g(w, line)?;
                    if g.group() != 255 {
                        if let Some((_, prev)) = gcodes.iter().find(|(o, _)| o.group() == g.group())
                        {
                            return Err(err(
                                line,
                                w.col,
                                Duplicate,
                                w.text,
                                format!("{} and {} on one line", prev.text, w.text),
                                "they exclude each other: keep one, or split the line",
                            ));
                        }
                    }
                    gcodes.push((g, w));
                }
                'M' => mcodes.push((classify_m(w, line)?, w)),
                c => match letter_index(c) {
                    Some(k) => {
                        if let Some(prev) = args[k] {
                            return Err(err(
                                line,
                                w.col,
                                Duplicate,
                                w.text,
                                format!("{c} given twice on one line (first as {})", prev.text),
                                "give each letter once per line; split the line in two",
                            ));
                        }
                        args[k] = Some(w);
                    }
                    None => {
                        let (message, hint) = match c {
                            'A' | 'B' | 'C' => (
                                format!("rotary axis word {c} is not supported"),
                                "the tool orientation is constant; remove the word",
                            ),
                            'U' | 'V' | 'W' => (
                                format!("axis word {c} is not supported"),
                                "only X, Y and Z are robot path axes",
                            ),
                            'E' => (
                                "E (extruder) words are not supported".to_string(),
                                "this looks like 3D-printer G-code; remove the E words",
                            ),
                            'D' | 'H' => (
                                format!("tool offset word {c} is not supported"),
                                "program the tool centre point; remove the word",
                            ),
                            _ => (
                                format!("the word {c} is not supported"),
                                "supported letters: G M N X Y Z I J K R F P L S T O",
                            ),
                        };
                        return Err(err(line, w.col, Unsupported, w.text, message, hint));
                    }
                },
            }
        }
        let args = Args(args);
        let arg = |c: char| args.get(c);

        // Harmless words.
        for (c, what) in [
            ('S', "spindle speed"),
            ('T', "tool"),
            ('O', "program number"),
        ] {
            if let Some(w) = arg(c) {
                self.warn(
                    line,
                    w.col,
                    format!("{} ({what}) ignored: no effect on the path", w.text),
                );
            }
        }
        for (m, w) in &mcodes {
            if let MCode::Warn(msg) = m {
                self.warn(line, w.col, msg.clone());
            }
        }
        for (g, w) in &gcodes {
            if let GCode::Ignored(msg) = g {
                self.warn(line, w.col, format!("{}: {msg}", w.text));
            }
        }

        // Modal settings, in LinuxCNC's order: units, plane, distance mode, feed.
        let mut explicit_motion = None;
        let mut dwell = None;
        let mut set_offset = None;
        let mut wcs = None;
        for &(g, w) in &gcodes {
            match g {
                GCode::Inch(b) => self.inch = b,
                GCode::Plane(p) => self.plane = p,
                GCode::Absolute(b) => self.absolute = b,
                GCode::Motion(m) => explicit_motion = Some((m, w)),
                GCode::Dwell => dwell = Some(w),
                GCode::SetOffset => set_offset = Some(w),
                GCode::Wcs(k) => wcs = Some(k),
                GCode::NoOp | GCode::Ignored(_) => {}
            }
        }
        if let Some(f) = arg('F') {
            if f.value <= 0.0 {
                return Err(err(
                    line,
                    f.col,
                    InvalidValue,
                    f.text,
                    "the feed must be positive",
                    "give F in mm/min (G21) or in/min (G20), e.g. F3000",
                ));
            }
            self.feed = Some(f.value);
        }
        let non_modal = dwell.or(set_offset);
        if let (Some(nm), Some((_, mw))) = (non_modal, explicit_motion) {
            return Err(err(
                line,
                mw.col,
                Conflict,
                line_text,
                format!("{} and {} on one line", nm.text, mw.text),
                "put the motion on its own line",
            ));
        }

        // Which argument letters this line's command uses.
        let mut used = [false; 13];
        for c in ['F', 'S', 'T', 'O'] {
            if let Some(k) = letter_index(c) {
                used[k] = true;
            }
        }
        let mut use_letters = |letters: &str| {
            for c in letters.chars() {
                if let Some(k) = letter_index(c) {
                    used[k] = true;
                }
            }
        };
        let motion_mode = explicit_motion.map(|(m, _)| m).or(self.motion);
        if dwell.is_some() {
            use_letters("PX");
        } else if set_offset.is_some() {
            use_letters("LPXYZ");
        } else if let Some(m) = motion_mode {
            use_letters("XYZ");
            if matches!(m, Motion::Cw | Motion::Ccw) {
                use_letters("IJKR");
            }
        }
        for (k, c) in ARG_LETTERS.chars().enumerate() {
            if let (Some(w), false) = (args.0[k], used[k]) {
                let (message, hint) = match c {
                    'X' | 'Y' | 'Z' if dwell.is_some() => (
                        format!("{c} is not used by G04"),
                        "G04 takes the dwell time as P (or X) seconds only",
                    ),
                    'X' | 'Y' | 'Z' => (
                        "coordinates without a motion mode".to_string(),
                        "add G00 or G01 (the first motion gives X, Y and Z of the start point)",
                    ),
                    'I' | 'J' | 'K' | 'R' => (
                        format!("{c} is only used by arcs (G02/G03) here"),
                        "add G02 or G03, or remove the word",
                    ),
                    'P' => (
                        "P is only used by G04 (dwell) and G10 here".to_string(),
                        "remove P (arcs with several turns are not supported: program each turn)",
                    ),
                    'L' => ("L is only used by G10 L2".to_string(), "remove the L word"),
                    _ => (format!("{c} is not used here"), "remove the word"),
                };
                return Err(err(line, w.col, Conflict, w.text, message, hint));
            }
        }

        if let Some(g10) = set_offset {
            self.set_offset(line, g10, &args)?;
        }
        if let Some(k) = wcs {
            self.wcs = k;
        }
        if let Some(g4) = dwell {
            let (p, x) = (arg('P'), arg('X'));
            let w = match (p, x) {
                (Some(p), None) => p,
                (None, Some(x)) => x,
                (Some(_), Some(x)) => {
                    return Err(err(
                        line,
                        x.col,
                        Conflict,
                        line_text,
                        "G04 with both P and X",
                        "give the dwell time once, as P seconds",
                    ))
                }
                (None, None) => {
                    return Err(err(
                        line,
                        g4.col,
                        Missing,
                        line_text,
                        "G04 without a time",
                        "give the dwell time in seconds, e.g. G04 P0.5",
                    ))
                }
            };
            if w.value < 0.0 {
                return Err(err(
                    line,
                    w.col,
                    InvalidValue,
                    w.text,
                    "negative dwell time",
                    "give the dwell time in seconds, >= 0",
                ));
            }
            if w.value > 0.0 {
                if self.pos.is_none() {
                    return Err(err(
                        line,
                        g4.col,
                        StartPoint,
                        line_text,
                        "dwell before the start point is known",
                        "start the program with G00 X.. Y.. Z..",
                    ));
                }
                self.moves.push(Move {
                    line,
                    kind: MoveKind::Dwell { seconds: w.value },
                });
            }
        }
        if let Some(m) = explicit_motion {
            self.motion = Some(m.0);
        }
        if dwell.is_none() && set_offset.is_none() {
            let has = |c| arg(c).is_some();
            let axes = has('X') || has('Y') || has('Z');
            let centre = has('I') || has('J') || has('K') || has('R');
            if let Some(m) = motion_mode {
                let is_arc = matches!(m, Motion::Cw | Motion::Ccw);
                if axes || (is_arc && centre) {
                    let anchor = explicit_motion
                        .map(|(_, w)| w.col)
                        .or_else(|| {
                            words
                                .iter()
                                .find(|w| "XYZIJKR".contains(w.letter))
                                .map(|w| w.col)
                        })
                        .unwrap_or(1);
                    self.motion(line, anchor, line_text, m, &args)?;
                }
            }
        }
        if mcodes.iter().any(|(m, _)| matches!(m, MCode::End)) {
            self.ended = true;
        }
        Ok(())
    }

    fn set_offset(
        &mut self,
        line: usize,
        g10: &Word<'_>,
        args: &Args<'_, '_>,
    ) -> Result<(), GcodeError> {
        use GcodeErrorKind::*;
        let arg = |c| args.get(c);
        match arg('L') {
            None => {
                return Err(err(
                    line,
                    g10.col,
                    Missing,
                    g10.text,
                    "G10 without L",
                    "set a work offset with G10 L2 P1 X.. Y.. Z..",
                ))
            }
            Some(l) if l.value != 2.0 => {
                return Err(err(
                    line,
                    l.col,
                    Unsupported,
                    l.text,
                    format!("G10 {} is not supported", l.text),
                    "only G10 L2 Pn X Y Z (work offset of G54..G59) is supported",
                ))
            }
            Some(_) => {}
        }
        let p = arg('P').ok_or_else(|| {
            err(
                line,
                g10.col,
                Missing,
                g10.text,
                "G10 L2 without P",
                "P1..P6 selects the work offset of G54..G59",
            )
        })?;
        if !(1.0..=6.0).contains(&p.value) || p.value.fract() != 0.0 {
            return Err(err(
                line,
                p.col,
                InvalidValue,
                p.text,
                "G10 L2 needs P1..P6",
                "P1..P6 selects the work offset of G54..G59",
            ));
        }
        let k = p.value as usize - 1;
        if k == 0 && self.p1_from_options {
            self.p1_from_options = false;
            if self.origin_given {
                self.warn(
                    line,
                    g10.col,
                    "the program sets the G54 offset: ParseOptions::origin is not used",
                );
            }
            self.offsets[0] = [0.0; 3];
        }
        let scale = self.scale();
        for (axis, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if let (Some(w), Some(o)) = (arg(c), self.offsets.get_mut(k)) {
                o[axis] = w.value * scale;
            }
        }
        Ok(())
    }

    fn motion(
        &mut self,
        line: usize,
        col: usize,
        line_text: &str,
        mode: Motion,
        args: &Args<'_, '_>,
    ) -> Result<(), GcodeError> {
        use GcodeErrorKind::*;
        let arg = |c| args.get(c);
        let scale = self.scale();
        let offset = self.offsets.get(self.wcs).copied().unwrap_or([0.0; 3]);
        let xyz = [arg('X'), arg('Y'), arg('Z')];
        let Some(pos) = self.pos else {
            // The first motion defines the start point.
            if matches!(mode, Motion::Cw | Motion::Ccw) {
                return Err(err(
                    line,
                    col,
                    StartPoint,
                    line_text,
                    "the first motion is an arc, but the start point is not known yet",
                    "start with G00 X.. Y.. Z.., which sets the start point",
                ));
            }
            if !self.absolute {
                return Err(err(
                    line,
                    col,
                    StartPoint,
                    line_text,
                    "the first motion is incremental (G91), but the start point is not known yet",
                    "give the start point in absolute coordinates (G90)",
                ));
            }
            let missing: Vec<&str> = ["X", "Y", "Z"]
                .iter()
                .zip(xyz)
                .filter(|(_, w)| w.is_none())
                .map(|(n, _)| *n)
                .collect();
            if !missing.is_empty() {
                return Err(err(
                    line,
                    col,
                    StartPoint,
                    line_text,
                    format!(
                        "the first motion sets the start point and must give X, Y and Z (missing: {})",
                        missing.join(", ")
                    ),
                    "give all three coordinates of the start point, e.g. G00 X630 Y-200 Z400",
                ));
            }
            let mut p = Vector3::zeros();
            for (a, w) in xyz.iter().enumerate() {
                p[a] = w.map_or(0.0, |w| w.value) * scale + offset[a];
            }
            self.pos = Some(p);
            self.start = p;
            self.start_line = line;
            return Ok(());
        };
        let mut target = pos;
        for (a, w) in xyz.iter().enumerate() {
            if let Some(w) = w {
                target[a] = if self.absolute {
                    w.value * scale + offset[a]
                } else {
                    pos[a] + w.value * scale
                };
            }
        }
        let feed = match (mode, self.feed) {
            (Motion::Rapid, _) | (_, None) => None,
            (_, Some(f)) => Some(f * scale / 60.0),
        };
        let segment = match mode {
            Motion::Rapid | Motion::Linear => {
                if (target - pos).norm() <= MIN_MOVE_LENGTH {
                    self.warn(line, col, "zero-length move skipped");
                    return Ok(());
                }
                Segment::line(pos, target)
            }
            Motion::Cw | Motion::Ccw => {
                let dir = if mode == Motion::Cw {
                    ArcDirection::Clockwise
                } else {
                    ArcDirection::CounterClockwise
                };
                let seg = if let Some(r) = arg('R') {
                    if let Some(w) = arg('I').or(arg('J')).or(arg('K')) {
                        return Err(err(
                            line,
                            w.col,
                            Conflict,
                            line_text,
                            "an arc with both R and I/J/K",
                            "give the centre either by R or by I/J/K offsets",
                        ));
                    }
                    self.arc_by_radius(line, col, line_text, mode, pos, target, r, dir)?
                } else {
                    self.arc_by_centre(line, col, line_text, mode, pos, target, args, dir)?
                };
                let shift = (seg.end() - target).norm();
                if shift > 1e-9 {
                    self.warn(
                        line,
                        col,
                        format!(
                            "arc end placed on the circle, {:.6} mm from the programmed end",
                            shift * 1e3
                        ),
                    );
                }
                seg
            }
        };
        self.pos = Some(segment.end());
        self.moves.push(Move {
            line,
            kind: MoveKind::Path { segment, feed },
        });
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn arc_by_radius(
        &self,
        line: usize,
        col: usize,
        line_text: &str,
        mode: Motion,
        start: Vector3<f64>,
        end: Vector3<f64>,
        r: &Word<'_>,
        dir: ArcDirection,
    ) -> Result<Segment, GcodeError> {
        use GcodeErrorKind::*;
        let plane = self.plane;
        let (u, v, _) = plane.axes();
        let radius = r.value * self.scale();
        let (du, dv) = (end[u] - start[u], end[v] - start[v]);
        let chord = du.hypot(dv);
        if radius == 0.0 {
            return Err(err(
                line,
                r.col,
                Arc,
                r.text,
                "arc radius R is zero",
                "give the radius (negative for the long way round, more than 180°)",
            ));
        }
        if chord <= CLOSED_ARC_TOLERANCE {
            return Err(err(
                line,
                col,
                Arc,
                line_text,
                format!(
                    "{} with R and a zero-length arc: start and end coincide in the {} plane ({})",
                    mode.code(),
                    plane.name(),
                    plane.gcode()
                ),
                "R cannot describe a full circle: give the centre with I/J/K offsets",
            ));
        }
        let half = chord / 2.0;
        let tol = arc_tolerance(self.inch);
        let h2 = radius * radius - half * half;
        let h = if h2 >= 0.0 {
            h2.sqrt()
        } else if radius.abs() >= half - tol {
            0.0
        } else {
            return Err(err(
                line,
                r.col,
                Arc,
                line_text,
                format!(
                    "|R| = {:.4} mm is less than half the chord ({:.4} mm)",
                    radius.abs() * 1e3,
                    half * 1e3
                ),
                "increase R or move the end point: no circle of that radius joins the points",
            ));
        };
        // Centre to the left of the chord (seen from +normal) for a short CCW or a long CW arc.
        let left = matches!(
            (dir, radius > 0.0),
            (ArcDirection::CounterClockwise, true) | (ArcDirection::Clockwise, false)
        );
        let sgn = if left { 1.0 } else { -1.0 };
        let (tu, tv) = (du / chord, dv / chord);
        let mut center = start;
        center[u] = start[u] + du / 2.0 - sgn * h * tv;
        center[v] = start[v] + dv / 2.0 + sgn * h * tu;
        Segment::arc(start, center, end, plane, dir).map_err(|e| arc_error(e, line, col, line_text))
    }

    #[allow(clippy::too_many_arguments)]
    fn arc_by_centre(
        &self,
        line: usize,
        col: usize,
        line_text: &str,
        mode: Motion,
        start: Vector3<f64>,
        end: Vector3<f64>,
        args: &Args<'_, '_>,
        dir: ArcDirection,
    ) -> Result<Segment, GcodeError> {
        let scale = self.scale();
        let ijk = [args.get('I'), args.get('J'), args.get('K')];
        let given = ijk.map(|w| w.is_some());
        let mut off = Vector3::zeros();
        for (a, w) in ijk.iter().enumerate() {
            off[a] = w.map_or(0.0, |w| w.value) * scale;
        }
        let tol = arc_tolerance(self.inch);
        let center = start + off;
        let check = |p: Plane| check_arc_plane(p, start, end, off, given, tol);
        let Err(problem) = check(self.plane) else {
            return Segment::arc(start, center, end, self.plane, dir)
                .map_err(|e| arc_error(e, line, col, line_text));
        };
        let letters = |p: Plane| {
            let (u, v, _) = p.axes();
            format!("{}/{}", IJK[u], IJK[v])
        };
        let unit = if self.inch { "in" } else { "mm" };
        let message = match problem {
            ArcProblem::MissingOffsets => format!(
                "{} in the {} plane ({}) needs the centre offsets {} (or R)",
                mode.code(),
                self.plane.name(),
                self.plane.gcode(),
                letters(self.plane)
            ),
            ArcProblem::ZeroRadius => format!(
                "arc radius is zero in the {} plane ({}): the {} offsets put the centre on the start point",
                self.plane.name(),
                self.plane.gcode(),
                letters(self.plane)
            ),
            ArcProblem::RadiusMismatch { r0, r1 } => format!(
                "arc start and end radii differ in the {} plane ({}): {:.4} {unit} vs {:.4} {unit} (tolerance {} {unit})",
                self.plane.name(),
                self.plane.gcode(),
                r0 / scale,
                r1 / scale,
                tol / scale
            ),
            ArcProblem::NormalOffset { letter } => format!(
                "the {letter} offset lies along the normal of the {} plane ({}) and must be 0",
                self.plane.name(),
                self.plane.gcode()
            ),
        };
        let fits: Vec<Plane> = Plane::ALL
            .into_iter()
            .filter(|&p| p != self.plane && check(p).is_ok())
            .collect();
        let hint = match fits.first() {
            Some(&p) => format!(
                "the {} offsets fit the {} plane ({}): did you mean {} instead of {}?",
                letters(p),
                p.name(),
                p.gcode(),
                p.gcode(),
                self.plane.gcode()
            ),
            None => match problem {
                ArcProblem::MissingOffsets => format!(
                    "give the centre as offsets {} from the start point",
                    letters(self.plane)
                ),
                ArcProblem::NormalOffset { letter } => {
                    format!("remove {letter} or select the plane the arc lies in (G17/G18/G19)")
                }
                _ => "check the end point and the centre offsets (relative to the start point)"
                    .to_string(),
            },
        };
        Err(err(
            line,
            col,
            GcodeErrorKind::Arc,
            line_text,
            message,
            hint,
        ))
    }
}

const IJK: [char; 3] = ['I', 'J', 'K'];

enum ArcProblem {
    MissingOffsets,
    ZeroRadius,
    RadiusMismatch { r0: f64, r1: f64 },
    NormalOffset { letter: char },
}

/// Whether centre offsets `off` (m, from `start`) describe a valid arc in `plane`.
fn check_arc_plane(
    plane: Plane,
    start: Vector3<f64>,
    end: Vector3<f64>,
    off: Vector3<f64>,
    given: [bool; 3],
    tol: f64,
) -> Result<(), ArcProblem> {
    let (u, v, w) = plane.axes();
    if !(given[u] || given[v]) {
        return Err(ArcProblem::MissingOffsets);
    }
    let c = start + off;
    let r0 = (start[u] - c[u]).hypot(start[v] - c[v]);
    let r1 = (end[u] - c[u]).hypot(end[v] - c[v]);
    if r0 <= tol {
        return Err(ArcProblem::ZeroRadius);
    }
    if (r1 - r0).abs() > tol || r1.is_nan() {
        return Err(ArcProblem::RadiusMismatch { r0, r1 });
    }
    if off[w].abs() > tol {
        return Err(ArcProblem::NormalOffset { letter: IJK[w] });
    }
    Ok(())
}

fn arc_error(e: ArcError, line: usize, col: usize, line_text: &str) -> GcodeError {
    err(
        line,
        col,
        GcodeErrorKind::Arc,
        line_text,
        e.to_string(),
        "check the end point and the centre",
    )
}
