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
// Index loops mirror the equations' subscripts (H_ij, C_ij, q_i); iterator
// chains over several parallel arrays would read worse.
#![allow(clippy::needless_range_loop)]

pub mod control;
pub mod dynamics;
pub mod gcode;
pub mod ik;
pub mod path;
pub mod reference;
pub mod robot;
pub mod sim;
pub mod spatial;
pub mod timelaw;
pub mod trajectory;
