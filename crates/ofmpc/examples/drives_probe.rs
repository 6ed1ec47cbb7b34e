//! Probe runs for the drives/sensors issue (#11): prints metrics of variants
//! of the paper's experiment. `cargo run --release -p ofmpc --example drives_probe -- CASE`.
//!
//! Knobs (environment): `NOCHECK` (plausibility check and safe stop off),
//! `QDU`, `QDY` (weights), `HORIZON` (N), `MODEL_PAYLOAD` (kg); for
//! `friction`/`friction-comp`: `FRIC` (the plant's Coulomb friction, N·m,
//! default 1), `VISC0` (viscous estimates 0, as `tests/drives_friction.rs`);
//! `DUMP=j`, `TRACE`, `AROUND=k` print samples; `WIN=k0 WJ=j` (`WLEN`,
//! `WCTRL`, default 60 samples of the second) prints reference, error,
//! velocity and torque of joint j from sample k0; `SUBSTEP` (the plant's
//! RK4 substep, s) and `PLANT_VS` (its Coulomb velocity scale, rad/s);
//! `DELAY` (the plant's measurement delay, samples); `OBSFRIC`
//! (`observer_friction` on); `OBS` (`state_observer` on).

use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::motion::{plan, PlanOptions};
use ofmpc::robot::{Drives, Payload, Robot};
use ofmpc::sim::{Experiment, PlantSettings};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let case = std::env::args().nth(1).unwrap_or_default();
    let mass: f64 = std::env::args()
        .nth(2)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(0.25);
    let scale: f64 = std::env::args()
        .nth(3)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(1.0);
    let mut robot = Robot::irb140();
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
    let mut mpc = MpcSettings::default();
    let mut plant = PlantSettings::default();
    match case.as_str() {
        "limits" | "limits-plant" => {
            // Lower limits: scale of the peak torques.
            let text: String = robot
                .joints()
                .iter()
                .take(1)
                .map(|j| format!("[joints.{}]\nmax_torque_nm = {}\n", j.name, scale))
                .collect();
            robot.apply_drives(&Drives::from_toml_str(&text)?)?;
            plant.torque_limits = true;
            mpc.torque_limits = case == "limits";
        }
        "friction" | "friction-comp" => {
            // FRIC: the plant's Coulomb friction (N·m), 1 by default.
            plant.coulomb_friction = vec![std::env::var("FRIC")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(1.0)];
            if case == "friction-comp" {
                let text: String = robot
                    .joints()
                    .iter()
                    .map(|j| {
                        let visc = if std::env::var_os("VISC0").is_some() {
                            "viscous_nms = 0.0\n"
                        } else {
                            ""
                        };
                        format!("[joints.{}]\ncoulomb_nm = {}\n{visc}", j.name, 0.8 * scale)
                    })
                    .collect();
                robot.apply_drives(&Drives::from_toml_str(&text)?)?;
                mpc.friction_compensation = true;
            }
        }
        "all" => {
            let text: String = robot
                .joints()
                .iter()
                .map(|j| format!("[joints.{}]\ncoulomb_nm = 0.8\nviscous_nms = 0.0\n", j.name))
                .collect();
            robot.apply_drives(&Drives::from_toml_str(&text)?)?;
            mpc.friction_compensation = std::env::var_os("NOCOMP").is_none();
            mpc.torque_limits = true;
            mpc.delay_compensation = true;
            plant.torque_limits = true;
            plant.coulomb_friction = vec![std::env::var("FRIC")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(1.0)];
            plant.encoder_counts = 1 << 22;
            plant.velocity_from_encoder = true;
            plant.delay_samples = 1;
        }
        "sensing" | "sensing-obs" | "sensing-nodelay" => {
            plant.encoder_counts = 1 << 22;
            plant.velocity_from_encoder = true;
            plant.delay_samples = if case == "sensing-nodelay" { 0 } else { 1 };
            mpc.delay_compensation = case != "sensing";
            mpc.state_observer = case != "sensing";
        }
        "glitch" | "dropout" | "glitch-nocheck" | "drop" => {
            let joint: usize = std::env::var("JOINT")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(1);
            let t: f64 = std::env::var("T")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(2.0);
            plant.faults = vec![if case == "drop" {
                ofmpc::sim::Fault::TorqueDrop {
                    t,
                    joint,
                    fraction: 0.0,
                    duration_s: 0.5,
                }
            } else if case.starts_with("glitch") {
                ofmpc::sim::Fault::EncoderGlitch {
                    t,
                    joint,
                    offset_rad: 0.01,
                }
            } else {
                ofmpc::sim::Fault::EncoderDropout {
                    t,
                    joint,
                    duration_s: std::env::var("DUR")
                        .ok()
                        .and_then(|v| v.parse().ok())
                        .unwrap_or(0.3),
                }
            }];
            plant.torque_limits = true;
            mpc.torque_limits = true;
        }
        _ => {}
    }
    if let Some(v) = std::env::var("QDU")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
    {
        mpc.q_du = ofmpc::control::Weight::Scalar(v);
    }
    if let Some(v) = std::env::var("HORIZON")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
    {
        mpc.horizon = v;
    }
    if let Some(v) = std::env::var("MODEL_PAYLOAD")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
    {
        mpc.model_payload_kg = v;
    }
    if let Some(v) = std::env::var("QDY")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
    {
        mpc.q_dy = ofmpc::control::Weight::Scalar(v);
    }
    if let Some(v) = std::env::var("SUBSTEP")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
    {
        plant.substep = v;
    }
    if let Some(v) = std::env::var("PLANT_VS")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
    {
        plant.coulomb_velocity = v;
    }
    if let Some(v) = std::env::var("DELAY")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
    {
        plant.delay_samples = v;
    }
    if std::env::var_os("OBS").is_some() {
        mpc.state_observer = true;
    }
    if std::env::var_os("OBSFRIC").is_some() {
        mpc.observer_friction = true;
    }
    let check = !case.ends_with("nocheck") && std::env::var_os("NOCHECK").is_none();
    println!("path {} s", reference.duration());
    let exp = Experiment {
        robot: robot.clone(),
        reference,
        mpc,
        plant,
        loop_settings: ofmpc::sim::LoopSettings {
            plausibility_check: check,
            safe_stop: check,
            ..Default::default()
        },
    };
    for kind in ControllerKind::ALL {
        let (r, m) = exp.run(kind, &Payload::point_mass(mass), &mut |_, _| {})?;
        let n = 6;
        let mut ratio: f64 = 0.0;
        for k in 0..r.record.len() {
            for i in 0..n {
                ratio = ratio.max(r.record.tau[k * n + i].abs() / robot.joints()[i].limits.effort);
            }
        }
        if let Some(j) = std::env::var("AROUND")
            .ok()
            .and_then(|v| v.parse::<usize>().ok())
        {
            let step: usize = std::env::var("EVERY")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(1);
            for k in (j.saturating_sub(3)..(j + 6 * step).min(r.record.len())).step_by(step) {
                println!(
                    "  k {k} q1 {:.6} qd {:.4?} tau {:.2?}",
                    r.record.q[k * n],
                    &r.record.qd[k * n..k * n + n],
                    &r.record.tau[k * n..k * n + n]
                );
            }
        }
        if let Some(j) = std::env::var("DUMP")
            .ok()
            .and_then(|v| v.parse::<usize>().ok())
        {
            if m.controller == "second" {
                let len = r.record.len();
                for k in len - 40..len {
                    println!(
                        "  k {k} e {:+.3e} qd {:+.3e} tau {:+.4}",
                        r.record.joint_error(k, j - 1),
                        r.record.qd[k * n + j - 1],
                        r.record.tau[k * n + j - 1]
                    );
                }
            }
        }
        if let (Some(k0), Some(j)) = (
            std::env::var("WIN")
                .ok()
                .and_then(|v| v.parse::<usize>().ok()),
            std::env::var("WJ")
                .ok()
                .and_then(|v| v.parse::<usize>().ok()),
        ) {
            // WIN=k0 WJ=j: samples k0..k0+WLEN of joint j (reference, true
            // position and velocity, torque) of the controller WCTRL (second).
            let want = std::env::var("WCTRL").unwrap_or_else(|_| "second".into());
            let len: usize = std::env::var("WLEN")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(60);
            if m.controller == want {
                let i = j - 1;
                for k in k0..(k0 + len).min(r.record.len()) {
                    let w = r.record.q_ref[k * n + i];
                    let wn = r.record.q_ref[((k + 1).min(r.record.len() - 1)) * n + i];
                    println!(
                        "  k {k} w {w:+.6} vref {:+.4e} e {:+.3e} qd {:+.4e} tau {:+.4}",
                        (wn - w) / ts,
                        w - r.record.q[k * n + i],
                        r.record.qd[k * n + i],
                        r.record.tau[k * n + i]
                    );
                }
            }
        }
        if std::env::var_os("ERRLOG").is_some() && m.controller == "second" {
            for k in (0..r.record.len()).step_by(
                std::env::var("EVERY")
                    .ok()
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(5),
            ) {
                let c = r.record.cartesian_error(k);
                let e = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() * 1e3;
                let sat = (0..n).any(|i| {
                    r.record.tau[k * n + i].abs() >= robot.joints()[i].limits.effort * (1.0 - 1e-9)
                });
                println!(
                    "  t {:.2} e {:.4} mm e1 {:+.2e} tau1 {:.2}{}",
                    r.record.t[k],
                    e,
                    r.record.joint_error(k, 0),
                    r.record.tau[k * n],
                    if sat { " SAT" } else { "" }
                );
            }
        }
        if std::env::var_os("TRACE").is_some() {
            let len = r.record.len();
            for i in 0..n {
                let e: Vec<f64> = (len.saturating_sub(200)..len)
                    .map(|k| r.record.joint_error(k, i))
                    .collect();
                let (lo, hi) = e
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
                let qd: f64 = (len.saturating_sub(200)..len)
                    .map(|k| r.record.qd[k * n + i].abs())
                    .fold(0.0, f64::max);
                println!(
                    "  joint {} last 2 s: e in [{lo:.3e}, {hi:.3e}]  max|qd| {qd:.3e}",
                    i + 1
                );
            }
        }
        println!(
            "  saturated_samples {} max_torque_ratio {:.4} faults {}",
            m.saturated_samples, m.max_torque_ratio, m.faults
        );
        println!(
            "{:8} rms {:8.4} mm max {:8.4} mm steady {:10.3e} mm  steady joint {:10.3e}  max|tau|/lim {:.4} tau_max {:?} step {:6.1} us {}",
            m.controller,
            m.cartesian_error_rms_mm,
            m.cartesian_error_max_mm,
            m.steady_cartesian_error_mm,
            m.steady_joint_error_max_rad.iter().cloned().fold(0.0, f64::max),
            ratio,
            m.torque_max_nm.iter().map(|v| (v * 10.0).round() / 10.0).collect::<Vec<_>>(),
            m.step_time_us.median,
            r.outcome
        );
    }
    Ok(())
}
