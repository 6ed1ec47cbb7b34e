//! The G and M codes the reader knows, their modal groups, and the argument letters.

use super::lexer::Word;
use super::program::{err, GcodeError, GcodeErrorKind};
use crate::geometry::Plane;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Motion {
    Rapid,
    Linear,
    Cw,
    Ccw,
    /// A canned cycle: G73, G74, G81, G82, G83, G84, G85, G86, G89 (the number).
    Cycle(u8),
}

impl Motion {
    pub(super) fn code(self) -> &'static str {
        match self {
            Motion::Rapid => "G00",
            Motion::Linear => "G01",
            Motion::Cw => "G02",
            Motion::Ccw => "G03",
            Motion::Cycle(73) => "G73",
            Motion::Cycle(74) => "G74",
            Motion::Cycle(84) => "G84",
            Motion::Cycle(81) => "G81",
            Motion::Cycle(82) => "G82",
            Motion::Cycle(83) => "G83",
            Motion::Cycle(85) => "G85",
            Motion::Cycle(86) => "G86",
            Motion::Cycle(_) => "G89",
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
    /// G92, G92.1, G92.2, G92.3 (tenths: 920..923) and G52 (520).
    Shift(u16),
    /// G53: this line's motion in machine coordinates.
    Machine,
    /// G28, G28.1, G30, G30.1 (tenths).
    Home(u16),
    /// G43 (430), G43.1 (431), G49 (490).
    ToolLength(u16),
    /// G90.1 (true) / G91.1 (false).
    ArcAbsolute(bool),
    /// G98 (true: retract to the initial Z) / G99 (false: to R).
    Retract(bool),
    /// G80: cancel the motion mode.
    CancelCycle,
    /// G93 (inverse time), G94 (per minute), G95 (per revolution).
    FeedMode(u8),
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
            GCode::Shift(_) | GCode::Home(_) => 0,
            GCode::Machine => 0,
            GCode::ToolLength(_) => 8,
            GCode::ArcAbsolute(_) => 4,
            GCode::Retract(_) => 10,
            GCode::CancelCycle => 1,
            GCode::FeedMode(_) => 5,
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
            "supported: G00 G01 G02 G03 G04 G10 G17 G18 G19 G20 G21 G28 G30 G40 G43 G49 G52 G53 G54-G59 G61 G64 G73 G74 G80-G86 G89 G90 G91 G92 G93-G95 G98 G99",
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
        400 | 80 | 970 => GCode::NoOp,
        911 => GCode::ArcAbsolute(false),
        901 => GCode::ArcAbsolute(true),
        800 => GCode::CancelCycle,
        930 => GCode::FeedMode(93),
        940 => GCode::FeedMode(94),
        950 => GCode::FeedMode(95),
        610 | 611 => GCode::ExactStop,
        640 => GCode::Blend,
        920..=923 | 520 => GCode::Shift(code as u16),
        530 => GCode::Machine,
        280 | 281 | 300 | 301 => GCode::Home(code as u16),
        430 | 431 | 490 => GCode::ToolLength(code as u16),
        980 => GCode::Retract(true),
        990 => GCode::Retract(false),
        730 | 740 | 810 | 820 | 830 | 840 | 850 | 860 | 890 => GCode::Motion(Motion::Cycle((code / 10) as u8)),
        410 | 420 | 411 | 421 => {
            return Err(unsupported(
                "G41/G42 cutter radius compensation is not supported",
                "program the tool centre path (most CAM systems can output it)",
            ))
        }
        432 => {
            return Err(unsupported(
                "G43.2 (additional tool length offset) is not supported",
                "give the tool length with G43.1 Z<length>",
            ))
        }
        382..=385 => {
            return Err(unsupported(
                &format!("{} (straight probe) is not supported", w.text),
                "a robot path has no probe input: remove the probing moves (and what uses their result, #5061–#5070)",
            ))
        }
        330 | 331 => {
            return Err(unsupported(
                "G33 (spindle-synchronized motion, threading) is not supported",
                "a robot path has no spindle synchronization; remove the threading",
            ))
        }
        760 | 870 | 880 => {
            return Err(unsupported(
                &format!("canned cycle {} is not supported", w.text),
                "supported cycles: G73 G74 G81 G82 G83 G84 G85 G86 G89; expand this one into G00/G01 moves",
            ))
        }
        50 | 51 | 52 | 53 | 62 => {
            return Err(unsupported(
                &format!("{} (spline or NURBS) is not supported", w.text),
                "let the CAM system output lines and arcs (G01/G02/G03)",
            ))
        }
        70 | 700 | 710 | 711 | 720 | 721 => {
            return Err(unsupported(
                &format!("{} (lathe mode or lathe cycle) is not supported", w.text),
                "a robot path is read in milling mode; remove it",
            ))
        }
        960 => {
            return Err(unsupported(
                &format!("{} (spindle speed mode) is not supported", w.text),
                "G96 constant surface speed needs a lathe; remove it (or write G97)",
            ))
        }
        591..=593 => {
            return Err(unsupported(
                "G59.1–G59.3 work offsets are not supported",
                "use G54–G59",
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

/// The argument letters M code `m` uses (LinuxCNC: M3/M4/M5 `$` (spindle number); M19 R Q P
/// `$`; M50–M53 P (overrides, adaptive feed, feed stop); M62–M65 P; M66 P E L Q; M67/M68 E Q;
/// M61 Q; M100–M199 P Q).
pub(super) fn m_letters(m: f64) -> &'static str {
    match m as i64 {
        3..=5 => "$",
        19 => "RQP$",
        50..=53 => "P",
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
            if v == 47.0 {
                "M47 (repeat the program from its first line) is not supported"
            } else {
                "M98/M99 with a computed number are not read (M98 P<n> L<k> and M99 are)"
            },
            if v == 47.0 {
                "write the moves out in full, or repeat them with M98 P<n> L<k> or o… repeat"
            } else {
                "write M98 or M99 as plain numbers"
            },
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
pub(super) const ARG_LETTERS: &str = "FIJKLOPRSTXYZDEHQ@^$";

/// Number of [`ARG_LETTERS`].
pub(super) const N_ARGS: usize = 20;

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
