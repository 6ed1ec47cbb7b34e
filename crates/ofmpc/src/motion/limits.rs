//! What the timing stage and the joint reference share, below both: the joint map (inverse
//! kinematics sample by sample, [`JointMap`]), the reference's failures, the plan size limit
//! and which joint limit a plan could not keep. The timing stage (topp.rs, exact.rs) checks
//! joint limits through the map; the joint reference (reference.rs) builds its samples with it.

use crate::dynamics::RobotDynamics;
use crate::ik::{ForwardKinematics, IkError, IkSolver, RobustIk, RobustIkSettings, UrSolver};
use crate::robot::Robot;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// Largest number of values (samples × columns) planning may allocate for one reference or
/// one timed path: 50 million (400 MB of `f64`). Planning checks the count before it
/// allocates and reports what makes it large.
pub const MAX_PLAN_VALUES: usize = 50_000_000;

/// The ratio of the flange Jacobian's smallest to largest singular value below which a
/// joint limit met by the continuous branch is blamed on a singularity
/// ([`ReferenceFailure::SingularPass`]).
pub const SINGULAR_PASS_RATIO: f64 = 1e-3;

/// The ratio of the smallest to the largest singular value of the flange Jacobian's position
/// rows below which a joint speed over its limit is blamed on the edge of the arm's reach
/// ([`ReferenceFailure::ReachEdge`]): the elbow straight, where the flange cannot move
/// along the arm.
pub const REACH_EDGE_RATIO: f64 = 0.02;

/// The ratio of the smallest to the largest singular value of the position rows of the arm
/// joints' Jacobian ([`JointMap::arm_ratio`]) below which a singular start pose is blamed on
/// the elbow (the arm stretched out, [`ReferenceFailure::StartStretched`]) rather than on the
/// wrist: measured 0.043–0.047 for a UR5 with its elbow at 0.02–0.05 rad, 0.34 for the
/// IRB 140's q = 0 (the wrist straight).
pub const ARM_STRETCHED_RATIO: f64 = 0.1;

/// Distance (m) from the path's start point within which a point out of reach is blamed on a
/// start pose at the edge of the reach ([`ReferenceFailure::StartAtReach`]).
pub const LEAVING_REACH: f64 = 5e-3;

/// Distance (m) from the path's start point within which a jump of the joints is blamed on a
/// singular start pose ([`ReferenceFailure::StartSingular`]).
pub const LEAVING_START: f64 = 1e-3;

/// How close (m, rad) the path's first tool pose must be to the start pose's for the run to
/// start at the start pose itself ([`super::reference::build_reference`]), and how far (rad) the inverse
/// kinematics' solution must then be from the start pose to be replaced by it.
pub const START_POSE_TOLERANCE: f64 = 1e-9;

/// Values stored per sample of a reference of `n` joints: q, q̇, q̈ (3n), the flange position
/// (3) and the program line (1).
pub const fn values_per_sample(n: usize) -> usize {
    3 * n + 4
}

/// A speed over its limit and the limit as a message shows them: to 3 decimals, more where
/// 3 would print the two the same (issue 38: "2.175 rad/s, above its speed limit 2.175").
fn shown(speed: f64, limit: f64) -> (String, String) {
    let mut digits = 3;
    while digits < 9 && format!("{speed:.digits$}") == format!("{limit:.digits$}") {
        digits += 1;
    }
    (format!("{speed:.digits$}"), format!("{limit:.digits$}"))
}

/// What went wrong at one sample of the path.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ReferenceFailure {
    /// The inverse kinematics failed (unreachable pose, joint limit, ...).
    #[error("{0}; move the part into the workspace with a work offset (G10 L2 P1 X.. Y.. Z..), or change the orientation")]
    Ik(IkError),
    /// Following the path continuously would take a joint outside its range; the only
    /// solutions within the limits are another arm configuration (a jump).
    #[error(
        "joint {joint} ({name}) would have to reach {:.1}°, outside its range [{:.1}°, {:.1}°], to follow the path \
         (the only solutions within the limits are another arm configuration, a jump); move the part with a \
         work offset (G10 L2 P1 X.. Y.. Z..), or change the orientation",
        value.to_degrees(), lower.to_degrees(), upper.to_degrees()
    )]
    BranchLimit {
        /// Joint number, 1-based.
        joint: usize,
        /// Joint name.
        name: String,
        /// Value the joint would need (rad).
        value: f64,
        /// Lower limit (rad).
        lower: f64,
        /// Upper limit (rad).
        upper: f64,
    },
    /// Following the path continuously would take a joint outside its range because the path
    /// passes next to a singularity of the arm (its Jacobian's smallest singular value below
    /// `SINGULAR_PASS_RATIO` of its largest), where the branch turns that joint by a large
    /// angle within a short distance.
    #[error(
        "the path passes next to a singularity of the arm (for a 6-axis arm, usually the wrist straight, joint 5 \
         near 0), where joint {joint} ({name}) would have to turn to {:.1}°, outside its range [{:.1}°, {:.1}°], \
         to follow it; move the part with a work offset (G10 L2 P1 X.. Y.. Z..) so that the path keeps away from \
         the singularity, or change the orientation (by default the start pose's: start from a pose with the \
         wrist bent)",
        value.to_degrees(), lower.to_degrees(), upper.to_degrees()
    )]
    SingularPass {
        /// Joint number, 1-based.
        joint: usize,
        /// Joint name.
        name: String,
        /// Value the joint would need (rad).
        value: f64,
        /// Lower limit (rad).
        lower: f64,
        /// Upper limit (rad).
        upper: f64,
    },
    /// A joint would move faster than its speed limit.
    #[error(
        "joint {joint} ({name}) would move at {} rad/s, above its speed limit {} rad/s; lower \
         the path speed (F) or acceleration, or move the part away from the wrist singularity with a work \
         offset",
        shown(*speed, *limit).0,
        shown(*speed, *limit).1
    )]
    JointSpeed {
        /// Joint number, 1-based.
        joint: usize,
        /// Joint name.
        name: String,
        /// Speed needed (rad/s).
        speed: f64,
        /// Its limit (rad/s).
        limit: f64,
    },
    /// A joint would move faster than its speed limit while the tool is still at its start
    /// point (within `LEAVING_START`) and the run started at the robot's start pose: the
    /// start pose is at (or next to) a singularity, where following the path at a constant
    /// orientation needs the joints to jump (q = 0 of the IRB 140: the wrist straight, joints
    /// 4 and 6 on one axis).
    #[error(
        "joint {joint} ({name}) would move at {} rad/s, above its speed limit {} rad/s, as the \
         tool leaves its start point: the robot's start pose is at a singularity (for a 6-axis arm, \
         usually the wrist straight, joint 5 at 0), where the path needs the joints to jump; start from a \
         pose away from it, e.g. with the wrist bent (joint 5 at 0.5 rad)",
        shown(*speed, *limit).0,
        shown(*speed, *limit).1
    )]
    StartSingular {
        /// Joint number, 1-based.
        joint: usize,
        /// Joint name.
        name: String,
        /// Speed needed (rad/s).
        speed: f64,
        /// Its limit (rad/s).
        limit: f64,
    },
    /// A joint would move faster than its speed limit while the tool is still at its start
    /// point (within `LEAVING_START`), the run started at the robot's start pose, and that
    /// pose holds the arm almost stretched out (the position rows of its arm joints' Jacobian
    /// near rank-deficient, `ARM_STRETCHED_RATIO`): the elbow is the straight joint, not the
    /// wrist, and the path leaves the reach the joints can follow smoothly.
    #[error(
        "the tool leaves the reach of the start pose as it leaves its start point: the robot's start pose \
         holds the arm almost stretched out (its elbow nearly straight, at the edge of the reach), where a \
         small move of the tool needs a jump of the joints (joint {joint} ({name}) would move at {} \
         rad/s, above its speed limit {} rad/s); start from a pose with the elbow bent",
        shown(*speed, *limit).0,
        shown(*speed, *limit).1
    )]
    StartStretched {
        /// Joint number, 1-based.
        joint: usize,
        /// Joint name.
        name: String,
        /// Speed needed (rad/s).
        speed: f64,
        /// Its limit (rad/s).
        limit: f64,
    },
    /// A joint would jump between two samples: the inverse kinematics' solution nearest to the
    /// previous one changes arm configuration (a branch change: the path crosses a singularity
    /// or a configuration boundary), so the step does not shrink with the distance travelled;
    /// a slower path would not help.
    #[error(
        "joint {joint} ({name}) would jump by {:.1}° between two samples ({speed:.1} rad/s, its limit \
         {limit:.3} rad/s): the inverse kinematics changes arm configuration there (a branch change at a \
         singularity), which no path speed can follow; move the part with a work offset so that the path \
         keeps away from the singularity, or change the orientation or the start pose",
        step.to_degrees()
    )]
    BranchJump {
        /// Joint number, 1-based.
        joint: usize,
        /// Joint name.
        name: String,
        /// The joint's step between the two samples (rad).
        step: f64,
        /// Speed that step needs (rad/s).
        speed: f64,
        /// Its limit (rad/s).
        limit: f64,
    },
    /// A joint would move faster than its speed limit because the path runs at the edge of
    /// the arm's reach: the flange Jacobian's position rows are near rank-deficient (the elbow
    /// straight, the arm stretched out), where a small move of the tool needs a large turn of
    /// the joints.
    #[error(
        "the path reaches the edge of the arm's reach (the arm stretched out, its elbow almost straight): \
         joint {joint} ({name}) would move at {} rad/s, above its speed limit {} rad/s, to \
         follow it; move the part towards the robot with a work offset, or start from a pose with the elbow \
         bent",
        shown(*speed, *limit).0,
        shown(*speed, *limit).1
    )]
    ReachEdge {
        /// Joint number, 1-based.
        joint: usize,
        /// Joint name.
        name: String,
        /// Speed needed (rad/s).
        speed: f64,
        /// Its limit (rad/s).
        limit: f64,
    },
    /// The path leaves the arm's reach right after the start pose, where the run starts: the
    /// start pose holds the arm at the edge of its reach (stretched out, e.g. a UR arm's q = 0).
    #[error(
        "the tool leaves the arm's reach as it leaves its start point (after {:.3} mm of path its wrist centre \
         lies {:.3} mm outside the workspace): the robot's start pose holds the arm stretched out at the edge \
         of its reach; start from a pose with the elbow bent",
        moved * 1e3, excess * 1e3
    )]
    StartAtReach {
        /// Distance (m) by which the wrist centre misses the reachable shell.
        excess: f64,
        /// Distance (m) of the failing point from the start point.
        moved: f64,
    },
    /// The sample period is not positive and finite.
    #[error("the sample period must be positive and finite, got {0} s")]
    SamplePeriod(f64),
    /// Sampling the path would need more values than [`MAX_PLAN_VALUES`].
    #[error("sampling the path needs {count:.3e} values, above the limit of {limit}; shorten the program, raise the speed or the sample period")]
    TooManySamples {
        /// Values needed.
        count: f64,
        /// The limit.
        limit: usize,
    },
}

/// Why a path cannot be followed in joint space: where (program line, time, flange
/// position) and what ([`ReferenceFailure`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "program line {line}{} (t = {time:.3} s), flange at ({:.1}, {:.1}, {:.1}) mm: {failure}",
    column_text(*column), position[0] * 1e3, position[1] * 1e3, position[2] * 1e3
)]
pub struct ReferenceError {
    /// Program line of the failing sample: the line of the motion that produced the point.
    pub line: usize,
    /// Column (1-based) of that motion on its line; 0 when unknown.
    pub column: usize,
    /// Time of the failing sample (s).
    pub time: f64,
    /// Requested flange position (m, base frame).
    pub position: [f64; 3],
    /// What failed.
    pub failure: ReferenceFailure,
}

/// `", column C"` for a known column `C` (> 0), else nothing.
fn column_text(column: usize) -> String {
    if column > 0 {
        format!(", column {column}")
    } else {
        String::new()
    }
}

/// How the flange orientation along the path is chosen: constant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Orientation {
    /// The flange (TCP) orientation of the robot at its start pose ([`Robot::start_q`]:
    /// q = 0 by default, where that is inside the limits; the IRB 140: tool axis along
    /// base +x, as in the paper).
    #[default]
    AtZero,
    /// A fixed rotation of the flange in the base frame.
    Fixed(UnitQuaternion<f64>),
}

pub(crate) enum Ik {
    Analytic(Box<IkSolver>),
    /// The UR closed form, solving for the TCP directly.
    Ur(Box<UrSolver>),
    Numeric(Box<RobustIk>),
}

/// Flange positions → joint positions along a path, each solution the one nearest to the
/// previous (the first nearest to the start pose), with a constant orientation. Shared by the
/// reference sampler and the planner's joint-limit grid.
pub(crate) struct JointMap {
    pub(crate) fk: RobotDynamics,
    pub(crate) ik: Ik,
    pub(crate) rotation: UnitQuaternion<f64>,
    pub(crate) prev: Vec<f64>,
    pub(crate) robot: Robot,
    /// The flange in the TCP frame (`tcp⁻¹`): the analytic IK solves for the flange.
    pub(crate) tcp_inverse: Isometry3<f64>,
}

impl JointMap {
    pub(crate) fn new(robot: &Robot, orientation: Orientation) -> Result<Self, IkError> {
        let n = robot.dof();
        let mut fk = RobotDynamics::new(robot.clone());
        let rotation = match orientation {
            Orientation::AtZero => fk.flange_pose(robot.start_q()).rotation,
            Orientation::Fixed(r) => r,
        };
        let lower = robot.lower_limits();
        let upper = robot.upper_limits();
        let ik = match (robot.opw_parameters(), robot.ur_kinematics()) {
            (Some(opw), _) if n == 6 => {
                let lo: [f64; 6] = std::array::from_fn(|i| lower[i].max(-1e6));
                let up: [f64; 6] = std::array::from_fn(|i| upper[i].min(1e6));
                Ik::Analytic(Box::new(IkSolver::new(*opw, lo, up)?))
            }
            (None, Some(ur)) => {
                let lo: [f64; 6] = std::array::from_fn(|i| lower[i].max(-1e6));
                let up: [f64; 6] = std::array::from_fn(|i| upper[i].min(1e6));
                Ik::Ur(Box::new(UrSolver::new(ur, lo, up)?))
            }
            _ => {
                let lo: Vec<f64> = lower.iter().map(|v| v.max(-1e6)).collect();
                let up: Vec<f64> = upper.iter().map(|v| v.min(1e6)).collect();
                Ik::Numeric(Box::new(RobustIk::new(
                    n,
                    &lo,
                    &up,
                    robot.start_q(),
                    RobustIkSettings::default(),
                )?))
            }
        };
        Ok(Self {
            fk,
            ik,
            rotation,
            prev: robot.start_q().to_vec(),
            robot: robot.clone(),
            tcp_inverse: robot.tcp().to_isometry().inverse(),
        })
    }

    /// When the tool pose at `p` (with the path's orientation) is the start pose's, within
    /// [`START_POSE_TOLERANCE`], and the last solution differs from the start pose by more than
    /// that: makes the start pose the solution (the run then starts where the robot stands,
    /// not in another configuration of the same tool pose) and returns it.
    pub(crate) fn keep_start_pose(&mut self, p: &Vector3<f64>) -> Option<&[f64]> {
        let start = self.robot.start_q();
        let close = self
            .prev
            .iter()
            .zip(start)
            .all(|(a, b)| (a - b).abs() <= START_POSE_TOLERANCE);
        if close {
            return None;
        }
        let pose = self.fk.flange_pose(start);
        let dp = (pose.translation.vector - p).norm();
        let dr = self.rotation.angle_to(&pose.rotation);
        if dp <= START_POSE_TOLERANCE && dr <= START_POSE_TOLERANCE {
            self.prev.copy_from_slice(start);
            Some(&self.prev)
        } else {
            None
        }
    }

    /// Restarts from the start pose (the next solution is the one nearest to it).
    pub(crate) fn reset(&mut self) {
        self.prev.copy_from_slice(self.robot.start_q());
    }

    /// The previous solution (the branch the next [`JointMap::solve`] stays near).
    pub(crate) fn state(&self) -> &[f64] {
        &self.prev
    }

    /// Sets the previous solution (a state saved by [`JointMap::state`]).
    pub(crate) fn set_state(&mut self, q: &[f64]) {
        self.prev.copy_from_slice(q);
    }

    /// The joint positions at flange position `p`, nearest to the previous solution; they
    /// become the previous solution.
    pub(crate) fn solve(&mut self, p: &Vector3<f64>) -> Result<&[f64], ReferenceFailure> {
        let pose = Isometry3::from_parts(Translation3::from(*p), self.rotation);
        let flange = self.flange_pose(&pose);
        match &mut self.ik {
            Ik::Analytic(s) => {
                let hint: [f64; 6] = std::array::from_fn(|i| self.prev[i]);
                let q = s.solve_near(&flange, &hint).map_err(ReferenceFailure::Ik)?;
                self.prev.copy_from_slice(&q);
            }
            Ik::Ur(s) => {
                let hint: [f64; 6] = std::array::from_fn(|i| self.prev[i]);
                let q = s.solve_near(&pose, &hint).map_err(ReferenceFailure::Ik)?;
                self.prev.copy_from_slice(&q);
            }
            Ik::Numeric(num) => {
                let mut x = self.prev.clone();
                num.solve(&mut self.fk, &pose, &mut x)
                    .map_err(ReferenceFailure::Ik)?;
                self.prev = x;
            }
        }
        Ok(&self.prev)
    }

    /// The flange pose of a TCP pose (the pose itself when the TCP is the flange: bit for
    /// bit the pose the analytic IK solved before TCPs).
    pub(crate) fn flange_pose(&self, tcp_pose: &Isometry3<f64>) -> Isometry3<f64> {
        if self.robot.tcp_is_identity() {
            *tcp_pose
        } else {
            tcp_pose * self.tcp_inverse
        }
    }

    /// When the analytic solution jumps to another configuration, whether the continuous
    /// branch (the solution nearest to `prev` with the limits lifted) leaves a joint's range:
    /// the real reason for the jump.
    pub(crate) fn branch_limit(
        &mut self,
        p: &Vector3<f64>,
        prev: &[f64],
    ) -> Option<ReferenceFailure> {
        let singular = self.singular_ratio(prev) < SINGULAR_PASS_RATIO;
        let pose = Isometry3::from_parts(Translation3::from(*p), self.rotation);
        let hint: [f64; 6] = std::array::from_fn(|i| prev.get(i).copied().unwrap_or(0.0));
        let q = match &self.ik {
            Ik::Analytic(s) => {
                let wide = IkSolver::new(*s.parameters(), [-100.0; 6], [100.0; 6]).ok()?;
                wide.solve_near(&self.flange_pose(&pose), &hint).ok()?
            }
            Ik::Ur(s) => {
                let wide = UrSolver::new(*s.kinematics(), [-100.0; 6], [100.0; 6]).ok()?;
                wide.solve_near(&pose, &hint).ok()?
            }
            Ik::Numeric(_) => return None,
        };
        self.robot.joints().iter().enumerate().find_map(|(i, j)| {
            let (joint, name, value) = (i + 1, j.name.clone(), q[i]);
            let (lower, upper) = (j.limits.lower, j.limits.upper);
            (value < lower || value > upper).then_some(if singular {
                ReferenceFailure::SingularPass {
                    joint,
                    name,
                    value,
                    lower,
                    upper,
                }
            } else {
                ReferenceFailure::BranchLimit {
                    joint,
                    name,
                    value,
                    lower,
                    upper,
                }
            })
        })
    }

    /// The ratio of the smallest to the largest singular value of the flange Jacobian at `q`
    /// (0 at a singularity).
    pub(crate) fn singular_ratio(&mut self, q: &[f64]) -> f64 {
        let mut jac = nalgebra::DMatrix::zeros(6, q.len());
        self.fk.flange_jacobian(q, &mut jac);
        let sv = jac.singular_values();
        let max = sv.max();
        if max > 0.0 {
            sv.min() / max
        } else {
            0.0
        }
    }

    /// The ratio of the smallest to the largest singular value of the position rows of the
    /// flange Jacobian at `q` (0 at the edge of the reach, where the elbow is straight).
    pub(crate) fn position_ratio(&mut self, q: &[f64]) -> f64 {
        let mut jac = nalgebra::DMatrix::zeros(6, q.len());
        self.fk.flange_jacobian(q, &mut jac);
        let sv = jac.rows(0, 3).singular_values();
        let max = sv.max();
        if max > 0.0 {
            sv.min() / max
        } else {
            0.0
        }
    }

    /// The ratio of the smallest to the largest singular value of the position rows of the
    /// flange Jacobian's arm columns at `q` (every joint but the last three, the wrist): 0
    /// where the arm is stretched out, its elbow straight, so that the wrist centre cannot
    /// move along the arm; a wrist singularity leaves it unchanged.
    pub(crate) fn arm_ratio(&mut self, q: &[f64]) -> f64 {
        let mut jac = nalgebra::DMatrix::zeros(6, q.len());
        self.fk.flange_jacobian(q, &mut jac);
        let arm = q.len().saturating_sub(3).max(1);
        let sv = jac.view((0, 0), (3, arm)).singular_values();
        let max = sv.max();
        if max > 0.0 {
            sv.min() / max
        } else {
            0.0
        }
    }

    /// Whether joint `i`'s step from `prev` (at `from`) to `sol` (at `to`) is a jump: halving
    /// the interval six times, keeping the half where the joint turns more, still leaves half
    /// of the step in 1/64 of the distance (a continuous branch would leave about 1/64).
    pub(crate) fn jumps(
        &mut self,
        from: &Vector3<f64>,
        to: &Vector3<f64>,
        prev: &[f64],
        sol: &[f64],
        i: usize,
    ) -> bool {
        let full = (sol[i] - prev[i]).abs();
        let (mut a, mut b) = (*from, *to);
        let (mut qa, mut qb) = (prev.to_vec(), sol.to_vec());
        for _ in 0..6 {
            let mid = (a + b) / 2.0;
            self.set_state(&qa);
            let Ok(qm) = self.solve(&mid).map(<[f64]>::to_vec) else {
                return false;
            };
            if (qm[i] - qa[i]).abs() >= (qb[i] - qm[i]).abs() {
                (b, qb) = (mid, qm);
            } else {
                (a, qa) = (mid, qm);
            }
        }
        (qb[i] - qa[i]).abs() >= 0.5 * full
    }

    /// Exact joint velocity `J(q)⁻¹ [v; 0]` at the current solution (six joints, regular
    /// Jacobian), else `None`.
    pub(crate) fn velocity(
        &mut self,
        v: &Vector3<f64>,
        jac: &mut nalgebra::DMatrix<f64>,
    ) -> Option<Vec<f64>> {
        if self.prev.len() != 6 {
            return None;
        }
        let q = self.prev.clone();
        self.fk.flange_jacobian(&q, jac);
        let rhs = nalgebra::DVector::from_column_slice(&[v.x, v.y, v.z, 0.0, 0.0, 0.0]);
        match jac.clone().lu().solve(&rhs) {
            Some(x) if x.iter().all(|y| y.is_finite()) => Some(x.iter().copied().collect()),
            _ => None,
        }
    }
}

/// Which joint limit a plan could not keep.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum JointQuantity {
    /// Speed (rad/s).
    Speed,
    /// Acceleration (rad/s²).
    Acceleration,
}

impl std::fmt::Display for JointQuantity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            JointQuantity::Speed => "speed",
            JointQuantity::Acceleration => "acceleration",
        })
    }
}

#[cfg(test)]
mod shown_tests {
    /// Three decimals, more only where three print a speed over its limit as the limit.
    #[test]
    fn a_speed_just_over_its_limit_shows_the_digits_that_differ() {
        assert_eq!(super::shown(2.2, 2.175), ("2.200".into(), "2.175".into()));
        assert_eq!(
            super::shown(2.17531, 2.175),
            ("2.1753".into(), "2.1750".into())
        );
    }
}
