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
            match chars
                .iter()
                .skip(i + 1)
                .position(|&(_, ch)| ch == ')' || ch == '(')
            {
                Some(k) if chars.get(i + 1 + k).is_some_and(|&(_, ch)| ch == '(') => {
                    let inner = i + 1 + k;
                    return Err(err(
                        line,
                        inner + 1,
                        Syntax,
                        &raw[byte_at(i)..],
                        "nested comment: a comment in ( ) contains another `(`",
                        "comments do not nest: remove the inner parentheses, or use ; for a comment to the end of the line",
                    ));
                }
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
            // Exponent notation (1e300, 2.5E-3) is not G-code: say so and show the number in
            // decimal, rather than reading the `E` as the next word.
            if matches!(chars.get(j), Some(&(_, 'e' | 'E'))) {
                let mut k = j + 1;
                if matches!(chars.get(k), Some(&(_, '+' | '-'))) {
                    k += 1;
                }
                if matches!(chars.get(k), Some(&(_, ch)) if ch.is_ascii_digit()) {
                    while matches!(chars.get(k), Some(&(_, ch)) if ch.is_ascii_digit()) {
                        k += 1;
                    }
                    let written = &raw[byte_at(num_start)..byte_at(k)];
                    let hint = match written.parse::<f64>() {
                        Ok(v) if v.is_finite() && v.abs() <= MAX_WORD_VALUE => {
                            format!("write the number in decimal: {letter}{v}")
                        }
                        _ => format!(
                            "write the number in decimal; {written} is also beyond the largest magnitude accepted, {MAX_WORD_VALUE}"
                        ),
                    };
                    return Err(err(
                        line,
                        col,
                        Syntax,
                        &raw[byte_at(i)..byte_at(k)],
                        "exponent notation is not G-code",
                        hint,
                    ));
                }
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
