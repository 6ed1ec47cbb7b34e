//! `ofmpc.run`: a whole scenario (every payload × controller) run in Rust with
//! the GIL released, through the scenario crate's loader and runner (those of
//! the `ofmpc` command); the result is the text of `metrics.json` (the Python
//! side parses it).
//!
//! The runs go on in a worker thread while the calling thread waits with the
//! GIL released and checks for signals every [`SIGNAL_POLL`]: a Ctrl-C sets the
//! runs' cancel flag (each run checks it before every sample), the worker is
//! joined, and the signal's exception (`KeyboardInterrupt`) is raised.

use crate::errors::chain_to_py;
use ofmpc_scenario::{metrics_json, run_metrics_cancellable, Scenario, ScenarioFile};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// How often the waiting thread checks for signals (Ctrl-C is raised within about this
/// long plus one sample of each running run).
const SIGNAL_POLL: Duration = Duration::from_millis(20);

fn run_file_inner(
    file: &ScenarioFile,
    origin: &str,
    cancel: &AtomicBool,
) -> anyhow::Result<String> {
    let scenario =
        Scenario::resolve(file).map_err(|e| anyhow::Error::new(e).context(origin.to_string()))?;
    // The robot's and the drives' warnings, on stderr as the command prints them.
    for w in &scenario.warnings {
        eprintln!("warning: {w}");
    }
    Ok(metrics_json(&run_metrics_cancellable(&scenario, cancel)?)?)
}

/// Runs `work` in a worker thread, the GIL released, checking for signals meanwhile: on a
/// signal's exception (Ctrl-C: `KeyboardInterrupt`) the work is cancelled through its
/// flag, joined, and the exception raised.
fn interruptible<F>(py: Python<'_>, work: F) -> PyResult<String>
where
    F: FnOnce(&AtomicBool) -> anyhow::Result<String> + Send,
{
    let cancel = AtomicBool::new(false);
    let cancel = &cancel;
    let waiter = std::thread::current();
    std::thread::scope(|s| {
        let worker = s.spawn(move || {
            let result = work(cancel);
            waiter.unpark();
            result
        });
        loop {
            if worker.is_finished() {
                return match worker.join() {
                    Ok(result) => result.map_err(chain_to_py),
                    Err(_) => Err(chain_to_py(anyhow::anyhow!(
                        "the run stopped on an internal error (a bug: please report it)"
                    ))),
                };
            }
            // A spurious or early wake-up only checks again.
            py.detach(|| std::thread::park_timeout(SIGNAL_POLL));
            if let Err(signal) = py.check_signals() {
                cancel.store(true, Ordering::Relaxed);
                // The runs end at their next sample; their result is dropped.
                let _ = py.detach(|| worker.join());
                return Err(signal);
            }
        }
    })
}

/// Runs `work` in a thread of its own, the GIL released, checking for signals meanwhile (as
/// [`interruptible`] does) for work that has no cancel flag (a program's reading and
/// planning, issue #36: Ctrl-C waited for them to end). On a signal's exception the call
/// returns it at once; the thread ends on its own later (its work is bounded by the
/// program's limits) and its result is dropped.
pub(crate) fn answering_signals<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce() -> PyResult<T> + Send + 'static,
{
    let waiter = std::thread::current();
    let worker = std::thread::spawn(move || {
        let result = work();
        waiter.unpark();
        result
    });
    loop {
        if worker.is_finished() {
            return worker.join().unwrap_or_else(|_| {
                Err(chain_to_py(anyhow::anyhow!(
                    "the call stopped on an internal error (a bug: please report it)"
                )))
            });
        }
        py.detach(|| std::thread::park_timeout(SIGNAL_POLL));
        py.check_signals()?;
    }
}

/// Runs a scenario file (TOML, paths inside relative to it); returns metrics.json's text.
#[pyfunction]
#[pyo3(name = "_run_file")]
pub fn run_file(py: Python<'_>, path: PathBuf) -> PyResult<String> {
    interruptible(py, move |cancel| {
        let file = ScenarioFile::from_file(&path)?;
        run_file_inner(&file, &path.display().to_string(), cancel)
    })
}

/// Runs a scenario given as JSON text with the keys of the TOML file (paths
/// inside relative to the working directory); returns metrics.json's text.
#[pyfunction]
#[pyo3(name = "_run_json")]
pub fn run_json(py: Python<'_>, text: String) -> PyResult<String> {
    interruptible(py, move |cancel| {
        // Sections written as lists are refused, naming them (never read by position).
        let file = ScenarioFile::from_json(&text)?;
        run_file_inner(&file, "scenario", cancel)
    })
}
