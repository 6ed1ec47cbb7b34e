use ofmpc::control::{ControllerKind, OutputMode};
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::motion::{plan, PlanOptions};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{Experiment, ServoProfile, ServoSettings};

#[test]
#[ignore]
fn explore() {
    let robot = Robot::irb140();
    let plan = plan(PAPER_TABLE1, &robot, &PlanOptions::default()).unwrap();
    let base = Experiment {
        robot,
        reference: plan.reference,
        mpc: Default::default(),
        plant: Default::default(),
        loop_settings: Default::default(),
        conditions: Default::default(),
        baselines: Default::default(),
    };
    let profiles: Vec<Option<ServoProfile>> = std::env::var("PROFILES").map(|s| s.split(',').map(|p| match p { "none" => None, "franka" => Some(ServoProfile::FrankaTorque), "ur" => Some(ServoProfile::UrServoj), "kuka" => Some(ServoProfile::KukaRsi), _ => Some(ServoProfile::AbbEgm)}).collect()).unwrap_or(vec![None, Some(ServoProfile::FrankaTorque), Some(ServoProfile::UrServoj), Some(ServoProfile::KukaRsi), Some(ServoProfile::AbbEgm)]);
    for kind in [ControllerKind::Second] {
        for mass in [0.25] {
            for prof in &profiles {
                let mut e = base.clone();
                if let Ok(b) = std::env::var("QDU") { e.mpc.q_du = ofmpc::control::Weight::Scalar(b.parse().unwrap()); }
                if let Ok(b) = std::env::var("QDY") { e.mpc.q_dy = ofmpc::control::Weight::Scalar(b.parse().unwrap()); }
                if let Some(p) = prof {
                    let mut s = ServoSettings::profile(*p);
                    if let Ok(b) = std::env::var("BW") { s.bandwidth_hz = Some(b.parse().unwrap()); }
                    if let Ok(b) = std::env::var("LAG") { s.lag_s = Some(b.parse().unwrap()); }
                    if let Ok(b) = std::env::var("LA") { s.lookahead_s = Some(b.parse().unwrap()); }
                    if let Ok(b) = std::env::var("GAIN") { s.gain = Some(b.parse().unwrap()); }
                    e.mpc.output = s.params().kind;
                    e.plant.servo = Some(s);
                } else {
                    e.mpc.output = OutputMode::Torque;
                }
                let (_r, m) = e.run(kind, &Payload::point_mass(mass), &mut |_, _| {}).unwrap();
                let steady = m.steady_joint_error_max_rad.iter().copied().fold(0.0, f64::max);
                println!("{kind:?} {mass} {:?}: status {:?} rms {:.4} mm max {:.4} steady {steady:.3e} servo {:?}", prof, m.status, m.cartesian_error_rms_mm, m.cartesian_error_max_mm, m.servo);
            }
        }
    }
}
