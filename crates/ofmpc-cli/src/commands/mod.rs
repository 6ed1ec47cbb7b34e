//! The commands. Each returns `anyhow::Result`; `main` prints the error chain.

pub mod analyze;
pub(crate) mod experiment;
pub mod init;
mod inspect;
mod robot;
pub mod robustness;
mod trajectory;
pub mod tune;
mod values;

use crate::cli::{Analyze, Cli, Command, Init, Inspect};
use ofmpc_scenario::{Override, Scenario, ScenarioError, ScenarioFile};

use robot::parse_vector;
use values::parse_controllers;

/// Runs one command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Inspect(Inspect::Dynamics(a)) => inspect::dynamics(&a),
        Command::Inspect(Inspect::Robot(a)) => inspect::robot(&a),
        Command::Inspect(Inspect::Program(a)) => inspect::program(&a),
        Command::Trajectory(a) => trajectory::trajectory(&a),
        Command::Run(a) => {
            let mut sets = shorthand_overrides(&Shorthands {
                controllers: a.controllers.as_deref(),
                robot: a.robot.as_deref(),
                origin: None,
                mode: a.mode.as_deref(),
            })?;
            sets.extend(chain_sets(&a.chain, a.tool_table.as_deref())?);
            sets.extend(parse_overrides(&a.set)?);
            let mut file = ScenarioFile::from_file_with(&a.scenario, &sets)
                .map_err(|e| override_error(e, Some(&a.scenario.display().to_string())))?;
            if let Some(p) = &a.payload {
                file.payload.masses_kg = parse_vector("--payload", p, None)?;
            }
            let mut scenario = Scenario::resolve(&file)
                .map_err(|e| anyhow::Error::new(e).context(a.scenario.display().to_string()))?;
            experiment::execute(&mut scenario, Some(&a.scenario), &a.out)
        }
        Command::Reproduce(a) => {
            let mut file = ScenarioFile::default();
            // Absolute, so that the scenario.toml written with the results re-runs from any
            // working directory.
            file.program.file = a.program.as_deref().map(ofmpc_scenario::absolute);
            let (payload, controllers) = compare_defaults(&a);
            file.payload.masses_kg = parse_vector("--payload", payload, None)?;
            file.controllers = parse_controllers("--controllers", controllers)?;
            file.payload.pick_up_at_s = a.pick_up_at;
            let mut sets = shorthand_overrides(&Shorthands {
                controllers: None,
                robot: a.robot.as_deref(),
                origin: a.origin.as_deref(),
                mode: a.mode.as_deref(),
            })?;
            sets.extend(chain_sets(&a.chain, a.tool_table.as_deref())?);
            sets.extend(parse_overrides(&a.set)?);
            let file = file
                .with_overrides(&sets)
                .map_err(|e| override_error(e, None))?;
            let mut scenario = Scenario::resolve(&file)?;
            experiment::execute(&mut scenario, None, &a.out)
        }
        Command::Analyze(Analyze::Stability(a)) => analyze::stability(&a),
        Command::Analyze(Analyze::Robustness(a)) => robustness::robustness_command(&a),
        Command::Tune(a) => tune::tune(&a),
        Command::Init(Init::Robot(a)) => init::robot(&a),
    }
}

/// The options of `run` and `reproduce` that are shorthands for a `--set` of one key.
struct Shorthands<'a> {
    /// `--controllers A,B` → `controllers = ["A", "B"]`.
    controllers: Option<&'a str>,
    /// `--robot R` → `robot.model = "R"`.
    robot: Option<&'a str>,
    /// `--origin X,Y,Z` → `program.origin_mm = [X, Y, Z]`.
    origin: Option<&'a str>,
    /// `--mode M` → `timing.mode = "M"`.
    mode: Option<&'a str>,
}

/// The overrides the shorthand options stand for, in the order above (before any `--set`, so
/// that `--set` has the last word). Lists are checked here, naming the option; the values
/// then meet every check of the scenario file, as the key written there would.
fn shorthand_overrides(s: &Shorthands) -> anyhow::Result<Vec<Override>> {
    let set = |key: &str, raw: &str, value: toml::Value| Override {
        key: key.into(),
        raw: raw.into(),
        value,
    };
    let mut v = Vec::new();
    if let Some(c) = s.controllers {
        let names = parse_controllers("--controllers", c)?
            .iter()
            .map(|k| toml::Value::String(k.name().to_string()))
            .collect();
        v.push(set("controllers", c, toml::Value::Array(names)));
    }
    if let Some(r) = s.robot {
        v.push(set("robot.model", r, toml::Value::String(r.into())));
    }
    if let Some(o) = s.origin {
        let xyz = parse_vector("--origin", o, Some(3))?;
        let xyz = xyz.into_iter().map(toml::Value::Float).collect();
        v.push(set("program.origin_mm", o, toml::Value::Array(xyz)));
    }
    if let Some(m) = s.mode {
        v.push(set("timing.mode", m, toml::Value::String(m.into())));
    }
    Ok(v)
}

/// The payloads and controllers of `reproduce`: those given, else the defaults (with
/// `--compare`, every controller over 0, 0.25, 1, 2, 6 kg). A value given is honoured even
/// when it equals a default (issue #36: `--compare --payload 0,0.25` was ignored).
fn compare_defaults(a: &crate::cli::ReproduceArgs) -> (&str, &str) {
    let (payload, controllers) = if a.compare {
        ("0,0.25,1,2,6", "all")
    } else {
        ("0,0.25", "usual,first,second")
    };
    (
        a.payload.as_deref().unwrap_or(payload),
        a.controllers.as_deref().unwrap_or(controllers),
    )
}

/// The overrides of `--tip`, `--tcp`, `--tcp-rpy`, `--start-q` and `--tool-table`.
fn chain_sets(
    c: &crate::args::ChainArgs,
    tool_table: Option<&std::path::Path>,
) -> anyhow::Result<Vec<Override>> {
    crate::chain_sets::chain_overrides(&crate::chain_sets::ChainFlags {
        tip: c.tip.as_deref(),
        tcp: c.tcp.as_deref(),
        tcp_rpy: c.tcp_rpy.as_deref(),
        start_q: c.start_q.as_deref(),
        tool_table,
    })
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
