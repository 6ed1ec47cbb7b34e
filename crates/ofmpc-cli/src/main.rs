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
            ExitCode::from(2)
        }
    }
}
