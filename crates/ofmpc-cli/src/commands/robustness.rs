//! `ofmpc analyze robustness`: each controller of a scenario over a grid of delay ×
//! encoder quantization × friction-estimate error × model error × payload
//! ([`ofmpc_scenario::robustness`]), written as `robustness.json`, a figure and
//! `report.html` (staged, as every command's output), and a table on stdout.

use super::analyze::progress;
use crate::cli::RobustnessArgs;
use crate::output::console;
use crate::output::plot::{render_both, Figure, Panel, Series};
use crate::output::report::{Image, Report, Table};
use anyhow::Context;
use ofmpc_scenario::robustness::{robustness, Robustness, RobustnessGrid};
use ofmpc_scenario::{Scenario, ScenarioFile};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The files `analyze robustness` writes into `--out`.
const FILES: [&str; 4] = [
    "robustness.json",
    "robustness.png",
    "robustness.svg",
    "report.html",
];

/// The grid of the options; every value checked.
fn grid(a: &RobustnessArgs) -> anyhow::Result<RobustnessGrid> {
    let list = |name: &str, text: &str| super::parse_vector(name, text, None);
    let whole = |name: &str, text: &str, max: f64| -> anyhow::Result<Vec<f64>> {
        let v = list(name, text)?;
        if let Some(x) = v
            .iter()
            .find(|x| !(x.fract() == 0.0 && (0.0..=max).contains(*x)))
        {
            anyhow::bail!("{name} {x}: give whole numbers from 0 to {max}");
        }
        Ok(v)
    };
    let fraction = |name: &str, text: &str| -> anyhow::Result<Vec<f64>> {
        let v = list(name, text)?;
        if let Some(x) = v.iter().find(|x| !(0.0..=1.0).contains(*x)) {
            anyhow::bail!("{name} {x}: give relative errors from 0 to 1");
        }
        Ok(v)
    };
    let payload_kg = list("--payload", &a.payload)?;
    if let Some(x) = payload_kg.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
        anyhow::bail!("--payload {x}: give masses ≥ 0 kg");
    }
    if !(a.steady_mm.is_finite() && a.steady_mm > 0.0) {
        anyhow::bail!("--steady-mm {}: give a bound > 0 mm", a.steady_mm);
    }
    Ok(RobustnessGrid {
        delay_samples: whole("--delay", &a.delay, ofmpc::sim::MAX_DELAY_SAMPLES as f64)?
            .into_iter()
            .map(|x| x as usize)
            .collect(),
        encoder_bits: whole("--encoder-bits", &a.encoder_bits, 48.0)?
            .into_iter()
            .map(|x| x as u32)
            .collect(),
        friction_error: fraction("--friction-error", &a.friction_error)?,
        inertia_error: fraction("--inertia-error", &a.inertia_error)?,
        payload_kg,
    })
}

/// Runs `ofmpc analyze robustness`.
pub fn robustness_command(a: &RobustnessArgs) -> anyhow::Result<()> {
    let file = match &a.scenario {
        Some(p) => ScenarioFile::from_file(p).with_context(|| p.display().to_string())?,
        None => ScenarioFile::default(),
    };
    let scenario = Scenario::resolve(&file)?;
    let kinds = match &a.controllers {
        Some(c) => super::parse_controllers("--controllers", c)?,
        None => file.controllers.clone(),
    };
    let grid = grid(a)?;
    let planned: Vec<PathBuf> = FILES.iter().map(PathBuf::from).collect();
    let mut dir = super::experiment::open_output(
        &a.out,
        super::experiment::inputs(&scenario, a.scenario.as_deref()),
        &planned,
    )?;
    let total = grid.cells().len() * kinds.len();
    let done = AtomicUsize::new(0);
    let r = robustness(&scenario, &kinds, &grid, a.steady_mm, &|| {
        let k = done.fetch_add(1, Ordering::Relaxed) + 1;
        progress(&format!("run {k} of {total}"));
    })?;
    let fig = figure(&r);
    let rendered = render_both(&fig).context("rendering the robustness figure")?;
    dir.write(FILES[0], serde_json::to_string_pretty(&r)?.as_bytes())?;
    dir.write(FILES[1], &rendered.png)?;
    dir.write(FILES[2], rendered.svg.as_bytes())?;
    dir.write(FILES[3], report(&r, rendered.png).to_html()?.as_bytes())?;
    dir.commit()
        .with_context(|| format!("moving the results into {}", a.out.display()))?;
    let text = if a.format.json() {
        serde_json::to_string_pretty(&r)?
    } else {
        words(&r)
    };
    console::println(&text)?;
    Ok(())
}

fn mm(x: Option<f64>) -> String {
    x.map_or("—".into(), |v| {
        if v != 0.0 && v.abs() < 1e-3 {
            format!("{v:.2e}")
        } else {
            format!("{v:.4}")
        }
    })
}

/// The per-controller table (stdout and report).
fn summary_table(r: &Robustness) -> Table {
    Table {
        caption: format!(
            "Where each controller holds: of {} cells, stable (status ok) and holding (steady error ≤ {} mm)",
            r.cells.len() / r.summary.len().max(1),
            r.steady_bound_mm
        ),
        header: ["controller", "cells", "stable", "holds", "worst steady (mm)", "worst RMS (mm)"]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        rows: r
            .summary
            .iter()
            .map(|s| {
                vec![
                    s.controller.clone(),
                    s.cells.to_string(),
                    s.stable.to_string(),
                    s.holds.to_string(),
                    mm(s.worst_steady_mm),
                    mm(s.worst_rms_mm),
                ]
            })
            .collect(),
    }
}

/// Every cell (report).
fn cell_table(r: &Robustness) -> Table {
    Table {
        caption: "Every controller in every cell".into(),
        header: [
            "controller",
            "delay",
            "encoder bits",
            "friction error",
            "inertia error",
            "payload (kg)",
            "status",
            "RMS (mm)",
            "steady (mm)",
            "holds",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect(),
        rows: r
            .cells
            .iter()
            .map(|c| {
                vec![
                    c.controller.clone(),
                    c.cell.delay_samples.to_string(),
                    c.cell.encoder_bits.to_string(),
                    c.cell.friction_error.to_string(),
                    c.cell.inertia_error.to_string(),
                    c.cell.payload_kg.to_string(),
                    c.status.to_string(),
                    mm(c.rms_mm),
                    mm(c.steady_mm),
                    if c.holds { "yes" } else { "no" }.into(),
                ]
            })
            .collect(),
    }
}

/// Steady and RMS error per cell (x: cell number), one marker series per controller; a
/// run that did not end "ok" has no marker.
fn figure(r: &Robustness) -> Figure {
    let mut f = Figure::new("Robustness: where each controller holds", 2);
    let mut steady = Panel::new(
        "steady Cartesian error per cell",
        "cell",
        "steady error (mm)",
    );
    let mut rms = Panel::new("Cartesian RMS per cell", "cell", "RMS (mm)");
    steady.log_y = true;
    rms.log_y = true;
    for s in &r.summary {
        let color = crate::output::plot::controller_color(&s.controller);
        let mine = || {
            r.cells
                .iter()
                .filter(|c| c.controller == s.controller)
                .enumerate()
        };
        let pts = |get: &dyn Fn(&ofmpc_scenario::robustness::CellResult) -> Option<f64>| {
            mine()
                .filter_map(|(i, c)| get(c).map(|v| (i as f64, v.max(1e-9))))
                .unzip::<f64, f64, Vec<f64>, Vec<f64>>()
        };
        let (x, y) = pts(&|c| c.steady_mm);
        steady
            .series
            .push(Series::markers(&s.controller, x, y, color));
        let (x, y) = pts(&|c| c.rms_mm);
        rms.series.push(Series::markers(&s.controller, x, y, color));
    }
    f.panels.push(steady);
    f.panels.push(rms);
    f
}

/// `report.html`: the summary, the figure, every cell.
fn report(r: &Robustness, png: Vec<u8>) -> Report {
    let mut rep = Report::new("Robustness study");
    rep.paragraph(format!(
        "Each controller over a grid of measurement delay {:?} samples × encoder bits {:?} \
         (0 = ideal) × friction-estimate error {:?} × model (inertia) error {:?} × payload {:?} kg. \
         A cell holds when the run ends \"ok\" with a steady Cartesian error ≤ {} mm.",
        r.grid.delay_samples,
        r.grid.encoder_bits,
        r.grid.friction_error,
        r.grid.inertia_error,
        r.grid.payload_kg,
        r.steady_bound_mm
    ));
    rep.table(summary_table(r));
    rep.figure(
        "Steady error and RMS per cell (cells in the order of the table below; no marker: the run did not end ok) (robustness.png, .svg)",
        Image::Png(png),
    );
    rep.table(cell_table(r));
    rep
}

/// The summary as text.
fn words(r: &Robustness) -> String {
    let t = summary_table(r);
    let mut s = format!("{}\n", t.caption);
    s.push_str(&format!(
        "{:<18}{:>7}{:>8}{:>7}{:>20}{:>17}\n",
        t.header[0], t.header[1], t.header[2], t.header[3], t.header[4], t.header[5]
    ));
    for row in &t.rows {
        s.push_str(&format!(
            "{:<18}{:>7}{:>8}{:>7}{:>20}{:>17}\n",
            row[0], row[1], row[2], row[3], row[4], row[5]
        ));
    }
    s
}
