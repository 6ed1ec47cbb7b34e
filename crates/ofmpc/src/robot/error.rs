//! Errors of the robot description and of the vectors given to it: typed,
//! each with the offending names and values.

use thiserror::Error;

/// Why a drives file cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DrivesError {
    /// Not TOML, or a value of the wrong type (the message has line and column).
    #[error("{0}")]
    Syntax(String),
    /// A table or key the format does not have (a typo?).
    #[error("unknown {what} '{key}'{}: expected {expected}", joint.as_ref().map(|j| format!(" in [joints.{j}]")).unwrap_or_default())]
    UnknownKey {
        /// `"table"` or `"key"`.
        what: &'static str,
        /// The key as written.
        key: String,
        /// The joint's table it is in, if any.
        joint: Option<String>,
        /// The keys that exist there.
        expected: &'static str,
    },
    /// A value is out of its range.
    #[error("[joints.{joint}] {key} = {value}: must be a finite number {requirement}")]
    Value {
        /// The joint.
        joint: String,
        /// The key.
        key: &'static str,
        /// The value.
        value: f64,
        /// `"≥ 0"` or `"> 0"`.
        requirement: &'static str,
    },
    /// The file sets nothing.
    #[error("the drives file sets no joint: add a [joints.<joint name>] table per joint (armature_kgm2, max_torque_nm, max_speed_rad_s)")]
    Empty,
    /// A joint table names no moving joint of the robot.
    #[error("joint '{name}' of the drives file is not a moving joint of the robot (its joints: {joints})")]
    UnknownJoint {
        /// The name in the file.
        name: String,
        /// The robot's moving joints, comma-separated.
        joints: String,
    },
}

/// What is wrong with an inertia tensor about a centre of mass.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
#[non_exhaustive]
pub enum InertiaError {
    /// `I ≠ Iᵀ` beyond round-off.
    #[error("the inertia tensor is not symmetric (asymmetry {0:e})")]
    NotSymmetric(f64),
    /// A principal moment is negative.
    #[error("the inertia tensor has a negative principal moment ({0:?})")]
    NegativeMoment([f64; 3]),
    /// The principal moments violate `a + b ≥ c`.
    #[error("the principal moments {0:?} violate the triangle inequality")]
    Triangle([f64; 3]),
    /// The principal moments violate `a + b ≥ c` by more than the accepted tolerance.
    #[error("the principal moments {moments:?} violate the triangle inequality a + b ≥ c by {:.2} % of c, beyond the accepted {:.0} %: correct the <inertia> (e.g. recompute it from the link's mesh)", excess * 100.0, tolerance * 100.0)]
    TriangleBeyond {
        /// Principal moments (kg·m²).
        moments: [f64; 3],
        /// Relative excess `(c − a − b)/c`.
        excess: f64,
        /// The accepted excess.
        tolerance: f64,
    },
}

/// Why a payload is not a physical rigid body for this robot.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
#[non_exhaustive]
pub enum PayloadError {
    /// Mass, centre of mass or inertia not finite.
    #[error("mass {mass} kg, centre of mass {com:?} m: every value must be finite")]
    NotFinite {
        /// Mass (kg).
        mass: f64,
        /// Centre of mass (m).
        com: [f64; 3],
    },
    /// A negative mass.
    #[error("mass {0} kg: a payload's mass must be ≥ 0")]
    NegativeMass(f64),
    /// The inertia tensor is not physical.
    #[error("payload of {mass} kg: {error}")]
    Inertia {
        /// Mass (kg).
        mass: f64,
        /// What is wrong.
        error: InertiaError,
    },
    /// So heavy against the robot that its dynamics lose all precision.
    #[error("mass {mass} kg is more than {factor} times the robot's own moving mass ({robot_kg:.3} kg): its dynamics would be dominated by round-off; check the payload's unit (kg)")]
    TooHeavy {
        /// Mass (kg).
        mass: f64,
        /// The robot's moving mass without payload (kg).
        robot_kg: f64,
        /// The accepted ratio.
        factor: f64,
    },
}

/// What is wrong with a URDF's structure or values (XML syntax errors are
/// [`ModelError::Urdf`]).
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum UrdfError {
    /// A joint names a link that is not defined.
    #[error("link '{0}' is used by a joint but not defined: add a <link name=\"{0}\"/>")]
    UndefinedLink(String),
    /// A link is defined twice.
    #[error("link '{0}' is defined twice")]
    DuplicateLink(String),
    /// A link's `<inertial>` has a negative or non-finite value.
    #[error("link '{link}': <inertial> must have a finite mass ≥ 0 (got {mass}) and finite origin and inertia")]
    BadInertial {
        /// The link.
        link: String,
        /// Its mass.
        mass: f64,
    },
    /// A link's inertia tensor is not physical.
    #[error("link '{link}': {error}")]
    LinkInertia {
        /// The link.
        link: String,
        /// What is wrong.
        error: InertiaError,
    },
    /// A moving link without mass and inertia.
    #[error("link '{link}' (moved by joint '{joint}') has no inertial: add an <inertial> with mass, origin and inertia")]
    NoInertial {
        /// The link.
        link: String,
        /// Its joint.
        joint: String,
    },
    /// Two moving joints leave one link.
    #[error("not a serial chain: link '{link}' branches into moving joints {joints:?}; only one path of moving joints is supported (fixed side branches are fine): choose the chain's tip link (the flange, e.g. tool0 or a hand) to hold the other branches rigid")]
    NotSerial {
        /// The link.
        link: String,
        /// The moving joints below it.
        joints: Vec<String>,
    },
    /// A joint's `<origin>` is not finite.
    #[error("joint '{0}': <origin> must be finite")]
    BadOrigin(String),
    /// A joint type other than revolute, continuous, prismatic, fixed.
    #[error("joint '{joint}' is of type {kind}: only revolute, continuous, prismatic and fixed joints are supported")]
    UnsupportedJointType {
        /// The joint.
        joint: String,
        /// Its type as parsed.
        kind: String,
    },
    /// A zero or non-finite axis.
    #[error("joint '{0}': <axis xyz> must be a non-zero finite vector")]
    BadAxis(String),
    /// `lower > upper` (or NaN).
    #[error("joint '{joint}': limit lower = {lower} > upper = {upper}: swap them")]
    LimitOrder {
        /// The joint.
        joint: String,
        /// `lower`.
        lower: f64,
        /// `upper`.
        upper: f64,
    },
    /// A revolute or prismatic joint whose range is empty (`lower == upper`,
    /// also what a missing `<limit>` reads as).
    #[error("joint '{joint}' ({kind}) has the empty range lower = upper = {value}: the URDF specification requires <limit lower upper effort velocity> on revolute and prismatic joints; give its range, or make it a continuous or fixed joint")]
    EmptyRange {
        /// The joint.
        joint: String,
        /// `"revolute"` or `"prismatic"`.
        kind: &'static str,
        /// The value of both limits.
        value: f64,
    },
    /// A revolute or prismatic joint without a positive velocity or effort
    /// limit (a missing `<limit>` reads as 0).
    #[error("joint '{joint}' ({kind}): <limit> {attribute} = {value}: the URDF specification requires a positive {attribute} limit on revolute and prismatic joints")]
    MissingLimit {
        /// The joint.
        joint: String,
        /// `"revolute"` or `"prismatic"`.
        kind: &'static str,
        /// `"velocity"` or `"effort"`.
        attribute: &'static str,
        /// Its value.
        value: f64,
    },
    /// A negative velocity or effort limit on a continuous joint.
    #[error("joint '{joint}': <limit> {attribute} = {value} is negative")]
    NegativeLimit {
        /// The joint.
        joint: String,
        /// `"velocity"` or `"effort"`.
        attribute: &'static str,
        /// Its value.
        value: f64,
    },
    /// A `<mimic>` joint (coupled to another): not an independent joint.
    #[error("joint '{joint}' mimics joint '{of}': mimic joints are not supported (every moving joint is driven on its own); remove <mimic> or model the coupling as one joint")]
    Mimic {
        /// The joint.
        joint: String,
        /// The joint it follows.
        of: String,
    },
    /// A link is the child of two joints.
    #[error("link '{link}' is the child of two joints ('{first}' and '{second}'): a closed loop is not a serial chain")]
    TwoParents {
        /// The link.
        link: String,
        /// First joint.
        first: String,
        /// Second joint.
        second: String,
    },
    /// A joint connects links that are not defined.
    #[error(
        "joint '{joint}' connects '{parent}' to '{child}', but one of these links is not defined"
    )]
    DanglingJoint {
        /// The joint.
        joint: String,
        /// Its parent link.
        parent: String,
        /// Its child link.
        child: String,
    },
    /// Every link is a child.
    #[error("the URDF has no root link (every link is a child): remove the loop")]
    NoRoot,
    /// Several trees.
    #[error("the URDF has {} root links {roots:?}: connect them into one tree", roots.len())]
    ManyRoots {
        /// The root links.
        roots: Vec<String>,
    },
    /// Links not reachable from the root.
    #[error("{0} link(s) are not reachable from the root link (a loop?)")]
    Unreachable(usize),
    /// Nothing moves.
    #[error("the URDF has no revolute or prismatic joint: nothing to control")]
    NoMovingJoint,
    /// More moving joints in the chain than `MAX_JOINTS` (1000; the dynamics' n×n
    /// matrices would not fit in memory; no arm comes near).
    #[error(
        "the chain has {count} moving joints, more than the limit of {limit}: check that this \
         is a robot arm's URDF, or choose a nearer tip link"
    )]
    TooManyJoints {
        /// The moving joints found.
        count: usize,
        /// The limit.
        limit: usize,
    },
    /// The XML nests deeper than [`crate::input::MAX_XML_DEPTH`] elements.
    #[error(
        "line {line}, column {column}: elements nested more than {limit} deep (the limit; a URDF \
         needs about 3): check that this is a URDF"
    )]
    TooDeep {
        /// 1-based line of the element past the limit.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The limit.
        limit: usize,
    },
    /// The chosen tip is not a link of the URDF.
    #[error("tip link '{tip}' is not a link of the URDF; its links: {}", links.join(", "))]
    UnknownTip {
        /// The tip asked for.
        tip: String,
        /// The URDF's links, sorted.
        links: Vec<String>,
    },
    /// Moving links without `<inertial>`: the kinematics work, the dynamics do not.
    #[error("{}: the dynamics need the mass and inertia of every moving link; add to each <link> an <inertial> with <origin xyz rpy> (centre of mass), <mass value> (kg) and <inertia ixx ixy ixz iyy iyz izz> (kg·m², about the centre of mass) — planning a path works without", links.iter().zip(joints).map(|(l, j)| format!("link '{l}' (moved by joint '{j}') has no inertial")).collect::<Vec<_>>().join("; "))]
    NoInertials {
        /// The links without inertial.
        links: Vec<String>,
        /// The joints moving them.
        joints: Vec<String>,
    },
}

/// Something the URDF says that ofmpc does not model: it is ignored, and the
/// caller should say so.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum UrdfWarning {
    /// `<dynamics damping friction>`: the model has no joint friction (the
    /// plant's friction is a setting of the simulation).
    /// The message quotes the non-zero values only (a value the file leaves out reads as 0:
    /// a `friction="0"` the file does not have is never quoted).
    #[error("joint '{joint}': <dynamics{}{}> is ignored (the robot model has no joint friction; set the simulated plant's friction instead)",
        if *damping != 0.0 { format!(" damping=\"{damping}\"") } else { String::new() },
        if *friction != 0.0 { format!(" friction=\"{friction}\"") } else { String::new() })]
    IgnoredDynamics {
        /// The joint.
        joint: String,
        /// Damping (N·m·s/rad).
        damping: f64,
        /// Friction (N·m).
        friction: f64,
    },
    /// `<safety_controller>` soft limits: the hard `<limit>` is used.
    #[error("joint '{0}': <safety_controller> soft limits are ignored; the <limit> range is used")]
    IgnoredSafetyController(String),
    /// `effort="0"` or `velocity="0"`: ROS tools read it as "not given"; the limit is
    /// unknown (infinite) unless a drives file gives it.
    #[error("joint '{joint}': <limit {attribute}=\"0\"> read as not given (no {attribute} limit); give it in a drives file ({}) if a controller or the planner needs it", if *attribute == "effort" { "max_torque_nm" } else { "max_speed_rad_s" })]
    UnspecifiedLimit {
        /// The joint.
        joint: String,
        /// `"effort"` or `"velocity"`.
        attribute: &'static str,
    },
    /// A link's principal moments break the triangle inequality by at most
    /// `super::TRIANGLE_TOLERANCE`: accepted as given.
    #[error("link '{link}': the principal moments {moments:?} violate the triangle inequality a + b ≥ c by {:.3} % of c (accepted up to 1 %, as given)", excess * 100.0)]
    InertiaTriangle {
        /// The link.
        link: String,
        /// Principal moments (kg·m²).
        moments: [f64; 3],
        /// Relative excess `(c − a − b)/c`.
        excess: f64,
    },
    /// Moving links without `<inertial>`: the robot serves for kinematics only (planning);
    /// simulation and control need the inertials ([`super::Robot::require_inertials`]).
    #[error("link(s) {} have no <inertial>: the robot loads for kinematics (planning a path), not for dynamics (runs, stability analysis) until each gets one", links.join(", "))]
    NoInertial {
        /// The moving links without inertial.
        links: Vec<String>,
    },
}

/// What can be wrong with a robot description or with the vectors given to it.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum ModelError {
    /// A file could not be read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The operating system's message.
        message: String,
    },
    /// A file is larger than its limit ([`super::MAX_URDF_BYTES`],
    /// `super::MAX_DRIVES_BYTES`): reading stopped at the limit.
    #[error(
        "cannot read {path}: it is {} than the limit of {limit} bytes ({} MiB) for {what}; reading \
         stopped there: check that it is the file you meant",
        match size { Some(s) => format!("{s} bytes, larger"), None => "larger".to_string() },
        limit >> 20
    )]
    FileTooLarge {
        /// The file.
        path: String,
        /// What it was read as: `"a URDF"`, `"a drives file"`.
        what: &'static str,
        /// Its size (bytes), when the file system knows it (not for a device or a pipe).
        size: Option<u64>,
        /// The limit (bytes).
        limit: u64,
    },
    /// A file is not UTF-8 text.
    #[error(
        "cannot read {path}: not UTF-8 text: byte {offset} (line {line}, column {column}) is \
         0x{byte:02x} ({}): save it as UTF-8 (e.g. iconv -f {} -t UTF-8)",
        if *utf16 { "it looks like UTF-16" } else { "it may be Latin-1 or another 8-bit encoding" },
        if *utf16 { "UTF-16" } else { "LATIN1" }
    )]
    NotUtf8 {
        /// The file.
        path: String,
        /// 0-based offset of the first byte that is not UTF-8.
        offset: usize,
        /// Its 1-based line.
        line: usize,
        /// Its 1-based column (bytes).
        column: usize,
        /// The byte.
        byte: u8,
        /// The file starts with a UTF-16 byte-order mark.
        utf16: bool,
    },
    /// The URDF is not well-formed XML or lacks required elements.
    #[error("{file}invalid URDF: {message}")]
    Urdf {
        /// `"path: "` when known.
        file: String,
        /// The parser's message.
        message: String,
    },
    /// The URDF describes a structure or values this crate does not model.
    #[error("{file}{error}")]
    Structure {
        /// `"path: "` when known.
        file: String,
        /// What is wrong and what to do.
        error: UrdfError,
    },
    /// The drives file is malformed or does not fit the robot.
    #[error("{file}drives file: {error}")]
    Drives {
        /// `"path: "` when known.
        file: String,
        /// What is wrong.
        error: DrivesError,
    },
    /// The payload is not a physical rigid body.
    #[error("invalid payload: {0}")]
    InvalidPayload(#[from] PayloadError),
    /// No built-in robot of that name.
    #[error("unknown robot '{0}': use 'irb140' or the path of a .urdf file")]
    UnknownRobot(String),
    /// A vector has the wrong length.
    #[error("{what} has {got} values, the robot has {expected} joints: give one value per joint")]
    Dimension {
        /// Which vector.
        what: String,
        /// Number of joints.
        expected: usize,
        /// Number given.
        got: usize,
    },
    /// A vector holds NaN or infinity.
    #[error("{what}[{index}] (joint {}) is {value}: every value must be a finite number", index + 1)]
    NonFinite {
        /// Which vector.
        what: String,
        /// 0-based index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A joint value outside the joint's position limits.
    #[error("{what}[{index}] (joint {}, '{joint}') is {value}, outside its limits [{lower}, {upper}]: give a value within the limits", index + 1)]
    OutsideLimits {
        /// Which vector.
        what: String,
        /// 0-based index.
        index: usize,
        /// The joint's name.
        joint: String,
        /// The value.
        value: f64,
        /// Lower limit.
        lower: f64,
        /// Upper limit.
        upper: f64,
    },
    /// A tool centre point that is not a rigid transform.
    #[error("the tool centre point at {position:?} m is not a rigid transform within 10 m of the tip (finite position at most 10 m away, proper rotation): check its units")]
    InvalidTcp {
        /// Its position (m).
        position: [f64; 3],
    },
    /// A dynamics workspace built for another robot.
    #[error("the workspace was built for {workspace} joints but the robot has {robot}: build it with Workspace::new(&robot)")]
    WorkspaceMismatch {
        /// Joints of the workspace.
        workspace: usize,
        /// Joints of the robot.
        robot: usize,
    },
    /// The joint-space inertia matrix is not positive definite (Cholesky
    /// pivot ≤ 0 or not finite) at this state.
    #[error("the joint-space inertia matrix is not positive definite at joint {} (pivot {pivot:e}){}", joint + 1,
        if *with_payload { ": check the payload (mass, centre of mass, inertia) and the link inertials" } else { ": check the link inertials" })]
    NotPositiveDefinite {
        /// 0-based joint of the failing pivot.
        joint: usize,
        /// The pivot.
        pivot: f64,
        /// Whether a payload was attached.
        with_payload: bool,
    },
    /// A result that should be finite is not (inputs too large).
    #[error("{what} is not finite at this state ({what}[{index}] = {value}): the inputs are too large for the model")]
    NonFiniteResult {
        /// Which result (`"tau"`, `"H"`, ...).
        what: &'static str,
        /// 0-based index of the first bad entry.
        index: usize,
        /// The value.
        value: f64,
    },
}

impl ModelError {
    /// Names the file in URDF errors.
    pub(crate) fn in_file(self, path: &std::path::Path) -> Self {
        let file = format!("{}: ", path.display());
        match self {
            ModelError::Urdf { message, .. } => ModelError::Urdf { file, message },
            ModelError::Structure { error, .. } => ModelError::Structure { file, error },
            e => e,
        }
    }
}

impl From<UrdfError> for ModelError {
    fn from(error: UrdfError) -> Self {
        ModelError::Structure {
            file: String::new(),
            error,
        }
    }
}

impl From<DrivesError> for ModelError {
    fn from(error: DrivesError) -> Self {
        ModelError::Drives {
            file: String::new(),
            error,
        }
    }
}
