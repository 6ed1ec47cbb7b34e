//! Lexer: one line of text → words (letter, value, column, source text).

use super::{err, GcodeError, GcodeErrorKind, MAX_WORD_VALUE};

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

pub(super) enum Lexed<'a> {
    Percent,
    Words(Vec<Word<'a>>),
}

pub(super) fn lex_line(raw: &str, line: usize) -> Result<Lexed<'_>, GcodeError> {
    use GcodeErrorKind::Syntax;
    let text = LineChars {
        raw,
        chars: raw.char_indices().collect(),
        line,
    };
    let mut words = Vec::new();
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
        first_content = false;
        if c == ';' {
            break;
        }
        if c == '(' {
            i = text.skip_comment(i)?;
            continue;
        }
        if c.is_ascii_alphabetic() {
            let (word, j) = text.word(i, c)?;
            words.push(word);
            i = j;
            continue;
        }
        return Err(text.unexpected_char(i, c));
    }
    Ok(Lexed::Words(words))
}

/// The characters of one line with their byte offsets, for the pieces of [`lex_line`].
struct LineChars<'a> {
    raw: &'a str,
    chars: Vec<(usize, char)>,
    line: usize,
}

impl<'a> LineChars<'a> {
    /// Byte offset of character `i` (the line's length past the end).
    fn byte_at(&self, i: usize) -> usize {
        self.chars.get(i).map_or(self.raw.len(), |&(b, _)| b)
    }

    /// Skips the comment in ( ) that opens at character `i`; returns the index after `)`.
    /// Errors: a nested `(`, or no `)` on the line.
    fn skip_comment(&self, i: usize) -> Result<usize, GcodeError> {
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
            Some(k) => Ok(i + k + 2),
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

    /// Reads the word whose letter `c` is character `i`: the letter, blanks, an optional
    /// sign and a decimal number. Returns the word and the index after it.
    fn word(&self, i: usize, c: char) -> Result<(Word<'a>, usize), GcodeError> {
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
        let word = Word {
            letter,
            value,
            col,
            text,
        };
        Ok((word, j))
    }

    /// The error for the letter at character `i` without a number (which would start at
    /// `j`), with a hint for the likely mistake (O for 0, `#` parameters, `[ ]` expressions).
    fn no_number(&self, i: usize, j: usize, letter: char) -> GcodeError {
        let next = self.chars.get(j).map(|&(_, ch)| ch);
        let hint = if matches!(next, Some('O' | 'o')) {
            format!("the letter O where the digit 0 was meant? write {letter}0")
        } else if next == Some('#') {
            "parameters (`#`) are not supported: write plain numbers".to_string()
        } else if next == Some('[') {
            "expressions (`[ ]`) are not supported: write plain numbers".to_string()
        } else {
            format!("write a number after {letter}, e.g. {letter}10.5")
        };
        let shown = &self.raw[self.byte_at(i)..self.byte_at((j + 1).min(self.chars.len()))];
        err(
            self.line,
            i + 1,
            GcodeErrorKind::Syntax,
            shown,
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
        let end = self.byte_at(i + 1);
        err(
            self.line,
            i + 1,
            GcodeErrorKind::Syntax,
            &self.raw[self.byte_at(i)..end],
            message,
            hint,
        )
    }
}
