//! The adaptive variants on the paper's path: final mass estimate, errors.
//! `cargo run --release -p ofmpc --example adaptive_quick -- 2 [pick_up_s]`.

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::motion::{plan, PlanOptions};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{Experiment, RunConditions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let payload: f64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(2.0);
    let pick_up: Option<f64> = args.next().map(|s| s.parse()).transpose()?;
    let robot = Robot::irb140();
    // The library's one planning entry point (parse, time, IK).
    let ts = 0.01;
    let reference = plan(
        PAPER_TABLE1,
        &robot,
        &PlanOptions {
            ts,
            ..PlanOptions::default()
        },
    )?
    .reference;
    let exp = Experiment {
        robot,
        reference,
        mpc: MpcSettings::default(),
        plant: Default::default(),
        loop_settings: Default::default(),
        conditions: RunConditions {
            pick_up_at_s: pick_up,
            ..Default::default()
        },
        baselines: Default::default(),
    };
    for kind in ControllerKind::WITH_ADAPTIVE {
        let (r, m) = exp.run(kind, &Payload::point_mass(payload), &mut |_, _| {})?;
        println!(
            "{:16} rms {:9.5} mm max {:8.4} mm steady joint {:10.3e}  m̂ {:?}  step {:5.1} us {}",
            m.name,
            m.cartesian_error_rms_mm,
            m.cartesian_error_max_mm,
            m.steady_joint_error_max_rad
                .iter()
                .cloned()
                .fold(0.0, f64::max),
            m.payload_estimate_kg,
            m.step_time_us.median,
            r.outcome
        );
    }
    Ok(())
}
