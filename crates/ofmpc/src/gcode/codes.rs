//! The G and M codes the reader knows, their modal groups, and the argument letters.

use super::lexer::Word;
use super::{err, GcodeError, GcodeErrorKind};
use crate::geometry::Plane;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Motion {
    Rapid,
    Linear,
    Cw,
    Ccw,
}

impl Motion {
    pub(super) fn code(self) -> &'static str {
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
pub(super) enum GCode {
    Motion(Motion),
    Dwell,
    SetOffset,
    Plane(Plane),
    Inch(bool),
    Wcs(usize),
    Absolute(bool),
    /// G61 / G61.1: exact stop at the end of every move.
    ExactStop,
    /// G64: blend corners (tolerance from P).
    Blend,
    /// Accepted, no effect.
    NoOp,
}

impl GCode {
    /// Modal group, for "two codes of one group on a line". Dwell and G10 share the
    /// non-modal group 0.
    pub(super) fn group(self) -> u8 {
        match self {
            GCode::Motion(_) => 1,
            GCode::Dwell | GCode::SetOffset => 0,
            GCode::Plane(_) => 2,
            GCode::Inch(_) => 6,
            GCode::Wcs(_) => 12,
            GCode::Absolute(_) => 3,
            GCode::ExactStop | GCode::Blend => 13,
            GCode::NoOp => 255,
        }
    }
}

pub(super) fn classify_g(w: &Word<'_>, line: usize) -> Result<GCode, GcodeError> {
    let tenths = (w.value * 10.0).round();
    let unknown = || {
        err(
            line,
            w.col,
            GcodeErrorKind::UnknownCode,
            w.text,
            format!("unknown G code {}", w.text),
            "supported: G00 G01 G02 G03 G04 G10 G17 G18 G19 G20 G21 G54-G59 G61 G64 G90 G91",
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
        610 | 611 => GCode::ExactStop,
        640 => GCode::Blend,
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

/// Action of an M code (each is also recorded as a program event).
pub(super) enum MCode {
    End,
    Warn(String),
}

/// The argument letters M code `m` uses (LinuxCNC: M62–M65 P; M66 P E L Q; M67/M68 E Q;
/// M61 Q; M100–M199 P Q; M3/M4 S; M6 T).
pub(super) fn m_letters(m: f64) -> &'static str {
    match m as i64 {
        62..=65 => "P",
        66 => "PELQ",
        67 | 68 => "EQ",
        61 => "Q",
        100..=199 => "PQ",
        _ => "",
    }
}

pub(super) fn classify_m(w: &Word<'_>, line: usize) -> Result<MCode, GcodeError> {
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
pub(super) const ARG_LETTERS: &str = "FIJKLOPRSTXYZDEHQ@^";

/// Number of [`ARG_LETTERS`].
pub(super) const N_ARGS: usize = 19;

pub(super) fn letter_index(c: char) -> Option<usize> {
    ARG_LETTERS.find(c)
}

/// The argument words of one line, by letter.
pub(super) struct Args<'l, 'w>(pub(super) [Option<&'l Word<'w>>; N_ARGS]);

impl<'l, 'w> Args<'l, 'w> {
    pub(super) fn get(&self, c: char) -> Option<&'l Word<'w>> {
        letter_index(c).and_then(|k| self.0.get(k).copied().flatten())
    }
}
