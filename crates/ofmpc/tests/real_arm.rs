//! Issue 35: the offset-free controllers on a plant that is not the model —
//! one sample of measurement delay, 20-bit encoders with the velocity from
//! their difference, Coulomb [5, 5, 3, 1, 1, 0.5] N·m and viscous
//! [8, 8, 4, 1, 1, 0.5] N·m·s/rad friction known 20 % low, 1e-6 rad position
//! noise, torque limits — on the paper's path at 0, 2 and 6 kg (the IRB 140's
//! rated payload), with the real-arm settings: delay and friction
//! compensation, the observer's friction model, the payload bound
//! (`mpc.max_payload_kg = 9`, 1.5 × rated) and the hold dead zone
//! (`mpc.encoder_counts`).
//!
//! Measured (the same set-up as `ofmpc run` of the probe with these keys,
//! Cartesian RMS / steady mm at 0/2/6 kg; docs/guide/real-arm.md): every run
//! "ok", payload estimates within 0.01 kg; steady first 0.020/0.022/0.028,
//! second 0.18/0.14/0.15, first-adaptive 0.018/0.032/0.050, second-adaptive
//! 0.18/0.22/0.14, ctc-adaptive 0.015/0.014/0.012, dob-mpc 0.050/0.044/0.046;
//! RMS at most 0.75 mm (dob-mpc at 6 kg). Each effect alone, the adaptive
//! kinds at 2 kg: steady ≤ 0.009 mm, estimates within 0.04 kg. Before (main):
//! the three adaptive kinds diverged at every payload.

mod common;

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{Experiment, LoopSettings, PlantSettings, RunMetrics, RunStatus};

const COULOMB: [f64; 6] = [5.0, 5.0, 3.0, 1.0, 1.0, 0.5];
const VISCOUS: [f64; 6] = [8.0, 8.0, 4.0, 1.0, 1.0, 0.5];

/// Which of the real arm's effects the plant has.
#[derive(Clone, Copy, Debug)]
struct Effects {
    delay: bool,
    encoder: bool,
    friction: bool,
    noise: bool,
}

const ALL: Effects = Effects {
    delay: true,
    encoder: true,
    friction: true,
    noise: true,
};

fn run(kind: ControllerKind, mass: f64, fx: Effects) -> RunMetrics {
    let mut robot = Robot::irb140();
    // The drives file: friction estimates 20 % below the plant's.
    let text: String = (0..6)
        .map(|j| {
            format!(
                "[joints.joint_{}]\ncoulomb_nm = {}\nviscous_nms = {}\n",
                j + 1,
                0.8 * COULOMB[j],
                0.8 * VISCOUS[j]
            )
        })
        .collect();
    robot
        .apply_drives(&Drives::from_toml_str(&text).unwrap())
        .unwrap();
    let reference = common::paper_reference(&robot);
    let observed = fx.delay || fx.encoder || fx.noise;
    let exp = Experiment {
        conditions: Default::default(),
        robot,
        reference,
        mpc: MpcSettings {
            torque_limits: true,
            friction_compensation: fx.friction,
            delay_compensation: fx.delay,
            state_observer: observed,
            observer_friction: fx.friction && observed,
            max_payload_kg: 9.0,
            encoder_counts: if fx.encoder { 1_048_576.0 } else { 0.0 },
            ..Default::default()
        },
        plant: PlantSettings {
            torque_limits: true,
            coulomb_friction: if fx.friction {
                COULOMB.to_vec()
            } else {
                vec![]
            },
            viscous_friction: if fx.friction {
                VISCOUS.to_vec()
            } else {
                vec![]
            },
            encoder_counts: if fx.encoder { 1_048_576 } else { 0 },
            velocity_from_encoder: fx.encoder,
            position_noise: if fx.noise { 1e-6 } else { 0.0 },
            delay_samples: usize::from(fx.delay),
            ..Default::default()
        },
        loop_settings: LoopSettings::default(),
        baselines: Default::default(),
    };
    let (_, m) = exp
        .run(kind, &Payload::point_mass(mass), &mut |_, _| {})
        .unwrap();
    m
}

const ADAPTIVE: [ControllerKind; 3] = [
    ControllerKind::FirstAdaptive,
    ControllerKind::SecondAdaptive,
    ControllerKind::CtcAdaptive,
];

fn check(m: &RunMetrics, mass: f64, steady_mm: f64, rms_mm: f64) {
    // The hold's judgement (tests/real_arm_rates.rs) calls the wrist's limit
    // cycle "hunting"; settling it is the controllers' part (what is left in
    // docs/guide/real-arm.md): completed, within the bounds.
    assert!(
        matches!(m.status, RunStatus::Ok | RunStatus::Hunting),
        "{}: {}",
        m.name,
        m.reason
    );
    assert!(!m.diverged, "{}", m.name);
    assert!(
        m.steady_cartesian_error_mm <= steady_mm,
        "{}: steady {} mm",
        m.name,
        m.steady_cartesian_error_mm
    );
    assert!(
        m.cartesian_error_rms_mm <= rms_mm,
        "{}: RMS {} mm",
        m.name,
        m.cartesian_error_rms_mm
    );
    if let Some(est) = m.payload_estimate_kg {
        // Within 10 % of the rated payload (6 kg).
        assert!((est - mass).abs() <= 0.6, "{}: estimate {est} kg", m.name);
    }
}

#[test]
fn every_offset_free_controller_holds_with_all_effects_at_0_2_6_kg() {
    for kind in [
        ControllerKind::First,
        ControllerKind::Second,
        ControllerKind::FirstAdaptive,
        ControllerKind::SecondAdaptive,
        ControllerKind::CtcAdaptive,
        ControllerKind::DobMpc,
    ] {
        for mass in [0.0, 2.0, 6.0] {
            let m = run(kind, mass, ALL);
            eprintln!(
                "all {}: {:?} RMS {:.4} steady {:.4} est {:?}",
                m.name,
                m.status,
                m.cartesian_error_rms_mm,
                m.steady_cartesian_error_mm,
                m.payload_estimate_kg
            );
            check(&m, mass, 0.3, 1.0);
            if kind.is_adaptive() {
                assert!(m.payload_estimate_kg.is_some(), "{}", m.name);
            }
        }
    }
}

#[test]
fn the_adaptive_kinds_identify_under_each_effect_alone() {
    let alone = [
        Effects {
            delay: true,
            encoder: false,
            friction: false,
            noise: false,
        },
        Effects {
            delay: false,
            encoder: true,
            friction: false,
            noise: false,
        },
        Effects {
            delay: false,
            encoder: false,
            friction: true,
            noise: false,
        },
        Effects {
            delay: false,
            encoder: false,
            friction: false,
            noise: true,
        },
    ];
    let mut failed = Vec::new();
    for fx in alone {
        for kind in ADAPTIVE {
            let m = run(kind, 2.0, fx);
            eprintln!(
                "{fx:?} {}: {:?} RMS {:.4} steady {:.4} est {:?}",
                m.name,
                m.status,
                m.cartesian_error_rms_mm,
                m.steady_cartesian_error_mm,
                m.payload_estimate_kg
            );
            if !matches!(m.status, RunStatus::Ok | RunStatus::Hunting)
                || m.steady_cartesian_error_mm > 0.25
                || m.cartesian_error_rms_mm > 1.5
                || m.payload_estimate_kg.is_none_or(|e| (e - 2.0).abs() > 0.6)
            {
                failed.push(format!("{fx:?} {}", m.name));
            }
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}

#[test]
fn the_real_arm_keys_are_validated() {
    for (s, what) in [
        (
            MpcSettings {
                max_payload_kg: -1.0,
                ..Default::default()
            },
            "max_payload_kg",
        ),
        (
            MpcSettings {
                encoder_counts: f64::NAN,
                ..Default::default()
            },
            "encoder_counts",
        ),
    ] {
        let e = s.validate().unwrap_err();
        assert!(e.to_string().contains(what), "{e}");
    }
}
