//! `ControllerBuilder`: every configuration that cannot work is refused with
//! its typed error, and the built `Controller` steps exactly (bit for bit) as the
//! `new_controller` + `Algorithm::step` path it wraps.

mod common;

use common::paper_reference;
use ofmpc::control::{
    new_controller, new_controller_with_baselines, BaselineSettings, BuildError, ControllerBuilder,
    ControllerKind, DriveModel, FrictionUse, MpcSettings, ObserverSettings, SettingsError, Solver,
    StepError, StepFailure, StepInput, StepStatus, Weight,
};
use ofmpc::dynamics::RobotDynamics;
use ofmpc::ident::RlsSettings;
use ofmpc::robot::{Payload, Robot};

fn drives(n: usize, tau_max: f64, friction: f64) -> DriveModel {
    DriveModel {
        max_torque_nm: vec![tau_max; n],
        coulomb_nm: vec![friction; n],
        viscous_nms: vec![friction; n],
        coulomb_velocity_rad_s: 1e-3,
    }
}

fn build(kind: ControllerKind, settings: MpcSettings) -> Result<(), BuildError> {
    ControllerBuilder::new(kind, &Robot::irb140())
        .settings(settings)
        .build()
        .map(|_| ())
}

/// Builds `kind` for the IRB 140 with `settings` and `drives`.
fn build_with(
    kind: ControllerKind,
    settings: MpcSettings,
    drives: DriveModel,
) -> Result<ofmpc::control::Controller, BuildError> {
    ControllerBuilder::new(kind, &Robot::irb140())
        .settings(settings)
        .drives(drives)
        .build()
}

#[test]
fn builds_the_paper_controllers_and_the_crate_root_reexport() {
    fn send<T: Send>() {}
    send::<ofmpc::control::Controller>();
    let robot = Robot::irb140();
    for kind in ControllerKind::WITH_ADAPTIVE {
        let mpc = ofmpc::ControllerBuilder::new(kind, &robot).build().unwrap();
        assert_eq!(mpc.kind(), kind);
        assert_eq!(mpc.dof(), 6);
        assert_eq!(mpc.horizon(), 10);
        assert_eq!(mpc.settings(), &MpcSettings::default());
        assert_eq!(mpc.output().tau.len(), 6);
        assert!(mpc.drives().is_none() && mpc.observer().is_none());
        assert!(mpc.model().robot().payload().is_none());
    }
}

#[test]
fn refuses_settings_that_do_not_fit_the_robot() {
    let bad = MpcSettings {
        horizon: 0,
        ..Default::default()
    };
    assert!(matches!(
        build(ControllerKind::First, bad),
        Err(BuildError::Settings(_))
    ));
    let bad_drives = DriveModel {
        max_torque_nm: vec![1.0; 5],
        ..drives(6, 1.0, 0.0)
    };
    let limits = MpcSettings {
        torque_limits: true,
        ..Default::default()
    };
    let err = build_with(ControllerKind::Usual, limits, bad_drives).unwrap_err();
    assert!(matches!(err, BuildError::Settings(_)), "{err}");
}

#[test]
fn refuses_torque_limits_without_a_finite_limit() {
    let s = MpcSettings {
        torque_limits: true,
        ..Default::default()
    };
    let err = build_with(
        ControllerKind::Second,
        s.clone(),
        drives(6, f64::INFINITY, 0.0),
    )
    .unwrap_err();
    assert_eq!(err, BuildError::NoTorqueLimits);
    // The built-in robot's drives have limits: builds, with them.
    let robot = Robot::irb140();
    let mpc = ControllerBuilder::new(ControllerKind::Second, &robot)
        .settings(s)
        .build()
        .unwrap();
    assert_eq!(mpc.drives(), Some(&DriveModel::from_robot(&robot)));
}

#[test]
fn refuses_friction_use_without_friction_estimates() {
    let comp = MpcSettings {
        friction_compensation: true,
        ..Default::default()
    };
    let err = build_with(ControllerKind::First, comp.clone(), drives(6, 10.0, 0.0)).unwrap_err();
    assert_eq!(
        err,
        BuildError::NoFrictionEstimates(FrictionUse::Compensation)
    );
    build_with(ControllerKind::First, comp, drives(6, 10.0, 0.5)).unwrap();
    let obs = MpcSettings {
        state_observer: true,
        observer_friction: true,
        ..Default::default()
    };
    let err = build_with(ControllerKind::First, obs, drives(6, 10.0, 0.0)).unwrap_err();
    assert_eq!(err, BuildError::NoFrictionEstimates(FrictionUse::Observer));
}

#[test]
fn refuses_observer_settings_that_would_do_nothing() {
    let robot = Robot::irb140();
    let s = MpcSettings {
        observer_friction: true,
        ..Default::default()
    };
    assert_eq!(
        build(ControllerKind::Second, s),
        Err(BuildError::ObserverFrictionWithoutObserver)
    );
    let err = ControllerBuilder::new(ControllerKind::Second, &robot)
        .observer(ObserverSettings::default())
        .build()
        .unwrap_err();
    assert_eq!(err, BuildError::ObserverNotEnabled);
    let delay = MpcSettings {
        delay_compensation: true,
        ..Default::default()
    };
    assert_eq!(
        build(ControllerKind::Second, delay.clone()),
        Err(BuildError::MeasurementDelayUnknown)
    );
    let err = ControllerBuilder::new(ControllerKind::Second, &robot)
        .settings(delay.clone())
        .observer(ObserverSettings {
            pole: 1.0,
            measurement_delay: 1,
        })
        .build()
        .unwrap_err();
    assert_eq!(err, BuildError::ObserverPole(1.0));
    let mpc = ControllerBuilder::new(ControllerKind::Second, &robot)
        .settings(delay)
        .observer(ObserverSettings {
            pole: 0.7,
            measurement_delay: 1,
        })
        .build()
        .unwrap();
    assert!(mpc.observer().is_some());
}

#[test]
fn refuses_parts_that_would_not_be_used() {
    let robot = Robot::irb140();
    let err = ControllerBuilder::new(ControllerKind::Usual, &robot)
        .drives(drives(6, 10.0, 0.5))
        .build()
        .unwrap_err();
    assert_eq!(err, BuildError::DrivesUnused);
    let s = MpcSettings {
        constraint_horizon: Some(3),
        ..Default::default()
    };
    assert_eq!(
        build(ControllerKind::First, s),
        Err(BuildError::ConstraintHorizonWithoutLimits(3))
    );
    let err = ControllerBuilder::new(ControllerKind::Second, &robot)
        .estimator(RlsSettings::default())
        .build()
        .unwrap_err();
    assert_eq!(
        err,
        BuildError::EstimatorWithoutIdentification(ControllerKind::Second)
    );
}

#[test]
fn refuses_a_payload_model_the_identification_would_replace() {
    let assumed = MpcSettings {
        model_payload_kg: 0.25,
        ..Default::default()
    };
    assert_eq!(
        build(ControllerKind::FirstAdaptive, assumed.clone()),
        Err(BuildError::PayloadWithIdentification {
            kind: ControllerKind::FirstAdaptive,
            mass: 0.25
        })
    );
    let mut loaded = Robot::irb140();
    loaded.set_payload(Some(Payload::point_mass(0.5))).unwrap();
    let err = ControllerBuilder::new(ControllerKind::SecondAdaptive, &loaded)
        .build()
        .unwrap_err();
    assert_eq!(
        err,
        BuildError::PayloadWithIdentification {
            kind: ControllerKind::SecondAdaptive,
            mass: 0.5
        }
    );
    let err = ControllerBuilder::new(ControllerKind::Second, &loaded)
        .settings(assumed.clone())
        .build()
        .unwrap_err();
    assert_eq!(
        err,
        BuildError::TwoPayloads {
            carried: 0.5,
            assumed: 0.25
        }
    );
    // A plain kind: the model carries the assumed payload.
    let mpc = ControllerBuilder::new(ControllerKind::Second, &Robot::irb140())
        .settings(assumed)
        .build()
        .unwrap();
    assert_eq!(mpc.model().robot().payload().map(|p| p.mass), Some(0.25));
    // An adaptive kind with its estimator's tuning builds.
    ControllerBuilder::new(ControllerKind::FirstAdaptive, &Robot::irb140())
        .estimator(RlsSettings::default())
        .build()
        .unwrap();
}

/// The old path's silent fallback is gone: torque limits (or friction
/// compensation) without a drive model refuse to step.
#[test]
fn old_path_refuses_to_step_without_its_drive_model() {
    let robot = Robot::irb140();
    let reference = paper_reference(&robot);
    let n = robot.dof();
    for s in [
        MpcSettings {
            torque_limits: true,
            ..Default::default()
        },
        MpcSettings {
            friction_compensation: true,
            ..Default::default()
        },
    ] {
        for kind in ControllerKind::WITH_ADAPTIVE {
            let mut c = new_controller(kind, n, &s).unwrap();
            let mut model = RobotDynamics::new(robot.clone());
            let x: Vec<f64> = [reference.q(0), &vec![0.0; n]].concat();
            c.reset(&x).unwrap();
            let mut preview = vec![0.0; s.horizon * n];
            reference.preview(0, s.horizon, &mut preview);
            let mut tau = vec![0.0; n];
            let r = c.step(
                &mut model,
                &ofmpc::control::StepInput {
                    x: &x,
                    w_k: reference.q(0),
                    preview: &preview,
                },
                &mut tau,
            );
            assert_eq!(r, Err(StepFailure::NoDriveModel), "{kind}");
            c.set_drive_model(&DriveModel::from_robot(&robot)).unwrap();
            c.step(
                &mut model,
                &ofmpc::control::StepInput {
                    x: &x,
                    w_k: reference.q(0),
                    preview: &preview,
                },
                &mut tau,
            )
            .unwrap();
        }
    }
}

/// A deterministic measured state near the reference at sample `k`.
fn measured(reference: &ofmpc::motion::JointReference, k: usize, x: &mut [f64]) {
    let n = reference.dof();
    for i in 0..n {
        let s = (0.37 * k as f64 + i as f64).sin();
        x[i] = reference.q(k)[i] + 2e-4 * s;
        x[n + i] = reference.qd(k)[i] * (1.0 + 1e-2 * s);
    }
}

/// Steps the built `Controller` and the old path side by side along the paper's
/// path; every torque, cost and status must agree bit for bit.
fn same_as_old_path(kind: ControllerKind, settings: &MpcSettings, drives: Option<&DriveModel>) {
    let robot = Robot::irb140();
    let reference = paper_reference(&robot);
    let n = robot.dof();
    let nh = settings.horizon;
    let mut builder = ControllerBuilder::new(kind, &robot).settings(settings.clone());
    if let Some(d) = drives {
        builder = builder.drives(d.clone());
    }
    let mut mpc = builder.build().unwrap();
    let mut old = new_controller(kind, n, settings).unwrap();
    if let Some(d) = drives {
        old.set_drive_model(d).unwrap();
    }
    let mut model = RobotDynamics::new(robot.clone());
    let mut x = vec![0.0; 2 * n];
    let mut preview = vec![0.0; nh * n];
    let mut tau = vec![0.0; n];
    measured(&reference, 0, &mut x);
    mpc.reset(&x).unwrap();
    old.reset(&x).unwrap();
    for k in 0..reference.len() {
        measured(&reference, k, &mut x);
        reference.preview(k, nh, &mut preview);
        let w = reference.q(k);
        let info = old
            .step(
                &mut model,
                &ofmpc::control::StepInput {
                    x: &x,
                    w_k: w,
                    preview: &preview,
                },
                &mut tau,
            )
            .unwrap();
        let out = mpc
            .step(&StepInput {
                x: &x,
                w_k: w,
                preview: &preview,
            })
            .unwrap();
        let bits = |v: &[f64]| v.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&out.tau), bits(&tau), "{kind}, k = {k}");
        assert_eq!(out.cost.to_bits(), info.cost.to_bits(), "{kind}, k = {k}");
        assert_eq!(out.r_diag_ratio.to_bits(), info.r_diag_ratio.to_bits());
        assert_eq!(out.zoh_squarings, info.zoh_squarings);
        assert_eq!(out.qp_status, old.qp_status());
        assert_eq!(out.payload_estimate, old.payload_estimate());
        assert_eq!(mpc.input(), old.input());
        assert_eq!(mpc.increments(), old.increments());
    }
}

#[test]
fn built_controllers_step_bit_for_bit_as_the_old_path_on_the_paper_path() {
    for kind in ControllerKind::WITH_ADAPTIVE {
        same_as_old_path(kind, &MpcSettings::default(), None);
    }
}

#[test]
fn built_controllers_with_drives_step_bit_for_bit_as_the_old_path() {
    // Limits that bind on the paper's path, with friction compensation, on
    // both solvers.
    let d = DriveModel {
        max_torque_nm: vec![8.0, 20.0, 8.0, 2.0, 2.0, 1.0],
        ..drives(6, 1.0, 0.3)
    };
    for solver in [Solver::DenseQr, Solver::Structured] {
        let s = MpcSettings {
            torque_limits: true,
            friction_compensation: true,
            constraint_horizon: Some(4),
            solver,
            ..Default::default()
        };
        for kind in ControllerKind::PAPER {
            same_as_old_path(kind, &s, Some(&d));
        }
    }
}

#[test]
fn reset_restores_the_adaptive_model_and_the_output_reports_the_step() {
    let robot = Robot::irb140();
    let reference = paper_reference(&robot);
    let n = robot.dof();
    let mut mpc = ControllerBuilder::new(ControllerKind::SecondAdaptive, &robot)
        .build()
        .unwrap();
    let mut x = vec![0.0; 2 * n];
    let mut preview = vec![0.0; 10 * n];
    let run = |mpc: &mut ofmpc::control::Controller, x: &mut Vec<f64>, preview: &mut Vec<f64>| {
        measured(&reference, 0, x);
        mpc.reset(x).unwrap();
        let mut taus = Vec::new();
        for k in 0..200 {
            measured(&reference, k, x);
            reference.preview(k, 10, preview);
            let out = mpc
                .step(&StepInput {
                    x,
                    w_k: reference.q(k),
                    preview,
                })
                .unwrap();
            assert!(out.payload_estimate.is_some() && out.qp_status.is_none());
            assert!(out.cost.is_finite() && out.solve_time.as_nanos() > 0);
            taus.extend_from_slice(&out.tau);
        }
        taus
    };
    let first = run(&mut mpc, &mut x, &mut preview);
    let second = run(&mut mpc, &mut x, &mut preview);
    assert_eq!(first, second, "a reset run repeats the first one");
    // A bad input is a typed error and keeps the last output.
    let last = mpc.output().tau.clone();
    let err = mpc
        .step(&StepInput {
            x: &x[1..],
            w_k: reference.q(0),
            preview: &preview,
        })
        .unwrap_err();
    assert!(matches!(err, StepError::WrongLength { what: "x", .. }));
    assert_eq!(mpc.output().tau, last);
}

/// A numerical failure is not an error but a status: the step holds the
/// last torque (`StepStatus::HeldLastTorque`), leaves the controller's state
/// as it was (a twin that never saw the failed sample steps identically
/// afterwards), and stepping before a reset is refused.
#[test]
fn a_numerical_failure_holds_the_last_torque_as_a_status() {
    let robot = Robot::irb140();
    let build = || {
        ControllerBuilder::new(ControllerKind::Second, &robot)
            .build()
            .unwrap()
    };
    let (mut c, mut twin) = (build(), build());
    let n = 6;
    let (x, w) = (vec![0.1; 2 * n], vec![0.2; n]);
    let preview = vec![0.2; c.horizon() * n];
    let input = StepInput {
        x: &x,
        w_k: &w,
        preview: &preview,
    };
    assert_eq!(c.step(&input).unwrap_err(), StepError::NotReset);
    c.reset(&x).unwrap();
    twin.reset(&x).unwrap();
    let held = c.step(&input).unwrap().clone();
    assert_eq!(held.status, StepStatus::Solved);
    assert_eq!(twin.step(&input).unwrap().tau, held.tau);
    // Velocities so large that `f0·Ts` cannot be discretized.
    let mut wild = x.clone();
    wild[n..].fill(1e200);
    let out = c.step(&StepInput { x: &wild, ..input }).unwrap();
    assert!(
        matches!(
            out.status,
            StepStatus::HeldLastTorque(StepFailure::Discretization(_) | StepFailure::Model(_))
        ),
        "{:?}",
        out.status
    );
    assert!(out.status.failure().is_some());
    assert_eq!(out.tau, held.tau, "the last torque is held");
    let after = c.step(&input).unwrap().tau.clone();
    assert_eq!(after, twin.step(&input).unwrap().tau, "state untouched");
}

/// The torques of `built` and `library` stepped side by side over the paper
/// path's first 300 samples (deterministic measurements near the reference),
/// asserted equal bit for bit; returns them.
fn torques_side_by_side(
    built: &mut ofmpc::control::Controller,
    library: &mut dyn ofmpc::control::Algorithm,
) -> Vec<f64> {
    let robot = Robot::irb140();
    let reference = paper_reference(&robot);
    let n = robot.dof();
    let nh = library.horizon();
    let mut model = RobotDynamics::new(robot.clone());
    let (mut x, mut preview, mut tau) = (vec![0.0; 2 * n], vec![0.0; nh * n], vec![0.0; n]);
    measured(&reference, 0, &mut x);
    built.reset(&x).unwrap();
    library.reset(&x).unwrap();
    let mut taus = Vec::new();
    for k in 0..300 {
        measured(&reference, k, &mut x);
        reference.preview(k, nh, &mut preview);
        let w = reference.q(k);
        library
            .step(
                &mut model,
                &ofmpc::control::StepInput {
                    x: &x,
                    w_k: w,
                    preview: &preview,
                },
                &mut tau,
            )
            .unwrap();
        let out = built
            .step(&StepInput {
                x: &x,
                w_k: w,
                preview: &preview,
            })
            .unwrap();
        let bits = |v: &[f64]| v.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&out.tau), bits(&tau), "{}, k = {k}", built.kind());
        taus.extend_from_slice(&tau);
    }
    taus
}

/// Issue #23 item 3: the baselines' bandwidths are their own settings type,
/// given to the builder. Refused for every kind that is not a baseline (it
/// reads none), checked for the robot's joints (all three bandwidths); a
/// baseline built with a bandwidth steps bit for bit as the library's own
/// constructor with it, and unlike the default bandwidth; without
/// `baselines()` the builder uses the defaults (`new_controller`'s).
#[test]
fn baselines_are_refused_for_the_paper_kinds_checked_and_used() {
    let robot = Robot::irb140();
    let n = robot.dof();
    let s = MpcSettings::default();
    for kind in ControllerKind::ALL.into_iter().filter(|k| !k.is_baseline()) {
        let err = ControllerBuilder::new(kind, &robot)
            .baselines(BaselineSettings::default())
            .build()
            .unwrap_err();
        assert_eq!(err, BuildError::BaselinesWithoutBaseline(kind));
        assert!(err.to_string().contains(kind.name()), "{err}");
    }
    let short = BaselineSettings {
        ctc_bandwidth: Weight::Diagonal(vec![100.0; n - 1]),
        ..Default::default()
    };
    let zero = BaselineSettings {
        dob_observer_bandwidth: Weight::Scalar(0.0),
        ..Default::default()
    };
    // The bandwidths of every baseline, 2/3 of the defaults (all stable on the IRB 140).
    let slower = BaselineSettings {
        pid_bandwidth: Weight::Scalar(40.0),
        ctc_bandwidth: Weight::Diagonal(vec![100.0, 100.0, 100.0, 120.0, 120.0, 120.0]),
        dob_observer_bandwidth: Weight::Scalar(66.0),
        ..Default::default()
    };
    for kind in ControllerKind::BASELINES {
        let built = |b: &BaselineSettings| {
            ControllerBuilder::new(kind, &robot)
                .baselines(b.clone())
                .build()
        };
        assert_eq!(
            built(&short).unwrap_err(),
            BuildError::Settings(SettingsError::WeightLength {
                name: "ctc_bandwidth",
                expected: n,
                got: n - 1,
            }),
            "{kind}"
        );
        assert!(
            matches!(
                built(&zero),
                Err(BuildError::Settings(SettingsError::BadBandwidth {
                    name: "dob_observer_bandwidth",
                    ..
                }))
            ),
            "{kind}"
        );
        let mut with = built(&slower).unwrap();
        let mut library = new_controller_with_baselines(kind, n, &s, &slower).unwrap();
        let slow = torques_side_by_side(&mut with, library.as_mut());
        let mut plain = ControllerBuilder::new(kind, &robot).build().unwrap();
        let mut default = new_controller(kind, n, &s).unwrap();
        let fast = torques_side_by_side(&mut plain, default.as_mut());
        assert_ne!(slow, fast, "{kind}: the bandwidth changed nothing");
    }
}
