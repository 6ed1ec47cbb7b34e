//! `ofmpc`: inspect robot models, plan trajectories from G-code, run and
//! reproduce the paper's closed-loop experiments.

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = ofmpc_cli::cli::Cli::parse();
    match ofmpc_cli::commands::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            // 1: the runs were made and written, but some failed; 2: nothing was run.
            if e.downcast_ref::<ofmpc_cli::errors::RunsFailed>().is_some() {
                ExitCode::from(1)
            } else {
                ExitCode::from(2)
            }
        }
    }
}
