//! A robot that is not its model: every link's inertial parameters and every
//! drive's rotor inertia drawn around the nominal values, as a real arm's
//! differ from its data sheet.
//!
//! The draw stays physical by construction: a mass is scaled by a
//! log-normal factor (positive), the inertia about the centre of mass is
//! rebuilt from its three second moments of mass along the principal axes
//! (`I₁ = b + c`, `I₂ = a + c`, `I₃ = a + b`), each scaled by a log-normal
//! factor, so the tensor stays positive (semi-)definite and its principal
//! moments satisfy the triangle inequality; the centre of mass moves by a
//! Gaussian offset scaled to the link (the larger of the distance to the
//! next joint and the nominal centre-of-mass distance); the rotor inertia is
//! scaled by a log-normal factor. Every factor has mean 1 and relative
//! standard deviation σ (`ln f ~ N(−s²/2, s²)`, `s² = ln(1 + σ²)`).

use super::{ModelError, Robot};
use crate::spatial::Inertia;
use nalgebra::{Matrix3, Vector3};
use serde::Serialize;

/// The relative errors drawn for one link and its drive
/// ([`Robot::with_inertia_error`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LinkInertiaError {
    /// Mass: `m / m₀ − 1`.
    pub mass: f64,
    /// Centre of mass offset over the link's length scale: `|c − c₀| / L`.
    pub com_offset: f64,
    /// Inertia about the centre of mass: `‖I − I₀‖_F / ‖I₀‖_F`.
    pub inertia: f64,
    /// Drive (rotor) inertia: `J / J₀ − 1` (0 without a rotor inertia).
    pub drive_inertia: f64,
}

/// The largest accepted relative standard deviation of the inertial
/// parameters ([`Robot::with_inertia_error`]).
pub(crate) const MAX_INERTIA_ERROR: f64 = 1.0;

/// A Gaussian generator (splitmix64 + Box–Muller): reproducible from its
/// seed, independent of the sensor's noise stream.
struct Draw {
    s: u64,
}

impl Draw {
    fn uniform(&mut self) -> f64 {
        self.s = self.s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        // (0, 1]: never 0, so the logarithm below is finite.
        ((z >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }
    fn gauss(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
    /// A log-normal factor of mean 1 and relative standard deviation `sd`.
    fn factor(&mut self, sd: f64) -> f64 {
        let s2 = (1.0 + sd * sd).ln();
        (self.gauss() * s2.sqrt() - 0.5 * s2).exp()
    }
}

impl Robot {
    /// This robot with every link's mass, centre of mass, inertia about the
    /// centre of mass and every drive's rotor inertia drawn with relative
    /// standard deviation `relative_sd` from `seed` (the same seed, the same
    /// robot), and the relative errors drawn, link by link. The payload, if
    /// any, is kept. `relative_sd` must be finite, in
    /// [0, 1] (`MAX_INERTIA_ERROR`); 0 returns the robot unchanged.
    pub fn with_inertia_error(
        &self,
        relative_sd: f64,
        seed: u64,
    ) -> Result<(Robot, Vec<LinkInertiaError>), ModelError> {
        if !(relative_sd.is_finite() && (0.0..=MAX_INERTIA_ERROR).contains(&relative_sd)) {
            return Err(ModelError::NonFinite {
                what: format!("the inertia error (at most {MAX_INERTIA_ERROR})"),
                index: 0,
                value: relative_sd,
            });
        }
        let mut robot = self.clone();
        let mut draws = Vec::with_capacity(robot.joints.len());
        if relative_sd == 0.0 {
            draws.resize(robot.joints.len(), LinkInertiaError::default());
            return Ok((robot, draws));
        }
        let mut rng = Draw {
            s: seed.wrapping_mul(0xD6E8_FEB8_6659_FD93) ^ 0x1F35_A7C2_9B4E_0D61,
        };
        let n = robot.joints.len();
        for i in 0..n {
            let length = match robot.joints.get(i + 1) {
                Some(next) => next.placement.pos.norm(),
                None => robot.flange.pos.norm(),
            };
            let body = robot.joints[i].body;
            let (drawn, mut e) = draw_body(&body, length, relative_sd, &mut rng);
            robot.joints[i].body = drawn;
            let j0 = robot.joints[i].armature;
            let f = rng.factor(relative_sd);
            if j0 > 0.0 {
                robot.joints[i].armature = j0 * f;
                e.drive_inertia = f - 1.0;
            }
            draws.push(e);
        }
        robot.set_payload(robot.payload)?;
        Ok((robot, draws))
    }
}

impl Default for LinkInertiaError {
    fn default() -> Self {
        Self {
            mass: 0.0,
            com_offset: 0.0,
            inertia: 0.0,
            drive_inertia: 0.0,
        }
    }
}

/// One body drawn around `body` (its joint frame), with the link length
/// scale `length` (m).
fn draw_body(body: &Inertia, length: f64, sd: f64, rng: &mut Draw) -> (Inertia, LinkInertiaError) {
    if body.mass <= 0.0 {
        return (*body, LinkInertiaError::default());
    }
    let (c0, i0) = (body.com(), body.i_com());
    let fm = rng.factor(sd);
    let scale = length.max(c0.norm());
    let dc = Vector3::new(rng.gauss(), rng.gauss(), rng.gauss()) * (sd * scale);
    let i = draw_inertia(&i0, fm, sd, rng);
    let drawn = Inertia::from_com(body.mass * fm, c0 + dc, i);
    let norm0 = i0.norm();
    let e = LinkInertiaError {
        mass: fm - 1.0,
        com_offset: if scale > 0.0 { dc.norm() / scale } else { 0.0 },
        inertia: if norm0 > 0.0 {
            (i - i0).norm() / norm0
        } else {
            0.0
        },
        drive_inertia: 0.0,
    };
    (drawn, e)
}

/// The inertia about the centre of mass `i0` with each principal second
/// moment of mass scaled by a log-normal factor (the body's mass scaled by
/// `fm`: a body that is heavier by `fm` is, at the same shape, `fm` times
/// more inertial; the shape then varies by `sd` on its own). Symmetric,
/// positive semi-definite and triangle-satisfying whatever the factors.
fn draw_inertia(i0: &Matrix3<f64>, fm: f64, sd: f64, rng: &mut Draw) -> Matrix3<f64> {
    let eig = nalgebra::SymmetricEigen::new(*i0);
    let l = eig.eigenvalues;
    // Second moments along the principal axes (clamped: a nominal tensor may
    // break the triangle inequality within the URDF reader's tolerance).
    let half = 0.5 * (l[0] + l[1] + l[2]);
    let moments = [half - l[0], half - l[1], half - l[2]].map(|m| m.max(0.0));
    let s = moments.map(|m| m * fm * rng.factor(sd));
    let diag = Vector3::new(s[1] + s[2], s[0] + s[2], s[0] + s[1]);
    let v = eig.eigenvectors;
    let i = v * Matrix3::from_diagonal(&diag) * v.transpose();
    0.5 * (i + i.transpose())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::check_inertia_tensor;

    /// The same seed draws the same robot, another seed another; σ = 0 is
    /// the nominal robot.
    #[test]
    fn the_draw_is_reproducible_by_seed() {
        let r = Robot::irb140();
        let (a, ea) = r.with_inertia_error(0.1, 7).unwrap();
        let (b, eb) = r.with_inertia_error(0.1, 7).unwrap();
        let (c, _) = r.with_inertia_error(0.1, 8).unwrap();
        assert_eq!(a, b);
        assert_eq!(ea, eb);
        assert_ne!(a, c);
        let (z, ez) = r.with_inertia_error(0.0, 7).unwrap();
        assert_eq!(z, r);
        assert!(ez.iter().all(|e| *e == LinkInertiaError::default()));
        assert!(r.with_inertia_error(-0.1, 1).is_err());
        assert!(r.with_inertia_error(f64::NAN, 1).is_err());
    }

    /// Over many draws at σ = 0.5 (far beyond a real arm's), every body
    /// stays physical: positive mass, inertia about the centre of mass
    /// symmetric positive semi-definite with the triangle inequality (the
    /// URDF reader's check, exact), positive rotor inertia.
    #[test]
    fn every_draw_is_physical() {
        let r = Robot::irb140();
        for seed in 0..300 {
            let (p, _) = r.with_inertia_error(0.5, seed).unwrap();
            for (j, j0) in p.joints().iter().zip(r.joints()) {
                assert!(j.body.mass > 0.0, "seed {seed}: mass {}", j.body.mass);
                check_inertia_tensor(&j.body.i_com())
                    .unwrap_or_else(|e| panic!("seed {seed}, {}: {e:?}", j.name));
                assert!(j.armature > 0.0 || j0.armature == 0.0);
            }
        }
    }

    /// The relative standard deviation of the drawn masses, rotor inertias
    /// and principal inertias matches the setting (within 10 % of σ over
    /// 6 × 400 draws), their mean is the nominal value (within 3 standard
    /// errors), and the centre-of-mass offset has RMS σ·√3 of the link scale.
    #[test]
    fn the_spread_matches_the_setting() {
        let r = Robot::irb140();
        let sd = 0.1;
        let (mut mass, mut drive, mut com) = (Vec::new(), Vec::new(), Vec::new());
        for seed in 0..400 {
            let (_, e) = r.with_inertia_error(sd, seed).unwrap();
            for x in &e {
                mass.push(x.mass);
                drive.push(x.drive_inertia);
                com.push(x.com_offset);
            }
        }
        let stats = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
            (m, var.sqrt())
        };
        for (what, v) in [("mass", &mass), ("drive inertia", &drive)] {
            let (m, s) = stats(v);
            assert!((s - sd).abs() < 0.1 * sd, "{what}: sd {s} vs {sd}");
            let se = sd / (v.len() as f64).sqrt();
            assert!(m.abs() < 3.0 * se, "{what}: mean {m} (se {se})");
        }
        let rms = (com.iter().map(|x| x * x).sum::<f64>() / com.len() as f64).sqrt();
        let expect = sd * 3f64.sqrt();
        assert!(
            (rms - expect).abs() < 0.1 * expect,
            "com rms {rms} vs {expect}"
        );
    }
}
