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

use super::error::{UrdfError, UrdfWarning};
use super::{check_inertia_tensor, Joint, JointKind, JointLimits, ModelError, Robot};
use crate::spatial::{Inertia, Transform};
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;

fn origin(p: &urdf_rs::Pose) -> Transform {
    Transform::from_xyz_rpy(*p.xyz, *p.rpy)
}

fn finite3(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn link_inertia(link: &urdf_rs::Link) -> Result<Inertia, UrdfError> {
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
    check_inertia_tensor(&tensor).map_err(|error| UrdfError::LinkInertia {
        link: link.name.clone(),
        error,
    })?;
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
    let l = &j.limit;
    let (lower, upper, velocity, effort) = if limited {
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
        for (attribute, value) in [("velocity", l.velocity), ("effort", l.effort)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(UrdfError::MissingLimit {
                    joint: j.name.clone(),
                    kind: kind_name,
                    attribute,
                    value,
                });
            }
        }
        (l.lower, l.upper, l.velocity, l.effort)
    } else {
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
        (f64::NEG_INFINITY, f64::INFINITY, velocity, effort)
    };
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

/// Parses a URDF text into a [`Robot`].
pub(super) fn parse(text: &str) -> Result<Robot, ModelError> {
    let urdf = urdf_rs::read_from_string(text).map_err(|e| ModelError::Urdf {
        file: String::new(),
        message: e.to_string(),
    })?;
    let tree = Tree::new(&urdf)?;
    let root = tree.root()?;
    let has_moving = tree.moving_below(root)?;
    let Walk {
        joints,
        warnings,
        frames,
        last_link,
    } = tree.walk(root, &has_moving)?;
    if joints.is_empty() {
        return Err(UrdfError::NoMovingJoint.into());
    }
    let n = joints.len();
    for j in &joints {
        if j.body.mass <= 0.0 && j.body.i_o.abs().max() <= 0.0 {
            return Err(UrdfError::NoInertial {
                link: j.link.clone(),
                joint: j.name.clone(),
            }
            .into());
        }
    }
    let named = ["tool0", "flange"]
        .iter()
        .find_map(|name| match frames.get(*name) {
            Some((Some(b), pose)) if *b == n - 1 => Some((name.to_string(), *pose)),
            _ => None,
        });
    let (flange_name, flange) = match named.or(last_link) {
        Some(f) => f,
        None => (joints[n - 1].link.clone(), Transform::identity()),
    };
    let name = if urdf.name.is_empty() {
        "robot".to_string()
    } else {
        urdf.name.clone()
    };
    let mut robot = Robot::assemble(name, joints, flange, flange_name);
    robot.warnings = warnings;
    Ok(robot)
}

/// The link tree of a URDF: link indices by name, the child joints of each link and the
/// parent joint of each link (indices into `urdf.joints`).
struct Tree<'u> {
    urdf: &'u urdf_rs::Robot,
    links: HashMap<&'u str, usize>,
    children: Vec<Vec<usize>>,
    parent_of: Vec<Option<usize>>,
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
        Ok(Self {
            urdf,
            links,
            children,
            parent_of,
        })
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
                .any(|&ji| !is_fixed(&urdf.joints[ji]) || has_moving[self.child_link(ji)]);
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
            .filter(|&ji| !is_fixed(&urdf.joints[ji]) || has_moving[self.child_link(ji)])
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
            let inertia = link_inertia(link)?;
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
                let placement = pose.compose(&origin(&j.origin));
                if is_fixed(j) {
                    stack.push((self.child_link(ji), placement, body));
                } else {
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
