//! The CLI's words for the library's typed errors: each is mapped to the
//! scenario key (or command-line flag) that set the offending value, followed
//! by the library's explanation. The library never names keys or flags.

use ofmpc::control::{DriveQuantity, SettingsError};
use ofmpc::sim::{
    ExperimentError, FrictionKind, LoopSettingsError, NoiseKind, PlantError, PlantSettingsError,
};
use std::fmt;

/// Some runs failed (a controller step or the plant's integration); their
/// results were written, and the process exits with status 1.
#[derive(Debug)]
pub struct RunsFailed {
    /// `name: reason` of each failed run.
    pub runs: Vec<String>,
}

impl fmt::Display for RunsFailed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} run(s) failed (their results so far are in metrics.json with \"status\": \"failed\"):",
            self.runs.len()
        )?;
        for r in &self.runs {
            write!(f, "\n  {r}")?;
        }
        Ok(())
    }
}

impl std::error::Error for RunsFailed {}

/// The scenario key that holds the value an [`ExperimentError`] is about,
/// with that value, e.g. `[plant] substep = 1e-300`.
pub fn experiment_key(e: &ExperimentError) -> Option<String> {
    Some(match e {
        ExperimentError::Loop(l) => match l {
            LoopSettingsError::HoldTime(v) => format!("[simulation] hold_s = {v}"),
            LoopSettingsError::DivergenceThreshold(v) => {
                format!("[simulation] divergence_threshold_rad = {v}")
            }
            LoopSettingsError::SteadyWindow { value, .. } => {
                format!("[simulation] steady_window_s = {value}")
            }
            LoopSettingsError::IdentificationTime { value, .. } => {
                format!("[simulation] identification_s = {value}")
            }
            LoopSettingsError::PickUpTime(v) => format!("[payload] pick_up_at_s = {v}"),
            LoopSettingsError::FaultTime { index, value } => {
                format!("[faults] nan_at_s[{index}] = {value}")
            }
            LoopSettingsError::DropoutInterval { index, from, to } => {
                format!("[faults] dropout_s[{index}] = [{from}, {to}]")
            }
            LoopSettingsError::MaxJointError(v) => format!("[safety] max_joint_error_rad = {v}"),
            _ => "[simulation]".into(),
        },
        ExperimentError::Plant(PlantError::Settings(p)) => match p {
            PlantSettingsError::Substep(v) => format!("[plant] substep = {v}"),
            PlantSettingsError::SubstepRatio { ts, substep, .. } => {
                format!("[plant] substep = {substep} with [mpc] ts = {ts}")
            }
            PlantSettingsError::FrictionLength { kind, .. }
            | PlantSettingsError::FrictionValue { kind, .. } => format!(
                "[plant] {}",
                match kind {
                    FrictionKind::Viscous => "viscous_friction",
                    _ => "coulomb_friction",
                }
            ),
            PlantSettingsError::CoulombVelocity(v) => format!("[plant] coulomb_velocity = {v}"),
            PlantSettingsError::Delay(v) => format!("[plant] delay_samples = {v}"),
            PlantSettingsError::Fault {
                index, what, value, ..
            } => format!("[plant] faults[{index}].{what} = {value}"),
            PlantSettingsError::Noise { kind, value } => format!(
                "[plant] {} = {value}",
                match kind {
                    NoiseKind::Position => "position_noise",
                    _ => "velocity_noise",
                }
            ),
            _ => "[plant]".into(),
        },
        ExperimentError::Mpc(SettingsError::DriveModelLength { what, .. })
        | ExperimentError::Mpc(SettingsError::DriveModelValue { what, .. }) => format!(
            "the drives file's {}",
            match what {
                DriveQuantity::MaxTorque => "max_torque_nm",
                DriveQuantity::Coulomb => "coulomb_nm",
                DriveQuantity::Viscous => "viscous_nms",
                _ => "values",
            }
        ),
        ExperimentError::Mpc(SettingsError::DrivesUnsupported(_)) => {
            "[mpc] torque_limits / friction_compensation".into()
        }
        ExperimentError::Mpc(_) => "[mpc]".into(),
        ExperimentError::TooManySamples { .. } => {
            "the program's duration with [simulation] hold_s at [mpc] ts".into()
        }
        ExperimentError::Model(_) => "[payload]".into(),
        _ => return None,
    })
}

/// `key: explanation` for an [`ExperimentError`].
pub fn experiment_error(e: &ExperimentError) -> String {
    match experiment_key(e) {
        Some(k) => format!("{k}: {e}"),
        None => e.to_string(),
    }
}
