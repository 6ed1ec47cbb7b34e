//! Command-line arguments (clap). The commands live in `commands/`.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

/// Offset-free model predictive control of industrial robots.
#[derive(Debug, Parser)]
#[command(name = "ofmpc", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Print model quantities as JSON.
    #[command(subcommand)]
    Inspect(Inspect),
}

/// `ofmpc inspect ...`
#[derive(Debug, Subcommand)]
pub enum Inspect {
    /// H, C, g, inverse dynamics and the flange pose at a state, as JSON.
    Dynamics(InspectDynamics),
}

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
}

/// `ofmpc inspect dynamics`
#[derive(Debug, Args)]
pub struct InspectDynamics {
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Point mass at the flange centre (kg).
    #[arg(long, default_value_t = 0.0)]
    pub payload: f64,
    /// Joint positions, comma-separated (rad or m).
    #[arg(long, allow_hyphen_values = true)]
    pub q: String,
    /// Joint velocities, comma-separated (default zero).
    #[arg(long, allow_hyphen_values = true)]
    pub qd: Option<String>,
    /// Joint accelerations, comma-separated (default zero).
    #[arg(long, allow_hyphen_values = true)]
    pub qdd: Option<String>,
}
