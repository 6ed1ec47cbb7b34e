//! Path geometry: straight lines and circular / helical arcs in 3-D, parameterized by arc
//! length.
//!
//! A [`Segment`] knows nothing about time; [`crate::motion::TimeLaw`] decides how fast the arc length
//! `s` advances and [`crate::motion::CartesianTrajectory`] combines both. Every query takes the arc length
//! `s ∈ [0, L]` (clamped) and returns the point `p(s)`, the unit tangent `p'(s)` and the
//! curvature vector `p''(s)`, so that along a time law `s(t)`:
//!
//! `ṗ = p'(s) ṡ`, `p̈ = p'(s) s̈ + p''(s) ṡ²`.
//!
//! Units are SI (metres, radians).

use nalgebra::Vector3;
use std::f64::consts::TAU;

/// A working plane of an arc, as selected in G-code by G17, G18 and G19.
///
/// Each plane has in-plane axes `(u, v)` and a normal axis `w` with `u × v = w`
/// (right-handed), so that a positive angle turns from `u` towards `v` and is counter-clockwise
/// when looking from `+w` down onto the plane (the G03 direction).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Plane {
    /// G17: `u = X`, `v = Y`, normal `Z`.
    XY,
    /// G18: `u = Z`, `v = X`, normal `Y` (so that G02/G03 read correctly when seen from `+Y`).
    ZX,
    /// G19: `u = Y`, `v = Z`, normal `X`.
    YZ,
}

impl Plane {
    /// All three planes, in G17, G18, G19 order.
    pub const ALL: [Plane; 3] = [Plane::XY, Plane::ZX, Plane::YZ];

    /// Indices `(u, v, w)` of the in-plane axes and the normal axis (0 = x, 1 = y, 2 = z).
    pub const fn axes(self) -> (usize, usize, usize) {
        match self {
            Plane::XY => (0, 1, 2),
            Plane::ZX => (2, 0, 1),
            Plane::YZ => (1, 2, 0),
        }
    }

    /// The G-code word that selects this plane (`"G17"`, `"G18"` or `"G19"`).
    pub const fn gcode(self) -> &'static str {
        match self {
            Plane::XY => "G17",
            Plane::ZX => "G18",
            Plane::YZ => "G19",
        }
    }

    /// A human-readable name (`"XY"`, `"ZX"` or `"YZ"`).
    pub const fn name(self) -> &'static str {
        match self {
            Plane::XY => "XY",
            Plane::ZX => "ZX",
            Plane::YZ => "YZ",
        }
    }

    /// Unit vectors `(e_u, e_v, e_w)` of the plane's axes.
    pub fn basis(self) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let (u, v, w) = self.axes();
        let unit = |i: usize| {
            let mut e = Vector3::zeros();
            e[i] = 1.0;
            e
        };
        (unit(u), unit(v), unit(w))
    }
}

/// Direction of travel around an arc, seen from the positive normal axis of its plane.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ArcDirection {
    /// Clockwise (G02): negative sweep.
    Clockwise,
    /// Counter-clockwise (G03): positive sweep.
    CounterClockwise,
}

/// In-plane distance below which an arc's end point counts as equal to its start point, so that
/// the arc is a full turn (m).
pub const CLOSED_ARC_TOLERANCE: f64 = 1e-9;

/// Why an arc could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ArcError {
    /// The start point lies on the centre (in-plane distance below [`CLOSED_ARC_TOLERANCE`]).
    #[error("the arc radius is zero (the start point lies on the centre)")]
    ZeroRadius,
    /// An input was NaN or infinite.
    #[error("the arc's points must be finite")]
    NotFinite,
}

/// One piece of path: a straight line or a circular arc, possibly helical.
#[derive(Debug, Clone, PartialEq)]
pub enum Segment {
    /// Straight line from `a` to `b`.
    Line {
        /// Start point (m).
        a: Vector3<f64>,
        /// End point (m).
        b: Vector3<f64>,
    },
    /// Circular arc in `plane`, a helix when `axial_travel ≠ 0`.
    ///
    /// With `(e_u, e_v, e_w) = plane.basis()` and `λ = s / L ∈ [0, 1]`:
    /// `p(s) = center + radius (cos φ e_u + sin φ e_v) + λ axial_travel e_w`,
    /// `φ = start_angle + λ sweep`.
    Arc {
        /// Centre at the start of the arc (its normal coordinate is the start point's) (m).
        center: Vector3<f64>,
        /// Radius (m), > 0.
        radius: f64,
        /// Working plane.
        plane: Plane,
        /// Angle of the start point about the centre, from `e_u` towards `e_v` (rad).
        start_angle: f64,
        /// Signed sweep (rad): positive counter-clockwise (G03), negative clockwise (G02);
        /// `|sweep| ∈ (0, 2π]`.
        sweep: f64,
        /// Travel along the plane's normal axis from start to end (m); non-zero for a helix.
        axial_travel: f64,
    },
}

impl Segment {
    /// A straight line from `a` to `b`.
    pub fn line(a: Vector3<f64>, b: Vector3<f64>) -> Self {
        Segment::Line { a, b }
    }

    /// An arc in `plane` from `start` about `center` towards `end`, turning in `direction`.
    ///
    /// The radius is the in-plane distance from `center` to `start`; the end angle is the
    /// direction of `end` seen from `center` (the caller checks that `end` lies on the circle;
    /// if it does not, the arc ends on the circle at that angle). The normal coordinate moves
    /// linearly with angle from `start` to `end` (helix). If `end` and `start` coincide in the
    /// plane (within `CLOSED_ARC_TOLERANCE`) the arc is a full turn. The normal coordinate of
    /// `center` is ignored.
    pub fn arc(
        start: Vector3<f64>,
        center: Vector3<f64>,
        end: Vector3<f64>,
        plane: Plane,
        direction: ArcDirection,
    ) -> Result<Self, ArcError> {
        if !(start.iter().chain(center.iter()).chain(end.iter())).all(|x| x.is_finite()) {
            return Err(ArcError::NotFinite);
        }
        let (u, v, w) = plane.axes();
        let (su, sv) = (start[u] - center[u], start[v] - center[v]);
        let (eu, ev) = (end[u] - center[u], end[v] - center[v]);
        let radius = su.hypot(sv);
        if radius <= CLOSED_ARC_TOLERANCE {
            return Err(ArcError::ZeroRadius);
        }
        let start_angle = sv.atan2(su);
        let end_angle = ev.atan2(eu);
        let closed = (end[u] - start[u]).hypot(end[v] - start[v]) <= CLOSED_ARC_TOLERANCE;
        let sweep = match direction {
            ArcDirection::CounterClockwise => {
                if closed {
                    TAU
                } else {
                    positive_angle(end_angle - start_angle)
                }
            }
            ArcDirection::Clockwise => {
                if closed {
                    -TAU
                } else {
                    -positive_angle(start_angle - end_angle)
                }
            }
        };
        let mut c = center;
        c[w] = start[w];
        Ok(Segment::Arc {
            center: c,
            radius,
            plane,
            start_angle,
            sweep,
            axial_travel: end[w] - start[w],
        })
    }

    /// Path length `L` (m). For a helix, `L = √((r·|sweep|)² + axial_travel²)`.
    pub fn length(&self) -> f64 {
        match self {
            Segment::Line { a, b } => (b - a).norm(),
            Segment::Arc {
                radius,
                sweep,
                axial_travel,
                ..
            } => (radius * sweep.abs()).hypot(*axial_travel),
        }
    }

    /// Start point `p(0)`.
    pub fn start(&self) -> Vector3<f64> {
        match self {
            Segment::Line { a, .. } => *a,
            Segment::Arc { .. } => self.point_at_fraction(0.0),
        }
    }

    /// End point `p(L)`.
    pub fn end(&self) -> Vector3<f64> {
        match self {
            Segment::Line { b, .. } => *b,
            Segment::Arc { .. } => self.point_at_fraction(1.0),
        }
    }

    /// Point at arc length `s` (clamped to `[0, L]`).
    pub fn point(&self, s: f64) -> Vector3<f64> {
        self.point_at_fraction(self.fraction(s))
    }

    /// Unit tangent `dp/ds` at arc length `s` (clamped to `[0, L]`).
    ///
    /// A zero-length line has no direction; it returns the zero vector.
    pub fn tangent(&self, s: f64) -> Vector3<f64> {
        match self {
            Segment::Line { a, b } => {
                let d = b - a;
                let n = d.norm();
                if n > 0.0 {
                    d / n
                } else {
                    Vector3::zeros()
                }
            }
            Segment::Arc {
                radius,
                plane,
                start_angle,
                sweep,
                axial_travel,
                ..
            } => {
                let len = self.length();
                let phi = start_angle + self.fraction(s) * sweep;
                let (eu, ev, ew) = plane.basis();
                (eu * (-radius * phi.sin() * sweep)
                    + ev * (radius * phi.cos() * sweep)
                    + ew * *axial_travel)
                    / len
            }
        }
    }

    /// Curvature vector `d²p/ds²` at arc length `s` (clamped to `[0, L]`): zero on a line,
    /// `−r (sweep/L)² (cos φ e_u + sin φ e_v)` on an arc (pointing at the axis).
    pub fn curvature(&self, s: f64) -> Vector3<f64> {
        match self {
            Segment::Line { .. } => Vector3::zeros(),
            Segment::Arc {
                radius,
                plane,
                start_angle,
                sweep,
                ..
            } => {
                let len = self.length();
                let phi = start_angle + self.fraction(s) * sweep;
                let (eu, ev, _) = plane.basis();
                let k = -radius * (sweep / len).powi(2);
                (eu * phi.cos() + ev * phi.sin()) * k
            }
        }
    }

    /// `λ = s / L` clamped to `[0, 1]` (0 for a zero-length segment).
    fn fraction(&self, s: f64) -> f64 {
        let len = self.length();
        if len > 0.0 {
            (s / len).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    fn point_at_fraction(&self, lambda: f64) -> Vector3<f64> {
        match self {
            Segment::Line { a, b } => {
                if lambda >= 1.0 {
                    *b
                } else {
                    a + (b - a) * lambda
                }
            }
            Segment::Arc {
                center,
                radius,
                plane,
                start_angle,
                sweep,
                axial_travel,
            } => {
                let phi = start_angle + lambda * sweep;
                let (eu, ev, ew) = plane.basis();
                center
                    + eu * (radius * phi.cos())
                    + ev * (radius * phi.sin())
                    + ew * (lambda * axial_travel)
            }
        }
    }
}

/// `x` mapped into `(0, 2π]`.
fn positive_angle(x: f64) -> f64 {
    let r = x.rem_euclid(TAU);
    if r <= 0.0 {
        TAU
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Sampled points of every arc lie at the radius from the axis, the ends are exact, the
    /// tangent is the finite difference of the point and has unit length, the curvature is the
    /// finite difference of the tangent.
    fn check_arc(seg: &Segment, start: Vector3<f64>, end: Vector3<f64>) {
        let Segment::Arc {
            center,
            radius,
            plane,
            ..
        } = seg.clone()
        else {
            panic!("not an arc");
        };
        let (u, vv, _) = plane.axes();
        assert!(
            (seg.start() - start).norm() < 1e-12,
            "start {}",
            seg.start()
        );
        assert!(
            (seg.end() - end).norm() < 1e-12,
            "end {} vs {}",
            seg.end(),
            end
        );
        let len = seg.length();
        let n = 400;
        let h = 1e-6 * len;
        for i in 0..=n {
            let s = len * i as f64 / n as f64;
            let p = seg.point(s);
            let r = (p[u] - center[u]).hypot(p[vv] - center[vv]);
            assert!((r - radius).abs() < 1e-12, "radius {r} vs {radius}");
            let t = seg.tangent(s);
            assert!((t.norm() - 1.0).abs() < 1e-12);
            // Central differences inside (error O(h²)), one-sided at the ends (error ≤ κh/2).
            let (s0, s1) = ((s - h).max(0.0), (s + h).min(len));
            let kappa = seg.curvature(s).norm();
            let one_sided = s1 - s0 < 1.5 * h;
            let tol = if one_sided { kappa * h } else { 1e-8 };
            let fd = (seg.point(s1) - seg.point(s0)) / (s1 - s0);
            assert!((fd - t).norm() < tol, "tangent {t} vs fd {fd}");
            let fdk = (seg.tangent(s1) - seg.tangent(s0)) / (s1 - s0);
            let tol = if one_sided {
                kappa * kappa * h
            } else {
                1e-6 * kappa
            };
            assert!((fdk - seg.curvature(s)).norm() < tol);
        }
    }

    #[test]
    fn quarter_arcs_in_every_plane_and_direction() {
        for plane in Plane::ALL {
            let (eu, ev, _) = plane.basis();
            let c = v(0.1, -0.2, 0.3);
            let r = 0.25;
            let start = c + eu * r;
            let end = c + ev * r;
            let ccw = Segment::arc(start, c, end, plane, ArcDirection::CounterClockwise).unwrap();
            check_arc(&ccw, start, end);
            assert!((ccw.length() - r * PI / 2.0).abs() < 1e-15);
            // Going clockwise takes the long way, three quarters.
            let cw = Segment::arc(start, c, end, plane, ArcDirection::Clockwise).unwrap();
            check_arc(&cw, start, end);
            assert!((cw.length() - r * 3.0 * PI / 2.0).abs() < 1e-14);
            // Counter-clockwise about +w: the cross product of radius and tangent is +w.
            let (_, _, ew) = plane.basis();
            let rad = ccw.point(0.01) - c;
            assert!(rad.cross(&ccw.tangent(0.01)).dot(&ew) > 0.0);
            assert!(rad.cross(&cw.tangent(0.01)).dot(&ew) < 0.0);
        }
    }

    #[test]
    fn full_circle_and_helix() {
        let c = v(0.43, 0.0, 0.4);
        let start = v(0.63, 0.0, 0.4);
        let full = Segment::arc(start, c, start, Plane::XY, ArcDirection::Clockwise).unwrap();
        check_arc(&full, start, start);
        assert!((full.length() - 2.0 * PI * 0.2).abs() < 1e-14);

        // Helix: a half turn in the YZ plane rising 0.1 m along its normal x.
        let c = v(0.0, 0.0, 0.0);
        let start = v(0.0, 0.3, 0.0);
        let end = v(0.1, -0.3, 0.0);
        let helix = Segment::arc(start, c, end, Plane::YZ, ArcDirection::CounterClockwise).unwrap();
        check_arc(&helix, start, end);
        assert!((helix.length() - (0.3 * PI).hypot(0.1)).abs() < 1e-15);
        // The axial coordinate grows linearly with arc length.
        for i in 0..=10 {
            let s = helix.length() * i as f64 / 10.0;
            assert!((helix.point(s).x - 0.1 * i as f64 / 10.0).abs() < 1e-15);
        }
    }

    #[test]
    fn line_queries_and_clamping() {
        let a = v(1.0, 2.0, 3.0);
        let b = v(1.3, 2.4, 3.0);
        let l = Segment::line(a, b);
        assert!((l.length() - 0.5).abs() < 1e-15);
        assert_eq!(l.point(-1.0), a);
        assert_eq!(l.point(9.0), b);
        assert_eq!(l.end(), b);
        assert!((l.point(0.25) - v(1.15, 2.2, 3.0)).norm() < 1e-15);
        assert!((l.tangent(0.1) - v(0.6, 0.8, 0.0)).norm() < 1e-15);
        assert_eq!(l.curvature(0.1), Vector3::zeros());
        let z = Segment::line(a, a);
        assert_eq!(z.tangent(0.0), Vector3::zeros());
        assert_eq!(z.point(1.0), a);
    }

    #[test]
    fn arc_errors() {
        let p = v(0.0, 0.0, 0.0);
        assert_eq!(
            Segment::arc(p, p, v(1.0, 0.0, 0.0), Plane::XY, ArcDirection::Clockwise),
            Err(ArcError::ZeroRadius)
        );
        assert_eq!(
            Segment::arc(
                v(f64::NAN, 0.0, 0.0),
                p,
                p,
                Plane::XY,
                ArcDirection::Clockwise
            ),
            Err(ArcError::NotFinite)
        );
    }
}
