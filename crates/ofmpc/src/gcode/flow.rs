//! Control flow of rs274ngc's O-words in one file (LinuxCNC's "O codes"): `sub/endsub/call/
//! return`, `if/elseif/else/endif`, `while/endwhile`, `do/while`, `repeat/endrepeat`,
//! `break/continue`; parameter settings and messages; and the walk over the lines with a step
//! limit, so that an endless loop ends with an error naming the loop.

use super::expr::{
    is_system_parameter, EvalError, Expr, Params, P_CALL_LEVEL, P_LINE, P_VALUE, P_VALUE_RETURNED,
};
use super::interpreter::Interpreter;
use super::lexer::{Block, Lexed, MessageKind, OKind, OStmt, Target, Value, Word};
use super::program::{err, GcodeError, GcodeErrorKind, ProgramMessage, MAX_WORD_VALUE};
use super::text::escape;
use std::collections::HashMap;

/// Lines a program may execute beyond its own length before the reader stops it as an
/// endless loop (10 million: well under a second of reading).
pub const DEFAULT_MAX_STEPS: usize = 10_000_000;

/// Deepest nesting of subroutine calls.
pub(super) const MAX_CALL_DEPTH: usize = 100;

const NONE: usize = usize::MAX;

/// One line of the source as read.
pub(super) struct SourceLine<'a> {
    pub(super) no: usize,
    pub(super) raw: &'a str,
    pub(super) lexed: Result<Lexed<'a>, GcodeError>,
}

/// The links between the O-word statements of a file (indices into the lines).
pub(super) struct Links {
    /// `if`/`elseif`: the next branch; `endwhile`/`endrepeat`/closing `while` of a `do`: the
    /// loop's start; `break`/`continue`: the loop's start.
    next: Vec<usize>,
    /// `if`/`elseif`/`else`: the `endif`; loop starts: their end statement; `sub`: `endsub`.
    end: Vec<usize>,
    /// The `while` that closes a `do`.
    do_while: Vec<bool>,
    /// Subroutines by label.
    pub(super) subs: HashMap<String, usize>,
}

fn o_stmt<'s, 'a>(l: &'s SourceLine<'a>) -> Option<&'s OStmt<'a>> {
    match &l.lexed {
        Ok(Lexed::Block(b)) if !b.delete => b.o.as_ref(),
        _ => None,
    }
}

fn structure_error(l: &SourceLine<'_>, o: &OStmt<'_>, message: String, hint: &str) -> GcodeError {
    err(l.no, o.col, GcodeErrorKind::Syntax, o.text, message, hint)
}

/// An open structure while [`link`] walks the file: kind, label, line index, branches.
struct Open {
    kind: OKind,
    label: String,
    at: usize,
    branches: Vec<usize>,
}

/// Matches the O-word statements of `lines` (see [`Links`]).
fn link(lines: &[SourceLine<'_>]) -> Result<Links, GcodeError> {
    let n = lines.len();
    let mut k = Links {
        next: vec![NONE; n],
        end: vec![NONE; n],
        do_while: vec![false; n],
        subs: HashMap::new(),
    };
    let mut stack: Vec<Open> = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        if let Some(o) = o_stmt(l) {
            link_one(lines, &mut stack, &mut k, i, o).map_err(|e| opener_error(lines, i, e))?;
        }
    }
    if let Some(t) = stack.pop() {
        let l = &lines[t.at];
        let closer = match t.kind {
            OKind::If => "endif",
            OKind::While => "endwhile",
            OKind::Do => "while",
            OKind::Repeat => "endrepeat",
            _ => "endsub",
        };
        if let Some(o) = o_stmt(l) {
            let m = format!("o{} {} is never closed", t.label, t.kind.name());
            let e = structure_error(l, o, m, &format!("close it with o{} {closer}", t.label));
            // A closer that could not be read is the real cause: report it at its line.
            return Err(lines[t.at..]
                .iter()
                .find_map(|l| match &l.lexed {
                    Err(le) if looks_like_o_word(l.raw) => Some(le.clone()),
                    _ => None,
                })
                .unwrap_or(e));
        }
    }
    Ok(k)
}

/// The error to report when linking fails at line index `i`: an O-word line before it that
/// could not be read (its statement is missing from the structure, so the closer seems
/// unmatched) is the real cause, reported at its own line; otherwise `e` itself.
fn opener_error(lines: &[SourceLine<'_>], i: usize, e: GcodeError) -> GcodeError {
    lines[..i]
        .iter()
        .find_map(|l| match &l.lexed {
            Err(le) if looks_like_o_word(l.raw) => Some(le.clone()),
            _ => None,
        })
        .unwrap_or(e)
}

/// A line whose first word (after an optional block delete `/` and line number `N…`) is an
/// O-word.
fn looks_like_o_word(raw: &str) -> bool {
    let s = raw.trim_start().trim_start_matches('/').trim_start();
    let s = match s.strip_prefix(['n', 'N']) {
        Some(rest) => rest.trim_start_matches(|c: char| c.is_ascii_digit() || c == '.'),
        None => s,
    };
    s.trim_start().starts_with(['o', 'O'])
}

/// Links the O-word statement `o` at line index `i` (see [`link`]).
fn link_one(
    lines: &[SourceLine<'_>],
    stack: &mut Vec<Open>,
    k: &mut Links,
    i: usize,
    o: &OStmt<'_>,
) -> Result<(), GcodeError> {
    let l = &lines[i];
    let open = |kind| Open {
        kind,
        label: o.label.clone(),
        at: i,
        branches: vec![i],
    };
    check_computed_label(l, o)?;
    let top_is = |s: &[Open], kinds: &[OKind]| {
        s.last()
            .is_some_and(|t| kinds.contains(&t.kind) && t.label == o.label)
    };
    match o.kind {
        OKind::Sub => {
            if let Some(t) = stack.last() {
                let m = format!(
                    "o{} sub inside o{} {} (line {})",
                    o.label,
                    t.label,
                    t.kind.name(),
                    lines[t.at].no
                );
                return Err(structure_error(
                    l,
                    o,
                    m,
                    "define subroutines at the top level of the file",
                ));
            }
            if let Some(&prev) = k.subs.get(&o.label) {
                let m = format!(
                    "subroutine o{} defined twice (first at line {})",
                    o.label, lines[prev].no
                );
                return Err(structure_error(
                    l,
                    o,
                    m,
                    "give each subroutine its own name",
                ));
            }
            k.subs.insert(o.label.clone(), i);
            stack.push(open(OKind::Sub));
        }
        OKind::If | OKind::Do | OKind::Repeat => stack.push(open(o.kind)),
        OKind::While if top_is(stack, &[OKind::Do]) => {
            let t = stack.pop().map_or(NONE, |t| t.at);
            k.end[t] = i;
            k.next[i] = t;
            k.do_while[i] = true;
        }
        OKind::While => stack.push(open(OKind::While)),
        OKind::Elseif | OKind::Else if top_is(stack, &[OKind::If]) => {
            if let Some(t) = stack.last_mut() {
                t.branches.push(i);
            }
        }
        OKind::Endif if top_is(stack, &[OKind::If]) => {
            let t = stack.pop().map_or(Vec::new(), |t| t.branches);
            for w in t.windows(2) {
                k.next[w[0]] = w[1];
            }
            for &b in &t {
                k.end[b] = i;
            }
            if let Some(&last) = t.last() {
                k.next[last] = i;
            }
        }
        OKind::Endwhile if top_is(stack, &[OKind::While]) => close_loop(stack, k, i),
        OKind::Endrepeat if top_is(stack, &[OKind::Repeat]) => close_loop(stack, k, i),
        OKind::Endsub if top_is(stack, &[OKind::Sub]) => close_loop(stack, k, i),
        OKind::Break | OKind::Continue | OKind::Return => link_jump(l, stack, k, i, o)?,
        OKind::Call | OKind::Title => {}
        _ => {
            let m = match stack.last() {
                Some(t) => format!(
                    "o{} {} does not close o{} {} (line {})",
                    o.label,
                    o.kind.name(),
                    t.label,
                    t.kind.name(),
                    lines[t.at].no
                ),
                None => format!(
                    "o{} {} without its opening statement",
                    o.label,
                    o.kind.name()
                ),
            };
            return Err(structure_error(l, o, m, "each if/while/do/repeat/sub is closed by its own endif/endwhile/while/endrepeat/endsub with the same label"));
        }
    }
    Ok(())
}

/// Links `break`/`continue` to their loop and checks that `return` is in its subroutine.
fn link_jump(
    l: &SourceLine<'_>,
    stack: &[Open],
    k: &mut Links,
    i: usize,
    o: &OStmt<'_>,
) -> Result<(), GcodeError> {
    match o.kind {
        OKind::Break | OKind::Continue => {
            let lp = stack.iter().rev().find(|t| {
                t.label == o.label && matches!(t.kind, OKind::While | OKind::Do | OKind::Repeat)
            });
            match lp {
                Some(t) => k.next[i] = t.at,
                None => {
                    let m = format!("o{} {} outside a loop o{}", o.label, o.kind.name(), o.label);
                    return Err(structure_error(l, o, m, "break and continue carry the label of the loop (while, do, repeat) they are in"));
                }
            }
        }
        OKind::Return if !stack.iter().any(|t| t.kind == OKind::Sub) => {
            let m = format!("o{} return outside the subroutine o{}", o.label, o.label);
            return Err(structure_error(
                l,
                o,
                m,
                "return carries the label of its subroutine",
            ));
        }
        _ => {}
    }
    Ok(())
}

/// Rejects a computed label (`o[#1] sub`) on anything but a call: the statements are linked
/// before the program runs.
fn check_computed_label(l: &SourceLine<'_>, o: &OStmt<'_>) -> Result<(), GcodeError> {
    if o.label_expr.is_some() && o.kind != OKind::Call {
        return Err(err(
            l.no,
            o.col,
            GcodeErrorKind::Unsupported,
            o.text,
            format!(
                "a computed O-word label (o{}) is read for call only, not for {}",
                o.label,
                o.kind.name()
            ),
            "write the label as a number or <name>, e.g. o100 sub",
        ));
    }
    Ok(())
}

fn close_loop(stack: &mut Vec<Open>, k: &mut Links, i: usize) {
    if let Some(t) = stack.pop() {
        k.end[t.at] = i;
        k.next[i] = t.at;
    }
}

/// A subroutine call in progress.
pub(super) struct Frame {
    pub(super) return_to: usize,
    pub(super) saved: [f64; 30],
    pub(super) repeats: usize,
    /// A numbered subprogram called by M98 ([`super::fanuc`]): its `O<n>` line and the
    /// runs left (this one included); `None`: an O-word subroutine.
    pub(super) numbered: Option<(usize, u64)>,
}

/// Walks the lines: executes blocks, follows O-words, stops at the end of the program.
pub(super) struct Runner<'s, 'a> {
    pub(super) lines: &'s [SourceLine<'a>],
    pub(super) links: Links,
    pub(super) params: Params,
    pub(super) frames: Vec<Frame>,
    /// Active `repeat` loops: the statement and the iterations left.
    pub(super) repeats: Vec<(usize, f64)>,
    /// The last loop that jumped back (named by the step-limit error).
    pub(super) last_loop: usize,
    /// Numbered subprograms `O<n>` (M98/M99) by number.
    pub(super) numbered: HashMap<u64, Vec<usize>>,
    warned_delete: bool,
    /// The program reads parameters (has a `#`): the predefined ones are kept up to date.
    uses_parameters: bool,
}

impl<'s, 'a> Runner<'s, 'a> {
    pub(super) fn new(lines: &'s [SourceLine<'a>]) -> Result<Self, GcodeError> {
        Ok(Runner {
            lines,
            links: link(lines)?,
            params: Params::default(),
            frames: Vec::new(),
            repeats: Vec::new(),
            last_loop: NONE,
            numbered: numbered_programs(lines),
            warned_delete: false,
            uses_parameters: lines.iter().any(|l| l.raw.contains('#')),
        })
    }

    /// Runs the program through `it`; returns the index of the line after the last one
    /// executed (where ignored text starts).
    pub(super) fn run(
        &mut self,
        it: &mut Interpreter,
        max_steps: usize,
    ) -> Result<usize, GcodeError> {
        let limit = self.lines.len().saturating_add(max_steps);
        let mut steps = 0usize;
        let mut pc = 0;
        let mut last = 0;
        while pc < self.lines.len() && !it.ended {
            steps += 1;
            if steps > limit {
                return Err(self.step_limit(pc, max_steps));
            }
            if let Some((what, max)) = it.over_budget() {
                return Err(self.budget_error(last, what, max));
            }
            last = pc;
            let l = &self.lines[pc];
            if self.uses_parameters {
                self.params.predefined[P_LINE] = l.no as f64;
                it.predefined(&mut self.params.predefined);
                it.system_parameters(&mut self.params.numbered);
            }
            let b = match &l.lexed {
                Err(e) => return Err(e.clone()),
                Ok(Lexed::Percent) => {
                    if it.seen_content {
                        it.ended = true;
                    } else {
                        it.seen_content = true;
                    }
                    pc += 1;
                    continue;
                }
                Ok(Lexed::Block(b)) => b,
            };
            if b.delete {
                self.skip_deleted(it, l.no);
                pc += 1;
                continue;
            }
            if let Some(o) = &b.o {
                it.seen_content = true;
                pc = self.o_word(it, pc, o)?;
                continue;
            }
            if !b.is_empty() {
                it.seen_content = true;
                if let Some(next) = self.fanuc(it, pc, b)? {
                    pc = next;
                    continue;
                }
                self.block(it, l, b)?;
            }
            pc += 1;
        }
        if let Some((what, max)) = it.over_budget() {
            return Err(self.budget_error(last, what, max));
        }
        Ok(pc)
    }

    /// The error for a program whose output passed its budget at the line of index `at`.
    fn budget_error(&self, at: usize, what: &str, max: usize) -> GcodeError {
        let l = &self.lines[at.min(self.lines.len().saturating_sub(1))];
        err(
            l.no,
            1,
            GcodeErrorKind::InvalidValue,
            &crate::input::quote(l.raw.trim(), crate::input::QUOTE_CHARS),
            match what.strip_prefix("bytes of ") {
                Some(rest) => format!(
                    "the program makes more than {} MB of {rest} (the limit) by line {}",
                    max >> 20,
                    l.no
                ),
                None => format!(
                    "the program makes more than {max} {what} (the limit) by line {}",
                    l.no
                ),
            },
            if what == "moves" {
                "check this line's repeats (L), peck depth (Q) and the loops around it; split the \
                 program into parts of fewer moves"
            } else {
                "check the loops around this line (how often they repeat it); split the program \
                 into parts, or move the statement out of the loop"
            },
        )
    }

    /// A block-delete line (`/`): skipped, with a warning the first time.
    fn skip_deleted(&mut self, it: &mut Interpreter, no: usize) {
        if !self.warned_delete {
            self.warned_delete = true;
            it.warn(
                no,
                1,
                "block delete: lines starting with `/` are skipped (LinuxCNC's default)",
            );
        }
        it.seen_content = true;
    }

    fn step_limit(&self, pc: usize, max_steps: usize) -> GcodeError {
        let at = if self.last_loop == NONE {
            pc
        } else {
            self.last_loop
        };
        let l = &self.lines[at];
        let (col, text, name) = match o_stmt(l) {
            Some(o) => (
                o.col,
                o.text.to_string(),
                format!("the loop o{} {} (line {})", o.label, o.kind.name(), l.no),
            ),
            None => (1, l.raw.trim().to_string(), format!("line {}", l.no)),
        };
        err(
            l.no,
            col,
            GcodeErrorKind::InvalidValue,
            &text,
            format!("the program ran {max_steps} lines more than it has (the limit on executed lines): {name} does not end or repeats more than that"),
            "check the loop's condition (an endless loop), or split the program",
        )
    }

    pub(super) fn eval(
        &self,
        l: &SourceLine<'_>,
        col: usize,
        text: &str,
        e: &Expr,
    ) -> Result<f64, GcodeError> {
        self.params
            .eval(e)
            .map_err(|e| eval_error(l.no, col, text, &e))
    }

    /// The condition or count of an O-word (its first `[ ]`), or an error naming it.
    fn arg0(&self, l: &SourceLine<'_>, o: &OStmt<'_>) -> Result<f64, GcodeError> {
        match o.args.first() {
            Some(e) => self.eval(l, o.col, o.text, e),
            None => Err(err(
                l.no,
                o.col,
                GcodeErrorKind::Missing,
                o.text,
                format!("o{} {} without its [condition]", o.label, o.kind.name()),
                "write the condition or count in [ ], e.g. o100 while [#1 LT 10]",
            )),
        }
    }

    /// Executes the O-word at line `pc`; returns the next line.
    fn o_word(
        &mut self,
        it: &mut Interpreter,
        pc: usize,
        o: &OStmt<'_>,
    ) -> Result<usize, GcodeError> {
        let l = &self.lines[pc];
        let k = &self.links;
        Ok(match o.kind {
            OKind::Sub => k.end[pc] + 1,
            OKind::If => self.branch(pc)?,
            OKind::Elseif | OKind::Else => k.end[pc] + 1,
            OKind::Endif | OKind::Do => pc + 1,
            OKind::Title => {
                let text = format!("o{} (program name) ignored: no effect on the path", o.label);
                it.warn(l.no, o.col, text);
                pc + 1
            }
            OKind::While if k.do_while[pc] => {
                if self.arg0(l, o)? != 0.0 {
                    self.last_loop = pc;
                    k.next[pc] + 1
                } else {
                    pc + 1
                }
            }
            OKind::While => {
                if self.arg0(l, o)? != 0.0 {
                    pc + 1
                } else {
                    k.end[pc] + 1
                }
            }
            OKind::Endwhile => {
                self.last_loop = k.next[pc];
                k.next[pc]
            }
            OKind::Repeat | OKind::Endrepeat | OKind::Break | OKind::Continue => {
                self.loop_word(pc, o)?
            }
            OKind::Call => self.call(pc, o)?,
            OKind::Return | OKind::Endsub => self.ret(it, pc, o)?,
        })
    }

    /// The `repeat` loop's statements and `break`/`continue` (of any loop) at `pc`; returns
    /// the next line to run.
    fn loop_word(&mut self, pc: usize, o: &OStmt<'_>) -> Result<usize, GcodeError> {
        let l = &self.lines[pc];
        let k = &self.links;
        Ok(match o.kind {
            OKind::Repeat => {
                let n = self.arg0(l, o)?.round();
                if n >= 1.0 {
                    self.repeats.push((pc, n));
                    pc + 1
                } else {
                    k.end[pc] + 1
                }
            }
            OKind::Endrepeat => {
                self.last_loop = k.next[pc];
                match self.repeats.last_mut() {
                    Some((_, n)) if *n > 1.0 => {
                        *n -= 1.0;
                        k.next[pc] + 1
                    }
                    _ => {
                        self.repeats.pop();
                        pc + 1
                    }
                }
            }
            OKind::Break => {
                let start = k.next[pc];
                self.repeats.retain(|&(r, _)| r < start);
                k.end[start] + 1
            }
            OKind::Continue => {
                let start = k.next[pc];
                self.last_loop = start;
                match self.lines.get(start).and_then(o_stmt).map(|s| s.kind) {
                    Some(OKind::While) => start,
                    _ => k.end[start],
                }
            }
            // Not one of those (o_word dispatches only them here): the next line.
            _ => pc + 1,
        })
    }

    /// Finds the branch of the `if` at `pc` to run; returns its first line.
    fn branch(&self, pc: usize) -> Result<usize, GcodeError> {
        let mut at = pc;
        loop {
            let l = &self.lines[at];
            let Some(o) = o_stmt(l) else {
                return Ok(at + 1);
            };
            match o.kind {
                OKind::If | OKind::Elseif => {
                    if self.arg0(l, o)? != 0.0 {
                        return Ok(at + 1);
                    }
                    at = self.links.next[at];
                }
                _ => return Ok(at + 1),
            }
        }
    }

    /// The label a call names: its own, or the value of its computed label (an integer,
    /// as LinuxCNC's `read_integer_value`).
    fn call_label(&self, l: &SourceLine<'_>, o: &OStmt<'_>) -> Result<String, GcodeError> {
        let Some(e) = &o.label_expr else {
            return Ok(o.label.clone());
        };
        let v = self.eval(l, o.col, o.text, e)?;
        let r = v.round();
        if (v - r).abs() > 1e-4 || r < 0.0 {
            return Err(err(
                l.no,
                o.col,
                GcodeErrorKind::InvalidValue,
                o.text,
                format!(
                    "the computed O-word label o{} is {v}, not a whole number >= 0",
                    o.label
                ),
                "compute the number of a subroutine, e.g. o[#1 * 100] call with #1 = 2 calls o200",
            ));
        }
        Ok(format!("{r:.0}"))
    }

    fn call(&mut self, pc: usize, o: &OStmt<'_>) -> Result<usize, GcodeError> {
        let l = &self.lines[pc];
        let label = self.call_label(l, o)?;
        let Some(&sub) = self.links.subs.get(&label) else {
            let computed = if o.label_expr.is_some() {
                format!(" (o{} is o{label})", o.label)
            } else {
                String::new()
            };
            return Err(err(
                l.no,
                o.col,
                GcodeErrorKind::Unsupported,
                o.text,
                format!("o{label} call{computed}: no subroutine o{label} sub in this file"),
                if label
                    .parse()
                    .ok()
                    .is_some_and(|n: u64| self.numbered.contains_key(&n))
                {
                    format!("O{label} … M99 is a numbered subprogram: call it with M98 P{label}")
                } else {
                    "subroutines in other files are not read: define it in this file with o… sub … o… endsub".to_string()
                },
            ));
        };
        if self.frames.len() >= MAX_CALL_DEPTH {
            return Err(err(
                l.no,
                o.col,
                GcodeErrorKind::InvalidValue,
                o.text,
                format!("subroutine calls nested deeper than {MAX_CALL_DEPTH}"),
                "check for a subroutine that calls itself without end",
            ));
        }
        let mut args = [0.0; 30];
        for (a, e) in args.iter_mut().zip(&o.args) {
            *a = self.eval(l, o.col, o.text, e)?;
        }
        let mut saved = [0.0; 30];
        saved.copy_from_slice(&self.params.numbered[1..31]);
        self.params.numbered[1..31].copy_from_slice(&args);
        self.params.locals.push(HashMap::new());
        self.frames.push(Frame {
            return_to: pc + 1,
            saved,
            repeats: self.repeats.len(),
            numbered: None,
        });
        self.params.predefined[P_CALL_LEVEL] = self.frames.len() as f64;
        self.last_loop = sub;
        Ok(sub + 1)
    }

    fn ret(&mut self, it: &mut Interpreter, pc: usize, o: &OStmt<'_>) -> Result<usize, GcodeError> {
        let l = &self.lines[pc];
        let value = match o.args.first() {
            Some(e) => Some(self.eval(l, o.col, o.text, e)?),
            None => None,
        };
        if self.frames.last().is_some_and(|f| f.numbered.is_some()) {
            return Err(err(
                l.no,
                o.col,
                GcodeErrorKind::Syntax,
                o.text,
                format!("o{} {} inside a numbered subprogram called by M98", o.label, o.kind.name()),
                "end a numbered subprogram O<n> with M99 (LinuxCNC refuses endsub and return there)",
            ));
        }
        let Some(f) = self.frames.pop() else {
            // endsub reached without a call: LinuxCNC ends the program there.
            it.ended = true;
            return Ok(pc + 1);
        };
        self.params.numbered[1..31].copy_from_slice(&f.saved);
        self.params.locals.pop();
        self.repeats.truncate(f.repeats);
        // LinuxCNC (interp_read.cc, read_o): a return or endsub without a value sets
        // #<_value> to 0 and #<_value_returned> to 0.
        self.params.predefined[P_VALUE] = value.unwrap_or(0.0);
        self.params.predefined[P_VALUE_RETURNED] = f64::from(u8::from(value.is_some()));
        self.params.predefined[P_CALL_LEVEL] = self.frames.len() as f64;
        Ok(f.return_to)
    }

    /// Executes a block: evaluates its words and settings with the parameters as they were
    /// before the line (rs274ngc), sets the parameters, records its messages and runs its
    /// words through the interpreter.
    fn block(
        &mut self,
        it: &mut Interpreter,
        l: &SourceLine<'a>,
        b: &Block<'a>,
    ) -> Result<(), GcodeError> {
        let words = self.evaluated_words(l, b)?;
        self.assign_parameters(l, b)?;
        self.messages(it, l, b);
        if !words.is_empty() {
            it.line(l.no, l.raw, &words)?;
        }
        Ok(())
    }

    /// The words of block `b` with their expressions evaluated (before the block's
    /// parameter assignments take effect).
    fn evaluated_words(
        &self,
        l: &SourceLine<'a>,
        b: &Block<'a>,
    ) -> Result<Vec<Word<'a>>, GcodeError> {
        let mut words: Vec<Word<'a>> = Vec::with_capacity(b.words.len());
        for w in &b.words {
            let value = match &w.value {
                Value::Num(v) => *v,
                Value::Expr(e) => {
                    let v = self.eval(l, w.col, w.text, e)?;
                    if v.abs() > MAX_WORD_VALUE {
                        return Err(err(
                            l.no,
                            w.col,
                            GcodeErrorKind::InvalidValue,
                            w.text,
                            format!("the value {v} is out of range"),
                            format!("numbers must not exceed {MAX_WORD_VALUE:e} in magnitude"),
                        ));
                    }
                    v
                }
            };
            words.push(Word {
                letter: w.letter,
                value,
                col: w.col,
                text: w.text,
            });
        }
        Ok(words)
    }

    /// The parameter assignments of block `b`: every value is evaluated first, then all are
    /// set (LinuxCNC's order).
    fn assign_parameters(&mut self, l: &SourceLine<'a>, b: &Block<'a>) -> Result<(), GcodeError> {
        let mut sets = Vec::with_capacity(b.assigns.len());
        for a in &b.assigns {
            let v = self.eval(l, a.col, a.text, &a.value)?;
            let target = match &a.target {
                Target::Named(n) if Params::predefined_index(n).is_some() => {
                    return Err(read_only(l.no, a.col, a.text, &format!("#<{n}>")));
                }
                Target::Named(n) => Err(n.as_str()),
                Target::Numbered(e) => {
                    let i = self.eval(l, a.col, a.text, e)?;
                    let i = Params::index(i).map_err(|e| eval_error(l.no, a.col, a.text, &e))?;
                    if is_system_parameter(i) {
                        return Err(read_only(l.no, a.col, a.text, &format!("#{i}")));
                    }
                    Ok(i)
                }
            };
            sets.push((target, v));
        }
        for (t, v) in sets {
            match t {
                Ok(i) => self.params.numbered[i] = v,
                Err(n) => self.params.set_named(n, v),
            }
        }
        Ok(())
    }

    /// Records the message comments (`MSG`, `PRINT`, `DEBUG`) of block `b`.
    pub(super) fn messages(&self, it: &mut Interpreter, l: &SourceLine<'_>, b: &Block<'_>) {
        for c in &b.comments {
            let text = match c.kind {
                MessageKind::Msg => c.text.trim().to_string(),
                _ => self.substitute(&c.text),
            };
            it.ext.message_bytes = it.ext.message_bytes.saturating_add(text.len());
            it.messages.push(ProgramMessage {
                line: l.no,
                kind: match c.kind {
                    MessageKind::Msg => "MSG",
                    MessageKind::Print => "PRINT",
                    MessageKind::Debug => "DEBUG",
                },
                text: escape(&text),
            });
        }
    }

    /// `text` with `#n` and `#<name>` replaced by their values, as LinuxCNC's `(PRINT,…)`
    /// and `(DEBUG,…)` (`Interp::convert_param_comment`, interp_convert.cc): `%lf` (six
    /// decimals) until a format in the text changes it for the values after it: `%d` (no
    /// decimals), `%f` (four), `%.Nf` (N, one digit).
    fn substitute(&self, text: &str) -> String {
        let mut out = String::new();
        let mut decimals = 6;
        let mut rest = text;
        while let Some(i) = rest.find(['#', '%']) {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            if rest[i..].starts_with('%') {
                let b = after.as_bytes();
                (decimals, rest) = match b {
                    [b'd', ..] => (0, &after[1..]),
                    [b'f', ..] => (4, &after[1..]),
                    [b'.', d, b'f', ..] if d.is_ascii_digit() => {
                        (usize::from(d - b'0'), &after[3..])
                    }
                    [b'.', ..] => {
                        out.push('.');
                        (decimals, &after[1..])
                    }
                    _ => {
                        out.push('%');
                        (decimals, after)
                    }
                };
                continue;
            }
            if let Some(name) = after.strip_prefix('<').and_then(|a| a.split_once('>')) {
                let key: String = name
                    .0
                    .chars()
                    .filter(|c| !c.is_whitespace())
                    .flat_map(char::to_lowercase)
                    .collect();
                match self.params.named(&key) {
                    Some(v) => out.push_str(&format!("{v:.decimals$}")),
                    None => out.push_str("######"),
                }
                rest = name.1;
                continue;
            }
            let digits = after.len() - after.trim_start_matches(|c: char| c.is_ascii_digit()).len();
            match after[..digits]
                .parse::<f64>()
                .ok()
                .and_then(|v| Params::index(v).ok())
            {
                Some(k) => out.push_str(&format!("{:.decimals$}", self.params.numbered[k])),
                None => out.push('#'),
            }
            rest = &after[digits..];
        }
        out.push_str(rest);
        out.trim().to_string()
    }
}

/// The error for a setting of a predefined parameter (`#<_x>`, `#5220`, …).
fn read_only(line: usize, col: usize, text: &str, name: &str) -> GcodeError {
    err(
        line,
        col,
        GcodeErrorKind::InvalidValue,
        text,
        format!("{name} is a predefined parameter that the reader keeps (read-only)"),
        "set work offsets with G10 L2/L20, the position with a move, the tool with T and M6; use another parameter for your own values",
    )
}

fn eval_error(line: usize, col: usize, text: &str, e: &EvalError) -> GcodeError {
    let (m, h) = e.describe();
    err(line, col, GcodeErrorKind::InvalidValue, text, m, h)
}

/// The numbered subprograms of a file (Fanuc `M98 P<n>` calls them, fanuc.rs): number → line indices of its `O<n>` lines, in order.
fn numbered_programs(lines: &[SourceLine<'_>]) -> HashMap<u64, Vec<usize>> {
    let mut out: HashMap<u64, Vec<usize>> = HashMap::new();
    for (i, l) in lines.iter().enumerate() {
        if let Some(n) = program_number(l) {
            out.entry(n).or_default().push(i);
        }
    }
    out
}

/// The number of a line that holds only `O<n>` (and comments).
fn program_number(l: &SourceLine<'_>) -> Option<u64> {
    let Ok(Lexed::Block(b)) = &l.lexed else {
        return None;
    };
    match b.words.as_slice() {
        [w] if w.letter == 'O' && !b.delete && b.o.is_none() && b.assigns.is_empty() => {
            match w.value {
                Value::Num(v) if v >= 0.0 && v.fract() == 0.0 && v < 1e15 => Some(v as u64),
                _ => None,
            }
        }
        _ => None,
    }
}
