//! Scenarios of ofmpc: what `ofmpc run` and `ofmpc.run` (Python) read and run.
//!
//! Two stages, as in ripgrep: [`ScenarioFile`] is what the user wrote (TOML,
//! serde, defaults filled in, [`Override`]s applied to the document before it
//! is deserialized), [`Scenario`] is the resolved experiment (robot loaded,
//! program parsed and timed, reference built, every setting checked).
//! `examples/scenario.toml` documents every key.
//!
//! * [`file`](mod@file): the file's types and loader; its sections `[mpc]`,
//!   `[simulation]` and `[plant]` are the library's own settings types.
//! * [`resolve`]: [`Scenario::resolve`], robot and program loading.
//! * [`runner`]: every payload × controller in parallel ([`run_jobs`]), their
//!   metrics ([`run_metrics`], [`metrics_json`]).
//! * [`analysis`]: stability margins ([`analysis::margin`]) and robust tuning
//!   ([`analysis::robust_tuning`]).
//! * [`error`]: [`ScenarioError`], which names the file, key and value; the
//!   front ends (the `ofmpc` command, the Python bindings) add their own advice.

#![warn(missing_docs)]

pub mod analysis;
pub mod baseline_tuning;
pub mod error;
pub mod file;
pub mod placement;
pub mod program_json;
pub mod resolve;
pub mod robustness;
pub mod runner;

pub use error::{
    chain_text, experiment_error, experiment_key, plan_error_message, ScenarioError, SettingNames,
    SCENARIO_KEYS,
};
pub use file::{
    absolute, expand_shorthand, mode_name, parse_mode, parse_profile, profile_name, FaultsSection,
    OrientationSection, OutputSection, Override, PayloadSection, ProgramSection, RobotSection,
    SafetySection, ScenarioFile, TimeseriesOutput, TimingSection, AUTO_TIMESERIES_BYTES,
    AUTO_TIMESERIES_TOTAL_BYTES,
};
pub use placement::{place_paper_program, Placement};
pub use program_json::{program_json, program_json_with_tool_axis};
pub use resolve::{
    is_model_path, load_plant_robot, load_robot, load_robot_section, load_robot_with, read_program,
    read_tool_table, urdf_warning_lines, Scenario,
};
pub use runner::{
    metrics_json, metrics_json_with_plant, plant_report, run_jobs, run_jobs_cancellable,
    run_metrics, run_metrics_cancellable, unique_runs, LinkDraw, PlantReport, Run,
};
