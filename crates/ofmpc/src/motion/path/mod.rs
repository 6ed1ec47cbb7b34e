//! The path stage: the program's moves with their corners blended within the tolerance
//! (`blend.rs`: the policy, which corners and how; `g2blend.rs`: the curvature-continuous
//! quintic blend of one corner). Upstream of the timing: no file here references it.

pub(super) mod blend;
pub(super) mod g2blend;
