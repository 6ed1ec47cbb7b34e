//! `ofmpc run` and `ofmpc reproduce`: run every controller × payload of a
//! scenario in parallel, then write the time series, `metrics.json`, the
//! figures and `report.html`, all through a staged directory so that a failed
//! run leaves no half-written file.

use crate::figures;
use crate::output::atomic::{Input, StagedDir};
use crate::output::console;
use crate::output::plot::{render_both, Figure};
use crate::output::replay::{replay_json_with, ReplayRun};
use crate::output::report::{Image, Report, Table};
use crate::output::run_files::{
    controllers_in_words, per_payload, per_run, the_controllers, RunFiles, CARTESIAN_REFERENCE,
    METRICS, PATH, PAYLOAD_SWEEP, REPORT, SCENARIO, TIMESERIES,
};
use crate::tables::{
    summary_rows, summary_text, timeseries_bytes_per_row, timeseries_csv_every, SUMMARY_HEADER,
};
use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use ofmpc::control::ControllerKind;
use ofmpc::robot::Payload;
use ofmpc::sim::{kind_name, mass_label, RunMetrics, RunStatus};
use ofmpc_scenario::{metrics_json_with_plant, plant_report, run_jobs, unique_runs, Run, Scenario};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The plant that is not the model: its files and the relative errors drawn per link.
fn plant_section(report: &mut Report, plant: &ofmpc_scenario::PlantReport) {
    let files: Vec<String> = [("robot", &plant.robot), ("drives", &plant.drives)]
        .iter()
        .filter_map(|(k, v)| v.as_ref().map(|v| format!("[plant] {k} = {v}")))
        .collect();
    report.paragraph(format!(
        "The plant is not the controllers' model: {}. The controllers keep the nominal model.",
        if files.is_empty() {
            format!(
                "every link's mass, centre of mass, inertia and rotor inertia drawn with relative \
                 standard deviation {} (seed {})",
                plant.inertia_error, plant.seed
            )
        } else {
            files.join(", ")
        }
    ));
    if plant.links.is_empty() {
        return;
    }
    let pct = |x: f64| format!("{:+.1}", 100.0 * x);
    report.table(Table {
        caption: "The plant's inertial parameters against the model (relative errors drawn, %)"
            .into(),
        header: [
            "link",
            "mass",
            "centre of mass offset / link",
            "inertia",
            "rotor inertia",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect(),
        rows: plant
            .links
            .iter()
            .map(|l| {
                vec![
                    l.link.clone(),
                    pct(l.error.mass),
                    format!("{:.1}", 100.0 * l.error.com_offset),
                    format!("{:.1}", 100.0 * l.error.inertia),
                    pct(l.error.drive_inertia),
                ]
            })
            .collect(),
    });
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
    let image = match crate::output::chart::chart_json(fig) {
        Some(json) => Image::Chart(json),
        None => Image::Png(r.png),
    };
    report.figure(format!("{caption} ({rel}.png, .svg)"), image);
    Ok(())
}

/// The files a scenario reads (never overwritten by its outputs).
pub(crate) fn inputs(scenario: &Scenario, scenario_path: Option<&Path>) -> Vec<Input> {
    let f = &scenario.file;
    let mut v = Vec::new();
    if let Some(p) = scenario_path {
        v.push(Input::new(p, "the scenario file"));
    }
    if let Some(p) = &f.program.file {
        v.push(Input::new(p, "the program"));
    }
    if ofmpc_scenario::is_model_path(&f.robot.model) && Path::new(&f.robot.model).is_file() {
        v.push(Input::new(&f.robot.model, "the robot model"));
    }
    if let Some(p) = &f.robot.drives {
        v.push(Input::new(p, "the drives file"));
    }
    v
}

/// Opens the output folder `out` for a run: lock, stale stages of dead runs removed (noted), a
/// note if `out` is a symbolic link, the inputs protected, and every planned destination
/// checked before anything is computed.
pub(crate) fn open_output(
    out: &Path,
    inputs: Vec<Input>,
    planned: &[PathBuf],
) -> anyhow::Result<StagedDir> {
    if let Ok(to) = std::fs::read_link(out) {
        if std::fs::metadata(out).is_err() {
            anyhow::bail!(
                "the output path {} is a symbolic link to {}, which does not exist: create that \
                 folder, remove the link, or choose another output path (nothing was written)",
                out.display(),
                to.display()
            );
        }
        console::note(&format!(
            "{} is a symbolic link to {}: the results go there",
            out.display(),
            to.display()
        ));
    }
    let mut dir = StagedDir::new(out)
        .with_context(|| format!("preparing the output directory {}", out.display()))?;
    for p in dir.removed_stale() {
        console::note(&format!(
            "removed {}, left by an interrupted run (its process no longer runs)",
            p.display()
        ));
    }
    dir.protect(inputs);
    dir.check(planned)?;
    Ok(dir)
}

/// Runs the scenario and writes everything into `out`. Prints the summary
/// table on stdout; progress on stderr when it is a terminal. `scenario_path` is the file the
/// scenario was read from, if any (never overwritten). The runs also record the predicted
/// horizons the report's replay draws ([`crate::output::replay::horizon_sampling`]).
pub fn execute(
    scenario: &mut Scenario,
    scenario_path: Option<&Path>,
    out: &Path,
) -> anyhow::Result<()> {
    let started = Instant::now();
    for w in &scenario.warnings {
        console::warn(w);
    }
    let (payloads, controllers, repeats) = unique_runs(scenario);
    for w in &repeats {
        console::warn(w);
    }
    scenario.experiment.conditions.horizons = Some(crate::output::replay::horizon_sampling(
        scenario.samples_per_run(),
        payloads.len() * controllers.len(),
    ));
    let scenario = &*scenario;
    let files = RunFiles::new(&scenario.file, &payloads, &controllers);
    let mut dir = open_output(out, inputs(scenario, scenario_path), &files.files())?;
    let leftovers = files.earlier_leftovers(out);
    if !leftovers.is_empty() {
        console::warn(&format!(
            "{} holds results of an earlier run that this run does not replace: {}. \
             metrics.json and report.html describe only this run; remove them or choose \
             another --out",
            out.display(),
            leftovers.join(", ")
        ));
    }
    size_notes(scenario, payloads.len() * controllers.len());
    let runs = run_with_progress(scenario, &payloads, &controllers)?;
    let metrics: Vec<RunMetrics> = runs.iter().map(|r| r.metrics.clone()).collect();
    let mut w = Writer {
        dir: &mut dir,
        report: Report::new(&scenario.file.title),
        scenario,
        runs: &runs,
        metrics: &metrics,
        payloads: &payloads,
        controllers: &controllers,
        files: &files,
    };
    w.verdict();
    w.summary();
    w.replay();
    if files.sweep {
        w.sweep()?;
    }
    w.tracking_errors()?;
    if files.identification {
        w.identification()?;
    }
    if files.drives {
        w.drives()?;
    }
    if files.compare {
        w.compare()?;
    }
    w.path()?;
    w.each_run()?;
    w.finish()?;
    dir.commit()
        .with_context(|| format!("moving the results into {}", out.display()))?;

    console::print(&summary_text(&metrics))?;
    console::println(&format!(
        "{} runs in {:.2} s (wall); results in {}/ (metrics.json, report.html, one folder per run)",
        runs.len(),
        started.elapsed().as_secs_f64(),
        out.display()
    ))?;
    let failed: Vec<String> = metrics
        .iter()
        .filter(|m| m.status.is_failure())
        .map(|m| format!("{}: {}", m.name, m.reason))
        .collect();
    if !failed.is_empty() {
        return Err(crate::errors::RunsFailed { runs: failed }.into());
    }
    Ok(())
}

/// `n` as an English ordinal: 2nd, 3rd, 11th, 21st.
fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

/// Time series above this total (bytes) get a warning before the run.
const LARGE_OUTPUT_BYTES: u64 = 300_000_000;

/// Before the runs: the time series' size estimated, a note when `[output] timeseries`
/// decimates them by default, a warning when they would pass [`LARGE_OUTPUT_BYTES`].
fn size_notes(scenario: &Scenario, runs: usize) {
    let rows = scenario.samples_per_run();
    let per_row = timeseries_bytes_per_row(scenario.experiment.robot.dof());
    let output = &scenario.file.output;
    let Some(stride) = output.timeseries_stride_of(rows, per_row, runs) else {
        return;
    };
    let full_mb = (rows as u64 * per_row) as f64 * 1e-6;
    let total = runs as u64 * (rows.div_ceil(stride) as u64) * per_row;
    if stride > 1 && output.timeseries == ofmpc_scenario::TimeseriesOutput::Auto {
        console::note(&format!(
            "each run's timeseries.csv holds every {} of its {rows} samples (about \
             {:.0} MB in all; every sample would take about {full_mb:.0} MB a run): [output] \
             timeseries = \"full\" writes them all; the metrics and figures use every sample",
            ordinal(stride),
            total as f64 * 1e-6
        ));
    }
    if total > LARGE_OUTPUT_BYTES {
        console::warn(&format!(
            "this run writes about {:.0} MB of time series ({runs} runs × {} rows): [output] \
             timeseries = \"decimated\" (with a stride) or \"none\" writes less",
            total as f64 * 1e-6,
            rows.div_ceil(stride)
        ));
    }
}

/// Every run of `controllers` × `payloads`, with a progress bar on stderr
/// when it is a terminal.
fn run_with_progress(
    scenario: &Scenario,
    payloads: &[Payload],
    controllers: &[ControllerKind],
) -> anyhow::Result<Vec<Run>> {
    let jobs = payloads.len() * controllers.len();
    let steps_per_run = scenario.samples_per_run() as u64;
    let bar = ProgressBar::new(steps_per_run * jobs as u64);
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
    // Not a terminal (a pipe, a CI log): a plain line every few seconds instead of the bar.
    let plain = (!std::io::stderr().is_terminal())
        .then(|| console::PlainProgress::new(steps_per_run * jobs as u64));
    let runs = run_jobs(scenario, payloads, controllers, &|samples| {
        bar.inc(samples);
        if let Some(p) = &plain {
            p.inc(samples);
        }
    })?;
    bar.finish_and_clear();
    Ok(runs)
}

/// Writes a run's results into the staged folder and its report, section
/// by section (the files are those of [`RunFiles`]).
struct Writer<'a> {
    dir: &'a mut StagedDir,
    report: Report,
    scenario: &'a Scenario,
    runs: &'a [Run],
    metrics: &'a [RunMetrics],
    payloads: &'a [Payload],
    controllers: &'a [ControllerKind],
    files: &'a RunFiles,
}

impl Writer<'_> {
    /// Renders a figure into the folder and the report ([`figure`]).
    fn figure(&mut self, rel: &str, caption: &str, fig: &Figure) -> anyhow::Result<()> {
        figure(self.dir, &mut self.report, rel, caption, fig)
    }

    /// The verdict in words from the metrics ([`crate::verdict`]) and the table of contents.
    fn verdict(&mut self) {
        let mut sentences = crate::verdict::verdict(self.metrics);
        // With the baselines compared: the section's recommendation, said up front.
        if self.files.compare {
            sentences.extend(crate::output::compare::verdict_choice(
                self.metrics,
                self.controllers,
            ));
        }
        if !sentences.is_empty() {
            self.report.list("verdict", sentences);
        }
        self.report.toc();
    }

    /// The 3-D replay of every run (robot, reference path, flange trace coloured by the error).
    fn replay(&mut self) {
        let runs: Vec<ReplayRun<'_>> = self
            .runs
            .iter()
            .map(|r| ReplayRun {
                name: &r.metrics.name,
                status: match r.metrics.stopped_at_s {
                    Some(t) if r.metrics.status != RunStatus::Ok => {
                        format!("{} at {t:.2} s", r.metrics.status)
                    }
                    _ => r.metrics.status.to_string(),
                },
                record: &r.result.record,
            })
            .collect();
        let robot = &self.scenario.experiment.robot;
        let model = &self.scenario.file.robot.model;
        let visuals = ofmpc_scenario::is_model_path(model).then(|| {
            crate::output::mesh::visuals::load(
                std::path::Path::new(model),
                robot,
                std::env::var("ROS_PACKAGE_PATH").ok().as_deref(),
            )
        });
        let mesh_summary = visuals.as_ref().and_then(|v| v.summary());
        if let Some(w) = &mesh_summary {
            console::warn(&format!("3-D replay: {w}"));
        }
        let drawn = match &visuals {
            Some(v) if !v.meshes.is_empty() => {
                "its URDF's visual meshes (capsules between the joint frames for links without one)"
            }
            _ => "its kinematics (capsules between the joint frames)",
        };
        self.report.heading("3-D replay");
        self.report.paragraph(format!(
            "The robot drawn from {drawn}, the reference \
             path (grey), the flange trace coloured by the Cartesian tracking error and, in magenta, what the \
             controller predicted over its horizon at the latest recorded sample. Play/pause, \
             the time slider and the run menu; drag to orbit, wheel to zoom. Stopped runs end at the stop.",
        ));
        if let Some(w) = &mesh_summary {
            self.report.paragraph(format!("{w}."));
        }
        self.report
            .replay(replay_json_with(robot, &runs, visuals.as_ref()));
    }

    /// Folds the figures of one payload (`<details>`) when there are more than two payloads.
    fn fold(&mut self, summary: &str) -> bool {
        let fold = self.payloads.len() > 2;
        if fold {
            self.report.details(summary);
        }
        fold
    }

    /// The summary: the setting in words, the table, why runs stopped.
    fn summary(&mut self) {
        let (scenario, metrics, runs) = (self.scenario, self.metrics, self.runs);
        let exp = &scenario.experiment;
        let report = &mut self.report;
        report.heading("Summary");
        let robot = &exp.robot;
        report.paragraph(format!(
            "Robot {} ({} joints), program {}, path duration {:.2} s sampled at Ts = {} s, hold {} s. \
             Controllers: {}, \
             horizon N = {}. The plant carries a point payload at the flange that the controllers' model does not know. \
             \"Steady\" is the last {} s of the hold.",
            robot.name(),
            robot.dof(),
            scenario.program_name,
            exp.reference.duration(),
            exp.reference.ts(),
            exp.loop_settings.hold_s,
            controllers_in_words(self.controllers),
            exp.mpc.horizon,
            exp.loop_settings.steady_window_s,
        ));
        report.table(Table {
            caption: "Summary (metrics.json has every number; a run brought to a safe stop: \
                      Cartesian RMS and max up to the stop, before it brakes)"
                .into(),
            header: SUMMARY_HEADER.iter().map(|s| s.to_string()).collect(),
            rows: summary_rows(metrics),
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
        if stopped
            .iter()
            .any(|r| r.metrics.status == RunStatus::FailedStop)
        {
            report.heading("Failed stops");
            report.paragraph(
                "A failed stop is a safe stop whose robot was not at rest by the end of the record or left \
                 its joint limits: the stop law alone could not hold it (a real cell needs its brakes).",
            );
        }
        for r in &stopped {
            report.paragraph(format!("{}: {}", r.metrics.name, r.result.outcome));
        }
    }

    /// The path and the timed Cartesian reference (Fig. 4).
    fn path(&mut self) -> anyhow::Result<()> {
        let scenario = self.scenario;
        let exp = &scenario.experiment;
        self.report.heading("The path");
        self.figure(
            PATH,
            "The path: top, isometric and side views, and the joint reference",
            &figures::path("Path and joint reference", &exp.reference),
        )?;
        self.figure(
            CARTESIAN_REFERENCE,
            "Fig. 4: the timed Cartesian reference (each segment rest to rest)",
            &figures::cartesian_reference(
                "Cartesian reference: position, velocity, acceleration",
                &scenario.trajectory,
                exp.reference.ts(),
            ),
        )
    }

    /// Joint and Cartesian errors per payload (Fig. 6 and 7).
    fn tracking_errors(&mut self) -> anyhow::Result<()> {
        let runs = self.runs;
        let names: Vec<String> = self
            .controllers
            .iter()
            .map(|k| kind_name(*k).to_string())
            .collect();
        self.report.heading(format!(
            "Tracking errors of {} (the paper's Fig. 6 and 7)",
            crate::verdict::and_list(&names)
        ));
        self.report.paragraph(format!(
            "Joint and Cartesian errors of {} per payload.",
            the_controllers(self.controllers.len())
        ));
        for p in self.payloads {
            let folded = self.fold(&format!("payload {} kg", mass_label(p.mass)));
            let these = records_with_mass(runs, p.mass);
            let label = if p.mass == 0.0 {
                "exact model (no payload)".to_string()
            } else {
                format!("payload {} kg unknown to the model", mass_label(p.mass))
            };
            let fig_no = if p.mass == 0.0 { "Fig. 6" } else { "Fig. 7" };
            self.figure(
                &format!("{}{}", per_payload::JOINT_ERRORS, mass_label(p.mass)),
                &format!("{fig_no}: joint errors, {label}"),
                &figures::joint_errors(&format!("Joint errors e = w − q, {label}"), &these),
            )?;
            self.figure(
                &format!("{}{}", per_payload::CARTESIAN_ERRORS, mass_label(p.mass)),
                &format!("Cartesian errors, {label}"),
                &figures::cartesian_errors(
                    &format!("Cartesian errors (reference − flange), {label}"),
                    &these,
                ),
            )?;
            if folded {
                self.report.end_details();
            }
        }
        Ok(())
    }

    /// The adaptive variants' identified mass against time.
    fn identification(&mut self) -> anyhow::Result<()> {
        let (exp, runs) = (&self.scenario.experiment, self.runs);
        let pick_up = exp.conditions.pick_up_at_s;
        self.report
            .heading("Online payload identification (adaptive variants)");
        self.report.paragraph(format!(
            "The adaptive variants identify the payload's inertial parameters by recursive least squares \
             from the measured motion and their own torque, and update their model at every sample; they \
             identify for {} s at rest before the path starts (not recorded).{}",
            exp.loop_settings.identification_s,
            match pick_up {
                Some(t) => format!(" The plant picks the payload up at t = {t} s; the controllers are not told."),
                None => String::new(),
            }
        ));
        for p in self.payloads {
            let these = records_with_mass(runs, p.mass);
            let m = p.mass;
            let label = mass_label(m);
            let truth = move |t: f64| match pick_up {
                Some(tp) if t < tp => 0.0,
                _ => m,
            };
            let folded = self.fold(&format!("payload {label} kg"));
            self.figure(
                &format!("{}{label}", per_payload::IDENTIFICATION),
                &format!("Error and identified mass against time, payload {label} kg"),
                &figures::identification(
                    &format!("Payload {label} kg: error and identified mass"),
                    &these,
                    &truth,
                ),
            )?;
            if folded {
                self.report.end_details();
            }
        }
        Ok(())
    }

    /// Drives, sensors and faults: the counters per run, the torque ratios,
    /// the measurement errors.
    fn drives(&mut self) -> anyhow::Result<()> {
        let (scenario, runs) = (self.scenario, self.runs);
        let robot = &scenario.experiment.robot;
        let effects = scenario.file.effects();
        let report = &mut self.report;
        report.heading("Drives, sensors and faults");
        report.paragraph(format!(
            "This scenario turns on: {}. Counters over each run: `faults` = samples whose \
             measurement was missing, invalid or implausible (the controller ran on its \
             model's prediction), `saturated samples` = samples at which the commanded torque \
             of some joint reached its limit, `max |τ|/τmax` = the largest commanded torque \
             relative to its limit.",
            effects.join("; ")
        ));
        report.table(Table {
            caption: "Drives, sensors and faults per run".into(),
            header: [
                "run",
                "status",
                "faults",
                "saturated samples",
                "max |τ|/τmax",
                "how it ended",
            ]
            .iter()
            .map(|s| s.to_string())
            .collect(),
            rows: runs
                .iter()
                .map(|r| {
                    let m = &r.metrics;
                    vec![
                        m.name.clone(),
                        m.status.to_string(),
                        m.faults.to_string(),
                        m.saturated_samples.to_string(),
                        format!("{:.3}", m.max_torque_ratio),
                        m.reason.clone(),
                    ]
                })
                .collect(),
        });
        if let Some(plant) = plant_report(scenario)? {
            plant_section(report, &plant);
        }
        let limits: Vec<f64> = robot.joints().iter().map(|j| j.limits.effort).collect();
        for p in self.payloads {
            let these = records_with_mass(runs, p.mass);
            let label = mass_label(p.mass);
            let folded = self.fold(&format!("payload {label} kg"));
            self.figure(
                &format!("{}{label}", per_payload::TORQUE_RATIOS),
                &format!("Commanded torque relative to the drives' limits, payload {label} kg"),
                &figures::torque_ratios(
                    &format!("|τ| / τmax, payload {label} kg"),
                    &these,
                    &limits,
                ),
            )?;
            if folded {
                self.report.end_details();
            }
        }
        let measured = self.files.measurement;
        if measured {
            self.report
                .details("Measured − true position, per run (what the controller was given)");
        }
        for r in runs
            .iter()
            .filter(|r| measured && r.result.record.has_measurement())
        {
            let name = &r.metrics.name;
            self.figure(
                &format!("{name}/{}", per_run::MEASUREMENT_ERROR),
                &format!("{name}: what the controller was given minus the true position (gaps: lost measurements)"),
                &figures::measurement_errors(
                    &format!("{name}: measured − true position"),
                    &r.result.record,
                ),
            )?;
        }
        if measured {
            self.report.end_details();
        }
        Ok(())
    }

    /// Steady and RMS errors against payload.
    fn sweep(&mut self) -> anyhow::Result<()> {
        let metrics = self.metrics;
        self.report.heading("Payload sweep");
        self.figure(
            PAYLOAD_SWEEP,
            "Steady and RMS Cartesian error against payload (markers: diverged runs, at the error when stopped)",
            &figures::payload_sweep("Cartesian error against payload", metrics),
        )
    }

    /// The "Controllers compared" section ([`crate::output::compare`]).
    fn compare(&mut self) -> anyhow::Result<()> {
        let limits: Vec<f64> = (self.scenario.experiment.robot.joints().iter())
            .map(|j| j.limits.effort)
            .collect();
        let dir = &mut *self.dir;
        crate::output::compare::section(
            &mut self.report,
            self.metrics,
            self.controllers,
            &limits,
            &mut |report, rel, caption, fig| figure(dir, report, rel, caption, fig),
        )
    }

    /// Each run's time series, joints and torques (Fig. 5), Cartesian error. In the page each
    /// run is folded (`<details>`), and the per-run Cartesian error (the same curve as in the
    /// per-payload figure) is only written as files, not shown twice.
    fn each_run(&mut self) -> anyhow::Result<()> {
        self.report
            .heading("Each run: joints and torques (the paper's Fig. 5)");
        self.report.paragraph(
            "One folded part per run (click to open). Each run's folder also holds its time series \
             (timeseries.csv) and its Cartesian error (cartesian_error.png, .svg; the same curve as in \
             the per-payload figure above).",
        );
        for r in self.runs {
            let name = &r.metrics.name;
            let rec = &r.result.record;
            let stride = self.scenario.file.output.timeseries_stride_of(
                rec.len(),
                timeseries_bytes_per_row(rec.n),
                self.runs.len(),
            );
            if let Some(stride) = stride {
                self.dir.write(
                    format!("{name}/{TIMESERIES}"),
                    timeseries_csv_every(rec, stride).as_bytes(),
                )?;
            }
            let m = &r.metrics;
            self.report.details(format!(
                "{name}: {}, RMS Cartesian error {}",
                m.status,
                crate::verdict::mm(m.cartesian_error_rms_mm)
            ));
            if m.status != RunStatus::Ok {
                self.report
                    .paragraph(format!("{name}: {}", r.result.outcome));
            }
            self.figure(
                &format!("{name}/{}", per_run::JOINTS_TORQUES),
                &format!("Fig. 5, {name}: joint coordinates and torques"),
                &figures::joints_and_torques(
                    &format!("{name}: joints and torques"),
                    &r.result.record,
                ),
            )?;
            self.report.end_details();
            let rel = format!("{name}/{}", per_run::CARTESIAN_ERROR);
            let fig = figures::cartesian_errors(
                &format!("{name}: Cartesian error"),
                &[(kind_name(r.kind), &r.result.record)],
            );
            let rendered = render_both(&fig).with_context(|| format!("rendering {rel}"))?;
            self.dir.write(format!("{rel}.png"), &rendered.png)?;
            self.dir
                .write(format!("{rel}.svg"), rendered.svg.as_bytes())?;
        }
        Ok(())
    }

    /// `metrics.json`: the runs, and the plant block when the plant is not the model.
    fn metrics_json(&self) -> anyhow::Result<String> {
        let plant = plant_report(self.scenario)?;
        Ok(metrics_json_with_plant(self.metrics, plant.as_ref())?)
    }

    /// `metrics.json`, the effective `scenario.toml` and `report.html`.
    fn finish(mut self) -> anyhow::Result<()> {
        self.dir.write(METRICS, self.metrics_json()?.as_bytes())?;
        // What ran: repeats removed; paths are absolute (see `ScenarioFile::from_file`), so the
        // file re-runs from any working directory.
        let effective = self
            .scenario
            .effective_file(self.payloads, self.controllers)
            .to_toml()
            .context("writing the effective scenario")?;
        let effective = format!(
            "# The scenario of this run, every default filled in: `ofmpc run scenario.toml` repeats it.\n{effective}"
        );
        self.report.heading("Scenario");
        self.report.code(effective.clone());
        self.dir.write(SCENARIO, effective.as_bytes())?;
        self.dir.write(REPORT, self.report.to_html()?.as_bytes())?;
        Ok(())
    }
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
        match ofmpc_scenario::analysis::margin(scenario, k).map_err(anyhow::Error::from) {
            Ok(m) => text.push_str(&format!(
                " the {k} algorithm is stable for an inertia ratio α = H_model/H_plant in {:.3}–{:.3}, \
                 i.e. a point payload up to {:.2} kg that the model does not know;",
                m.alpha_interval[0], m.alpha_interval[1], m.max_payload_kg
            )),
            Err(e) => text.push_str(&format!(" the {k} algorithm's margin could not be computed ({});",
                ofmpc_scenario::chain_text(e.as_ref()))),
        }
    }
    text.push_str(
        " a divergence beyond those payloads is the physics of the tuning, not a numerical failure. \
         The adaptive variants identify the payload and keep α near 1; `ofmpc tune` finds weights for a payload range.",
    );
    text
}

/// `(controller, record)` of the runs with payload `mass`, in run order.
fn records_with_mass(runs: &[Run], mass: f64) -> Vec<(&'static str, &ofmpc::sim::Record)> {
    runs.iter()
        .filter(|r| r.payload.mass == mass)
        .map(|r| (kind_name(r.kind), &r.result.record))
        .collect()
}
