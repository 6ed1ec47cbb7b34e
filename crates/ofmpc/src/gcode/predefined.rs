//! The values of LinuxCNC's predefined parameters from the modal state: the read-only named
//! parameters (`#<_x>`, `#<_metric>`, `#<_motion_mode>`, …; LinuxCNC's
//! `Interp::lookup_named_param`, interp_namedparams.cc) and the numbered system parameters
//! (`#5220` coordinate system, `#5221…` work offsets, `#5420…` position; LinuxCNC's
//! "Numbered Parameters" table), in program units.

use super::codes::Motion;
use super::expr::{MAX_PARAMETER, N_PREDEFINED};
use super::interpreter::Interpreter;
use crate::geometry::Plane;

/// The LinuxCNC version the reader reports in `#<_vmajor>` and `#<_vminor>` (2.9.0, whose
/// G-code it follows).
const VERSION: (f64, f64) = (2.9, 0.0);

impl Interpreter {
    /// Writes the predefined named parameters that come from the modal state into `out`
    /// (indexed as [`super::expr::PREDEFINED`]; the first four, `_line` … `_call_level`, are left to the
    /// O-word runner).
    pub(super) fn predefined(&self, out: &mut [f64; N_PREDEFINED]) {
        let t = |b: bool| f64::from(u8::from(b));
        let scale = self.scale();
        let here = self.here();
        let local = self.to_program_modal(here);
        let prog = [0, 1, 2].map(|a| local[a] / scale);
        let motion = match self.motion {
            Some(Motion::Rapid) => 0.0,
            Some(Motion::Linear) => 10.0,
            Some(Motion::Cw) => 20.0,
            Some(Motion::Ccw) => 30.0,
            Some(Motion::Cycle(n)) => f64::from(n) * 10.0,
            None => 800.0,
        };
        let plane = match self.plane {
            Plane::XY => 170.0,
            Plane::ZX => 180.0,
            Plane::YZ => 190.0,
        };
        let e = &self.ext;
        let values: [f64; N_PREDEFINED - 4] = [
            0.0,                            // _remap_level
            0.0,                  // _task: read as a preview reads it (LinuxCNC's rs274: 0)
            VERSION.0,            // _vmajor
            VERSION.1,            // _vminor
            1.0,                  // _metric_machine: the robot is metric
            motion,               // _motion_mode
            plane,                // _plane
            400.0,                // _ccomp: G40 (cutter compensation is not supported)
            t(!self.inch),        // _metric
            t(self.inch),         // _imperial
            t(self.absolute),     // _absolute
            t(!self.absolute),    // _incremental
            t(e.feed_mode == 93), // _inverse_time
            t(e.feed_mode == 94), // _units_per_minute
            t(e.feed_mode == 95), // _units_per_rev
            540.0 + 10.0 * self.wcs as f64, // _coord_system
            t(self.tool_length != 0.0), // _tool_offset
            t(!e.retract_initial), // _retract_r_plane (G99)
            t(e.retract_initial), // _retract_old_z (G98)
            1.0,                  // _spindle_rpm_mode (G97)
            0.0,                  // _spindle_css_mode (G96 is not supported)
            t(e.arc_absolute),    // _ijk_absolute_mode
            0.0,                  // _lathe_diameter_mode
            1.0,                  // _lathe_radius_mode
            t(e.spindle_dir != 0), // _spindle_on
            t(e.spindle_dir > 0), // _spindle_cw
            t(e.mist),            // _mist
            t(e.flood),           // _flood
            1.0,                  // _speed_override
            1.0,                  // _feed_override
            0.0,                  // _adaptive_feed
            0.0,                  // _feed_hold
            self.feed.unwrap_or(0.0), // _feed
            e.spindle.unwrap_or(0.0).abs(), // _rpm
            e.tool_current,       // _current_tool
            0.0,                  // _current_pocket
            0.0,                  // _selected_pocket
            e.tool_selected,      // _selected_tool
            prog[0],              // _x
            prog[1],              // _y
            prog[2],              // _z
            0.0,                  // _a
            0.0,                  // _b
            0.0,                  // _c
            0.0,                  // _u
            0.0,                  // _v
            0.0,                  // _w
            here[0] / scale,      // _abs_x
            here[1] / scale,      // _abs_y
            here[2] / scale,      // _abs_z
            0.0,                  // _abs_a
            0.0,                  // _abs_b
            0.0,                  // _abs_c
            0.0,                  // _abs_u
            0.0,                  // _abs_v
            0.0,                  // _abs_w
        ];
        out[4..].copy_from_slice(&values);
    }

    /// Writes the numbered system parameters into `numbered` (see
    /// [`super::expr::is_system_parameter`]), in program units: #5161–5163 and #5181–5183
    /// the G28/G30 positions, #5210 G92 on, #5211–5213 the G92 offset, #5220 the
    /// coordinate system (1 = G54), #5221 + 20 k the offset of G54 + k (#5230 + 20 k its
    /// rotation, degrees), #5400 the tool,
    /// #5403 its length, #5420–5422 the position (program coordinates).
    pub(super) fn system_parameters(&self, numbered: &mut [f64]) {
        if numbered.len() <= MAX_PARAMETER.min(5428) {
            return;
        }
        let scale = self.scale();
        let e = &self.ext;
        for (k, base) in [5161, 5181].into_iter().enumerate() {
            let p = e.home[k].or(self.initial).unwrap_or_default();
            for a in 0..3 {
                numbered[base + a] = p[a] / scale;
            }
        }
        numbered[5210] = f64::from(u8::from(e.g92 != [0.0; 3]));
        for a in 0..3 {
            numbered[5211 + a] = e.g92[a] / scale;
        }
        numbered[5220] = self.wcs as f64 + 1.0;
        for (k, o) in self.offsets.iter().enumerate() {
            for a in 0..3 {
                numbered[5221 + 20 * k + a] = o[a] / scale;
            }
            numbered[5230 + 20 * k] = e.rotation.get(k).copied().unwrap_or(0.0);
        }
        numbered[5400] = e.tool_current;
        numbered[5403] = self.tool_length / scale;
        let local = self.to_program_modal(self.here());
        for a in 0..3 {
            numbered[5420 + a] = local[a] / scale;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::expr::{N_PREDEFINED, PREDEFINED};

    #[test]
    fn predefined_names_are_unique_and_start_with_underscore() {
        for (i, n) in PREDEFINED.iter().enumerate() {
            assert!(n.starts_with('_'));
            assert!(!PREDEFINED[..i].contains(n), "{n} twice");
        }
        assert_eq!(PREDEFINED[4], "_remap_level");
        assert_eq!(PREDEFINED[N_PREDEFINED - 1], "_abs_w");
    }
}
