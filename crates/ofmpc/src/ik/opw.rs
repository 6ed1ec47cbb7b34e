//! Closed-form kinematics of ortho-parallel arms with a spherical wrist (OPW).
//!
//! After M. Brandstötter, A. Angerer, M. Hofbaur, "An analytical solution of the
//! inverse kinematics problem of industrial serial manipulators with an
//! ortho-parallel basis and a spherical wrist", Austrian Robotics Workshop 2014,
//! with the parameter conventions of ROS-Industrial `opw_kinematics`.
//!
//! Geometry (internal angles θ, all zero = arm pointing straight up):
//! axis 1 vertical through the base origin; axis 2 at (a1, b, c1) in the arm plane;
//! upper arm c2; forearm c3 with perpendicular offset a2; wrist centre to flange c4.
//! Joint values seen by the user are `q_i = (θ_i + offsets_i)·signs_i`.
//!
//! The inverse is derived here rather than transcribed: wrist centre → θ1 (two
//! shoulder branches) → planar two-link problem for θ2, θ3 (two elbow branches) →
//! ZYZ Euler angles of the wrist (two wrist branches), with θ6 computed from the
//! exact residual rotation so that every returned solution reproduces the pose to
//! rounding even near the wrist singularity.

use std::f64::consts::PI;

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use super::solutions::Solutions;
use super::{pose_is_finite, IkError};

/// Distance (m) by which a wrist centre may lie outside the reachable shell and
/// still be solved (the arm is then fully stretched or folded; the position error
/// of such a solution is at most this).
pub const REACH_TOLERANCE: f64 = 1e-10;

/// Wrist singularity band: when `|sin θ5|` is at most this, θ4 computed from the
/// pose is ill-conditioned (rounding error ≈ 1e-16 / |sin θ5| ≥ 1e-9 rad), and
/// [`OpwParameters::inverse_near`] keeps q4 at the hint instead (see
/// [`SINGULAR_ORIENTATION_TOLERANCE`]).
pub const WRIST_SINGULAR_SIN: f64 = 1e-7;

/// Largest orientation error (rad) accepted for a solution with q4 held at the
/// hint inside the wrist singularity band. Holding q4 at a value δ away from the
/// exact one costs about `|sin θ5|·|sin δ|` rad; if that exceeds this tolerance the
/// exact (regular) solution is used.
pub const SINGULAR_ORIENTATION_TOLERANCE: f64 = 1e-10;

/// Shoulder singularity band: when the wrist centre is within this distance (m) of
/// axis 1, q1 is ill-conditioned and [`OpwParameters::inverse_near`] keeps q1 at the
/// hint if that moves the wrist centre by at most [`SINGULAR_POSITION_TOLERANCE`].
pub const SHOULDER_SINGULAR_RADIUS: f64 = 1e-7;

/// Largest wrist-centre position error (m) accepted for a solution with q1 held at
/// the hint inside the shoulder singularity band.
pub const SINGULAR_POSITION_TOLERANCE: f64 = 1e-10;

/// Kinematic parameters of an OPW arm plus the constant flange transform.
///
/// Lengths in m, offsets in rad, signs ±1. `tool` is the pose of the project's
/// flange frame in the raw OPW end frame (identity for the IRB 140, whose URDF
/// `flange` already follows the OPW/ROS-I `tool0` convention: z out of the flange).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpwParameters {
    /// Shoulder offset along x (axis 1 → axis 2).
    pub a1: f64,
    /// Elbow offset perpendicular to the forearm.
    pub a2: f64,
    /// Lateral (y) offset of the arm plane.
    pub b: f64,
    /// Height of axis 2 above the base origin.
    pub c1: f64,
    /// Upper-arm length (axis 2 → axis 3).
    pub c2: f64,
    /// Forearm length (axis 3 → wrist centre).
    pub c3: f64,
    /// Wrist centre → flange distance.
    pub c4: f64,
    /// Joint zero offsets: `q_i = (θ_i + offsets_i)·signs_i`.
    pub offsets: [f64; 6],
    /// Joint direction signs (+1 or −1).
    pub signs: [f64; 6],
    /// Flange frame in the raw OPW end frame (constant).
    pub tool: Isometry3<f64>,
}

/// All closed-form solutions of one pose (up to 8 joint vectors, no allocation) and its
/// wrist centre ([`Solutions::wrist_centre`]).
pub type OpwSolutions = Solutions<Vector3<f64>>;

/// Rotation about z by `t`.
pub(super) fn rz(t: f64) -> Matrix3<f64> {
    let (s, c) = t.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// Rotation about y by `t`.
pub(super) fn ry(t: f64) -> Matrix3<f64> {
    let (s, c) = t.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// Wraps an angle to (−π, π].
pub(crate) fn wrap_angle(x: f64) -> f64 {
    let y = (x + PI).rem_euclid(2.0 * PI) - PI;
    if y <= -PI {
        y + 2.0 * PI
    } else {
        y
    }
}

/// θ6 such that `Rz(θ4)·Ry(θ5)·Rz(θ6)` best matches `m`: the angle of the residual
/// `Ry(θ5)ᵀ·Rz(θ4)ᵀ·m` about z. Returns θ6 and the sine of the remaining orientation
/// error (the residual's deviation from a pure z rotation).
fn wrist_residual(m: &Matrix3<f64>, t4: f64, t5: f64) -> (f64, f64) {
    let n = ry(t5).transpose() * rz(t4).transpose() * m;
    let t6 = n[(1, 0)].atan2(n[(0, 0)]);
    let e = rz(t6).transpose() * n;
    let err = 0.5
        * Vector3::new(
            e[(2, 1)] - e[(1, 2)],
            e[(0, 2)] - e[(2, 0)],
            e[(1, 0)] - e[(0, 1)],
        )
        .norm();
    // A residual rotated by more than π/2 is not a small error.
    let err = if e.trace() < 1.0 { f64::INFINITY } else { err };
    (t6, err)
}

impl OpwParameters {
    /// ABB IRB 140 (PARAMETERS.md): a1 0.070, a2 0, b 0, c1 0.352, c2 0.360,
    /// c3 0.380, c4 0.065 m, offsets (0, 0, −π/2, 0, 0, 0), signs +1; `forward`
    /// gives the URDF `flange` pose (z out of the flange), so `tool` is identity.
    pub fn irb140() -> Self {
        Self {
            a1: 0.070,
            a2: 0.0,
            b: 0.0,
            c1: 0.352,
            c2: 0.360,
            c3: 0.380,
            c4: 0.065,
            offsets: [0.0, 0.0, -PI / 2.0, 0.0, 0.0, 0.0],
            signs: [1.0; 6],
            tool: Isometry3::identity(),
        }
    }

    /// Checks that all numbers are finite, `c2 > 0`, `hypot(a2, c3) > 0` and every
    /// sign is ±1.
    pub fn validate(&self) -> Result<(), IkError> {
        let lengths = [
            ("a1", self.a1),
            ("a2", self.a2),
            ("b", self.b),
            ("c1", self.c1),
            ("c2", self.c2),
            ("c3", self.c3),
            ("c4", self.c4),
        ];
        for (name, value) in lengths {
            if !value.is_finite() {
                return Err(IkError::InvalidParameter {
                    name,
                    value,
                    requirement: "must be finite",
                });
            }
        }
        if self.c2 <= 0.0 {
            return Err(IkError::InvalidParameter {
                name: "c2",
                value: self.c2,
                requirement: "the upper-arm length must be positive",
            });
        }
        if self.a2.hypot(self.c3) <= 0.0 {
            return Err(IkError::InvalidParameter {
                name: "c3",
                value: self.c3,
                requirement: "the forearm (a2, c3) must not have zero length",
            });
        }
        for (&o, &s) in self.offsets.iter().zip(&self.signs) {
            if !o.is_finite() {
                return Err(IkError::InvalidParameter {
                    name: "offsets",
                    value: o,
                    requirement: "must be finite",
                });
            }
            if s != 1.0 && s != -1.0 {
                return Err(IkError::InvalidParameter {
                    name: "signs",
                    value: s,
                    requirement: "each sign must be +1 or -1",
                });
            }
        }
        if !pose_is_finite(&self.tool) {
            return Err(IkError::NonFinite {
                what: "OPW tool transform",
            });
        }
        Ok(())
    }

    /// Internal OPW angle θ_i of user joint value q_i.
    fn theta(&self, i: usize, q: f64) -> f64 {
        q * self.signs[i] - self.offsets[i]
    }

    /// User joint value q_i of internal OPW angle θ_i.
    fn user(&self, i: usize, theta: f64) -> f64 {
        (theta + self.offsets[i]) * self.signs[i]
    }

    /// Flange pose in the base frame at joint positions `q` (closed form).
    pub fn forward(&self, q: &[f64; 6]) -> Isometry3<f64> {
        let t: [f64; 6] = std::array::from_fn(|i| self.theta(i, q[i]));
        let k = self.a2.hypot(self.c3);
        let psi3 = self.a2.atan2(self.c3);
        let (s1, c1) = t[0].sin_cos();
        let (s2, c2) = t[1].sin_cos();
        let (s3p, c3p) = (t[1] + t[2] + psi3).sin_cos();
        // Wrist centre in the arm plane, then rotated about axis 1.
        let cx1 = self.c2 * s2 + k * s3p + self.a1;
        let cz1 = self.c2 * c2 + k * c3p;
        let centre = Vector3::new(
            cx1 * c1 - self.b * s1,
            cx1 * s1 + self.b * c1,
            cz1 + self.c1,
        );
        let r = rz(t[0]) * ry(t[1] + t[2]) * rz(t[3]) * ry(t[4]) * rz(t[5]);
        let p = centre + r.column(2) * self.c4;
        let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
        Isometry3::from_parts(Translation3::from(p), rot) * self.tool
    }

    /// All closed-form solutions of `pose` (flange in base frame), each joint wrapped
    /// to (−π, π]. Up to 8: 2 shoulder × 2 elbow × 2 wrist configurations; fewer when
    /// a shoulder branch cannot reach. At a singularity the free angle is whatever
    /// `atan2` gives; use [`OpwParameters::inverse_near`] to hold it at a hint.
    pub fn inverse(&self, pose: &Isometry3<f64>) -> OpwSolutions {
        self.solve(pose, None)
    }

    /// Like [`OpwParameters::inverse`], but inside the singularity bands the free
    /// joint takes the hint's value: q4 when `|sin θ5| ≤` `WRIST_SINGULAR_SIN`
    /// (then q6 takes the rest of q4 + q6), q1 when the wrist centre is within
    /// `SHOULDER_SINGULAR_RADIUS` of axis 1 — each only if the resulting pose error
    /// stays below `SINGULAR_ORIENTATION_TOLERANCE` /
    /// `SINGULAR_POSITION_TOLERANCE`. Hinted joints are returned unwrapped (equal to
    /// the hint). A non-finite hint is ignored.
    pub fn inverse_near(&self, pose: &Isometry3<f64>, hint: &[f64; 6]) -> OpwSolutions {
        if hint.iter().all(|x| x.is_finite()) {
            self.solve(pose, Some(hint))
        } else {
            self.solve(pose, None)
        }
    }

    fn solve(&self, pose: &Isometry3<f64>, hint: Option<&[f64; 6]>) -> OpwSolutions {
        let mut out = OpwSolutions::empty(Vector3::zeros());
        if !pose_is_finite(pose) {
            return out;
        }
        let raw = pose * self.tool.inverse();
        let r = raw.rotation.to_rotation_matrix().into_inner();
        let centre = raw.translation.vector - r.column(2) * self.c4;
        out.extra = centre;
        let (cx, cy, cz) = (centre.x, centre.y, centre.z);

        // Shoulder: the arm plane must pass at distance b from axis 1.
        let rho = cx.hypot(cy);
        let lat2 = rho * rho - self.b * self.b;
        let lat = if lat2 >= 0.0 {
            lat2.sqrt()
        } else if self.b.abs() - rho <= REACH_TOLERANCE {
            0.0
        } else {
            out.reach_excess = self.b.abs() - rho;
            return out;
        };
        let base = cy.atan2(cx);
        let off = self.b.atan2(lat);
        // (θ1, wrist-centre x in the rotated arm plane, θ1 hinted?)
        let mut shoulders = [(base - off, lat, false), (base + off - PI, -lat, false)];
        if let Some(h) = hint {
            self.hint_shoulder(h, centre, rho, &mut shoulders);
        }

        let k = self.a2.hypot(self.c3);
        let psi3 = self.a2.atan2(self.c3);
        let h = cz - self.c1;
        let mut best_excess = f64::INFINITY;
        for &(t1, x1, t1_hinted) in &shoulders {
            // Planar two-link problem: h + i·d = e^{iθ2}·(c2 + k·e^{i(θ3+ψ3)}).
            let d = x1 - self.a1;
            let s = d.hypot(h);
            let excess = (s - (self.c2 + k)).max((self.c2 - k).abs() - s);
            if excess > REACH_TOLERANCE {
                best_excess = best_excess.min(excess);
                continue;
            }
            best_excess = 0.0;
            let cos3 = ((s * s - self.c2 * self.c2 - k * k) / (2.0 * self.c2 * k)).clamp(-1.0, 1.0);
            let phi = cos3.acos();
            for p3 in [phi, -phi] {
                let t3 = p3 - psi3;
                let t2 = d.atan2(h) - (k * p3.sin()).atan2(self.c2 + k * p3.cos());
                let m = (rz(t1) * ry(t2 + t3)).transpose() * r;
                self.push_wrist(&mut out, [t1, t2, t3], t1_hinted, &m, hint);
            }
        }
        out.reach_excess = best_excess;
        out
    }

    /// At the shoulder singularity (wrist centre on axis 1) θ1 is free: the hinted θ1
    /// replaces the shoulder configuration on its side of the arm plane.
    fn hint_shoulder(
        &self,
        h: &[f64; 6],
        centre: Vector3<f64>,
        rho: f64,
        shoulders: &mut [(f64, f64, bool); 2],
    ) {
        let (cx, cy) = (centre.x, centre.y);
        let t1 = self.theta(0, h[0]);
        let (s, c) = t1.sin_cos();
        let x1 = cx * c + cy * s;
        let y1 = -cx * s + cy * c;
        if rho <= SHOULDER_SINGULAR_RADIUS && (y1 - self.b).abs() <= SINGULAR_POSITION_TOLERANCE {
            let idx = usize::from(x1 < 0.0);
            shoulders[idx] = (t1, x1, true);
        }
    }

    /// Appends the two wrist configurations of one arm configuration.
    fn push_wrist(
        &self,
        out: &mut OpwSolutions,
        arm: [f64; 3],
        t1_hinted: bool,
        m: &Matrix3<f64>,
        hint: Option<&[f64; 6]>,
    ) {
        // Rz(θ4)·Ry(θ5)·Rz(θ6) = m: third column (c4·s5, s4·s5, c5).
        let s5 = m[(0, 2)].hypot(m[(1, 2)]);
        let t5 = s5.atan2(m[(2, 2)]);
        let t4 = m[(1, 2)].atan2(m[(0, 2)]);
        let mut wrists = [(t4, t5, false), (t4 + PI, -t5, false)];
        if let (Some(h), true) = (hint, s5 <= WRIST_SINGULAR_SIN) {
            let t4h = self.theta(3, h[3]);
            let mp = rz(t4h).transpose() * m;
            let t5h = mp[(0, 2)].atan2(mp[(2, 2)]);
            let (_, err) = wrist_residual(m, t4h, t5h);
            if err <= SINGULAR_ORIENTATION_TOLERANCE {
                let idx = usize::from(wrap_angle(t4 - t4h).abs() > PI / 2.0);
                wrists[idx] = (t4h, t5h, true);
            }
        }
        for (t4, t5, t4_hinted) in wrists {
            let (t6, _) = wrist_residual(m, t4, t5);
            let thetas = [arm[0], arm[1], arm[2], t4, t5, t6];
            let mut q: [f64; 6] = std::array::from_fn(|i| wrap_angle(self.user(i, thetas[i])));
            if let Some(h) = hint {
                if t1_hinted {
                    q[0] = h[0];
                }
                if t4_hinted {
                    q[3] = h[3];
                }
            }
            out.push(q);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_angle_maps_into_half_open_interval() {
        for (x, y) in [
            (0.0, 0.0),
            (PI, PI),
            (-PI, PI),
            (3.0 * PI, PI),
            (2.0 * PI + 0.5, 0.5),
            (-2.0 * PI - 0.5, -0.5),
        ] {
            assert!(
                (wrap_angle(x) - y).abs() < 1e-15,
                "{x} -> {}",
                wrap_angle(x)
            );
        }
    }

    #[test]
    fn validate_rejects_bad_parameters() {
        assert!(OpwParameters::irb140().validate().is_ok());
        let mut p = OpwParameters::irb140();
        p.c2 = 0.0;
        assert!(matches!(
            p.validate(),
            Err(IkError::InvalidParameter { name: "c2", .. })
        ));
        let mut p = OpwParameters::irb140();
        p.signs[2] = 0.5;
        assert!(matches!(
            p.validate(),
            Err(IkError::InvalidParameter { name: "signs", .. })
        ));
        let mut p = OpwParameters::irb140();
        p.a1 = f64::NAN;
        assert!(matches!(
            p.validate(),
            Err(IkError::InvalidParameter { name: "a1", .. })
        ));
    }

    #[test]
    fn non_finite_pose_has_no_solution() {
        let p = OpwParameters::irb140();
        let pose = Isometry3::translation(f64::NAN, 0.0, 0.5);
        let sols = p.inverse(&pose);
        assert!(sols.is_empty());
        assert_eq!(sols.reach_excess(), f64::INFINITY);
    }

    #[test]
    fn far_pose_reports_reach_excess() {
        let p = OpwParameters::irb140();
        // Wrist centre 2 m away from axis 2: excess ≈ 2 − (0.36 + 0.38).
        let mut pose = p.forward(&[0.0; 6]);
        pose.translation.vector.x += 2.0;
        let sols = p.inverse(&pose);
        assert!(sols.is_empty());
        let c = sols.wrist_centre();
        let s = (c.x - 0.070).hypot(c.z - 0.352);
        assert!((sols.reach_excess() - (s - 0.74)).abs() < 1e-12);
    }
}
