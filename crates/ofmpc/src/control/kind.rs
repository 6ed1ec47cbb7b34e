//! Which controller: the paper's three, the adaptive variants and the
//! baselines, by name.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Which controller: the paper's three, and the adaptive variants of the
/// incremental ones (`crate::control::adaptive`). Serde names: `"usual"`, `"first"`,
/// `"second"`, `"first-adaptive"`, `"second-adaptive"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ControllerKind {
    /// Usual positional MPC, Eq. (43): no integrator, steady offset under mismatch.
    Usual,
    /// First incremental algorithm, Eq. (32)/(37): one integrator.
    First,
    /// Second incremental algorithm, Eq. (34)/(39): two integrators.
    Second,
    /// The first algorithm with online payload identification ([`crate::control::AdaptiveMpc`]).
    #[serde(rename = "first-adaptive")]
    FirstAdaptive,
    /// The second algorithm with online payload identification ([`crate::control::AdaptiveMpc`]).
    #[serde(rename = "second-adaptive")]
    SecondAdaptive,
    /// Baseline: independent joint PID with gravity compensation and velocity
    /// feed-forward (`crate::control::baselines::pid`).
    Pid,
    /// Baseline: computed torque on the nominal model with PID on the error
    /// (`crate::control::baselines::ctc`).
    Ctc,
    /// Baseline: computed torque with the payload identified online by the
    /// adaptive controllers' estimator ([`crate::control::AdaptiveMpc`]).
    #[serde(rename = "ctc-adaptive")]
    CtcAdaptive,
    /// Baseline: offset-free MPC with an input-disturbance model and observer
    /// (`crate::control::baselines::dob_mpc`).
    #[serde(rename = "dob-mpc")]
    DobMpc,
}

impl ControllerKind {
    /// The paper's three, in its order of comparison.
    pub const PAPER: [ControllerKind; 3] = [
        ControllerKind::Usual,
        ControllerKind::First,
        ControllerKind::Second,
    ];

    /// Every kind: the paper's three, then the adaptive variants.
    pub const WITH_ADAPTIVE: [ControllerKind; 5] = [
        ControllerKind::Usual,
        ControllerKind::First,
        ControllerKind::Second,
        ControllerKind::FirstAdaptive,
        ControllerKind::SecondAdaptive,
    ];

    /// The baselines an engineer compares against: PID with gravity
    /// compensation, computed torque, adaptive computed torque and the
    /// disturbance-observer MPC (`crate::control::baselines::baseline`).
    pub const BASELINES: [ControllerKind; 4] = [
        ControllerKind::Pid,
        ControllerKind::Ctc,
        ControllerKind::CtcAdaptive,
        ControllerKind::DobMpc,
    ];

    /// Every kind: the paper's three ([`Self::PAPER`]), the adaptive
    /// variants, the baselines ([`Self::BASELINES`]).
    pub const ALL: [ControllerKind; 9] = [
        ControllerKind::Usual,
        ControllerKind::First,
        ControllerKind::Second,
        ControllerKind::FirstAdaptive,
        ControllerKind::SecondAdaptive,
        ControllerKind::Pid,
        ControllerKind::Ctc,
        ControllerKind::CtcAdaptive,
        ControllerKind::DobMpc,
    ];

    /// The lowercase name (`"usual"`, `"first"`, `"second"`,
    /// `"first-adaptive"`, `"second-adaptive"`, `"pid"`, `"ctc"`,
    /// `"ctc-adaptive"`, `"dob-mpc"`).
    pub fn name(self) -> &'static str {
        match self {
            ControllerKind::Usual => "usual",
            ControllerKind::First => "first",
            ControllerKind::Second => "second",
            ControllerKind::FirstAdaptive => "first-adaptive",
            ControllerKind::SecondAdaptive => "second-adaptive",
            ControllerKind::Pid => "pid",
            ControllerKind::Ctc => "ctc",
            ControllerKind::CtcAdaptive => "ctc-adaptive",
            ControllerKind::DobMpc => "dob-mpc",
        }
    }

    /// Whether it identifies the payload online.
    pub fn is_adaptive(self) -> bool {
        matches!(
            self,
            ControllerKind::FirstAdaptive
                | ControllerKind::SecondAdaptive
                | ControllerKind::CtcAdaptive
        )
    }

    /// Whether it is one of the baselines ([`Self::BASELINES`]), not a
    /// predictive controller of the paper.
    pub fn is_baseline(self) -> bool {
        Self::BASELINES.contains(&self)
    }

    /// The algorithm it runs: the adaptive variants' plain kind.
    pub fn base(self) -> ControllerKind {
        match self {
            ControllerKind::FirstAdaptive => ControllerKind::First,
            ControllerKind::SecondAdaptive => ControllerKind::Second,
            ControllerKind::CtcAdaptive => ControllerKind::Ctc,
            k => k,
        }
    }
}

impl fmt::Display for ControllerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An unknown controller name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown controller {0:?}: expected one of \"usual\", \"first\", \"second\", \"first-adaptive\", \"second-adaptive\", \"pid\", \"ctc\", \"ctc-adaptive\", \"dob-mpc\"")]
pub struct UnknownControllerKind(pub String);

impl FromStr for ControllerKind {
    type Err = UnknownControllerKind;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        ControllerKind::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| UnknownControllerKind(s.to_string()))
    }
}
