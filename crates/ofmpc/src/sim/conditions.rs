//! What a run meets besides its loop settings ([`super::LoopSettings`], a
//! scenario's `[simulation]`): the payload's pick-up, the safety function and
//! the measurement faults, each the settings type of the section it is read
//! from (`[payload]`'s `pick_up_at_s`, `[safety]`, `[faults]`), and the
//! horizons to record. Gathered in [`RunConditions`] and given to the loop
//! when it is built ([`super::ClosedLoop::with_conditions`]).

use super::faults::MeasurementFaults;
use super::horizon::HorizonSampling;
use super::settings_error::LoopSettingsError;
use serde::{Deserialize, Serialize};

/// The events, checks and faults of a run that are not loop settings: each
/// comes from its own scenario section, deserialized as it is.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunConditions {
    /// When the plant picks up its payload (s, path time): it carries none
    /// before and the payload of the run from then on. `None`: from the
    /// start. The controllers are not told.
    pub pick_up_at_s: Option<f64>,
    /// The safety function: a joint error beyond its limit brings the robot
    /// to a safe stop ([`super::Supervisor`]).
    pub safety: SafetySettings,
    /// Invalid and missing measurements (the controller runs on its own
    /// prediction over them).
    pub faults: MeasurementFaults,
    /// Record what a predictive controller predicts over its horizon at these samples
    /// ([`super::Record::horizons`], for the report's replay; computed only at those samples,
    /// it changes nothing of the run). `None`: off.
    pub horizons: Option<HorizonSampling>,
}

impl RunConditions {
    /// No pick-up (the payload is carried from the start), no safety limit,
    /// no fault, no horizon recorded: [`RunConditions::default`] as a
    /// constant.
    pub const NONE: RunConditions = RunConditions {
        pick_up_at_s: None,
        safety: SafetySettings {
            max_joint_error_rad: None,
        },
        faults: MeasurementFaults {
            nan_at_s: Vec::new(),
            dropout_s: Vec::new(),
        },
        horizons: None,
    };

    /// Checks the values: a pick-up time `≥ 0`, a joint error limit `> 0`,
    /// fault times `≥ 0` and dropouts `0 ≤ from < to`, all finite.
    pub fn validate(&self) -> Result<(), LoopSettingsError> {
        if let Some(t) = self.pick_up_at_s {
            if !(t.is_finite() && t >= 0.0) {
                return Err(LoopSettingsError::PickUpTime(t));
            }
        }
        if let Some(e) = self.safety.max_joint_error_rad {
            if !(e.is_finite() && e > 0.0) {
                return Err(LoopSettingsError::MaxJointError(e));
            }
        }
        self.faults.validate()
    }
}

/// The safety function of a run: a joint error (of the state the controller
/// is given) beyond `max_joint_error_rad` brings the robot to a safe stop
/// ([`super::Supervisor`]). A scenario's `[safety]` section.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SafetySettings {
    /// Joint error limit (rad); off when absent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_joint_error_rad: Option<f64>,
}
