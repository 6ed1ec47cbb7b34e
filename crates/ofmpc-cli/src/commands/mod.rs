//! The commands. Each returns `anyhow::Result`; `main` prints the error chain.

pub(crate) mod experiment;
mod inspect;
mod robot;
mod trajectory;

use crate::cli::{Cli, Command, Inspect};
use crate::scenario::{Scenario, ScenarioFile};

pub use robot::{load_robot, parse_fixed, parse_vector};

/// Runs one command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Inspect(Inspect::Dynamics(a)) => inspect::dynamics(&a),
        Command::Inspect(Inspect::Robot(a)) => inspect::robot(&a),
        Command::Trajectory(a) => trajectory::trajectory(&a),
        Command::Run(a) => {
            let file = ScenarioFile::from_file(&a.scenario)?;
            let scenario = Scenario::resolve(&file)
                .map_err(|e| anyhow::anyhow!("{}: {e:#}", a.scenario.display()))?;
            experiment::execute(&scenario, Some(&a.scenario), &a.out)
        }
        Command::Reproduce(a) => {
            let mut file = ScenarioFile::default();
            // Absolute, so that the scenario.toml written with the results re-runs from any
            // working directory.
            file.program.file = a.program.as_deref().map(crate::scenario::absolute);
            file.payload.masses_kg = parse_vector("--payload", &a.payload, None)?;
            let scenario = Scenario::resolve(&file)?;
            experiment::execute(&scenario, None, &a.out)
        }
    }
}
