//! `cargo run --release -p ofmpc --example stability_quick`
use ofmpc::analysis::{max_payload, StabilityOptions, StabilityProblem};
use ofmpc::control::{BaselineSettings, ControllerKind, MpcSettings};
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::motion::{plan, PlanOptions};
use ofmpc::robot::Robot;

fn main() -> Result<(), Box<dyn std::error::Error>> {
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
    let q0 = reference.q(0).to_vec();
    let opts = StabilityOptions::default();
    let baselines = BaselineSettings::default();
    let poses: Vec<&[f64]> = (0..reference.len())
        .step_by(20)
        .map(|k| reference.q(k))
        .collect();
    for kind in ControllerKind::PAPER {
        for a in [0.5, 0.8, 1.0, 1.1] {
            let r = StabilityProblem {
                robot: &robot,
                kind,
                settings: &MpcSettings::default(),
                baselines: &baselines,
                q0: &q0,
                options: &opts,
            }
            .spectral_radius(a)?;
            println!("{kind} α={a} ρ={r:.6}");
        }
        let t = std::time::Instant::now();
        let iv = StabilityProblem {
            robot: &robot,
            kind,
            settings: &MpcSettings::default(),
            baselines: &baselines,
            q0: &q0,
            options: &opts,
        }
        .alpha_interval()?;
        let m = max_payload(&robot, iv, &poses, 100.0)?;
        println!(
            "{kind}: {iv:?} max payload {m:.3} kg ({:.2} s)",
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
