//! What the reader produces and how it fails: the program ([`Program`], its moves, events,
//! messages and warnings), the options ([`ParseOptions`]), the errors ([`GcodeError`]) and
//! the limits every part of the reader checks. A leaf: the lexer, the interpreter and the
//! control flow all build on it.

use super::tools::ToolTable;
use crate::geometry::Segment;
use nalgebra::Vector3;
use std::fmt;

/// Largest magnitude accepted for any number in a program.
pub const MAX_WORD_VALUE: f64 = 1e9;

/// Moves shorter than this (m) are skipped with a warning.
pub const MIN_MOVE_LENGTH: f64 = 1e-12;

/// Options of [`parse`](super::parse).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParseOptions {
    /// Initial `G54` work offset (m, base frame), used when the program does not set the G54
    /// offset itself with `G10 L2 P1`. `None`: zero.
    pub origin: Option<[f64; 3]>,
    /// Where the tool is when the program starts (m, base frame: the frame of the program's
    /// points after the work offset is applied), e.g. the tool position of the robot's start
    /// pose. `Some`: a first motion that does not give all of X, Y and Z absolutely (or an
    /// arc) moves from here, as a CNC moves from where the machine is. `None`: the first
    /// motion must give X, Y and Z (it sets the start point).
    pub start: Option<Vector3<f64>>,
    /// Lines the program may execute beyond its own length (loops, calls) before it is
    /// stopped as an endless loop; `None`: `DEFAULT_MAX_STEPS`.
    pub max_steps: Option<usize>,
    /// The tool table `G43 H<n>` takes tool n's length from; `None`: `G43 H<n>` (n > 0)
    /// is refused.
    pub tool_table: Option<ToolTable>,
    /// Unit direction (base frame) from the controlled point to the tool tip: a tool of
    /// length `L` has its tip `L` along it. A change of the tool length by `ΔL` (`G43`,
    /// `G43.1`, `G49`) moves no axis, so the tip's current point moves by `ΔL` along this
    /// direction (LinuxCNC's `convert_tool_length_offset`: `current_z += old − new` with
    /// the tool along machine −Z). `None`: −Z, LinuxCNC's tool axis; the planner passes the
    /// robot's TCP z axis ([`crate::motion::plan`]).
    pub tool_axis: Option<Vector3<f64>>,
}

impl ParseOptions {
    /// The default options with the initial `G54` work offset `origin` (m, base frame).
    pub fn with_origin(origin: Option<[f64; 3]>) -> Self {
        Self {
            origin,
            ..Self::default()
        }
    }
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
    /// M codes, S and T words in program order (passed through; no effect on the path).
    pub events: Vec<ProgramEvent>,
    /// `(MSG,…)`, `(PRINT,…)`, `(DEBUG,…)` comments in program order.
    pub messages: Vec<ProgramMessage>,
    /// Tool length offset in force at the end of the program (m, along the tool axis, from
    /// `G43 H…` / `G43.1 Z…`; 0 after `G49`): for the TCP.
    pub tool_length: f64,
    /// Tool length offset (m) in force when the start point was set: [`Program::start`] is
    /// the tip of a tool this long.
    pub start_tool_length: f64,
    /// `(line, column)` of each line's first motion block (1-based; the column of its
    /// anchor word, e.g. `G1` or its first axis word), in program order: where a point of the
    /// path came from ([`Program::motion_column`]).
    pub motion_columns: Vec<(usize, usize)>,
}

impl Program {
    /// The column (1-based) of the motion on program line `line` (see
    /// [`Program::motion_columns`]); `None` for a line without one.
    pub fn motion_column(&self, line: usize) -> Option<usize> {
        self.motion_columns
            .iter()
            .find(|&&(l, _)| l == line)
            .map(|&(_, c)| c)
    }
}

/// An M code or an S/T word of a program: recorded in order, never a reason to reject.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramEvent {
    /// Source line (1-based).
    pub line: usize,
    /// `M3`, `M62`, `S`, `T`, … (M codes without leading zeros).
    pub code: String,
    /// The words that go with it (`P`, `Q`, `E`, `L`, `S`, `T`), letter and value.
    pub words: Vec<(char, f64)>,
    /// Number of [`Program::moves`] before the event: it happens after those moves.
    pub after_moves: usize,
}

/// A message comment of a program.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramMessage {
    /// Source line (1-based).
    pub line: usize,
    /// `MSG`, `PRINT` or `DEBUG`.
    pub kind: &'static str,
    /// The text (parameters substituted for PRINT and DEBUG; invisible characters escaped).
    pub text: String,
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

/// How consecutive moves are joined: the path mode of `G61` (exact stop) and `G64 P…`
/// (blending), a modal state of the program that each [`MoveKind::Path`] carries and the
/// planner ([`crate::motion`]) honours.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum PathMode {
    /// `G61`: every move runs rest to rest with the septic law (the paper's).
    #[default]
    ExactStop,
    /// `G64 P<tol>`: corners are rounded within `tolerance` (m) and the path does not stop
    /// where it does not have to; `None` (`G64` without `P`): the planner's default tolerance.
    Blend {
        /// Largest distance (m) between the path and a programmed corner.
        tolerance: Option<f64>,
    },
}

/// One move of a program.
#[derive(Debug, Clone, PartialEq)]
pub struct Move {
    /// Source line (1-based) of the block that commanded the move.
    pub line: usize,
    /// What the move does.
    pub kind: MoveKind,
    /// Tool length offset (m, along the tool axis) in force during the move: its points are
    /// those of the tip of a tool this long (`G43 H…`, `G43.1 Z…`; 0 without, or after `G49`).
    pub tool_length: f64,
}

/// The kinds of move.
#[derive(Debug, Clone, PartialEq)]
pub enum MoveKind {
    /// Travel along a path segment (base frame, m).
    Path {
        /// The geometry.
        segment: Segment,
        /// Programmed feed from the `F` word (m/s); `None` for `G00` and when no `F` was given
        /// (then the planner's speed limit applies). Under `G61` it is the move's peak speed,
        /// under `G64` its cruise speed.
        feed: Option<f64>,
        /// Path mode in force (`G61` / `G64 P…`); `None` when the program selected neither
        /// (the planner's default applies).
        mode: Option<PathMode>,
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

/// A [`GcodeError`] (shared by the submodules).
pub(super) fn err(
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
