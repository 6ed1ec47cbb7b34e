//! Tool tables in LinuxCNC's `.tbl` format, for `G43 H<n>` (tool length offset from the
//! table). One tool a line: words of a letter and a number separated by blanks, a comment
//! after `;`, e.g. `T1 P1 Z+1.5 D0.25 ;drill`. `T` (the tool number) is required; `Z` is
//! the tool's length along the tool axis (mm: the robot is a metric machine, and LinuxCNC's
//! table is in machine units); a tool without `Z` has length 0. The other words of the
//! format (`P` pocket, `X Y A B C U V W` offsets, `D` diameter, `I J Q` lathe data) are
//! read and checked as numbers but not used (LinuxCNC's "Tool Table Format").

use std::collections::BTreeMap;
use thiserror::Error;

/// Letters of LinuxCNC's tool table format.
const LETTERS: &str = "TPXYZABCUVWDIJQ";

/// A tool table: the length (m) of each tool number.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ToolTable {
    lengths: BTreeMap<u32, f64>,
}

/// Why a tool table cannot be read; `line` and `column` are 1-based.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("line {line}, column {column}: {message} in `{text}` ({hint})")]
pub struct ToolTableError {
    /// Line (1-based).
    pub line: usize,
    /// Column (1-based, in characters).
    pub column: usize,
    /// The offending word.
    pub text: String,
    /// What is wrong.
    pub message: String,
    /// What to do.
    pub hint: String,
}

impl ToolTable {
    /// Reads a table in LinuxCNC's `.tbl` format (see the module documentation).
    pub fn parse(text: &str) -> Result<ToolTable, ToolTableError> {
        let mut lengths = BTreeMap::new();
        for (i, raw) in text.lines().enumerate() {
            let content = raw.split(';').next().unwrap_or("");
            let mut tool = None;
            let mut z = 0.0;
            if content
                .trim_start()
                .to_ascii_uppercase()
                .starts_with("TOOLNO")
            {
                return Err(ToolTableError {
                    line: i + 1,
                    column: 1,
                    text: super::text::escape(content.trim()),
                    message: "LinuxCNC's old tool table format (a TOOLNO POCKET LENGTH … header and columns) is not read".into(),
                    hint: "write one tool a line as T<tool> P<pocket> Z<length> D<diameter> (LinuxCNC's current format)".into(),
                });
            }
            for (col, word) in words(content) {
                let (letter, value) = letter_value(i + 1, col, word)?;
                match letter {
                    'T' if value >= 0.0 && value.fract() == 0.0 && value <= f64::from(u32::MAX) => {
                        tool = Some(value as u32);
                    }
                    'T' => {
                        return Err(word_error(
                            i + 1,
                            col,
                            word,
                            "the tool number must be a whole number >= 0".into(),
                            "write e.g. T3",
                        ))
                    }
                    'Z' => z = value * 1e-3,
                    _ => {}
                }
            }
            match tool {
                // A tool listed twice: LinuxCNC finds the first pocket that holds it
                // (tooldata_find_index_for_tool), so the first line counts.
                Some(t) => {
                    lengths.entry(t).or_insert(z);
                }
                None if content.trim().is_empty() => {}
                None => {
                    return Err(ToolTableError {
                        line: i + 1,
                        column: 1,
                        text: super::text::escape(content.trim()),
                        message: "a tool line without T (the tool number)".into(),
                        hint: "start the line with T<tool>, e.g. T1 P1 Z12.5".into(),
                    })
                }
            }
        }
        Ok(ToolTable { lengths })
    }

    /// The length (m) of tool `tool`, if the table lists it.
    pub fn length(&self, tool: u32) -> Option<f64> {
        self.lengths.get(&tool).copied()
    }

    /// The number of tools.
    pub fn len(&self) -> usize {
        self.lengths.len()
    }

    /// Whether the table lists no tool.
    pub fn is_empty(&self) -> bool {
        self.lengths.is_empty()
    }
}

/// The error at word `word` (column `column`) of line `line`.
fn word_error(
    line: usize,
    column: usize,
    word: &str,
    message: String,
    hint: &str,
) -> ToolTableError {
    ToolTableError {
        line,
        column,
        text: super::text::escape(word),
        message,
        hint: hint.to_string(),
    }
}

/// The letter (upper case, one of the table's) and the finite number of word `word`
/// (column `col`) of line `line`.
fn letter_value(line: usize, col: usize, word: &str) -> Result<(char, f64), ToolTableError> {
    let fail = |message: String, hint: &str| word_error(line, col, word, message, hint);
    let mut chars = word.chars();
    let letter = chars.next().unwrap_or(' ').to_ascii_uppercase();
    if !LETTERS.contains(letter) {
        return Err(fail(
            format!("`{letter}` is not a word of a tool table"),
            "write T<tool> P<pocket> Z<length> D<diameter> ;comment (LinuxCNC's .tbl format)",
        ));
    }
    let value: f64 = chars
        .as_str()
        .parse()
        .ok()
        .filter(|v: &f64| v.is_finite())
        .ok_or_else(|| {
            fail(
                format!("{letter} has no number"),
                "write the letter and its number without a blank, e.g. Z12.5",
            )
        })?;
    Ok((letter, value))
}

/// The blank-separated words of `s` with their 1-based columns (in characters).
fn words(s: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut col = 0;
    let mut out = Vec::new();
    let mut start: Option<(usize, usize)> = None;
    for (b, c) in s.char_indices() {
        col += 1;
        if c.is_whitespace() {
            if let Some((sc, sb)) = start.take() {
                out.push((sc, &s[sb..b]));
            }
        } else if start.is_none() {
            start = Some((col, b));
        }
    }
    if let Some((sc, sb)) = start {
        out.push((sc, &s[sb..]));
    }
    out.into_iter()
}
