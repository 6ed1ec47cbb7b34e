//! Interpreter: modal state (units, plane, distance mode, work offsets, motion mode, feed,
//! position) and the execution of one line's words.

use super::codes::{
    classify_g, classify_m, letter_index, m_letters, Args, GCode, MCode, Motion, ARG_LETTERS,
    N_ARGS,
};
use super::lexer::Word;
use super::program::{
    err, GcodeError, GcodeErrorKind, GcodeWarning, Move, MoveKind, ParseOptions, PathMode, Program,
    ProgramEvent, ProgramMessage, MIN_MOVE_LENGTH,
};
use crate::geometry::{ArcDirection, Plane, Segment};
use nalgebra::Vector3;

/// State of the codes `modal.rs` executes (G92/G52, G53, G28/G30 homes, arcs, canned-cycle
/// retract, ...): part of the interpreter's state.
#[derive(Debug, Clone, Default)]
pub(super) struct Extra {
    /// G92/G52 offset (m) and the one G92.2 suspended.
    pub(super) g92: [f64; 3],
    pub(super) g92_saved: [f64; 3],
    /// This line is G53 (machine coordinates).
    pub(super) machine: bool,
    /// Positions stored by G28.1 / G30.1 (m, machine).
    pub(super) home: [Option<Vector3<f64>>; 2],
    /// G90.1 in force.
    pub(super) arc_absolute: bool,
    /// G98 (retract to the initial Z) in force; default G99 (LinuxCNC's R_PLANE).
    pub(super) retract_initial: bool,
    /// 93, 94 or 95.
    pub(super) feed_mode: u8,
    /// Last spindle speed S (for G95).
    pub(super) spindle: Option<f64>,
    /// Sticky canned-cycle words R, Z, Q, P (program units / s) and the Z (m) where the
    /// cycles began.
    pub(super) cycle: [Option<f64>; 4],
    pub(super) cycle_z0: Option<f64>,
    /// G64 Q tolerance (m) and the points removed from the last move by merging.
    pub(super) merge_q: Option<f64>,
    pub(super) merged: Vec<Vector3<f64>>,
    /// Spindle direction from M3 (1), M4 (-1), M5 (0); coolant from M7/M8/M9.
    pub(super) spindle_dir: i8,
    pub(super) mist: bool,
    pub(super) flood: bool,
    /// Rotation (degrees about Z) of the coordinate systems G54 … G59 (G10 L2 R).
    pub(super) rotation: [f64; 6],
    /// Tool selected by T and the tool in the spindle (M6, M61 Q).
    pub(super) tool_selected: f64,
    pub(super) tool_current: f64,
    /// Where the tool is when it is not at the current point `pos` (after G74/G84 in
    /// G18/G19, see `tap_point`): the next move starts there.
    pub(super) machine_at: Option<Vector3<f64>>,
    /// The warning on G74/G84 in G18/G19 was given.
    pub(super) warned_tap: bool,
    /// Bytes of the messages (MSG, PRINT, DEBUG) recorded so far.
    pub(super) message_bytes: usize,
}

/// The most moves a program may make (issue #36: a canned cycle with a tiny peck or a huge
/// L, or a loop, made millions and aborted on memory): far above a hand-written or CAM
/// program for a robot arm; planning past it would take minutes anyway.
pub const MAX_MOVES: usize = 250_000;

/// The most events (M codes, tool changes) a program may record.
pub const MAX_EVENTS: usize = 250_000;

/// The most bytes of messages (MSG, PRINT, DEBUG) a program may record.
pub const MAX_MESSAGE_BYTES: usize = 16 << 20;

impl Interpreter {
    /// What the program has produced past its budget, if anything: the thing counted and
    /// its limit. Checked as the program grows (after every line, and inside the loops of a
    /// canned cycle, which stop at once).
    pub(super) fn over_budget(&self) -> Option<(&'static str, usize)> {
        if self.moves.len() > MAX_MOVES {
            Some(("moves", MAX_MOVES))
        } else if self.events.len() > MAX_EVENTS {
            Some(("events (M codes, tool changes)", MAX_EVENTS))
        } else if self.ext.message_bytes > MAX_MESSAGE_BYTES {
            Some(("bytes of messages (MSG, PRINT, DEBUG)", MAX_MESSAGE_BYTES))
        } else {
            None
        }
    }
}

/// Modal state of the reader while it walks the program, and the moves produced so far.
pub(super) struct Interpreter {
    pub(super) inch: bool,
    pub(super) absolute: bool,
    pub(super) plane: Plane,
    pub(super) wcs: usize,
    /// Work offsets G54..G59 (m).
    pub(super) offsets: [[f64; 3]; 6],
    /// The G54 offset still comes from `ParseOptions::origin`.
    pub(super) p1_from_options: bool,
    pub(super) origin_given: bool,
    pub(super) motion: Option<Motion>,
    /// Modal feed as written (program units per minute).
    pub(super) feed: Option<f64>,
    pub(super) pos: Option<Vector3<f64>>,
    pub(super) start: Vector3<f64>,
    pub(super) start_line: usize,
    /// `(line, column)` of each line's first motion block ([`Program::motion_columns`]).
    pub(super) motion_columns: Vec<(usize, usize)>,
    pub(super) moves: Vec<Move>,
    pub(super) warnings: Vec<GcodeWarning>,
    pub(super) ended: bool,
    pub(super) seen_content: bool,
    pub(super) warned_ignored: bool,
    /// Path mode selected by G61 / G64; `None` until the program selects one.
    pub(super) mode: Option<PathMode>,
    /// M codes, S and T words so far.
    pub(super) events: Vec<ProgramEvent>,
    /// Message comments so far.
    pub(super) messages: Vec<ProgramMessage>,
    /// Tool position before the program (m), from the options.
    pub(super) initial: Option<Vector3<f64>>,
    /// Tool length offset (m) along the tool axis.
    pub(super) tool_length: f64,
    /// Tool length offset (m) when the start point was set.
    pub(super) start_tool_length: f64,
    /// Unit direction from the controlled point to the tip ([`ParseOptions::tool_axis`]).
    pub(super) tool_axis: Vector3<f64>,
    /// State of the codes of [`super::modal`].
    pub(super) ext: Extra,
    /// The tool table of the options (G43 H).
    pub(super) tools: Option<super::tools::ToolTable>,
    /// The warning that the origin option applies to G54 only was given.
    warned_wcs: bool,
}

impl Interpreter {
    pub(super) fn new(options: &ParseOptions) -> Result<Self, GcodeError> {
        let offsets = Self::initial_offsets(options)?;
        let tool_axis = Self::checked_tool_axis(options)?;
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
            motion_columns: Vec::new(),
            moves: Vec::new(),
            warnings: Vec::new(),
            ended: false,
            seen_content: false,
            warned_ignored: false,
            mode: None,
            events: Vec::new(),
            messages: Vec::new(),
            initial: options.start,
            tool_length: 0.0,
            start_tool_length: 0.0,
            tool_axis,
            ext: Extra {
                feed_mode: 94,
                ..Extra::default()
            },
            tools: options.tool_table.clone(),
            warned_wcs: false,
        })
    }

    /// The work offsets G54..G59 before the program: the part origin of the options as
    /// G54's, which must be finite.
    fn initial_offsets(options: &ParseOptions) -> Result<[[f64; 3]; 6], GcodeError> {
        let mut offsets = [[0.0; 3]; 6];
        if let Some(o) = options.origin {
            if !o.iter().all(|x| x.is_finite()) {
                return Err(err(
                    0,
                    0,
                    GcodeErrorKind::InvalidOption,
                    "",
                    format!("the part origin (work offset) must be finite, got {o:?} m"),
                    "give the part origin in metres",
                ));
            }
            offsets[0] = o;
        }
        Ok(offsets)
    }

    /// The tool axis of the options (default −Z), which must be a finite unit vector.
    fn checked_tool_axis(options: &ParseOptions) -> Result<Vector3<f64>, GcodeError> {
        let tool_axis = options.tool_axis.unwrap_or(-Vector3::z());
        if !(tool_axis.iter().all(|x| x.is_finite()) && (tool_axis.norm() - 1.0).abs() < 1e-9) {
            return Err(err(
                0,
                0,
                GcodeErrorKind::InvalidOption,
                "",
                format!(
                    "the tool axis must be a finite unit vector, got [{}, {}, {}]",
                    tool_axis.x, tool_axis.y, tool_axis.z
                ),
                "give the direction from the controlled point to the tool tip, of length 1",
            ));
        }
        Ok(tool_axis)
    }

    pub(super) fn scale(&self) -> f64 {
        if self.inch {
            0.0254
        } else {
            1e-3
        }
    }

    pub(super) fn warn(&mut self, line: usize, column: usize, message: impl Into<String>) {
        self.warnings.push(GcodeWarning {
            line,
            column,
            message: message.into(),
        });
    }

    pub(super) fn note_ignored(&mut self, line: usize, raw: &str) {
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

    pub(super) fn finish(mut self) -> Result<Program, GcodeError> {
        if let (None, Some(p0)) = (self.pos, self.initial_tip()) {
            // No motion, but the tool position is known: an empty path from there.
            self.begin_at(p0, 0);
        }
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
            events: self.events,
            messages: self.messages,
            tool_length: self.tool_length,
            start_tool_length: self.start_tool_length,
            motion_columns: self.motion_columns,
        })
    }

    pub(super) fn line(
        &mut self,
        line: usize,
        raw: &str,
        words: &[Word<'_>],
    ) -> Result<(), GcodeError> {
        let line_text = raw.trim();
        Self::check_n_label(line, words)?;
        let sorted = Self::sort_words(line, words)?;
        let args = &sorted.args;
        self.warn_ignored_words(line, &sorted);

        // Modal settings, in LinuxCNC's order: units, plane, distance mode, feed.
        let cmd = self.apply_modal_gcodes(&sorted.gcodes);
        self.apply_feed(line, args.get('F'))?;
        self.apply_blend(line, &cmd, args)?;
        cmd.check_non_modal_conflict(line, line_text)?;

        let motion_mode = cmd.explicit_motion.map(|(m, _)| m).or(self.motion);
        let mletters: String = sorted
            .mcodes
            .iter()
            .map(|(_, w)| m_letters(w.value))
            .collect();
        Self::check_unused_args(line, &cmd, motion_mode, args, &mletters)?;
        self.record_events(line, &sorted);
        self.apply_commands(line, line_text, &cmd, args)?;
        let consumes_axes = cmd.axis_cmd.is_some() || cmd.tool.is_some_and(|(c, _)| c == 431);
        // G04 uses no axis words, so a motion may share its line (LinuxCNC: the dwell
        // runs first); without one, G04 X… is a dwell time.
        let dwell_only = cmd.dwell.is_some() && cmd.explicit_motion.is_none();
        if !dwell_only && cmd.set_offset.is_none() && !consumes_axes {
            if let Some(m) = motion_mode {
                self.line_motion(line, line_text, words, &cmd, m, args)?;
            }
        }
        if sorted.mcodes.iter().any(|(m, _)| matches!(m, MCode::End)) {
            self.ended = true;
        }
        Ok(())
    }

    /// The line's non-motion commands, in LinuxCNC's order: G10, the work offset, the
    /// spindle speed, the tool length, G28/G30/G92, G04; then the new motion mode.
    fn apply_commands(
        &mut self,
        line: usize,
        line_text: &str,
        cmd: &LineCommands<'_, '_>,
        args: &Args<'_, '_>,
    ) -> Result<(), GcodeError> {
        if let Some(g10) = cmd.set_offset {
            self.set_offset(line, g10, args)?;
        }
        if let Some(k) = cmd.wcs {
            self.select_wcs(line, k, cmd);
        }
        if let Some(sw) = args.get('S') {
            self.ext.spindle = Some(sw.value);
        }
        if let Some((c, w)) = cmd.tool {
            self.tool_length_code(line, w, c, args)?;
        }
        if let Some((g, c, w)) = cmd.axis_cmd {
            match g {
                GCode::Home(_) => self.home(line, w, c, args)?,
                _ => self.shift(c, args),
            }
        }
        if let Some(g4) = cmd.dwell {
            self.dwell(line, line_text, g4, args, cmd.explicit_motion.is_some())?;
        }
        if let Some(m) = cmd.explicit_motion {
            if !matches!(m.0, Motion::Cycle(_)) {
                self.ext.cycle_z0 = None;
            }
            self.motion = Some(m.0);
        }
        Ok(())
    }

    /// Checks the N label: if present it must be the first word and a non-negative integer.
    fn check_n_label(line: usize, words: &[Word<'_>]) -> Result<(), GcodeError> {
        use GcodeErrorKind::*;
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
                if w.value < 0.0 {
                    return Err(err(
                        line,
                        w.col,
                        InvalidValue,
                        w.text,
                        "an N label must not be negative (a non-negative integer)",
                        "write e.g. N010",
                    ));
                }
            }
        }
        Ok(())
    }

    /// Sorts a line's words into G codes, M codes and argument words (N is skipped).
    ///
    /// Rejects two G codes of one modal group, a letter given twice and unsupported letters.
    fn sort_words<'l, 'w>(
        line: usize,
        words: &'l [Word<'w>],
    ) -> Result<LineWords<'l, 'w>, GcodeError> {
        use GcodeErrorKind::*;
        let mut gcodes: Vec<(GCode, &Word<'_>)> = Vec::new();
        let mut mcodes: Vec<(MCode, &Word<'_>)> = Vec::new();
        let mut args: [Option<&Word<'_>>; N_ARGS] = [None; N_ARGS];
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
                // An axis the robot does not have, kept at 0 where LinuxCNC starts it
                // (A0, or an increment of 0): no motion, nothing to reject.
                'A' | 'B' | 'C' | 'U' | 'V' | 'W' if w.value == 0.0 => {}
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
                    None => return Err(Self::unsupported_letter(line, w)),
                },
            }
        }
        Ok(LineWords {
            gcodes,
            mcodes,
            args: Args(args),
        })
    }

    /// The error for a word whose letter the reader does not support (A, B, C, U, V, W, E, ...).
    fn unsupported_letter(line: usize, w: &Word<'_>) -> GcodeError {
        let c = w.letter;
        let (message, hint) = match c {
            'A' | 'B' | 'C' => (
                format!("rotary axis word {c} moves the {c} axis: rotary axes are not supported"),
                "the tool orientation is constant; remove the word (A0, B0, C0 are read: the axis stays at 0)",
            ),
            'U' | 'V' | 'W' => (
                format!("axis word {c} moves the {c} axis: only X, Y and Z are robot path axes"),
                "remove the word (U0, V0, W0 are read: the axis stays at 0)",
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
                format!("the word {c} is not supported here"),
                "supported letters: G M N X Y Z I J K R F P L S T O (Q with G64 and M61/M66–M68)",
            ),
        };
        err(
            line,
            w.col,
            GcodeErrorKind::Unsupported,
            w.text,
            message,
            hint,
        )
    }

    /// Records the line's S and T words and M codes (with the words they use) as events.
    fn record_events(&mut self, line: usize, sorted: &LineWords<'_, '_>) {
        let after_moves = self.moves.len();
        if let Some(t) = sorted.args.get('T') {
            self.ext.tool_selected = t.value;
        }
        for c in ['S', 'T'] {
            if let Some(w) = sorted.args.get(c) {
                self.events.push(ProgramEvent {
                    line,
                    code: c.to_string(),
                    words: vec![(c, w.value)],
                    after_moves,
                });
            }
        }
        for (_, w) in &sorted.mcodes {
            let words = m_letters(w.value)
                .chars()
                .filter_map(|c| sorted.args.get(c).map(|a| (c, a.value)))
                .collect();
            self.track_m_state(w.value, &sorted.args);
            let code = if w.value.fract() == 0.0 {
                format!("M{}", w.value as i64)
            } else {
                format!("M{}", w.value)
            };
            self.events.push(ProgramEvent {
                line,
                code,
                words,
                after_moves,
            });
        }
    }

    /// Keeps the spindle, coolant and tool state of M code `m` (for the predefined
    /// parameters `#<_spindle_on>`, `#<_flood>`, `#<_current_tool>`, …).
    fn track_m_state(&mut self, m: f64, args: &Args<'_, '_>) {
        let e = &mut self.ext;
        match m as i64 {
            3 => e.spindle_dir = 1,
            4 => e.spindle_dir = -1,
            5 => e.spindle_dir = 0,
            6 => e.tool_current = e.tool_selected,
            7 => e.mist = true,
            8 => e.flood = true,
            9 => (e.mist, e.flood) = (false, false),
            61 => e.tool_current = args.get('Q').map_or(e.tool_current, |q| q.value),
            _ => {}
        }
    }

    /// Warns about harmless words without effect on the path: S, T, O and the ignored M codes.
    /// With a tool table, T and M6 choose the length `G43` takes: not warned (issue #36).
    fn warn_ignored_words(&mut self, line: usize, sorted: &LineWords<'_, '_>) {
        let table = self.tools.is_some();
        for (c, what) in [
            ('S', "spindle speed"),
            ('T', "tool"),
            ('O', "program number"),
        ] {
            if c == 'T' && table {
                continue;
            }
            if let Some(w) = sorted.args.get(c) {
                self.warn(
                    line,
                    w.col,
                    format!("{} ({what}) ignored: no effect on the path", w.text),
                );
            }
        }
        for (m, w) in &sorted.mcodes {
            if let MCode::Warn(msg) = m {
                if !(table && msg.contains("(tool change)")) {
                    self.warn(line, w.col, msg.clone());
                }
            }
        }
    }

    /// Applies the modal G codes of a line (units, plane, distance mode, G61) and collects
    /// the ones that act on this line only (motion, G04, G10, G54..G59, G64).
    fn apply_modal_gcodes<'l, 'w>(
        &mut self,
        gcodes: &[(GCode, &'l Word<'w>)],
    ) -> LineCommands<'l, 'w> {
        let mut cmd = LineCommands {
            explicit_motion: None,
            dwell: None,
            set_offset: None,
            wcs: None,
            blend: None,
            axis_cmd: None,
            tool: None,
            wcs_col: 0,
        };
        self.ext.machine = false;
        for &(g, w) in gcodes {
            match g {
                GCode::Inch(b) => self.inch = b,
                GCode::Plane(p) => self.plane = p,
                GCode::Absolute(b) => self.absolute = b,
                GCode::Motion(m) => cmd.explicit_motion = Some((m, w)),
                GCode::Dwell => cmd.dwell = Some(w),
                GCode::SetOffset => cmd.set_offset = Some(w),
                GCode::Wcs(k) => {
                    cmd.wcs = Some(k);
                    cmd.wcs_col = w.col;
                }
                GCode::ExactStop => self.mode = Some(PathMode::ExactStop),
                GCode::Blend => cmd.blend = Some(w),
                GCode::NoOp => {}
                GCode::Shift(c) | GCode::Home(c) => cmd.axis_cmd = Some((g, c, w)),
                GCode::Machine => self.ext.machine = true,
                GCode::ToolLength(c) => cmd.tool = Some((c, w)),
                GCode::ArcAbsolute(b) => self.ext.arc_absolute = b,
                GCode::Retract(b) => self.ext.retract_initial = b,
                GCode::CancelCycle => {
                    self.motion = None;
                    self.ext.cycle_z0 = None;
                }
                GCode::FeedMode(m) => self.ext.feed_mode = m,
            }
        }
        cmd
    }

    /// Sets the modal feed from the F word (program units per minute; must be positive).
    fn apply_feed(&mut self, line: usize, f: Option<&Word<'_>>) -> Result<(), GcodeError> {
        if let Some(f) = f {
            if f.value <= 0.0 {
                return Err(err(
                    line,
                    f.col,
                    GcodeErrorKind::InvalidValue,
                    f.text,
                    "the feed must be positive",
                    "give F in mm/min (G21) or in/min (G20), e.g. F3000",
                ));
            }
            self.feed = Some(f.value);
        }
        Ok(())
    }

    /// G64: selects blending, with the path tolerance from P (unless P belongs to G04 / G10).
    fn apply_blend(
        &mut self,
        line: usize,
        cmd: &LineCommands<'_, '_>,
        args: &Args<'_, '_>,
    ) -> Result<(), GcodeError> {
        if cmd.blend.is_some() {
            let tolerance = match args.get('P') {
                Some(p) if cmd.dwell.is_none() && cmd.set_offset.is_none() => {
                    if p.value < 0.0 {
                        return Err(err(
                            line,
                            p.col,
                            GcodeErrorKind::InvalidValue,
                            p.text,
                            "the G64 path tolerance must not be negative",
                            "give the largest corner deviation in program units, e.g. G64 P0.05",
                        ));
                    }
                    Some(p.value * self.scale())
                }
                _ => None,
            };
            self.mode = Some(PathMode::Blend { tolerance });
            self.ext.merge_q = match args.get('Q') {
                Some(q) if q.value > 0.0 => Some(q.value * self.scale()),
                _ => None,
            };
            let r_of_motion = cmd
                .explicit_motion
                .is_some_and(|(m, _)| matches!(m, Motion::Cw | Motion::Ccw | Motion::Cycle(_)));
            if let (Some(r), false) = (args.get('R'), r_of_motion) {
                self.warn(
                    line,
                    r.col,
                    format!(
                        "{} (G64 R: LinuxCNC's planner selection) ignored: the robot's planner is chosen by the scenario ([timing])",
                        r.text
                    ),
                );
            }
        }
        Ok(())
    }

    /// Rejects argument words the line's command does not use (see [`Self::used_letters`]).
    fn check_unused_args(
        line: usize,
        cmd: &LineCommands<'_, '_>,
        motion_mode: Option<Motion>,
        args: &Args<'_, '_>,
        mletters: &str,
    ) -> Result<(), GcodeError> {
        let used = Self::used_letters(cmd, motion_mode, mletters);
        for (k, c) in ARG_LETTERS.chars().enumerate() {
            if let (Some(w), false) = (args.0[k], used[k]) {
                let (message, hint) = match c {
                    'X' | 'Y' | 'Z' if cmd.dwell.is_some() => (
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
                        "P is only used by G04 (dwell), G10 and G64 here".to_string(),
                        "remove P (G64 P<tolerance> sets the corner tolerance; arcs with several turns are not supported: program each turn)",
                    ),
                    'L' => ("L is only used by G10 L2".to_string(), "remove the L word"),
                    'D' | 'E' | 'H' | 'Q' => return Err(Self::unsupported_letter(line, w)),
                    '@' | '^' => (
                        format!("{c} (polar coordinate) is only used by G00–G03"),
                        "write the move with G01 @distance ^angle, or remove the word",
                    ),
                    _ => (format!("{c} is not used here"), "remove the word"),
                };
                return Err(err(
                    line,
                    w.col,
                    GcodeErrorKind::Conflict,
                    w.text,
                    message,
                    hint,
                ));
            }
        }
        Ok(())
    }

    /// Which argument letters (indexed as [`ARG_LETTERS`]) this line's command uses:
    /// F S T O always, P for G64, P X for G04, L P X Y Z for G10, else X Y Z for a motion
    /// (and I J K R for an arc).
    fn used_letters(
        cmd: &LineCommands<'_, '_>,
        motion_mode: Option<Motion>,
        mletters: &str,
    ) -> [bool; N_ARGS] {
        let mut used = [false; N_ARGS];
        for c in ['F', 'S', 'T', 'O', '$'] {
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
        use_letters(mletters);
        if cmd.blend.is_some() && cmd.dwell.is_none() && cmd.set_offset.is_none() {
            use_letters("PQR");
        }
        match cmd.tool {
            Some((430, _)) => use_letters("H"),
            Some((431, _)) => use_letters("Z"),
            _ => {}
        }
        if cmd.axis_cmd.is_some() {
            use_letters("XYZ");
            return used;
        }
        if cmd.dwell.is_some() && cmd.explicit_motion.is_none() {
            use_letters("PX");
        } else if cmd.set_offset.is_some() {
            use_letters("LPXYZR");
        } else if let Some(m) = motion_mode {
            if cmd.dwell.is_some() {
                use_letters("P");
            }
            use_letters("XYZ@^");
            if matches!(m, Motion::Cw | Motion::Ccw) {
                use_letters("IJKR");
            }
            if matches!(m, Motion::Cycle(_)) {
                use_letters("RQPL");
            }
        }
        used
    }

    /// G04: a dwell of P (or X) seconds; a positive one becomes a dwell move.
    fn dwell(
        &mut self,
        line: usize,
        line_text: &str,
        g4: &Word<'_>,
        args: &Args<'_, '_>,
        motion_on_line: bool,
    ) -> Result<(), GcodeError> {
        let w = Self::dwell_time(line, line_text, g4, args, motion_on_line)?;
        if w.value > 0.0 {
            if let (None, Some(p0)) = (self.pos, self.initial_tip()) {
                self.begin_at(p0, line);
            }
            if self.pos.is_none() {
                return Err(err(
                    line,
                    g4.col,
                    GcodeErrorKind::StartPoint,
                    line_text,
                    "dwell before the start point is known",
                    "start the program with G00 X.. Y.. Z..",
                ));
            }
            self.moves.push(Move {
                line,
                kind: MoveKind::Dwell { seconds: w.value },
                tool_length: self.tool_length,
            });
        }
        Ok(())
    }

    /// G04's time word: P, or X when no motion shares the line; one of them, >= 0.
    fn dwell_time<'l, 'w>(
        line: usize,
        line_text: &str,
        g4: &Word<'_>,
        args: &Args<'l, 'w>,
        motion_on_line: bool,
    ) -> Result<&'l Word<'w>, GcodeError> {
        use GcodeErrorKind::*;
        let p = args.get('P');
        let x = args.get('X').filter(|_| !motion_on_line);
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
        Ok(w)
    }

    /// Executes the line's motion in mode `m` if the line gives coordinates (or, for an arc,
    /// a centre); errors point at the motion word, else at the first coordinate word.
    fn line_motion(
        &mut self,
        line: usize,
        line_text: &str,
        words: &[Word<'_>],
        cmd: &LineCommands<'_, '_>,
        m: Motion,
        args: &Args<'_, '_>,
    ) -> Result<(), GcodeError> {
        let has = |c| args.get(c).is_some();
        let axes = has('X') || has('Y') || has('Z') || has('@') || has('^');
        let centre = has('I') || has('J') || has('K') || has('R');
        let is_arc = matches!(m, Motion::Cw | Motion::Ccw);
        if axes || (is_arc && centre) {
            let anchor = cmd
                .explicit_motion
                .map(|(_, w)| w.col)
                .or_else(|| {
                    words
                        .iter()
                        .find(|w| "XYZIJKR".contains(w.letter))
                        .map(|w| w.col)
                })
                .unwrap_or(1);
            self.motion(line, anchor, line_text, m, args)?;
        }
        Ok(())
    }

    pub(super) fn set_offset(
        &mut self,
        line: usize,
        g10: &Word<'_>,
        args: &Args<'_, '_>,
    ) -> Result<(), GcodeError> {
        let arg = |c| args.get(c);
        let l20 = Self::g10_is_l20(line, g10, args)?;
        let k = self.g10_offset_index(line, g10, args)?;
        if k == 0 && self.p1_from_options {
            self.p1_from_options = false;
            if self.origin_given {
                self.warn(
                    line,
                    g10.col,
                    "the program sets the G54 offset itself (G10 L2 P1): the part origin given with the reading options is not used",
                );
            }
            self.offsets[0] = [0.0; 3];
        }
        if let (Some(r), Some(rot)) = (arg('R'), self.ext.rotation.get_mut(k)) {
            *rot = r.value;
        }
        let theta = self.ext.rotation.get(k).copied().unwrap_or(0.0);
        if l20 && theta != 0.0 {
            self.set_offset_l20_rotated(k, args);
            return Ok(());
        }
        let scale = self.scale();
        let here = self.here();
        let g92 = self.ext.g92;
        for (axis, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if let (Some(w), Some(o)) = (arg(c), self.offsets.get_mut(k)) {
                // L20: the offset that makes the current point read as the given value.
                o[axis] = if l20 {
                    here[axis] - w.value * scale - g92[axis]
                } else {
                    w.value * scale
                };
            }
        }
        Ok(())
    }

    /// G10's P: the work offset it sets (P1..P6: G54..G59, P0: the active one).
    fn g10_offset_index(
        &self,
        line: usize,
        g10: &Word<'_>,
        args: &Args<'_, '_>,
    ) -> Result<usize, GcodeError> {
        use GcodeErrorKind::*;
        let p = args.get('P').ok_or_else(|| {
            err(
                line,
                g10.col,
                Missing,
                g10.text,
                "G10 L2 without P",
                "P1..P6 selects the work offset of G54..G59",
            )
        })?;
        if !(0.0..=6.0).contains(&p.value) || p.value.fract() != 0.0 {
            return Err(err(
                line,
                p.col,
                InvalidValue,
                p.text,
                "G10 L2 needs P1..P6 (or P0)",
                "P1..P6 selects the work offset of G54..G59, P0 the active one",
            ));
        }
        Ok(if p.value == 0.0 {
            self.wcs
        } else {
            p.value as usize - 1
        })
    }

    /// G10's L: L2 (the offset itself) or L20 (the offset that makes the current point read
    /// as the given value); R (the rotation about Z) only with L2. Returns whether L20.
    fn g10_is_l20(line: usize, g10: &Word<'_>, args: &Args<'_, '_>) -> Result<bool, GcodeError> {
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
            Some(l) if l.value != 2.0 && l.value != 20.0 => {
                return Err(err(
                    line,
                    l.col,
                    Unsupported,
                    l.text,
                    format!("G10 {} is not supported", l.text),
                    "only G10 L2 / L20 Pn X Y Z (work offsets of G54..G59) are supported: there is no tool table",
                ))
            }
            Some(_) => {}
        }
        // LinuxCNC's G10 L2 R: the rotation of the coordinate system about Z (not with L20).
        let l20 = arg('L').is_some_and(|l| l.value == 20.0);
        if let (Some(r), true) = (arg('R'), l20) {
            return Err(err(
                line,
                r.col,
                Conflict,
                r.text,
                "R is not allowed in G10 L20 (as in LinuxCNC)",
                "set the rotation with G10 L2 Pn R<degrees>, then the origin with G10 L20",
            ));
        }
        Ok(l20)
    }

    /// Selects work offset `k` (G54 + k); warns once when the origin option, which sets
    /// G54 only, was given and the program selects another.
    fn select_wcs(&mut self, line: usize, k: usize, cmd: &LineCommands<'_, '_>) {
        self.wcs = k;
        if k != 0 && self.origin_given && self.p1_from_options && !self.warned_wcs {
            self.warned_wcs = true;
            let o = self.offsets.get(k).copied().unwrap_or([0.0; 3]);
            let col = cmd.wcs_col;
            self.warn(
                line,
                col,
                format!(
                    "G{} selected: the part origin given with the reading options is the G54 offset and does not apply; G{}'s offset is ({:.3}, {:.3}, {:.3}) mm (set it with G10 L2 P{} or remove the G{})",
                    54 + k,
                    54 + k,
                    o[0] * 1e3,
                    o[1] * 1e3,
                    o[2] * 1e3,
                    k + 1,
                    54 + k
                ),
            );
        }
    }

    pub(super) fn motion(
        &mut self,
        line: usize,
        col: usize,
        line_text: &str,
        mode: Motion,
        args: &Args<'_, '_>,
    ) -> Result<(), GcodeError> {
        if self.motion_columns.last().is_none_or(|&(l, _)| l != line) {
            self.motion_columns.push((line, col));
        }
        let block = MotionBlock {
            line,
            col,
            line_text,
            mode,
            args,
        };
        let Some(pos) = self.pos else {
            let full = matches!(mode, Motion::Rapid | Motion::Linear)
                && self.absolute
                && ['X', 'Y', 'Z'].iter().all(|&c| args.get(c).is_some());
            if let (Some(p0), false) = (self.initial_tip(), full) {
                // The tool is where the options say (the robot's start pose): move from there.
                self.begin_at(p0, line);
                return self.motion(line, col, line_text, mode, args);
            }
            // The first motion defines the start point.
            return self.first_motion(&block);
        };
        if let Motion::Cycle(n) = mode {
            return self.cycle(line, col, line_text, n, args);
        }
        let target = match self.polar_target(line, pos, args)? {
            Some(p) => p,
            None => self.motion_target(pos, args),
        };
        let segment = match mode {
            Motion::Rapid | Motion::Linear | Motion::Cycle(_) => {
                if (target - pos).norm() <= MIN_MOVE_LENGTH && self.ext.machine_at.is_none() {
                    self.warn(line, col, "zero-length move skipped");
                    return Ok(());
                }
                self.push_line(line, pos, target, mode == Motion::Rapid);
                return Ok(());
            }
            Motion::Cw | Motion::Ccw => self.arc_segment(&block, pos, target)?,
        };
        self.push_arc(line, pos, segment);
        Ok(())
    }

    /// Appends the arc `segment` from `pos` (after a straight move to `pos` when a
    /// G74/G84 in G18/G19 left the tool elsewhere).
    fn push_arc(&mut self, line: usize, pos: Vector3<f64>, segment: Segment) {
        if let Some(m) = self.ext.machine_at {
            // After G74/G84 in G18/G19 the tool is elsewhere: a straight move to the arc.
            self.push_line(line, m, pos, true);
        }
        let feed = self.move_feed(false, segment.length());
        self.ext.merged.clear();
        self.pos = Some(segment.end());
        self.moves.push(Move {
            line,
            kind: MoveKind::Path {
                segment,
                feed,
                mode: self.mode,
            },
            tool_length: self.tool_length,
        });
    }

    /// Starts the program at `p` (the tool position before the program), at `line`.
    pub(super) fn begin_at(&mut self, p: Vector3<f64>, line: usize) {
        self.pos = Some(p);
        self.start = p;
        self.start_line = line;
        self.start_tool_length = self.tool_length;
    }

    /// The first motion: sets the start point, which must be given in absolute
    /// coordinates with all of X, Y and Z, by a straight move (G00/G01).
    fn first_motion(&mut self, b: &MotionBlock<'_, '_, '_>) -> Result<(), GcodeError> {
        use GcodeErrorKind::*;
        let (line, col, line_text) = (b.line, b.col, b.line_text);
        let arg = |c| b.args.get(c);
        let scale = self.scale();
        let xyz = [arg('X'), arg('Y'), arg('Z')];
        if matches!(b.mode, Motion::Cw | Motion::Ccw) {
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
        let given = xyz.map(|w| Some(w.map_or(0.0, |w| w.value) * scale));
        let p = self.place(Vector3::zeros(), given);
        self.pos = Some(p);
        self.start = p;
        self.start_line = line;
        self.start_tool_length = self.tool_length;
        Ok(())
    }

    /// The programmed end point of a move from `pos`: each given coordinate in the active
    /// work offset (G90) or relative to `pos` (G91), the others unchanged.
    pub(super) fn motion_target(&self, pos: Vector3<f64>, args: &Args<'_, '_>) -> Vector3<f64> {
        let scale = self.scale();
        let xyz = ['X', 'Y', 'Z'].map(|c| args.get(c).map(|w| w.value * scale));
        if self.absolute {
            self.place(pos, xyz)
        } else {
            self.shift_by(pos, xyz)
        }
    }

    /// The arc (G02/G03) from `pos` to `target`, its centre given by R or by I/J/K; warns
    /// if its end had to be moved onto the circle.
    fn arc_segment(
        &mut self,
        b: &MotionBlock<'_, '_, '_>,
        pos: Vector3<f64>,
        target: Vector3<f64>,
    ) -> Result<Segment, GcodeError> {
        let (line, col, line_text, mode) = (b.line, b.col, b.line_text, b.mode);
        let arg = |c| b.args.get(c);
        let dir = if mode == Motion::Cw {
            ArcDirection::Clockwise
        } else {
            ArcDirection::CounterClockwise
        };
        if self.rotation() != 0.0 && self.plane != Plane::XY {
            return Err(err(
                line,
                col,
                GcodeErrorKind::Unsupported,
                line_text,
                format!(
                    "an arc in the {} plane of a rotated coordinate system (G10 L2 R) is not supported",
                    self.plane.gcode()
                ),
                "program arcs of a rotated system in G17, or rotate the program in the CAM system",
            ));
        }
        let seg = if let Some(r) = arg('R') {
            if let Some(w) = arg('I').or(arg('J')).or(arg('K')) {
                return Err(err(
                    line,
                    w.col,
                    GcodeErrorKind::Conflict,
                    line_text,
                    "an arc with both R and I/J/K",
                    "give the centre either by R or by I/J/K offsets",
                ));
            }
            self.arc_by_radius(line, col, line_text, mode, pos, target, r, dir)?
        } else {
            self.arc_by_centre(line, col, line_text, mode, pos, target, b.args, dir)?
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
        Ok(seg)
    }
}

/// The words of one line, sorted by kind (see [`Interpreter::line`]).
struct LineWords<'l, 'w> {
    gcodes: Vec<(GCode, &'l Word<'w>)>,
    mcodes: Vec<(MCode, &'l Word<'w>)>,
    args: Args<'l, 'w>,
}

/// The G codes of one line that act on that line only (modal settings are applied at once).
struct LineCommands<'l, 'w> {
    explicit_motion: Option<(Motion, &'l Word<'w>)>,
    dwell: Option<&'l Word<'w>>,
    set_offset: Option<&'l Word<'w>>,
    wcs: Option<usize>,
    blend: Option<&'l Word<'w>>,
    /// G92 family, G52, G28/G30 (+.1): the code, its tenths and its word.
    axis_cmd: Option<(GCode, u16, &'l Word<'w>)>,
    /// G43 / G43.1 / G49.
    tool: Option<(u16, &'l Word<'w>)>,
    wcs_col: usize,
}

impl LineCommands<'_, '_> {
    /// Rejects a motion on the same line as G10 (both use the axis words; G04 uses none, so
    /// a motion may follow it on its line, as in LinuxCNC).
    fn check_non_modal_conflict(&self, line: usize, line_text: &str) -> Result<(), GcodeError> {
        if let (Some(nm), Some((_, mw))) = (self.set_offset, self.explicit_motion) {
            return Err(err(
                line,
                mw.col,
                GcodeErrorKind::Conflict,
                line_text,
                format!("{} and {} on one line", nm.text, mw.text),
                "put the motion on its own line",
            ));
        }
        Ok(())
    }
}

/// One motion block as [`Interpreter::motion`] executes it: where it is (line, column of
/// the anchor word, text), its motion mode and its argument words.
struct MotionBlock<'a, 'l, 'w> {
    line: usize,
    col: usize,
    line_text: &'a str,
    mode: Motion,
    args: &'a Args<'l, 'w>,
}
