//! Robot description: a serial chain of revolute and prismatic joints with
//! limits, inertials, drives (armature) and an optional payload at the flange.
//!
//! [`Robot`] holds constants only (Pinocchio's `Model`); the algorithms in
//! [`crate::dynamics`] write into a [`crate::dynamics::Workspace`] sized once
//! from it.

mod drives;
mod error;
mod joint;
mod links;
mod perturb;
mod read;
mod urdf;
mod urdf_locate;

pub use drives::{DriveData, Drives};
pub use error::DrivesError;
pub use error::{InertiaError, ModelError, PayloadError, UrdfError, UrdfWarning};
pub use joint::{Joint, JointKind, JointLimits};
pub use links::LinkFrame;
pub use perturb::LinkInertiaError;
pub(crate) use perturb::MAX_INERTIA_ERROR;
#[doc(hidden)]
pub use read::MAX_URDF_BYTES;

use crate::ik::{OpwParameters, UrKinematics};
use crate::spatial::{Inertia, Transform};
use joint::check_inertia_tensor;
use nalgebra::{Matrix3, Vector3};

/// The built-in ABB IRB 140 URDF (copied from `shared/robots/irb140`; every
/// number and its source: `robots/irb140/PARAMETERS.md` in this crate).
pub const IRB140_URDF: &str = include_str!("../../robots/irb140/irb140.urdf");
/// The built-in IRB 140 drive data: armature, torque and speed limits.
#[doc(hidden)]
pub const IRB140_DRIVES: &str = include_str!("../../robots/irb140/drives.toml");

/// Standard gravity (m/s²).
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// A rigid payload attached at the flange: mass, centre of mass and inertia
/// about the centre of mass, both in flange coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Payload {
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the flange frame (m).
    pub com: Vector3<f64>,
    /// Inertia tensor about the centre of mass, flange axes (kg·m²).
    pub inertia: Matrix3<f64>,
}

impl Payload {
    /// A point mass at the centre of the flange (the paper's 0.25 kg load).
    pub fn point_mass(mass: f64) -> Self {
        Self {
            mass,
            com: Vector3::zeros(),
            inertia: Matrix3::zeros(),
        }
    }
    /// Checks the payload is physical: finite, mass ≥ 0, inertia symmetric
    /// positive semi-definite and satisfying the triangle inequalities.
    pub fn validate(&self) -> Result<(), PayloadError> {
        let finite = self.mass.is_finite()
            && self.com.iter().all(|v| v.is_finite())
            && self.inertia.iter().all(|v| v.is_finite());
        if !finite {
            return Err(PayloadError::NotFinite {
                mass: self.mass,
                com: [self.com.x, self.com.y, self.com.z],
            });
        }
        if self.mass < 0.0 {
            return Err(PayloadError::NegativeMass(self.mass));
        }
        check_inertia_tensor(&self.inertia).map_err(|error| PayloadError::Inertia {
            mass: self.mass,
            error,
        })
    }
}

/// A payload may weigh at most this many times the robot's own moving mass:
/// beyond, the joint-space inertia loses the robot's terms to round-off.
pub(crate) const MAX_PAYLOAD_RATIO: f64 = 1e3;

/// The farthest a tool centre point may lie from the tip (m): past it, a unit error.
const MAX_TCP_DISTANCE_M: f64 = 10.0;

/// The default start pose: q = 0 where it lies inside every joint's limits, else the centre
/// of the limits (an infinite bound taken as 0 on its side, the result clamped into the limits).
fn default_start_q(joints: &[Joint]) -> Vec<f64> {
    let inside = joints
        .iter()
        .all(|j| j.limits.lower <= 0.0 && 0.0 <= j.limits.upper);
    if inside {
        return vec![0.0; joints.len()];
    }
    joints
        .iter()
        .map(|j| {
            let lo = if j.limits.lower.is_finite() {
                j.limits.lower
            } else {
                0.0
            };
            let hi = if j.limits.upper.is_finite() {
                j.limits.upper
            } else {
                0.0
            };
            (0.5 * (lo + hi)).max(j.limits.lower).min(j.limits.upper)
        })
        .collect()
}

/// A fixed-base serial robot: the constants every algorithm reads.
#[derive(Debug, Clone, PartialEq)]
pub struct Robot {
    name: String,
    joints: Vec<Joint>,
    /// Flange frame in the last body's frame.
    flange: Transform,
    flange_name: String,
    gravity: Vector3<f64>,
    payload: Option<Payload>,
    /// Inertia of each body in its joint frame, payload included on the last one.
    bodies: Vec<Inertia>,
    /// What the description said that is not modelled.
    warnings: Vec<UrdfWarning>,
    /// Closed-form (OPW) kinematic parameters, when the arm has them.
    opw: Option<OpwParameters>,
    /// The start pose (rad or m): the initial state of a run and the inverse kinematics'
    /// first seed ([`Robot::start_q`]).
    start_q: Vec<f64>,
    /// The tool centre point in the flange (tip) frame ([`Robot::tcp`]).
    tcp: Transform,
    /// Moving links without `<inertial>` and their joints ([`Robot::require_inertials`]).
    missing_inertials: Vec<(String, String)>,
    /// Every URDF link and the body it is attached to ([`Robot::link_frames`]).
    link_frames: Vec<LinkFrame>,
}

/// The joint axes of a six-joint chain at q = 0: unit directions, a point on each (base
/// frame), and the last body's frame ([`Robot::ur_kinematics`], [`Robot::detected_opw_parameters`]).
type ZeroPoseAxes = ([Vector3<f64>; 6], [Vector3<f64>; 6], Transform);

/// Which inverse kinematics the planner uses for a robot ([`Robot::ik_method`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum IkMethod {
    /// The closed form of ortho-parallel arms with a spherical wrist ([`OpwParameters`]).
    Opw,
    /// The closed form of the Universal Robots family: axes 2–4 parallel, axes 5 and 6
    /// intersecting (`UrKinematics`), detected from the joint axes.
    Ur,
    /// Multi-start damped least squares within the joint limits ([`crate::ik::RobustIk`]).
    Numeric,
}

impl IkMethod {
    /// A one-line description (e.g. for `inspect robot`).
    pub fn description(&self) -> &'static str {
        match self {
            IkMethod::Opw => "analytic: OPW closed form (ortho-parallel arm, spherical wrist; up to 8 branches)",
            IkMethod::Ur => "analytic: UR closed form (axes 2-4 parallel, axes 5 and 6 intersecting; up to 8 branches)",
            IkMethod::Numeric => "numeric: damped least squares within the joint limits, multi-start (start pose, limits' centre, Halton points), null-space posture for redundant arms",
        }
    }
}

/// How to cut a kinematic chain out of a URDF and where its tool is: the options of
/// [`Robot::from_urdf_str_with`] and [`Robot::from_urdf_file_with`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ChainOptions {
    /// The link that ends the chain (the flange): the chain runs from the root to it;
    /// moving joints not on that path are held rigid (at 0, or the limit nearest to it)
    /// and their links count as carried mass, so a branched tree (a hand with fingers)
    /// loads. `None`: the one path of moving joints, ending at a link named `tool0`,
    /// `flange` or like an end effector on the last body if there is one, else at the
    /// last link there.
    pub tip: Option<String>,
    /// The tool centre point in the tip's frame (`None`: the tip itself). See
    /// [`Robot::set_tcp`].
    pub tcp: Option<Transform>,
}

impl Robot {
    /// The built-in ABB IRB 140 with its drives (armature, torque and speed limits).
    pub fn irb140() -> Self {
        let mut r = Self::from_urdf_str(IRB140_URDF).expect("the built-in IRB 140 URDF is valid");
        let d = Drives::from_toml_str(IRB140_DRIVES)
            .expect("the built-in IRB 140 drives file is valid");
        r.apply_drives(&d)
            .expect("the built-in drives match the built-in URDF");
        r.opw = Some(OpwParameters::irb140());
        r
    }

    /// The arm's closed-form (OPW) kinematic parameters, if it has them: the motion planner
    /// then uses the analytic inverse kinematics, else the numeric one. The built-in IRB 140
    /// has them ([`OpwParameters::irb140`]); a robot loaded from a URDF has them when its
    /// kinematics are of that form ([`Robot::detected_opw_parameters`], e.g. the ABB
    /// IRB 140, 2400 and 6640 as ROS-Industrial ships them).
    pub fn opw_parameters(&self) -> Option<&OpwParameters> {
        self.opw.as_ref()
    }

    /// The inverse kinematics the planner uses for this robot: OPW when the robot has its
    /// parameters (declared, or detected from the URDF), else the UR closed form when the joint axes are of that family
    /// ([`Robot::ur_kinematics`]), else numeric.
    pub fn ik_method(&self) -> IkMethod {
        match self.opw {
            Some(_) if self.dof() == 6 => IkMethod::Opw,
            _ if self.ur_kinematics().is_some() => IkMethod::Ur,
            _ => IkMethod::Numeric,
        }
    }

    /// The closed-form kinematics of the Universal Robots family (`UrKinematics::detect`:
    /// six revolute joints, axes 2–4 parallel, axes 5 and 6 intersecting), from the joint
    /// axes at q = 0 and the tool centre point; `None` for any other arm.
    pub fn ur_kinematics(&self) -> Option<UrKinematics> {
        let (axes, points, frame) = self.zero_pose_axes()?;
        let tool = frame.compose(&self.tool_offset()).to_isometry();
        UrKinematics::detect(&axes, &points, &tool)
    }

    /// The joint axes of a six-revolute chain at q = 0 (directions and a point on each, base
    /// frame) and the last body's frame there; `None` for any other chain.
    fn zero_pose_axes(&self) -> Option<ZeroPoseAxes> {
        if self.dof() != 6 || self.joints.iter().any(|j| j.kind != JointKind::Revolute) {
            return None;
        }
        let mut frame = Transform::identity();
        let mut axes = [Vector3::zeros(); 6];
        let mut points = [Vector3::zeros(); 6];
        for (i, j) in self.joints.iter().enumerate() {
            frame = frame.compose(&j.placement);
            axes[i] = frame.rot * j.axis;
            points[i] = frame.pos;
        }
        Some((axes, points, frame))
    }

    /// The OPW parameters of the chain's flange ([`OpwParameters::detect`]: six revolute
    /// joints, an ortho-parallel arm with a spherical wrist, axis 1 the base z axis), from
    /// the joint axes at q = 0; `None` for any other arm. The tool centre point is not part
    /// of them: the planner solves for the flange and maps the TCP to it.
    pub fn detected_opw_parameters(&self) -> Option<OpwParameters> {
        let (axes, points, frame) = self.zero_pose_axes()?;
        let flange = frame.compose(&self.flange).to_isometry();
        OpwParameters::detect(&axes, &points, &flange)
    }

    /// Declares (or with `None`, removes) the arm's OPW parameters. They must reproduce the
    /// robot's forward kinematics (flange frame) exactly; the caller is responsible.
    pub fn set_opw_parameters(&mut self, opw: Option<OpwParameters>) {
        self.opw = opw;
    }

    /// A built-in robot by name (`irb140`).
    pub fn builtin(name: &str) -> Result<Self, ModelError> {
        match name.to_ascii_lowercase().as_str() {
            "irb140" | "irb-140" | "abb_irb140" => Ok(Self::irb140()),
            _ => Err(ModelError::UnknownRobot(name.to_string())),
        }
    }

    /// Loads a URDF text (see [`ModelError`] for what is rejected). No drives:
    /// armature zero, limits from the URDF.
    pub fn from_urdf_str(text: &str) -> Result<Self, ModelError> {
        Self::from_urdf_str_with(text, &ChainOptions::default())
    }

    /// Loads a URDF text with a chosen tip and tool centre point ([`ChainOptions`]).
    pub fn from_urdf_str_with(text: &str, options: &ChainOptions) -> Result<Self, ModelError> {
        let chain = urdf::parse(text, options.tip.as_deref())?;
        let mut robot = Self::assemble(chain.name, chain.joints, chain.flange, chain.flange_name);
        robot.warnings = chain.warnings;
        robot.missing_inertials = chain.missing_inertials;
        robot.link_frames = chain.link_frames;
        if let Some(t) = &options.tcp {
            robot.set_tcp(*t)?;
        }
        Ok(robot)
    }

    /// Loads a URDF file.
    pub fn from_urdf_file(path: &std::path::Path) -> Result<Self, ModelError> {
        Self::from_urdf_file_with(path, &ChainOptions::default())
    }

    /// Loads a URDF file with a chosen tip and tool centre point ([`ChainOptions`]).
    pub fn from_urdf_file_with(
        path: &std::path::Path,
        options: &ChainOptions,
    ) -> Result<Self, ModelError> {
        let text = read::read_text_limited(path, MAX_URDF_BYTES, "a URDF")?;
        Self::from_urdf_str_with(&text, options).map_err(|e| e.in_file(path))
    }

    /// The tool centre point (TCP) in the flange (tip) frame; the identity unless set.
    /// Forward kinematics, the Jacobian, the inverse kinematics, planning and the recorded
    /// Cartesian positions are those of the TCP; a payload stays given in the flange frame.
    pub fn tcp(&self) -> &Transform {
        &self.tcp
    }

    /// Sets the tool centre point in the flange frame (rotation proper, values finite, at
    /// most 10 m from the flange).
    pub fn set_tcp(&mut self, tcp: Transform) -> Result<(), ModelError> {
        let finite = tcp.pos.iter().chain(tcp.rot.iter()).all(|v| v.is_finite());
        // A tool centre point kilometres away is a unit error, not a tool (issue #36).
        let proper = finite
            && tcp.pos.norm() <= MAX_TCP_DISTANCE_M
            && (tcp.rot.transpose() * tcp.rot - nalgebra::Matrix3::identity())
                .abs()
                .max()
                < 1e-9
            && (tcp.rot.determinant() - 1.0).abs() < 1e-9;
        if !proper {
            return Err(ModelError::InvalidTcp {
                position: [tcp.pos.x, tcp.pos.y, tcp.pos.z],
            });
        }
        self.tcp = tcp;
        Ok(())
    }

    /// The robot with its TCP moved `length` (m) along the TCP's own z axis (the tool axis):
    /// the tip of a tool of that length held at the TCP, as G-code's tool length offset
    /// (`G43 H…`) means it (LinuxCNC: the programmed point is the tip, the controlled point
    /// lies the tool length back along the tool axis). `TCP' = TCP · Trans(0, 0, length)`;
    /// the orientation is unchanged.
    pub fn with_tool_length(&self, length: f64) -> Result<Robot, ModelError> {
        let mut r = self.clone();
        if length == 0.0 {
            return Ok(r);
        }
        let along = Transform {
            rot: Matrix3::identity(),
            pos: Vector3::new(0.0, 0.0, length),
        };
        r.set_tcp(self.tcp.compose(&along))?;
        Ok(r)
    }

    /// The flange with the TCP: pose of the TCP in the last body's frame.
    pub(crate) fn tool_offset(&self) -> Transform {
        self.flange.compose(&self.tcp)
    }

    /// Whether the TCP is the flange itself.
    pub(crate) fn tcp_is_identity(&self) -> bool {
        self.tcp == Transform::identity()
    }

    /// Ok when every moving link has mass or inertia; else the links without `<inertial>`
    /// and what to add ([`UrdfError::NoInertials`]). Simulation, control and stability
    /// analysis need them; kinematics and planning do not.
    pub fn require_inertials(&self) -> Result<(), ModelError> {
        if self.missing_inertials.is_empty() {
            return Ok(());
        }
        Err(UrdfError::NoInertials {
            links: self
                .missing_inertials
                .iter()
                .map(|(l, _)| l.clone())
                .collect(),
            joints: self
                .missing_inertials
                .iter()
                .map(|(_, j)| j.clone())
                .collect(),
        }
        .into())
    }

    pub(crate) fn assemble(
        name: String,
        joints: Vec<Joint>,
        flange: Transform,
        flange_name: String,
    ) -> Self {
        let bodies = joints.iter().map(|j| j.body).collect();
        let start_q = default_start_q(&joints);
        let mut robot = Self {
            name,
            joints,
            flange,
            flange_name,
            gravity: Vector3::new(0.0, 0.0, -STANDARD_GRAVITY),
            payload: None,
            bodies,
            warnings: Vec::new(),
            opw: None,
            start_q,
            tcp: Transform::identity(),
            missing_inertials: Vec::new(),
            link_frames: Vec::new(),
        };
        robot.opw = robot.detected_opw_parameters();
        robot
    }

    /// The start pose (rad for revolute joints, m for prismatic ones): the robot's initial
    /// state in a run and the first seed of the inverse kinematics. By default q = 0 where
    /// that is inside every joint's limits, else the limits' centre (a bound that is
    /// infinite counts as 0 on that side).
    pub fn start_q(&self) -> &[f64] {
        &self.start_q
    }

    /// Sets the start pose: one finite value per joint, each within its position limits.
    pub fn set_start_q(&mut self, q: &[f64]) -> Result<(), ModelError> {
        self.check_vector("start_q", q)?;
        for (i, (j, &v)) in self.joints.iter().zip(q).enumerate() {
            if v < j.limits.lower || v > j.limits.upper {
                return Err(ModelError::OutsideLimits {
                    what: "start_q".to_string(),
                    index: i,
                    joint: j.name.clone(),
                    value: v,
                    lower: j.limits.lower,
                    upper: j.limits.upper,
                });
            }
        }
        self.start_q = q.to_vec();
        Ok(())
    }

    /// Applies a drives file: armature and, where given, speed and torque limits
    /// (they replace the URDF's). Every joint named in the file must exist.
    /// Returns the names of the robot's moving joints the file sets nothing
    /// for (they keep the URDF's values and no armature): a caller should say so.
    pub fn apply_drives(&mut self, drives: &Drives) -> Result<Vec<String>, ModelError> {
        let names: Vec<String> = self.joints.iter().map(|j| j.name.clone()).collect();
        for (name, d) in &drives.joints {
            let j = self
                .joints
                .iter_mut()
                .find(|j| &j.name == name)
                .ok_or_else(|| DrivesError::UnknownJoint {
                    name: name.clone(),
                    joints: names.join(", "),
                })?;
            if let Some(a) = d.armature_kgm2 {
                j.armature = a;
            }
            if let Some(t) = d.max_torque_nm {
                j.limits.effort = t;
            }
            if let Some(v) = d.max_speed_rad_s {
                j.limits.velocity = v;
            }
            if let Some(v) = d.coulomb_nm {
                j.coulomb_nm = v;
            }
            if let Some(v) = d.viscous_nms {
                j.viscous_nms = v;
            }
            if let Some(a) = d.max_accel_rad_s2 {
                j.limits.acceleration = a;
            }
        }
        Ok(names
            .into_iter()
            .filter(|n| !drives.joints.contains_key(n))
            .collect())
    }

    /// Robot name (URDF `<robot name>`).
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Number of moving joints `n`.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }
    /// The moving joints, base to tip.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }
    /// Name of the flange frame (`tool0`, `flange` or the last link).
    pub fn flange_name(&self) -> &str {
        &self.flange_name
    }
    /// Every link of the URDF (document order) with the body it is rigidly attached to and
    /// its pose there: where the report draws the link's `<visual>` geometry.
    pub fn link_frames(&self) -> &[LinkFrame] {
        &self.link_frames
    }
    /// Pose of the flange frame in the last body's frame.
    pub fn flange_offset(&self) -> &Transform {
        &self.flange
    }
    /// Gravity acceleration in the base frame (default (0, 0, −9.80665) m/s²).
    pub fn gravity(&self) -> Vector3<f64> {
        self.gravity
    }
    /// Sets the gravity vector (base frame).
    pub fn set_gravity(&mut self, g: Vector3<f64>) {
        self.gravity = g;
    }
    /// The payload attached at the flange, if any.
    pub fn payload(&self) -> Option<&Payload> {
        self.payload.as_ref()
    }
    /// What the URDF said that the model ignores (say so to the user).
    pub fn warnings(&self) -> &[UrdfWarning] {
        &self.warnings
    }
    /// Attaches (or with `None`, removes) a payload at the flange. It must be
    /// physical ([`Payload::validate`]) and weigh at most
    /// `MAX_PAYLOAD_RATIO` (1000) times the robot's own moving mass.
    pub fn set_payload(&mut self, payload: Option<Payload>) -> Result<(), ModelError> {
        if let Some(p) = &payload {
            p.validate()?;
            let robot_kg: f64 = self.joints.iter().map(|j| j.body.mass).sum();
            if p.mass > MAX_PAYLOAD_RATIO * robot_kg {
                return Err(PayloadError::TooHeavy {
                    mass: p.mass,
                    robot_kg,
                    factor: MAX_PAYLOAD_RATIO,
                }
                .into());
            }
        }
        self.payload = payload;
        let last = self.joints.len() - 1;
        for (b, j) in self.bodies.iter_mut().zip(&self.joints) {
            *b = j.body;
        }
        if let Some(p) = &self.payload {
            let in_flange = Inertia::from_com(p.mass, p.com, p.inertia);
            self.bodies[last] = self.bodies[last] + in_flange.to_parent(&self.flange);
        }
        Ok(())
    }
    /// Inertia of body `i` in its joint frame, payload included.
    pub fn body_inertia(&self, i: usize) -> &Inertia {
        &self.bodies[i]
    }
    /// Armature of every joint.
    pub fn armature(&self) -> impl Iterator<Item = f64> + '_ {
        self.joints.iter().map(|j| j.armature)
    }
    /// Lower position limits.
    pub fn lower_limits(&self) -> Vec<f64> {
        self.joints.iter().map(|j| j.limits.lower).collect()
    }
    /// Upper position limits.
    pub fn upper_limits(&self) -> Vec<f64> {
        self.joints.iter().map(|j| j.limits.upper).collect()
    }
    /// Total moving mass (kg), payload included.
    pub fn moving_mass(&self) -> f64 {
        self.bodies.iter().map(|b| b.mass).sum()
    }

    /// Checks a joint vector: length `n` and finite values. `what` names it in
    /// the error ("q", "qd", ...).
    pub fn check_vector(&self, what: &str, v: &[f64]) -> Result<(), ModelError> {
        if v.len() != self.dof() {
            return Err(ModelError::Dimension {
                what: what.to_string(),
                expected: self.dof(),
                got: v.len(),
            });
        }
        if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(ModelError::NonFinite {
                what: what.to_string(),
                index: i,
                value: *x,
            });
        }
        Ok(())
    }
}
