//! The command modes against the simulated servo interfaces (issue 37):
//! each vendor profile in closed loop against a payload the controller does
//! not know (offset-free hold, RMS against the torque mode's), the missed
//! deadlines (hold, extrapolate, the watchdog's trip), and the settings
//! refused with typed errors.

mod common;

use ofmpc::control::{
    BuildError, ControllerBuilder, ControllerKind, MpcSettings, OutputMode, StepError, StepInput,
    Weight,
};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{
    Experiment, ExperimentError, LateSteps, OnLate, PlantError, PlantSettingsError, RunFailure,
    RunMetrics, RunOutcome, RunStatus, Servo, ServoProfile, ServoSettings, ServoSettingsError,
    ServoStatus,
};

/// The paper's path on the IRB 140 with `q_du` (the paper's 1e-5 is too
/// aggressive for a 40 ms lag or a 100 Hz torque low-pass at Ts = 10 ms),
/// the interface `servo` (`None`: torque straight to the plant).
fn experiment(q_du: f64, servo: Option<ServoSettings>) -> Experiment {
    let robot = Robot::irb140();
    let reference = common::paper_reference(&robot);
    let output = servo.as_ref().map_or(OutputMode::Torque, |s| s.kind());
    let mut e = Experiment {
        robot,
        reference,
        mpc: MpcSettings {
            q_du: Weight::Scalar(q_du),
            output,
            ..Default::default()
        },
        plant: Default::default(),
        loop_settings: Default::default(),
        conditions: Default::default(),
        baselines: Default::default(),
    };
    e.plant.servo = servo;
    e
}

fn run(e: &Experiment, kind: ControllerKind, mass: f64) -> (RunOutcome, RunMetrics) {
    let (r, m) = e
        .run(kind, &Payload::point_mass(mass), &mut |_, _| {})
        .unwrap();
    (r.outcome, m)
}

/// Each profile against a payload the controller does not know, the
/// second algorithm and its adaptive variant, at 0.25 and 2 kg: the run
/// completes, the hold is offset-free (the vendor's joint loop has
/// integral action and the controller's command converges to the
/// reference; to 1e-9 rad over the steady window of a hold long enough for
/// the interface's slowest mode: 2 s, abb-egm 3 s, ur-servoj 9 s: its
/// stream model converges more slowly, 3.2e-8 rad after 5 s), every
/// cycle was on time, and the Cartesian RMS is within a bound of the
/// torque mode's with the same tuning and hold. The default lead covers
/// the lag and the setpoint's hold over the interface cycle, and the
/// command inverts ur-servoj's smoothing through its stream model
/// (`control/command.rs`); measured (docs/guide/tutorials/command-modes.md),
/// against the second algorithm: franka-torque 1.2×, kuka-rsi 1.8×, abb-egm
/// 1.24× / 0.47× (0.25 / 2 kg), ur-servoj 1.00× / 0.82× (before: kuka-rsi
/// 37×, abb-egm 12× at 0.25 kg, ur-servoj 21×, then 2.6× / 1.3× with
/// `q + T q̇`); against the adaptive variant (torque mode 0.1–2 µm), through
/// abb-egm and ur-servoj identifying from the drives' reported torque with
/// its torque feed-forward: abb-egm 2.31× / 2.24×, ur-servoj 1.16× / 1.14×
/// (running as the second: abb-egm 2.5× / 9.7×, ur-servoj 2.05× / 17×, and
/// 5.3× / 27× with `q + T q̇`); kuka-rsi, without the report, 13×. The
/// paper's `Q_Δu = 1e-5`
/// diverges at 2 kg in torque mode and against a 40 ms lag: the cases use
/// 1e-3 except kuka-rsi (1e-5 at 0.25 kg).
#[test]
fn each_profile_tracks_an_unknown_payload() {
    let ur = ServoSettings {
        gain: Some(2000.0),
        ..ServoSettings::profile(ServoProfile::UrServoj)
    };
    // abb-egm and ur-servoj: the second-adaptive runs through an interface
    // that reports its drives' torque and takes a torque feed-forward (the
    // identification's data, the payload's torque); `None` for the others.
    let reporting = |s: &ServoSettings| ServoSettings {
        reports_torque: Some(true),
        torque_feedforward: Some(true),
        ..s.clone()
    };
    // (interface, q_du, payloads, hold (s), RMS ratio bounds: second, second-adaptive)
    let cases = [
        (
            ServoSettings::profile(ServoProfile::FrankaTorque),
            1e-3,
            &[2.0][..],
            2.0,
            [1.5, 1.5],
        ),
        (
            ServoSettings::profile(ServoProfile::KukaRsi),
            1e-5,
            &[0.25][..],
            2.0,
            [2.5, 15.0],
        ),
        (
            ServoSettings::profile(ServoProfile::AbbEgm),
            1e-3,
            &[0.25, 2.0][..],
            3.0,
            [1.6, 3.0],
        ),
        (ur, 1e-3, &[0.25, 2.0][..], 9.0, [1.2, 3.0]),
    ];
    for (servo, q_du, masses, hold_s, ratio_max) in cases {
        let kinds = [ControllerKind::Second, ControllerKind::SecondAdaptive];
        for (&mass, (kind, ratio_max)) in masses
            .iter()
            .flat_map(|m| std::iter::repeat(m).zip(kinds.into_iter().zip(ratio_max)))
        {
            let held = |servo: Option<ServoSettings>| {
                let mut e = experiment(q_du, servo);
                e.loop_settings.hold_s = hold_s;
                e
            };
            let (_, torque) = run(&held(None), kind, mass);
            let profile = servo.profile;
            let identifies = kind == ControllerKind::SecondAdaptive
                && matches!(profile, ServoProfile::AbbEgm | ServoProfile::UrServoj);
            let interface = if identifies {
                reporting(&servo)
            } else {
                servo.clone()
            };
            let (outcome, m) = run(&held(Some(interface)), kind, mass);
            if identifies {
                // Identified from the drives' reported torque.
                let estimate = m.payload_estimate_kg.unwrap();
                assert!(
                    (estimate - mass).abs() < 0.01 * mass,
                    "{profile} {mass}: estimate {estimate}"
                );
            }
            assert!(
                outcome.is_completed(),
                "{profile} {kind:?} {mass}: {outcome}"
            );
            let steady = common::experiment::steady(&m);
            assert!(
                steady <= 1e-9,
                "{profile} {kind:?} {mass}: steady {steady:e}"
            );
            let ratio = m.cartesian_error_rms_mm / torque.cartesian_error_rms_mm;
            eprintln!(
                "ROW {profile} {kind:?} {mass}: {:.5} {:.5} {ratio:.3} {steady:.1e} {}",
                m.cartesian_error_rms_mm,
                torque.cartesian_error_rms_mm,
                m.servo.unwrap().misses
            );
            assert!(
                ratio <= ratio_max,
                "{profile} {kind:?} {mass}: RMS ratio {ratio}"
            );
            let report = m.servo.unwrap();
            assert_eq!((report.misses, report.status), (0, ServoStatus::Ok));
            assert!(report.cycles > 0);
        }
    }
}

/// ur-servoj's own cost, the payload known to the controller and the
/// drive (only the interface's dynamics left), through the command's
/// stream model (`control/command.rs`, the default when the lead and the
/// smoothing are left to the interface): at servoj's gain 2000 and its
/// default 300, at 0.25 and 2 kg, the example's 5 s hold. Measured
/// 0.0025 mm at gain 2000 and 0.0027 at 300 (both masses); before the
/// stream model (`q + T q̇` one lead ahead: `output_lead_s` and
/// `output_smoothing_s` given, as the defaults were) 0.0099 and 0.084 mm,
/// and 0.0023 with the smoothing all but off (`lookahead_s` 1 ms). The
/// stream model's settings given as the defaults are the default run, to
/// the bit.
#[test]
fn ur_servoj_costs_little_through_the_stream_model() {
    for gain in [2000.0, 300.0] {
        for mass in [0.25, 2.0] {
            let servo = ServoSettings {
                gain: Some(gain),
                ..ServoSettings::profile(ServoProfile::UrServoj)
            };
            let mut e = experiment(1e-3, Some(servo));
            e.loop_settings.hold_s = 5.0;
            e.mpc.model_payload_kg = mass;
            let (outcome, m) = run(&e, ControllerKind::Second, mass);
            assert!(outcome.is_completed(), "{gain} {mass}: {outcome}");
            let rms = m.cartesian_error_rms_mm;
            assert!(rms <= 0.003, "gain {gain}, {mass} kg: {rms} mm");
            let mut old = e.clone();
            (old.mpc.output_lead_s, old.mpc.output_smoothing_s) = (Some(0.0045), Some(0.0295));
            let (_, before) = run(&old, ControllerKind::Second, mass);
            assert!(
                rms * 3.5 < before.cartesian_error_rms_mm,
                "gain {gain}, {mass} kg: {rms} against {} mm",
                before.cartesian_error_rms_mm
            );
            if gain == 2000.0 && mass == 2.0 {
                let ur = ServoSettings::profile(ServoProfile::UrServoj);
                let smoothing = ur.smoothing_s_at(1e-3);
                let mut given = e.clone();
                given.mpc.output_lead_s = Some(ur.command_lead_s_at(1e-3));
                given.mpc.output_smoothing_s = Some(smoothing);
                given.mpc.output_cycle_s = Some(0.002);
                given.mpc.output_smoothing_step_s = Some(1e-3);
                let (_, same) = run(&given, ControllerKind::Second, mass);
                assert_eq!(same.cartesian_error_rms_mm.to_bits(), rms.to_bits());
            }
        }
    }
}

/// The stage itself on missed cycles: a fresh command is streamed along
/// its prediction; a late period holds the last setpoint (at rest) or
/// extrapolates it, and the watchdog trips at exactly `watchdog_misses`
/// consecutive misses.
#[test]
fn hold_extrapolate_and_fault_on_missed_cycles() {
    let robot = Robot::irb140();
    let (ts, h) = (0.01, 1e-3);
    let q0 = [0.1, 0.2, -0.1, 0.0, 0.3, 0.0];
    let qd = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let zero = [0.0; 6];
    let mut tau = [0.0; 6];
    let period = |servo: &mut Servo, late: bool, tau: &mut [f64]| {
        servo.receive(&zero, &q0, &qd, &zero, late);
        for i in 0..10 {
            servo.drive(i, &q0, &zero, tau, h).unwrap();
        }
        servo.setpoint()[0]
    };
    for on_late in [OnLate::Hold, OnLate::Extrapolate, OnLate::Fault] {
        let settings = ServoSettings {
            period_s: Some(0.002),
            on_late: Some(on_late),
            watchdog_misses: Some(7),
            ..ServoSettings::profile(ServoProfile::KukaRsi)
        };
        let mut servo = Servo::new(&settings, &robot, ts, h).unwrap();
        servo.start(&q0).unwrap();
        // On time: cycles at 0, 2, …, 8 ms along q̇ = 1 rad/s.
        let on_time = period(&mut servo, false, &mut tau);
        assert!((on_time - (0.1 + 0.008)).abs() < 1e-15, "{on_time}");
        // Late: five missed cycles.
        let late = period(&mut servo, true, &mut tau);
        let expected = match on_late {
            OnLate::Extrapolate => 0.108 + 5.0 * 0.002,
            _ => 0.108,
        };
        assert!((late - expected).abs() < 1e-15, "{on_late:?}: {late}");
        assert_eq!(servo.report().misses, 5);
        assert!(!servo.tripped());
        // Two more misses: seven in a row trip the watchdog.
        servo.receive(&zero, &q0, &qd, &zero, true);
        servo.drive(0, &q0, &zero, &mut tau, h).unwrap();
        assert!(!servo.tripped());
        for i in 1..3 {
            servo.drive(i, &q0, &zero, &mut tau, h).unwrap();
        }
        assert!(servo.tripped(), "{on_late:?}");
        assert_eq!(servo.report().status, ServoStatus::WatchdogTrip);
        assert_eq!(servo.report().max_consecutive_misses, 7);
    }
}

/// Injected late steps in closed loop: with `hold` and no watchdog the run
/// completes and counts the missed cycles (5 late steps of 10 ms at 4 ms:
/// 12 or 13 cycles); with the watchdog at 10 cycles it ends the run as a
/// typed watchdog failure, recorded in the metrics.
#[test]
fn injected_late_steps_hold_or_trip_the_watchdog() {
    let late = vec![LateSteps {
        t: 1.0,
        duration_s: 0.05,
    }];
    let hold = ServoSettings {
        on_late: Some(OnLate::Hold),
        watchdog_misses: Some(0),
        late: late.clone(),
        ..ServoSettings::profile(ServoProfile::KukaRsi)
    };
    let (outcome, m) = run(&experiment(1e-5, Some(hold)), ControllerKind::Second, 0.25);
    assert!(outcome.is_completed(), "{outcome}");
    let report = m.servo.unwrap();
    assert!((12..=13).contains(&report.misses), "{report:?}");
    assert_eq!(report.status, ServoStatus::Ok);
    let fault = ServoSettings {
        on_late: Some(OnLate::Fault),
        watchdog_misses: Some(10),
        late,
        ..ServoSettings::profile(ServoProfile::KukaRsi)
    };
    let (outcome, m) = run(&experiment(1e-5, Some(fault)), ControllerKind::Second, 0.25);
    match outcome {
        RunOutcome::Failed {
            t,
            cause: RunFailure::ServoWatchdog { misses },
        } => {
            assert_eq!(misses, 10);
            assert!((1.0..1.06).contains(&t), "{t}");
        }
        o => panic!("{o}"),
    }
    assert_eq!(m.status, RunStatus::Failed);
    assert_eq!(m.servo.unwrap().status, ServoStatus::WatchdogTrip);
    let json = serde_json::to_value(&m).unwrap();
    assert_eq!(json["servo"]["status"], "watchdog_trip");
}

/// Settings that cannot work are refused, each with its typed error.
#[test]
fn settings_that_cannot_work_are_refused() {
    let refused = |s: ServoSettings| s.validate_for(0.01, 1e-3).unwrap_err();
    let kuka = ServoSettings::profile(ServoProfile::KukaRsi);
    assert_eq!(
        refused(ServoSettings {
            on_late: Some(OnLate::Fault),
            watchdog_misses: Some(0),
            ..kuka.clone()
        }),
        ServoSettingsError::FaultWithoutWatchdog
    );
    assert!(matches!(
        refused(ServoSettings {
            period_s: Some(0.0025),
            ..kuka.clone()
        }),
        ServoSettingsError::Multiple { .. }
    ));
    assert!(matches!(
        refused(ServoSettings {
            lag_s: Some(0.005),
            ..kuka.clone()
        }),
        ServoSettingsError::Multiple { .. }
    ));
    assert!(matches!(
        refused(ServoSettings {
            gain: Some(1e6),
            ..kuka.clone()
        }),
        ServoSettingsError::LoopTooFast { .. }
    ));
    assert!(matches!(
        refused(ServoSettings {
            period_s: Some(-1.0),
            ..kuka.clone()
        }),
        ServoSettingsError::Value {
            key: "period_s",
            ..
        }
    ));
    assert!(matches!(
        refused(ServoSettings {
            gain: Some(300.0),
            ..ServoSettings::profile(ServoProfile::FrankaTorque)
        }),
        ServoSettingsError::Unused { key: "gain", .. }
    ));
    // The controller's output must be what the interface takes.
    let mut e = experiment(1e-3, Some(kuka));
    e.mpc.output = OutputMode::Torque;
    let err = e.validate().unwrap_err();
    assert!(
        matches!(
            err,
            ExperimentError::Plant(PlantError::Settings(PlantSettingsError::Servo(
                ServoSettingsError::OutputMismatch { .. }
            )))
        ),
        "{err:?}"
    );
    let mut e = experiment(1e-3, None);
    e.mpc.output = OutputMode::PositionVelocity;
    assert!(matches!(
        e.validate().unwrap_err(),
        ExperimentError::Plant(PlantError::Settings(PlantSettingsError::Servo(
            ServoSettingsError::NoInterface { .. }
        )))
    ));
    // The builder: a baseline predicts nothing; the lead must fit the horizon.
    let robot = Robot::irb140();
    let pv = |lead: Option<f64>| MpcSettings {
        output: OutputMode::PositionVelocity,
        output_lead_s: lead,
        ..Default::default()
    };
    let build = |kind, s| ControllerBuilder::new(kind, &robot).settings(s).build();
    assert!(matches!(
        build(ControllerKind::Pid, pv(None)).unwrap_err(),
        BuildError::OutputWithoutPrediction { .. }
    ));
    assert!(matches!(
        build(ControllerKind::Second, pv(Some(0.2))).unwrap_err(),
        BuildError::OutputLead { .. }
    ));
    // The smoothing the command pre-compensates: a finite time ≥ 0, with a
    // position or velocity output only.
    for bad in [-0.01, f64::NAN, f64::INFINITY] {
        let s = MpcSettings {
            output_smoothing_s: Some(bad),
            ..pv(Some(0.01))
        };
        assert!(matches!(
            build(ControllerKind::Second, s).unwrap_err(),
            BuildError::OutputSmoothing { .. }
        ));
    }
    let torque_with_smoothing = MpcSettings {
        output_smoothing_s: Some(0.03),
        ..Default::default()
    };
    assert!(matches!(
        build(ControllerKind::Second, torque_with_smoothing).unwrap_err(),
        BuildError::OutputSmoothing { .. }
    ));
    let torque_with_lead = MpcSettings {
        output_lead_s: Some(0.01),
        ..Default::default()
    };
    assert!(matches!(
        build(ControllerKind::Second, torque_with_lead).unwrap_err(),
        BuildError::OutputLead { .. }
    ));
    // The stream model: a cycle dividing Ts, a step dividing the cycle, a
    // smoothing to invert, a horizon of four samples; a step needs a cycle.
    let stream =
        |cycle: Option<f64>, step: Option<f64>, smoothing: Option<f64>, horizon| MpcSettings {
            output_cycle_s: cycle,
            output_smoothing_step_s: step,
            output_smoothing_s: smoothing,
            horizon,
            ..pv(Some(0.0045))
        };
    for bad in [
        stream(Some(0.003), None, Some(0.03), 10),
        stream(Some(0.0), None, Some(0.03), 10),
        stream(Some(f64::NAN), None, Some(0.03), 10),
        stream(Some(0.002), Some(0.0015), Some(0.03), 10),
        stream(Some(0.002), Some(0.001), None, 10),
        stream(Some(0.002), Some(0.001), Some(0.0), 10),
        stream(Some(0.002), Some(0.001), Some(0.03), 3),
        stream(None, Some(0.001), Some(0.03), 10),
    ] {
        let err = build(ControllerKind::Second, bad.clone()).unwrap_err();
        assert!(
            matches!(err, BuildError::OutputStream { .. }),
            "{bad:?}: {err:?}"
        );
    }
    assert!(build(
        ControllerKind::Second,
        stream(Some(0.002), Some(0.001), Some(0.03), 4)
    )
    .is_ok());
    assert!(build(
        ControllerKind::Second,
        stream(Some(0.01), None, Some(0.03), 10)
    )
    .is_ok());
    for kind in [
        ControllerKind::Usual,
        ControllerKind::First,
        ControllerKind::Second,
    ] {
        assert!(build(kind, pv(Some(0.09))).is_ok(), "{kind:?}");
    }
}

/// The safe stop through a position interface: the stop law's braking
/// trajectory is what the interface receives (a decelerating, then
/// holding position, `SupervisedController::command`), not the
/// controller's last command (a stale point one lead ahead with its
/// velocity, which the interface would keep streaming) nor a torque the
/// drive ignores. A safety limit the run passes brings the arm to rest
/// (`Stopped`: at rest by the end, within its limits) within the braking
/// run-out of where it was, every cycle on time. Measured (8 kg picked up
/// at 3 s, limit 1.5 mrad): the stop begins at 0.54–0.60 rad/s and the arm
/// travels 0.024 rad, at rest (< 1e-4 rad/s) one second later; with the
/// controller's last command instead, abb-egm's stop failed (0.088 rad/s
/// one second later).
#[test]
fn a_safe_stop_through_a_position_interface_commands_a_braking_position() {
    for profile in [ServoProfile::AbbEgm, ServoProfile::UrServoj] {
        let servo = ServoSettings {
            gain: (profile == ServoProfile::UrServoj).then_some(2000.0),
            ..ServoSettings::profile(profile)
        };
        let mut e = experiment(1e-3, Some(servo));
        // A heavy load picked up mid-path passes the limit at speed.
        e.conditions.safety.max_joint_error_rad = Some(1.5e-3);
        e.conditions.pick_up_at_s = Some(3.0);
        let (r, m) = e
            .run(
                ControllerKind::Second,
                &Payload::point_mass(8.0),
                &mut |_, _| {},
            )
            .unwrap();
        let stop = m.stopped_at_s.expect("the limit brought no stop");
        let rec = &r.record;
        let n = rec.n;
        let k0 = rec.t.iter().position(|t| *t >= stop).unwrap();
        // The speed when the stop began and the travel after it.
        let v0 = (0..n).fold(0.0f64, |a, i| a.max(rec.qd[k0 * n + i].abs()));
        let travel = (k0..rec.t.len()).fold(0.0f64, |a, k| {
            (0..n).fold(a, |a, i| {
                a.max((rec.q[k * n + i] - rec.q[k0 * n + i]).abs())
            })
        });
        let last = rec.t.len() - 1;
        let v_end = (0..n).fold(0.0f64, |a, i| a.max(rec.qd[last * n + i].abs()));
        assert_eq!(m.status, RunStatus::Stopped, "{profile}: {}", m.reason);
        assert!(v_end < 1e-3, "{profile}: still moving at {v_end} rad/s");
        // The braking run-out (BRAKE_TIME = 30 ms) behind the interface's
        // lead (40 ms, 34 ms).
        assert!(
            travel <= v0 * (0.03 + 0.04) + 1e-3,
            "{profile}: travelled {travel} rad after the stop at {v0} rad/s"
        );
        let report = m.servo.unwrap();
        assert_eq!((report.misses, report.status), (0, ServoStatus::Ok));
    }
}

/// Through an interface that closes its own joint loop and does not report
/// its drives' torque (the default) the adaptive kinds do not identify
/// (`control/adaptive.rs`): the torque the arm receives is
/// the drive's, not the controller's `τ_k`, and fed `τ_k` the estimate ran
/// to the 1000 kg bound (measured through abb-egm and ur-servoj before this
/// rule). They then run as their base algorithm — the same run as
/// `second`, to the bit — and report no estimate; with a torque output
/// (franka-torque) they identify the payload.
#[test]
fn the_adaptive_kinds_do_not_identify_through_a_position_interface() {
    for profile in [ServoProfile::AbbEgm, ServoProfile::UrServoj] {
        let e = experiment(1e-3, Some(ServoSettings::profile(profile)));
        let (_, base) = run(&e, ControllerKind::Second, 2.0);
        let (outcome, adaptive) = run(&e, ControllerKind::SecondAdaptive, 2.0);
        assert!(outcome.is_completed(), "{profile}: {outcome}");
        assert_eq!(adaptive.payload_estimate_kg, None, "{profile}");
        assert_eq!(
            adaptive.cartesian_error_rms_mm.to_bits(),
            base.cartesian_error_rms_mm.to_bits(),
            "{profile}"
        );
        assert_eq!(
            adaptive.steady_joint_error_max_rad,
            base.steady_joint_error_max_rad
        );
    }
    let e = experiment(
        1e-3,
        Some(ServoSettings::profile(ServoProfile::FrankaTorque)),
    );
    let (_, m) = run(&e, ControllerKind::SecondAdaptive, 2.0);
    let mass = m.payload_estimate_kg.expect("a torque output identifies");
    assert!((mass - 2.0).abs() < 0.2, "franka-torque: {mass} kg");
}

/// `torque_feedforward`: the joint loop adds the setpoint's torque to its
/// own, exactly, once the setpoint has come through the lag line; a torque
/// interface refuses the key (it takes the torque itself).
#[test]
fn the_drive_adds_the_commanded_torque_feed_forward() {
    let robot = Robot::irb140();
    let (ts, h) = (0.01, 1e-3);
    let q0 = [0.1, 0.2, -0.1, 0.0, 0.3, 0.0];
    let qd = [0.4, -0.2, 0.1, 0.0, 0.0, 0.3];
    let ff = [1.5, -20.0, 3.25, 0.5, -0.75, 0.125];
    let zero = [0.0; 6];
    let torques = |feed: bool, sent: &[f64]| {
        let settings = ServoSettings {
            torque_feedforward: feed.then_some(true),
            ..ServoSettings::profile(ServoProfile::AbbEgm)
        };
        let mut servo = Servo::new(&settings, &robot, ts, h).unwrap();
        servo.start(&q0).unwrap();
        let mut out = Vec::new();
        let mut tau = [0.0; 6];
        // 40 ms of lag: the fifth period's torques see the first command.
        for _ in 0..6 {
            servo.receive(sent, &q0, &qd, &zero, false);
            for i in 0..10 {
                servo.drive(i, &q0, &zero, &mut tau, h).unwrap();
                out.push(tau);
            }
        }
        out
    };
    let plain = torques(false, &ff);
    let added = torques(true, &ff);
    let without = torques(true, &zero);
    assert_eq!(plain, without, "no feed-forward sent: nothing added");
    let mut seen = 0;
    for (a, p) in added.iter().zip(&plain) {
        let d: Vec<f64> = a.iter().zip(p).map(|(a, p)| a - p).collect();
        if d.iter().any(|v| *v != 0.0) {
            for (d, f) in d.iter().zip(&ff) {
                assert!((d - f).abs() < 1e-12 * (1.0 + f.abs()), "{d} vs {f}");
            }
            seen += 1;
        }
    }
    assert!(seen >= 10, "the feed-forward arrived in {seen} substeps");
    let franka = ServoSettings {
        torque_feedforward: Some(true),
        ..ServoSettings::profile(ServoProfile::FrankaTorque)
    };
    assert!(matches!(
        franka.validate_for(0.01, 1e-3).unwrap_err(),
        ServoSettingsError::Unused {
            key: "torque_feedforward",
            ..
        }
    ));
}

/// The identification's torque is the one the arm received: with a torque
/// output the drives apply `τ_{k−1}` over `[t_{k−1}, t_k]`, so reporting it
/// before step `k` leaves every torque and estimate unchanged, to the bit
/// (and a report shifted by one period changes them); a report of the wrong
/// size or not finite is refused with nothing changed.
#[test]
fn the_applied_torque_of_a_torque_output_is_its_own_last_torque() {
    let robot = Robot::irb140();
    let reference = common::paper_reference(&robot);
    let build = || {
        let mut c = ControllerBuilder::new(ControllerKind::SecondAdaptive, &robot)
            .build()
            .unwrap();
        c.reset(&[reference.q(0), &[0.0; 6][..]].concat()).unwrap();
        c
    };
    let n = 6;
    let horizon = build().horizon();
    // A made-up measured motion (the identification only needs data).
    let x_at = |k: usize| -> Vec<f64> {
        let t = k as f64 * 0.01;
        let q: Vec<f64> = (0..n)
            .map(|i| reference.q(k.min(reference.len() - 1))[i] + 1e-3 * (t * (i + 1) as f64).sin())
            .collect();
        let qd: Vec<f64> = (0..n)
            .map(|i| 1e-3 * (i + 1) as f64 * (t * (i + 1) as f64).cos())
            .collect();
        [q, qd].concat()
    };
    let mut runs = Vec::new();
    for report in [None, Some(1), Some(2)] {
        let mut c = build();
        let mut history: Vec<Vec<f64>> = Vec::new();
        let mut out = Vec::new();
        let mut preview = vec![0.0; horizon * n];
        for k in 0..60 {
            let x = x_at(k);
            let w = reference.q(k);
            reference.preview(k, horizon, &mut preview);
            if let Some(back) = report.filter(|b| history.len() >= *b) {
                c.set_applied_torque(&history[history.len() - back])
                    .unwrap();
            }
            let o = c
                .step(&StepInput {
                    x: &x,
                    w_k: w,
                    preview: &preview,
                })
                .unwrap();
            history.push(o.tau.to_vec());
            out.push((o.tau.to_vec(), o.payload_estimate));
        }
        runs.push(out);
    }
    assert_eq!(runs[0], runs[1], "reporting τ_(k−1) changed the run");
    assert_ne!(runs[0], runs[2], "a report one period off changed nothing");
    let mut c = build();
    assert!(matches!(
        c.set_applied_torque(&[0.0; 5]),
        Err(StepError::WrongLength {
            expected: 6,
            got: 5,
            ..
        })
    ));
    assert!(matches!(
        c.set_applied_torque(&[0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0]),
        Err(StepError::NonFiniteInput { index: 2, .. })
    ));
}
