//! The CLI's own errors. The scenario keys of the library's typed errors are
//! named by `ofmpc_scenario` ([`ofmpc_scenario::experiment_error`]); the
//! command-line flags by the commands.

use std::fmt;

/// Some runs failed (a controller step or the plant's integration); their
/// results were written, and the process exits with status 1.
#[derive(Debug)]
pub struct RunsFailed {
    /// `name: reason` of each failed run.
    pub runs: Vec<String>,
}

impl fmt::Display for RunsFailed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} run(s) failed (their results so far are in metrics.json with \"status\": \"failed\", or \"failed_stop\" for a safe stop that did not stop):",
            self.runs.len()
        )?;
        for r in &self.runs {
            write!(f, "\n  {r}")?;
        }
        Ok(())
    }
}

impl std::error::Error for RunsFailed {}
