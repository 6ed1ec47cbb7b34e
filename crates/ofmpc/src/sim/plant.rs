//! The simulated robot: the full nonlinear model, with the payload the
//! controller does not know, integrated by RK4 under zero-order-hold torque.

use super::actuator::Actuator;
use super::faults::{Fault, FaultSchedule};
use super::servo::{ServoSettings, ServoSettingsError};
use super::state::JointState;
use crate::dynamics::{forward_dynamics, forward_kinematics, Workspace};
use crate::linalg::{rk4_second_order_step, RK4_WORK_PER_DOF};
use crate::robot::{ModelError, Robot};
use serde::{Deserialize, Serialize};
use std::fmt;

/// Options of the plant; every effect is off by default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlantSettings {
    /// RK4 substep (s); the control period must be a whole number of substeps
    /// (at most [`super::MAX_SUBSTEPS`]).
    pub substep: f64,
    /// Viscous friction per joint (N·m·s/rad); one value for all joints or one per joint.
    pub viscous_friction: Vec<f64>,
    /// Coulomb friction per joint (N·m), smoothed by `tanh(q̇ / coulomb_velocity)`.
    pub coulomb_friction: Vec<f64>,
    /// Velocity scale of the smoothed Coulomb friction (rad/s).
    pub coulomb_velocity: f64,
    /// Saturate the commanded torque at the robot's effort limits.
    pub torque_limits: bool,
    /// Standard deviation of Gaussian noise on measured positions (rad).
    pub position_noise: f64,
    /// Standard deviation of Gaussian noise on measured velocities (rad/s).
    pub velocity_noise: f64,
    /// Encoder resolution (counts per joint revolution); 0 = ideal.
    pub encoder_counts: u64,
    /// Seed of the measurement noise.
    pub seed: u64,
    /// Derive the measured velocity from the measured (noisy, quantized)
    /// positions by a backward difference over the control period, as a
    /// drive without a tachometer does.
    pub velocity_from_encoder: bool,
    /// The measurement the controller sees is this many control periods old.
    pub delay_samples: usize,
    /// Injected faults (encoder glitch, encoder dropout, torque drop).
    pub faults: Vec<Fault>,
    /// Relative standard deviation of every link's mass, centre of mass
    /// (scaled to the link), inertia and drive inertia in the plant, drawn
    /// once per run from `seed` ([`Robot::with_inertia_error`]); the
    /// controllers keep the nominal model. 0 = the plant is the model.
    #[serde(skip_serializing_if = "is_zero")]
    pub inertia_error: f64,
    /// Stribeck friction per joint (N·m): the breakaway torque's excess over
    /// the Coulomb level, fading as `exp(−(q̇/stribeck_velocity)²)`; one value
    /// for all joints or one per joint. Empty = none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub stribeck_friction: Vec<f64>,
    /// Velocity scale of the Stribeck effect (rad/s).
    #[serde(skip_serializing_if = "is_default_stribeck_velocity")]
    pub stribeck_velocity: f64,
    /// The plant's own URDF (a measured arm against the nominal model), as
    /// the caller named it; the library does not read it: the caller loads
    /// it into [`Self::model`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub robot: Option<std::path::PathBuf>,
    /// The plant's own drives file, likewise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drives: Option<std::path::PathBuf>,
    /// The robot's servo interface between the controller's command and
    /// the drives' torque (`[plant.servo]`, [`super::ServoSettings`]);
    /// `None` (default): the controller's torque reaches the drives as it
    /// is, held over the period.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub servo: Option<ServoSettings>,
    /// The plant's own robot (joints matching the controllers' robot,
    /// [`check_plant_model`]); `None` = the controllers' robot.
    #[serde(skip)]
    pub model: Option<Robot>,
}

/// Default velocity scale of the Stribeck effect (rad/s).
pub const DEFAULT_STRIBECK_VELOCITY: f64 = 0.01;

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn is_default_stribeck_velocity(x: &f64) -> bool {
    *x == DEFAULT_STRIBECK_VELOCITY
}

/// The largest number of integration substeps per control period.
pub const MAX_SUBSTEPS: usize = 100_000;

/// Largest accepted measurement delay (control periods).
pub const MAX_DELAY_SAMPLES: usize = 1000;

impl Default for PlantSettings {
    fn default() -> Self {
        Self {
            substep: 1e-3,
            viscous_friction: Vec::new(),
            coulomb_friction: Vec::new(),
            coulomb_velocity: crate::dynamics::friction::DEFAULT_COULOMB_VELOCITY,
            torque_limits: false,
            position_noise: 0.0,
            velocity_noise: 0.0,
            encoder_counts: 0,
            seed: 1,
            velocity_from_encoder: false,
            delay_samples: 0,
            faults: Vec::new(),
            inertia_error: 0.0,
            stribeck_friction: Vec::new(),
            stribeck_velocity: DEFAULT_STRIBECK_VELOCITY,
            robot: None,
            drives: None,
            servo: None,
            model: None,
        }
    }
}

/// Which friction vector of [`PlantSettings`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum FrictionKind {
    /// Viscous friction (N·m·s/rad).
    Viscous,
    /// Coulomb friction (N·m).
    Coulomb,
    /// Stribeck friction (N·m).
    Stribeck,
}

impl fmt::Display for FrictionKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            FrictionKind::Viscous => "viscous friction",
            FrictionKind::Coulomb => "Coulomb friction",
            FrictionKind::Stribeck => "Stribeck friction",
        })
    }
}

/// Which noise of [`PlantSettings`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum NoiseKind {
    /// On measured positions (rad).
    Position,
    /// On measured velocities (rad/s).
    Velocity,
}

impl fmt::Display for NoiseKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NoiseKind::Position => "position noise",
            NoiseKind::Velocity => "velocity noise",
        })
    }
}

/// Why plant settings cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlantSettingsError {
    /// The integration substep is not a positive time.
    #[error("the integration substep is {0} s: it must be a positive time")]
    Substep(f64),
    /// The control period is not a whole number of substeps, or too many.
    #[error(
        "the control period {ts} s is {ratio} integration substeps of {substep} s: it must be a whole number \
         of substeps, from 1 to {max}{}",
        suggest_substep(*ts, *ratio, *max)
    )]
    SubstepRatio {
        /// Control period (s).
        ts: f64,
        /// Substep (s).
        substep: f64,
        /// `ts / substep`.
        ratio: f64,
        /// [`super::MAX_SUBSTEPS`].
        max: usize,
    },
    /// A friction vector has neither 0, 1 nor n values.
    #[error("{kind} has {got} values: give none, one for all joints, or one per joint ({n})")]
    FrictionLength {
        /// Which friction.
        kind: FrictionKind,
        /// Values given.
        got: usize,
        /// Joints.
        n: usize,
    },
    /// A friction value is negative or not finite.
    #[error("{kind} of joint {} is {value}: it must be finite and ≥ 0", index + 1)]
    FrictionValue {
        /// Which friction.
        kind: FrictionKind,
        /// 0-based index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A fault names no joint of the robot, or has a bad time, duration,
    /// offset or fraction.
    #[error("fault {} is invalid: {what} = {value} ({requirement})", index + 1)]
    Fault {
        /// 0-based index in the list.
        index: usize,
        /// Which value.
        what: &'static str,
        /// The value.
        value: f64,
        /// What it must be.
        requirement: &'static str,
    },
    /// The measurement delay is too long.
    #[error("the measurement delay is {0} samples: at most {MAX_DELAY_SAMPLES}")]
    Delay(usize),
    /// The velocity scale of the smoothed Coulomb friction is not > 0.
    #[error("the Coulomb friction's velocity scale is {0} rad/s: it must be finite and > 0")]
    CoulombVelocity(f64),
    /// The inertia error is not in [0, 1] (`MAX_INERTIA_ERROR`).
    #[error("the inertia error is {0}: it must be a relative standard deviation from 0 to {max}", max = crate::robot::MAX_INERTIA_ERROR)]
    InertiaError(f64),
    /// The Stribeck velocity scale is not > 0.
    #[error("the Stribeck friction's velocity scale is {0} rad/s: it must be finite and > 0")]
    StribeckVelocity(f64),
    /// The plant's own robot does not have the controllers' joints.
    #[error("the plant's robot does not match the controllers' robot: {what} (the plant's {plant}, the controllers' {model}); give a plant robot with the same joints")]
    ModelMismatch {
        /// What differs.
        what: String,
        /// The plant robot's value.
        plant: String,
        /// The controllers' robot's value.
        model: String,
    },
    /// The servo interface's settings do not fit
    /// ([`super::ServoSettings::validate_for`]).
    #[error(transparent)]
    Servo(#[from] ServoSettingsError),
    /// A noise level is negative or not finite.
    #[error("the {kind} is {value}: it must be finite and ≥ 0")]
    Noise {
        /// Which noise.
        kind: NoiseKind,
        /// The standard deviation.
        value: f64,
    },
}

fn suggest_substep(ts: f64, ratio: f64, max: usize) -> String {
    if !(ratio.is_finite() && ratio >= 0.5 && ts > 0.0) {
        return String::new();
    }
    let k = ratio.round().clamp(1.0, max as f64);
    format!(" (e.g. {} s, {k} substeps)", ts / k)
}

/// Why the plant could not be built or advanced.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlantError {
    /// Its settings do not fit.
    #[error(transparent)]
    Settings(#[from] PlantSettingsError),
    /// A vector has the wrong length or is not finite, or the robot's
    /// dynamics failed.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The measurement buffer does not have `2n` entries.
    #[error("the measurement buffer has {got} entries but the plant measures {expected} (q and q̇ of every joint)")]
    MeasurementLength {
        /// `2n`.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// The state stopped being finite during the integration (the state is
    /// left as before the step).
    #[error("the simulated state of joint {} stopped being finite during the integration: the torque or the motion is beyond what the model can integrate", joint + 1)]
    NonFiniteState {
        /// 0-based joint.
        joint: usize,
    },
}

impl PlantSettings {
    /// True when the controller is given the plant's exact state: no noise,
    /// no encoder quantization, no encoder-derived velocity, no delay and no
    /// encoder fault.
    pub fn measurement_is_ideal(&self) -> bool {
        self.position_noise == 0.0
            && self.velocity_noise == 0.0
            && self.encoder_counts == 0
            && !self.velocity_from_encoder
            && self.delay_samples == 0
            && !self.faults.iter().any(|f| {
                matches!(
                    f,
                    Fault::EncoderGlitch { .. } | Fault::EncoderDropout { .. }
                )
            })
    }

    /// The drives between the controller and this plant: the robot's rated
    /// torques, the clamp of `torque_limits` and the torque drops of
    /// `faults`, at the control period `ts` ([`Actuator::with_faults`]).
    pub fn actuator(&self, robot: &Robot, ts: f64) -> Actuator {
        Actuator::with_faults(robot, self.torque_limits, &self.faults, ts)
    }

    /// Checks the settings against a robot with `n` joints.
    pub fn validate(&self, n: usize) -> Result<(), PlantSettingsError> {
        if !(self.substep.is_finite() && self.substep > 0.0) {
            return Err(PlantSettingsError::Substep(self.substep));
        }
        for (kind, v) in [
            (FrictionKind::Viscous, &self.viscous_friction),
            (FrictionKind::Coulomb, &self.coulomb_friction),
            (FrictionKind::Stribeck, &self.stribeck_friction),
        ] {
            if !(v.is_empty() || v.len() == 1 || v.len() == n) {
                return Err(PlantSettingsError::FrictionLength {
                    kind,
                    got: v.len(),
                    n,
                });
            }
            if let Some((index, &value)) = v
                .iter()
                .enumerate()
                .find(|(_, x)| !x.is_finite() || **x < 0.0)
            {
                return Err(PlantSettingsError::FrictionValue { kind, index, value });
            }
        }
        for (index, f) in self.faults.iter().enumerate() {
            check_fault(index, f, n)?;
        }
        if self.delay_samples > MAX_DELAY_SAMPLES {
            return Err(PlantSettingsError::Delay(self.delay_samples));
        }
        let e = self.inertia_error;
        if !(e.is_finite() && (0.0..=crate::robot::MAX_INERTIA_ERROR).contains(&e)) {
            return Err(PlantSettingsError::InertiaError(e));
        }
        let sv = self.stribeck_velocity;
        if !(sv.is_finite() && sv > 0.0) {
            return Err(PlantSettingsError::StribeckVelocity(sv));
        }
        if let Some(m) = &self.model {
            if m.dof() != n {
                return Err(PlantSettingsError::ModelMismatch {
                    what: "the number of joints".into(),
                    plant: m.dof().to_string(),
                    model: n.to_string(),
                });
            }
        }
        let cv = self.coulomb_velocity;
        if !(cv.is_finite() && cv > 0.0) {
            return Err(PlantSettingsError::CoulombVelocity(cv));
        }
        for (kind, value) in [
            (NoiseKind::Position, self.position_noise),
            (NoiseKind::Velocity, self.velocity_noise),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(PlantSettingsError::Noise { kind, value });
            }
        }
        Ok(())
    }

    /// Checks the settings for a control period `ts`: [`Self::validate`],
    /// and `ts` a whole number of substeps (within 1e-9 relative), at most
    /// [`super::MAX_SUBSTEPS`]. Returns the number of substeps.
    pub fn validate_for(&self, n: usize, ts: f64) -> Result<usize, PlantSettingsError> {
        self.validate(n)?;
        let k = substeps(ts, self.substep)?;
        if let Some(servo) = &self.servo {
            servo.validate_for(ts, self.substep)?;
        }
        Ok(k)
    }

    /// The plant's robot for a controller whose model is `nominal`: its own
    /// robot ([`Self::model`], checked against `nominal` by
    /// [`check_plant_model`], with `nominal`'s tool centre point) or
    /// `nominal`, with the inertial parameters drawn by `inertia_error` from
    /// `seed` ([`Robot::with_inertia_error`]), and the relative errors drawn
    /// (empty when `inertia_error` is 0).
    pub fn plant_robot(
        &self,
        nominal: &Robot,
    ) -> Result<(Robot, Vec<crate::robot::LinkInertiaError>), PlantError> {
        let base = match &self.model {
            Some(m) => {
                check_plant_model(m, nominal)?;
                let mut m = m.clone();
                m.set_tcp(*nominal.tcp())?;
                m
            }
            None => nominal.clone(),
        };
        if self.inertia_error == 0.0 {
            return Ok((base, Vec::new()));
        }
        Ok(base.with_inertia_error(self.inertia_error, self.seed)?)
    }
}

/// Checks that a plant's own robot has the joints of the controllers' robot
/// `model`: as many, of the same kinds, with the same names, in order.
pub fn check_plant_model(plant: &Robot, model: &Robot) -> Result<(), PlantSettingsError> {
    let mismatch = |what: String, plant: String, model: String| {
        Err(PlantSettingsError::ModelMismatch { what, plant, model })
    };
    if plant.dof() != model.dof() {
        return mismatch(
            "the number of joints".into(),
            plant.dof().to_string(),
            model.dof().to_string(),
        );
    }
    for (i, (a, b)) in plant.joints().iter().zip(model.joints()).enumerate() {
        if a.name != b.name {
            return mismatch(
                format!("joint {}'s name", i + 1),
                a.name.clone(),
                b.name.clone(),
            );
        }
        if a.kind != b.kind {
            return mismatch(
                format!("joint {} ({})'s kind", i + 1, a.name),
                format!("{:?}", a.kind),
                format!("{:?}", b.kind),
            );
        }
    }
    Ok(())
}

/// Checks fault `index` of the plant's settings for `n` joints: a joint
/// from 1 to n, a finite start time and duration `≥ 0`, a finite glitch
/// offset, a torque-drop fraction in [0, 1].
fn check_fault(index: usize, f: &Fault, n: usize) -> Result<(), PlantSettingsError> {
    let (t, j, d) = f.span();
    let bad = |what, value: f64, requirement| {
        Err(PlantSettingsError::Fault {
            index,
            what,
            value,
            requirement,
        })
    };
    if j >= n {
        return bad(
            "joint",
            j.wrapping_add(1) as f64,
            "a joint number from 1 to n",
        );
    }
    if !(t.is_finite() && t >= 0.0) {
        return bad("t", t, "a finite time >= 0 s");
    }
    if !(d.is_finite() && d >= 0.0) {
        return bad("duration_s", d, "a finite duration >= 0 s");
    }
    match *f {
        Fault::EncoderGlitch { offset_rad, .. } if !offset_rad.is_finite() => {
            return bad("offset_rad", offset_rad, "a finite angle");
        }
        Fault::TorqueDrop { fraction, .. } if !(0.0..=1.0).contains(&fraction) => {
            return bad("fraction", fraction, "between 0 and 1");
        }
        _ => {}
    }
    Ok(())
}

/// `ts / substep` as a whole number of substeps, within bounds.
fn substeps(ts: f64, substep: f64) -> Result<usize, PlantSettingsError> {
    let ratio = ts / substep;
    let k = ratio.round();
    let max = MAX_SUBSTEPS;
    if !(ts.is_finite() && ts > 0.0 && k >= 1.0 && k <= max as f64) || (ratio - k).abs() > 1e-9 * k
    {
        return Err(PlantSettingsError::SubstepRatio {
            ts,
            substep,
            ratio,
            max,
        });
    }
    Ok(k as usize)
}

fn per_joint(v: &[f64], n: usize) -> Vec<f64> {
    match v.len() {
        0 => vec![0.0; n],
        1 => vec![v[0]; n],
        _ => v.to_vec(),
    }
}

/// The torque law of [`Plant::advance_with`]: `(substep, q, q̇, τ out)`.
type SubstepDrive<'a> = dyn FnMut(usize, &[f64], &[f64], &mut [f64]) -> Result<(), PlantError> + 'a;

/// The plant: state, model and effects. No allocation after construction.
#[derive(Debug, Clone)]
pub struct Plant {
    robot: Robot,
    ws: Workspace,
    settings: PlantSettings,
    viscous: Vec<f64>,
    coulomb: Vec<f64>,
    /// Stribeck excess per joint; empty when there is none.
    stribeck: Vec<f64>,
    q: Vec<f64>,
    qd: Vec<f64>,
    t: f64,
    // The applied torque, the net torque (applied minus friction) and the RK4 scratch.
    tau: Vec<f64>,
    /// The period's mean torque of [`Plant::advance_with`].
    mean: Vec<f64>,
    net: Vec<f64>,
    rk4: Vec<f64>,
    backup: Vec<f64>,
    /// The control period (s) and its RK4 substeps ([`Plant::with_period`]).
    ts: f64,
    substeps: usize,
    /// The faults' samples ([`FaultSchedule::for_plant`]), counted from the
    /// path's first sample: `origin` periods after the plant was built
    /// ([`Plant::start_path_after`]); `steps` periods have been simulated.
    schedule: FaultSchedule,
    steps: usize,
    origin: usize,
}

impl Plant {
    /// A plant at rest at `q0`, advanced by the control period `ts` (s) at
    /// each [`Self::advance`]: `ts` must be a whole number of the settings'
    /// substeps ([`PlantSettings::validate_for`]). The faults of the
    /// settings are matched to samples of `ts` here, once
    /// (`FaultSchedule::for_plant`); the path starts at once
    /// ([`Self::start_path_after`]).
    pub fn with_period(
        robot: Robot,
        settings: PlantSettings,
        q0: &[f64],
        ts: f64,
    ) -> Result<Self, PlantError> {
        let n = robot.dof();
        robot.check_vector("q0", q0)?;
        let substeps = settings.validate_for(n, ts)?;
        let schedule = FaultSchedule::for_plant(&settings.faults, ts);
        let ws = Workspace::new(&robot);
        let z = vec![0.0; n];
        Ok(Self {
            viscous: per_joint(&settings.viscous_friction, n),
            coulomb: per_joint(&settings.coulomb_friction, n),
            stribeck: if settings.stribeck_friction.is_empty() {
                Vec::new()
            } else {
                per_joint(&settings.stribeck_friction, n)
            },
            robot,
            ws,
            settings,
            q: q0.to_vec(),
            qd: z.clone(),
            t: 0.0,
            tau: z.clone(),
            mean: z.clone(),
            net: z.clone(),
            rk4: vec![0.0; RK4_WORK_PER_DOF * n],
            backup: vec![0.0; 2 * n],
            ts,
            substeps,
            schedule,
            steps: 0,
            origin: 0,
        })
    }

    /// The plant's robot (with its payload).
    pub fn robot(&self) -> &Robot {
        &self.robot
    }
    /// The plant's settings.
    pub fn settings(&self) -> &PlantSettings {
        &self.settings
    }

    /// The integration substeps per control period.
    pub fn substeps(&self) -> usize {
        self.substeps
    }

    /// The control period (s): how far [`Self::advance`] goes.
    pub fn period(&self) -> f64 {
        self.ts
    }

    /// Sets the control period to `ts` (s), a whole number of the settings'
    /// substeps, and matches the faults to its samples again; nothing when
    /// `ts` is the period already. Allocation-free. An error leaves the
    /// period as it was.
    pub fn set_period(&mut self, ts: f64) -> Result<(), PlantError> {
        if ts.to_bits() == self.ts.to_bits() {
            return Ok(());
        }
        let k = substeps(ts, self.settings.substep)?;
        if let Some(servo) = &self.settings.servo {
            servo
                .validate_for(ts, self.settings.substep)
                .map_err(PlantSettingsError::from)?;
        }
        self.substeps = k;
        self.ts = ts;
        self.schedule.reschedule(&self.settings.faults, ts);
        Ok(())
    }

    /// The faults' samples, counted from the path's first sample.
    pub fn fault_schedule(&self) -> &FaultSchedule {
        &self.schedule
    }

    /// The path — sample 0 of the faults' schedule, whose times are path
    /// times — begins after `samples` more periods: a loop that holds the
    /// robot at rest before the path (the adaptive controllers'
    /// identification, `super::RunEvents::pre_roll`) says so before its
    /// first sample, and no fault happens in those periods. Without it the
    /// path begins with the plant's first period.
    pub fn start_path_after(&mut self, samples: usize) {
        self.origin = self.steps.saturating_add(samples);
    }

    /// The path sample of the current period, `None` before the path.
    fn path_sample(&self) -> Option<usize> {
        self.steps.checked_sub(self.origin)
    }

    /// Time constant of the smoothed Coulomb friction at rest, the shortest
    /// over the joints at the current configuration:
    /// `min_i H_ii · v_s / F_c,i` (s). Near zero velocity the friction
    /// `F_c tanh(q̇/v_s)` acts as a damping `F_c/v_s`; the RK4 substep must be
    /// a few of these time constants at most for a joint's sticking to be
    /// resolved (measured on the IRB 140's wrist, `H_66` ≈ 0.05 kg·m², 1 N·m,
    /// `v_s` = 1e-3 rad/s: τ = 5e-5 s; steady errors change 1e4-fold between
    /// substeps of 1 ms and 0.2 ms and do not change below 0.2 ms ≈ 4τ).
    /// `None` without Coulomb friction.
    pub fn coulomb_time_constant(&mut self) -> Result<Option<f64>, ModelError> {
        if self.coulomb.iter().all(|c| *c <= 0.0) {
            return Ok(None);
        }
        let h = crate::dynamics::crba(&self.robot, &mut self.ws, &self.q)?;
        let vs = self.settings.coulomb_velocity;
        Ok(self
            .coulomb
            .iter()
            .enumerate()
            .filter(|(_, c)| **c > 0.0)
            .map(|(i, c)| h[(i, i)] * vs / c)
            .reduce(f64::min))
    }
    /// Attaches (or with `None`, removes) the payload at the flange from now
    /// on: a part picked up or put down. The state is unchanged.
    pub fn set_payload(
        &mut self,
        payload: Option<crate::robot::Payload>,
    ) -> Result<(), ModelError> {
        self.robot.set_payload(payload)
    }
    /// Sets the true state (for replays and tests); lengths must be `n`.
    pub fn set_state(&mut self, q: &[f64], qd: &[f64]) -> Result<(), ModelError> {
        self.robot.check_vector("q", q)?;
        self.robot.check_vector("qd", qd)?;
        self.q.copy_from_slice(q);
        self.qd.copy_from_slice(qd);
        Ok(())
    }
    /// True joint positions.
    pub fn q(&self) -> &[f64] {
        &self.q
    }
    /// True joint velocities.
    pub fn qd(&self) -> &[f64] {
        &self.qd
    }
    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.t
    }
    /// The torque actually applied over the last period (after saturation).
    pub fn applied_torque(&self) -> &[f64] {
        &self.tau
    }

    /// The true state for the sensor ([`JointState`]): the joint
    /// positions and velocities, the periods simulated, and the path sample
    /// of the current period (`None` before the path).
    pub fn state(&self) -> JointState<'_> {
        JointState {
            q: &self.q,
            qd: &self.qd,
            sample: self.steps,
            path_sample: self.path_sample(),
        }
    }

    /// Advances the plant by one control period ([`Self::period`]) under the
    /// constant torque `tau` (zero-order hold: the torque the drives apply,
    /// [`super::Actuator::apply`]), by RK4 substeps. Returns an
    /// error (and leaves the state as it was) when the state or torque stops
    /// being finite.
    pub fn advance(&mut self, tau: &[f64]) -> Result<(), PlantError> {
        let n = self.q.len();
        self.robot.check_vector("tau", tau)?;
        self.tau.copy_from_slice(tau);
        let (steps, ts) = (self.substeps, self.ts);
        let h = ts / steps as f64;
        self.backup[..n].copy_from_slice(&self.q);
        self.backup[n..].copy_from_slice(&self.qd);
        let r = self.integrate(steps, h);
        if r.is_err() {
            self.q.copy_from_slice(&self.backup[..n]);
            self.qd.copy_from_slice(&self.backup[n..]);
            return r;
        }
        self.t += ts;
        self.steps += 1;
        Ok(())
    }

    /// Advances the plant by one control period with the torque of each
    /// substep given by `drive(i, q, q̇, τ)` (substep `i` of the period, the
    /// true state at its start; `τ` held over the substep): a servo
    /// interface's joint loop ([`super::Servo`]) running at the integration
    /// substep. [`Self::applied_torque`] is then the period's mean torque.
    /// An error (of `drive`, or a state that stops being finite) leaves the
    /// state as it was. Allocation-free.
    pub fn advance_with(&mut self, drive: &mut SubstepDrive<'_>) -> Result<(), PlantError> {
        let n = self.q.len();
        let steps = self.substeps;
        let h = self.ts / steps as f64;
        self.backup[..n].copy_from_slice(&self.q);
        self.backup[n..].copy_from_slice(&self.qd);
        self.mean.fill(0.0);
        let r = self.drive_substeps(drive, steps, h);
        if r.is_err() {
            self.q.copy_from_slice(&self.backup[..n]);
            self.qd.copy_from_slice(&self.backup[n..]);
            return r;
        }
        self.tau.copy_from_slice(&self.mean);
        self.t += self.ts;
        self.steps += 1;
        Ok(())
    }

    /// The substeps of [`Self::advance_with`].
    fn drive_substeps(
        &mut self,
        drive: &mut SubstepDrive<'_>,
        steps: usize,
        h: f64,
    ) -> Result<(), PlantError> {
        for i in 0..steps {
            drive(i, &self.q, &self.qd, &mut self.tau)?;
            self.robot.check_vector("tau", &self.tau)?;
            for (m, t) in self.mean.iter_mut().zip(&self.tau) {
                *m += t / steps as f64;
            }
            self.integrate(1, h)?;
        }
        Ok(())
    }

    fn integrate(&mut self, steps: usize, h: f64) -> Result<(), PlantError> {
        let n = self.q.len();
        let vs = self.settings.coulomb_velocity;
        let vst = self.settings.stribeck_velocity;
        for _ in 0..steps {
            let Self {
                robot,
                ws,
                viscous,
                coulomb,
                stribeck,
                tau,
                net,
                rk4,
                q,
                qd,
                ..
            } = self;
            rk4_second_order_step(q, qd, h, rk4, |q, v, a| {
                // Net torque: applied minus friction (opposes motion).
                for i in 0..n {
                    net[i] = tau[i]
                        - crate::dynamics::friction::torque(viscous[i], coulomb[i], vs, v[i]);
                }
                // Stribeck: the breakaway excess, fading with speed.
                for (i, s) in stribeck.iter().enumerate() {
                    net[i] -= s * (-(v[i] / vst).powi(2)).exp() * (v[i] / vs).tanh();
                }
                a.copy_from_slice(forward_dynamics(robot, ws, q, v, net)?.as_slice());
                Ok::<(), ModelError>(())
            })?;
            if let Some(joint) =
                (0..n).find(|&i| !(self.q[i].is_finite() && self.qd[i].is_finite()))
            {
                return Err(PlantError::NonFiniteState { joint });
            }
        }
        Ok(())
    }

    /// Flange position of the true robot at its current state (base frame, m).
    pub fn flange_position(&mut self) -> [f64; 3] {
        match forward_kinematics(&self.robot, &mut self.ws, &self.q) {
            Ok(f) => [f.pos.x, f.pos.y, f.pos.z],
            Err(_) => [f64::NAN; 3],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::{gravity, kinetic_energy, potential_energy};

    /// The friction's time constant at rest is min H_ii·v_s/F_c (brute force
    /// from the CRBA diagonal), and a substep of 4 of them resolves a joint's
    /// sticking: from rest, under a torque 10 % below the Coulomb level, the
    /// wrist creeps at v_s·atanh(0.9) as the exact solution does (a substep
    /// of 40 of them does not).
    #[test]
    fn coulomb_time_constant_bounds_the_substep_that_resolves_sticking() {
        let q0 = [0.0, 0.3, -0.2, 0.0, 0.5, 0.0];
        let settings = PlantSettings {
            coulomb_friction: vec![1.0],
            ..Default::default()
        };
        let robot = Robot::irb140();
        let mut ws = Workspace::new(&robot);
        let h = crate::dynamics::crba(&robot, &mut ws, &q0).unwrap().clone();
        let expect = (0..6)
            .map(|i| h[(i, i)] * 1e-3 / 1.0)
            .fold(f64::INFINITY, f64::min);
        let mut p = Plant::with_period(robot.clone(), settings.clone(), &q0, 0.01).unwrap();
        let tau_c = p.coulomb_time_constant().unwrap().unwrap();
        assert!(
            (tau_c - expect).abs() <= 1e-12 * expect,
            "{tau_c} vs {expect}"
        );
        let none = Plant::with_period(robot.clone(), PlantSettings::default(), &q0, 0.01)
            .unwrap()
            .coulomb_time_constant()
            .unwrap();
        assert_eq!(none, None);
        // Creep of the wrist (joint 6) under gravity compensation plus 0.9 N·m.
        let g: Vec<f64> = crate::dynamics::gravity(&robot, &mut ws, &q0)
            .unwrap()
            .iter()
            .copied()
            .collect();
        let creep = |substep: f64| {
            let s = PlantSettings {
                substep,
                ..settings.clone()
            };
            let mut p = Plant::with_period(robot.clone(), s, &q0, 0.01).unwrap();
            let mut tau = g.clone();
            tau[5] += 0.9;
            for _ in 0..5 {
                p.advance(&tau).unwrap();
            }
            p.qd()[5]
        };
        let exact = 1e-3 * 0.9f64.atanh();
        let resolved = creep(1e-2 / (1e-2 / (4.0 * tau_c)).ceil());
        assert!(
            (resolved - exact).abs() <= 0.05 * exact,
            "{resolved} vs {exact}"
        );
        let coarse = creep(1e-2 / (1e-2 / (40.0 * tau_c)).ceil());
        assert!(
            (coarse - exact).abs() > 0.05 * exact,
            "coarse {coarse} vs {exact}"
        );
    }

    #[test]
    fn gravity_compensated_robot_stays_at_rest() {
        let robot = Robot::irb140();
        let q0 = [0.2, 0.3, -0.2, 0.5, 0.6, 0.1];
        let mut ws = Workspace::new(&robot);
        let g: Vec<f64> = gravity(&robot, &mut ws, &q0)
            .unwrap()
            .iter()
            .copied()
            .collect();
        let mut p = Plant::with_period(robot, PlantSettings::default(), &q0, 0.01).unwrap();
        for _ in 0..100 {
            p.advance(&g).unwrap();
        }
        let drift = p
            .q()
            .iter()
            .zip(&q0)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(drift < 1e-10, "drift {drift:e}");
    }

    #[test]
    fn unforced_plant_conserves_energy_and_friction_dissipates_it() {
        let q0 = [0.0, 0.3, 0.2, 0.0, 0.4, 0.0];
        let energy = |p: &Plant| {
            let mut ws = Workspace::new(p.robot());
            kinetic_energy(p.robot(), &mut ws, p.q(), p.qd()).unwrap()
                + potential_energy(p.robot(), &mut ws, p.q()).unwrap()
        };
        let mut free =
            Plant::with_period(Robot::irb140(), PlantSettings::default(), &q0, 0.01).unwrap();
        let settings = PlantSettings {
            viscous_friction: vec![2.0],
            coulomb_friction: vec![1.0],
            ..Default::default()
        };
        let mut damped = Plant::with_period(Robot::irb140(), settings, &q0, 0.01).unwrap();
        let e0 = energy(&free);
        let zero = [0.0; 6];
        for _ in 0..100 {
            free.advance(&zero).unwrap();
            damped.advance(&zero).unwrap();
        }
        let (e_free, e_damped) = (energy(&free), energy(&damped));
        assert!(
            (e_free - e0).abs() < 1e-6 * e0.abs().max(1.0),
            "{e0} → {e_free}"
        );
        assert!(
            e_damped < e0 - 1.0,
            "friction must dissipate: {e0} → {e_damped}"
        );
    }

    #[test]
    fn a_non_finite_torque_is_an_error() {
        let mut p =
            Plant::with_period(Robot::irb140(), PlantSettings::default(), &[0.0; 6], 0.01).unwrap();
        assert!(p.advance(&[f64::NAN; 6]).is_err());
        assert!(PlantSettings {
            viscous_friction: vec![1.0, 2.0],
            ..Default::default()
        }
        .validate(6)
        .is_err());
    }

    /// The faults are matched to the samples of the period the plant is
    /// built with, and again (in place) when the period changes: a torque
    /// drop at 0.05 s for 0.03 s covers samples [5, 8) at 10 ms, [10, 16) at
    /// 5 ms.
    #[test]
    fn the_faults_are_scheduled_at_the_plants_period() {
        let q0 = [0.0, 0.3, 0.2, 0.0, 0.4, 0.0];
        let s = PlantSettings {
            faults: vec![Fault::TorqueDrop {
                t: 0.05,
                joint: 2,
                fraction: 0.0,
                duration_s: 0.03,
            }],
            ..Default::default()
        };
        let mut p = Plant::with_period(Robot::irb140(), s, &q0, 0.01).unwrap();
        assert_eq!(p.fault_schedule().range(0), Some((5, 8)));
        p.set_period(0.005).unwrap();
        assert_eq!(p.fault_schedule().range(0), Some((10, 16)));
    }
}
