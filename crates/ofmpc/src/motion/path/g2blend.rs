//! Curvature-continuous (G2) corner blends for corners that involve an arc: a quintic
//! Hermite curve from a point of the incoming move to a point of the outgoing one that
//! matches position, tangent and curvature at both ends, and the parts of moves it leaves.
//!
//! # The curve
//!
//! With `p(u)`, `u ∈ [0, 1]`, the quintic Hermite interpolant of the end points `P₀`, `P₁`,
//! first derivatives `V₀ = λ t₀`, `V₁ = λ t₁` and second derivatives `A₀ = λ² k₀`,
//! `A₁ = λ² k₁` (`t` unit tangents, `k` curvature vectors of the moves at the joins, `λ` the
//! chord `|P₁ − P₀|`) has, at each end, the moves' tangent and curvature vector: the tangent
//! of a regular curve is `p'/|p'|` and its curvature vector
//! `(p'' |p'|² − p' (p'·p''))/|p'|⁴`, which for `p' = λ t`, `p'' = λ² k` (`k ⊥ t`) is `k`
//! (do Carmo, *Differential Geometry of Curves and Surfaces*, §1-5). The basis is the
//! quintic Hermite one (e.g. Farin, *Curves and Surfaces for CAGD*, §7.5), written here in
//! monomial form.
//!
//! # Arc length
//!
//! `s(u) = ∫ |p'|` is tabulated on `TABLE` (128) intervals with 5-point Gauss–Legendre
//! quadrature; `u(s)` inside an interval is the cubic Hermite interpolant of the table with
//! the slopes `du/ds = 1/|p'|`, so that `point(s)`, `tangent(s)` and `curvature(s)` are
//! functions of the arc length as for the other pieces.

use crate::geometry::Segment;
use nalgebra::Vector3;

/// Intervals of the arc-length table (64: the table of every corner blend is most of the
/// planning cost of a CAM program; 128 intervals and a 5-point rule took a quarter of the
/// 100 000-segment plan).
const TABLE: usize = 64;

/// Nodes and weights of 3-point Gauss–Legendre quadrature on `[-1, 1]` (Abramowitz &
/// Stegun, table 25.4): exact for polynomials of degree 5; on each of the [`TABLE`]
/// intervals the speed `|p'(u)|` of a blend is smooth, and the error is below 1e-11 of the
/// length on line corners from 10° to 170° (test below).
const GAUSS: [(f64, f64); 3] = [
    (0.0, 8.0 / 9.0),
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// A quintic G2 blend parameterised by arc length (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct QuinticBlend {
    /// Monomial coefficients `c₀ … c₅` of `p(u)`.
    c: [Vector3<f64>; 6],
    /// Arc length at `u = i / TABLE`.
    s: Vec<f64>,
    /// `|p'|` at `u = i / TABLE`.
    speed: Vec<f64>,
    /// Largest curvature and `|dk/ds|` over the table (computed once).
    bounds: (f64, f64),
}

impl QuinticBlend {
    /// The blend from `p0` (unit tangent `t0`, curvature vector `k0`) to `p1` (`t1`, `k1`);
    /// `None` if it is degenerate (coincident ends, a cusp).
    pub fn new(
        p0: Vector3<f64>,
        t0: Vector3<f64>,
        k0: Vector3<f64>,
        p1: Vector3<f64>,
        t1: Vector3<f64>,
        k1: Vector3<f64>,
    ) -> Option<Self> {
        Self::with_tangent_scale(p0, t0, k0, p1, t1, k1, 1.0)
    }

    /// [`QuinticBlend::new`] with the end derivatives `λ = alpha · |P₁ − P₀|` (`alpha` > 0):
    /// any `λ` gives the same end tangents and curvatures; between two lines `alpha` = 1.4
    /// spreads the curvature change more evenly than 1 (its largest `|dk/ds|` times the
    /// squared deviation is about a quarter of that at 1 for a 90° corner).
    #[allow(clippy::too_many_arguments)]
    pub fn with_tangent_scale(
        p0: Vector3<f64>,
        t0: Vector3<f64>,
        k0: Vector3<f64>,
        p1: Vector3<f64>,
        t1: Vector3<f64>,
        k1: Vector3<f64>,
        alpha: f64,
    ) -> Option<Self> {
        let lambda = (p1 - p0).norm() * alpha;
        if lambda.is_nan() || lambda <= 1e-12 {
            return None;
        }
        let (v0, v1) = (t0 * lambda, t1 * lambda);
        let (a0, a1) = (k0 * lambda * lambda, k1 * lambda * lambda);
        let c = [
            p0,
            v0,
            a0 * 0.5,
            (p1 - p0) * 10.0 - v0 * 6.0 - v1 * 4.0 - a0 * 1.5 + a1 * 0.5,
            (p0 - p1) * 15.0 + v0 * 8.0 + v1 * 7.0 + a0 * 1.5 - a1,
            (p1 - p0) * 6.0 - v0 * 3.0 - v1 * 3.0 - a0 * 0.5 + a1 * 0.5,
        ];
        let mut blend = Self {
            c,
            s: Vec::with_capacity(TABLE + 1),
            speed: Vec::with_capacity(TABLE + 1),
            bounds: (0.0, 0.0),
        };
        let h = 1.0 / TABLE as f64;
        let mut s = 0.0;
        for i in 0..=TABLE {
            let u = i as f64 * h;
            let sp = blend.d1(u).norm();
            if sp.is_nan() || sp <= 1e-9 * lambda {
                return None;
            }
            blend.s.push(s);
            blend.speed.push(sp);
            if i < TABLE {
                let mid = u + 0.5 * h;
                s += GAUSS
                    .iter()
                    .map(|(x, w)| w * blend.d1(mid + 0.5 * h * x).norm())
                    .sum::<f64>()
                    * 0.5
                    * h;
            }
        }
        blend.bounds = blend.table_bounds();
        Some(blend)
    }

    fn eval(&self, u: f64) -> Vector3<f64> {
        let c = &self.c;
        c[0] + (c[1] + (c[2] + (c[3] + (c[4] + c[5] * u) * u) * u) * u) * u
    }

    fn d1(&self, u: f64) -> Vector3<f64> {
        let c = &self.c;
        c[1] + (c[2] * 2.0 + (c[3] * 3.0 + (c[4] * 4.0 + c[5] * (5.0 * u)) * u) * u) * u
    }

    fn d2(&self, u: f64) -> Vector3<f64> {
        let c = &self.c;
        c[2] * 2.0 + (c[3] * 6.0 + (c[4] * 12.0 + c[5] * (20.0 * u)) * u) * u
    }

    /// Length (m).
    pub fn length(&self) -> f64 {
        self.s[TABLE]
    }

    /// The parameter `u` at arc length `s` (clamped).
    fn param(&self, s: f64) -> f64 {
        let len = self.length();
        if s.is_nan() || s <= 0.0 {
            return 0.0;
        }
        if s >= len {
            return 1.0;
        }
        let i = self.s.partition_point(|&x| x <= s).clamp(1, TABLE) - 1;
        let (s0, s1) = (self.s[i], self.s[i + 1]);
        let ds = s1 - s0;
        let h = 1.0 / TABLE as f64;
        if ds <= 0.0 {
            return i as f64 * h;
        }
        // Cubic Hermite in s of u, slopes du/ds = 1/|p'| at both ends.
        let x = (s - s0) / ds;
        let (m0, m1) = (ds / self.speed[i], ds / self.speed[i + 1]);
        let (x2, x3) = (x * x, x * x * x);
        let u0 = i as f64 * h;
        let u = (2.0 * x3 - 3.0 * x2 + 1.0) * u0
            + (x3 - 2.0 * x2 + x) * m0
            + (-2.0 * x3 + 3.0 * x2) * (u0 + h)
            + (x3 - x2) * m1;
        u.clamp(u0, u0 + h)
    }

    /// Point at the parameter `u ∈ [0, 1]` (not arc length: points evenly spaced in `u`,
    /// without the arc-length search).
    pub(crate) fn point_at_parameter(&self, u: f64) -> Vector3<f64> {
        self.eval(u.clamp(0.0, 1.0))
    }

    /// Point at arc length `s`.
    pub fn point(&self, s: f64) -> Vector3<f64> {
        self.eval(self.param(s))
    }

    /// Unit tangent at arc length `s`.
    pub fn tangent(&self, s: f64) -> Vector3<f64> {
        self.d1(self.param(s)).normalize()
    }

    /// Curvature vector `d²p/ds²` at arc length `s`.
    pub fn curvature(&self, s: f64) -> Vector3<f64> {
        self.curvature_at(self.param(s))
    }

    /// Curvature vector `d²p/ds²` at the parameter `u`:
    /// `(p'' |p'|² − p' (p'·p'')) / |p'|⁴`.
    fn curvature_at(&self, u: f64) -> Vector3<f64> {
        let (d1, d2) = (self.d1(u), self.d2(u));
        let n2 = d1.norm_squared();
        (d2 * n2 - d1 * d1.dot(&d2)) / (n2 * n2)
    }

    /// Largest curvature (1/m) over the table's points.
    pub fn max_curvature(&self) -> f64 {
        self.bounds.0
    }

    /// Largest curvature and largest `|dk/ds|` over the table (see
    /// [`QuinticBlend::max_curvature_rate`]).
    ///
    /// The table's point `i` is at `u = i / TABLE` exactly (`param(s[i])` returns it), so
    /// the curvature is evaluated there directly, without the search of `param`.
    fn table_bounds(&self) -> (f64, f64) {
        let h = 1.0 / TABLE as f64;
        let mut previous = self.curvature_at(0.0);
        let (mut kmax, mut rate) = (0.0f64.max(previous.norm()), 0.0f64);
        for i in 0..TABLE {
            let k = self.curvature_at((i + 1) as f64 * h);
            kmax = kmax.max(k.norm());
            let ds = self.s[i + 1] - self.s[i];
            if ds > 0.0 {
                rate = rate.max((k - previous).norm() / ds);
            }
            previous = k;
        }
        (kmax, rate)
    }

    /// Largest rate of change of the curvature vector along the arc length, `|dk/ds|`
    /// (1/m²), over the table's intervals (differences of the curvature vectors at their
    /// ends). Along the blend the Cartesian jerk at constant path speed is `ṡ³ dk/ds`.
    pub fn max_curvature_rate(&self) -> f64 {
        self.bounds.1
    }
}

/// The part `[from, from + length]` (arc length) of a segment.
#[derive(Debug, Clone, PartialEq)]
pub struct SegmentPart {
    /// The whole segment.
    pub segment: Segment,
    /// Arc length (m) of the part's start on the segment.
    pub from: f64,
    /// Length (m) of the part.
    pub length: f64,
}

impl SegmentPart {
    /// Point at arc length `s` from the part's start.
    pub fn point(&self, s: f64) -> Vector3<f64> {
        self.segment.point(self.from + s.clamp(0.0, self.length))
    }
    /// Unit tangent at arc length `s`.
    pub fn tangent(&self, s: f64) -> Vector3<f64> {
        self.segment.tangent(self.from + s.clamp(0.0, self.length))
    }
    /// Curvature vector at arc length `s`.
    pub fn curvature(&self, s: f64) -> Vector3<f64> {
        self.segment
            .curvature(self.from + s.clamp(0.0, self.length))
    }
}

/// Samples per side with which [`blend_deviation`] follows the moves' removed parts.
const DEVIATION_SAMPLES: usize = 32;

/// Distance from `p` to the segment `[a, b]`.
fn to_chord(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let u = b - a;
    let n2 = u.norm_squared();
    let t = if n2 > 0.0 {
        ((p - a).dot(&u) / n2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + u * t)).norm()
}

/// Largest distance from the blend to the programmed path it replaces: the last `d_in` of
/// `incoming` and the first `d_out` of `outgoing` (each followed by a polyline of
/// `DEVIATION_SAMPLES` (32) chords, which lies within `d²/(8 R n²)` of an arc of radius `R`).
pub fn blend_deviation(
    blend: &QuinticBlend,
    incoming: &Segment,
    d_in: f64,
    outgoing: &Segment,
    d_out: f64,
) -> f64 {
    let n = DEVIATION_SAMPLES;
    let l_in = incoming.length();
    let mut path: Vec<Vector3<f64>> = (0..=n)
        .map(|i| incoming.point(l_in - d_in + d_in * i as f64 / n as f64))
        .collect();
    path.extend((1..=n).map(|i| outgoing.point(d_out * i as f64 / n as f64)));
    let len = blend.length();
    (0..=4 * n)
        .map(|i| {
            let p = blend.point(len * i as f64 / (4 * n) as f64);
            path.windows(2)
                .map(|w| to_chord(&p, &w[0], &w[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// The blend meets both ends with their tangents and curvatures, its arc length matches
    /// a dense polyline, and `point`, `tangent`, `curvature` agree with finite differences in
    /// the arc length.
    #[test]
    fn ends_match_and_derivatives_agree_with_finite_differences() {
        let (t0, t1) = (v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        let (k0, k1) = (v(0.0, 0.0, 0.0), v(-200.0, 0.0, 0.0));
        let (p0, p1) = (v(0.0, 0.0, 0.0), v(0.001, 0.001, 0.0));
        let b = QuinticBlend::new(p0, t0, k0, p1, t1, k1).unwrap();
        let len = b.length();
        assert!((b.point(0.0) - p0).norm() < 1e-15 && (b.point(len) - p1).norm() < 1e-15);
        assert!((b.tangent(0.0) - t0).norm() < 1e-12 && (b.tangent(len) - t1).norm() < 1e-12);
        assert!((b.curvature(0.0) - k0).norm() < 1e-6);
        assert!((b.curvature(len) - k1).norm() < 1e-6 * 200.0);
        let poly: f64 = (0..10_000)
            .map(|i| (b.eval((i + 1) as f64 / 1e4) - b.eval(i as f64 / 1e4)).norm())
            .sum();
        // A polyline of n chords is shorter by about L κ² (L/n)² / 24 (≈ 1e-9 L here).
        assert!((poly - len).abs() < 1e-8 * len, "{poly} vs {len}");
        let h = len * 1e-4;
        for i in 1..100 {
            let s = len * i as f64 / 100.0;
            let fd = (b.point(s + h) - b.point(s - h)) / (2.0 * h);
            assert!((fd - b.tangent(s)).norm() < 1e-5, "{s}");
            let fk = (b.tangent(s + h) - b.tangent(s - h)) / (2.0 * h);
            let k = b.curvature(s);
            assert!(
                (fk - k).norm() < 1e-3 * k.norm().max(1.0),
                "{s}: {fk} vs {k}"
            );
        }
    }

    /// The 3-point rule's arc-length table agrees with a reference quadrature (Simpson's rule
    /// on 2¹⁶ intervals) to 1e-11 of the length on line corners from 10° to 170° and a
    /// line-to-arc join.
    #[test]
    fn arc_length_table_matches_a_fine_quadrature() {
        let mut cases = Vec::new();
        for deg in [10.0f64, 45.0, 90.0, 135.0, 170.0] {
            let th = deg.to_radians();
            let (t0, t1) = (v(1.0, 0.0, 0.0), v(th.cos(), th.sin(), 0.0));
            let d = 1e-4;
            let (p0, p1) = (-t0 * d, t1 * d);
            cases.push((p0, t0, Vector3::zeros(), p1, t1, Vector3::zeros()));
        }
        cases.push((
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            Vector3::zeros(),
            v(0.001, 0.001, 0.0),
            v(0.0, 1.0, 0.0),
            v(-200.0, 0.0, 0.0),
        ));
        for (p0, t0, k0, p1, t1, k1) in cases {
            let b = QuinticBlend::new(p0, t0, k0, p1, t1, k1).unwrap();
            let n = 1 << 16;
            let f = |i: usize| b.d1(i as f64 / n as f64).norm();
            let simpson: f64 = (0..n / 2)
                .map(|k| f(2 * k) + 4.0 * f(2 * k + 1) + f(2 * k + 2))
                .sum::<f64>()
                / (3.0 * n as f64);
            let len = b.length();
            assert!((len - simpson).abs() < 1e-11 * len, "{len} vs {simpson}");
        }
    }
}
