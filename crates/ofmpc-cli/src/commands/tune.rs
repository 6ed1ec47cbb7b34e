//! `ofmpc tune`: robust tuning of the non-adaptive controllers over a payload
//! range, written as a complete scenario file.
//!
//! 1. For each weight pair `(Q_Δy, Q_Δu)` of a grid (`Q_yw = I`, `Q_u` as
//!    given) and each controller, the α interval near rest at the program's
//!    first point ([`ofmpc::analysis::alpha_interval`]).
//! 2. For each pair, the payload the model should assume: on a grid over the
//!    range, the one whose inertia ratios along the program, for the lightest
//!    and the heaviest payload, stay inside every controller's interval with
//!    the largest margin `min(ln(α_min/lo), ln(hi/α_max))`.
//! 3. The candidates with a positive margin are simulated along the program
//!    at the range's ends and middle; the tuning with the least worst RMS
//!    Cartesian error among the runs that completed offset-free wins.

use super::analyze::{scenario_file, SetupArgs};
use crate::output::atomic::write_atomic;
use crate::output::plot::{render_both, Figure, Panel, Series, COLOR_FIRST, COLOR_SECOND};
use crate::scenario::Scenario;
use anyhow::{bail, Context};
use clap::Args;
use ofmpc::analysis::{alpha_interval, inertia_ratio_range, StabilityOptions};
use ofmpc::control::{MpcSettings, Weight};
use ofmpc::robot::Payload;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// `ofmpc tune`
#[derive(Debug, Args)]
pub struct TuneArgs {
    /// Robot and program.
    #[command(flatten)]
    pub setup: SetupArgs,
    /// Payload range LO,HI in kg (point mass at the flange).
    #[arg(long)]
    pub payload_range: String,
    /// Controllers to tune for, comma-separated (usual, first, second).
    #[arg(long, default_value = "first,second")]
    pub controllers: String,
    /// The scenario file to write (TOML).
    #[arg(long)]
    pub out: PathBuf,
}

const Q_DY: [f64; 3] = [0.1, 0.5, 2.0];
const Q_DU: [f64; 5] = [1e-5, 1e-4, 1e-3, 1e-2, 1e-1];
const MODEL_GRID: usize = 13;

#[derive(Debug, Clone)]
struct Candidate {
    q_dy: f64,
    q_du: f64,
    model_payload: f64,
    margin: f64,
    rms_mm: f64,
    offset_free: bool,
}

/// An absolute path where it exists, so that the scenario written elsewhere
/// still finds it.
fn absolute(p: &Path) -> PathBuf {
    std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf())
}

/// Runs `ofmpc tune`.
pub fn tune(a: &TuneArgs) -> anyhow::Result<()> {
    let range = super::parse_vector("--payload-range", &a.payload_range, Some(2))?;
    let (lo_kg, hi_kg) = (range[0], range[1]);
    if !(lo_kg >= 0.0 && hi_kg >= lo_kg) {
        bail!("--payload-range {lo_kg},{hi_kg}: give LO,HI with 0 ≤ LO ≤ HI (kg)");
    }
    let kinds = super::parse_controllers("--controllers", &a.controllers)?;
    if let Some(k) = kinds.iter().find(|k| k.is_adaptive()) {
        bail!("--controllers {k}: tune the non-adaptive controllers (the adaptive ones identify the payload)");
    }
    let mut setup = a.setup.clone();
    if setup.robot.ends_with(".urdf") || Path::new(&setup.robot).is_file() {
        setup.robot = absolute(Path::new(&setup.robot)).display().to_string();
    }
    setup.drives = setup.drives.as_deref().map(absolute);
    setup.program = setup.program.as_deref().map(absolute);
    let base = Scenario::resolve(&scenario_file(&setup, MpcSettings::default())?)?;
    let exp = &base.experiment;
    let q0 = exp.reference.q(0).to_vec();
    let poses: Vec<&[f64]> = (0..exp.reference.len())
        .step_by(10)
        .map(|k| exp.reference.q(k))
        .collect();
    let opts = StabilityOptions {
        tolerance: 4e-3,
        ..Default::default()
    };
    let pairs: Vec<(f64, f64)> = Q_DY
        .iter()
        .flat_map(|&d| Q_DU.iter().map(move |&u| (d, u)))
        .collect();
    let settings_of = |q_dy: f64, q_du: f64, m: f64| MpcSettings {
        q_dy: Weight::Scalar(q_dy),
        q_du: Weight::Scalar(q_du),
        model_payload_kg: m,
        ..MpcSettings::default()
    };
    // 1. Intervals per weight pair (the intersection over the controllers).
    let intervals: Vec<Option<(f64, f64)>> = pairs
        .par_iter()
        .map(|&(d, u)| {
            let s = settings_of(d, u, 0.0);
            let mut iv = (0.0f64, f64::INFINITY);
            for &k in &kinds {
                match alpha_interval(&exp.robot, k, &s, &q0, &opts) {
                    Ok((lo, hi)) => iv = (iv.0.max(lo), iv.1.min(hi)),
                    Err(_) => return None,
                }
            }
            Some(iv)
        })
        .collect();
    // 2. The model payload with the largest margin per pair.
    let mut candidates = Vec::new();
    for (&(d, u), iv) in pairs.iter().zip(&intervals) {
        let Some((lo, hi)) = *iv else { continue };
        let mut best: Option<(f64, f64)> = None;
        for i in 0..MODEL_GRID {
            let m = lo_kg + (hi_kg - lo_kg) * i as f64 / (MODEL_GRID - 1) as f64;
            let mut model = exp.robot.clone();
            if m > 0.0 {
                model.set_payload(Some(Payload::point_mass(m)))?;
            }
            let mut amin = f64::INFINITY;
            let mut amax = f64::NEG_INFINITY;
            for p in [lo_kg, hi_kg] {
                let (a0, a1) = inertia_ratio_range(&model, &Payload::point_mass(p), &poses)?;
                amin = amin.min(a0);
                amax = amax.max(a1);
            }
            let margin = (amin / lo).ln().min((hi / amax).ln());
            if !matches!(best, Some((_, b)) if b >= margin) {
                best = Some((m, margin));
            }
        }
        if let Some((m, margin)) = best {
            candidates.push(Candidate {
                q_dy: d,
                q_du: u,
                model_payload: m,
                margin,
                rms_mm: f64::NAN,
                offset_free: false,
            });
        }
    }
    // 3. Simulate the stable candidates at the range's ends and middle.
    let masses = [lo_kg, 0.5 * (lo_kg + hi_kg), hi_kg];
    candidates
        .par_iter_mut()
        .filter(|c| c.margin > 0.0)
        .for_each(|c| {
            let mut e = exp.clone();
            e.mpc = settings_of(c.q_dy, c.q_du, c.model_payload);
            let mut worst = 0.0f64;
            let mut ok = true;
            for &k in &kinds {
                for &m in &masses {
                    match e.run(k, &Payload::point_mass(m), &mut |_, _| {}) {
                        Ok((r, metrics)) => {
                            let steady = metrics
                                .steady_joint_error_max_rad
                                .iter()
                                .copied()
                                .fold(0.0, f64::max);
                            ok &= r.outcome.is_completed() && steady <= 1e-9;
                            worst = worst.max(metrics.cartesian_error_rms_mm);
                        }
                        Err(_) => ok = false,
                    }
                }
            }
            c.rms_mm = worst;
            c.offset_free = ok;
        });
    let chosen = candidates
        .iter()
        .filter(|c| c.offset_free)
        .min_by(|a, b| a.rms_mm.total_cmp(&b.rms_mm))
        .cloned()
        .with_context(|| {
            format!(
                "no tuning of the grid keeps {} stable and offset-free over {lo_kg}..{hi_kg} kg on this robot and program: narrow the payload range",
                a.controllers
            )
        })?;
    // The scenario file.
    let mut file = base.file.clone();
    file.title = format!(
        "Robust tuning for {lo_kg}..{hi_kg} kg: Q_Δy = {}, Q_Δu = {}, model payload {} kg",
        chosen.q_dy, chosen.q_du, chosen.model_payload
    );
    file.controllers = kinds.clone();
    file.mpc = settings_of(chosen.q_dy, chosen.q_du, chosen.model_payload);
    file.payload.masses_kg = (0..=4)
        .map(|i| lo_kg + (hi_kg - lo_kg) * i as f64 / 4.0)
        .collect();
    let text = format!(
        "# Written by `ofmpc tune --payload-range {lo_kg},{hi_kg}`: `ofmpc run` this file.\n\
         # Stability margin (min over the range of ln(α/α_lo), ln(α_hi/α)): {:.3}; worst RMS Cartesian error \
         over {lo_kg}, {}, {hi_kg} kg: {:.4} mm.\n{}",
        chosen.margin,
        masses[1],
        chosen.rms_mm,
        toml::to_string(&file).context("writing the scenario")?
    );
    write_atomic(&a.out, text.as_bytes())
        .with_context(|| format!("writing {}", a.out.display()))?;
    // The trade-off figure beside it.
    let fig = tradeoff_figure(&candidates, &chosen);
    let r = render_both(&fig).context("rendering the trade-off figure")?;
    let stem = a.out.with_extension("");
    let png = PathBuf::from(format!("{}_tradeoff.png", stem.display()));
    let svg = PathBuf::from(format!("{}_tradeoff.svg", stem.display()));
    write_atomic(&png, &r.png).with_context(|| format!("writing {}", png.display()))?;
    write_atomic(&svg, r.svg.as_bytes()).with_context(|| format!("writing {}", svg.display()))?;
    println!(
        "{}",
        serde_json::to_string_pretty(&serde_json::json!({
            "q_dy": chosen.q_dy,
            "q_du": chosen.q_du,
            "model_payload_kg": chosen.model_payload,
            "stability_margin": chosen.margin,
            "worst_rms_mm": chosen.rms_mm,
            "candidates_stable": candidates.iter().filter(|c| c.margin > 0.0).count(),
            "candidates_offset_free": candidates.iter().filter(|c| c.offset_free).count(),
            "scenario": a.out.display().to_string(),
            "figure": png.display().to_string(),
        }))?
    );
    Ok(())
}

fn tradeoff_figure(candidates: &[Candidate], chosen: &Candidate) -> Figure {
    let mut p = Panel::new(
        "robust tuning: stability margin against the worst RMS error",
        "stability margin over the payload range, min ln(α/α_lo), ln(α_hi/α)",
        "worst RMS Cartesian error (mm)",
    );
    p.log_y = true;
    let sim: Vec<&Candidate> = candidates.iter().filter(|c| c.rms_mm.is_finite()).collect();
    let ok: Vec<&&Candidate> = sim.iter().filter(|c| c.offset_free).collect();
    let bad: Vec<&&Candidate> = sim.iter().filter(|c| !c.offset_free).collect();
    p.series.push(Series::markers(
        "offset-free over the range",
        ok.iter().map(|c| c.margin).collect(),
        ok.iter().map(|c| c.rms_mm.max(1e-9)).collect(),
        COLOR_SECOND,
    ));
    if !bad.is_empty() {
        p.series.push(Series::markers(
            "not offset-free (diverged or slow)",
            bad.iter().map(|c| c.margin).collect(),
            bad.iter().map(|c| c.rms_mm.max(1e-9)).collect(),
            COLOR_FIRST,
        ));
    }
    p.series.push(Series::markers(
        "chosen",
        vec![chosen.margin],
        vec![chosen.rms_mm.max(1e-9)],
        0,
    ));
    let mut f = Figure::new("Robust tuning trade-off", 1);
    f.panels.push(p);
    f
}
