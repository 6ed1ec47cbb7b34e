//! The true state of the joints as a sensor sees it: a plain struct, so that
//! the [`super::Sensor`] reads a simulated plant ([`super::Plant::state`]) or
//! real hardware alike.

/// The true joint state at one sample, with the sample's place in the run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointState<'a> {
    /// Joint positions (rad, n).
    pub q: &'a [f64],
    /// Joint velocities (rad/s, n).
    pub qd: &'a [f64],
    /// Control periods since the run began (0 before the first period: the
    /// robot is at rest, so an encoder velocity reads 0).
    pub sample: usize,
    /// The path's sample of this period, `None` before the path (a pre-roll
    /// at rest): the encoder faults, given at path times, are matched to it.
    pub path_sample: Option<usize>,
}
