//! Arc blocks (G02/G03): centre from I/J/K offsets or from R (the circle itself:
//! [`crate::geometry::arc`]), the radius check, and the hint naming the plane the offsets
//! would fit.

use super::codes::{Args, Motion};
use super::frames::rotate_z;
use super::interpreter::Interpreter;
use super::lexer::Word;
use super::program::{arc_tolerance, err, GcodeError, GcodeErrorKind};
use crate::geometry::{center_from_radius, ArcDirection, ArcError, Plane, RadiusArcError, Segment};
use nalgebra::Vector3;

impl Interpreter {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn arc_by_radius(
        &self,
        line: usize,
        col: usize,
        line_text: &str,
        mode: Motion,
        start: Vector3<f64>,
        end: Vector3<f64>,
        r: &Word<'_>,
        dir: ArcDirection,
    ) -> Result<Segment, GcodeError> {
        use GcodeErrorKind::*;
        let plane = self.plane;
        let radius = r.value * self.scale();
        let tol = arc_tolerance(self.inch);
        let center =
            center_from_radius(start, end, plane, radius, dir, tol).map_err(|e| match e {
                RadiusArcError::ZeroRadius => err(
                    line,
                    r.col,
                    Arc,
                    r.text,
                    "arc radius R is zero",
                    "give the radius (negative for the long way round, more than 180°)",
                ),
                RadiusArcError::ZeroChord => err(
                    line,
                    col,
                    Arc,
                    line_text,
                    format!(
                    "{} with R and a zero-length arc: start and end coincide in the {} plane ({})",
                    mode.code(),
                    plane.name(),
                    plane.gcode()
                ),
                    "R cannot describe a full circle: give the centre with I/J/K offsets",
                ),
                RadiusArcError::RadiusBelowHalfChord { radius, half_chord } => err(
                    line,
                    r.col,
                    Arc,
                    line_text,
                    format!(
                        "|R| = {:.4} mm is less than half the chord ({:.4} mm)",
                        radius * 1e3,
                        half_chord * 1e3
                    ),
                    "increase R or move the end point: no circle of that radius joins the points",
                ),
            })?;
        Segment::arc(start, center, end, plane, dir).map_err(|e| arc_error(e, line, col, line_text))
    }

    /// The centre's offset from `start` that I, J, K give (program units scaled to metres;
    /// G90.1: from the centre in program coordinates; rotated with a rotated system) and which
    /// of the three are given.
    fn centre_offset(&self, start: Vector3<f64>, args: &Args<'_, '_>) -> (Vector3<f64>, [bool; 3]) {
        let scale = self.scale();
        let ijk = [args.get('I'), args.get('J'), args.get('K')];
        let mut given = ijk.map(|w| w.is_some());
        let mut off = Vector3::zeros();
        for (a, w) in ijk.iter().enumerate() {
            off[a] = w.map_or(0.0, |w| w.value) * scale;
        }
        if self.ext.arc_absolute {
            // G90.1: I J K are the centre in program coordinates (LinuxCNC).
            let work = self.work();
            let (u, v) = match self.plane {
                Plane::XY => (0, 1),
                Plane::ZX => (2, 0),
                Plane::YZ => (1, 2),
            };
            let local = self.to_program(start);
            for a in [u, v] {
                off[a] += if self.rotation() == 0.0 {
                    work[a] - start[a]
                } else {
                    -local[a]
                };
                given[a] = true;
            }
        }
        if self.rotation() != 0.0 {
            // A rotated system (G10 L2 R, G17 only): the offsets rotate with it.
            off = rotate_z(off, self.rotation());
        }
        (off, given)
    }

    /// What is wrong with an arc whose centre offsets do not fit the plane.
    fn arc_problem_text(&self, problem: &ArcProblem, mode: Motion, tol: f64) -> String {
        let scale = self.scale();
        let letters = |p: Plane| {
            let (u, v, _) = p.axes();
            format!("{}/{}", IJK[u], IJK[v])
        };
        let unit = if self.inch { "in" } else { "mm" };
        match problem {
            ArcProblem::MissingOffsets => format!(
                "{} in the {} plane ({}) needs the centre offsets {} (or R)",
                mode.code(),
                self.plane.name(),
                self.plane.gcode(),
                letters(self.plane)
            ),
            ArcProblem::ZeroRadius => format!(
                "arc radius is zero in the {} plane ({}): the {} offsets put the centre on the start point",
                self.plane.name(),
                self.plane.gcode(),
                letters(self.plane)
            ),
            &ArcProblem::RadiusMismatch { r0, r1 } => format!(
                "arc start and end radii differ in the {} plane ({}): {:.4} {unit} vs {:.4} {unit} (tolerance {} {unit})",
                self.plane.name(),
                self.plane.gcode(),
                r0 / scale,
                r1 / scale,
                tol / scale
            ),
            &ArcProblem::NormalOffset { letter } => format!(
                "the {letter} offset lies along the normal of the {} plane ({}) and must be 0",
                self.plane.name(),
                self.plane.gcode()
            ),
        }
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn arc_by_centre(
        &self,
        line: usize,
        col: usize,
        line_text: &str,
        mode: Motion,
        start: Vector3<f64>,
        end: Vector3<f64>,
        args: &Args<'_, '_>,
        dir: ArcDirection,
    ) -> Result<Segment, GcodeError> {
        let (off, given) = self.centre_offset(start, args);
        let tol = arc_tolerance(self.inch);
        let center = start + off;
        let check = |p: Plane| check_arc_plane(p, start, end, off, given, tol);
        let Err(problem) = check(self.plane) else {
            return Segment::arc(start, center, end, self.plane, dir)
                .map_err(|e| arc_error(e, line, col, line_text));
        };
        let letters = |p: Plane| {
            let (u, v, _) = p.axes();
            format!("{}/{}", IJK[u], IJK[v])
        };
        let message = self.arc_problem_text(&problem, mode, tol);
        let fits: Vec<Plane> = Plane::ALL
            .into_iter()
            .filter(|&p| p != self.plane && check(p).is_ok())
            .collect();
        let hint = match fits.first() {
            Some(&p) => format!(
                "the {} offsets fit the {} plane ({}): did you mean {} instead of {}?",
                letters(p),
                p.name(),
                p.gcode(),
                p.gcode(),
                self.plane.gcode()
            ),
            None => match problem {
                ArcProblem::MissingOffsets => format!(
                    "give the centre as offsets {} from the start point",
                    letters(self.plane)
                ),
                ArcProblem::NormalOffset { letter } => {
                    format!("remove {letter} or select the plane the arc lies in (G17/G18/G19)")
                }
                _ => "check the end point and the centre offsets (relative to the start point)"
                    .to_string(),
            },
        };
        Err(err(
            line,
            col,
            GcodeErrorKind::Arc,
            line_text,
            message,
            hint,
        ))
    }
}

pub(super) const IJK: [char; 3] = ['I', 'J', 'K'];

pub(super) enum ArcProblem {
    MissingOffsets,
    ZeroRadius,
    RadiusMismatch { r0: f64, r1: f64 },
    NormalOffset { letter: char },
}

/// Whether centre offsets `off` (m, from `start`) describe a valid arc in `plane`.
pub(super) fn check_arc_plane(
    plane: Plane,
    start: Vector3<f64>,
    end: Vector3<f64>,
    off: Vector3<f64>,
    given: [bool; 3],
    tol: f64,
) -> Result<(), ArcProblem> {
    let (u, v, w) = plane.axes();
    if !(given[u] || given[v]) {
        return Err(ArcProblem::MissingOffsets);
    }
    let c = start + off;
    let r0 = (start[u] - c[u]).hypot(start[v] - c[v]);
    let r1 = (end[u] - c[u]).hypot(end[v] - c[v]);
    if r0 <= tol {
        return Err(ArcProblem::ZeroRadius);
    }
    if (r1 - r0).abs() > tol || r1.is_nan() {
        return Err(ArcProblem::RadiusMismatch { r0, r1 });
    }
    if off[w].abs() > tol {
        return Err(ArcProblem::NormalOffset { letter: IJK[w] });
    }
    Ok(())
}

pub(super) fn arc_error(e: ArcError, line: usize, col: usize, line_text: &str) -> GcodeError {
    err(
        line,
        col,
        GcodeErrorKind::Arc,
        line_text,
        e.to_string(),
        "check the end point and the centre",
    )
}
