//! Runs the baselines on the paper's experiment and prints their metrics:
//! `cargo run --release -p ofmpc --example baselines_quick -- 0,0.25,1,2,6 [pid,ctc,...]`.

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::motion::{plan, PlanOptions};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::Experiment;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let payloads: Vec<f64> = args
        .next()
        .unwrap_or_else(|| "0,0.25,1,2,6".into())
        .split(',')
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let kinds: Vec<ControllerKind> = match args.next() {
        Some(s) => s.split(',').map(|k| k.parse()).collect::<Result<_, _>>()?,
        None => ControllerKind::BASELINES.to_vec(),
    };
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
    for kind in kinds {
        for &m in &payloads {
            let (r, met) = exp.run(kind, &Payload::point_mass(m), &mut |_, _| {})?;
            println!(
                "{:13} {:5} kg rms {:10.6} mm max {:9.5} mm steady {:9.2e} mm joint {:9.2e} rad step {:5.1} us {}",
                met.controller,
                m,
                met.cartesian_error_rms_mm,
                met.cartesian_error_max_mm,
                met.steady_cartesian_error_mm,
                met.steady_joint_error_max_rad.iter().cloned().fold(0.0, f64::max),
                met.step_time_us.median,
                r.outcome
            );
        }
    }
    Ok(())
}
