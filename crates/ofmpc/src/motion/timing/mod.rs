//! The timing stage: the blended path timed under the feed and the path and joint limits
//! (`timelaw.rs`: the rest-to-rest laws of exact-stop moves; `exact.rs`: such a move slowed
//! down to keep the joints' limits; `topp.rs`: time-optimal timing of blended runs;
//! `trajectory.rs`: the timed path, [`CartesianTrajectory`](super::CartesianTrajectory)).
//! It uses the path stage and the joint map of `limits.rs`, never the joint reference.

pub(super) mod exact;
pub(super) mod timelaw;
pub(super) mod topp;
pub(super) mod trajectory;
