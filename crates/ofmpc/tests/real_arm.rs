//! Issue 35: the offset-free controllers on a plant that is not the model —
//! one sample of measurement delay, 20-bit encoders with the velocity from
//! their difference, Coulomb [5, 5, 3, 1, 1, 0.5] N·m and viscous
//! [8, 8, 4, 1, 1, 0.5] N·m·s/rad friction known 20 % low, 1e-6 rad position
//! noise, torque limits, every link's inertial parameters 10 % off — on the
//! paper's path at 0, 2 and 6 kg (the IRB 140's rated payload), with the
//! controller keys of `examples/real-arm.toml`: delay and friction
//! compensation, the observer's friction model as the creeping law
//! (`friction_creep`), the payload bound (`max_payload_kg = 9`, 1.5 × rated)
//! and its centre-of-mass bound (`payload_com_max_m = 0.2`), the wrist's
//! stiff hold (`hold_q_du_scale = [1, 1, 1, 0.01, 0.01, 0.01]`, no dead
//! zone) and the baselines' (`ctc_hold_gain_scale = [1, 1, 1, 3, 3, 3]`,
//! `dob_hold_gain_scale = [1, 1, 1, 10, 10, 10]`), `q_du = 1e-4`, `q_u = 1e-5`,
//! and dob-mpc's payload fitted at rest (`dob_identify_at_rest`).
//!
//! The non-adaptive kinds settle 0.4 s at rest before the path
//! (`simulation.settle_s`), as a real controller is engaged at rest; dob-mpc
//! with its fit rests the identification's 0.5 s.
//!
//! Measured (`ofmpc run examples/real-arm.toml`, Cartesian RMS / steady mm at
//! 0/2/6 kg; docs/guide/real-arm.md): steady 0.0022–0.0057 mm for every
//! controller at every payload; RMS first-adaptive 0.063/0.086/0.17,
//! second-adaptive 0.061/0.077/0.16, ctc-adaptive 0.063/0.079/0.17, dob-mpc
//! 0.096/0.106/0.117, first 0.059/0.075/0.14, second 0.057/0.068/0.12; the hold
//! within 2 encoder counts ("ok") for every run (dob-mpc at 6 kg hunted by 4
//! counts before its fit at rest); estimates within 0.42 kg (dob-mpc's fit
//! 0.28/2.43/5.79 kg).

mod common;

use ofmpc::control::{BaselineSettings, ControllerKind, MpcSettings, Weight};
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
    /// Every link's inertial parameters 10 % off (`plant.inertia_error`).
    model_error: bool,
}

const ALL: Effects = Effects {
    delay: true,
    encoder: true,
    friction: true,
    noise: true,
    model_error: true,
};

/// The preset's settling at rest before the path (`simulation.settle_s`).
const SETTLE_S: f64 = 0.4;

fn run(kind: ControllerKind, mass: f64, fx: Effects) -> RunMetrics {
    run_settled(kind, mass, fx, SETTLE_S)
}

/// [`run`] with `settle_s` of settling at rest (the non-adaptive kinds).
fn run_settled(kind: ControllerKind, mass: f64, fx: Effects, settle_s: f64) -> RunMetrics {
    run_with(kind, mass, fx, settle_s, true)
}

/// [`run_settled`] with `dob-mpc`'s identification at rest on (the preset)
/// or off (`identify`).
fn run_with(
    kind: ControllerKind,
    mass: f64,
    fx: Effects,
    settle_s: f64,
    identify: bool,
) -> RunMetrics {
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
            friction_creep: fx.friction && observed,
            max_payload_kg: 9.0,
            payload_com_max_m: 0.2,
            // As the preset: no dead zone, the wrist's stiff hold at rest.
            hold_q_du_scale: Weight::Diagonal(vec![1.0, 1.0, 1.0, 0.01, 0.01, 0.01]),
            q_du: Weight::Scalar(1e-4),
            q_u: Weight::Scalar(1e-5),
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
            inertia_error: if fx.model_error { 0.1 } else { 0.0 },
            // As the preset: resolves the friction's sticking.
            substep: if fx.friction {
                2e-4
            } else {
                PlantSettings::default().substep
            },
            ..Default::default()
        },
        // As the preset: every kind that does not identify settles at rest first.
        loop_settings: LoopSettings {
            settle_s,
            ..Default::default()
        },
        // As the preset: the baselines' stiffer hold on the wrist, and
        // dob-mpc's payload from its hold at rest.
        baselines: BaselineSettings {
            ctc_hold_gain_scale: Weight::Diagonal(vec![1.0, 1.0, 1.0, 3.0, 3.0, 3.0]),
            dob_hold_gain_scale: Weight::Diagonal(vec![1.0, 1.0, 1.0, 10.0, 10.0, 10.0]),
            dob_identify_at_rest: identify,
            ..Default::default()
        },
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
    // The hold's judgement (tests/real_arm_rates.rs) calls a wrist's limit
    // cycle "hunting"; where the controllers settle it the callers require
    // "ok" (`holds_with_all_effects`), elsewhere (docs/guide/real-arm.md):
    // completed, within the bounds.
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

/// `kind` with every effect at 0, 2 and 6 kg: status "ok", steady error at
/// most 0.01 mm (about two encoder counts at the flange), RMS at most
/// `rms_mm[i]` at payload `i`, an adaptive estimate within 10 % of the rated
/// payload.
fn holds_with_all_effects(kind: ControllerKind, rms_mm: [f64; 3], settles: [bool; 3]) {
    for ((mass, rms), settle) in [0.0, 2.0, 6.0].into_iter().zip(rms_mm).zip(settles) {
        let m = run(kind, mass, ALL);
        eprintln!(
            "all {}: {:?} RMS {:.4} steady {:.4} est {:?}",
            m.name,
            m.status,
            m.cartesian_error_rms_mm,
            m.steady_cartesian_error_mm,
            m.payload_estimate_kg
        );
        check(&m, mass, 0.01, rms);
        if settle {
            // The hold settles within 2 encoder counts peak-to-peak.
            assert_eq!(m.status, RunStatus::Ok, "{}: {}", m.name, m.reason);
            assert!(m.hold_error_pp_counts.is_some_and(|pp| pp <= 2.0 + 1e-6));
        }
        if kind.is_adaptive() || kind == ControllerKind::DobMpc {
            assert!(m.payload_estimate_kg.is_some(), "{}", m.name);
        }
    }
}

// The targets (RMS ≤ 0.25 mm) for every kind at every payload,
// with the non-adaptive kinds settled 0.4 s at rest before the path
// (`the_settling_at_rest_carries_the_start`).

#[test]
fn first_adaptive_holds_with_all_effects() {
    holds_with_all_effects(ControllerKind::FirstAdaptive, [0.25, 0.25, 0.25], [true; 3]);
}

#[test]
fn second_adaptive_holds_with_all_effects() {
    holds_with_all_effects(
        ControllerKind::SecondAdaptive,
        [0.25, 0.25, 0.25],
        [true; 3],
    );
}

#[test]
fn ctc_adaptive_holds_with_all_effects() {
    // The wrist's kp × 3 at a creeping hold: within 2 counts (4–8 without).
    holds_with_all_effects(ControllerKind::CtcAdaptive, [0.25, 0.25, 0.25], [true; 3]);
}

#[test]
fn dob_mpc_holds_with_all_effects() {
    // The wrist's stiffer hold (q_u ÷ 10, observer × 10) and the payload
    // fitted at rest (`dob_identify_at_rest`): within 2 counts at every
    // payload, RMS 0.096 / 0.106 / 0.117 mm, estimates 0.28 / 2.43 / 5.79 kg
    // (the fit also takes in the links' gravity error, `inertia_error`).
    holds_with_all_effects(ControllerKind::DobMpc, [0.15, 0.15, 0.15], [true; 3]);
}

/// Without its payload fitted at rest, dob-mpc's model keeps the nominal
/// 0 kg: at 6 kg its wrist rings by 4 counts over the hold ("hunting") and
/// the RMS is 0.22 mm; with the fit "ok" (2 counts) and 0.12 mm
/// (`dob_mpc_holds_with_all_effects`). Its rest is the identification's
/// (0.5 s) with the fit, the settling's (0.4 s) without.
#[test]
fn without_its_fit_at_rest_dob_mpc_hunts_at_6_kg() {
    let m = run_with(ControllerKind::DobMpc, 6.0, ALL, SETTLE_S, false);
    eprintln!(
        "{}: {:?} RMS {:.4} hold {:?} est {:?}",
        m.name, m.status, m.cartesian_error_rms_mm, m.hold_error_pp_counts, m.payload_estimate_kg
    );
    assert_eq!(m.status, RunStatus::Hunting, "{}", m.reason);
    assert!(m.hold_error_pp_counts.unwrap() >= 3.0);
    assert!(
        m.cartesian_error_rms_mm > 0.15,
        "{}",
        m.cartesian_error_rms_mm
    );
    assert_eq!(m.payload_estimate_kg, None, "no estimate without the fit");
}

#[test]
fn first_and_second_hold_with_all_effects() {
    // 6 kg is inside first's stable range (up to 7.1 kg): the target applies.
    holds_with_all_effects(ControllerKind::First, [0.25, 0.25, 0.25], [true; 3]);
    // Settled at rest, second's hold stays within 2 counts at 2 and 6 kg
    // too (3 counts without the settling).
    holds_with_all_effects(ControllerKind::Second, [0.25, 0.25, 0.25], [true; 3]);
}

/// Released under a 6 kg payload the model does not know, the start alone
/// breaks the RMS target (first 0.48 mm, dob-mpc 0.57 mm): the settling at
/// rest carries that transient before the path (0.14 / 0.22 mm), and its
/// peak is reported (`pre_roll_peak_joint_rad`) instead of hidden. The
/// adaptive kinds identify there instead: the settling leaves them as they were.
#[test]
fn the_settling_at_rest_carries_the_start() {
    for kind in [ControllerKind::First, ControllerKind::DobMpc] {
        // dob-mpc as it settles without its fit at rest.
        let released = run_with(kind, 6.0, ALL, 0.0, false);
        let settled = run_with(kind, 6.0, ALL, SETTLE_S, false);
        eprintln!(
            "{}: RMS {:.4} released, {:.4} settled (peak {:.5} rad at rest)",
            settled.name,
            released.cartesian_error_rms_mm,
            settled.cartesian_error_rms_mm,
            settled.pre_roll_peak_joint_rad
        );
        assert!(released.cartesian_error_rms_mm > 0.4, "{}", released.name);
        assert!(settled.cartesian_error_rms_mm <= 0.25, "{}", settled.name);
        assert_eq!(released.pre_roll_peak_joint_rad, 0.0);
        // The transient moved before the path: about 0.01 rad at rest
        // under 6 kg, far above the path's error after the settling.
        assert!(
            (0.005..0.05).contains(&settled.pre_roll_peak_joint_rad),
            "{}: {}",
            settled.name,
            settled.pre_roll_peak_joint_rad
        );
    }
    let adaptive = |settle_s| run_settled(ControllerKind::FirstAdaptive, 6.0, ALL, settle_s);
    let (a, b) = (adaptive(0.0), adaptive(SETTLE_S));
    assert_eq!(
        a.cartesian_error_rms_mm.to_bits(),
        b.cartesian_error_rms_mm.to_bits()
    );
    assert!(
        a.pre_roll_peak_joint_rad > 0.0,
        "the identification's peak is reported too"
    );
}

#[test]
fn the_settling_key_is_validated() {
    for bad in [-0.1, 1.5, f64::NAN] {
        let e = LoopSettings {
            settle_s: bad,
            ..Default::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("settling at rest"), "{e}");
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
            model_error: false,
        },
        Effects {
            delay: false,
            encoder: true,
            friction: false,
            noise: false,
            model_error: false,
        },
        Effects {
            delay: false,
            encoder: false,
            friction: true,
            noise: false,
            model_error: false,
        },
        Effects {
            delay: false,
            encoder: false,
            friction: false,
            noise: true,
            model_error: false,
        },
        Effects {
            delay: false,
            encoder: false,
            friction: false,
            noise: false,
            model_error: true,
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
            // "hunting": the wrist's limit cycle (see `check`).
            if !matches!(m.status, RunStatus::Ok | RunStatus::Hunting)
                || m.steady_cartesian_error_mm > 0.01
                || m.cartesian_error_rms_mm > 0.75
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
        (
            MpcSettings {
                payload_com_max_m: -0.1,
                ..Default::default()
            },
            "centre of mass",
        ),
        (
            MpcSettings {
                hold_q_du_scale: Weight::Diagonal(vec![1.0, 0.0]),
                ..Default::default()
            },
            "hold_q_du_scale",
        ),
        (
            MpcSettings {
                hold_q_du_scale: Weight::Scalar(1.5),
                ..Default::default()
            },
            "within (0, 1]",
        ),
        (
            MpcSettings {
                identification_raw_mass: true,
                ..Default::default()
            },
            "payload_com_max_m > 0",
        ),
        (
            MpcSettings {
                hold_ebar_scale: 1.5,
                ..Default::default()
            },
            "(hold_ebar_scale) is 1.5",
        ),
        (
            MpcSettings {
                hold_ebar_scale: f64::NAN,
                ..Default::default()
            },
            "within [0, 1]",
        ),
        (
            MpcSettings {
                dead_zone_counts: Weight::Diagonal(vec![1.0, 2.0, 0.0]),
                ..Default::default()
            },
            "(dead_zone_counts) is 0 encoder counts at entry 2",
        ),
        (
            MpcSettings {
                dead_zone_counts: Weight::Scalar(f64::INFINITY),
                ..Default::default()
            },
            "finite number > 0",
        ),
    ] {
        let e = s.validate().unwrap_err();
        assert!(e.to_string().contains(what), "{e}");
    }
}

#[test]
fn the_baselines_hold_keys_are_validated() {
    use ofmpc::control::new_controller_with_baselines;
    let mpc = MpcSettings::default();
    for (b, what) in [
        (
            BaselineSettings {
                ctc_hold_gain_scale: Weight::Scalar(0.5),
                ..Default::default()
            },
            "ctc_hold_gain_scale) is 0.5 at entry 0",
        ),
        (
            BaselineSettings {
                dob_hold_gain_scale: Weight::Diagonal(vec![1.0, 1.0, 1.0, 1.0, 1.0, f64::NAN]),
                ..Default::default()
            },
            "dob_hold_gain_scale) is NaN at entry 5",
        ),
        (
            BaselineSettings {
                ctc_hold_gain_scale: Weight::Diagonal(vec![1.0, 2.0]),
                ..Default::default()
            },
            "ctc_hold_gain_scale",
        ),
    ] {
        let e = b.validate_for_dof(6).unwrap_err();
        assert!(e.to_string().contains(what), "{e}");
        for kind in [ControllerKind::CtcAdaptive, ControllerKind::DobMpc] {
            let named = if what.starts_with("ctc") {
                kind == ControllerKind::CtcAdaptive
            } else {
                kind == ControllerKind::DobMpc
            };
            // The controller that reads the key refuses to build.
            if named {
                let e = new_controller_with_baselines(kind, 6, &mpc, &b)
                    .err()
                    .unwrap();
                assert!(e.to_string().contains(&what[..19]), "{e}");
            }
        }
    }
    // dob-mpc's stiffer hold weights its inner MPC per sample: the dense solver.
    let b = BaselineSettings {
        dob_hold_gain_scale: Weight::Scalar(10.0),
        ..Default::default()
    };
    let structured = MpcSettings {
        solver: ofmpc::control::Solver::Structured,
        ..Default::default()
    };
    let e = new_controller_with_baselines(ControllerKind::DobMpc, 6, &structured, &b)
        .err()
        .unwrap();
    assert!(e.to_string().contains("dense solver"), "{e}");
    assert!(new_controller_with_baselines(ControllerKind::DobMpc, 6, &mpc, &b).is_ok());
}

/// dob-mpc's fit at rest needs a mass bound; the other kinds do not read
/// the key.
#[test]
fn the_fit_at_rest_key_is_validated() {
    use ofmpc::control::new_controller_with_baselines;
    let identify = BaselineSettings {
        dob_identify_at_rest: true,
        ..Default::default()
    };
    let e = new_controller_with_baselines(
        ControllerKind::DobMpc,
        6,
        &MpcSettings::default(),
        &identify,
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("max_payload_kg > 0"), "{e}");
    let bounded = MpcSettings {
        max_payload_kg: 9.0,
        ..Default::default()
    };
    assert!(new_controller_with_baselines(ControllerKind::DobMpc, 6, &bounded, &identify).is_ok());
    for kind in [
        ControllerKind::Ctc,
        ControllerKind::Pid,
        ControllerKind::First,
    ] {
        let mpc = MpcSettings::default();
        assert!(
            new_controller_with_baselines(kind, 6, &mpc, &identify).is_ok(),
            "{kind}"
        );
    }
}
