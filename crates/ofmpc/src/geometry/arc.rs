//! The circle of a given radius through two points of a plane (the `R` form of a G02/G03
//! arc).
//!
//! With `(u, v)` the plane's in-plane axes, the chord from `start` to `end` is
//! `d = (Δu, Δv)`, `c = |d|`, its unit direction `t = d / c`. The centre lies on the chord's
//! perpendicular bisector at distance `h = √(R² − (c/2)²)` from the chord's midpoint:
//!
//! `centre = start + d/2 + σ h (−t_v, t_u)`,
//!
//! with `σ = +1` (to the left of the chord, seen from the plane's positive normal) for a
//! counter-clockwise arc of `R > 0` (at most half a turn) or a clockwise arc of `R < 0` (the
//! long way round), `σ = −1` otherwise.

use super::segment::{ArcDirection, Plane, CLOSED_ARC_TOLERANCE};
use nalgebra::Vector3;

/// Why no arc of the given radius joins two points.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum RadiusArcError {
    /// The radius is zero.
    #[error("the arc radius is zero")]
    ZeroRadius,
    /// Start and end coincide in the plane (within [`CLOSED_ARC_TOLERANCE`]): a radius cannot
    /// describe a full circle.
    #[error("start and end coincide in the plane: a radius cannot describe a full circle")]
    ZeroChord,
    /// `|R|` is less than half the chord by more than the tolerance: no circle of that radius
    /// passes through both points.
    #[error("the radius {radius} is less than half the chord ({half_chord})")]
    RadiusBelowHalfChord {
        /// `|R|` (m).
        radius: f64,
        /// Half the in-plane chord `c/2` (m).
        half_chord: f64,
    },
}

/// Centre of the arc in `plane` from `start` to `end` with signed radius `radius` (m; `R < 0`:
/// the long way round, more than half a turn), turning in `direction` (see the module's
/// equation). The normal coordinate of the result is `start`'s.
///
/// A radius short of half the chord by at most `tolerance` (m) counts as exactly half the
/// chord (`h = 0`: a half turn), so that programs rounded to their units still read.
pub fn center_from_radius(
    start: Vector3<f64>,
    end: Vector3<f64>,
    plane: Plane,
    radius: f64,
    direction: ArcDirection,
    tolerance: f64,
) -> Result<Vector3<f64>, RadiusArcError> {
    let (u, v, _) = plane.axes();
    let (du, dv) = (end[u] - start[u], end[v] - start[v]);
    let chord = du.hypot(dv);
    if radius == 0.0 {
        return Err(RadiusArcError::ZeroRadius);
    }
    if chord <= CLOSED_ARC_TOLERANCE {
        return Err(RadiusArcError::ZeroChord);
    }
    let half = chord / 2.0;
    let h2 = radius * radius - half * half;
    let h = if h2 >= 0.0 {
        h2.sqrt()
    } else if radius.abs() >= half - tolerance {
        0.0
    } else {
        return Err(RadiusArcError::RadiusBelowHalfChord {
            radius: radius.abs(),
            half_chord: half,
        });
    };
    // Centre to the left of the chord (seen from +normal) for a short CCW or a long CW arc.
    let left = matches!(
        (direction, radius > 0.0),
        (ArcDirection::CounterClockwise, true) | (ArcDirection::Clockwise, false)
    );
    let sgn = if left { 1.0 } else { -1.0 };
    let (tu, tv) = (du / chord, dv / chord);
    let mut center = start;
    center[u] = start[u] + du / 2.0 - sgn * h * tv;
    center[v] = start[v] + dv / 2.0 + sgn * h * tu;
    Ok(center)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both points lie at `|R|` from the centre, on the side the direction and the sign of `R`
    /// ask for.
    #[test]
    fn centre_is_at_the_radius_on_the_requested_side() {
        let start = Vector3::new(0.1, 0.2, 0.3);
        let end = Vector3::new(0.4, 0.6, 0.3);
        let plane = Plane::XY;
        for (dir, r, left) in [
            (ArcDirection::CounterClockwise, 0.4, true),
            (ArcDirection::CounterClockwise, -0.4, false),
            (ArcDirection::Clockwise, 0.4, false),
            (ArcDirection::Clockwise, -0.4, true),
        ] {
            let c = center_from_radius(start, end, plane, r, dir, 1e-9).unwrap();
            assert!(((start - c).norm() - 0.4).abs() < 1e-12);
            assert!(((end - c).norm() - 0.4).abs() < 1e-12);
            let chord = end - start;
            let side = chord.x * (c.y - start.y) - chord.y * (c.x - start.x);
            assert_eq!(side > 0.0, left);
        }
    }

    #[test]
    fn errors_and_the_half_chord_tolerance() {
        let s = Vector3::zeros();
        let e = Vector3::new(1.0, 0.0, 0.0);
        let ccw = ArcDirection::CounterClockwise;
        assert_eq!(
            center_from_radius(s, e, Plane::XY, 0.0, ccw, 0.0),
            Err(RadiusArcError::ZeroRadius)
        );
        assert_eq!(
            center_from_radius(s, s, Plane::XY, 1.0, ccw, 0.0),
            Err(RadiusArcError::ZeroChord)
        );
        assert_eq!(
            center_from_radius(s, e, Plane::XY, 0.49, ccw, 0.001),
            Err(RadiusArcError::RadiusBelowHalfChord {
                radius: 0.49,
                half_chord: 0.5
            })
        );
        let c = center_from_radius(s, e, Plane::XY, 0.4995, ccw, 0.001).unwrap();
        assert_eq!(c, Vector3::new(0.5, 0.0, 0.0));
    }
}
