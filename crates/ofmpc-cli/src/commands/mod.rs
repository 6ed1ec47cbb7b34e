//! The commands. Each returns `anyhow::Result`; `main` prints the error chain.

pub mod analyze;
pub(crate) mod experiment;
mod inspect;
mod robot;
mod trajectory;
pub mod tune;

use crate::cli::{Analyze, Cli, Command, Inspect};
use ofmpc_scenario::{Override, Scenario, ScenarioError, ScenarioFile};

pub(crate) use robot::{load_model, load_robot, parse_fixed, parse_vector};

/// Runs one command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Inspect(Inspect::Dynamics(a)) => inspect::dynamics(&a),
        Command::Inspect(Inspect::Robot(a)) => inspect::robot(&a),
        Command::Inspect(Inspect::Program(a)) => inspect::program(&a),
        Command::Trajectory(a) => trajectory::trajectory(&a),
        Command::Run(a) => {
            let sets = parse_overrides(&a.set)?;
            let mut file = ScenarioFile::from_file_with(&a.scenario, &sets)
                .map_err(|e| override_error(e, Some(&a.scenario.display().to_string())))?;
            if let Some(p) = &a.payload {
                file.payload.masses_kg = parse_vector("--payload", p, None)?;
            }
            let scenario = Scenario::resolve(&file)
                .map_err(|e| anyhow::Error::new(e).context(a.scenario.display().to_string()))?;
            experiment::execute(&scenario, Some(&a.scenario), &a.out)
        }
        Command::Reproduce(a) => {
            let mut file = ScenarioFile::default();
            // Absolute, so that the scenario.toml written with the results re-runs from any
            // working directory.
            file.program.file = a.program.as_deref().map(ofmpc_scenario::absolute);
            file.payload.masses_kg = parse_vector("--payload", &a.payload, None)?;
            file.controllers = parse_controllers("--controllers", &a.controllers)?;
            file.payload.pick_up_at_s = a.pick_up_at;
            let file = file
                .with_overrides(&parse_overrides(&a.set)?)
                .map_err(|e| override_error(e, None))?;
            let scenario = Scenario::resolve(&file)?;
            experiment::execute(&scenario, None, &a.out)
        }
        Command::Analyze(Analyze::Stability(a)) => analyze::stability(&a),
        Command::Tune(a) => tune::tune(&a),
    }
}

/// Parses the `--set KEY=VALUE` options.
fn parse_overrides(sets: &[String]) -> anyhow::Result<Vec<Override>> {
    sets.iter()
        .map(|s| s.parse().map_err(|e| anyhow::anyhow!("--set {e}")))
        .collect()
}

/// A scenario error of loading with `--set` in the command line's words: an override that
/// does not fit names the option; other errors keep the scenario crate's words (prefixed by
/// `origin`, the scenario file, when they do not name it already).
fn override_error(e: ScenarioError, origin: Option<&str>) -> anyhow::Error {
    let prefix = origin.map(|o| format!("{o}: ")).unwrap_or_default();
    match e {
        ScenarioError::Override {
            key,
            value,
            message,
        } => anyhow::anyhow!(
            "{prefix}--set {key}={value}: {message} (examples/scenario.toml lists every key)"
        ),
        e @ (ScenarioError::Read { .. } | ScenarioError::Parse { .. }) => e.into(),
        e => match origin {
            Some(o) => anyhow::Error::new(e).context(o.to_string()),
            None => e.into(),
        },
    }
}

/// Parses a comma-separated list of controller names for option `name`.
pub(crate) fn parse_controllers(
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
