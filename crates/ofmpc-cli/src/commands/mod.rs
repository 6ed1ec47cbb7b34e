//! The commands. Each returns `anyhow::Result`; `main` prints the error chain.

mod inspect;
mod robot;

use crate::cli::{Cli, Command, Inspect};

pub use robot::{load_robot, parse_vector};

/// Runs one command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Inspect(Inspect::Dynamics(a)) => inspect::dynamics(&a),
    }
}
