//! Runs the paper's experiment once and prints the metrics:
//! `cargo run --release -p ofmpc --example paper_quick -- 0.25`.

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::motion::{plan, PlanOptions};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::Experiment;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let payload: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(0.25);
    let robot = Robot::irb140();
    let reference = plan(PAPER_TABLE1, &robot, &PlanOptions::default())?.reference;
    let exp = Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc: MpcSettings::default(),
        plant: Default::default(),
        loop_settings: Default::default(),
        baselines: Default::default(),
    };
    for kind in [
        ControllerKind::Usual,
        ControllerKind::First,
        ControllerKind::Second,
    ] {
        let (r, m) = exp.run(kind, &Payload::point_mass(payload), &mut |_, _| {})?;
        println!(
            "{:8} rms {:8.4} mm max {:8.4} mm steady {:10.3e} mm  steady joint {:10.3e}  step {:6.1} us  wall {:.2}s {}",
            m.controller,
            m.cartesian_error_rms_mm,
            m.cartesian_error_max_mm,
            m.steady_cartesian_error_mm,
            m.steady_joint_error_max_rad.iter().cloned().fold(0.0, f64::max),
            m.step_time_us.median,
            m.wall_s,
            r.outcome
        );
    }
    Ok(())
}
