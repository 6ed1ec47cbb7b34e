//! Command-line arguments (clap): every command's, with the groups they share in
//! `args.rs`. The commands live in `commands/`.

use crate::args::{ChainArgs, FormatArgs, RobotArgs, SetupArgs, TuningArgs};
use clap::{Args, Parser, Subcommand};
use ofmpc::motion::{PlanOptions, TimingOptions};
use ofmpc_scenario::{mode_name, profile_name};
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
    /// Plan a program: the timed path and its joint reference, as CSV and figures.
    Trajectory(TrajectoryArgs),
    /// Run a scenario file (TOML; see examples/scenario.toml).
    Run(RunArgs),
    /// Reproduce the paper's experiment (section IV): all three controllers,
    /// with and without a payload the model does not know.
    Reproduce(ReproduceArgs),
    /// Analyses that need no run: the stability margins of the controllers.
    #[command(subcommand)]
    Analyze(Analyze),
    /// Search the tuning that keeps the non-adaptive controllers stable over a
    /// payload range with the least RMS error; write it as a scenario file.
    Tune(TuneArgs),
    /// Starting files for your own robot: `init robot my.urdf` writes drives.toml and
    /// scenario.toml.
    #[command(subcommand)]
    Init(Init),
}

/// `ofmpc init ...`
#[derive(Debug, Subcommand)]
pub enum Init {
    /// A drives file (one table per moving joint, the URDF's limits filled in) and a scenario
    /// that runs the robot, in --out.
    Robot(InitRobotArgs),
}

/// `ofmpc analyze ...`
#[derive(Debug, Subcommand)]
pub enum Analyze {
    /// The range of the inertia ratio α = H_model/H_plant over which each
    /// controller is stable near rest, and the largest payload that keeps the
    /// ratio inside it along the program, as JSON; the spectral radius against
    /// α as a figure.
    Stability(StabilityArgs),
    /// Each controller over a grid of measurement delay × encoder quantization ×
    /// friction-estimate error × model (inertia) error × payload: where it holds (stable,
    /// steady error, RMS), as robustness.json, a figure and report.html, and a table.
    Robustness(RobustnessArgs),
}

/// `ofmpc trajectory`
#[derive(Debug, Args)]
pub struct TrajectoryArgs {
    /// G-code program file, or `paper` for the built-in Table I program.
    pub program: String,
    /// `irb140` (built in) or the path of a .urdf file.
    #[arg(long, default_value = "irb140")]
    pub robot: String,
    /// Drives file for a URDF robot.
    #[arg(long)]
    pub drives: Option<PathBuf>,
    /// Tip, tool centre point and start pose.
    #[command(flatten)]
    pub chain: ChainArgs,
    /// G54 work offset X,Y,Z in mm, for programs that set none.
    #[arg(long, allow_hyphen_values = true)]
    pub origin: Option<String>,
    /// Tool table (LinuxCNC's .tbl format, lengths in mm) for `G43 H<n>`.
    #[arg(long)]
    pub tool_table: Option<PathBuf>,
    /// Sample period (s).
    #[arg(long, default_value_t = PlanOptions::default().ts)]
    pub ts: f64,
    /// Constant flange orientation as roll,pitch,yaw in degrees (base frame,
    /// R = Rz·Ry·Rx); default: the flange orientation at q = 0.
    #[arg(long, allow_hyphen_values = true)]
    pub rpy: Option<String>,
    /// Time law of each exact-stop (G61) move: `septic` (the paper's) or `quintic`.
    #[arg(long, default_value = profile_name(TimingOptions::default().profile))]
    pub profile: String,
    /// Path speed (m/s) of moves without an F word: the peak speed under G61, the
    /// cruise speed under G64.
    #[arg(long, default_value_t = TimingOptions::default().max_speed)]
    pub speed: f64,
    /// Path acceleration limit (m/s²).
    #[arg(long, default_value_t = TimingOptions::default().max_accel)]
    pub accel: f64,
    /// Path jerk limit (m/s³) of blended (G64) moves.
    #[arg(long, default_value_t = TimingOptions::default().max_jerk)]
    pub jerk: f64,
    /// Corner tolerance (mm) of G64 without P.
    #[arg(long, default_value_t = TimingOptions::default().blend_tolerance * 1e3)]
    pub tolerance: f64,
    /// Path mode of programs that select neither G61 nor G64: `G61` (exact stop, the
    /// default: the paper's program runs as published) or `G64` (blend corners within
    /// --tolerance).
    #[arg(long, default_value = mode_name(TimingOptions::default().default_mode))]
    pub mode: String,
    /// Output CSV (`t,x,y,z,q1..qn,qd1..qdn`; SI units: t in s, x,y,z in m (flange position,
    /// base frame), q in rad (m for a prismatic joint), qd in rad/s (m/s)); the figures go
    /// beside it: `<stem>_path.png/.svg` (XY, 3-D and side views, q(t)),
    /// `<stem>_cartesian.png/.svg` (position, velocity, acceleration; the paper's Fig. 4) and
    /// `<stem>_speed.png/.svg` (top view, path speed, joint speeds against their limits).
    /// The files appear together or not at all; an existing file that is an input, a
    /// folder, a device, a FIFO or a symbolic link is never replaced.
    #[arg(long, default_value = "ofmpc-out/reference.csv")]
    pub out: PathBuf,
}

/// What the output folder of `run` and `reproduce` holds (shown by their `--help`).
const RESULTS_HELP: &str = "\
Output: metrics.json, report.html, the figures (PNG and SVG), scenario.toml (re-runs this run), \
and one folder per run (<controller>_m<payload kg>/) with timeseries.csv. Files appear only \
when the whole run succeeded; a second run into the same folder fails until the first ends.

timeseries.csv columns, SI units: t (s); q1..qn joint positions (rad; m for a prismatic \
joint); qd1..qdn joint velocities (rad/s; m/s); tau1..taun joint torques applied over \
[t, t + Ts) (N·m; N); qref1..qrefn reference (rad); e1..en = qref − q (rad); x,y,z flange \
position (m, base frame); xref,yref,zref its reference (m); ex,ey,ez = ref − flange (m).";

/// The help of `--set` (`run`, `reproduce`).
const SET_HELP: &str = "Sets a scenario key, as if written in the file: KEY=VALUE with a dotted \
key (e.g. mpc.horizon=20, plant.substep=2e-4, timing.mode=G64, plant.coulomb_friction=[1.0]); the \
value is read as TOML (a number, true, an array, a \"string\") and otherwise taken as a string. \
Repeatable, applied in order; every check of the file applies, and an unknown key is an error. A \
path set this way is relative to the working directory.";

/// `ofmpc run`
#[derive(Debug, Args)]
#[command(after_help = RESULTS_HELP)]
pub struct RunArgs {
    /// Scenario file (TOML). Paths in it are relative to its own folder.
    pub scenario: PathBuf,
    /// Payloads in kg, comma-separated: replaces the scenario's
    /// `[payload] masses_kg`.
    #[arg(long, allow_hyphen_values = true)]
    pub payload: Option<String>,
    /// Controllers, comma-separated: replaces the scenario's `controllers`
    /// (as `--set 'controllers=[...]'`).
    #[arg(long)]
    pub controllers: Option<String>,
    /// `irb140` or the path of a .urdf file (relative to the working directory): replaces
    /// `[robot] model` (as `--set robot.model=...`).
    #[arg(long)]
    pub robot: Option<String>,
    /// Path mode of programs that select neither, `G61` or `G64`: replaces `[timing] mode`
    /// (as `--set timing.mode=...`).
    #[arg(long)]
    pub mode: Option<String>,
    /// Tip, tool centre point and start pose: set `[robot] tip`, `tcp_mm`, `tcp_rpy_deg`,
    /// `start_q` (as `--set robot.start_q=[...]`).
    #[command(flatten)]
    pub chain: ChainArgs,
    /// Tool table (LinuxCNC's .tbl format, lengths in mm) for `G43 H<n>`: sets
    /// `[program] tool_table`.
    #[arg(long)]
    pub tool_table: Option<PathBuf>,
    /// Set a scenario key (KEY=VALUE; repeatable), after the options above.
    #[arg(long = "set", value_name = "KEY=VALUE", long_help = SET_HELP, allow_hyphen_values = true)]
    pub set: Vec<String>,
    /// Output directory.
    #[arg(long, default_value = "ofmpc-out")]
    pub out: PathBuf,
}

/// `ofmpc reproduce`
#[derive(Debug, Args)]
#[command(after_help = RESULTS_HELP)]
pub struct ReproduceArgs {
    /// G-code program (default: the paper's Table I, built in).
    #[arg(long)]
    pub program: Option<PathBuf>,
    /// Payloads in kg, comma-separated; e.g. 0,0.25,0.5,1,2,4,6 for a sweep
    /// [default: 0,0.25; with --compare: 0,0.25,1,2,6].
    #[arg(long, allow_hyphen_values = true)]
    pub payload: Option<String>,
    /// Controllers, comma-separated: usual, first, second, first-adaptive,
    /// second-adaptive, and the baselines pid, ctc, ctc-adaptive, dob-mpc;
    /// "all" for every one, "baselines" for the four baselines, "paper" for
    /// the paper's three [default: usual,first,second; with --compare: all].
    #[arg(long)]
    pub controllers: Option<String>,
    /// Compare every controller (the paper's, their adaptive variants and the
    /// baselines) over 0, 0.25, 1, 2, 6 kg; --payload and --controllers, when
    /// given (even with their usual defaults' values), still choose.
    #[arg(long)]
    pub compare: bool,
    /// The payload is picked up at this time (s) of the path: the plant carries
    /// none before (the controllers are not told).
    #[arg(long)]
    pub pick_up_at: Option<f64>,
    /// `irb140` (built in) or the path of a .urdf file: sets `[robot] model` (a URDF's drives
    /// file: `--set robot.drives=FILE`).
    #[arg(long)]
    pub robot: Option<String>,
    /// G54 work offset X,Y,Z in mm, for programs that set none: sets `[program] origin_mm`.
    #[arg(long, allow_hyphen_values = true)]
    pub origin: Option<String>,
    /// Path mode of programs that select neither, `G61` (exact stop, the default) or `G64`
    /// (blend): sets `[timing] mode`.
    #[arg(long)]
    pub mode: Option<String>,
    /// Tip, tool centre point and start pose: set `[robot] tip`, `tcp_mm`, `tcp_rpy_deg`,
    /// `start_q` (as `--set robot.start_q=[...]`).
    #[command(flatten)]
    pub chain: ChainArgs,
    /// Tool table (LinuxCNC's .tbl format, lengths in mm) for `G43 H<n>`: sets
    /// `[program] tool_table`.
    #[arg(long)]
    pub tool_table: Option<PathBuf>,
    /// Set a scenario key (KEY=VALUE; repeatable), after the options above.
    #[arg(long = "set", value_name = "KEY=VALUE", long_help = SET_HELP, allow_hyphen_values = true)]
    pub set: Vec<String>,
    /// Output directory.
    #[arg(long, default_value = "ofmpc-out")]
    pub out: PathBuf,
}

/// `ofmpc inspect ...`
#[derive(Debug, Subcommand)]
pub enum Inspect {
    /// H, C, g, inverse dynamics and the flange pose at a state, as JSON.
    Dynamics(InspectDynamics),
    /// The robot as loaded: joints, limits, drives, masses, flange, as JSON.
    Robot(InspectRobot),
    /// A G-code program as read (moves in machine coordinates, mm; events; messages;
    /// warnings), as JSON, without planning its timing.
    Program(InspectProgram),
}

/// `ofmpc inspect program`
#[derive(Debug, Args)]
pub struct InspectProgram {
    /// The G-code file.
    pub file: PathBuf,
    /// Work offset (G54) x,y,z in mm; default none (as a CNC from machine zero).
    #[arg(long, allow_hyphen_values = true)]
    pub origin: Option<String>,
    /// Robot (`irb140` or a .urdf): the program starts from the tool position of its start
    /// pose; without it the start is (0, 0, 0).
    #[arg(long)]
    pub robot: Option<String>,
    /// Drives file of the robot.
    #[arg(long)]
    pub drives: Option<PathBuf>,
    /// The robot's start pose, comma-separated joint positions (rad or m).
    #[arg(long, allow_hyphen_values = true)]
    pub start_q: Option<String>,
    /// Tool table (LinuxCNC's .tbl format, lengths in mm) for `G43 H<n>`.
    #[arg(long)]
    pub tool_table: Option<PathBuf>,
}

/// `ofmpc inspect robot`
#[derive(Debug, Args)]
pub struct InspectRobot {
    /// Which robot.
    #[command(flatten)]
    pub robot: RobotArgs,
}

/// `ofmpc inspect dynamics`
#[derive(Debug, Args)]
pub struct InspectDynamics {
    /// Which robot.
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

/// `ofmpc analyze stability`
#[derive(Debug, Args)]
pub struct StabilityArgs {
    /// Robot and program.
    #[command(flatten)]
    pub setup: SetupArgs,
    /// Controllers, comma-separated (usual, first, second).
    #[arg(long, default_value = "usual,first,second")]
    pub controllers: String,
    /// Tuning.
    #[command(flatten)]
    pub tuning: TuningArgs,
    /// Directory for the figure (`stability.png`, `stability.svg`).
    #[arg(long, default_value = "ofmpc-out")]
    pub out: PathBuf,
    /// JSON or words.
    #[command(flatten)]
    pub format: FormatArgs,
}

/// `ofmpc tune`
#[derive(Debug, Args)]
pub struct TuneArgs {
    /// Robot and program.
    #[command(flatten)]
    pub setup: SetupArgs,
    /// Payload range LO,HI in kg (point mass at the flange).
    #[arg(long)]
    pub payload_range: String,
    /// Controllers to tune for, comma-separated (usual, first, second); or
    /// one baseline (pid, ctc, ctc-adaptive, dob-mpc): its bandwidth.
    #[arg(long, default_value = "first,second")]
    pub controllers: String,
    /// The scenario file to write (TOML).
    #[arg(long)]
    pub out: PathBuf,
    /// JSON or words.
    #[command(flatten)]
    pub format: FormatArgs,
}

/// `ofmpc init robot`
#[derive(Debug, Args)]
pub struct InitRobotArgs {
    /// The robot's URDF file.
    pub urdf: PathBuf,
    /// Folder for `drives.toml` and `scenario.toml` (made if absent; existing files are never
    /// replaced).
    #[arg(long, default_value = ".")]
    pub out: PathBuf,
    /// The link that ends the chain (as `--tip` of run, written as `[robot] tip`): a branched
    /// tree such as an arm with a hand and fingers loads with the hand as its tip.
    #[arg(long)]
    pub tip: Option<String>,
}

/// `ofmpc analyze robustness`
#[derive(Debug, Args)]
pub struct RobustnessArgs {
    /// Scenario file (TOML): the arm, program, tuning and plant the grid varies
    /// (default: the built-in default scenario, the paper's).
    pub scenario: Option<PathBuf>,
    /// Controllers, comma-separated (default: the scenario's).
    #[arg(long)]
    pub controllers: Option<String>,
    /// Measurement delays (control periods), comma-separated.
    #[arg(long, default_value = "0,1")]
    pub delay: String,
    /// Encoder resolutions in bits per revolution (0 = ideal; > 0 also derives the velocity
    /// from the encoder), comma-separated.
    #[arg(long, default_value = "0,20")]
    pub encoder_bits: String,
    /// Friction-estimate errors (the controllers' estimates are the plant's friction times
    /// 1 − e), comma-separated.
    #[arg(long, default_value = "0.2")]
    pub friction_error: String,
    /// Model errors: `[plant] inertia_error` values, comma-separated.
    #[arg(long, default_value = "0,0.1")]
    pub inertia_error: String,
    /// Payloads (kg), comma-separated.
    #[arg(long, default_value = "0,6")]
    pub payload: String,
    /// A cell holds when its run ends "ok" with a steady Cartesian error at most this (mm).
    #[arg(long, default_value_t = 0.01)]
    pub steady_mm: f64,
    /// Output directory (robustness.json, robustness.png/.svg, report.html).
    #[arg(long, default_value = "ofmpc-out")]
    pub out: PathBuf,
    /// JSON or words on stdout.
    #[command(flatten)]
    pub format: FormatArgs,
}
