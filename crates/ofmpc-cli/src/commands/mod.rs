//! The commands. Each returns `anyhow::Result`; `main` prints the error chain.

pub mod analyze;
pub(crate) mod experiment;
mod inspect;
mod robot;
mod trajectory;
pub mod tune;

use crate::cli::{Analyze, Cli, Command, Inspect};
use crate::scenario::{Scenario, ScenarioFile};

pub use robot::{load_robot, parse_fixed, parse_vector};

/// Runs one command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Inspect(Inspect::Dynamics(a)) => inspect::dynamics(&a),
        Command::Inspect(Inspect::Robot(a)) => inspect::robot(&a),
        Command::Trajectory(a) => trajectory::trajectory(&a),
        Command::Run(a) => {
            let mut file = ScenarioFile::from_file(&a.scenario)?;
            if let Some(p) = &a.payload {
                file.payload.masses_kg = parse_vector("--payload", p, None)?;
            }
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
            file.controllers = parse_controllers("--controllers", &a.controllers)?;
            file.payload.pick_up_at_s = a.pick_up_at;
            let scenario = Scenario::resolve(&file)?;
            experiment::execute(&scenario, None, &a.out)
        }
        Command::Analyze(Analyze::Stability(a)) => analyze::stability(&a),
        Command::Tune(a) => tune::tune(&a),
    }
}

/// Parses a comma-separated list of controller names for option `name`.
pub fn parse_controllers(
    name: &str,
    text: &str,
) -> anyhow::Result<Vec<ofmpc::control::ControllerKind>> {
    let mut v = Vec::new();
    for (i, part) in text.split(',').enumerate() {
        let k: ofmpc::control::ControllerKind = part
            .trim()
            .parse()
            .map_err(|e| anyhow::anyhow!("{name}: value {} '{}': {e}", i + 1, part.trim()))?;
        if !v.contains(&k) {
            v.push(k);
        }
    }
    Ok(v)
}
