//! Path geometry, the layer below both the G-code reader ([`crate::gcode`], which builds
//! segments from a program) and the planner ([`crate::motion`], which blends and times them):
//! working planes, straight lines and circular / helical arcs parameterized by arc length
//! (`segment`), the circle through two points of a given radius (`arc`) and the arc that
//! rounds a corner between two lines (`corner`).
//!
//! Pure geometry: no time, no G-code words, no robot. Units are SI (metres, radians).

pub(crate) mod arc;
pub(crate) mod corner;
pub(crate) mod segment;

pub(crate) use arc::{center_from_radius, RadiusArcError};
pub(crate) use segment::ArcError;
pub use segment::{ArcDirection, Plane, Segment};
