//! The job runner: a resolved scenario turned into runs (repeats removed,
//! every payload × controller in parallel) and their metrics. Front ends
//! write the results (`ofmpc run`) or return them (`ofmpc.run` in Python).

use crate::error::ScenarioError;
use crate::resolve::Scenario;
use ofmpc::control::ControllerKind;
use ofmpc::robot::Payload;
use ofmpc::sim::{kind_name, mass_label, run_name, ExperimentError, RunMetrics, RunResult};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// One finished run.
pub struct Run {
    /// The controller.
    pub kind: ControllerKind,
    /// The payload the plant carried.
    pub payload: Payload,
    /// The record and how the run ended.
    pub result: RunResult,
    /// Its line of `metrics.json`.
    pub metrics: RunMetrics,
}

/// The payloads and controllers of a scenario with repeats removed (a repeat would write the
/// same run folder twice); `-0` counts as `0`. Returns the warnings for the repeats.
pub fn unique_runs(scenario: &Scenario) -> (Vec<Payload>, Vec<ControllerKind>, Vec<String>) {
    let mut warnings = Vec::new();
    let mut payloads: Vec<Payload> = Vec::new();
    for p in &scenario.payloads {
        let mut p = *p;
        p.mass += 0.0; // -0.0 → 0.0: one run folder `_m0`
                       // Same folder name (the label rounds masses past 6 digits) = same run.
        if payloads
            .iter()
            .any(|q| mass_label(q.mass) == mass_label(p.mass))
        {
            warnings.push(format!(
                "the payload {} kg is listed more than once ({:?}): it is run once",
                mass_label(p.mass),
                scenario.file.payload.masses_kg
            ));
        } else {
            payloads.push(p);
        }
    }
    let mut controllers: Vec<ControllerKind> = Vec::new();
    for k in &scenario.file.controllers {
        if controllers.contains(k) {
            warnings.push(format!(
                "the controller \"{}\" is listed more than once: it is run once per payload",
                kind_name(*k)
            ));
        } else {
            controllers.push(*k);
        }
    }
    warnings.dedup();
    (payloads, controllers, warnings)
}

/// Runs every payload × controller (payloads outer, controllers inner: the
/// order of `metrics.json`) in parallel. `progress(samples)` is called as
/// samples are simulated.
pub fn run_jobs(
    scenario: &Scenario,
    payloads: &[Payload],
    controllers: &[ControllerKind],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Run>, ScenarioError> {
    run_jobs_cancellable(
        scenario,
        payloads,
        controllers,
        progress,
        &AtomicBool::new(false),
    )
}

/// [`run_jobs`] that stops when `cancel` becomes true (set by another thread, e.g. on a
/// user's Ctrl-C): the running runs end at their next sample and the others do not start;
/// the result is then the error of an interrupted run ([`ExperimentError::Interrupted`]
/// in [`ScenarioError::Run`]).
pub fn run_jobs_cancellable(
    scenario: &Scenario,
    payloads: &[Payload],
    controllers: &[ControllerKind],
    progress: &(dyn Fn(u64) + Sync),
    cancel: &AtomicBool,
) -> Result<Vec<Run>, ScenarioError> {
    let exp = &scenario.experiment;
    let jobs: Vec<(ControllerKind, Payload)> = payloads
        .iter()
        .flat_map(|p| controllers.iter().map(move |k| (*k, *p)))
        .collect();
    jobs.par_iter()
        .map(|&(kind, payload)| {
            let mut last = 0usize;
            // A run not started when the flag is set does not start.
            let ran = if cancel.load(Ordering::Relaxed) {
                Err(ExperimentError::Interrupted { t: 0.0 })
            } else {
                exp.run_cancellable(
                    kind,
                    &payload,
                    &mut |k, _| {
                        progress((k - last) as u64);
                        last = k;
                    },
                    cancel,
                )
            };
            let (result, metrics) = ran.map_err(|error| ScenarioError::Run {
                run: run_name(kind, &payload),
                error: Box::new(error),
            })?;
            Ok(Run {
                kind,
                payload,
                result,
                metrics,
            })
        })
        .collect()
}

/// Runs a scenario as `ofmpc run` does (repeats removed; the caller warns about them
/// from [`unique_runs`]) and returns the metrics of its runs.
pub fn run_metrics(scenario: &Scenario) -> Result<Vec<RunMetrics>, ScenarioError> {
    run_metrics_cancellable(scenario, &AtomicBool::new(false))
}

/// [`run_metrics`] that stops when `cancel` becomes true ([`run_jobs_cancellable`]).
pub fn run_metrics_cancellable(
    scenario: &Scenario,
    cancel: &AtomicBool,
) -> Result<Vec<RunMetrics>, ScenarioError> {
    let (payloads, controllers, _) = unique_runs(scenario);
    Ok(
        run_jobs_cancellable(scenario, &payloads, &controllers, &|_| {}, cancel)?
            .into_iter()
            .map(|r| r.metrics)
            .collect(),
    )
}

/// The text of `metrics.json` for these metrics: `{"runs": [...]}`, pretty-printed.
pub fn metrics_json(runs: &[RunMetrics]) -> Result<String, ScenarioError> {
    metrics_json_with_plant(runs, None)
}

/// The plant that is not the model, as `metrics.json`'s `plant` block says it: the drawn
/// relative errors of `[plant] inertia_error` and the plant's own robot and drives files.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PlantReport {
    /// `[plant] inertia_error` (relative standard deviation).
    pub inertia_error: f64,
    /// `[plant] seed`, which drew them.
    pub seed: u64,
    /// The relative errors drawn, link by link (empty without `inertia_error`).
    pub links: Vec<LinkDraw>,
    /// `[plant] robot`, when set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub robot: Option<String>,
    /// `[plant] drives`, when set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drives: Option<String>,
}

/// One link's drawn relative errors ([`PlantReport`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LinkDraw {
    /// The link (URDF).
    pub link: String,
    /// The errors.
    #[serde(flatten)]
    pub error: ofmpc::robot::LinkInertiaError,
}

/// The plant block of a scenario's runs: `None` when the plant is the model (no
/// `[plant] inertia_error`, robot or drives), so `metrics.json` stays as it was.
pub fn plant_report(scenario: &Scenario) -> Result<Option<PlantReport>, ScenarioError> {
    let e = &scenario.experiment;
    let p = &e.plant;
    if p.inertia_error == 0.0 && p.robot.is_none() && p.drives.is_none() {
        return Ok(None);
    }
    let (robot, draws) = p
        .plant_robot(&e.robot)
        .map_err(|error| ScenarioError::experiment(None, error.into()))?;
    let links = robot
        .joints()
        .iter()
        .zip(draws)
        .map(|(j, error)| LinkDraw {
            link: j.link.clone(),
            error,
        })
        .collect();
    let path = |p: &Option<std::path::PathBuf>| p.as_ref().map(|p| p.display().to_string());
    Ok(Some(PlantReport {
        inertia_error: p.inertia_error,
        seed: p.seed,
        links,
        robot: path(&p.robot),
        drives: path(&p.drives),
    }))
}

/// `metrics.json` with the plant block ([`plant_report`]) when there is one.
pub fn metrics_json_with_plant(
    runs: &[RunMetrics],
    plant: Option<&PlantReport>,
) -> Result<String, ScenarioError> {
    #[derive(serde::Serialize)]
    struct MetricsFile<'a> {
        runs: &'a [RunMetrics],
        #[serde(skip_serializing_if = "Option::is_none")]
        plant: Option<&'a PlantReport>,
    }
    serde_json::to_string_pretty(&MetricsFile { runs, plant }).map_err(|e| ScenarioError::Write {
        what: "metrics.json",
        message: e.to_string(),
    })
}
