//! # ofmpc — offset-free model predictive control of serial robots
//!
//! Pure computation, no printing. Data flow, one module per concept:
//! G-code text → [`gcode`] → path segments → timed Cartesian reference → joint
//! reference (IK) → controller (robot model) → torque → plant (robot model +
//! payload) → measurement → record → metrics.
//!
//! Equations are referenced as in the paper ("Predictive Control for Offset-Free
//! Motion of Industrial Articulated Robots"), e.g. *Eq. (39)*.

#![warn(missing_docs)]

pub mod dynamics;
pub mod ik;
