//! Sensing (#11 item 3) on the paper's path with 0.25 kg: a 22-bit encoder,
//! the velocity derived from the encoder positions, one sample of delay.
//! With the measurement used directly every controller diverges; with the
//! state observer and delay compensation the second algorithm holds and its
//! steady joint error is ≤ 5e-6 rad.

mod common;

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{Experiment, LoopSettings, PlantSettings, RunMetrics, RunOutcome, RunResult};

fn run(kind: ControllerKind, observer: bool) -> (RunResult, RunMetrics) {
    let robot = Robot::irb140();
    let reference = common::paper_reference(&robot);
    let exp = Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc: MpcSettings {
            delay_compensation: observer,
            ..Default::default()
        },
        plant: PlantSettings {
            encoder_counts: 1 << 22,
            velocity_from_encoder: true,
            delay_samples: 1,
            ..Default::default()
        },
        loop_settings: LoopSettings::default(),
        baselines: Default::default(),
    };
    exp.run(kind, &Payload::point_mass(0.25), &mut |_, _| {})
        .unwrap()
}

#[test]
fn encoder_velocity_and_delay_diverge_without_the_observer_and_hold_with_it() {
    let (raw, _) = run(ControllerKind::Second, false);
    let RunOutcome::Diverged { t, .. } = raw.outcome else {
        panic!("expected a divergence, got {}", raw.outcome);
    };
    assert!(t < 0.5, "diverged late: {t}");
    for kind in [ControllerKind::First, ControllerKind::Second] {
        let (r, m) = run(kind, true);
        assert!(r.outcome.is_completed(), "{kind}: {}", r.outcome);
        assert!(r
            .record
            .q
            .iter()
            .chain(&r.record.tau)
            .all(|v| v.is_finite()));
        let steady = m
            .steady_joint_error_max_rad
            .iter()
            .copied()
            .fold(0.0, f64::max);
        assert!(steady <= 5e-6, "{kind}: steady joint error {steady:e}");
    }
}
