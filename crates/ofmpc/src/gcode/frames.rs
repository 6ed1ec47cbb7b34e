//! Program ↔ machine coordinates with LinuxCNC's rotated work coordinate systems
//! (`G10 L2 Pn R<degrees>`): the machine point of a program point `p` is
//!
//! `m = Rz(θ) · (p + g92) + o`
//!
//! with `o` the work offset of the active system (G54 … G59.3), `g92` the G92/G52 offset and
//! `θ` the system's rotation about Z (only X and Y rotate). This is LinuxCNC's
//! `rotate_and_offset_pos` (src/emc/task/emccanon.cc): G92 is added to the programmed
//! point, the sum is rotated, then the work offset is added. On a G53 line the program point
//! is the machine point. Without a rotation the formulas reduce to `m = p + (o + g92)`,
//! computed exactly as before rotations were read (the same floating-point operations).

use super::interpreter::Interpreter;
use nalgebra::Vector3;

/// `v` rotated about Z by `deg` degrees (X and Y only).
pub(super) fn rotate_z(v: Vector3<f64>, deg: f64) -> Vector3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Vector3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
}

impl Interpreter {
    /// The rotation (degrees about Z) of the active coordinate system; 0 on a G53 line.
    pub(super) fn rotation(&self) -> f64 {
        if self.ext.machine {
            return 0.0;
        }
        self.ext.rotation.get(self.wcs).copied().unwrap_or(0.0)
    }

    /// The machine point (m) of program point `p` (m) in the active system.
    pub(super) fn to_machine(&self, p: Vector3<f64>) -> Vector3<f64> {
        let work = self.work();
        let theta = self.rotation();
        if theta == 0.0 {
            return Vector3::new(p.x + work[0], p.y + work[1], p.z + work[2]);
        }
        let o = self.offsets.get(self.wcs).copied().unwrap_or([0.0; 3]);
        let g = self.ext.g92;
        rotate_z(Vector3::new(p.x + g[0], p.y + g[1], p.z + g[2]), theta) + Vector3::from(o)
    }

    /// The program point (m) of machine point `m` in the active system (the inverse of
    /// [`Self::to_machine`]).
    pub(super) fn to_program(&self, m: Vector3<f64>) -> Vector3<f64> {
        let work = self.work();
        let theta = self.rotation();
        if theta == 0.0 {
            return Vector3::new(m.x - work[0], m.y - work[1], m.z - work[2]);
        }
        self.to_program_in(m, self.wcs)
    }

    /// The program point (m) of machine point `m` in the active coordinate system, also
    /// on a G53 line (G53 acts on its own line's moves only): what `#5420…` and `#<_x>`
    /// read.
    pub(super) fn to_program_modal(&self, m: Vector3<f64>) -> Vector3<f64> {
        if self.ext.rotation.get(self.wcs).copied().unwrap_or(0.0) == 0.0 {
            let o = self.offsets.get(self.wcs).copied().unwrap_or([0.0; 3]);
            let g = self.ext.g92;
            return Vector3::from([0, 1, 2].map(|a| m[a] - (o[a] + g[a])));
        }
        self.to_program_in(m, self.wcs)
    }

    /// The program point (m) of machine point `m` in coordinate system `k` (G54 + k), not
    /// on a G53 line.
    pub(super) fn to_program_in(&self, m: Vector3<f64>, k: usize) -> Vector3<f64> {
        let o = self.offsets.get(k).copied().unwrap_or([0.0; 3]);
        let theta = self.ext.rotation.get(k).copied().unwrap_or(0.0);
        let g = self.ext.g92;
        let r = rotate_z(m - Vector3::from(o), -theta);
        Vector3::new(r.x - g[0], r.y - g[1], r.z - g[2])
    }

    /// The machine point of a move from machine point `pos` whose program coordinates are
    /// given (absolute, m) for some axes; the other axes keep their program coordinates.
    pub(super) fn place(&self, pos: Vector3<f64>, given: [Option<f64>; 3]) -> Vector3<f64> {
        if self.rotation() == 0.0 {
            let work = self.work();
            let mut t = pos;
            for (a, v) in given.iter().enumerate() {
                if let Some(v) = v {
                    t[a] = v + work[a];
                }
            }
            return t;
        }
        let mut p = self.to_program(pos);
        for (a, v) in given.iter().enumerate() {
            if let Some(v) = v {
                p[a] = *v;
            }
        }
        self.to_machine(p)
    }

    /// The machine point of an incremental move (G91) from machine point `pos` by `delta`
    /// (program axes, m; `None`: 0): the rotated program displacement.
    pub(super) fn shift_by(&self, pos: Vector3<f64>, delta: [Option<f64>; 3]) -> Vector3<f64> {
        let theta = self.rotation();
        if theta == 0.0 {
            let mut t = pos;
            for (a, v) in delta.iter().enumerate() {
                if let Some(v) = v {
                    t[a] = pos[a] + v;
                }
            }
            return t;
        }
        let d = Vector3::from(delta.map(|v| v.unwrap_or(0.0)));
        pos + rotate_z(d, theta)
    }
}

impl Interpreter {
    /// G10 L20 Pk in a rotated system k: the offset `o` that makes the current point read
    /// as the given program coordinates, `o = here - Rz(θ)·(p + g92)`; the axes not given
    /// keep their current program coordinates, so a new X or Y moves both XY offsets
    /// (LinuxCNC's `convert_setup`).
    pub(super) fn set_offset_l20_rotated(&mut self, k: usize, args: &super::codes::Args<'_, '_>) {
        let scale = self.scale();
        let here = self.here();
        let theta = self.ext.rotation.get(k).copied().unwrap_or(0.0);
        let mut p = self.to_program_in(here, k);
        let given = ['X', 'Y', 'Z'].map(|c| args.get(c).map(|w| w.value * scale));
        for (a, v) in given.iter().enumerate() {
            if let Some(v) = v {
                p[a] = *v;
            }
        }
        let g = Vector3::from(self.ext.g92);
        let m = rotate_z(p + g, theta);
        let Some(o) = self.offsets.get_mut(k) else {
            return;
        };
        if given[0].is_some() || given[1].is_some() {
            o[0] = here.x - m.x;
            o[1] = here.y - m.y;
        }
        if given[2].is_some() {
            o[2] = here.z - m.z;
        }
    }
}
