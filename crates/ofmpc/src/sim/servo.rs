//! The servo interface stage: what a real arm's controller does between the
//! command it is streamed and the torque its drives apply
//! (`[plant.servo]`).
//!
//! The loop's controller runs every `Ts`; the arm's interface runs on its
//! own clock every `period_s` (at most `Ts`, not necessarily a divisor: a
//! 4 ms interface under a 10 ms controller has 2 or 3 cycles per period)
//! and its drives at the plant's integration substep (a whole divisor of
//! `period_s`). Per control period
//! the stage
//! 1. **receives** the controller's command ([`Servo::receive`]): its
//!    torque and, for an interface that closes its own joint loop, the
//!    predicted position, velocity and acceleration one lead time ahead
//!    ([`crate::control::OutputMode`], `control/command.rs`) — unless the
//!    controller's step was late;
//! 2. **sends** one setpoint per interface cycle: an on-time command is
//!    streamed along its own prediction (`q + q̇ τ + ½ q̈ τ²` at `τ` into the
//!    period, as a bridge between a 100 Hz planner and a 500 Hz interface
//!    interpolates); a cycle without a fresh command is a **miss**, bridged
//!    as [`OnLate`] says (hold the last setpoint, or extrapolate it), and
//!    `watchdog_misses` consecutive misses trip the robot's watchdog
//!    ([`Servo::tripped`]: the loop ends the run, `RunFailure::ServoWatchdog`);
//! 3. **delays** each setpoint by the interface's lag (`lag_s`, whole
//!    cycles, sample-and-hold per cycle);
//! 4. **drives** the joints at every substep ([`Servo::drive`]):
//!    * torque interface: the torque through a first-order low-pass of
//!      `bandwidth_hz` (libfranka's `lowpassFilter`, 100 Hz by default);
//!    * position/velocity interface: the vendor's own joint loop, the
//!      setpoint smoothed over `lookahead_s` (UR's `lookahead_time`) then a
//!      computed-torque PID on the vendor's model of the arm (the nominal
//!      model with the payload the user declared — not the one it carries):
//!      `a = q̈_s + K_d (q̇_s − q̇) + K_p (q_s − q) + K_i ∫(q_s − q)`,
//!      `τ = M(q) a + C(q, q̇) q̇ + g(q)`, gains from a triple pole at
//!      `ω = √(gain/3)` (`K_p = gain = 3ω²`, `K_d = 3ω`, `K_i = ω³`; `gain`
//!      is UR's `servoj` gain, or `3 (2π bandwidth_hz)²`); the integral is
//!      what makes an industrial joint loop stiff against a constant load;
//!    * velocity interface: `a = q̈_s + 2ω (q̇_s − q̇) + ω² ∫(q̇_s − q̇)`.
//!
//! The torque then goes through the [`super::Actuator`] (clamp, torque
//! drops) onto the plant, one substep at a time
//! ([`super::Plant::advance_with`]). Everything is sized at construction;
//! [`Servo::receive`], [`Servo::drive`] and [`Servo::start`] allocate nothing.

use super::faults::sample_at;
use crate::control::OutputMode;
use crate::dynamics::{rnea, Workspace};
use crate::robot::{ModelError, Robot};
use serde::{Deserialize, Serialize};
use std::fmt;

/// The vendor interfaces the stage models (`[plant.servo] profile`); every
/// value is a default that the table's keys override
/// (`ServoSettings::params`).
///
/// | profile | kind | period | lag | bandwidth | lookahead | gain | on_late | watchdog |
/// |---|---|---|---|---|---|---|---|---|
/// | `franka-torque` | torque | 1 ms | 0 | 100 Hz (low-pass) | – | – | fault | 20 |
/// | `ur-servoj` | position_velocity | 2 ms | 4 ms | – | 30 ms | 300 | hold | 10 |
/// | `kuka-rsi` | position_velocity | 4 ms | 4 ms | 10 Hz | – | – | hold | 100 |
/// | `abb-egm` | position_velocity | 4 ms | 40 ms | 10 Hz | – | – | extrapolate | 25 |
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum ServoProfile {
    /// Franka's FCI torque interface (libfranka): 1 kHz joint torque behind
    /// its 100 Hz first-order low-pass (`kDefaultCutoffFrequency`); a
    /// session that misses 20 consecutive cycles ends with
    /// `communication_constraints_violation`.
    FrankaTorque,
    /// Universal Robots' `servoj` over RTDE: a 2 ms (500 Hz, e-Series)
    /// position stream with `lookahead_time` (0.03–0.2 s) and `gain`
    /// (100–2000); the External Control program stops the arm after 20 ms
    /// without a command.
    UrServoj,
    /// KUKA's RobotSensorInterface: position corrections every 4 ms
    /// (`IPO_FAST`); the RSI object times out after 100 late packets.
    KukaRsi,
    /// ABB's Externally Guided Motion, joint position guidance: a 4 ms
    /// (250 Hz) cycle with 40–80 ms measured lag (40 ms here).
    AbbEgm,
}

impl ServoProfile {
    /// Every profile.
    pub const ALL: [ServoProfile; 4] = [
        ServoProfile::FrankaTorque,
        ServoProfile::UrServoj,
        ServoProfile::KukaRsi,
        ServoProfile::AbbEgm,
    ];

    /// Its name in a scenario (`"franka-torque"`, …).
    pub fn name(self) -> &'static str {
        match self {
            ServoProfile::FrankaTorque => "franka-torque",
            ServoProfile::UrServoj => "ur-servoj",
            ServoProfile::KukaRsi => "kuka-rsi",
            ServoProfile::AbbEgm => "abb-egm",
        }
    }

    /// The profile's values (the table of [`ServoProfile`]).
    pub(crate) fn params(self) -> ServoParams {
        let position = |period_s, lag_s, on_late, watchdog_misses| ServoParams {
            kind: OutputMode::PositionVelocity,
            period_s,
            lag_s,
            bandwidth_hz: 10.0,
            lookahead_s: 0.0,
            gain: triple_pole_gain(10.0),
            on_late,
            watchdog_misses,
        };
        match self {
            ServoProfile::FrankaTorque => ServoParams {
                kind: OutputMode::Torque,
                period_s: 1e-3,
                lag_s: 0.0,
                bandwidth_hz: 100.0,
                lookahead_s: 0.0,
                gain: 0.0,
                on_late: OnLate::Fault,
                watchdog_misses: 20,
            },
            ServoProfile::UrServoj => ServoParams {
                lookahead_s: 0.03,
                gain: 300.0,
                bandwidth_hz: (100.0f64).sqrt() / (2.0 * std::f64::consts::PI),
                ..position(2e-3, 4e-3, OnLate::Hold, 10)
            },
            ServoProfile::KukaRsi => position(4e-3, 4e-3, OnLate::Hold, 100),
            ServoProfile::AbbEgm => position(4e-3, 40e-3, OnLate::Extrapolate, 25),
        }
    }
}

impl fmt::Display for ServoProfile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// `3 (2π f)²`: the position gain of a triple pole at `f` Hz (s⁻²).
fn triple_pole_gain(f: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * f;
    3.0 * w * w
}

/// What a missed interface cycle delivers (`[plant.servo] on_late`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum OnLate {
    /// The last setpoint again (a position interface holds the position,
    /// at zero velocity; a velocity or torque interface holds its value).
    Hold,
    /// The last setpoint continued along its velocity and acceleration.
    Extrapolate,
    /// As [`OnLate::Hold`], and the watchdog is mandatory
    /// (`watchdog_misses ≥ 1`): the robot faults after that many
    /// consecutive misses.
    Fault,
}

impl OnLate {
    /// `"hold"`, `"extrapolate"` or `"fault"`.
    pub fn name(self) -> &'static str {
        match self {
            OnLate::Hold => "hold",
            OnLate::Extrapolate => "extrapolate",
            OnLate::Fault => "fault",
        }
    }
}

/// Control steps at path times `[t, t + duration_s)` report late: their
/// command misses every interface cycle of its period (a test's or a
/// scenario's injected overrun).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LateSteps {
    /// Path time of the first late step (s).
    pub t: f64,
    /// How long the steps stay late (s; at least one step).
    #[serde(default)]
    pub duration_s: f64,
}

/// A scenario's `[plant.servo]`: a profile and the values that override it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoSettings {
    /// The vendor interface ([`ServoProfile`]).
    pub profile: ServoProfile,
    /// What the interface takes (must be the controller's output).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<OutputMode>,
    /// The interface's cycle (s): at most the control period, a whole
    /// multiple of the plant's substep (the interface runs on its own
    /// clock).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period_s: Option<f64>,
    /// How long a setpoint takes to reach the drives (s, whole cycles).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lag_s: Option<f64>,
    /// Torque interface: the low-pass's cutoff (Hz). Position/velocity
    /// interface: the joint loop's bandwidth (Hz; `gain = 3 (2π f)²`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bandwidth_hz: Option<f64>,
    /// Position/velocity interface: the setpoint's smoothing time constant
    /// (s; UR's `lookahead_time`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lookahead_s: Option<f64>,
    /// Position/velocity interface: the proportional gain on the position
    /// error (s⁻²; UR's `servoj` gain), instead of `bandwidth_hz`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain: Option<f64>,
    /// What a missed cycle delivers ([`OnLate`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub on_late: Option<OnLate>,
    /// Consecutive missed cycles that trip the robot's watchdog (0: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub watchdog_misses: Option<u32>,
    /// Injected late controller steps ([`LateSteps`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub late: Vec<LateSteps>,
    /// A controller step whose measured wall time exceeds this (s) is late
    /// too (`None`, the default: only the injected ones; depends on the
    /// machine, so off in reproducible runs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deadline_s: Option<f64>,
    /// The interface reports the torque its drives applied over each
    /// control period to the controller (`None`, the default: it does not;
    /// the drives' joint torques that UR RTDE, KUKA FRI or libfranka
    /// stream): the adaptive kinds then identify their payload from it
    /// (`Controller::set_applied_torque`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reports_torque: Option<bool>,
    /// Position/velocity interface: the drives add the command's torque
    /// feed-forward to their joint loop's torque (`None`, the default: they
    /// do not; KUKA FRI's torque overlay, a joint-impedance mode with
    /// feed-forward). The controller sends the identified payload's torque
    /// there (`StepOutput::tau_command`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_feedforward: Option<bool>,
}

impl ServoSettings {
    /// Settings of `profile` with nothing overridden.
    pub fn profile(profile: ServoProfile) -> Self {
        Self {
            profile,
            kind: None,
            period_s: None,
            lag_s: None,
            bandwidth_hz: None,
            lookahead_s: None,
            gain: None,
            on_late: None,
            watchdog_misses: None,
            late: Vec::new(),
            deadline_s: None,
            reports_torque: None,
            torque_feedforward: None,
        }
    }

    /// Whether the interface reports its applied torque
    /// ([`Self::reports_torque`]; no by default).
    pub fn reports_applied_torque(&self) -> bool {
        self.reports_torque.unwrap_or(false)
    }

    /// The profile's values with the overrides: `gain` before
    /// `bandwidth_hz` (which sets `gain = 3 (2π f)²` on a position or
    /// velocity interface) before the profile's.
    pub(crate) fn params(&self) -> ServoParams {
        let d = self.profile.params();
        let bandwidth_hz = self.bandwidth_hz.unwrap_or(d.bandwidth_hz);
        let gain = match (self.gain, self.bandwidth_hz) {
            (Some(g), _) => g,
            (None, Some(f)) => triple_pole_gain(f),
            (None, None) => d.gain,
        };
        ServoParams {
            kind: self.kind.unwrap_or(d.kind),
            period_s: self.period_s.unwrap_or(d.period_s),
            lag_s: self.lag_s.unwrap_or(d.lag_s),
            bandwidth_hz,
            lookahead_s: self.lookahead_s.unwrap_or(d.lookahead_s),
            gain,
            on_late: self.on_late.unwrap_or(d.on_late),
            watchdog_misses: self.watchdog_misses.unwrap_or(d.watchdog_misses),
        }
    }

    /// What the interface takes: the `kind` given, else the profile's.
    pub fn kind(&self) -> OutputMode {
        self.params().kind
    }

    /// How far ahead a controller should command this interface (s): its
    /// lag plus its smoothing's delay of a ramp (`lookahead_s`); 0 for a
    /// torque interface.
    pub fn command_lead_s(&self) -> f64 {
        self.params().command_lead_s()
    }

    /// The delay of this interface's lag and setpoint hold as the
    /// simulation runs them, with the drives at the integration substep
    /// `substep` (s): `lag_s` plus the mean delay of the setpoint held over
    /// its interface cycle while the drives act on it once per substep,
    /// `(period_s − substep)/2`; 0 for a torque interface. With
    /// [`Self::smoothing_s_at`] pre-compensated by the command
    /// (`[mpc] output_smoothing_s`, `control/command.rs`), the lead that
    /// remains: the simulated loop's default (`[mpc] output_lead_s` unset).
    /// Measured on the paper's path (second algorithm, 0.25 kg, no
    /// smoothing): kuka-rsi RMS 0.037 mm at the lag alone (4 ms), 0.0018 mm
    /// with the hold (5.5 ms); abb-egm 0.058 mm at 40 ms, 0.0058 mm at 41.5.
    pub fn command_lead_s_at(&self, substep: f64) -> f64 {
        self.params().command_lead_s_at(substep)
    }

    /// The delay of this interface's smoothing (`lookahead_s`, a
    /// first-order filter) as the simulation runs it at the substep `h`
    /// (s): `h e^{−h/T}/(1 − e^{−h/T})` with `T = lookahead_s` (`T − h/2`
    /// to second order; 29.5 ms for ur-servoj's 30 ms at 1 ms); 0 without
    /// smoothing or for a torque interface. The simulated loop's default
    /// `[mpc] output_smoothing_s`.
    pub fn smoothing_s_at(&self, substep: f64) -> f64 {
        self.params().smoothing_s_at(substep)
    }

    /// Checks the settings for a control period `ts` and an integration
    /// substep `substep` (the interface's timing, the injected late
    /// steps, the deadline, the keys that do nothing for the kind).
    pub fn validate_for(&self, ts: f64, substep: f64) -> Result<(), ServoSettingsError> {
        let p = self.params();
        if p.kind.is_torque() {
            for (key, given) in [
                ("gain", self.gain.is_some()),
                ("lookahead_s", self.lookahead_s.is_some()),
                ("torque_feedforward", self.torque_feedforward.is_some()),
            ] {
                if given {
                    return Err(ServoSettingsError::Unused { key, kind: p.kind });
                }
            }
        }
        for (index, l) in self.late.iter().enumerate() {
            if !(l.t.is_finite() && l.t >= 0.0 && l.duration_s.is_finite() && l.duration_s >= 0.0) {
                return Err(ServoSettingsError::Late {
                    index,
                    t: l.t,
                    duration_s: l.duration_s,
                });
            }
        }
        if let Some(d) = self.deadline_s.filter(|d| !(d.is_finite() && *d > 0.0)) {
            return Err(ServoSettingsError::Value {
                key: "deadline_s",
                value: d,
                requirement: "a finite time > 0 s",
            });
        }
        p.timing(ts, substep).map(|_| ())
    }
}

/// The largest lag of an interface, in cycles.
pub const MAX_LAG_CYCLES: usize = 1000;

/// The largest `ω·substep` of a joint loop (its discrete stability).
pub const MAX_LOOP_RATE: f64 = 0.2;

/// An interface's values, every one given (`ServoSettings::params`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ServoParams {
    /// What the interface takes.
    pub kind: OutputMode,
    /// Its cycle (s).
    pub period_s: f64,
    /// Its lag (s).
    pub lag_s: f64,
    /// The torque low-pass's cutoff, or the joint loop's bandwidth (Hz).
    pub bandwidth_hz: f64,
    /// The setpoint's smoothing time constant (s).
    pub lookahead_s: f64,
    /// The joint loop's position gain (s⁻²).
    pub gain: f64,
    /// What a missed cycle delivers.
    pub on_late: OnLate,
    /// Consecutive misses that trip the watchdog (0: none).
    pub watchdog_misses: u32,
}

/// How an interface's cycles fit the loop (`ServoParams::timing`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ServoTiming {
    /// Interface cycles per control period, at most (the interface runs
    /// on its own clock: with a period that does not divide the control
    /// period, some control periods have one cycle fewer).
    pub cycles_per_period: usize,
    /// Integration substeps per interface cycle.
    pub substeps_per_cycle: usize,
    /// The lag in cycles.
    pub lag_cycles: usize,
}

impl ServoParams {
    /// How far ahead a controller should command this interface (s): its
    /// lag plus its smoothing's delay of a ramp (`lookahead_s`); 0 for a
    /// torque interface (no lead).
    pub(crate) fn command_lead_s(&self) -> f64 {
        if self.kind.is_torque() {
            0.0
        } else {
            self.lag_s + self.lookahead_s
        }
    }

    /// [`ServoSettings::command_lead_s_at`].
    pub(crate) fn command_lead_s_at(&self, substep: f64) -> f64 {
        if self.kind.is_torque() {
            0.0
        } else {
            self.lag_s + 0.5 * (self.period_s - substep).max(0.0)
        }
    }

    /// [`ServoSettings::smoothing_s_at`].
    pub(crate) fn smoothing_s_at(&self, h: f64) -> f64 {
        if self.kind.is_torque() || self.lookahead_s <= 0.0 {
            return 0.0;
        }
        let a = (-h / self.lookahead_s).exp();
        h * a / (1.0 - a)
    }

    /// The joint loop's `ω` (rad/s) from its gain: `√(gain/3)`.
    fn omega(&self) -> f64 {
        match self.kind {
            OutputMode::Velocity => 2.0 * std::f64::consts::PI * self.bandwidth_hz,
            _ => (self.gain / 3.0).sqrt(),
        }
    }

    /// Checks every value and how the interface's cycle fits a control
    /// period `ts` and a substep `substep`.
    pub(crate) fn timing(&self, ts: f64, substep: f64) -> Result<ServoTiming, ServoSettingsError> {
        self.check_values()?;
        let whole = |what, a: f64, b: f64| {
            let r = a / b;
            let k = r.round();
            if k >= 1.0 && (r - k).abs() <= 1e-9 * k && k <= MAX_LAG_CYCLES as f64 * 1e3 {
                Ok(k as usize)
            } else {
                Err(ServoSettingsError::Multiple { what, of: a, by: b })
            }
        };
        let cycles_per_period = (ts / self.period_s).ceil() as usize;
        if self.period_s > ts * (1.0 + 1e-9) {
            return Err(ServoSettingsError::Value {
                key: "period_s",
                value: self.period_s,
                requirement: "at most the control period",
            });
        }
        let substeps_per_cycle = whole("the interface period", self.period_s, substep)?;
        let lag_cycles = if self.lag_s == 0.0 {
            0
        } else {
            whole("the lag", self.lag_s, self.period_s)?
        };
        if lag_cycles > MAX_LAG_CYCLES {
            return Err(ServoSettingsError::Value {
                key: "lag_s",
                value: self.lag_s,
                requirement: "at most 1000 interface cycles",
            });
        }
        let rate = self.omega() * substep;
        if !self.kind.is_torque() && rate > MAX_LOOP_RATE {
            return Err(ServoSettingsError::LoopTooFast {
                omega: self.omega(),
                substep,
            });
        }
        Ok(ServoTiming {
            cycles_per_period,
            substeps_per_cycle,
            lag_cycles,
        })
    }

    /// Each value in its range, and a watchdog for `on_late = fault`.
    fn check_values(&self) -> Result<(), ServoSettingsError> {
        let positive = |key, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ServoSettingsError::Value {
                    key,
                    value,
                    requirement: "a finite value > 0",
                })
            }
        };
        positive("period_s", self.period_s)?;
        positive("bandwidth_hz", self.bandwidth_hz)?;
        if !self.kind.is_torque() {
            positive("gain", self.gain)?;
        }
        for (key, value) in [("lag_s", self.lag_s), ("lookahead_s", self.lookahead_s)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ServoSettingsError::Value {
                    key,
                    value,
                    requirement: "a finite time >= 0 s",
                });
            }
        }
        if self.on_late == OnLate::Fault && self.watchdog_misses == 0 {
            return Err(ServoSettingsError::FaultWithoutWatchdog);
        }
        Ok(())
    }
}

/// Why servo settings cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ServoSettingsError {
    /// A value is out of its range.
    #[error("the servo interface's {key} is {value}: it must be {requirement}")]
    Value {
        /// Which value.
        key: &'static str,
        /// The value.
        value: f64,
        /// What it must be.
        requirement: &'static str,
    },
    /// A period is not a whole number of another.
    #[error("{what} ({of} s) is not a whole number of {by} s: the interface's cycle must be a whole number of integration substeps and the lag whole cycles")]
    Multiple {
        /// Which time.
        what: &'static str,
        /// The time (s).
        of: f64,
        /// The unit it must be a multiple of (s).
        by: f64,
    },
    /// A value that does nothing for the interface's kind.
    #[error("{key} does nothing for a {kind} interface: remove it")]
    Unused {
        /// Which value.
        key: &'static str,
        /// The interface's kind.
        kind: OutputMode,
    },
    /// `on_late = "fault"` without a watchdog.
    #[error("an interface that faults on late commands needs a watchdog: give it a number of consecutive missed cycles of 1 or more")]
    FaultWithoutWatchdog,
    /// An injected late span is not a time.
    #[error("late step {} is at t = {t} s for {duration_s} s: both must be finite and >= 0", index + 1)]
    Late {
        /// 0-based index.
        index: usize,
        /// Its time (s).
        t: f64,
        /// Its duration (s).
        duration_s: f64,
    },
    /// The joint loop is too stiff for the integration substep.
    #[error("the servo's joint loop (ω = {omega:.1} rad/s) is too fast for the {substep} s integration substep (ω·substep must be at most 0.2): lower gain or bandwidth_hz, or integrate in finer substeps")]
    LoopTooFast {
        /// The loop's ω (rad/s).
        omega: f64,
        /// The substep (s).
        substep: f64,
    },
    /// The controller outputs positions or velocities but the plant has no
    /// servo interface to take them (it takes torque).
    #[error("the controller outputs {output} but the plant has no servo interface to take it (the plant takes torque): give the plant a servo interface of that kind, or output torque")]
    NoInterface {
        /// The controller's output.
        output: OutputMode,
    },
    /// The controller's output is not what the interface takes.
    #[error("the servo interface takes {interface} but the controller outputs {controller}: make the controller output {interface}")]
    OutputMismatch {
        /// The interface's kind.
        interface: OutputMode,
        /// The controller's output.
        controller: OutputMode,
    },
}

/// What the stage saw over a run ([`Servo::report`]), for `metrics.json`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ServoReport {
    /// The profile.
    pub profile: ServoProfile,
    /// Interface cycles run.
    pub cycles: u64,
    /// Cycles without a fresh command.
    pub misses: u64,
    /// The longest run of consecutive misses.
    pub max_consecutive_misses: u32,
    /// `"ok"`, or `"watchdog_trip"` when the watchdog ended the run.
    pub status: ServoStatus,
}

/// How the interface ended ([`ServoReport::status`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum ServoStatus {
    /// No trip.
    Ok,
    /// The watchdog tripped: `watchdog_misses` consecutive missed cycles.
    WatchdogTrip,
}

/// Setpoint slot layout: q, q̇, q̈, τ (n each).
const SLOT: usize = 4;

/// The servo interface stage (module docs). Sized at construction.
#[derive(Debug, Clone)]
pub struct Servo {
    profile: ServoProfile,
    p: ServoParams,
    timing: ServoTiming,
    n: usize,
    /// The vendor's model of the arm and its workspace.
    model: Robot,
    ws: Workspace,
    /// The period's command (4n) and whether it came on time.
    command: Vec<f64>,
    fresh: bool,
    /// The last setpoint sent (4n).
    last: Vec<f64>,
    /// Setpoints in flight: `lag_cycles + 1` slots of 4n; `head` the next
    /// written.
    ring: Vec<f64>,
    head: usize,
    /// The joint loop adds the setpoint's torque (`torque_feedforward`).
    torque_ff: bool,
    /// The drive's smoothed setpoint (4n) and its integral (n).
    filtered: Vec<f64>,
    integral: Vec<f64>,
    accel: Vec<f64>,
    /// Injected late steps, as path-sample ranges.
    late: Vec<(usize, usize)>,
    deadline_s: Option<f64>,
    /// Substeps driven since [`Servo::start`] (the interface's clock).
    substep: u64,
    cycles: u64,
    misses: u64,
    consecutive: u32,
    max_consecutive: u32,
    tripped: bool,
}

impl Servo {
    /// The stage of `settings` for a loop at the control period `ts` on a
    /// plant integrated in substeps of `substep`, whose drives model the
    /// arm as `model` (the controller's nominal model: the payload the user
    /// declared, not the one it carries). Checks the settings
    /// ([`ServoSettings::validate_for`]); allocates.
    pub fn new(
        settings: &ServoSettings,
        model: &Robot,
        ts: f64,
        substep: f64,
    ) -> Result<Self, ServoSettingsError> {
        settings.validate_for(ts, substep)?;
        let p = settings.params();
        let timing = p.timing(ts, substep)?;
        let n = model.dof();
        let late = settings
            .late
            .iter()
            .map(|l| {
                let from = sample_at(l.t, ts);
                (from, sample_at(l.t + l.duration_s, ts).max(from + 1))
            })
            .collect();
        Ok(Self {
            profile: settings.profile,
            torque_ff: settings.torque_feedforward.unwrap_or(false),
            p,
            timing,
            n,
            ws: Workspace::new(model),
            model: model.clone(),
            command: vec![0.0; SLOT * n],
            fresh: false,
            last: vec![0.0; SLOT * n],
            ring: vec![0.0; (timing.lag_cycles + 1) * SLOT * n],
            head: 0,
            filtered: vec![0.0; SLOT * n],
            integral: vec![0.0; n],
            accel: vec![0.0; n],
            late,
            deadline_s: settings.deadline_s,
            substep: 0,
            cycles: 0,
            misses: 0,
            consecutive: 0,
            max_consecutive: 0,
            tripped: false,
        })
    }

    /// Checks that the controller's `output` is what the interface takes.
    pub fn check_output(&self, output: OutputMode) -> Result<(), ServoSettingsError> {
        if output == self.p.kind {
            Ok(())
        } else {
            Err(ServoSettingsError::OutputMismatch {
                interface: self.p.kind,
                controller: output,
            })
        }
    }

    /// Starts at rest at `q` (n): every setpoint is `q` at rest with the
    /// torque that holds the arm there on the vendor's model (`g(q)`: the
    /// drives hold the arm as the brakes release), the drive's state and the
    /// counters are reset. Allocation-free.
    pub fn start(&mut self, q: &[f64]) -> Result<(), ModelError> {
        let n = self.n;
        self.accel.fill(0.0);
        let zero = &self.accel;
        let g = rnea(&self.model, &mut self.ws, q, zero, zero)?;
        // A torque interface starts holding the arm; the feed-forward of
        // one that closes its own loop starts at none.
        let torque = self.p.kind.is_torque();
        let tau = g.as_slice();
        for slot in self.ring.chunks_mut(SLOT * n).chain([
            &mut self.last[..],
            &mut self.command[..],
            &mut self.filtered[..],
        ]) {
            slot.fill(0.0);
            slot[..n].copy_from_slice(q);
            if torque {
                slot[3 * n..].copy_from_slice(tau);
            }
        }
        self.integral.fill(0.0);
        self.fresh = false;
        self.head = 0;
        self.substep = 0;
        (
            self.cycles,
            self.misses,
            self.consecutive,
            self.max_consecutive,
        ) = (0, 0, 0, 0);
        self.tripped = false;
        Ok(())
    }

    /// Whether the controller's step of path sample `path_sample` (`None`
    /// before the path) that took `step_s` seconds is late: injected
    /// ([`ServoSettings::late`]) or slower than the deadline.
    pub fn is_late(&self, path_sample: Option<usize>, step_s: f64) -> bool {
        let injected =
            path_sample.is_some_and(|k| self.late.iter().any(|(a, b)| (*a..*b).contains(&k)));
        injected || self.deadline_s.is_some_and(|d| step_s > d)
    }

    /// The controller's command of this control period: its torque `tau`
    /// and its predicted `q`, `q̇`, `q̈` (n each; ignored by a torque
    /// interface); `late`: the step missed its deadline, the command does
    /// not arrive this period.
    pub fn receive(&mut self, tau: &[f64], q: &[f64], qd: &[f64], qdd: &[f64], late: bool) {
        self.fresh = !late;
        if late {
            return;
        }
        let n = self.n;
        for (i, src) in [q, qd, qdd, tau].into_iter().enumerate() {
            self.command[i * n..(i + 1) * n].copy_from_slice(src);
        }
    }

    /// The last setpoint sent: `q`, `q̇`, `q̈`, `τ` (n each).
    pub fn setpoint(&self) -> &[f64] {
        &self.last
    }

    /// Whether the watchdog tripped.
    pub fn tripped(&self) -> bool {
        self.tripped
    }

    /// What the stage saw so far.
    pub fn report(&self) -> ServoReport {
        ServoReport {
            profile: self.profile,
            cycles: self.cycles,
            misses: self.misses,
            max_consecutive_misses: self.max_consecutive,
            status: if self.tripped {
                ServoStatus::WatchdogTrip
            } else {
                ServoStatus::Ok
            },
        }
    }

    /// The drives' torque at substep `i` of the control period (the true
    /// `q`, `q̇` the drives measure), into `tau` (n). At the first substep of
    /// each interface cycle the cycle's setpoint is sent. Allocation-free.
    pub fn drive(
        &mut self,
        i: usize,
        q: &[f64],
        qd: &[f64],
        tau: &mut [f64],
        substep: f64,
    ) -> Result<(), ModelError> {
        if self
            .substep
            .is_multiple_of(self.timing.substeps_per_cycle as u64)
        {
            // The interface's own clock: a cycle begins; `i` substeps into
            // the control period.
            self.send(i as f64 * substep);
        }
        self.substep += 1;
        let n = self.n;
        let slots = self.timing.lag_cycles + 1;
        // The setpoint sent `lag_cycles` cycles ago (the oldest in flight).
        let at = (self.head % slots) * SLOT * n;
        let setpoint = &self.ring[at..at + SLOT * n];
        match self.p.kind {
            OutputMode::Torque => {
                let alpha =
                    1.0 - (-2.0 * std::f64::consts::PI * self.p.bandwidth_hz * substep).exp();
                let f = &mut self.filtered[3 * n..];
                for ((f, s), t) in f.iter_mut().zip(&setpoint[3 * n..]).zip(tau.iter_mut()) {
                    *f += alpha * (s - *f);
                    *t = *f;
                }
                Ok(())
            }
            _ => self.joint_loop(q, qd, tau, substep),
        }
    }

    /// The vendor's joint loop on the smoothed setpoint (module docs).
    fn joint_loop(
        &mut self,
        q: &[f64],
        qd: &[f64],
        tau: &mut [f64],
        h: f64,
    ) -> Result<(), ModelError> {
        let n = self.n;
        let slots = self.timing.lag_cycles + 1;
        let at = (self.head % slots) * SLOT * n;
        let beta = if self.p.lookahead_s > 0.0 {
            1.0 - (-h / self.p.lookahead_s).exp()
        } else {
            1.0
        };
        for (f, s) in self.filtered[..3 * n]
            .iter_mut()
            .zip(&self.ring[at..at + 3 * n])
        {
            *f += beta * (s - *f);
        }
        let w = self.p.omega();
        let (fq, rest) = self.filtered.split_at(n);
        let (fqd, fqdd) = (&rest[..n], &rest[n..2 * n]);
        for j in 0..n {
            let ev = fqd[j] - qd[j];
            self.accel[j] = match self.p.kind {
                OutputMode::Velocity => {
                    self.integral[j] += ev * h;
                    fqdd[j] + 2.0 * w * ev + w * w * self.integral[j]
                }
                _ => {
                    let e = fq[j] - q[j];
                    self.integral[j] += e * h;
                    fqdd[j] + 3.0 * w * ev + self.p.gain * e + w * w * w * self.integral[j]
                }
            };
        }
        let t = rnea(&self.model, &mut self.ws, q, qd, &self.accel)?;
        tau.copy_from_slice(t.as_slice());
        if self.torque_ff {
            for (t, f) in tau.iter_mut().zip(&self.ring[at + 3 * n..at + 4 * n]) {
                *t += f;
            }
        }
        Ok(())
    }

    /// Sends the setpoint of the cycle that begins `since_command` seconds
    /// after the control period's command into the lag line: the
    /// fresh command along its prediction, or a miss bridged by
    /// [`OnLate`] (and counted by the watchdog).
    fn send(&mut self, since_command: f64) {
        let n = self.n;
        self.cycles += 1;
        let dt = if self.fresh {
            self.consecutive = 0;
            self.last.copy_from_slice(&self.command);
            since_command
        } else {
            self.misses += 1;
            self.consecutive = self.consecutive.saturating_add(1);
            self.max_consecutive = self.max_consecutive.max(self.consecutive);
            let w = self.p.watchdog_misses;
            self.tripped |= w > 0 && self.consecutive >= w;
            match self.p.on_late {
                OnLate::Extrapolate => self.p.period_s,
                OnLate::Hold | OnLate::Fault => {
                    if self.p.kind == OutputMode::PositionVelocity {
                        self.last[n..3 * n].fill(0.0);
                    } else {
                        self.last[2 * n..3 * n].fill(0.0);
                    }
                    0.0
                }
            }
        };
        let slots = self.timing.lag_cycles + 1;
        self.head = (self.head + 1) % slots;
        // The slot just freed is the newest: the one `lag_cycles` ahead of
        // the oldest, which `drive` reads at `head`.
        let at = ((self.head + slots - 1) % slots) * SLOT * n;
        let (q, rest) = self.last.split_at_mut(n);
        let (qd, rest) = rest.split_at_mut(n);
        let (qdd, tau) = rest.split_at_mut(n);
        let out = &mut self.ring[at..at + SLOT * n];
        for j in 0..n {
            let (p, v, a) = (q[j], qd[j], qdd[j]);
            out[j] = p + v * dt + 0.5 * a * dt * dt;
            out[n + j] = v + a * dt;
            out[2 * n + j] = a;
            out[3 * n + j] = tau[j];
        }
        // The setpoint sent is the last one (a miss goes on from it).
        q.copy_from_slice(&out[..n]);
        qd.copy_from_slice(&out[n..2 * n]);
    }
}
