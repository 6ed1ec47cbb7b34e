//! The closed-loop tests' helpers: an experiment on a program with the default settings,
//! one run's metrics, its steady joint error.

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::gcode::{parse, ParseOptions};
use ofmpc::motion::{build_reference, Orientation};
use ofmpc::motion::{CartesianTrajectory, TimingOptions};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{Experiment, LoopSettings, RunMetrics};

/// `robot` on `program` (placed at `origin`, mm), timed and mapped to joints at Ts = 10 ms,
/// the orientation at q = 0; the controller's, plant's and loop's default settings.
pub fn experiment(robot: Robot, program: &str, origin: Option<[f64; 3]>) -> Experiment {
    let program = parse(
        program,
        &ParseOptions {
            origin,
            ..ParseOptions::default()
        },
    )
    .unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let reference = build_reference(&robot, &traj, Orientation::AtZero, 0.01).unwrap();
    Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc: MpcSettings::default(),
        plant: Default::default(),
        loop_settings: LoopSettings::default(),
        baselines: Default::default(),
    }
}

/// The metrics of `kind` under a point-mass payload of `mass` kg.
pub fn run(exp: &Experiment, kind: ControllerKind, mass: f64) -> RunMetrics {
    exp.run(kind, &Payload::point_mass(mass), &mut |_, _| {})
        .unwrap()
        .1
}

/// The largest steady joint error of a run (rad).
pub fn steady(m: &RunMetrics) -> f64 {
    m.steady_joint_error_max_rad
        .iter()
        .copied()
        .fold(0.0, f64::max)
}
