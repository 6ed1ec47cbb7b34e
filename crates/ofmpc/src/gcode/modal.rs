//! The modal codes CAM output uses beyond the basic ones (LinuxCNC's G-code reference):
//! G92/G92.1/G92.2/G92.3 and G52 offsets, G53, G28/G30 (+.1) stored positions, G43 H (tool
//! table)/G43.1/G49 tool length (the points are the tip's; a change of length moves the
//! current point along the tool axis; the planner extends the TCP), G90.1 absolute arc centres, G93/G95
//! feed modes, polar `@ ^`, the canned cycles G73 G74 G81 G82 G83 G84 G85 G86 G89 with G98/G99
//! and L in G17, G18 and G19,
//! and G64 Q (collinear moves within Q merged, LinuxCNC's naive-CAM detector).

use super::codes::{Args, Motion};
use super::frames::rotate_z;
use super::interpreter::{Extra, Interpreter};
use super::lexer::Word;
use super::program::{
    err, GcodeError, GcodeErrorKind, Move, MoveKind, PathMode, ProgramEvent, MIN_MOVE_LENGTH,
};
use crate::geometry::{Plane, Segment};
use nalgebra::Vector3;

/// Retract after each peck of G73 and re-approach of G83 (LinuxCNC: 0.010 in).
const PECK_DELTA_INCH: f64 = 0.010;

/// Longest run of moves G64 Q merges into one (bounds the work per move).
const MAX_MERGE_RUN: usize = 1000;

impl Interpreter {
    /// The offset from program to machine coordinates (m): work offset plus G92/G52, or
    /// zero on a G53 line.
    pub(super) fn work(&self) -> [f64; 3] {
        if self.ext.machine {
            let t = self.tip_offset();
            return [t.x, t.y, t.z];
        }
        let o = self.offsets.get(self.wcs).copied().unwrap_or([0.0; 3]);
        [0, 1, 2].map(|a| o[a] + self.ext.g92[a])
    }

    /// Where the tool is, for commands that need it before any motion: the position, else
    /// the tool position before the program, else machine zero.
    pub(super) fn here(&self) -> Vector3<f64> {
        self.pos
            .or(self.initial_tip())
            .unwrap_or_else(Vector3::zeros)
    }

    /// The tip's position before the program: the options' start (the controlled point,
    /// with no tool length) plus the tool length in force along the tool axis.
    pub(super) fn initial_tip(&self) -> Option<Vector3<f64>> {
        self.initial.map(|p| p + self.tool_length * self.tool_axis)
    }

    /// The offset (m) from a controlled point (machine coordinates: G53, G28/G30 stored
    /// positions) to the tip: the tool length along the tool axis (LinuxCNC's find_ends
    /// and find_relative subtract the tool offset from machine coordinates).
    pub(super) fn tip_offset(&self) -> Vector3<f64> {
        self.tool_length * self.tool_axis
    }

    /// G92 (920), G92.1, G92.2, G92.3, G52 (520).
    pub(super) fn shift(&mut self, code: u16, args: &Args<'_, '_>) {
        let scale = self.scale();
        let here = self.here();
        let o = self.offsets.get(self.wcs).copied().unwrap_or([0.0; 3]);
        match code {
            920 => {
                // With a rotation θ: g92 = Rz(-θ)·(here - o) - p (see super::frames).
                let theta = self.ext.rotation.get(self.wcs).copied().unwrap_or(0.0);
                let unrotated = rotate_z(here - Vector3::from(o), -theta);
                for (a, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
                    if let Some(w) = args.get(c) {
                        self.ext.g92[a] = if theta == 0.0 {
                            here[a] - w.value * scale - o[a]
                        } else {
                            unrotated[a] - w.value * scale
                        };
                    }
                }
            }
            520 => {
                for (a, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
                    if let Some(w) = args.get(c) {
                        self.ext.g92[a] = w.value * scale;
                    }
                }
            }
            921 => {
                self.ext = Extra {
                    g92: [0.0; 3],
                    g92_saved: [0.0; 3],
                    ..std::mem::take(&mut self.ext)
                }
            }
            922 => {
                self.ext.g92_saved = self.ext.g92;
                self.ext.g92 = [0.0; 3];
            }
            _ => self.ext.g92 = self.ext.g92_saved,
        }
    }

    /// G28/G30 (go to the stored position, through the given point) and G28.1/G30.1 (store).
    pub(super) fn home(
        &mut self,
        line: usize,
        w: &Word<'_>,
        code: u16,
        args: &Args<'_, '_>,
    ) -> Result<(), GcodeError> {
        let k = usize::from(code >= 300);
        if code % 10 == 1 {
            self.ext.home[k] = Some(self.here() - self.tip_offset());
            return Ok(());
        }
        if self.pos.is_none() {
            match self.initial_tip() {
                Some(p0) => self.begin_at(p0, line),
                None => {
                    return Err(err(
                        line,
                        w.col,
                        GcodeErrorKind::StartPoint,
                        w.text,
                        format!("{} before the start point is known", w.text),
                        "start the program with G00 X.. Y.. Z..",
                    ))
                }
            }
        }
        let pos = self.here();
        let stored = self.ext.home[k]
            .or(self.initial)
            .unwrap_or_else(Vector3::zeros)
            + self.tip_offset();
        let given: Vec<usize> = ['X', 'Y', 'Z']
            .iter()
            .enumerate()
            .filter(|(_, &c)| args.get(c).is_some())
            .map(|(a, _)| a)
            .collect();
        let mut end = stored;
        if !given.is_empty() {
            let via = self.motion_target(pos, args);
            self.push_line(line, pos, via, true);
            end = via;
            for a in given {
                end[a] = stored[a];
            }
        }
        let from = self.here();
        self.push_line(line, from, end, true);
        Ok(())
    }

    /// G43 H<n> (tool n's length from the tool table; without H the tool in the spindle;
    /// H0: no length), G43.1 Z<length>, G49 (LinuxCNC's G43).
    pub(super) fn tool_length_code(
        &mut self,
        line: usize,
        w: &Word<'_>,
        code: u16,
        args: &Args<'_, '_>,
    ) -> Result<(), GcodeError> {
        let length = match (code, args.get('Z')) {
            (431, Some(z)) => z.value * self.scale(),
            (430, _) => self.g43_length(line, w, args)?,
            _ => 0.0,
        };
        // No axis moves, so the tip's current point moves with the length (LinuxCNC's
        // convert_tool_length_offset: current_z += old − new, the tool along −Z).
        let delta = length - self.tool_length;
        if delta != 0.0 {
            if let Some(p) = self.pos.as_mut() {
                *p += delta * self.tool_axis;
            }
            self.ext.merged.clear();
        }
        self.tool_length = length;
        Ok(())
    }

    /// G43's length: tool H<n>'s (without H the tool in the spindle) from the tool table;
    /// H0: no length.
    fn g43_length(
        &self,
        line: usize,
        w: &Word<'_>,
        args: &Args<'_, '_>,
    ) -> Result<f64, GcodeError> {
        let (n, at) = match args.get('H') {
            Some(h) => (h.value, h),
            None => (self.ext.tool_current, w),
        };
        let fail = |message: String, hint: &str| {
            Err(err(
                line,
                at.col,
                GcodeErrorKind::InvalidValue,
                at.text,
                message,
                hint,
            ))
        };
        if !(n >= 0.0 && n.fract() == 0.0 && n <= f64::from(u32::MAX)) {
            return fail(
                format!("G43 H{n}: the tool number must be a whole number >= 0"),
                "write e.g. G43 H1",
            );
        }
        Ok(if n == 0.0 {
            0.0
        } else {
            match &self.tools {
                None => {
                    return Err(err(
                        line,
                        at.col,
                        GcodeErrorKind::Missing,
                        at.text,
                        format!("G43 with tool {n}: no tool table was given, so its length is not known"),
                        "give a tool table (LinuxCNC's .tbl format, lengths in mm) with the reading options, or the length with G43.1 Z<length>",
                    ))
                }
                Some(t) => match t.length(n as u32) {
                    Some(z) => z,
                    None => {
                        return fail(
                            format!("G43 with tool {n}: the tool table has no tool {n}"),
                            "add the tool to the table (T<n> Z<length>) or use a tool it lists",
                        )
                    }
                },
            }
        })
    }

    /// The feed (m/s) of a move of `length` m in the active feed mode.
    pub(super) fn move_feed(&self, rapid: bool, length: f64) -> Option<f64> {
        let f = self.feed.filter(|_| !rapid)?;
        let scale = self.scale();
        match self.ext.feed_mode {
            93 => Some(length * f / 60.0),
            95 => self.ext.spindle.map(|s| f * s * scale / 60.0),
            _ => Some(f * scale / 60.0),
        }
    }

    /// Appends a straight move from `a` to `b` (skipped if zero-length); G64 Q merges it
    /// with the last one where the points stay within Q of one line.
    pub(super) fn push_line(&mut self, line: usize, a: Vector3<f64>, b: Vector3<f64>, rapid: bool) {
        let a = self.ext.machine_at.take().unwrap_or(a);
        self.pos = Some(b);
        if (b - a).norm() <= MIN_MOVE_LENGTH {
            return;
        }
        let feed = self.move_feed(rapid, (b - a).norm());
        if !rapid && self.try_merge(a, b, feed) {
            return;
        }
        self.ext.merged.clear();
        self.moves.push(Move {
            line,
            kind: MoveKind::Path {
                segment: Segment::line(a, b),
                feed,
                mode: self.mode,
            },
            tool_length: self.tool_length,
        });
    }

    /// G64 Q: replaces the last move by one to `b` if it is a straight feed move at the same
    /// feed, ends at `a`, no event came between, and every point it replaces stays within Q.
    fn try_merge(&mut self, a: Vector3<f64>, b: Vector3<f64>, feed: Option<f64>) -> bool {
        let Some(q) = self.ext.merge_q else {
            return false;
        };
        if !matches!(self.mode, Some(PathMode::Blend { .. }))
            || self.ext.merged.len() >= MAX_MERGE_RUN
            || self
                .events
                .last()
                .is_some_and(|e| e.after_moves == self.moves.len())
        {
            return false;
        }
        let mode = self.mode;
        let Some(Move {
            kind:
                MoveKind::Path {
                    segment: Segment::Line { .. },
                    feed: f0,
                    mode: m0,
                },
            ..
        }) = self.moves.last()
        else {
            return false;
        };
        if *f0 != feed
            || *m0 != mode
            || self.moves.last().map(|m| m.tool_length) != Some(self.tool_length)
        {
            return false;
        }
        let s = match self.moves.last() {
            Some(Move {
                kind: MoveKind::Path { segment, .. },
                ..
            }) => segment.start(),
            _ => return false,
        };
        let near = |p: &Vector3<f64>| distance_to_segment(p, &s, &b) <= q;
        if (self.moves.last().map(|m| m.line).is_none())
            || !near(&a)
            || !self.ext.merged.iter().all(near)
        {
            return false;
        }
        self.ext.merged.push(a);
        if let Some(Move {
            kind: MoveKind::Path { segment, .. },
            ..
        }) = self.moves.last_mut()
        {
            *segment = Segment::line(s, b);
        }
        true
    }

    /// The polar end point (`@` distance, `^` angle in degrees, plane XY): from the origin
    /// of the coordinate system (G90) or from the current point (G91).
    pub(super) fn polar_target(
        &self,
        line: usize,
        pos: Vector3<f64>,
        args: &Args<'_, '_>,
    ) -> Result<Option<Vector3<f64>>, GcodeError> {
        let (r, t) = (args.get('@'), args.get('^'));
        let Some(w) = r.or(t) else { return Ok(None) };
        let bad = |m: &str| {
            Err(err(
                line,
                w.col,
                GcodeErrorKind::Conflict,
                w.text,
                m.to_string(),
                "write G01 @<distance> ^<angle> in G17, without X and Y",
            ))
        };
        if self.plane != Plane::XY || args.get('X').is_some() || args.get('Y').is_some() {
            return bad("polar coordinates are read in the XY plane (G17) and replace X and Y");
        }
        let (Some(r), Some(t)) = (r, t) else {
            return bad("a polar point needs both @ (distance) and ^ (angle)");
        };
        let scale = self.scale();
        let (s, c) = t.value.to_radians().sin_cos();
        let (dx, dy) = (r.value * scale * c, r.value * scale * s);
        let given = [Some(dx), Some(dy), args.get('Z').map(|z| z.value * scale)];
        Ok(Some(if self.absolute {
            self.place(pos, given)
        } else {
            self.shift_by(pos, given)
        }))
    }

    /// A canned cycle (G73 G74 G81 G82 G83 G84 G85 G86 G89) at the line's position in the
    /// selected plane, drilling along the plane's normal: G17 along Z (position X Y), G18
    /// along Y (position Z X), G19 along X (position Y Z), LinuxCNC's `convert_cycle_xy`,
    /// `_zx`, `_yz`. R and the bottom are coordinates of the drilling axis.
    pub(super) fn cycle(
        &mut self,
        line: usize,
        w_col: usize,
        line_text: &str,
        n: u8,
        args: &Args<'_, '_>,
    ) -> Result<(), GcodeError> {
        use GcodeErrorKind::*;
        let code = Motion::Cycle(n).code();
        let fail = |kind, message: String, hint: &str| {
            Err(err(line, w_col, kind, line_text, message, hint))
        };
        let (_, _, d) = self.plane.axes();
        if self.plane != Plane::XY && self.rotation() != 0.0 {
            return fail(
                Unsupported,
                format!(
                    "{code} in the {} plane of a rotated coordinate system (G10 L2 R) is not supported",
                    self.plane.gcode()
                ),
                "drill in G17 in a rotated system, or rotate the program in the CAM system",
            );
        }
        let letters = ['X', 'Y', 'Z'];
        for (k, c) in ['R', letters[d], 'Q', 'P'].into_iter().enumerate() {
            if let Some(w) = args.get(c) {
                self.ext.cycle[k] = Some(w.value);
            }
        }
        let [Some(r), Some(z)] = [self.ext.cycle[0], self.ext.cycle[1]] else {
            return fail(
                Missing,
                format!("{code} without R or {}", letters[d]),
                "give the retract plane R and the bottom along the drilling axis (Z in G17, Y in G18, X in G19; they stay in force for the next holes)",
            );
        };
        let q = self.ext.cycle[2].unwrap_or(0.0);
        if matches!(n, 73 | 83) && q <= 0.0 {
            return fail(
                Missing,
                format!("{code} needs a peck depth Q > 0"),
                "give Q, e.g. Q1",
            );
        }
        self.check_tapping_spindle(line, w_col, line_text, n)?;
        let repeats = cycle_repeats(line, args)?;
        let Some(mut p) = self.pos.or(self.initial_tip()) else {
            return fail(
                StartPoint,
                format!("{code} before the start point is known"),
                "start the program with G00 X.. Y.. Z..",
            );
        };
        if self.pos.is_none() {
            self.begin_at(p, line);
        }
        let scale = self.scale();
        let work = self.work();
        let z0 = *self.ext.cycle_z0.get_or_insert(p[d]);
        // G91: R is relative to the initial level (LinuxCNC's cycle_il, kept from the first
        // cycle line until a motion that is not a cycle), not to the current point.
        let (r_m, bottom) = if self.absolute {
            (r * scale + work[d], z * scale + work[d])
        } else {
            (z0 + r * scale, z0 + r * scale + z * scale)
        };
        let clear = if self.ext.retract_initial {
            z0.max(r_m)
        } else {
            r_m
        };
        if p[d] < r_m {
            let mut to = p;
            to[d] = r_m;
            self.push_line(line, p, to, true);
            p = to;
        }
        let dwell = self.ext.cycle[3].unwrap_or(0.0);
        if let Some((message, hint)) = cycle_checks(code, r_m, bottom, dwell) {
            return fail(InvalidValue, message, hint);
        }
        let mut given = [None; 3];
        for (a, c) in letters.into_iter().enumerate() {
            if a != d {
                given[a] = args.get(c).map(|w| w.value * scale);
            }
        }
        let hole = Hole {
            top: p,
            axis: d,
            bottom,
            clear,
        };
        self.drill_holes(
            line,
            n,
            (p, given),
            (repeats, r_m),
            &hole,
            (q * scale, dwell),
        );
        Ok(())
    }

    /// The holes of a canned cycle from `p` (its `repeats`, each shifted by `given` in G91):
    /// to the hole's position, down to the retract plane `r_m`, drilled as `hole` says (its
    /// `top` set per hole), and out to its clearance level.
    fn drill_holes(
        &mut self,
        line: usize,
        n: u8,
        (mut p, given): (Vector3<f64>, [Option<f64>; 3]),
        (repeats, r_m): (usize, f64),
        hole: &Hole,
        (peck, dwell): (f64, f64),
    ) {
        let (d, clear) = (hole.axis, hole.clear);
        for _ in 0..repeats {
            if self.over_budget().is_some() {
                break; // reported by the caller, naming the limit
            }
            let mut xy = if self.absolute {
                self.place(p, given)
            } else {
                self.shift_by(p, given)
            };
            xy[d] = p[d];
            self.push_line(line, p, xy, true);
            let mut top = xy;
            top[d] = r_m;
            self.push_line(line, xy, top, true);
            let hole = Hole { top, ..*hole };
            self.drill(line, n, &hole, peck, dwell);
            let mut end = xy;
            end[d] = clear;
            if self.ext.machine_at.is_none() {
                let here = self.here();
                self.push_line(line, here, end, true);
            }
            p = end;
        }
    }

    /// G74 needs the spindle turning counter-clockwise, G84 clockwise (LinuxCNC's
    /// `check_g74_g84_spindle`).
    fn check_tapping_spindle(
        &self,
        line: usize,
        col: usize,
        line_text: &str,
        n: u8,
    ) -> Result<(), GcodeError> {
        let turning = if n == 74 { -1 } else { 1 };
        if !matches!(n, 74 | 84) || self.ext.spindle_dir == turning {
            return Ok(());
        }
        let (m, dir) = if n == 74 {
            ("M4", "counter-clockwise")
        } else {
            ("M3", "clockwise")
        };
        Err(err(
            line,
            col,
            GcodeErrorKind::Conflict,
            line_text,
            format!(
                "{} (tapping) needs the spindle turning {dir} (LinuxCNC refuses it otherwise)",
                Motion::Cycle(n).code()
            ),
            format!("start the spindle with {m} S… before the cycle"),
        ))
    }

    /// The drilling of one hole from `top` (on R) to the bottom, ending at the bottom or,
    /// for G85/G89, back on R, for G74/G84 back on the clear plane.
    fn drill(&mut self, line: usize, n: u8, hole: &Hole, q: f64, dwell: f64) {
        let (top, d, bottom) = (hole.top, hole.axis, hole.bottom);
        let at = |z: f64| {
            let mut v = top;
            v[d] = z;
            v
        };
        let delta = PECK_DELTA_INCH * 0.0254;
        match n {
            73 | 83 => {
                let mut depth = top[d];
                // Stopped at once past the program's budget (the caller reports it).
                while depth > bottom + MIN_MOVE_LENGTH && self.over_budget().is_none() {
                    let next = (depth - q).max(bottom);
                    let here = self.here();
                    if n == 83 && depth < top[d] {
                        self.push_line(line, here, at(depth + delta), true);
                    }
                    let here = self.here();
                    self.push_line(line, here, at(next), false);
                    depth = next;
                    if depth > bottom + MIN_MOVE_LENGTH {
                        let up = if n == 83 { top[d] } else { depth + delta };
                        self.push_line(line, at(depth), at(up), true);
                    }
                }
            }
            74 | 84 => {
                // LinuxCNC's convert_cycle_g74_g84: feed in, stop and reverse the spindle,
                // dwell, feed out to the clear plane, stop and restore the spindle.
                let (reverse, forward) = if n == 84 { ("M4", "M3") } else { ("M3", "M4") };
                let (down, up) = (
                    self.tap_point(line, n, at(bottom)),
                    self.tap_point(line, n, at(hole.clear)),
                );
                self.push_line(line, top, down, false);
                self.spindle_event(line, "M5");
                self.spindle_event(line, reverse);
                self.push_dwell(line, dwell);
                self.push_line(line, down, up, false);
                self.spindle_event(line, "M5");
                self.spindle_event(line, forward);
                if up != at(hole.clear) {
                    // The interpreter's point is the hole's clear point; the tool is at `up`.
                    self.pos = Some(at(hole.clear));
                    self.ext.machine_at = Some(up);
                }
            }
            _ => {
                self.push_line(line, top, at(bottom), false);
                if matches!(n, 82 | 89) {
                    self.push_dwell(line, dwell);
                }
                if matches!(n, 85 | 89) {
                    self.push_line(line, at(bottom), top, false);
                }
            }
        }
    }

    /// A dwell move of `seconds` if it is positive.
    fn push_dwell(&mut self, line: usize, seconds: f64) {
        if seconds > 0.0 {
            self.moves.push(Move {
                line,
                kind: MoveKind::Dwell { seconds },
                tool_length: self.tool_length,
            });
        }
    }

    /// A spindle event of a tapping cycle (`M3`, `M4`, `M5`), after the moves so far.
    fn spindle_event(&mut self, line: usize, code: &str) {
        self.events.push(ProgramEvent {
            line,
            code: code.to_string(),
            words: Vec::new(),
            after_moves: self.moves.len(),
        });
    }
}

/// One hole of a canned cycle: its top (on R, m, machine), the drilling axis (0 X, 1 Y,
/// 2 Z), the bottom and the clear plane (coordinates along that axis, m).
struct Hole {
    top: Vector3<f64>,
    axis: usize,
    bottom: f64,
    clear: f64,
}

impl Interpreter {
    /// The point G74/G84 feeds to for the hole point `c` (machine coordinates): `c` in G17;
    /// in G18 and G19 the point LinuxCNC's interpreter outputs, whose
    /// `convert_cycle_g74_g84` passes the plane's already permuted coordinates to
    /// `cycle_feed`, which permutes them again (interp_cycles.cc): with `c = (x, y, z)` in
    /// program coordinates, G18 feeds to `(y, z, x)` and G19 to `(z, x, y)`. Warns once.
    fn tap_point(&mut self, line: usize, n: u8, c: Vector3<f64>) -> Vector3<f64> {
        let w = Vector3::from(self.work());
        let p = c - w;
        let q = match self.plane {
            Plane::XY => return c,
            Plane::ZX => Vector3::new(p.y, p.z, p.x),
            Plane::YZ => Vector3::new(p.z, p.x, p.y),
        };
        if !self.ext.warned_tap {
            self.ext.warned_tap = true;
            let (x, y, z) = if self.plane == Plane::ZX {
                ("the bottom", "the hole's Z", "the hole's X")
            } else {
                ("the hole's Z", "the bottom", "the hole's Y")
            };
            self.warn(
                line,
                1,
                format!(
                    "G{n} in {}: the tap point follows LinuxCNC's interpreter, which feeds to X = {x}, Y = {y}, Z = {z} (its axes permuted twice), not into the hole",
                    self.plane.gcode()
                ),
            );
        }
        q + w
    }
}

/// LinuxCNC's checks of a canned cycle's words (issue #36): the retract plane `r_m` not
/// below the hole's `bottom` ("R less than Z in cycle": it would rapid below the bottom,
/// then drill up), and a dwell ≥ 0 (as G4 P-1). The message and the hint, if one fails.
fn cycle_checks(code: &str, r_m: f64, bottom: f64, dwell: f64) -> Option<(String, &'static str)> {
    if r_m < bottom - MIN_MOVE_LENGTH {
        return Some((
            format!("{code}: the retract plane R is below the hole's bottom"),
            "R is the plane the drill starts from, above the bottom: give R greater than the \
             bottom (in G91, a bottom word below 0)",
        ));
    }
    (dwell < 0.0).then(|| {
        (
            format!("{code}: negative dwell time P"),
            "give P ≥ 0 (seconds), or leave it out",
        )
    })
}

/// The L word of a canned cycle (repeats; default 1).
fn cycle_repeats(line: usize, args: &Args<'_, '_>) -> Result<usize, GcodeError> {
    match args.get('L') {
        Some(l) if l.value >= 0.0 && l.value.fract() == 0.0 && l.value <= 1e6 => {
            Ok(l.value as usize)
        }
        Some(l) => Err(err(
            line,
            l.col,
            GcodeErrorKind::InvalidValue,
            l.text,
            "L (repeats) must be a whole number from 0 to 1000000 (the limit)",
            "write e.g. L3",
        )),
        None => Ok(1),
    }
}

/// Distance from `p` to the segment `a`–`b`.
fn distance_to_segment(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let d = b - a;
    let l2 = d.norm_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(&d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + d * t)).norm()
}
