//! `ofmpc run` and `ofmpc reproduce`: run every controller × payload of a
//! scenario in parallel, then write the time series, `metrics.json`, the
//! figures and `report.html`, all through a staged directory so that a failed
//! run leaves no half-written file.

use crate::figures;
use crate::output::atomic::StagedDir;
use crate::output::plot::{render_both, Figure};
use crate::output::report::{Image, Report, Table};
use crate::scenario::Scenario;
use crate::tables::{summary_rows, summary_text, timeseries_csv, SUMMARY_HEADER};
use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use ofmpc::control::ControllerKind;
use ofmpc::robot::Payload;
use ofmpc::sim::{kind_name, run_name, RunMetrics, RunResult, RunStatus};
use rayon::prelude::*;
use std::io::IsTerminal;
use std::path::Path;
use std::time::Instant;

struct Run {
    kind: ControllerKind,
    payload: Payload,
    result: RunResult,
    metrics: RunMetrics,
}

/// Renders `fig` into the staged directory as `<rel>.png` and `<rel>.svg`,
/// and adds the PNG to the report.
fn figure(
    dir: &mut StagedDir,
    report: &mut Report,
    rel: &str,
    caption: &str,
    fig: &Figure,
) -> anyhow::Result<()> {
    let r = render_both(fig).with_context(|| format!("rendering {rel}"))?;
    dir.write(format!("{rel}.png"), &r.png)?;
    dir.write(format!("{rel}.svg"), r.svg.as_bytes())?;
    report.figure(format!("{caption} ({rel}.png, .svg)"), Image::Png(r.png));
    Ok(())
}

/// Runs the scenario and writes everything into `out`. Prints the summary
/// table on stdout; progress on stderr when it is a terminal.
pub fn execute(scenario: &Scenario, out: &Path) -> anyhow::Result<()> {
    let started = Instant::now();
    for w in &scenario.warnings {
        eprintln!("warning: {w}");
    }
    let exp = &scenario.experiment;
    let jobs: Vec<(ControllerKind, Payload)> = scenario
        .payloads
        .iter()
        .flat_map(|p| scenario.file.controllers.iter().map(move |k| (*k, *p)))
        .collect();
    let steps_per_run = (exp.reference.len()
        + (exp.loop_settings.hold_s / exp.reference.ts()).round() as usize)
        as u64;
    let bar = ProgressBar::new(steps_per_run * jobs.len() as u64);
    if std::io::stderr().is_terminal() {
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} samples ({eta})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
    } else {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    let runs: Vec<anyhow::Result<Run>> = jobs
        .par_iter()
        .map(|&(kind, payload)| {
            let mut last = 0usize;
            let (result, metrics) = exp
                .run(kind, &payload, &mut |k, _| {
                    bar.inc((k - last) as u64);
                    last = k;
                })
                .map_err(|e| {
                    anyhow::anyhow!(
                        "{}: {}",
                        run_name(kind, &payload),
                        crate::errors::experiment_error(&e)
                    )
                })?;
            Ok(Run {
                kind,
                payload,
                result,
                metrics,
            })
        })
        .collect();
    bar.finish_and_clear();
    let runs: Vec<Run> = runs.into_iter().collect::<anyhow::Result<_>>()?;
    let metrics: Vec<RunMetrics> = runs.iter().map(|r| r.metrics.clone()).collect();

    let mut dir = StagedDir::new(out)
        .with_context(|| format!("preparing the output directory {}", out.display()))?;
    let mut report = Report::new(&scenario.file.title);
    report.heading("Summary");
    let robot = &exp.robot;
    report.paragraph(format!(
        "Robot {} ({} joints), program {}, path duration {:.2} s sampled at Ts = {} s, hold {} s. \
         Controllers: the usual MPC (Eq. 43), the first incremental algorithm (Eq. 32/37) and the second (Eq. 34/39), \
         horizon N = {}. The plant carries a point payload at the flange that the controllers' model does not know. \
         \"Steady\" is the last {} s of the hold.",
        robot.name(),
        robot.dof(),
        scenario.program_name,
        exp.reference.duration(),
        exp.reference.ts(),
        exp.loop_settings.hold_s,
        exp.mpc.horizon,
        exp.loop_settings.steady_window_s,
    ));
    report.table(Table {
        caption: "Summary (metrics.json has every number)".into(),
        header: SUMMARY_HEADER.iter().map(|s| s.to_string()).collect(),
        rows: summary_rows(&metrics),
    });
    let stopped: Vec<&Run> = runs
        .iter()
        .filter(|r| !r.result.outcome.is_completed())
        .collect();
    if stopped
        .iter()
        .any(|r| r.metrics.status == RunStatus::Diverged)
    {
        report.heading("Diverged runs");
        report.paragraph(diverged_explanation(scenario, &stopped));
    }
    if stopped
        .iter()
        .any(|r| r.metrics.status == RunStatus::Failed)
    {
        report.heading("Failed runs");
        report.paragraph(
            "A failed run could not go on (a controller step or the plant's integration failed); its \
             metrics cover what was recorded before, and metrics that do not exist are null.",
        );
    }
    for r in &stopped {
        report.paragraph(format!("{}: {}", r.metrics.name, r.result.outcome));
    }

    report.heading("The path");
    figure(
        &mut dir,
        &mut report,
        "path",
        "The path: top, isometric and side views, and the joint reference",
        &figures::path("Path and joint reference", &exp.reference),
    )?;
    figure(
        &mut dir,
        &mut report,
        "cartesian_reference",
        "Fig. 4: the timed Cartesian reference (each segment rest to rest)",
        &figures::cartesian_reference(
            "Cartesian reference: position, velocity, acceleration",
            &scenario.trajectory,
            exp.reference.ts(),
        ),
    )?;
    report.heading("Tracking errors of the three controllers (the paper's Fig. 6 and 7)");
    for p in &scenario.payloads {
        let these: Vec<(&str, &ofmpc::sim::Record)> = runs
            .iter()
            .filter(|r| r.payload.mass == p.mass)
            .map(|r| (kind_name(r.kind), &r.result.record))
            .collect();
        let label = if p.mass == 0.0 {
            "exact model (no payload)".to_string()
        } else {
            format!("payload {} kg unknown to the model", p.mass)
        };
        let fig_no = if p.mass == 0.0 { "Fig. 6" } else { "Fig. 7" };
        figure(
            &mut dir,
            &mut report,
            &format!("joint_errors_m{}", p.mass),
            &format!("{fig_no}: joint errors, {label}"),
            &figures::joint_errors(&format!("Joint errors e = w − q, {label}"), &these),
        )?;
        figure(
            &mut dir,
            &mut report,
            &format!("cartesian_errors_m{}", p.mass),
            &format!("Cartesian errors, {label}"),
            &figures::cartesian_errors(
                &format!("Cartesian errors (reference − flange), {label}"),
                &these,
            ),
        )?;
    }
    if runs.iter().any(|r| r.kind.is_adaptive()) {
        let pick_up = exp.loop_settings.pick_up_at_s;
        report.heading("Online payload identification (adaptive variants)");
        report.paragraph(format!(
            "The adaptive variants identify the payload's inertial parameters by recursive least squares \
             from the measured motion and their own torque, and update their model at every sample; they \
             identify for {} s at rest before the path starts (not recorded).{}",
            exp.loop_settings.identification_s,
            match pick_up {
                Some(t) => format!(" The plant picks the payload up at t = {t} s; the controllers are not told."),
                None => String::new(),
            }
        ));
        for p in &scenario.payloads {
            let these: Vec<(&str, &ofmpc::sim::Record)> = runs
                .iter()
                .filter(|r| r.payload.mass == p.mass)
                .map(|r| (kind_name(r.kind), &r.result.record))
                .collect();
            let m = p.mass;
            let truth = move |t: f64| match pick_up {
                Some(tp) if t < tp => 0.0,
                _ => m,
            };
            figure(
                &mut dir,
                &mut report,
                &format!("identification_m{m}"),
                &format!("Error and identified mass against time, payload {m} kg"),
                &figures::identification(
                    &format!("Payload {m} kg: error and identified mass"),
                    &these,
                    &truth,
                ),
            )?;
        }
    }
    if scenario.payloads.len() >= 3 {
        report.heading("Payload sweep");
        figure(
            &mut dir,
            &mut report,
            "payload_sweep",
            "Steady and RMS Cartesian error against payload (markers: diverged runs, at the error when stopped)",
            &figures::payload_sweep("Cartesian error against payload", &metrics),
        )?;
    }
    report.heading("Each run: joints and torques (the paper's Fig. 5), Cartesian error");
    for r in &runs {
        let name = &r.metrics.name;
        dir.write(
            format!("{name}/timeseries.csv"),
            timeseries_csv(&r.result.record).as_bytes(),
        )?;
        figure(
            &mut dir,
            &mut report,
            &format!("{name}/joints_torques"),
            &format!("Fig. 5, {name}: joint coordinates and torques"),
            &figures::joints_and_torques(&format!("{name}: joints and torques"), &r.result.record),
        )?;
        figure(
            &mut dir,
            &mut report,
            &format!("{name}/cartesian_error"),
            &format!("{name}: Cartesian error"),
            &figures::cartesian_errors(
                &format!("{name}: Cartesian error"),
                &[(kind_name(r.kind), &r.result.record)],
            ),
        )?;
    }
    #[derive(serde::Serialize)]
    struct MetricsFile<'a> {
        runs: &'a [RunMetrics],
    }
    let json = serde_json::to_string_pretty(&MetricsFile { runs: &metrics })?;
    dir.write("metrics.json", json.as_bytes())?;
    let effective = toml::to_string(&scenario.file).context("writing the effective scenario")?;
    let effective = format!(
        "# The scenario of this run, every default filled in: `ofmpc run scenario.toml` repeats it.\n{effective}"
    );
    report.heading("Scenario");
    report.code(effective.clone());
    dir.write("scenario.toml", effective.as_bytes())?;
    dir.write("report.html", report.to_html()?.as_bytes())?;
    dir.commit()
        .with_context(|| format!("moving the results into {}", out.display()))?;

    print!("{}", summary_text(&metrics));
    println!(
        "{} runs in {:.2} s (wall); results in {}/ (metrics.json, report.html, one folder per run)",
        runs.len(),
        started.elapsed().as_secs_f64(),
        out.display()
    );
    let failed: Vec<String> = metrics
        .iter()
        .filter(|m| m.status == RunStatus::Failed)
        .map(|m| format!("{}: {}", m.name, m.reason))
        .collect();
    if !failed.is_empty() {
        return Err(crate::errors::RunsFailed { runs: failed }.into());
    }
    Ok(())
}

fn weight_text(w: &ofmpc::control::Weight) -> String {
    match w {
        ofmpc::control::Weight::Scalar(v) => format!("{v} I"),
        ofmpc::control::Weight::Diagonal(d) => format!("diag{d:?}"),
    }
}

/// The "Diverged runs" paragraph: the stability margins computed for this
/// robot, tuning and program (`ofmpc analyze stability`), never fixed text.
fn diverged_explanation(scenario: &Scenario, stopped: &[&Run]) -> String {
    let exp = &scenario.experiment;
    let mpc = &exp.mpc;
    let mut kinds: Vec<ControllerKind> = stopped
        .iter()
        .filter(|r| r.metrics.status == RunStatus::Diverged)
        .map(|r| r.kind.base())
        .collect();
    kinds.sort_by_key(|k| k.name());
    kinds.dedup();
    let mut text = format!(
        "A run stops when a joint error passes the divergence threshold ({} rad). With this tuning \
         (N = {}, Ts = {} s, Q_yw = {}, Q_Δy = {}, Q_Δu = {}, model payload {} kg), computed for {} along this \
         program from the controllers' own step linearized near rest (`ofmpc analyze stability`):",
        exp.loop_settings.divergence_threshold_rad,
        mpc.horizon,
        mpc.ts,
        weight_text(&mpc.q_yw),
        weight_text(&mpc.q_dy),
        weight_text(&mpc.q_du),
        mpc.model_payload_kg,
        exp.robot.name(),
    );
    for k in kinds {
        match super::analyze::margin(scenario, k) {
            Ok(m) => text.push_str(&format!(
                " the {k} algorithm is stable for an inertia ratio α = H_model/H_plant in {:.3}–{:.3}, \
                 i.e. a point payload up to {:.2} kg that the model does not know;",
                m.alpha_interval[0], m.alpha_interval[1], m.max_payload_kg
            )),
            Err(e) => text.push_str(&format!(" the {k} algorithm's margin could not be computed ({e:#});")),
        }
    }
    text.push_str(
        " a divergence beyond those payloads is the physics of the tuning, not a numerical failure. \
         The adaptive variants identify the payload and keep α near 1; `ofmpc tune` finds weights for a payload range.",
    );
    text
}
