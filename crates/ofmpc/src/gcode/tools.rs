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
    /// Reads a table in LinuxCNC's `.tbl` format (see the module documentation). A UTF-8
    /// byte-order mark is skipped; a tool listed twice, a word given twice on one line and a
    /// length past `MAX_TOOL_LENGTH_MM` are refused with their line and column (issue #36:
    /// they were kept or dropped silently).
    pub fn parse(text: &str) -> Result<ToolTable, ToolTableError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lengths = BTreeMap::new();
        let mut lines_of: BTreeMap<u32, usize> = BTreeMap::new();
        for (i, raw) in text.lines().enumerate() {
            let content = raw.split(';').next().unwrap_or("");
            let Some((tool, col, z)) = tool_line(i + 1, content)? else {
                continue;
            };
            if let Some(first) = lines_of.insert(tool, i + 1) {
                return Err(word_error(
                    i + 1,
                    col,
                    &format!("T{tool}"),
                    format!("tool {tool} is listed twice (lines {first} and {})", i + 1),
                    "keep one line per tool (LinuxCNC would take the first silently)",
                ));
            }
            lengths.insert(tool, z);
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

/// The largest tool length (mm, either sign) read: far beyond any tool a robot holds.
pub const MAX_TOOL_LENGTH_MM: f64 = 10_000.0;

/// One line of a tool table: its tool number, the column of its T word and its length (m);
/// `None` for a blank or comment line.
fn tool_line(line: usize, content: &str) -> Result<Option<(u32, usize, f64)>, ToolTableError> {
    if content
        .trim_start()
        .to_ascii_uppercase()
        .starts_with("TOOLNO")
    {
        return Err(ToolTableError {
            line,
            column: 1,
            text: super::text::escape(content.trim()),
            message: "LinuxCNC's old tool table format (a TOOLNO POCKET LENGTH … header and columns) is not read".into(),
            hint: "write one tool a line as T<tool> P<pocket> Z<length> D<diameter> (LinuxCNC's current format)".into(),
        });
    }
    let mut tool = None;
    let mut z = 0.0;
    let mut seen = String::new();
    for (col, word) in words(content) {
        let (letter, value) = letter_value(line, col, word)?;
        if seen.contains(letter) {
            return Err(word_error(
                line,
                col,
                word,
                format!("{letter} is given twice on this line"),
                "give each word once per tool line",
            ));
        }
        seen.push(letter);
        match letter {
            'T' if value >= 0.0 && value.fract() == 0.0 && value <= f64::from(u32::MAX) => {
                tool = Some((value as u32, col));
            }
            'T' => {
                return Err(word_error(
                    line,
                    col,
                    word,
                    "the tool number must be a whole number >= 0".into(),
                    "write e.g. T3",
                ))
            }
            'Z' if value.abs() > MAX_TOOL_LENGTH_MM => {
                return Err(word_error(
                    line,
                    col,
                    word,
                    format!("a tool length past {MAX_TOOL_LENGTH_MM} mm"),
                    "give the length in mm (LinuxCNC's .tbl is in the machine's units)",
                ))
            }
            'Z' => z = value * 1e-3,
            _ => {}
        }
    }
    match tool {
        Some((t, col)) => Ok(Some((t, col, z))),
        None if content.trim().is_empty() => Ok(None),
        None => Err(ToolTableError {
            line,
            column: 1,
            text: super::text::escape(content.trim()),
            message: "a tool line without T (the tool number)".into(),
            hint: "start the line with T<tool>, e.g. T1 P1 Z12.5".into(),
        }),
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
