//! The circular arc that rounds a corner between two straight lines (the geometry of a `G64`
//! blend; the policy, which corners to round and by how much, is [`crate::motion::blend`]'s).
//!
//! A corner between two straight lines with unit directions `u₁`, `u₂` turns by
//! `θ = acos(u₁·u₂)`. The circular arc tangent to both lines at distance `d` from the corner
//! has radius `R = d / tan(θ/2)`; it starts at `corner − d u₁`, its centre lies `R` from there
//! along `m = (u₂ − (u₁·u₂) u₁) / |…|` (in the lines' plane, ⊥ `u₁`, towards the inside), and
//! it sweeps `θ`.

use nalgebra::Vector3;

/// Angle (rad) below which two moves count as tangent-continuous: no blend, no stop.
pub const TANGENT_ANGLE: f64 = 1e-6;

/// Turning angle (rad) above which a corner counts as a reversal: the path stops there.
pub const REVERSAL_ANGLE: f64 = std::f64::consts::PI - 1e-3;

/// A circular arc in any plane: `p(φ) = c + R (cos φ e₁ + sin φ e₂)`, `φ = s/R ∈ [0, sweep]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CornerArc {
    /// Centre (m).
    pub center: Vector3<f64>,
    /// Radius (m), > 0.
    pub radius: f64,
    /// Unit vector from the centre to the start point.
    pub e1: Vector3<f64>,
    /// Unit tangent at the start point (⊥ `e1`).
    pub e2: Vector3<f64>,
    /// Angle swept (rad), in `(0, π)`.
    pub sweep: f64,
}

impl CornerArc {
    /// The blend of the corner `corner` between incoming direction `u1` and outgoing `u2`
    /// (unit vectors) with tangent distance `d`; `None` for a straight or reversing corner.
    pub fn new(corner: Vector3<f64>, u1: Vector3<f64>, u2: Vector3<f64>, d: f64) -> Option<Self> {
        let cos = u1.dot(&u2).clamp(-1.0, 1.0);
        let theta = cos.acos();
        if !(TANGENT_ANGLE..=REVERSAL_ANGLE).contains(&theta) || d.is_nan() || d <= 0.0 {
            return None;
        }
        let m = (u2 - u1 * cos).normalize(); // in the plane, ⊥ u1, towards the inside
        let radius = d / (theta / 2.0).tan();
        let start = corner - u1 * d;
        let center = start + m * radius;
        Some(Self {
            center,
            radius,
            e1: -m,
            e2: u1,
            sweep: theta,
        })
    }

    /// Arc length (m).
    pub fn length(&self) -> f64 {
        self.radius * self.sweep
    }

    fn angle(&self, s: f64) -> f64 {
        (s / self.radius).clamp(0.0, self.sweep)
    }

    /// Point at arc length `s` (clamped).
    pub fn point(&self, s: f64) -> Vector3<f64> {
        let phi = self.angle(s);
        self.center + (self.e1 * phi.cos() + self.e2 * phi.sin()) * self.radius
    }

    /// Unit tangent at arc length `s`.
    pub fn tangent(&self, s: f64) -> Vector3<f64> {
        let phi = self.angle(s);
        self.e2 * phi.cos() - self.e1 * phi.sin()
    }

    /// Curvature vector `d²p/ds²` at arc length `s` (towards the centre, norm `1/R`).
    pub fn curvature(&self, s: f64) -> Vector3<f64> {
        let phi = self.angle(s);
        -(self.e1 * phi.cos() + self.e2 * phi.sin()) / self.radius
    }
}
