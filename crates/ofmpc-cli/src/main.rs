//! `ofmpc`: inspect robot models, plan trajectories from G-code, run and
//! reproduce the paper's closed-loop experiments.
//!
//! Exit status: 0 on success and when stdout is closed early (`ofmpc inspect robot | head -1`
//! stops quietly, like ripgrep); 2 on an error (the message on stderr); 130 / 143 / 129 on
//! SIGINT / SIGTERM / SIGHUP, after removing the run's staging folder and lock (a signal
//! inherited as ignored, as SIGHUP under `nohup`, stays ignored).

use clap::Parser;
use ofmpc_cli::output::{cleanup, console};
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = ofmpc_cli::cli::Cli::parse();
    if let Err(e) = cleanup::install_signal_handler() {
        console::warn(&format!(
            "cannot watch for Ctrl-C ({e}): an interrupted run may leave a hidden .ofmpc-stage-* \
             folder, removed by the next run"
        ));
    }
    match ofmpc_cli::commands::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if console::is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            use std::io::Write;
            // The chain `a: b: c`, a cause the message already holds said once.
            let _ = writeln!(
                std::io::stderr().lock(),
                "error: {}",
                ofmpc_scenario::chain_text(e.as_ref())
            );
            // 1: the runs were made and written, but some failed; 2: nothing was run.
            if e.downcast_ref::<ofmpc_cli::errors::RunsFailed>().is_some() {
                ExitCode::from(1)
            } else {
                ExitCode::from(2)
            }
        }
    }
}
