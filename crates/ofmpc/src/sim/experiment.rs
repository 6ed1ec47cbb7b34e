//! One experiment of the paper's section IV: a controller, its model of the
//! robot (no payload), the plant with the payload it does not know, the joint
//! reference; run, then judged.

use super::closed_loop::{
    record_columns, records_measurement, ClosedLoop, LoopSettings, RunEvents, RunResult,
};
use super::conditions::RunConditions;
use super::metrics::{compute, judge_hold, RunMetrics};
use super::outcome::{ExperimentError, RunFailure, RunOutcome, MAX_RECORD_VALUES};
use super::plant::{Plant, PlantSettings, PlantSettingsError};
use super::servo::ServoSettingsError;
use crate::control::{
    max_output_lead, BaselineSettings, BuildError, ControllerBuilder, ControllerKind, DriveModel,
    Mpc, MpcSettings, ObserverSettings, OutputMode,
};

/// Poles of the state observer's error dynamics (per sample). Measured on
/// the paper's path with a 22-bit encoder and one sample of delay (second
/// algorithm, 0.25 kg): 0.3 → steady joint error 1.7e-5 rad, 0.5 → 8.4e-6,
/// 0.7 → 3.0e-6, 0.85 → 2.0e-6 rad but Cartesian RMS 0.068 mm (0.012 at 0.7).
/// The builder's default (`crate::control::DEFAULT_OBSERVER_POLE`).
pub const OBSERVER_POLE: f64 = crate::control::DEFAULT_OBSERVER_POLE;
use crate::motion::JointReference;
use crate::robot::{ModelError, Payload, Robot};
use std::sync::atomic::AtomicBool;

/// Everything a run needs but the controller kind and the payload.
#[derive(Debug, Clone)]
pub struct Experiment {
    /// The robot as the controller knows it (no payload).
    pub robot: Robot,
    /// The joint reference (its `ts` is the control period).
    pub reference: JointReference,
    /// Controller tuning (its `ts` must equal the reference's).
    pub mpc: MpcSettings,
    /// Plant options.
    pub plant: PlantSettings,
    /// Hold, divergence threshold, steady window.
    pub loop_settings: LoopSettings,
    /// The payload's pick-up time, the safety limit, the measurement faults
    /// and the horizons to record ([`RunConditions::NONE`]: none).
    pub conditions: RunConditions,
    /// The baselines' bandwidths ([`BaselineSettings::default`]: the
    /// reference tuning): a baseline kind ([`ControllerKind::BASELINES`])
    /// builds with them ([`ControllerBuilder::baselines`], which checks them
    /// for the robot's joints); the predictive kinds do not read them.
    pub baselines: BaselineSettings,
}

/// Name of a run's folder: `<controller>_m<payload>`, e.g. `second_m0.25`.
///
/// The mass is written in its shortest round-trip form when that is short
/// (`0.25`, `6`, `1e-7`), else with 6 significant digits, so that a name stays
/// bounded (at most 13 characters for the mass) whatever the value.
pub fn run_name(kind: ControllerKind, payload: &Payload) -> String {
    format!("{}_m{}", kind_name(kind), mass_label(payload.mass))
}

/// The payload mass as written in run names (see [`run_name`]): its
/// shortest round-trip form when that has at most 12 characters, else rounded
/// to 6 significant digits (`0.30000000000000004` → `0.3`), in exponent form
/// when even that is long (`1e-300`).
pub fn mass_label(mass: f64) -> String {
    let m = if mass == 0.0 { 0.0 } else { mass }; // -0 → 0
    let short = format!("{m}");
    if short.len() <= 12 {
        return short;
    }
    let e = format!("{m:.5e}");
    let rounded = format!("{}", e.parse::<f64>().unwrap_or(m));
    if rounded.len() <= 12 {
        return rounded;
    }
    // Trim trailing zeros of the mantissa: 1.50000e300 → 1.5e300.
    match e.split_once('e') {
        Some((mant, exp)) => {
            let mant = mant.trim_end_matches('0').trim_end_matches('.');
            format!("{mant}e{exp}")
        }
        None => e,
    }
}

/// "usual", "first" or "second".
pub fn kind_name(kind: ControllerKind) -> &'static str {
    kind.name()
}

impl Experiment {
    /// Checks everything a run needs but the payload, before anything is
    /// allocated: the reference fits the robot and the controller's sample
    /// time, the tuning, the loop and plant settings, and the number of
    /// samples the run would record (`MAX_RECORD_VALUES`).
    pub fn validate(&self) -> Result<(), ExperimentError> {
        let n = self.robot.dof();
        if self.reference.dof() != n {
            return Err(ExperimentError::ReferenceDof {
                reference: self.reference.dof(),
                robot: n,
            });
        }
        let ts = self.reference.ts();
        if (self.mpc.ts - ts).abs() > 1e-12 {
            return Err(ExperimentError::SampleTime {
                controller: self.mpc.ts,
                reference: ts,
            });
        }
        self.mpc.validate_for_dof(n)?;
        // The controllers' limits are the robot's peak torques: the builder's rule.
        crate::control::check_torque_limits(&self.mpc, &DriveModel::from_robot(&self.robot))?;
        self.loop_settings.validate()?;
        self.conditions.validate()?;
        self.plant.validate_for(n, ts)?;
        check_servo_output(&self.plant, self.mpc.output)?;
        if let Some(smoothing_s) = self.mpc.output_smoothing_s {
            if self.mpc.output.is_torque() || !(smoothing_s.is_finite() && smoothing_s >= 0.0) {
                return Err(ExperimentError::Build(BuildError::OutputSmoothing {
                    smoothing_s,
                }));
            }
        }
        if let Some(lead_s) = self
            .output_lead_s()
            .filter(|l| !(*l >= 0.0 && *l <= max_output_lead(self.mpc.horizon, ts) * (1.0 + 1e-12)))
        {
            let max_s = max_output_lead(self.mpc.horizon, ts);
            return Err(ExperimentError::Build(BuildError::OutputLead {
                lead_s,
                max_s,
            }));
        }
        if let Some(m) = &self.plant.model {
            super::plant::check_plant_model(m, &self.robot)?;
        }
        let samples = self
            .reference
            .len()
            .saturating_add(self.loop_settings.hold_samples(ts));
        let columns = record_columns(n, records_measurement(&self.plant, &self.conditions.faults));
        let values = samples.saturating_mul(columns);
        if values > MAX_RECORD_VALUES {
            return Err(ExperimentError::TooManySamples {
                samples,
                columns,
                values,
                limit: MAX_RECORD_VALUES,
            });
        }
        Ok(())
    }

    /// The controllers' model: [`Self::robot`] with the payload the tuning
    /// assumes ([`MpcSettings::model_payload_kg`], when > 0).
    pub fn model_robot(&self) -> Result<Robot, ExperimentError> {
        Ok(crate::control::model_robot(&self.robot, &self.mpc)?)
    }

    /// Runs `kind` against the plant carrying `payload`. Errors only for
    /// settings that do not fit ([`Self::validate`], the payload); how the run
    /// ended (completed, diverged, failed) is its [`RunResult::outcome`].
    pub fn run(
        &self,
        kind: ControllerKind,
        payload: &Payload,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<(RunResult, RunMetrics), ExperimentError> {
        self.run_cancellable(kind, payload, progress, &AtomicBool::new(false))
    }

    /// [`Self::run`] that ends early when `cancel` becomes true (set by another thread,
    /// e.g. on a user's Ctrl-C; checked before every sample, [`ClosedLoop::cancel_on`]):
    /// then [`ExperimentError::Interrupted`], no result.
    pub fn run_cancellable(
        &self,
        kind: ControllerKind,
        payload: &Payload,
        progress: &mut dyn FnMut(usize, usize),
        cancel: &AtomicBool,
    ) -> Result<(RunResult, RunMetrics), ExperimentError> {
        self.validate()?;
        let mpc = self.controller(kind)?;
        payload.validate().map_err(ModelError::from)?;
        let ls = &self.loop_settings;
        let events = RunEvents {
            // The pre-roll at rest lets an adaptive kind identify its load;
            // through a position or velocity output it identifies nothing
            // unless the interface reports the torque it applied
            // (`control/adaptive.rs`), and settles as every other kind
            // (`LoopSettings::settle_s`, none by default). `dob-mpc` that
            // identifies its payload at rest (`dob_identify_at_rest`) rests
            // as long as the adaptive kinds.
            pre_roll: if self.identifies(kind) {
                ls.identification_samples(self.reference.ts())
            } else {
                ls.settle_samples(self.reference.ts())
            },
            pick_up: self.conditions.pick_up_at_s.map(|t| (t, *payload)),
        };
        let mut plant = self.plant_for(payload, events.pick_up.is_some())?;
        let result =
            ClosedLoop::with_conditions(mpc, &mut plant, &self.reference, ls, &self.conditions)
                .events(&events)
                .cancel_on(cancel)
                .run(progress);
        if let RunOutcome::Failed {
            t,
            cause: RunFailure::Interrupted,
        } = result.outcome
        {
            return Err(ExperimentError::Interrupted { t });
        }
        let mut metrics = compute(
            &run_name(kind, payload),
            kind_name(kind),
            payload.mass,
            &result.record,
            self.loop_settings.steady_window_s,
            result.wall_s,
            &result.outcome,
        );
        metrics.pre_roll_peak_joint_rad = result.pre_roll_peak_rad;
        judge_hold(
            &mut metrics,
            &result.record,
            self.loop_settings.steady_window_s,
            self.plant.encoder_counts,
        );
        Ok((result, metrics))
    }

    /// Whether `kind` identifies its payload in the pre-roll at rest (the
    /// identification's length, not the settling's): the adaptive kinds
    /// through a torque output or an interface that reports its applied
    /// torque, and `dob-mpc` with `dob_identify_at_rest` through a torque
    /// output.
    fn identifies(&self, kind: ControllerKind) -> bool {
        let dob = kind == ControllerKind::DobMpc && self.baselines.dob_identify_at_rest;
        let reported = (self.plant.servo.as_ref()).is_some_and(|s| s.reports_applied_torque());
        (kind.is_adaptive() && (self.mpc.output.is_torque() || reported))
            || (dob && self.mpc.output.is_torque())
    }

    /// The plant of a run with `payload`, at rest on the path's first point;
    /// with `picked_up_later` it carries nothing until the pick-up.
    fn plant_for(
        &self,
        payload: &Payload,
        picked_up_later: bool,
    ) -> Result<Plant, ExperimentError> {
        let (mut plant_robot, _) = self.plant.plant_robot(&self.robot)?;
        plant_robot.set_payload((!picked_up_later).then_some(*payload))?;
        Ok(Plant::with_period(
            plant_robot,
            self.plant.clone(),
            self.reference.q(0),
            self.reference.ts(),
        )?)
    }

    /// The controller's lead time: the tuning's, else — with a position or
    /// velocity output — the servo interface's lag and hold as the plant's
    /// substep runs them ([`super::ServoSettings::command_lead_s_at`]) and
    /// the part of its smoothing's delay the command does not
    /// pre-compensate ([`Self::output_smoothing_s`]).
    fn output_lead_s(&self) -> Option<f64> {
        match (&self.plant.servo, self.mpc.output_lead_s) {
            (Some(servo), None) if !self.mpc.output.is_torque() => {
                let h = self.plant.substep;
                let smoothing = servo.smoothing_s_at(h);
                let compensated = self.output_smoothing_s().unwrap_or(0.0);
                Some(servo.command_lead_s_at(h) + (smoothing - compensated).max(0.0))
            }
            (_, lead) => lead,
        }
    }

    /// The smoothing the command pre-compensates: the tuning's, else — the
    /// lead also left to the servo interface — the interface's own
    /// ([`super::ServoSettings::smoothing_s_at`]; `None` when it has none).
    fn output_smoothing_s(&self) -> Option<f64> {
        match (&self.plant.servo, self.mpc.output_smoothing_s) {
            (Some(servo), None)
                if !self.mpc.output.is_torque() && self.mpc.output_lead_s.is_none() =>
            {
                Some(servo.smoothing_s_at(self.plant.substep)).filter(|t| *t > 0.0)
            }
            (_, smoothing) => smoothing,
        }
    }

    /// The interface cycle and smoothing step the command's stream model
    /// runs at (`control/command.rs`): the tuning's, else — the smoothing
    /// also left to the servo interface ([`Self::output_smoothing_s`]) —
    /// the interface's cycle and the plant's substep (its filter's step).
    fn output_stream(&self) -> (Option<f64>, Option<f64>) {
        let (cycle, step) = (self.mpc.output_cycle_s, self.mpc.output_smoothing_step_s);
        match &self.plant.servo {
            Some(servo)
                if cycle.is_none()
                    && self.mpc.output_smoothing_s.is_none()
                    && self.output_smoothing_s().is_some() =>
            {
                (
                    Some(servo.params().period_s),
                    step.or(Some(self.plant.substep)),
                )
            }
            _ => (cycle, step),
        }
    }

    /// The controller `kind` of this experiment, built: the experiment's
    /// tuning, its baselines' gains, and an observer when the settings ask
    /// for one (with the plant's measurement delay).
    fn controller(&self, kind: ControllerKind) -> Result<Mpc, ExperimentError> {
        let observed = self.mpc.state_observer || self.mpc.delay_compensation;
        let mut settings = self.mpc.clone();
        settings.output_lead_s = self.output_lead_s();
        settings.output_smoothing_s = self.output_smoothing_s();
        (settings.output_cycle_s, settings.output_smoothing_step_s) = self.output_stream();
        let mut builder = ControllerBuilder::new(kind, &self.robot)
            .settings(settings)
            .accept_ineffective_settings();
        if kind.is_baseline() {
            builder = builder.baselines(self.baselines.clone());
        }
        if observed {
            builder = builder.observer(ObserverSettings {
                pole: OBSERVER_POLE,
                measurement_delay: self.plant.delay_samples,
            });
        }
        builder.build().map_err(|e| match e {
            // As the settings' and the model's own errors.
            BuildError::Settings(e) => ExperimentError::Mpc(e),
            BuildError::Model(e) => ExperimentError::Model(e),
            e => ExperimentError::Build(e),
        })
    }
}

/// The controller's `output` is what the plant's servo interface takes
/// (torque without one).
fn check_servo_output(plant: &PlantSettings, output: OutputMode) -> Result<(), PlantSettingsError> {
    let interface = plant
        .servo
        .as_ref()
        .map_or(OutputMode::Torque, |s| s.kind());
    if interface == output {
        return Ok(());
    }
    Err(match plant.servo {
        Some(_) => ServoSettingsError::OutputMismatch {
            interface,
            controller: output,
        },
        None => ServoSettingsError::NoInterface { output },
    }
    .into())
}

#[cfg(test)]
mod tests {
    use super::mass_label;

    #[test]
    fn mass_labels_are_short_and_distinct_where_it_matters() {
        assert_eq!(mass_label(0.25), "0.25");
        assert_eq!(mass_label(-0.0), "0");
        assert_eq!(mass_label(6.0), "6");
        assert_eq!(mass_label(0.1 + 0.2), "0.3");
        assert_eq!(mass_label(1e-300), "1e-300");
        assert_eq!(mass_label(1.5e300), "1.5e300");
        assert_eq!(mass_label(1.0 / 3.0), "0.333333");
        for m in [1e-300, 1e300, 0.1 + 0.2, 123456.789012345, f64::MAX] {
            assert!(mass_label(m).len() <= 13, "{m}: {}", mass_label(m));
        }
    }
}
