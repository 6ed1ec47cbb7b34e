//! `ofmpc tune`: robust tuning of the non-adaptive controllers over a payload
//! range, written as a complete scenario file.
//!
//! The search is `ofmpc_scenario::analysis::robust_tuning`; this command
//! parses the options, writes the scenario and the trade-off figure, and
//! prints the choice as JSON.

use super::analyze::{progress, scenario_file};
use crate::cli::TuneArgs;
use crate::output::console;
use crate::output::plot::{
    render_both, Figure, Panel, Series, COLOR_FIRST, COLOR_SECOND, COLOR_USUAL,
};
use anyhow::{bail, Context};
use ofmpc::control::MpcSettings;
use ofmpc_scenario::analysis::{robust_tuning, Candidate, Tuning};
use ofmpc_scenario::Scenario;
use std::path::{Path, PathBuf};

/// The result of `tune` in words (the JSON's fields, explained).
fn tune_words(summary: &serde_json::Value, lo_kg: f64, hi_kg: f64) -> String {
    let f = |k: &str| summary[k].as_f64().unwrap_or(f64::NAN);
    let n = |k: &str| summary[k].as_u64().unwrap_or(0);
    let s = |k: &str| summary[k].as_str().unwrap_or("").to_string();
    let verdict = if f("stability_margin") > 0.0 {
        "every payload of the range stays inside the controllers' stability interval"
    } else {
        "no candidate keeps the whole range stable: this is the best compromise found; narrow \
         the range or use an adaptive controller"
    };
    format!(
        "Tuning for an unknown payload of {lo_kg}–{hi_kg} kg: q_dy = {}, q_du = {}, the model \
         assuming {} kg.\n\
         Stability margin {:.3} (ln of the distance to the interval's ends; > 0 is stable): {verdict}.\n\
         Worst RMS Cartesian error at the range's ends and middle: {:.4} mm.\n\
         Candidates searched: {} stable, {} offset-free over the range, {} stopped early (could \
         not beat the best).\n\
         Written: {} (run it with `ofmpc run {}`) and the trade-off figure {}. `--json` prints the numbers.",
        f("q_dy"),
        f("q_du"),
        f("model_payload_kg"),
        f("stability_margin"),
        f("worst_rms_mm"),
        n("candidates_stable"),
        n("candidates_offset_free"),
        n("candidates_pruned"),
        s("scenario"),
        s("scenario"),
        s("figure"),
    )
}

/// An absolute path where it exists, so that the scenario written elsewhere
/// still finds it.
fn absolute(p: &Path) -> PathBuf {
    std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf())
}

/// The folder of `--out` and the files `tune` writes there: the scenario, `<stem>_tradeoff.png`
/// and `<stem>_tradeoff.svg`.
fn out_files(out: &Path) -> anyhow::Result<(PathBuf, [PathBuf; 3])> {
    let Some(name) = out.file_name() else {
        bail!("--out {}: give the path of a file to write", out.display());
    };
    let folder = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let stem = Path::new(name).with_extension("");
    let stem = stem.display();
    Ok((
        folder,
        [
            PathBuf::from(name),
            PathBuf::from(format!("{stem}_tradeoff.png")),
            PathBuf::from(format!("{stem}_tradeoff.svg")),
        ],
    ))
}

/// The scenario of `tune`'s options with the paper's tuning, its paths absolute (the written
/// scenario then runs from any folder).
fn base_scenario(a: &TuneArgs) -> anyhow::Result<Scenario> {
    let mut setup = a.setup.clone();
    if ofmpc_scenario::is_model_path(&setup.robot) {
        setup.robot = absolute(Path::new(&setup.robot)).display().to_string();
    }
    setup.drives = setup.drives.as_deref().map(absolute);
    setup.program = setup.program.as_deref().map(absolute);
    Ok(Scenario::resolve(&scenario_file(
        &setup,
        MpcSettings::default(),
    )?)?)
}

/// The `tune` summary (stdout, as JSON or in words): the chosen tuning and the search's counts.
fn tune_summary(tuning: &Tuning, chose: &str, out: &Path, png: &Path) -> serde_json::Value {
    let (candidates, chosen) = (&tuning.candidates, &tuning.chosen);
    serde_json::json!({
        "q_dy": chosen.q_dy,
        "q_du": chosen.q_du,
        "wrist_scale": chosen.wrist_scale,
        "controllers": chose,
        "adaptive": tuning.adaptive,
        "model_payload_kg": chosen.model_payload_kg,
        "stability_margin": chosen.margin,
        "worst_rms_mm": chosen.rms_mm,
        "candidates_stable": candidates.iter().filter(|c| c.margin > 0.0).count(),
        "candidates_offset_free": candidates.iter().filter(|c| c.offset_free).count(),
        "candidates_pruned": candidates.iter().filter(|c| c.pruned).count(),
        "scenario": out.display().to_string(),
        "figure": png.display().to_string(),
    })
}

/// The tuned scenario file's text, its header saying how it was found (and a warning when
/// only the adaptive controllers hold the range).
fn scenario_text(
    tuning: &Tuning,
    lo_kg: f64,
    hi_kg: f64,
    controllers: &str,
    chose: &str,
) -> anyhow::Result<String> {
    let (chosen, masses) = (&tuning.chosen, tuning.simulated_kg);
    if tuning.adaptive {
        crate::output::console::warn(&format!(
            "no plain {} tuning (scalar or per-joint weights) holds {lo_kg}..{hi_kg} kg; the scenario runs \
             {chose} (online payload identification), which held every payload simulated",
            controllers
        ));
    }
    let margin_text = if tuning.adaptive {
        "Stability margin of the identified (exact) model, min ln(1/α_lo), ln(α_hi)"
    } else {
        "Stability margin (min over the range of ln(α/α_lo), ln(α_hi/α))"
    };
    Ok(format!(
        "# Written by `ofmpc tune --payload-range {lo_kg},{hi_kg}`: `ofmpc run` this file.\n\
         # Controllers: {chose}. {margin_text}: {:.3}; worst RMS Cartesian error \
         over {lo_kg}, {}, {hi_kg} kg: {:.4} mm.\n{}",
        chosen.margin,
        masses[1],
        chosen.rms_mm,
        tuning.file.to_toml()?
    ))
}

/// Runs `ofmpc tune`.
pub fn tune(a: &TuneArgs) -> anyhow::Result<()> {
    let range =
        super::robot::parse_fixed("--payload-range", &a.payload_range, 2, "LO,HI in kg", "0,3")?;
    let (lo_kg, hi_kg) = (range[0], range[1]);
    if !(lo_kg >= 0.0 && hi_kg >= lo_kg) {
        bail!("--payload-range {lo_kg},{hi_kg}: give LO,HI with 0 ≤ LO ≤ HI (kg)");
    }
    let kinds = super::values::parse_controllers("--controllers", &a.controllers)?;
    if kinds.iter().any(|k| k.is_baseline()) {
        return tune_baselines(a, lo_kg, hi_kg, &kinds);
    }
    if let Some(k) = kinds.iter().find(|k| k.is_adaptive()) {
        bail!("--controllers {k}: tune the non-adaptive controllers (the adaptive ones identify the payload)");
    }
    let base = base_scenario(a)?;
    // The scenario and its figure go through the same staged, input-checked output as `run`:
    // checked before the search, moved into place only when all three are written.
    let (folder, names) = out_files(&a.out)?;
    let mut dir =
        super::experiment::open_output(&folder, super::experiment::inputs(&base, None), &names)?;
    progress(&format!(
        "searching the weights and the model payload for {lo_kg}–{hi_kg} kg, then simulating \
         the best candidates at the range's ends and middle (a minute or so)"
    ));
    let started = std::time::Instant::now();
    let tuning = robust_tuning(&base, lo_kg, hi_kg, &kinds)?;
    progress(&format!(
        "searched in {:.0} s",
        started.elapsed().as_secs_f64()
    ));
    let (candidates, chosen) = (&tuning.candidates, &tuning.chosen);
    let chose = tuning
        .controllers
        .iter()
        .map(|k| k.name())
        .collect::<Vec<_>>()
        .join(",");
    let text = scenario_text(&tuning, lo_kg, hi_kg, &a.controllers, &chose)?;
    // The trade-off figure beside it; all three files staged and moved into place together.
    let fig = tradeoff_figure(candidates, chosen);
    let r = render_both(&fig).context("rendering the trade-off figure")?;
    dir.write(&names[0], text.as_bytes())?;
    dir.write(&names[1], &r.png)?;
    dir.write(&names[2], r.svg.as_bytes())?;
    dir.commit()
        .with_context(|| format!("moving the results into {}", folder.display()))?;
    let png = a.out.with_file_name(&names[1]);
    let summary = tune_summary(&tuning, &chose, &a.out, &png);
    let text = if a.format.json() {
        serde_json::to_string_pretty(&summary)?
    } else {
        tune_words(&summary, lo_kg, hi_kg)
    };
    console::println(&text)?;
    Ok(())
}

/// `ofmpc tune --controllers pid|ctc|ctc-adaptive|dob-mpc`: the largest
/// bandwidth that keeps the payload range stable and offset-free, with its
/// margin ([`ofmpc_scenario::baseline_tuning`]); one baseline at a time.
fn tune_baselines(
    a: &TuneArgs,
    lo_kg: f64,
    hi_kg: f64,
    kinds: &[ofmpc::control::ControllerKind],
) -> anyhow::Result<()> {
    let [kind] = kinds else {
        bail!(
            "--controllers {}: tune one baseline at a time (its bandwidth), not together with other controllers",
            kinds.iter().map(|k| k.name()).collect::<Vec<_>>().join(",")
        );
    };
    let base = base_scenario(a)?;
    let (folder, names) = out_files(&a.out)?;
    let mut dir = super::experiment::open_output(
        &folder,
        super::experiment::inputs(&base, None),
        &names[..1],
    )?;
    let t = ofmpc_scenario::baseline_tuning::baseline_bandwidth(&base, lo_kg, hi_kg, *kind)?;
    let margin = match t.margin {
        Some(m) => format!("{m:.3} (ln of the first failing bandwidth over it)"),
        None => "not bounded by the grid (no bandwidth up to 316 rad/s failed)".into(),
    };
    let text = format!(
        "# Written by `ofmpc tune --payload-range {lo_kg},{hi_kg} --controllers {kind}`: `ofmpc run` this file.\n\
         # Largest bandwidth keeping {lo_kg}, {}, {hi_kg} kg offset-free: {} rad/s; margin {margin}; \
         worst RMS Cartesian error {:.4} mm.\n{}",
        t.simulated_kg[1],
        t.chosen.bandwidth,
        t.chosen.rms_mm,
        t.file.to_toml()?
    );
    dir.write(&names[0], text.as_bytes())?;
    dir.commit()
        .with_context(|| format!("moving the results into {}", folder.display()))?;
    let summary = serde_json::json!({
            "controller": kind.name(),
            "bandwidth_rad_s": t.chosen.bandwidth,
            "margin": t.margin,
            "worst_rms_mm": t.chosen.rms_mm,
            "candidates": t.candidates,
            "scenario": a.out.display().to_string(),
    });
    let text = if a.format.json() {
        serde_json::to_string_pretty(&summary)?
    } else {
        format!(
            "Tuning {kind} for an unknown payload of {lo_kg}–{hi_kg} kg: the largest bandwidth \
             keeping {lo_kg}, {}, {hi_kg} kg offset-free is {} rad/s ({} bandwidths tried).\n\
             Margin {margin}.\n\
             Worst RMS Cartesian error over the range: {:.4} mm.\n\
             Written: {} (run it with `ofmpc run {}`). `--json` prints the numbers.",
            t.simulated_kg[1],
            t.chosen.bandwidth,
            t.candidates.len(),
            t.chosen.rms_mm,
            a.out.display(),
            a.out.display(),
        )
    };
    console::println(&text)?;
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
    let bad: Vec<&&Candidate> = sim.iter().filter(|c| !c.offset_free && !c.pruned).collect();
    let pruned: Vec<&&Candidate> = sim.iter().filter(|c| c.pruned).collect();
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
    if !pruned.is_empty() {
        p.series.push(Series::markers(
            "stopped early: worse than the best (RMS of the runs made)",
            pruned.iter().map(|c| c.margin).collect(),
            pruned.iter().map(|c| c.rms_mm.max(1e-9)).collect(),
            COLOR_USUAL,
        ));
    }
    p.series.push(Series::markers(
        format!(
            "chosen: margin {:.3}, worst RMS {:.3e} mm",
            chosen.margin, chosen.rms_mm
        ),
        vec![chosen.margin],
        vec![chosen.rms_mm.max(1e-9)],
        0,
    ));
    let mut f = Figure::new("Robust tuning trade-off", 1);
    f.panels.push(p);
    f
}
