//! Builds the algorithm of a kind ([`new_controller_with_baselines`]), for
//! [`ControllerBuilder`](crate::control::ControllerBuilder).

use crate::control::adaptive::AdaptiveMpc;
use crate::control::algorithm::Algorithm;
use crate::control::baselines::ctc::CtcController;
use crate::control::baselines::dob_mpc::DobMpc;
use crate::control::baselines::pid::PidController;
use crate::control::kind::ControllerKind;
use crate::control::mpc::first::FirstMpc;
use crate::control::mpc::second::SecondMpc;
use crate::control::mpc::usual::UsualMpc;
use crate::control::settings::{BaselineSettings, MpcSettings, SettingsError};

/// Builds the controller `kind` for `n` joints after
/// [`MpcSettings::validate_for_dof`], a baseline with the default bandwidths
/// ([`BaselineSettings::default`]): [`new_controller_with_baselines`] with
/// those.
pub fn new_controller(
    kind: ControllerKind,
    n: usize,
    settings: &MpcSettings,
) -> Result<Box<dyn Algorithm + Send>, SettingsError> {
    new_controller_with_baselines(kind, n, settings, &BaselineSettings::default())
}

/// Builds the controller `kind` for `n` joints: a predictive controller of
/// the paper from `settings`, a baseline ([`ControllerKind::BASELINES`])
/// from `settings` and its bandwidth of `baselines` (the predictive kinds
/// do not read `baselines`; a baseline checks only its own bandwidth).
pub fn new_controller_with_baselines(
    kind: ControllerKind,
    n: usize,
    settings: &MpcSettings,
    baselines: &BaselineSettings,
) -> Result<Box<dyn Algorithm + Send>, SettingsError> {
    Ok(match kind {
        ControllerKind::Usual => Box::new(UsualMpc::new(n, settings)?),
        ControllerKind::First => Box::new(FirstMpc::new(n, settings)?),
        ControllerKind::Second => Box::new(SecondMpc::new(n, settings)?),
        ControllerKind::FirstAdaptive
        | ControllerKind::SecondAdaptive
        | ControllerKind::CtcAdaptive => Box::new(AdaptiveMpc::new(kind, n, settings, baselines)?),
        ControllerKind::Pid => Box::new(PidController::new(n, settings, baselines)?),
        ControllerKind::Ctc => Box::new(CtcController::new(n, settings, baselines)?),
        ControllerKind::DobMpc => Box::new(DobMpc::new(n, settings, baselines)?),
    })
}
