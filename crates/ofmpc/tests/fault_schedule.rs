//! One fault schedule (#23 item 4): a fault of the plant (`[plant] faults`)
//! and a fault of the measurement channel (`[faults]`) given at the same path
//! time hit the same recorded sample, `sample_at(t, Ts)`, with and without
//! the adaptive controllers' identification pre-roll at rest before the path.

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::gcode::{parse, ParseOptions};
use ofmpc::motion::{build_reference, Orientation};
use ofmpc::motion::{CartesianTrajectory, TimingOptions};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{
    sample_at, Experiment, Fault, LoopSettings, MeasurementFaults, PlantSettings, Record,
    RunConditions,
};

/// The first three lines of the paper's program (Table I, its work offset):
/// two moves, about 2 s.
const PROGRAM: &str = "G21 G90\nG10 L2 P1 X150 Y0 Z-250\nG54 G17\n\
                       G00 X630 Y-200 Z400\nG00 X630 Y200 Z400\nG00 X630 Y0 Z400\nM30\n";

const TS: f64 = 0.01;
/// The torque drop (joint 1) and the lost measurement: at 1 s.
const DROP_AT: f64 = 1.0;
const DROP_S: f64 = 0.03;
/// The encoder glitch (joint 3): between two samples, 0.703 s (sample 71).
const GLITCH_AT: f64 = 0.703;
const GLITCH_RAD: f64 = 0.01;

fn experiment() -> Experiment {
    let robot = Robot::irb140();
    let program = parse(PROGRAM, &ParseOptions::default()).unwrap();
    let traj = CartesianTrajectory::new(&program, &TimingOptions::default()).unwrap();
    let reference = build_reference(&robot, &traj, Orientation::AtZero, TS).unwrap();
    assert!(
        reference.len() as f64 * TS > DROP_AT + 0.5,
        "a path that is still moving: {} samples",
        reference.len()
    );
    Experiment {
        robot,
        reference,
        mpc: MpcSettings::default(),
        plant: PlantSettings {
            faults: vec![
                Fault::TorqueDrop {
                    t: DROP_AT,
                    joint: 1,
                    fraction: 0.0,
                    duration_s: DROP_S,
                },
                Fault::EncoderGlitch {
                    t: GLITCH_AT,
                    joint: 3,
                    offset_rad: GLITCH_RAD,
                },
            ],
            ..Default::default()
        },
        loop_settings: LoopSettings {
            hold_s: 0.5,
            steady_window_s: 0.25,
            ..Default::default()
        },
        conditions: RunConditions {
            faults: MeasurementFaults {
                nan_at_s: vec![DROP_AT],
                dropout_s: Vec::new(),
            },
            ..Default::default()
        },
        baselines: Default::default(),
    }
}

/// The recorded samples where each fault took effect: the applied torque of
/// joint 1 is exactly zero, the reading is NaN, the reading of joint 3 is
/// off the true position (no noise: it equals it otherwise).
fn hits(r: &Record) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let n = r.n;
    let rows = 0..r.len();
    let dropped = rows.clone().filter(|&k| r.tau[k * n] == 0.0).collect();
    let lost = rows.clone().filter(|&k| r.q_meas[k * n].is_nan()).collect();
    let glitched = rows
        .filter(|&k| {
            let (seen, q) = (r.q_meas[k * n + 2], r.q[k * n + 2]);
            seen.is_finite() && (seen - q - GLITCH_RAD).abs() < 1e-9
        })
        .collect();
    (dropped, lost, glitched)
}

#[test]
fn plant_and_measurement_faults_hit_the_same_path_sample_with_and_without_the_pre_roll() {
    let exp = experiment();
    let at = sample_at(DROP_AT, TS);
    let until = sample_at(DROP_AT + DROP_S, TS);
    assert_eq!((at, until), (100, 103));
    let glitch = sample_at(GLITCH_AT, TS);
    assert_eq!(glitch, 71);
    // The adaptive variant holds the first point 0.5 s before the path.
    assert_eq!(exp.loop_settings.identification_samples(TS), 50);
    for kind in [ControllerKind::Second, ControllerKind::SecondAdaptive] {
        let (run, _) = exp
            .run(kind, &Payload::point_mass(0.25), &mut |_, _| {})
            .unwrap();
        let (dropped, lost, glitched) = hits(&run.record);
        assert_eq!(
            dropped,
            (at..until).collect::<Vec<_>>(),
            "{kind}: torque drop ({})",
            run.outcome
        );
        // Without torque the adaptive variant's identification goes astray
        // and its run diverges: after the faults.
        assert!(run.record.len() > until, "{kind}: {}", run.outcome);
        assert_eq!(lost, vec![at], "{kind}: lost measurement");
        assert_eq!(glitched, vec![glitch], "{kind}: encoder glitch");
    }
}
