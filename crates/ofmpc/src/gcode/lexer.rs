//! Lexer: one line of text → words (letter, value, column, source text).

use super::expr::{Expr, Func, Op};
use super::program::{err, GcodeError, GcodeErrorKind, MAX_WORD_VALUE};
use super::text::{escape, is_invisible};
use std::cell::Cell;

/// One word of a line: an upper-case letter and its value.
#[derive(Debug, Clone)]
pub(super) struct Word<'a> {
    pub(super) letter: char,
    pub(super) value: f64,
    /// 1-based column of the letter.
    pub(super) col: usize,
    /// Source text of the word.
    pub(super) text: &'a str,
}

/// The value of a word as read: a plain number, or an expression evaluated when the line runs.
#[derive(Debug, Clone)]
pub(super) enum Value {
    Num(f64),
    Expr(Expr),
}

/// A word as read (its value possibly an expression).
#[derive(Debug, Clone)]
pub(super) struct RawWord<'a> {
    pub(super) letter: char,
    pub(super) value: Value,
    pub(super) col: usize,
    pub(super) text: &'a str,
}

/// The parameter a `#… = …` setting writes.
#[derive(Debug, Clone)]
pub(super) enum Target {
    Numbered(Expr),
    Named(String),
}

/// A parameter setting `#… = value`.
#[derive(Debug, Clone)]
pub(super) struct Assign<'a> {
    pub(super) target: Target,
    pub(super) value: Expr,
    pub(super) col: usize,
    pub(super) text: &'a str,
}

/// The keyword of an O-word statement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum OKind {
    Sub,
    Endsub,
    Call,
    Return,
    If,
    Elseif,
    Else,
    Endif,
    While,
    Endwhile,
    Do,
    Repeat,
    Endrepeat,
    Break,
    Continue,
    /// `O<name>` alone on a line: the program's name (LinuxCNC reads it as the program
    /// number line of Fanuc-style programs, `O42`); no effect.
    Title,
}

impl OKind {
    fn from_word(w: &str) -> Option<OKind> {
        Some(match w {
            "SUB" => OKind::Sub,
            "ENDSUB" => OKind::Endsub,
            "CALL" => OKind::Call,
            "RETURN" => OKind::Return,
            "IF" => OKind::If,
            "ELSEIF" => OKind::Elseif,
            "ELSE" => OKind::Else,
            "ENDIF" => OKind::Endif,
            "WHILE" => OKind::While,
            "ENDWHILE" => OKind::Endwhile,
            "DO" => OKind::Do,
            "REPEAT" => OKind::Repeat,
            "ENDREPEAT" => OKind::Endrepeat,
            "BREAK" => OKind::Break,
            "CONTINUE" => OKind::Continue,
            _ => return None,
        })
    }

    /// The keyword as written in programs (lower case).
    pub(super) fn name(self) -> &'static str {
        match self {
            OKind::Sub => "sub",
            OKind::Endsub => "endsub",
            OKind::Call => "call",
            OKind::Return => "return",
            OKind::If => "if",
            OKind::Elseif => "elseif",
            OKind::Else => "else",
            OKind::Endif => "endif",
            OKind::While => "while",
            OKind::Endwhile => "endwhile",
            OKind::Do => "do",
            OKind::Repeat => "repeat",
            OKind::Endrepeat => "endrepeat",
            OKind::Break => "break",
            OKind::Continue => "continue",
            OKind::Title => "(program name)",
        }
    }
}

/// An O-word statement (`o100 while [#1 LT 3]`, `o<name> call [1] [2]`).
#[derive(Debug, Clone)]
pub(super) struct OStmt<'a> {
    /// The label: the number (without leading zeros) or `<name>` in lower case; for a
    /// computed label, its source text.
    pub(super) label: String,
    /// A computed label (`o[#1 + 2] call`, `o#<sub> call`), evaluated when the line runs.
    pub(super) label_expr: Option<Expr>,
    pub(super) kind: OKind,
    pub(super) args: Vec<Expr>,
    pub(super) col: usize,
    pub(super) text: &'a str,
}

/// The kind of a comment that is a program message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum MessageKind {
    Msg,
    Print,
    Debug,
}

/// A comment `(MSG,…)`, `(PRINT,…)` or `(DEBUG,…)`.
#[derive(Debug, Clone)]
pub(super) struct Comment {
    pub(super) kind: MessageKind,
    pub(super) text: String,
}

/// One line as read.
#[derive(Debug, Clone, Default)]
pub(super) struct Block<'a> {
    pub(super) words: Vec<RawWord<'a>>,
    pub(super) assigns: Vec<Assign<'a>>,
    pub(super) o: Option<OStmt<'a>>,
    pub(super) comments: Vec<Comment>,
    /// The line starts with `/` (block delete).
    pub(super) delete: bool,
}

impl Block<'_> {
    /// Nothing to execute.
    pub(super) fn is_empty(&self) -> bool {
        self.words.is_empty()
            && self.assigns.is_empty()
            && self.o.is_none()
            && self.comments.is_empty()
    }
}

pub(super) enum Lexed<'a> {
    Percent,
    Block(Block<'a>),
}

/// Most nodes in the expressions of one line (bounds the reader's recursion).
const MAX_EXPR_NODES: usize = 2000;
/// Deepest nesting of `[ ]` and `#`.
const MAX_EXPR_DEPTH: usize = 32;

pub(super) fn lex_line(raw: &str, line: usize) -> Result<Lexed<'_>, GcodeError> {
    use GcodeErrorKind::Syntax;
    let text = LineChars {
        raw,
        chars: raw.char_indices().collect(),
        line,
        nodes: Cell::new(0),
    };
    let mut block = Block::default();
    let mut i = 0;
    let mut first_content = true;
    while let Some(&(_, c)) = text.chars.get(i) {
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
        if c == '/' && first_content {
            block.delete = true;
            first_content = false;
            i += 1;
            continue;
        }
        first_content = false;
        if c == ';' {
            break;
        }
        if c == '(' {
            let (j, comment) = text.comment(i)?;
            block.comments.extend(comment);
            i = j;
            continue;
        }
        if block.o.is_some() {
            return Err(text.after_o_word(i));
        }
        if c == '#' {
            let (a, j) = text.assignment(i)?;
            block.assigns.push(a);
            i = j;
            continue;
        }
        if c == 'O' || c == 'o' {
            if let Some((o, j)) = text.o_word(i)? {
                if let Some(w) = block.words.first() {
                    return Err(err(
                        line,
                        w.col,
                        Syntax,
                        raw.trim(),
                        format!("{} before an O-word statement", w.text),
                        "an O-word statement (sub, call, if, while, …) stands alone on its line",
                    ));
                }
                block.o = Some(o);
                i = j;
                continue;
            }
        }
        if c.is_ascii_alphabetic() || c == '@' || c == '^' || c == '$' {
            let (word, j) = text.word(i, c)?;
            block.words.push(word);
            i = j;
            continue;
        }
        return Err(text.unexpected_char(i, c));
    }
    Ok(Lexed::Block(block))
}

/// The characters of one line with their byte offsets, for the pieces of [`lex_line`].
struct LineChars<'a> {
    raw: &'a str,
    chars: Vec<(usize, char)>,
    line: usize,
    /// Expression nodes read so far on this line.
    nodes: Cell<usize>,
}

impl<'a> LineChars<'a> {
    /// Byte offset of character `i` (the line's length past the end).
    fn byte_at(&self, i: usize) -> usize {
        self.chars.get(i).map_or(self.raw.len(), |&(b, _)| b)
    }

    /// Reads the comment in ( ) that opens at character `i`; returns the index after `)` and
    /// the comment if it is a message (`MSG,` `PRINT,` `DEBUG,`, any case).
    /// Errors: a nested `(`, or no `)` on the line.
    fn comment(&self, i: usize) -> Result<(usize, Option<Comment>), GcodeError> {
        let (raw, chars, line) = (self.raw, &self.chars, self.line);
        match chars
            .iter()
            .skip(i + 1)
            .position(|&(_, ch)| ch == ')' || ch == '(')
        {
            Some(k) if chars.get(i + 1 + k).is_some_and(|&(_, ch)| ch == '(') => {
                let inner = i + 1 + k;
                Err(err(
                    line,
                    inner + 1,
                    GcodeErrorKind::Syntax,
                    &raw[self.byte_at(i)..],
                    "nested comment: a comment in ( ) contains another `(`",
                    "comments do not nest: remove the inner parentheses, or use ; for a comment to the end of the line",
                ))
            }
            Some(k) => {
                let body = &raw[self.byte_at(i + 1)..self.byte_at(i + 1 + k)];
                Ok((i + k + 2, message_comment(body)))
            }
            None => Err(err(
                line,
                i + 1,
                GcodeErrorKind::Syntax,
                &raw[self.byte_at(i)..],
                "unclosed comment",
                "close the comment with `)` on the same line",
            )),
        }
    }

    /// The next non-blank character at or after `j` and its index.
    fn peek(&self, mut j: usize) -> (usize, Option<char>) {
        while matches!(self.chars.get(j), Some(&(_, ' ' | '\t'))) {
            j += 1;
        }
        (j, self.chars.get(j).map(|&(_, c)| c))
    }

    /// The ASCII letters starting at `j` (upper case) and the index after them.
    fn letters(&self, j: usize) -> (String, usize) {
        let mut k = j;
        let mut s = String::new();
        while let Some(&(_, c)) = self.chars.get(k) {
            if !c.is_ascii_alphabetic() {
                break;
            }
            s.push(c.to_ascii_uppercase());
            k += 1;
        }
        (s, k)
    }

    /// An error of kind Syntax at character `i`.
    /// The error for an O-word keyword not known (characters `k..k2` after o`label`): a
    /// known keyword followed by more text (`o100 sub X5`) is text after the statement.
    fn unknown_keyword(&self, k: usize, k2: usize, label: &str) -> GcodeError {
        let shown = self.raw[self.byte_at(k)..self.byte_at(k2)].to_lowercase();
        let known = shown
            .split_once(char::is_whitespace)
            .and_then(|(head, rest)| {
                OKind::from_word(&head.to_ascii_uppercase()).map(|o| (o, rest.trim()))
            });
        match known {
            Some((o, rest)) => self.syntax(
                k,
                format!("text `{rest}` after the statement o{label} {}", o.name()),
                "an O-word statement (sub, call, if, while, …) stands alone on its line; \
                 conditions and arguments go in [ ]",
            ),
            None => self.syntax(
                k,
                format!("unknown O-word keyword `{shown}` after o{label}"),
                "O-word keywords: sub endsub call return if elseif else endif while endwhile do repeat endrepeat break continue",
            ),
        }
    }

    fn syntax(&self, i: usize, message: impl Into<String>, hint: impl Into<String>) -> GcodeError {
        let i = i.min(self.chars.len().saturating_sub(1));
        let end = self.byte_at((i + 1).min(self.chars.len()));
        err(
            self.line,
            i + 1,
            GcodeErrorKind::Syntax,
            &escape(&self.raw[self.byte_at(i.min(self.chars.len()))..end]),
            message,
            hint,
        )
    }

    /// Does a value that is an expression start at `j` (`#`, `[`, a function name followed
    /// by `[`, or a sign before one of them)?
    fn expression_starts(&self, j: usize) -> bool {
        let (j, c) = self.peek(j);
        match c {
            Some('#' | '[') => true,
            Some('+' | '-') => self.expression_starts(j + 1),
            Some(c) if c.is_ascii_alphabetic() => {
                let (name, k) = self.letters(j);
                let known = Func::from_word(&name).is_some() || name == "ATAN" || name == "EXISTS";
                known && self.peek(k).1 == Some('[')
            }
            _ => false,
        }
    }

    /// Counts one expression node; errors past [`MAX_EXPR_NODES`] or [`MAX_EXPR_DEPTH`].
    fn node(&self, i: usize, depth: usize) -> Result<(), GcodeError> {
        self.nodes.set(self.nodes.get() + 1);
        if self.nodes.get() > MAX_EXPR_NODES || depth > MAX_EXPR_DEPTH {
            return Err(self.syntax(
                i,
                format!(
                    "expression too large (more than {MAX_EXPR_NODES} terms or {MAX_EXPR_DEPTH} levels of [ ] on one line)"
                ),
                "split the computation over several parameter settings",
            ));
        }
        Ok(())
    }

    /// A real value at `j` (rs274ngc's `real_value`): a number, `#…`, `[ … ]`, a function,
    /// or a signed one of these. Returns the expression and the index after it.
    fn real_value(&self, j: usize, depth: usize) -> Result<(Expr, usize), GcodeError> {
        let (j, c) = self.peek(j);
        self.node(j, depth)?;
        match c {
            Some('-') => {
                let (e, k) = self.real_value(j + 1, depth + 1)?;
                Ok((Expr::Neg(Box::new(e)), k))
            }
            Some('+') => self.real_value(j + 1, depth + 1),
            Some('[') => self.bracket(j, depth + 1),
            Some('#') => self.parameter(j, depth + 1),
            Some(c) if c.is_ascii_digit() || c == '.' => {
                let mut k = j;
                while matches!(self.chars.get(k), Some(&(_, ch)) if ch.is_ascii_digit() || ch == '.')
                {
                    k += 1;
                }
                let s = &self.raw[self.byte_at(j)..self.byte_at(k)];
                let v: f64 = s.parse().map_err(|_| {
                    self.syntax(
                        j,
                        format!("the number `{s}` does not parse"),
                        "write a decimal number with at most one point, e.g. 12.5",
                    )
                })?;
                if v.abs() > MAX_WORD_VALUE {
                    return Err(self.syntax(
                        j,
                        "number out of range",
                        format!("numbers must not exceed {MAX_WORD_VALUE:e} in magnitude"),
                    ));
                }
                Ok((Expr::Num(v), k))
            }
            Some(c) if c.is_ascii_alphabetic() => self.function(j, depth + 1),
            Some(c) => Err(self.syntax(
                j,
                format!("a value was expected, found `{}`", escape(&c.to_string())),
                "write a number, #parameter, [expression] or function such as SIN[30]",
            )),
            None => Err(self.syntax(
                j,
                "a value was expected at the end of the line",
                "complete the expression",
            )),
        }
    }

    /// A function call at `j`: `NAME[expr]`, `ATAN[a]/[b]` or `EXISTS[#<name>]`.
    fn function(&self, j: usize, depth: usize) -> Result<(Expr, usize), GcodeError> {
        let (name, k) = self.letters(j);
        let (k, c) = self.peek(k);
        if c != Some('[') {
            return Err(self.syntax(j, format!("`{name}` where a value was expected"), "functions take their argument in [ ], e.g. SIN[30]; operators such as MOD and EQ stand between two values"));
        }
        if name == "EXISTS" {
            return self.exists(j, k, depth);
        }
        let (a, k) = self.bracket(k, depth)?;
        if name == "ATAN" {
            let (k2, c2) = self.peek(k);
            if c2 != Some('/') {
                return Err(self.syntax(k2, "ATAN takes two arguments", "write ATAN[y]/[x]"));
            }
            let (k3, c3) = self.peek(k2 + 1);
            if c3 != Some('[') {
                return Err(self.syntax(k3, "ATAN takes two arguments", "write ATAN[y]/[x]"));
            }
            let (b, k4) = self.bracket(k3, depth)?;
            return Ok((Expr::Atan(Box::new(a), Box::new(b)), k4));
        }
        match Func::from_word(&name) {
            Some(f) => Ok((Expr::Func(f, Box::new(a)), k)),
            None => Err(self.syntax(
                j,
                format!("unknown function `{name}`"),
                "functions: ABS ACOS ASIN ATAN COS EXISTS EXP FIX FUP LN ROUND SIN SQRT TAN",
            )),
        }
    }

    /// `EXISTS[#<name>]` (or `EXISTS[#n]`: whether n is a valid parameter number) whose
    /// name starts at `j` and `[` is at `k`.
    fn exists(&self, j: usize, k: usize, depth: usize) -> Result<(Expr, usize), GcodeError> {
        let (k2, c2) = self.peek(k + 1);
        let (k3, c3) = self.peek(k2 + 1);
        if c2 == Some('#') && c3 != Some('<') {
            let (e, k4) = self.real_value(k2 + 1, depth)?;
            let (k5, c5) = self.peek(k4);
            if c5 == Some(']') {
                // A numbered parameter exists when its number is valid.
                let exists = Expr::Bin(
                    Op::And,
                    Box::new(Expr::Bin(
                        Op::Ge,
                        Box::new(e.clone()),
                        Box::new(Expr::Num(1.0)),
                    )),
                    Box::new(Expr::Bin(
                        Op::Le,
                        Box::new(e),
                        Box::new(Expr::Num(super::expr::MAX_PARAMETER as f64)),
                    )),
                );
                return Ok((exists, k5 + 1));
            }
        }
        if c2 == Some('#') && c3 == Some('<') {
            let (n, k4) = self.name(k3)?;
            let (k5, c5) = self.peek(k4);
            if c5 == Some(']') {
                return Ok((Expr::Exists(n), k5 + 1));
            }
        }
        Err(self.syntax(
            j,
            "EXISTS takes one named parameter",
            "write EXISTS[#<name>]",
        ))
    }

    /// A name `<…>` whose `<` is at `j`: lower case, blanks removed; the index after `>`.
    fn name(&self, j: usize) -> Result<(String, usize), GcodeError> {
        let mut k = j + 1;
        let mut s = String::new();
        while let Some(&(_, c)) = self.chars.get(k) {
            if c == '>' {
                if s.is_empty() {
                    return Err(self.syntax(j, "empty name `<>`", "write a name, e.g. #<depth>"));
                }
                return Ok((s, k + 1));
            }
            if !c.is_whitespace() {
                s.extend(c.to_lowercase());
            }
            k += 1;
        }
        Err(self.syntax(
            j,
            "name without closing `>`",
            "close the name, e.g. #<depth>",
        ))
    }

    /// A parameter `#n`, `#[expr]`, `##n` or `#<name>` at `j`.
    fn parameter(&self, j: usize, depth: usize) -> Result<(Expr, usize), GcodeError> {
        let (k, c) = self.peek(j + 1);
        if c == Some('<') {
            let (n, k2) = self.name(k)?;
            return Ok((Expr::Named(n), k2));
        }
        let (e, k2) = self.real_value(j + 1, depth)?;
        Ok((Expr::Param(Box::new(e)), k2))
    }

    /// A binary operator at `j` (after blanks), its precedence and the index after it.
    fn operator(&self, j: usize) -> Option<(Op, usize)> {
        let (j, c) = self.peek(j);
        match c? {
            '*' if self.chars.get(j + 1).is_some_and(|&(_, c)| c == '*') => Some((Op::Pow, j + 2)),
            '*' => Some((Op::Mul, j + 1)),
            '/' => Some((Op::Div, j + 1)),
            '+' => Some((Op::Add, j + 1)),
            '-' => Some((Op::Sub, j + 1)),
            c if c.is_ascii_alphabetic() => {
                let (w, k) = self.letters(j);
                Op::from_word(&w).map(|op| (op, k))
            }
            _ => None,
        }
    }

    /// `[ expr ]` with its `[` at `j`; binary operators by precedence climbing.
    fn bracket(&self, j: usize, depth: usize) -> Result<(Expr, usize), GcodeError> {
        let (lhs, k) = self.real_value(j + 1, depth)?;
        let (e, k) = self.climb(lhs, k, 0, depth)?;
        let (k, c) = self.peek(k);
        if c != Some(']') {
            return Err(match c {
                None => self.syntax(j, "`[` without `]`", "close the expression with `]`"),
                Some(_) => self.syntax(
                    k,
                    "an operator or `]` was expected",
                    "operators: ** * / MOD + - EQ NE GT GE LT LE AND OR XOR",
                ),
            });
        }
        Ok((e, k + 1))
    }

    /// Precedence climbing: extends `lhs` with operators of precedence at least `min`.
    fn climb(
        &self,
        mut lhs: Expr,
        mut k: usize,
        min: u8,
        depth: usize,
    ) -> Result<(Expr, usize), GcodeError> {
        while let Some((op, k1)) = self.operator(k).filter(|(op, _)| op.precedence() >= min) {
            self.node(k, depth)?;
            let (mut rhs, mut k2) = self.real_value(k1, depth)?;
            while let Some((next, _)) = self
                .operator(k2)
                .filter(|(n, _)| n.precedence() > op.precedence())
            {
                (rhs, k2) = self.climb(rhs, k2, next.precedence(), depth + 1)?;
            }
            lhs = Expr::Bin(op, Box::new(lhs), Box::new(rhs));
            k = k2;
        }
        Ok((lhs, k))
    }

    /// A parameter setting `#… = value` with its `#` at `i`.
    fn assignment(&self, i: usize) -> Result<(Assign<'a>, usize), GcodeError> {
        let (k, c) = self.peek(i + 1);
        let (target, k) = if c == Some('<') {
            let (n, k2) = self.name(k)?;
            (Target::Named(n), k2)
        } else {
            let (e, k2) = self.real_value(i + 1, 1)?;
            (Target::Numbered(e), k2)
        };
        let (k, c) = self.peek(k);
        if c != Some('=') {
            return Err(self.syntax(k.min(self.chars.len().saturating_sub(1)), "a parameter at the start of a word must be set with `=`", "write #1 = 2.5 or #<name> = [#1 + 1]; to use a parameter as a value write it after a letter, e.g. X#1"));
        }
        let (value, k2) = self.real_value(k + 1, 1)?;
        let text = &self.raw[self.byte_at(i)..self.byte_at(k2)];
        Ok((
            Assign {
                target,
                value,
                col: i + 1,
                text,
            },
            k2,
        ))
    }

    /// An O-word statement at `i` (`o100 while …`, `o<name> call …`); `None` when the O is
    /// followed by a number and no keyword (a program number, read as a word).
    fn o_word(&self, i: usize) -> Result<Option<(OStmt<'a>, usize)>, GcodeError> {
        let (j, c) = self.peek(i + 1);
        let mut label_expr = None;
        let (label, k) = match c {
            Some('<') => {
                let (n, k) = self.name(j)?;
                (format!("<{n}>"), k)
            }
            // LinuxCNC reads the number of an O-word as an integer value: a parameter or an
            // expression gives a computed label ("O codes: indirection").
            Some('#' | '[') => {
                let (e, k) = self.real_value(j, 1)?;
                label_expr = Some(e);
                (self.raw[self.byte_at(j)..self.byte_at(k)].to_string(), k)
            }
            Some(c) if c.is_ascii_digit() => {
                let mut k = j;
                while matches!(self.chars.get(k), Some(&(_, ch)) if ch.is_ascii_digit()) {
                    k += 1;
                }
                let digits = &self.raw[self.byte_at(j)..self.byte_at(k)];
                let t = digits.trim_start_matches('0');
                (
                    if t.is_empty() {
                        "0".to_string()
                    } else {
                        t.to_string()
                    },
                    k,
                )
            }
            _ => return Ok(None),
        };
        let (k, _) = self.peek(k);
        // Blanks inside the keyword are ignored, as LinuxCNC removes them (`end sub`).
        let mut kw = String::new();
        let mut k2 = k;
        loop {
            let (w, e) = self.letters(k2);
            if w.is_empty() {
                break;
            }
            kw.push_str(&w);
            k2 = e;
            let (next, c) = self.peek(k2);
            if !c.is_some_and(|c| c.is_ascii_alphabetic()) {
                break;
            }
            k2 = next;
        }
        let Some(kind) = OKind::from_word(&kw) else {
            if kw.len() >= 2 && (label.starts_with('<') || label_expr.is_some() || kw.len() >= 3) {
                return Err(self.unknown_keyword(k, k2, &label));
            }
            if label.starts_with('<') && kw.is_empty() {
                return Ok(Some((
                    OStmt {
                        label,
                        label_expr: None,
                        kind: OKind::Title,
                        args: Vec::new(),
                        col: i + 1,
                        text: self.raw[self.byte_at(i)..self.byte_at(k)].trim_end(),
                    },
                    k,
                )));
            }
            if label.starts_with('<') || label_expr.is_some() {
                return Err(self.syntax(
                    k,
                    format!("O-word {label} without a keyword"),
                    "write o<name> sub, call, if, while, … (LinuxCNC's O-words)",
                ));
            }
            return Ok(None);
        };
        let mut args = Vec::new();
        let mut k = k2;
        loop {
            let (k1, c) = self.peek(k);
            match c {
                Some('[') => {
                    let (e, k3) = self.bracket(k1, 1)?;
                    args.push(e);
                    k = k3;
                }
                Some('(') => k = self.comment(k1)?.0,
                _ => break,
            }
        }
        let text = &self.raw[self.byte_at(i)..self.byte_at(k)];
        Ok(Some((
            OStmt {
                label,
                label_expr,
                kind,
                args,
                col: i + 1,
                text,
            },
            k,
        )))
    }

    /// The error for anything but a comment after an O-word statement, at `i`.
    fn after_o_word(&self, i: usize) -> GcodeError {
        self.syntax(i, "text after an O-word statement", "an O-word statement (sub, call, if, while, …) stands alone on its line; conditions and arguments go in [ ]")
    }

    /// Reads the word whose letter `c` is character `i`: the letter, blanks, an optional
    /// sign and a decimal number. Returns the word and the index after it.
    fn word(&self, i: usize, c: char) -> Result<(RawWord<'a>, usize), GcodeError> {
        if self.expression_starts(i + 1) {
            return self.expression_word(i, c);
        }
        let (raw, chars, line) = (self.raw, &self.chars, self.line);
        let col = i + 1;
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
        let text = &raw[self.byte_at(i)..self.byte_at(j)];
        if j == digits_start {
            return Err(self.no_number(i, j, letter));
        }
        self.check_exponent(i, num_start, j, letter)?;
        let number = &raw[self.byte_at(num_start)..self.byte_at(j)];
        let value: f64 = number.parse().map_err(|_| {
            err(
                line,
                col,
                GcodeErrorKind::Syntax,
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
        let word = RawWord {
            letter,
            value: Value::Num(value),
            col,
            text,
        };
        Ok((word, j))
    }

    /// The word of letter `c` at character `i` whose value is an expression (`X[…]`, `X#1`).
    fn expression_word(&self, i: usize, c: char) -> Result<(RawWord<'a>, usize), GcodeError> {
        let letter = c.to_ascii_uppercase();
        let (e, k) = self.real_value(i + 1, 0)?;
        let text = &self.raw[self.byte_at(i)..self.byte_at(k)];
        let word = RawWord {
            letter,
            value: Value::Expr(e),
            col: i + 1,
            text,
        };
        Ok((word, k))
    }

    /// The error for the letter at character `i` without a number (which would start at
    /// `j`), with a hint for the likely mistake (O for 0, `#` parameters, `[ ]` expressions).
    fn no_number(&self, i: usize, j: usize, letter: char) -> GcodeError {
        let next = self.chars.get(j).map(|&(_, ch)| ch);
        // A run of letters (`gsw_meta`, `GOTO`, `IF`) is text of another language.
        let mut k = i;
        while matches!(self.chars.get(k), Some(&(_, ch)) if ch.is_ascii_alphanumeric() || ch == '_')
        {
            k += 1;
        }
        let run = &self.raw[self.byte_at(i)..self.byte_at(k)];
        if next.is_some_and(|c| c.is_ascii_alphabetic() && c != 'O' && c != 'o') && k > i + 2 {
            return err(
                self.line,
                i + 1,
                GcodeErrorKind::Syntax,
                &escape(run),
                format!(
                    "`{}` is not G-code: a word is one letter and a number",
                    escape(run)
                ),
                "is this a G-code file? Comments go in ( ) or after ;",
            );
        }
        let hint = if matches!(next, Some('O' | 'o')) {
            format!("the letter O where the digit 0 was meant? write {letter}0")
        } else {
            format!("write a number after {letter}, e.g. {letter}10.5")
        };
        let shown = escape(&self.raw[self.byte_at(i)..self.byte_at((j + 1).min(self.chars.len()))]);
        err(
            self.line,
            i + 1,
            GcodeErrorKind::Syntax,
            &shown,
            format!("{letter} has no number"),
            hint,
        )
    }

    /// Rejects exponent notation after the number `num_start..j` of the word at character
    /// `i`.
    ///
    /// Exponent notation (1e300, 2.5E-3) is not G-code: say so and show the number in
    /// decimal, rather than reading the `E` as the next word.
    fn check_exponent(
        &self,
        i: usize,
        num_start: usize,
        j: usize,
        letter: char,
    ) -> Result<(), GcodeError> {
        let chars = &self.chars;
        if matches!(chars.get(j), Some(&(_, 'e' | 'E'))) {
            let mut k = j + 1;
            if matches!(chars.get(k), Some(&(_, '+' | '-'))) {
                k += 1;
            }
            if matches!(chars.get(k), Some(&(_, ch)) if ch.is_ascii_digit()) {
                while matches!(chars.get(k), Some(&(_, ch)) if ch.is_ascii_digit()) {
                    k += 1;
                }
                let written = &self.raw[self.byte_at(num_start)..self.byte_at(k)];
                let hint = match written.parse::<f64>() {
                    Ok(v) if v.is_finite() && v.abs() <= MAX_WORD_VALUE => {
                        format!("write the number in decimal: {letter}{v}")
                    }
                    _ => format!(
                        "write the number in decimal; {written} is also beyond the largest magnitude accepted, {MAX_WORD_VALUE}"
                    ),
                };
                return Err(err(
                    self.line,
                    i + 1,
                    GcodeErrorKind::Syntax,
                    &self.raw[self.byte_at(i)..self.byte_at(k)],
                    "exponent notation is not G-code",
                    hint,
                ));
            }
        }
        Ok(())
    }

    /// The error for character `c` at `i`, which starts no word, comment or `%`.
    fn unexpected_char(&self, i: usize, c: char) -> GcodeError {
        let (message, hint) = match c {
            '[' | ']' => (
                "an expression `[ ]` where a word was expected".to_string(),
                "expressions are values: write them after a letter (X[1+2]) or a parameter setting (#1 = [1+2])".to_string(),
            ),
            '/' => (
                "block delete `/` inside a line".to_string(),
                "`/` (block delete) may only start a line".to_string(),
            ),
            '*' => ("checksums (`*`) are not supported".to_string(), "remove the checksum".to_string()),
            ')' => ("`)` without `(`".to_string(), "comments are written `(like this)`".to_string()),
            '@' | '^' => (
                format!("polar word `{c}` without a value or in a motion it does not apply to"),
                "polar coordinates: G1 @<distance> ^<angle in degrees> in the active plane".to_string(),
            ),
            c if is_invisible(c) => (
                format!("invisible character {} (shown escaped)", escape(&c.to_string())),
                "delete it: editors and copy-paste insert such characters".to_string(),
            ),
            _ => (
                "unexpected character".to_string(),
                "a line holds words such as G01 X10.5, comments in ( ) or after ;".to_string(),
            ),
        };
        let end = self.byte_at(i + 1);
        err(
            self.line,
            i + 1,
            GcodeErrorKind::Syntax,
            &escape(&self.raw[self.byte_at(i)..end]),
            message,
            hint,
        )
    }
}

/// The message in a comment's `body` (`MSG,…`, `PRINT,…`, `DEBUG,…`, any case).
fn message_comment(body: &str) -> Option<Comment> {
    let t = body.trim_start();
    let (kw, rest) = t.split_once(',')?;
    let kind = match kw.trim().to_ascii_uppercase().as_str() {
        "MSG" => MessageKind::Msg,
        "PRINT" => MessageKind::Print,
        "DEBUG" => MessageKind::Debug,
        _ => return None,
    };
    Some(Comment {
        kind,
        text: rest.to_string(),
    })
}
