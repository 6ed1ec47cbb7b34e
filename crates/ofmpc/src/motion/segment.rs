//! Path geometry: straight lines and circular / helical arcs in 3-D, parameterized by arc
//! length. The items live in [`crate::geometry`] (below both [`crate::gcode`], which builds
//! segments, and [`crate::motion`], which times them); this path re-exports them unchanged.

pub use crate::geometry::segment::*;
