//! URDF loading (via the `urdf-rs` crate) into a serial chain.
//!
//! Accepted: one tree rooted at a single link, whose moving joints (revolute,
//! continuous, prismatic) lie on one path from the root. Fixed joints are
//! folded: links attached through them add their inertia to the body they hang
//! on, and fixed frames between two moving joints go into the next joint's
//! placement. Side branches that hold only fixed joints are allowed (a camera
//! bracket, a tool); a second branch with a moving joint is not a serial chain.
//!
//! As the URDF specification requires, revolute and prismatic joints must have
//! a `<limit>` with a non-empty range and positive `effort` and `velocity`;
//! continuous joints may omit them (unlimited). `<mimic>` is rejected;
//! `<dynamics>` and `<safety_controller>` are ignored with a [`UrdfWarning`].
//!
//! The walk over the tree is iterative and linear in the number of links
//! (a chain of thousands of fixed frames neither recurses nor rescans).

use super::error::{InertiaError, ModelError};
use super::error::{UrdfError, UrdfWarning};
use super::joint::{check_inertia_tensor, Joint, JointKind, JointLimits};
use super::links::LinkFrame;
use crate::spatial::{Inertia, Transform};
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;

fn origin(p: &urdf_rs::Pose) -> Transform {
    Transform::from_xyz_rpy(*p.xyz, *p.rpy)
}

fn finite3(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Largest relative excess `(c − a − b)/c` of the principal moments over the triangle
/// inequality that a URDF link may have: accepted with a [`UrdfWarning::InertiaTriangle`]
/// (CAD exports round; MuJoCo and Pinocchio load such files).
pub const TRIANGLE_TOLERANCE: f64 = 0.01;

/// The relative excess of principal moments over the triangle inequality: the largest
/// `(c − a − b)/c` over the three orderings (≤ 0 when it holds).
fn triangle_excess(m: &[f64; 3]) -> f64 {
    let [a, b, c] = *m;
    [(c, a + b), (b, a + c), (a, b + c)]
        .iter()
        .map(|&(big, sum)| if big > 0.0 { (big - sum) / big } else { 0.0 })
        .fold(f64::NEG_INFINITY, f64::max)
}

fn link_inertia(
    link: &urdf_rs::Link,
    warnings: &mut Vec<UrdfWarning>,
) -> Result<Inertia, UrdfError> {
    let i = &link.inertial;
    let m = i.mass.value;
    let t = &i.inertia;
    let tensor = Matrix3::new(
        t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
    );
    if !m.is_finite()
        || m < 0.0
        || tensor.iter().any(|v| !v.is_finite())
        || !finite3(&i.origin.xyz)
        || !finite3(&i.origin.rpy)
    {
        return Err(UrdfError::BadInertial {
            link: link.name.clone(),
            mass: m,
        });
    }
    match check_inertia_tensor(&tensor) {
        Ok(()) => {}
        Err(InertiaError::Triangle(moments)) if triangle_excess(&moments) <= TRIANGLE_TOLERANCE => {
            warnings.push(UrdfWarning::InertiaTriangle {
                link: link.name.clone(),
                moments,
                excess: triangle_excess(&moments),
            });
        }
        Err(InertiaError::Triangle(moments)) => {
            return Err(UrdfError::LinkInertia {
                link: link.name.clone(),
                error: InertiaError::TriangleBeyond {
                    moments,
                    excess: triangle_excess(&moments),
                    tolerance: TRIANGLE_TOLERANCE,
                },
            })
        }
        Err(error) => {
            return Err(UrdfError::LinkInertia {
                link: link.name.clone(),
                error,
            })
        }
    }
    let frame = origin(&i.origin);
    let i_com = frame.rot * tensor * frame.rot.transpose();
    Ok(Inertia::from_com(m, frame.pos, i_com))
}

fn is_fixed(j: &urdf_rs::Joint) -> bool {
    j.joint_type == urdf_rs::JointType::Fixed
}

/// The moving joint a URDF joint becomes, with its checks.
fn moving_joint(
    j: &urdf_rs::Joint,
    placement: Transform,
    warnings: &mut Vec<UrdfWarning>,
) -> Result<Joint, UrdfError> {
    let (kind, kind_name, limited) = match j.joint_type {
        urdf_rs::JointType::Revolute => (JointKind::Revolute, "revolute", true),
        urdf_rs::JointType::Continuous => (JointKind::Revolute, "continuous", false),
        urdf_rs::JointType::Prismatic => (JointKind::Prismatic, "prismatic", true),
        ref other => {
            return Err(UrdfError::UnsupportedJointType {
                joint: j.name.clone(),
                kind: format!("{other:?}").to_lowercase(),
            })
        }
    };
    if let Some(m) = &j.mimic {
        return Err(UrdfError::Mimic {
            joint: j.name.clone(),
            of: m.joint.clone(),
        });
    }
    let axis = Vector3::from(*j.axis.xyz);
    let norm = axis.norm();
    if !norm.is_finite() || norm < 1e-9 {
        return Err(UrdfError::BadAxis(j.name.clone()));
    }
    let (lower, upper, velocity, effort) = if limited {
        limited_range(j, kind_name, warnings)?
    } else {
        continuous_limits(j)?
    };
    warn_ignored(j, warnings);
    Ok(Joint {
        name: j.name.clone(),
        link: j.child.link.clone(),
        kind,
        placement,
        axis: axis / norm,
        body: Inertia::zero(),
        limits: JointLimits {
            lower,
            upper,
            velocity,
            effort,
            acceleration: f64::INFINITY,
        },
        armature: 0.0,
        coulomb_nm: 0.0,
        viscous_nms: 0.0,
    })
}

/// Warns of what a joint declares that the model ignores: damping and friction
/// (`<dynamics>`), a `<safety_controller>`.
fn warn_ignored(j: &urdf_rs::Joint, warnings: &mut Vec<UrdfWarning>) {
    if let Some(d) = &j.dynamics {
        if d.damping != 0.0 || d.friction != 0.0 {
            warnings.push(UrdfWarning::IgnoredDynamics {
                joint: j.name.clone(),
                damping: d.damping,
                friction: d.friction,
            });
        }
    }
    if j.safety_controller.is_some() {
        warnings.push(UrdfWarning::IgnoredSafetyController(j.name.clone()));
    }
}

/// The limits of a revolute or prismatic joint: an ordered, non-empty range, a positive
/// speed and effort (0 = not given: unlimited, with a warning).
fn limited_range(
    j: &urdf_rs::Joint,
    kind_name: &'static str,
    warnings: &mut Vec<UrdfWarning>,
) -> Result<(f64, f64, f64, f64), UrdfError> {
    let l = &j.limit;
    if l.lower.is_nan() || l.upper.is_nan() || l.lower > l.upper {
        return Err(UrdfError::LimitOrder {
            joint: j.name.clone(),
            lower: l.lower,
            upper: l.upper,
        });
    }
    if l.lower == l.upper {
        return Err(UrdfError::EmptyRange {
            joint: j.name.clone(),
            kind: kind_name,
            value: l.lower,
        });
    }
    // ROS tools read 0 as "not given" (ROS-Industrial's descriptions write effort="0"):
    // unlimited, with a warning; a negative or non-finite value is an error.
    let mut given = |attribute: &'static str, value: f64| {
        if value == 0.0 {
            warnings.push(UrdfWarning::UnspecifiedLimit {
                joint: j.name.clone(),
                attribute,
            });
            Ok(f64::INFINITY)
        } else if value.is_finite() && value > 0.0 {
            Ok(value)
        } else {
            Err(UrdfError::MissingLimit {
                joint: j.name.clone(),
                kind: kind_name,
                attribute,
                value,
            })
        }
    };
    let velocity = given("velocity", l.velocity)?;
    let effort = given("effort", l.effort)?;
    Ok((l.lower, l.upper, velocity, effort))
}

/// The limits of a continuous joint: no range; speed and effort optional (0 = not given).
fn continuous_limits(j: &urdf_rs::Joint) -> Result<(f64, f64, f64, f64), UrdfError> {
    let l = &j.limit;
    // Continuous: no range; velocity and effort optional (0 = not given).
    let optional = |attribute: &'static str, v: f64| {
        if v.is_nan() || v < 0.0 {
            Err(UrdfError::NegativeLimit {
                joint: j.name.clone(),
                attribute,
                value: v,
            })
        } else if v == 0.0 {
            Ok(f64::INFINITY)
        } else {
            Ok(v)
        }
    };
    let velocity = optional("velocity", l.velocity)?;
    let effort = optional("effort", l.effort)?;
    Ok((f64::NEG_INFINITY, f64::INFINITY, velocity, effort))
}

/// The most moving joints a robot read from a URDF may have: far above any arm (6 to 7, a
/// few dozen for a hand), far below what the dynamics' n×n matrices can hold in memory
/// (1000 joints: three 8 MB matrices; 20 000 would need 3.2 GB each).
pub(crate) const MAX_JOINTS: usize = 1000;

/// Link names that mark the end of an arm, in order of preference, for the default flange:
/// exact names first, then parts of names. A finger or other leaf is taken only when no
/// link on the last body is named like this.
const FLANGE_NAMES: [&str; 2] = ["tool0", "flange"];
const FLANGE_NAME_PARTS: [&str; 5] = ["end_effector", "tool0", "flange", "ee_link", "tcp"];

/// A kinematic chain read from a URDF: what the robot is assembled from.
pub(super) struct Chain {
    /// The robot's name (`robot` when the URDF has none).
    pub(super) name: String,
    /// The moving joints, base to tip.
    pub(super) joints: Vec<Joint>,
    /// The flange frame in the last body's frame.
    pub(super) flange: Transform,
    /// The flange link's name.
    pub(super) flange_name: String,
    /// What the description said that is not modelled.
    pub(super) warnings: Vec<UrdfWarning>,
    /// Moving links without `<inertial>` and their joints.
    pub(super) missing_inertials: Vec<(String, String)>,
    /// Every URDF link and the body it is attached to.
    pub(super) link_frames: Vec<LinkFrame>,
}

/// The URDF document of `text`, its nesting bounded and its errors located (line, element).
fn read(text: &str) -> Result<urdf_rs::Robot, ModelError> {
    // The XML reader recurses on nesting: bounded before it sees the text.
    let limit = crate::input::MAX_XML_DEPTH;
    if let Some((line, column)) = crate::input::xml_too_deep(text, limit) {
        return Err(UrdfError::TooDeep {
            line,
            column,
            limit,
        }
        .into());
    }
    let malformed = || {
        super::urdf_locate::malformed_vector(text).map(|place| ModelError::Urdf {
            file: String::new(),
            message: format!(
                "expected three numbers separated by spaces ({place}); write e.g. \
                 xyz=\"0 0 0.1\" (a decimal point, not a comma)"
            ),
        })
    };
    // The deserializer gives no position: a malformed xyz/rpy (four values, a comma) is
    // found in the text with its line and column; other errors get the element's line.
    let urdf = urdf_rs::read_from_string(text).map_err(|e| {
        malformed().unwrap_or_else(|| ModelError::Urdf {
            file: String::new(),
            message: super::urdf_locate::locate(text, &e.to_string()),
        })
    })?;
    if let Some(e) = malformed() {
        return Err(e);
    }
    Ok(urdf)
}

/// Parses a URDF text into a [`Chain`]: the chain from the root to `tip` (a link name),
/// or when `None` the one path of moving joints.
pub(super) fn parse(text: &str, tip: Option<&str>) -> Result<Chain, ModelError> {
    let urdf = read(text)?;
    let mut tree = Tree::new(&urdf)?;
    let root = tree.root()?;
    if let Some(t) = tip {
        tree.choose_tip(t)?;
    }
    let has_moving = tree.moving_below(root)?;
    let Walk {
        joints,
        mut warnings,
        frames,
        last_link,
    } = tree.walk(root, &has_moving)?;
    if joints.is_empty() {
        return Err(UrdfError::NoMovingJoint.into());
    }
    if joints.len() > MAX_JOINTS {
        return Err(UrdfError::TooManyJoints {
            count: joints.len(),
            limit: MAX_JOINTS,
        }
        .into());
    }
    let missing = missing_inertials(&joints, &mut warnings);
    let (flange_name, flange) = flange(tip, &frames, &joints, last_link);
    let name = if urdf.name.is_empty() {
        "robot".to_string()
    } else {
        urdf.name.clone()
    };
    let link_frames = urdf
        .links
        .iter()
        .filter_map(|l| {
            let (body, pose) = frames.get(l.name.as_str())?;
            Some(LinkFrame {
                name: l.name.clone(),
                body: *body,
                pose: *pose,
            })
        })
        .collect();
    Ok(Chain {
        name,
        joints,
        flange,
        flange_name,
        warnings,
        missing_inertials: missing,
        link_frames,
    })
}

/// The moving links without `<inertial>` and their joints, with a warning naming them.
fn missing_inertials(joints: &[Joint], warnings: &mut Vec<UrdfWarning>) -> Vec<(String, String)> {
    let missing: Vec<(String, String)> = joints
        .iter()
        .filter(|j| j.body.mass <= 0.0 && j.body.i_o.abs().max() <= 0.0)
        .map(|j| (j.link.clone(), j.name.clone()))
        .collect();
    if !missing.is_empty() {
        warnings.push(UrdfWarning::NoInertial {
            links: missing.iter().map(|(l, _)| l.clone()).collect(),
        });
    }
    missing
}

/// The flange of a chain of `joints`: the `tip` link when it lies on the last body, else,
/// with no tip given, a link on the last body named like a flange ([`FLANGE_NAMES`] first,
/// then [`FLANGE_NAME_PARTS`]), else the last link on the last body; failing all, the last
/// joint's link itself.
fn flange(
    tip: Option<&str>,
    frames: &HashMap<&str, (Option<usize>, Transform)>,
    joints: &[Joint],
    last_link: Option<(String, Transform)>,
) -> (String, Transform) {
    let n = joints.len();
    let on_last = |name: &str| matches!(frames.get(name), Some((Some(b), _)) if *b == n - 1);
    match tip {
        Some(t) => match frames.get(t) {
            Some((Some(b), pose)) if *b == n - 1 => (t.to_string(), *pose),
            _ => (joints[n - 1].link.clone(), Transform::identity()),
        },
        None => {
            let exact = FLANGE_NAMES
                .iter()
                .find(|name| on_last(name))
                .map(|s| s.to_string());
            let mut named: Vec<&str> = frames
                .keys()
                .copied()
                .filter(|name| {
                    let lower = name.to_ascii_lowercase();
                    on_last(name) && FLANGE_NAME_PARTS.iter().any(|p| lower.contains(p))
                })
                .collect();
            named.sort_by_key(|name| {
                let lower = name.to_ascii_lowercase();
                (
                    FLANGE_NAME_PARTS.iter().position(|p| lower.contains(p)),
                    name.to_string(),
                )
            });
            match exact.or(named.first().map(|s| s.to_string())) {
                Some(name) => (name.clone(), frames[name.as_str()].1),
                None => match last_link {
                    Some(f) => f,
                    None => (joints[n - 1].link.clone(), Transform::identity()),
                },
            }
        }
    }
}

/// The link tree of a URDF: link indices by name, the child joints of each link and the
/// parent joint of each link (indices into `urdf.joints`).
struct Tree<'u> {
    urdf: &'u urdf_rs::Robot,
    links: HashMap<&'u str, usize>,
    children: Vec<Vec<usize>>,
    parent_of: Vec<Option<usize>>,
    /// Per URDF joint: it is a moving joint of the chain (not fixed, and on the path to
    /// the tip when one is chosen). Other joints are rigid: a moving joint off the chain
    /// is held at 0 (or the limit nearest to it).
    moves: Vec<bool>,
}

/// What the walk down the tree ([`Tree::walk`]) collects.
struct Walk<'u> {
    /// The moving joints, base to tip, with the inertia of the bodies they carry.
    joints: Vec<Joint>,
    warnings: Vec<UrdfWarning>,
    /// Each link's body (None = base) and its pose in that body's frame.
    frames: HashMap<&'u str, (Option<usize>, Transform)>,
    /// The last link on the last body (the flange unless a `tool0`/`flange` link exists).
    last_link: Option<(String, Transform)>,
}

impl<'u> Tree<'u> {
    /// Indexes the links and joints. Errors: duplicate link names, joints naming unknown
    /// links, links with two parent joints.
    fn new(urdf: &'u urdf_rs::Robot) -> Result<Self, UrdfError> {
        let mut links: HashMap<&str, usize> = HashMap::new();
        for (i, l) in urdf.links.iter().enumerate() {
            if links.insert(l.name.as_str(), i).is_some() {
                return Err(UrdfError::DuplicateLink(l.name.clone()));
            }
        }
        // Children of each link (indices into urdf.joints), parent joint of each link.
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); urdf.links.len()];
        let mut parent_of: Vec<Option<usize>> = vec![None; urdf.links.len()];
        for (ji, j) in urdf.joints.iter().enumerate() {
            let (Some(&p), Some(&c)) = (
                links.get(j.parent.link.as_str()),
                links.get(j.child.link.as_str()),
            ) else {
                return Err(UrdfError::DanglingJoint {
                    joint: j.name.clone(),
                    parent: j.parent.link.clone(),
                    child: j.child.link.clone(),
                });
            };
            if let Some(prev) = parent_of[c] {
                return Err(UrdfError::TwoParents {
                    link: j.child.link.clone(),
                    first: urdf.joints[prev].name.clone(),
                    second: j.name.clone(),
                });
            }
            parent_of[c] = Some(ji);
            children[p].push(ji);
        }
        let moves = urdf.joints.iter().map(|j| !is_fixed(j)).collect();
        Ok(Self {
            urdf,
            links,
            children,
            parent_of,
            moves,
        })
    }

    /// Makes the chain end at link `tip`: only the moving joints on the path from the root
    /// to it stay moving; the others become rigid (held at 0 or the nearest limit).
    fn choose_tip(&mut self, tip: &str) -> Result<(), UrdfError> {
        let Some(&t) = self.links.get(tip) else {
            let mut names: Vec<String> = self.urdf.links.iter().map(|l| l.name.clone()).collect();
            names.sort();
            return Err(UrdfError::UnknownTip {
                tip: tip.to_string(),
                links: names,
            });
        };
        let mut on_path = vec![false; self.urdf.joints.len()];
        let mut l = t;
        let mut steps = 0;
        while let Some(ji) = self.parent_of[l] {
            on_path[ji] = true;
            l = self.links[self.urdf.joints[ji].parent.link.as_str()];
            steps += 1;
            if steps > self.urdf.joints.len() {
                break; // a loop: reported by moving_below
            }
        }
        for (m, on) in self.moves.iter_mut().zip(on_path) {
            *m = *m && on;
        }
        Ok(())
    }

    /// The joint `ji` moves in the chain.
    fn is_moving(&self, ji: usize) -> bool {
        self.moves[ji]
    }

    /// The origin of joint `ji` and, for a moving URDF joint held rigid off the chain, its
    /// motion at the held value (0, or the limit nearest to it).
    fn rigid_origin(&self, ji: usize) -> Transform {
        let j = &self.urdf.joints[ji];
        let o = origin(&j.origin);
        let axis = Vector3::from(*j.axis.xyz);
        let norm = axis.norm();
        if is_fixed(j) || !(norm.is_finite() && norm > 0.0) {
            return o;
        }
        let (lo, hi) = (j.limit.lower, j.limit.upper);
        let v = if lo <= hi && lo.is_finite() && hi.is_finite() {
            0.0f64.clamp(lo, hi)
        } else {
            0.0
        };
        if v == 0.0 {
            return o;
        }
        let axis = axis / norm;
        let motion = match j.joint_type {
            urdf_rs::JointType::Prismatic => Transform {
                rot: Matrix3::identity(),
                pos: axis * v,
            },
            _ => Transform {
                rot: crate::spatial::axis_angle(&axis, v),
                pos: Vector3::zeros(),
            },
        };
        o.compose(&motion)
    }

    /// The one link without a parent joint.
    fn root(&self) -> Result<usize, UrdfError> {
        let urdf = self.urdf;
        let roots: Vec<usize> = (0..urdf.links.len())
            .filter(|&l| self.parent_of[l].is_none())
            .collect();
        match roots.as_slice() {
            [r] => Ok(*r),
            [] => Err(UrdfError::NoRoot),
            many => Err(UrdfError::ManyRoots {
                roots: many.iter().map(|&l| urdf.links[l].name.clone()).collect(),
            }),
        }
    }

    /// Index of the child link of joint `ji`.
    fn child_link(&self, ji: usize) -> usize {
        self.links[self.urdf.joints[ji].child.link.as_str()]
    }

    /// `has_moving[l]`: a moving joint lies at or below one of link `l`'s child joints.
    /// Errors if some link is not reachable from `root` (a loop).
    fn moving_below(&self, root: usize) -> Result<Vec<bool>, UrdfError> {
        let urdf = self.urdf;
        // Pre-order from the root (iterative); links unreachable from it are in a loop.
        let mut order = Vec::with_capacity(urdf.links.len());
        let mut stack = vec![root];
        while let Some(l) = stack.pop() {
            order.push(l);
            stack.extend(self.children[l].iter().map(|&ji| self.child_link(ji)));
        }
        if order.len() != urdf.links.len() {
            return Err(UrdfError::Unreachable(urdf.links.len() - order.len()));
        }
        // Reverse pre-order visits children before parents: one linear pass.
        let mut has_moving = vec![false; urdf.links.len()];
        for &l in order.iter().rev() {
            has_moving[l] = self.children[l]
                .iter()
                .any(|&ji| self.is_moving(ji) || has_moving[self.child_link(ji)]);
        }
        Ok(has_moving)
    }

    /// The child joint of link `l` on the moving path, if any; an error if there are
    /// several (not a serial chain).
    fn moving_child(&self, l: usize, has_moving: &[bool]) -> Result<Option<usize>, UrdfError> {
        let urdf = self.urdf;
        let moving: Vec<usize> = self.children[l]
            .iter()
            .copied()
            .filter(|&ji| self.is_moving(ji) || has_moving[self.child_link(ji)])
            .collect();
        if moving.len() > 1 {
            return Err(UrdfError::NotSerial {
                link: urdf.links[l].name.clone(),
                joints: moving
                    .iter()
                    .map(|&ji| urdf.joints[ji].name.clone())
                    .collect(),
            });
        }
        Ok(moving.first().copied())
    }

    /// Walks the tree from `root`: each link sits at `pose` in the frame of body `body`
    /// (None = base). Fixed joints fold into the pose, moving ones start a new body.
    fn walk(&self, root: usize, has_moving: &[bool]) -> Result<Walk<'u>, UrdfError> {
        let urdf = self.urdf;
        let mut walk = Walk {
            joints: Vec::new(),
            warnings: Vec::new(),
            frames: HashMap::new(),
            last_link: None,
        };
        let mut stack: Vec<(usize, Transform, Option<usize>)> =
            vec![(root, Transform::identity(), None)];
        while let Some((l, pose, body)) = stack.pop() {
            let link = &urdf.links[l];
            let inertia = link_inertia(link, &mut walk.warnings)?;
            if let Some(b) = body {
                let j = &mut walk.joints[b];
                j.body = j.body + inertia.to_parent(&pose);
            }
            walk.frames.insert(link.name.as_str(), (body, pose));
            let main = self.moving_child(l, has_moving)?;
            if main.is_none() && body.is_some() && body == walk.joints.len().checked_sub(1) {
                // End of the moving path, or a fixed side branch of the last body.
                walk.last_link = Some((link.name.clone(), pose));
            }
            // The main child goes on the stack first: side branches (fixed only)
            // are finished before the chain goes on.
            // Side branches are pushed in reverse so that they are visited in
            // document order (the last leaf of the last body names the flange).
            for ji in main.into_iter().chain(
                self.children[l]
                    .iter()
                    .rev()
                    .copied()
                    .filter(|&ji| Some(ji) != main),
            ) {
                let j = &urdf.joints[ji];
                if !finite3(&j.origin.xyz) || !finite3(&j.origin.rpy) {
                    return Err(UrdfError::BadOrigin(j.name.clone()));
                }
                if !self.is_moving(ji) {
                    let placement = pose.compose(&self.rigid_origin(ji));
                    stack.push((self.child_link(ji), placement, body));
                } else {
                    let placement = pose.compose(&origin(&j.origin));
                    // One moving child per link: joints are numbered base to tip.
                    walk.joints
                        .push(moving_joint(j, placement, &mut walk.warnings)?);
                    stack.push((
                        self.child_link(ji),
                        Transform::identity(),
                        Some(walk.joints.len() - 1),
                    ));
                }
            }
        }
        Ok(walk)
    }
}
