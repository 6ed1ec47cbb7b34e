//! Spatial (6-D) algebra on fixed-size 3-vectors, after Featherstone,
//! *Rigid Body Dynamics Algorithms* (2008), ch. 2.
//!
//! A motion vector is `(ω, v)`: angular velocity and the linear velocity of the
//! point at the frame's origin. A force vector is `(n, f)`: moment about the
//! origin and force. Both are kept as pairs of [`Vector3`], so that the
//! recursions cost 3-D products only.

use nalgebra::{Matrix3, Rotation3, Vector3};

/// A spatial motion vector `(ω, v)` (twist, spatial velocity or acceleration).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motion {
    /// Angular part ω.
    pub ang: Vector3<f64>,
    /// Linear part: velocity of the point at the frame origin.
    pub lin: Vector3<f64>,
}

/// A spatial force vector `(n, f)` (wrench about the frame origin).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Force {
    /// Moment about the frame origin.
    pub ang: Vector3<f64>,
    /// Force.
    pub lin: Vector3<f64>,
}

impl Motion {
    /// Zero motion.
    pub fn zero() -> Self {
        Self::default()
    }
    /// `self ×ₘ m` — spatial cross product of motions (Featherstone eq. 2.31).
    #[inline]
    pub fn cross_motion(&self, m: &Motion) -> Motion {
        Motion {
            ang: self.ang.cross(&m.ang),
            lin: self.ang.cross(&m.lin) + self.lin.cross(&m.ang),
        }
    }
    /// `self ×* f` — spatial cross product of a motion with a force (eq. 2.32).
    #[inline]
    pub fn cross_force(&self, f: &Force) -> Force {
        Force {
            ang: self.ang.cross(&f.ang) + self.lin.cross(&f.lin),
            lin: self.ang.cross(&f.lin),
        }
    }
    /// Scalar product with a force (power).
    #[inline]
    pub fn dot(&self, f: &Force) -> f64 {
        self.ang.dot(&f.ang) + self.lin.dot(&f.lin)
    }
    /// `self · s` for a scalar.
    #[inline]
    pub fn scale(&self, s: f64) -> Motion {
        Motion {
            ang: self.ang * s,
            lin: self.lin * s,
        }
    }
}

impl std::ops::Add for Motion {
    type Output = Motion;
    #[inline]
    fn add(self, o: Motion) -> Motion {
        Motion {
            ang: self.ang + o.ang,
            lin: self.lin + o.lin,
        }
    }
}

impl std::ops::Add for Force {
    type Output = Force;
    #[inline]
    fn add(self, o: Force) -> Force {
        Force {
            ang: self.ang + o.ang,
            lin: self.lin + o.lin,
        }
    }
}

impl std::ops::Sub for Force {
    type Output = Force;
    #[inline]
    fn sub(self, o: Force) -> Force {
        Force {
            ang: self.ang - o.ang,
            lin: self.lin - o.lin,
        }
    }
}

/// A rigid transform between two frames: the child frame's orientation `rot`
/// and origin `pos`, both expressed in the parent frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    /// Child axes in parent coordinates.
    pub rot: Matrix3<f64>,
    /// Child origin in parent coordinates.
    pub pos: Vector3<f64>,
}

impl Default for Transform {
    fn default() -> Self {
        Self::identity()
    }
}

impl Transform {
    /// The identity transform.
    pub fn identity() -> Self {
        Self {
            rot: Matrix3::identity(),
            pos: Vector3::zeros(),
        }
    }
    /// From URDF `xyz` and `rpy` (fixed-axis roll, pitch, yaw: R = Rz(y) Ry(p) Rx(r)).
    pub fn from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Self {
        let rot = Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]).into_inner();
        Self {
            rot,
            pos: Vector3::new(xyz[0], xyz[1], xyz[2]),
        }
    }
    /// `self ∘ other`: the pose of `other`'s child in `self`'s parent frame.
    #[inline]
    pub fn compose(&self, other: &Transform) -> Transform {
        Transform {
            rot: self.rot * other.rot,
            pos: self.pos + self.rot * other.pos,
        }
    }
    /// The inverse transform.
    #[inline]
    pub fn inverse(&self) -> Transform {
        let rt = self.rot.transpose();
        Transform {
            rot: rt,
            pos: -(rt * self.pos),
        }
    }
    /// From a nalgebra isometry (rotation matrix of its unit quaternion).
    pub fn from_isometry(x: &nalgebra::Isometry3<f64>) -> Self {
        Self {
            rot: x.rotation.to_rotation_matrix().into_inner(),
            pos: x.translation.vector,
        }
    }
    /// As a nalgebra isometry (rotation re-orthonormalized through a quaternion).
    pub fn to_isometry(&self) -> nalgebra::Isometry3<f64> {
        let r = nalgebra::UnitQuaternion::from_rotation_matrix(
            &nalgebra::Rotation3::from_matrix_unchecked(self.rot),
        );
        nalgebra::Isometry3::from_parts(nalgebra::Translation3::from(self.pos), r)
    }
    /// Maps a point from child to parent coordinates.
    #[inline]
    pub fn apply_point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.pos + self.rot * p
    }
    /// Expresses a motion given in the parent frame in the child frame.
    #[inline]
    pub fn motion_to_child(&self, m: &Motion) -> Motion {
        let rt = self.rot.transpose();
        Motion {
            ang: rt * m.ang,
            lin: rt * (m.lin + m.ang.cross(&self.pos)),
        }
    }
    /// Expresses a motion given in the child frame in the parent frame.
    #[inline]
    pub fn motion_to_parent(&self, m: &Motion) -> Motion {
        let ang = self.rot * m.ang;
        Motion {
            ang,
            lin: self.rot * m.lin + self.pos.cross(&ang),
        }
    }
    /// Expresses a force given in the child frame in the parent frame.
    #[inline]
    pub fn force_to_parent(&self, f: &Force) -> Force {
        let lin = self.rot * f.lin;
        Force {
            ang: self.rot * f.ang + self.pos.cross(&lin),
            lin,
        }
    }
}

/// The 3×3 skew-symmetric matrix `[v]×` with `[v]× w = v × w`.
#[inline]
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Rotation by `angle` about the unit `axis` (Rodrigues).
#[inline]
pub(crate) fn axis_angle(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    let k = skew(axis);
    Matrix3::identity() + k * s + (k * k) * (1.0 - c)
}

/// Spatial inertia of a rigid body about a frame's origin, in that frame:
/// mass `m`, first moment `h = m c` (c: centre of mass) and the rotational
/// inertia `i_o` about the origin (not about the centre of mass).
///
/// As a 6×6 matrix, `[[i_o, [h]×], [[h]×ᵀ, m 1]]` (Featherstone eq. 2.63).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertia {
    /// Mass (kg).
    pub mass: f64,
    /// First moment of mass `m c` (kg·m).
    pub h: Vector3<f64>,
    /// Rotational inertia about the frame origin (kg·m²).
    pub i_o: Matrix3<f64>,
}

impl Default for Inertia {
    fn default() -> Self {
        Self::zero()
    }
}

impl Inertia {
    /// A massless body.
    pub fn zero() -> Self {
        Self {
            mass: 0.0,
            h: Vector3::zeros(),
            i_o: Matrix3::zeros(),
        }
    }
    /// From mass, centre of mass and the inertia tensor about the centre of
    /// mass, all in this frame's axes (the URDF `<inertial>` convention once
    /// its `origin` rotation has been applied).
    pub fn from_com(mass: f64, com: Vector3<f64>, i_com: Matrix3<f64>) -> Self {
        let cx = skew(&com);
        Self {
            mass,
            h: com * mass,
            i_o: i_com - cx * cx * mass,
        }
    }
    /// A point mass at `p`.
    pub fn point_mass(mass: f64, p: Vector3<f64>) -> Self {
        Self::from_com(mass, p, Matrix3::zeros())
    }
    /// Centre of mass (origin for a massless body).
    pub fn com(&self) -> Vector3<f64> {
        if self.mass > 0.0 {
            self.h / self.mass
        } else {
            Vector3::zeros()
        }
    }
    /// Rotational inertia about the centre of mass.
    pub fn i_com(&self) -> Matrix3<f64> {
        let c = self.com();
        let cx = skew(&c);
        self.i_o + cx * cx * self.mass
    }
    /// The same body expressed in the parent frame of `x` (this inertia is
    /// given in `x`'s child frame).
    pub fn to_parent(&self, x: &Transform) -> Inertia {
        let rh = x.rot * self.h;
        let px = skew(&x.pos);
        let rhx = skew(&rh);
        Inertia {
            mass: self.mass,
            h: rh + x.pos * self.mass,
            i_o: x.rot * self.i_o * x.rot.transpose() - (rhx * px + px * rhx) - px * px * self.mass,
        }
    }
    /// `I · m`: the momentum of the body moving with `m` (Featherstone eq. 2.63).
    #[inline]
    pub fn apply(&self, m: &Motion) -> Force {
        Force {
            ang: self.i_o * m.ang + self.h.cross(&m.lin),
            lin: m.lin * self.mass - self.h.cross(&m.ang),
        }
    }
}

impl std::ops::Add for Inertia {
    type Output = Inertia;
    fn add(self, o: Inertia) -> Inertia {
        Inertia {
            mass: self.mass + o.mass,
            h: self.h + o.h,
            i_o: self.i_o + o.i_o,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::linalg::random::symmetric as rnd;
    fn v3(s: &mut u64) -> Vector3<f64> {
        Vector3::new(rnd(s), rnd(s), rnd(s))
    }

    #[test]
    fn inertia_transform_matches_kinetic_energy() {
        // The kinetic energy ½ vᵀ I v is frame-independent.
        let mut s = 7u64;
        for _ in 0..100 {
            let a = v3(&mut s);
            let inertia = Inertia::from_com(
                2.0 + rnd(&mut s),
                v3(&mut s),
                Matrix3::from_diagonal(&Vector3::new(0.3, 0.4, 0.5)),
            );
            let x = Transform {
                rot: axis_angle(&a.normalize(), rnd(&mut s) * 3.0),
                pos: v3(&mut s),
            };
            let m_child = Motion {
                ang: v3(&mut s),
                lin: v3(&mut s),
            };
            let m_parent = x.motion_to_parent(&m_child);
            let e_child = m_child.dot(&inertia.apply(&m_child));
            let e_parent = m_parent.dot(&inertia.to_parent(&x).apply(&m_parent));
            assert!((e_child - e_parent).abs() < 1e-12 * e_child.abs().max(1.0));
            // Round trip of motions and duality of forces.
            let back = x.motion_to_child(&m_parent);
            assert!((back.ang - m_child.ang).norm() < 1e-13);
            assert!((back.lin - m_child.lin).norm() < 1e-13);
            let f = Force {
                ang: v3(&mut s),
                lin: v3(&mut s),
            };
            let p1 = m_child.dot(&f);
            let p2 = m_parent.dot(&x.force_to_parent(&f));
            assert!((p1 - p2).abs() < 1e-13);
        }
    }

    #[test]
    fn com_and_parallel_axis_round_trip() {
        let i = Inertia::from_com(
            3.0,
            Vector3::new(0.1, -0.2, 0.3),
            Matrix3::from_diagonal(&Vector3::new(0.1, 0.2, 0.3)),
        );
        assert!((i.com() - Vector3::new(0.1, -0.2, 0.3)).norm() < 1e-15);
        assert!((i.i_com() - Matrix3::from_diagonal(&Vector3::new(0.1, 0.2, 0.3))).norm() < 1e-15);
    }
}
