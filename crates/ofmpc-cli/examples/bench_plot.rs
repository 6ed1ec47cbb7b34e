//! Log–log plot of one control step's time against the horizon N for both
//! least-squares solvers, from the criterion results of
//! `cargo bench -p ofmpc --bench control -- step_irb140/`
//! (`target/criterion/step_irb140/<controller>-<solver>/<N>/new/estimates.json`,
//! the median). Writes the PNG given as the only argument (default
//! `docs/step-time-vs-horizon.png`) and prints the medians as a table.
//!
//! Run: `cargo run -p ofmpc-cli --example bench_plot -- docs/step-time-vs-horizon.png`

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use ofmpc_cli::output::plot::{color, ensure_font};
use plotters::prelude::*;

const HORIZONS: [u32; 6] = [5, 10, 20, 50, 100, 200];

/// The criterion median (µs) of one benchmark, `None` when it was not run.
fn median_us(root: &Path, id: &str, nh: u32) -> Result<Option<f64>> {
    let path = root
        .join(id)
        .join(nh.to_string())
        .join("new/estimates.json");
    if !path.exists() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&path).with_context(|| format!("{}", path.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}", path.display()))?;
    let ns = v["median"]["point_estimate"]
        .as_f64()
        .with_context(|| format!("{}: no median.point_estimate", path.display()))?;
    Ok(Some(ns / 1e3))
}

/// One curve: benchmark id, colour index, dashed (the dense solver), (N, median µs) points.
type Curve = (String, usize, bool, Vec<(f64, f64)>);

fn main() -> Result<()> {
    let out = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("docs/step-time-vs-horizon.png"));
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/criterion/step_irb140");
    let curves = table_and_curves(&root)?;
    anyhow::ensure!(
        !curves.is_empty(),
        "no results under {}: run the benchmark first",
        root.display()
    );
    ensure_font().map_err(|e| anyhow::anyhow!("{e}"))?;
    plot(&out, &curves)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// Prints the Markdown table of median step times (controller × solver × horizon) and returns
/// the curves that have results.
fn table_and_curves(root: &Path) -> Result<Vec<Curve>> {
    let mut curves = Vec::new();
    println!(
        "| controller | solver | {} |",
        HORIZONS.map(|n| format!("N = {n}")).join(" | ")
    );
    println!("|---|---|{}", "---|".repeat(HORIZONS.len()));
    for (ci, kind) in ["usual", "first", "second"].into_iter().enumerate() {
        for solver in ["structured", "dense-qr"] {
            let id = format!("{kind}-{solver}");
            let mut pts = Vec::new();
            let mut cells = Vec::new();
            for nh in HORIZONS {
                match median_us(root, &id, nh)? {
                    Some(us) => {
                        pts.push((nh as f64, us));
                        cells.push(if us >= 1000.0 {
                            format!("{:.2} ms", us / 1e3)
                        } else {
                            format!("{us:.0} µs")
                        });
                    }
                    None => cells.push("–".into()),
                }
            }
            println!("| {kind} | {solver} | {} |", cells.join(" | "));
            if !pts.is_empty() {
                curves.push((id, ci, solver == "dense-qr", pts));
            }
        }
    }
    Ok(curves)
}

/// Draws the curves on log-log axes into the PNG `out`.
fn plot(out: &Path, curves: &[Curve]) -> Result<()> {
    let (ymin, ymax) = curves
        .iter()
        .flat_map(|c| c.3.iter().map(|p| p.1))
        .fold((f64::INFINITY, 0.0f64), |(a, b), y| (a.min(y), b.max(y)));
    let root_area = BitMapBackend::new(out, (800, 560)).into_drawing_area();
    root_area.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root_area)
        .caption(
            "One control step, IRB 140: time against horizon N",
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (4.0f64..250.0).log_scale(),
            (ymin / 1.5..ymax * 1.5).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("horizon N")
        .y_desc("median step time (µs)")
        .x_label_formatter(&|x| {
            let n = x.round();
            if (x - n).abs() < 1e-6 && HORIZONS.contains(&(n as u32)) {
                format!("{n:.0}")
            } else {
                String::new()
            }
        })
        .y_label_formatter(&|y| format!("{y:.0}"))
        .draw()?;
    for (id, ci, dashed, pts) in curves {
        let c = color(*ci + 1);
        let style = ShapeStyle::from(&c).stroke_width(if *dashed { 1 } else { 3 });
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), style))?
            .label(id.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root_area.present()?;
    Ok(())
}
