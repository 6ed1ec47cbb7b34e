//! Fanuc-style numbered subprograms as LinuxCNC 2.9 reads them (its G-code manual, "O Codes:
//! Fanuc-Style Numbered Programs", and `read_o`/`execute_call` in interp_read.cc and
//! interp_o_word.cc):
//!
//! - `O<n>` alone on its line (comments allowed) starts subprogram `n`; `M99` ends it.
//! - `M98 P<n> [L<repeats>]` calls the first `O<n>` that *follows* the call in the file
//!   (`O0002` and `O2` are both number 2), `L` times (default 1; `L0` does not call). `P` is
//!   a whole number (within 0.0001, as `read_o`).
//! - `#1 … #30` are global in numbered subprograms: a call neither passes nor restores them.
//! - `M99` in the main program (LinuxCNC's task: an endless program) ends the program, as
//!   LinuxCNC's stand-alone interpreter and preview read it, with a warning.
//! - The styles do not mix: `M99` ends no `o… sub`, `o… endsub` ends no `O<n>` subprogram,
//!   `M98` calls no `o… sub` and `o… call` no `O<n>` (LinuxCNC refuses each).
//!
//! Calls count towards the step limit like every executed line.

use super::expr::{P_CALL_LEVEL, P_VALUE, P_VALUE_RETURNED};
use super::flow::{Frame, Runner, MAX_CALL_DEPTH};
use super::interpreter::Interpreter;
use super::lexer::{Block, Value};
use super::program::{err, GcodeError, GcodeErrorKind};
use std::collections::HashMap;

/// Which Fanuc code a block holds.
enum Code {
    Call,
    Return,
}

impl<'s, 'a> Runner<'s, 'a> {
    /// Executes `M98`/`M99` if block `b` at line `pc` holds one: `Some(next line)`; `None`
    /// for any other block.
    pub(super) fn fanuc(
        &mut self,
        it: &mut Interpreter,
        pc: usize,
        b: &Block<'a>,
    ) -> Result<Option<usize>, GcodeError> {
        let l = &self.lines[pc];
        let mut code = None;
        for w in &b.words {
            match (w.letter, &w.value) {
                ('M', Value::Num(v)) if *v == 98.0 => code = Some((Code::Call, w)),
                ('M', Value::Num(v)) if *v == 99.0 => code = Some((Code::Return, w)),
                _ => {}
            }
        }
        let Some((code, mw)) = code else {
            return Ok(None);
        };
        let allowed = match code {
            Code::Call => "MPLN",
            Code::Return => "MN",
        };
        if let Some(w) = b
            .words
            .iter()
            .find(|w| !allowed.contains(w.letter) || (w.letter == 'M' && !std::ptr::eq(*w, mw)))
        {
            return Err(err(
                l.no,
                w.col,
                GcodeErrorKind::Conflict,
                w.text,
                format!("{} shares its line with {}", mw.text, w.text),
                format!(
                    "write {} on a line of its own",
                    if matches!(code, Code::Call) {
                        "M98 P<n> L<repeats>"
                    } else {
                        "M99"
                    }
                ),
            ));
        }
        if !b.assigns.is_empty() {
            let a = &b.assigns[0];
            return Err(err(
                l.no,
                a.col,
                GcodeErrorKind::Conflict,
                a.text,
                format!("{} shares its line with a parameter setting", mw.text),
                "set the parameter on the line before",
            ));
        }
        self.messages(it, l, b);
        match code {
            Code::Call => self.m98(pc, b, mw.col, mw.text).map(Some),
            Code::Return => self.m99(it, pc, mw.col, mw.text).map(Some),
        }
    }

    /// `M98 P<n> L<k>`: calls the first `O<n>` after line `pc`, `k` times.
    fn m98(
        &mut self,
        pc: usize,
        b: &Block<'a>,
        col: usize,
        text: &str,
    ) -> Result<usize, GcodeError> {
        let (n, repeats) = self.m98_args(pc, b, col, text)?;
        let sub = self.find_numbered(pc, n, col, text)?;
        if repeats == 0 {
            return Ok(pc + 1);
        }
        if self.frames.len() >= MAX_CALL_DEPTH {
            return Err(err(
                self.lines[pc].no,
                col,
                GcodeErrorKind::InvalidValue,
                text,
                format!("subprogram calls nested deeper than {MAX_CALL_DEPTH}"),
                "check for a subprogram that calls itself without end",
            ));
        }
        let mut saved = [0.0; 30];
        saved.copy_from_slice(&self.params.numbered[1..31]);
        self.params.locals.push(HashMap::new());
        self.frames.push(Frame {
            return_to: pc + 1,
            saved,
            repeats: self.repeats.len(),
            numbered: Some((sub, repeats)),
        });
        self.params.predefined[P_CALL_LEVEL] = self.frames.len() as f64;
        self.last_loop = sub;
        Ok(sub + 1)
    }

    /// M98's P (the subprogram's number) and L (the repeat count, default 1) of block `b`
    /// at line `pc`: whole numbers >= 0, possibly expressions.
    fn m98_args(
        &self,
        pc: usize,
        b: &Block<'a>,
        col: usize,
        text: &str,
    ) -> Result<(u64, u64), GcodeError> {
        let l = &self.lines[pc];
        let word = |c: char| b.words.iter().find(|w| w.letter == c);
        let value =
            |r: &Runner<'s, 'a>, c: char| -> Result<Option<(f64, usize, &str)>, GcodeError> {
                match word(c) {
                    None => Ok(None),
                    Some(w) => {
                        let v = match &w.value {
                            Value::Num(v) => *v,
                            Value::Expr(e) => r.eval(l, w.col, w.text, e)?,
                        };
                        Ok(Some((v, w.col, w.text)))
                    }
                }
            };
        let Some((p, pcol, ptext)) = value(self, 'P')? else {
            return Err(err(
                l.no,
                col,
                GcodeErrorKind::Missing,
                text,
                "M98 without P (the number of the subprogram to call)",
                "write M98 P<n>, e.g. M98 P100 for the subprogram O100 … M99",
            ));
        };
        let n = whole_number(p).ok_or_else(|| {
            err(
                l.no,
                pcol,
                GcodeErrorKind::InvalidValue,
                ptext,
                format!("M98 P{p}: the subprogram number must be a whole number >= 0"),
                "write e.g. M98 P100",
            )
        })?;
        let repeats = match value(self, 'L')? {
            None => 1,
            Some((v, lcol, ltext)) => whole_number(v).ok_or_else(|| {
                err(
                    l.no,
                    lcol,
                    GcodeErrorKind::InvalidValue,
                    ltext,
                    format!("M98 L{v}: the repeat count must be a whole number >= 0"),
                    "write e.g. M98 P100 L3",
                )
            })?,
        };
        Ok((n, repeats))
    }

    /// The line index of the first `O<n>` after line `pc`, or the error that names why
    /// there is none.
    fn find_numbered(
        &self,
        pc: usize,
        n: u64,
        col: usize,
        text: &str,
    ) -> Result<usize, GcodeError> {
        let l = &self.lines[pc];
        let found = self.numbered.get(&n);
        if let Some(&i) = found.and_then(|v| v.iter().find(|&&i| i > pc)) {
            return Ok(i);
        }
        let (message, hint) = if let Some(&i) = found.and_then(|v| v.first()) {
            (
                format!("M98 P{n}: the subprogram O{n} (line {}) comes before the call", self.lines[i].no),
                "move the subprogram after the call: LinuxCNC looks for numbered subprograms after the M98 line".to_string(),
            )
        } else if self.links.subs.contains_key(&n.to_string()) {
            (
                format!("M98 P{n}: o{n} is an O-word subroutine (o{n} sub … endsub)"),
                format!("call it with o{n} call, or write it as O{n} … M99"),
            )
        } else {
            (
                format!("M98 P{n}: no subprogram O{n} in this file"),
                format!("define it after the main program's M30 as O{n} on its own line … M99 (subprograms in other files are not read)"),
            )
        };
        Err(err(
            l.no,
            col,
            GcodeErrorKind::Unsupported,
            text,
            message,
            hint,
        ))
    }

    /// `M99`: the end of a numbered subprogram (repeats it while `L` lasts), or in the main
    /// program the end of the program.
    fn m99(
        &mut self,
        it: &mut Interpreter,
        pc: usize,
        col: usize,
        text: &str,
    ) -> Result<usize, GcodeError> {
        let l = &self.lines[pc];
        let Some(f) = self.frames.last_mut() else {
            it.warn(
                l.no,
                col,
                "M99 in the main program: LinuxCNC's task repeats such a program without end; the path is read once (as LinuxCNC's stand-alone interpreter and preview read it)",
            );
            it.ended = true;
            return Ok(pc + 1);
        };
        let Some((sub, left)) = f.numbered else {
            return Err(err(
                l.no,
                col,
                GcodeErrorKind::Syntax,
                text,
                "M99 inside an O-word subroutine (o… sub): it ends only a numbered subprogram O<n> called by M98",
                "end the subroutine with o… endsub (LinuxCNC refuses M99 there)",
            ));
        };
        // LinuxCNC (read_o): M99 returns no value.
        self.params.predefined[P_VALUE] = 0.0;
        self.params.predefined[P_VALUE_RETURNED] = 0.0;
        if left > 1 {
            f.numbered = Some((sub, left - 1));
            if let Some(locals) = self.params.locals.last_mut() {
                locals.clear();
            }
            self.repeats.truncate(f.repeats);
            self.last_loop = sub;
            return Ok(sub + 1);
        }
        let return_to = f.return_to;
        let repeats = f.repeats;
        self.frames.pop();
        self.params.locals.pop();
        self.repeats.truncate(repeats);
        self.params.predefined[P_CALL_LEVEL] = self.frames.len() as f64;
        Ok(return_to)
    }
}

/// `v` as a whole number >= 0, within 0.0001 (LinuxCNC's `read_o` for the P of M98).
fn whole_number(v: f64) -> Option<u64> {
    let r = v.round();
    ((v - r).abs() <= 1e-4 && (0.0..1e15).contains(&r)).then_some(r as u64)
}
