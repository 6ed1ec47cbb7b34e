//! The scenario runner without the output layer: for callers that want the
//! numbers of `metrics.json` but no files (the Python bindings' `ofmpc.run`).

use crate::scenario::Scenario;
use ofmpc::control::ControllerKind;
use ofmpc::robot::Payload;
use ofmpc::sim::{run_name, RunMetrics};
use rayon::prelude::*;

/// Runs every payload × controller of `scenario` (payloads outer, controllers
/// inner: the order of `metrics.json`), in parallel, and returns their metrics.
pub fn run_metrics(scenario: &Scenario) -> anyhow::Result<Vec<RunMetrics>> {
    let exp = &scenario.experiment;
    let jobs: Vec<(ControllerKind, Payload)> = scenario
        .payloads
        .iter()
        .flat_map(|p| scenario.file.controllers.iter().map(move |k| (*k, *p)))
        .collect();
    jobs.par_iter()
        .map(|&(kind, payload)| {
            exp.run(kind, &payload, &mut |_, _| {})
                .map(|(_, metrics)| metrics)
                .map_err(|e| anyhow::anyhow!("{}: {e}", run_name(kind, &payload)))
        })
        .collect()
}

/// The text of `metrics.json` for these metrics: `{"runs": [...]}`, pretty-printed.
pub fn metrics_json(runs: &[RunMetrics]) -> anyhow::Result<String> {
    #[derive(serde::Serialize)]
    struct MetricsFile<'a> {
        runs: &'a [RunMetrics],
    }
    Ok(serde_json::to_string_pretty(&MetricsFile { runs })?)
}
