//! `ofmpc`: inspect robot models, plan trajectories from G-code, run and
//! reproduce the paper's closed-loop experiments.

mod cli;
mod commands;
mod figures;
mod output;
mod scenario;
mod tables;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = cli::Cli::parse();
    match commands::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
