//! URDF loading (via the `urdf-rs` crate) into a serial chain.
//!
//! Accepted: one tree rooted at a single link, whose moving joints (revolute,
//! continuous, prismatic) lie on one path from the root. Fixed joints are
//! folded: links attached through them add their inertia to the body they hang
//! on, and fixed frames between two moving joints go into the next joint's
//! placement. Side branches that hold only fixed joints are allowed (a camera
//! bracket, a tool); a second branch with a moving joint is not a serial chain.

use super::{check_inertia_tensor, Joint, JointKind, JointLimits, ModelError, Robot};
use crate::spatial::{Inertia, Transform};
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;

struct Walker<'a> {
    links: HashMap<&'a str, &'a urdf_rs::Link>,
    children: HashMap<&'a str, Vec<&'a urdf_rs::Joint>>,
    joints: Vec<Joint>,
    /// Named frames: link name → (body index or None for the fixed base, pose in that body).
    frames: HashMap<String, (Option<usize>, Transform)>,
    /// The last link on the moving path, and its pose in the last body.
    last_link: Option<(String, Transform)>,
}

fn origin(p: &urdf_rs::Pose) -> Transform {
    Transform::from_xyz_rpy(*p.xyz, *p.rpy)
}

fn finite3(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

impl<'a> Walker<'a> {
    fn has_moving(&self, link: &str) -> bool {
        self.children.get(link).is_some_and(|js| {
            js.iter().any(|j| {
                j.joint_type != urdf_rs::JointType::Fixed || self.has_moving(&j.child.link)
            })
        })
    }

    fn link_inertia(&self, name: &str) -> Result<Inertia, ModelError> {
        let link = self.links.get(name).ok_or_else(|| {
            ModelError::structure(format!(
                "link '{name}' is used by a joint but not defined: add a <link name=\"{name}\"/>"
            ))
        })?;
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
            return Err(ModelError::structure(format!(
                "link '{name}': <inertial> must have a finite mass ≥ 0 (got {m}) and finite origin and inertia"
            )));
        }
        check_inertia_tensor(&tensor)
            .map_err(|e| ModelError::structure(format!("link '{name}': {e}")))?;
        let frame = origin(&i.origin);
        let i_com = frame.rot * tensor * frame.rot.transpose();
        Ok(Inertia::from_com(m, frame.pos, i_com))
    }

    /// Visits `link`, which sits at `pose` in the frame of `body`.
    fn walk(
        &mut self,
        link: &'a str,
        pose: Transform,
        body: Option<usize>,
        depth: usize,
    ) -> Result<(), ModelError> {
        if depth > 10_000 {
            return Err(ModelError::structure(
                "the kinematic tree is too deep (a loop?)",
            ));
        }
        let inertia = self.link_inertia(link)?;
        if let Some(b) = body {
            let j = &mut self.joints[b];
            j.body = j.body + inertia.to_parent(&pose);
        }
        self.frames.insert(link.to_string(), (body, pose));
        let children: Vec<&'a urdf_rs::Joint> =
            self.children.get(link).cloned().unwrap_or_default();
        let moving: Vec<&&urdf_rs::Joint> = children
            .iter()
            .filter(|j| j.joint_type != urdf_rs::JointType::Fixed || self.has_moving(&j.child.link))
            .collect();
        if moving.len() > 1 {
            let names: Vec<&str> = moving.iter().map(|j| j.name.as_str()).collect();
            return Err(ModelError::structure(format!(
                "not a serial chain: link '{link}' branches into moving joints {names:?}; \
                 only one path of moving joints is supported (fixed side branches are fine)"
            )));
        }
        let main = moving.first().map(|j| j.name.clone());
        if main.is_none() {
            // End of the moving path, or a fixed side branch.
            if body.is_some() && body == self.joints.len().checked_sub(1) {
                self.last_link = Some((link.to_string(), pose));
            }
        }
        for j in &children {
            if Some(&j.name) == main.as_ref() {
                continue;
            }
            self.visit_joint(j, pose, body, depth)?;
        }
        if let Some(name) = main {
            let j = children.iter().find(|j| j.name == name).copied();
            if let Some(j) = j {
                self.visit_joint(j, pose, body, depth)?;
            }
        }
        Ok(())
    }

    fn visit_joint(
        &mut self,
        j: &'a urdf_rs::Joint,
        pose: Transform,
        body: Option<usize>,
        depth: usize,
    ) -> Result<(), ModelError> {
        if !finite3(&j.origin.xyz) || !finite3(&j.origin.rpy) {
            return Err(ModelError::structure(format!(
                "joint '{}': <origin> must be finite",
                j.name
            )));
        }
        let placement = pose.compose(&origin(&j.origin));
        let kind = match j.joint_type {
            urdf_rs::JointType::Fixed => return self.walk(&j.child.link, placement, body, depth + 1),
            urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => JointKind::Revolute,
            urdf_rs::JointType::Prismatic => JointKind::Prismatic,
            ref other => {
                return Err(ModelError::structure(format!(
                    "joint '{}' is of type {other:?}: only revolute, continuous, prismatic and fixed joints are supported",
                    j.name
                )))
            }
        };
        let axis = Vector3::from(*j.axis.xyz);
        let norm = axis.norm();
        if !norm.is_finite() || norm < 1e-9 {
            return Err(ModelError::structure(format!(
                "joint '{}': <axis xyz> must be a non-zero finite vector",
                j.name
            )));
        }
        let l = &j.limit;
        let positive_or_inf = |v: f64| {
            if v.is_finite() && v > 0.0 {
                v
            } else {
                f64::INFINITY
            }
        };
        let (lower, upper) = if j.joint_type == urdf_rs::JointType::Continuous || l.lower == l.upper
        {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (l.lower, l.upper)
        };
        if lower.is_nan() || upper.is_nan() || lower > upper {
            return Err(ModelError::structure(format!(
                "joint '{}': limit lower = {} > upper = {}: swap them",
                j.name, l.lower, l.upper
            )));
        }
        let limits = JointLimits {
            lower,
            upper,
            velocity: positive_or_inf(l.velocity),
            effort: positive_or_inf(l.effort),
            acceleration: f64::INFINITY,
        };
        self.joints.push(Joint {
            name: j.name.clone(),
            link: j.child.link.clone(),
            kind,
            placement,
            axis: axis / norm,
            body: Inertia::zero(),
            limits,
            armature: 0.0,
        });
        let b = self.joints.len() - 1;
        self.walk(&j.child.link, Transform::identity(), Some(b), depth + 1)
    }
}

/// Parses a URDF text into a [`Robot`].
pub(super) fn parse(text: &str) -> Result<Robot, ModelError> {
    let urdf = urdf_rs::read_from_string(text).map_err(|e| ModelError::Urdf {
        file: String::new(),
        message: e.to_string(),
    })?;
    let mut links = HashMap::new();
    for l in &urdf.links {
        if links.insert(l.name.as_str(), l).is_some() {
            return Err(ModelError::structure(format!(
                "link '{}' is defined twice",
                l.name
            )));
        }
    }
    let mut children: HashMap<&str, Vec<&urdf_rs::Joint>> = HashMap::new();
    let mut parent_of: HashMap<&str, &str> = HashMap::new();
    for j in &urdf.joints {
        if let Some(prev) = parent_of.insert(j.child.link.as_str(), j.name.as_str()) {
            return Err(ModelError::structure(format!(
                "link '{}' is the child of two joints ('{prev}' and '{}'): a closed loop is not a serial chain",
                j.child.link, j.name
            )));
        }
        if !links.contains_key(j.parent.link.as_str()) || !links.contains_key(j.child.link.as_str())
        {
            return Err(ModelError::structure(format!(
                "joint '{}' connects '{}' to '{}', but one of these links is not defined",
                j.name, j.parent.link, j.child.link
            )));
        }
        children.entry(j.parent.link.as_str()).or_default().push(j);
    }
    let roots: Vec<&str> = urdf
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|n| !parent_of.contains_key(n))
        .collect();
    let root = match roots.as_slice() {
        [r] => *r,
        [] => {
            return Err(ModelError::structure(
                "the URDF has no root link (every link is a child): remove the loop",
            ))
        }
        many => {
            return Err(ModelError::structure(format!(
                "the URDF has {} root links {many:?}: connect them into one tree",
                many.len()
            )))
        }
    };
    let mut w = Walker {
        links,
        children,
        joints: Vec::new(),
        frames: HashMap::new(),
        last_link: None,
    };
    w.walk(root, Transform::identity(), None, 0)?;
    if w.frames.len() != urdf.links.len() {
        return Err(ModelError::structure(
            "some links are not reachable from the root link (a loop?)",
        ));
    }
    if w.joints.is_empty() {
        return Err(ModelError::structure(
            "the URDF has no revolute or prismatic joint: nothing to control",
        ));
    }
    let n = w.joints.len();
    for j in &w.joints {
        if j.body.mass <= 0.0 && j.body.i_o.abs().max() <= 0.0 {
            return Err(ModelError::structure(format!(
                "link '{}' (moved by joint '{}') has no inertial: add an <inertial> with mass, origin and inertia",
                j.link, j.name
            )));
        }
    }
    let named = ["tool0", "flange"]
        .iter()
        .find_map(|name| match w.frames.get(*name) {
            Some((Some(b), pose)) if *b == n - 1 => Some((name.to_string(), *pose)),
            _ => None,
        });
    let (flange_name, flange) = match named.or(w.last_link.clone()) {
        Some(f) => f,
        None => (w.joints[n - 1].link.clone(), Transform::identity()),
    };
    let name = if urdf.name.is_empty() {
        "robot".to_string()
    } else {
        urdf.name.clone()
    };
    Ok(Robot::assemble(name, w.joints, flange, flange_name))
}
