//! The settings text of the C API: a scenario's `[mpc]`, `[baselines]`,
//! `[plant]`, `[simulation]`, `[safety]` and `[faults]` tables as TOML
//! (every key as in docs/guide/reference/scenario.md; a whole scenario
//! file is accepted, its other tables ignored).

use crate::ffi::{ofmpc_status, Failure};
use ofmpc::control::ObserverSettings;
use ofmpc::sim::{LoopSettings, MeasurementFaults, PlantSettings, SafetySettings, OBSERVER_POLE};
use ofmpc::{BaselineSettings, Controller, ControllerBuilder, ControllerKind, MpcSettings, Robot};
use serde::Deserialize;

/// The tables the C API reads; the scenario's others are accepted and ignored.
#[derive(Debug, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub(crate) struct Settings {
    pub mpc: MpcSettings,
    pub baselines: BaselineSettings,
    pub plant: PlantSettings,
    pub simulation: LoopSettings,
    pub safety: SafetySettings,
    pub faults: MeasurementFaults,
    // A scenario file's other keys: read by `ofmpc run`, not by the C API.
    title: Option<toml::Value>,
    controllers: Option<toml::Value>,
    robot: Option<toml::Value>,
    payload: Option<toml::Value>,
    program: Option<toml::Value>,
    timing: Option<toml::Value>,
    orientation: Option<toml::Value>,
}

impl Settings {
    /// Parses the settings text (NULL text: every default).
    pub fn parse(text: Option<&str>) -> Result<Self, Failure> {
        let Some(text) = text else {
            return Ok(Self::default());
        };
        toml::from_str(text).map_err(|e| {
            Failure::new(
                ofmpc_status::OFMPC_PARSE,
                format!("settings TOML: {}", e.to_string().trim_end()),
            )
        })
    }
}

/// The kind named `name` ("second", "pid", …).
pub(crate) fn kind(name: &str) -> Result<ControllerKind, Failure> {
    name.parse::<ControllerKind>().map_err(|e| {
        Failure::new(
            ofmpc_status::OFMPC_INVALID_ARG,
            format!("kind {name:?}: {e}"),
        )
    })
}

/// The controller `kind` on `robot` as `ofmpc run` builds it from the same
/// settings: the tuning, the baselines' gains, an observer when the settings
/// ask for one (with the plant's measurement delay).
pub(crate) fn build_controller(
    robot: &Robot,
    kind: ControllerKind,
    s: &Settings,
) -> Result<Controller, Failure> {
    let mut builder = ControllerBuilder::new(kind, robot)
        .settings(s.mpc.clone())
        .accept_ineffective_settings();
    if kind.is_baseline() {
        builder = builder.baselines(s.baselines.clone());
    }
    if s.mpc.state_observer || s.mpc.delay_compensation {
        builder = builder.observer(ObserverSettings {
            pole: OBSERVER_POLE,
            measurement_delay: s.plant.delay_samples,
        });
    }
    builder.build().map_err(|e| {
        Failure::new(
            ofmpc_status::OFMPC_BUILD,
            format!("the {kind} controller cannot be built: {}", chain(&e)),
        )
    })
}

/// An error and its sources, "a: b: c".
pub(crate) fn chain(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let s_text = s.to_string();
        if !text.contains(&s_text) {
            text.push_str(": ");
            text.push_str(&s_text);
        }
        source = s.source();
    }
    text
}
