//! `ofmpc tune` for a baseline controller (`pid`, `ctc`, `ctc-adaptive`,
//! `dob-mpc`): the largest bandwidth of a grid that keeps every payload of
//! the range stable and offset-free, with its margin.
//!
//! A baseline has one tuning parameter, a bandwidth ([`BaselineSettings`]):
//! `ωn` of the PID/computed-torque error dynamics, `ω_o` of the
//! disturbance observer. Faster is more accurate until the payload the model
//! does not know (and the sampling) make the loop unstable. The search
//! simulates the range's ends and middle for each bandwidth of
//! [`BANDWIDTH_GRID`], ascending, and takes the last of the first run of
//! bandwidths that keep them all offset-free: below that run a loop is too
//! slow to settle within the hold (the integrator's pole scales with the
//! bandwidth), above it the unmodelled inertia leaves the sampled loop's
//! stable range (`control::baseline`, Jury bound). The margin is
//! `ln(ω_fail / ω)`, the logarithmic distance to the first failing bandwidth
//! above the chosen one (`None`: none above it failed).

use crate::error::ScenarioError;
use crate::file::ScenarioFile;
use crate::resolve::Scenario;
use ofmpc::control::{BaselineSettings, ControllerKind, Weight};
use ofmpc::sim::Experiment;
use rayon::prelude::*;

/// The bandwidths tried (rad/s), ascending: a geometric grid of ratio ≈ 1.26.
pub const BANDWIDTH_GRID: [f64; 16] = [
    10.0, 12.6, 15.8, 20.0, 25.1, 31.6, 39.8, 50.1, 63.1, 79.4, 100.0, 126.0, 158.0, 200.0, 251.0,
    316.0,
];

/// One bandwidth of the grid, simulated.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BandwidthCandidate {
    /// The bandwidth (rad/s).
    pub bandwidth: f64,
    /// Worst Cartesian RMS error over the simulated payloads (mm).
    pub rms_mm: f64,
    /// Every simulated run completed with steady joint error ≤ 1e-9 rad.
    pub offset_free: bool,
}

/// What [`baseline_bandwidth`] found.
#[derive(Debug, Clone)]
pub struct BandwidthTuning {
    /// Every bandwidth simulated, ascending.
    pub candidates: Vec<BandwidthCandidate>,
    /// The largest bandwidth of the first run of offset-free ones.
    pub chosen: BandwidthCandidate,
    /// `ln(ω_fail / ω_chosen)`; `None` when no bandwidth of the grid failed.
    pub margin: Option<f64>,
    /// The payloads simulated (the range's ends and middle, kg).
    pub simulated_kg: [f64; 3],
    /// The base scenario with this controller, the chosen bandwidth and five
    /// payloads over the range.
    pub file: ScenarioFile,
}

/// The settings with `kind`'s bandwidth set to `w` (every joint).
fn with_bandwidth(b: &BaselineSettings, kind: ControllerKind, w: f64) -> BaselineSettings {
    let mut b = b.clone();
    match kind.base() {
        ControllerKind::Pid => b.pid_bandwidth = Weight::Scalar(w),
        ControllerKind::DobMpc => b.dob_observer_bandwidth = Weight::Scalar(w),
        _ => b.ctc_bandwidth = Weight::Scalar(w),
    }
    b
}

fn simulate(exp: &Experiment, kind: ControllerKind, w: f64, masses: &[f64]) -> BandwidthCandidate {
    let mut e = exp.clone();
    e.baselines = with_bandwidth(&exp.baselines, kind, w);
    let (ok, worst) = crate::analysis::runs_hold(&e, &[kind], masses.iter());
    BandwidthCandidate {
        bandwidth: w,
        rms_mm: worst,
        offset_free: ok,
    }
}

/// The largest bandwidth of [`BANDWIDTH_GRID`] that keeps the baseline
/// `kind` offset-free at the payloads `lo_kg`, the middle and `hi_kg` on the
/// robot and program of `base` (module docs).
pub fn baseline_bandwidth(
    base: &Scenario,
    lo_kg: f64,
    hi_kg: f64,
    kind: ControllerKind,
) -> Result<BandwidthTuning, ScenarioError> {
    if !(lo_kg >= 0.0 && hi_kg >= lo_kg) {
        return Err(ScenarioError::PayloadRange {
            lo: lo_kg,
            hi: hi_kg,
        });
    }
    let exp = &base.experiment;
    let masses = [lo_kg, 0.5 * (lo_kg + hi_kg), hi_kg];
    let candidates: Vec<BandwidthCandidate> = BANDWIDTH_GRID
        .par_iter()
        .map(|&w| simulate(exp, kind, w, &masses))
        .collect();
    // The first run of offset-free bandwidths (module docs).
    let first_ok = candidates.iter().position(|c| c.offset_free);
    let first_fail = first_ok.and_then(|s| {
        candidates[s..]
            .iter()
            .position(|c| !c.offset_free)
            .map(|i| s + i)
    });
    let chosen_at = match (first_ok, first_fail) {
        (None, _) => None,
        (Some(_), Some(i)) => i.checked_sub(1),
        (Some(_), None) => candidates.len().checked_sub(1),
    };
    let no_tuning = || ScenarioError::NoRobustTuning {
        controllers: kind.name().to_string(),
        lo: lo_kg,
        hi: hi_kg,
    };
    let chosen = candidates
        .get(chosen_at.ok_or_else(no_tuning)?)
        .cloned()
        .ok_or_else(no_tuning)?;
    let margin = first_fail.map(|i| (candidates[i].bandwidth / chosen.bandwidth).ln());
    let mut file = base.file.clone();
    file.title = format!(
        "Bandwidth of {kind} for {lo_kg}..{hi_kg} kg: {} rad/s",
        chosen.bandwidth
    );
    file.controllers = vec![kind];
    file.baselines = with_bandwidth(&file.baselines, kind, chosen.bandwidth);
    file.payload.masses_kg = (0..=4)
        .map(|i| lo_kg + (hi_kg - lo_kg) * i as f64 / 4.0)
        .collect();
    Ok(BandwidthTuning {
        candidates,
        chosen,
        margin,
        simulated_kg: masses,
        file,
    })
}
