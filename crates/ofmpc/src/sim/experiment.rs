//! One experiment of the paper's section IV: a controller, its model of the
//! robot (no payload), the plant with the payload it does not know, the joint
//! reference; run, then judged.

use super::closed_loop::{run_closed_loop, LoopSettings, RunResult};
use super::metrics::{compute, RunMetrics};
use super::plant::{Plant, PlantSettings};
use crate::control::{new_controller, ControllerKind, MpcSettings};
use crate::dynamics::RobotDynamics;
use crate::motion::JointReference;
use crate::robot::{Payload, Robot};

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
}

/// Name of a run's folder: `<controller>_m<payload>`, e.g. `second_m0.25`.
pub fn run_name(kind: ControllerKind, payload: &Payload) -> String {
    format!("{}_m{}", kind_name(kind), payload.mass)
}

/// "usual", "first" or "second".
pub fn kind_name(kind: ControllerKind) -> &'static str {
    match kind {
        ControllerKind::Usual => "usual",
        ControllerKind::First => "first",
        ControllerKind::Second => "second",
    }
}

impl Experiment {
    /// Runs `kind` against the plant carrying `payload`. Errors only for
    /// settings that do not fit; a diverging run is a result, not an error.
    pub fn run(
        &self,
        kind: ControllerKind,
        payload: &Payload,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<(RunResult, RunMetrics), String> {
        let n = self.robot.dof();
        if self.reference.dof() != n {
            return Err(format!(
                "the reference has {} joints, the robot {n}: build the reference for this robot",
                self.reference.dof()
            ));
        }
        if (self.mpc.ts - self.reference.ts()).abs() > 1e-12 {
            return Err(format!(
                "the controller's ts {} s differs from the reference's {} s",
                self.mpc.ts,
                self.reference.ts()
            ));
        }
        let mut controller = new_controller(kind, n, &self.mpc).map_err(|e| e.to_string())?;
        let mut model = RobotDynamics::new(self.robot.clone());
        let mut plant_robot = self.robot.clone();
        plant_robot
            .set_payload(Some(*payload))
            .map_err(|e| e.to_string())?;
        let mut plant = Plant::new(plant_robot, self.plant.clone(), self.reference.q(0))
            .map_err(|e| e.to_string())?;
        let result = run_closed_loop(
            controller.as_mut(),
            &mut model,
            &mut plant,
            &self.reference,
            &self.loop_settings,
            progress,
        );
        let metrics = compute(
            &run_name(kind, payload),
            kind_name(kind),
            payload.mass,
            &result.record,
            self.loop_settings.steady_window_s,
            result.wall_s,
            result.diverged_at,
        );
        Ok((result, metrics))
    }
}
