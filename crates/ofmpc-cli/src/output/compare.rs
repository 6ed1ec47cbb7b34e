//! The report's "Controllers compared" section: when a baseline ran beside
//! other controllers, a table per controller and payload (RMS, max and
//! steady Cartesian error, peak |τ|/τmax, largest torque step, status), a
//! figure of the RMS error against payload per controller (log scale,
//! diverged runs marked) and, generated from the metrics, which controller
//! to choose for which payload range.

use super::plot::{Figure, Panel, Series};
use super::report::{Report, Table};
use ofmpc::control::ControllerKind;
use ofmpc::sim::{RunMetrics, RunStatus};

/// Stem of the comparison figure (`controllers_compared.png`, `.svg`).
pub(crate) const COMPARE_FIGURE: &str = "controllers_compared";

/// Whether the section is written: more than one controller ran and one of
/// them is a baseline (the paper's own runs keep their report as it was).
pub(crate) fn wanted(controllers: &[ControllerKind]) -> bool {
    controllers.len() > 1 && controllers.iter().any(|k| k.is_baseline())
}

fn num(v: f64) -> String {
    if v.is_nan() {
        "—".into()
    } else if v == 0.0 {
        "0".into()
    } else {
        crate::verdict::number(v)
    }
}

fn status(m: &RunMetrics) -> String {
    match (m.status, m.stopped_at_s) {
        (RunStatus::Ok, _) => "ok".into(),
        (s, Some(t)) => format!("{} at {t:.2} s", s.name()),
        (s, None) => s.name().into(),
    }
}

/// Peak `|τ_i| / τmax_i` of a run over the joints with a finite limit (NaN
/// when no joint has one).
fn peak_ratio(m: &RunMetrics, limits: &[f64]) -> f64 {
    m.torque_max_nm
        .iter()
        .zip(limits)
        .filter(|(_, l)| l.is_finite() && **l > 0.0)
        .map(|(t, l)| t / l)
        .fold(f64::NAN, f64::max)
}

/// The table, the figure (from `figure`, which renders and writes it) and
/// the recommendation, appended to `report`.
pub(crate) fn section(
    report: &mut Report,
    metrics: &[RunMetrics],
    controllers: &[ControllerKind],
    limits: &[f64],
    figure: &mut dyn FnMut(&mut Report, &str, &str, &Figure) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    report.heading("Controllers compared");
    report.paragraph(
        "The paper's predictive controllers beside the baselines a control engineer compares \
         against: pid (independent joint PID with gravity compensation and velocity feed-forward), \
         ctc (computed torque on the nominal model with PID on the error), ctc-adaptive (the same \
         on the model whose payload is identified online) and dob-mpc (the usual MPC with an \
         input-disturbance observer and the target U_s = −d̂). Their bandwidths are [baselines] \
         pid_bandwidth, ctc_bandwidth and dob_observer_bandwidth; the equations are in the crate \
         documentation (ofmpc::control::baseline).",
    );
    let mut rows = Vec::new();
    for k in controllers {
        for m in metrics.iter().filter(|m| m.controller == k.name()) {
            rows.push(vec![
                k.name().to_string(),
                num(m.payload_kg),
                num(m.cartesian_error_rms_to_stop_mm),
                num(m.cartesian_error_max_to_stop_mm),
                num(m.steady_cartesian_error_mm),
                num(peak_ratio(m, limits)),
                num(m.torque_step_max_nm),
                status(m),
            ]);
        }
    }
    report.table(Table {
        caption: "Controllers compared: Cartesian error (mm), torque use".into(),
        header: [
            "controller",
            "payload (kg)",
            "RMS (mm)",
            "max (mm)",
            "steady (mm)",
            "peak |τ|/τmax",
            "largest torque step (N·m)",
            "status",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect(),
        rows,
    });
    figure(
        report,
        COMPARE_FIGURE,
        "Cartesian RMS error against payload per controller (log scale; markers: diverged or stopped runs, at their maximum error)",
        &rms_figure(metrics, controllers),
    )?;
    report.paragraph(recommendation(metrics, controllers));
    Ok(())
}

/// RMS against payload, one line per controller (the baselines dashed),
/// stopped runs as markers.
pub(crate) fn rms_figure(metrics: &[RunMetrics], controllers: &[ControllerKind]) -> Figure {
    let mut f = Figure::new("Controllers compared", 1);
    let mut p = Panel::new("Cartesian RMS error", "payload (kg)", "RMS error (mm)");
    p.log_y = true;
    for k in controllers {
        let mine: Vec<&RunMetrics> = metrics
            .iter()
            .filter(|m| m.controller == k.name())
            .collect();
        let (ok, bad): (Vec<&RunMetrics>, Vec<&RunMetrics>) =
            mine.iter().partition(|m| m.status == RunStatus::Ok);
        let color = crate::output::plot::controller_color(k.name());
        // The baselines dashed: the palette has 8 colours for 9 controllers.
        let line = if k.is_baseline() {
            Series::dashed
        } else {
            Series::line
        };
        p.series.push(line(
            k.name(),
            ok.iter().map(|m| m.payload_kg).collect(),
            ok.iter().map(|m| m.cartesian_error_rms_mm).collect(),
            color,
        ));
        if !bad.is_empty() {
            p.series.push(Series::markers(
                format!("{} {}", k.name(), "diverged/stopped"),
                bad.iter().map(|m| m.payload_kg).collect(),
                bad.iter()
                    .map(|m| m.cartesian_error_max_to_stop_mm)
                    .collect(),
                color,
            ));
        }
    }
    f.panels.push(p);
    f
}

/// Completed and offset-free: steady joint error ≤ 1e-6 rad.
fn offset_free(m: &RunMetrics) -> bool {
    m.status == RunStatus::Ok
        && m.steady_joint_error_max_rad
            .iter()
            .all(|e| e.is_finite() && *e <= 1e-6)
}

/// Per payload the offset-free run of the least RMS error among `metrics`
/// whose controller passes `keep`, grouped into ranges of one winner.
fn winners(metrics: &[RunMetrics], keep: &dyn Fn(&str) -> bool) -> String {
    let mut payloads: Vec<f64> = metrics.iter().map(|m| m.payload_kg).collect();
    payloads.sort_by(f64::total_cmp);
    payloads.dedup();
    let mut ranges: Vec<(String, f64, f64, f64)> = Vec::new();
    for &p in &payloads {
        let best = metrics
            .iter()
            .filter(|m| m.payload_kg == p && offset_free(m) && keep(&m.controller))
            .filter(|m| m.cartesian_error_rms_mm.is_finite())
            .min_by(|a, b| {
                a.cartesian_error_rms_mm
                    .total_cmp(&b.cartesian_error_rms_mm)
            });
        let Some(b) = best else { continue };
        match ranges.last_mut() {
            Some((name, _, hi, worst)) if *name == b.controller => {
                *hi = p;
                *worst = worst.max(b.cartesian_error_rms_mm);
            }
            _ => ranges.push((b.controller.clone(), p, p, b.cartesian_error_rms_mm)),
        }
    }
    ranges
        .iter()
        .map(|(name, lo, hi, worst)| {
            let range = if lo == hi {
                format!("{} kg", num(*lo))
            } else {
                format!("{}–{} kg", num(*lo), num(*hi))
            };
            format!("{name} at {range} (RMS ≤ {} mm)", num(*worst))
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The recommendation for the verdict at the top of the report: the sentence of
/// [`robust_choice`] over the controllers offset-free at every payload (`None` when none is).
pub(crate) fn verdict_choice(
    metrics: &[RunMetrics],
    controllers: &[ControllerKind],
) -> Option<String> {
    let mut payloads: Vec<f64> = metrics.iter().map(|m| m.payload_kg).collect();
    payloads.sort_by(f64::total_cmp);
    payloads.dedup();
    let complete: Vec<&str> = controllers
        .iter()
        .filter(|k| {
            metrics
                .iter()
                .filter(|m| m.controller == k.name())
                .all(offset_free)
        })
        .map(|k| k.name())
        .collect();
    let s = robust_choice(metrics, &complete, &payloads);
    (!s.is_empty()).then(|| format!("Recommendation: {}", s.trim_end()))
}

/// The most robust choice: of the controllers offset-free at every payload (`complete`), the
/// one with the least worst RMS error over the payloads, as a sentence (empty when none).
fn robust_choice(metrics: &[RunMetrics], complete: &[&str], payloads: &[f64]) -> String {
    let worst = |name: &str| {
        metrics
            .iter()
            .filter(|m| m.controller == name)
            .map(|m| m.cartesian_error_rms_mm)
            .fold(0.0, f64::max)
    };
    let Some(robust) = complete.iter().min_by(|a, b| worst(a).total_cmp(&worst(b))) else {
        return String::new();
    };
    format!(
        "Over the whole range {} kg the controller with the least worst-case RMS among those \
         offset-free at every payload is {robust} ({} mm): choose it when the payload is not known. ",
        match (payloads.first(), payloads.last()) {
            (Some(a), Some(b)) => format!("{}–{}", num(*a), num(*b)),
            _ => String::new(),
        },
        num(worst(robust))
    )
}

/// Which controller to choose for which payload range, from the metrics: per
/// payload the completed run with the least RMS error, grouped into ranges
/// of the same winner, and which controllers did not complete somewhere.
pub(crate) fn recommendation(metrics: &[RunMetrics], controllers: &[ControllerKind]) -> String {
    let mut payloads: Vec<f64> = metrics.iter().map(|m| m.payload_kg).collect();
    payloads.sort_by(f64::total_cmp);
    payloads.dedup();
    let adaptive = |name: &str| {
        name.parse::<ControllerKind>()
            .is_ok_and(|k| k.is_adaptive())
    };
    let mut text = format!(
        "Least RMS error among the offset-free runs (steady joint error ≤ 1e-6 rad): {}. ",
        winners(metrics, &|_| true)
    );
    let fixed = winners(metrics, &|n| !adaptive(n));
    if controllers.iter().any(|k| k.is_adaptive()) && !fixed.is_empty() {
        text.push_str(&format!(
            "Without online identification (a fixed model, the payload unknown): {fixed}. "
        ));
    }
    let complete: Vec<&str> = controllers
        .iter()
        .filter(|k| {
            metrics
                .iter()
                .filter(|m| m.controller == k.name())
                .all(offset_free)
        })
        .map(|k| k.name())
        .collect();
    let incomplete: Vec<String> = controllers
        .iter()
        .filter(|k| !complete.contains(&k.name()))
        .map(|k| {
            let from = metrics
                .iter()
                .filter(|m| m.controller == k.name() && !offset_free(m))
                .map(|m| m.payload_kg)
                .fold(f64::INFINITY, f64::min);
            format!("{} (from {} kg)", k.name(), num(from))
        })
        .collect();
    if !complete.is_empty() {
        text.push_str(&robust_choice(metrics, &complete, &payloads));
        text.push_str(&format!(
            "Offset-free at every payload: {}. ",
            complete.join(", ")
        ));
    }
    if !incomplete.is_empty() {
        text.push_str(&format!(
            "Not offset-free at every payload (a steady offset by construction, as the usual MPC's, \
             or the payload the model does not know moves them out of their stability margin): {}.",
            incomplete.join(", ")
        ));
    }
    text
}
