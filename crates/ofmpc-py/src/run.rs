//! `ofmpc.run`: a whole scenario (every payload × controller) run in Rust with
//! the GIL released, through the scenario crate's loader and runner (those of
//! the `ofmpc` command); the result is the text of `metrics.json` (the Python
//! side parses it).

use crate::errors::chain_to_py;
use ofmpc_scenario::{metrics_json, run_metrics, Scenario, ScenarioFile};
use pyo3::prelude::*;
use std::path::PathBuf;

fn run_file_inner(file: &ScenarioFile, origin: &str) -> anyhow::Result<String> {
    let scenario =
        Scenario::resolve(file).map_err(|e| anyhow::Error::new(e).context(origin.to_string()))?;
    // The robot's and the drives' warnings, on stderr as the command prints them.
    for w in &scenario.warnings {
        eprintln!("warning: {w}");
    }
    Ok(metrics_json(&run_metrics(&scenario)?)?)
}

/// Runs a scenario file (TOML, paths inside relative to it); returns metrics.json's text.
#[pyfunction]
#[pyo3(name = "_run_file")]
pub fn run_file(py: Python<'_>, path: PathBuf) -> PyResult<String> {
    py.detach(|| {
        let file = ScenarioFile::from_file(&path)?;
        run_file_inner(&file, &path.display().to_string())
    })
    .map_err(chain_to_py)
}

/// Runs a scenario given as JSON text with the keys of the TOML file (paths
/// inside relative to the working directory); returns metrics.json's text.
#[pyfunction]
#[pyo3(name = "_run_json")]
pub fn run_json(py: Python<'_>, text: String) -> PyResult<String> {
    py.detach(|| {
        // Sections written as lists are refused, naming them (never read by position).
        let file = ScenarioFile::from_json(&text)?;
        run_file_inner(&file, "scenario")
    })
    .map_err(chain_to_py)
}
