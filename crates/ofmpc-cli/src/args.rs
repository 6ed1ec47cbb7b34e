//! Argument groups that several commands share (clap, flattened into the commands' arguments
//! in `cli.rs`): which robot, its chain and tool, the robot-and-program setup and the tuning
//! of `analyze stability` and `tune`, and the output format. A leaf: it names no command.

use clap::Args;
use ofmpc::control::{MpcSettings, Weight};
use std::io::IsTerminal;
use std::path::PathBuf;

/// Which robot: built in by name, or a URDF file, with drives and payload.
#[derive(Debug, Args, Clone)]
pub struct RobotArgs {
    /// `irb140` (built in, with its drives) or the path of a .urdf file.
    #[arg(long, default_value = "irb140")]
    pub robot: String,
    /// Drives file (TOML: armature, torque and speed limits per joint). The
    /// built-in IRB 140 has its own; a URDF has none by default.
    #[arg(long)]
    pub drives: Option<PathBuf>,
    /// Tip, tool centre point and start pose.
    #[command(flatten)]
    pub chain: ChainArgs,
}

/// The robot's chain and tool (as the scenario's `[robot] tip`, `tcp_mm`, `tcp_rpy_deg`,
/// `start_q`).
#[derive(Debug, Args, Clone, Default)]
pub struct ChainArgs {
    /// The URDF link that ends the chain (the flange); joints beyond it or on other
    /// branches are held rigid (e.g. --tip panda_hand for a Panda with fingers). Default:
    /// the one path of moving joints, ending at tool0, flange or an end-effector link.
    #[arg(long)]
    pub tip: Option<String>,
    /// Tool centre point X,Y,Z in mm, in the tip's frame: planning, IK, metrics and
    /// figures use it. Default: the tip itself.
    #[arg(long, allow_hyphen_values = true)]
    pub tcp: Option<String>,
    /// Orientation of the tool centre point relative to the tip: roll,pitch,yaw in degrees
    /// (R = Rz·Ry·Rx).
    #[arg(long = "tcp-rpy", allow_hyphen_values = true)]
    pub tcp_rpy: Option<String>,
    /// Start pose, one value per joint, comma-separated (rad; m for a prismatic joint):
    /// the robot's initial state and the IK's first seed. Default: q = 0 where that is
    /// inside the limits, else the limits' centre.
    #[arg(long = "start-q", allow_hyphen_values = true)]
    pub start_q: Option<String>,
}

/// How `analyze stability` and `tune` print their result: JSON for scripts (the default when
/// stdout is not a terminal: a pipe or a file), a summary in words for a person (the default
/// on a terminal).
#[derive(Debug, Args, Clone)]
pub struct FormatArgs {
    /// Print the result as JSON (the default when stdout is not a terminal).
    #[arg(long, conflicts_with = "words")]
    pub json: bool,
    /// Print a summary in words (the default when stdout is a terminal).
    #[arg(long)]
    pub words: bool,
}

impl FormatArgs {
    /// Whether to print JSON.
    pub fn json(&self) -> bool {
        self.json || (!self.words && !std::io::stdout().is_terminal())
    }
}

/// Robot, program and tuning options shared by `analyze stability` and `tune`.
#[derive(Debug, Args, Clone)]
pub struct SetupArgs {
    /// `irb140` (built in, with its drives) or the path of a .urdf file.
    #[arg(long, default_value = "irb140")]
    pub robot: String,
    /// Drives file for a URDF robot.
    #[arg(long)]
    pub drives: Option<PathBuf>,
    /// G-code program (default: the paper's Table I, built in).
    #[arg(long)]
    pub program: Option<PathBuf>,
    /// G54 work offset X,Y,Z in mm, for programs that set none.
    #[arg(long, allow_hyphen_values = true)]
    pub origin: Option<String>,
    /// Constant tool orientation as roll,pitch,yaw in degrees (base frame, R = Rz·Ry·Rx),
    /// as `trajectory --rpy` and `[orientation] rpy_deg`; default: the orientation at the
    /// start pose.
    #[arg(long, allow_hyphen_values = true)]
    pub rpy: Option<String>,
    /// Tip, tool centre point and start pose (as `[robot] tip`, `tcp_mm`, `tcp_rpy_deg`,
    /// `start_q`).
    #[command(flatten)]
    pub chain: ChainArgs,
}

/// Tuning options, as in `[mpc]` (default: the paper's).
#[derive(Debug, Args, Clone)]
pub struct TuningArgs {
    /// Sampling period Ts (s).
    #[arg(long)]
    pub ts: Option<f64>,
    /// Prediction horizon N (samples).
    #[arg(long)]
    pub horizon: Option<usize>,
    /// Output-error weight Q_yw (scalar, times I).
    #[arg(long)]
    pub q_yw: Option<f64>,
    /// Output-increment weight Q_Δy (scalar, times I).
    #[arg(long)]
    pub q_dy: Option<f64>,
    /// Input-increment weight Q_Δu (scalar, times I).
    #[arg(long)]
    pub q_du: Option<f64>,
    /// Input weight Q_u of the usual MPC (scalar, times I).
    #[arg(long)]
    pub q_u: Option<f64>,
    /// The payload the controllers' model assumes (kg, point mass at the flange).
    #[arg(long)]
    pub model_payload_kg: Option<f64>,
}

impl TuningArgs {
    /// The paper's tuning with these options applied.
    pub fn settings(&self) -> MpcSettings {
        let mut s = MpcSettings::default();
        if let Some(v) = self.ts {
            s.ts = v;
        }
        if let Some(v) = self.horizon {
            s.horizon = v;
        }
        for (w, v) in [
            (&mut s.q_yw, self.q_yw),
            (&mut s.q_dy, self.q_dy),
            (&mut s.q_du, self.q_du),
            (&mut s.q_u, self.q_u),
        ] {
            if let Some(v) = v {
                *w = Weight::Scalar(v);
            }
        }
        if let Some(v) = self.model_payload_kg {
            s.model_payload_kg = v;
        }
        s
    }
}
