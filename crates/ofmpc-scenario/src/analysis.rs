//! Analyses of a resolved scenario that need no full run: the stability
//! margin of each controller ([`margin`], [`radius_curves`]) and robust
//! tuning over a payload range ([`robust_tuning`]).

use crate::error::ScenarioError;
use crate::file::ScenarioFile;
use crate::resolve::Scenario;
use ofmpc::analysis::{inertia_ratio_range, max_payload, StabilityOptions, StabilityProblem};
use ofmpc::control::{BaselineSettings, ControllerKind, MpcSettings, Weight};
use ofmpc::robot::{Payload, Robot};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// The heaviest payload `max_payload_kg` reports (kg): a controller still
/// inside its interval there reports this bound.
pub const PAYLOAD_SEARCH_LIMIT_KG: f64 = 1000.0;

/// What `analyze stability` computes for one controller.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Margin {
    /// `[lo, hi]` of α = H_model/H_plant, stable near rest.
    pub alpha_interval: [f64; 2],
    /// Largest point payload at the flange keeping α inside along the program (kg).
    pub max_payload_kg: f64,
}

/// The controllers' model of the robot (with the payload `[mpc] model_payload_kg` assumes).
pub fn model_robot(scenario: &Scenario) -> Result<Robot, ScenarioError> {
    scenario
        .experiment
        .model_robot()
        .map_err(|error| ScenarioError::experiment(None, error))
}

/// The margin of `kind` for the robot, tuning and program of `scenario`:
/// α interval at the program's first point, payload along the program.
pub fn margin(scenario: &Scenario, kind: ControllerKind) -> Result<Margin, ScenarioError> {
    let exp = &scenario.experiment;
    let robot = model_robot(scenario)?;
    let q0 = exp.reference.q(0);
    let opts = StabilityOptions::default();
    let (lo, hi) = StabilityProblem {
        robot: &robot,
        kind: kind.base(),
        settings: &exp.mpc,
        baselines: &exp.baselines,
        q0,
        options: &opts,
    }
    .alpha_interval()
    .map_err(|source| ScenarioError::Stability {
        kind,
        source: Box::new(source),
    })?;
    let poses = program_poses(scenario);
    let m = max_payload(&robot, (lo, hi), &poses, PAYLOAD_SEARCH_LIMIT_KG)?;
    Ok(Margin {
        alpha_interval: [lo, hi],
        max_payload_kg: m,
    })
}

/// Every 10th point of the joint reference.
pub fn program_poses(scenario: &Scenario) -> Vec<&[f64]> {
    let r = &scenario.experiment.reference;
    (0..r.len()).step_by(10).map(|k| r.q(k)).collect()
}

/// One controller's spectral radius near rest against the inertia ratio.
#[derive(Debug, Clone)]
pub struct RadiusCurve {
    /// The controller.
    pub kind: ControllerKind,
    /// α = H_model/H_plant.
    pub alpha: Vec<f64>,
    /// The spectral radius ρ at each α (stable below 1).
    pub radius: Vec<f64>,
}

/// The spectral radius against α ∈ [0.3, 1.7] (step 0.025) of each controller near rest
/// at `q0` with `mpc` (a baseline with its bandwidth of `baselines`), on the model `robot`.
pub fn radius_curves(
    robot: &Robot,
    mpc: &MpcSettings,
    baselines: &BaselineSettings,
    q0: &[f64],
    kinds: &[ControllerKind],
) -> Result<Vec<RadiusCurve>, ScenarioError> {
    let alpha: Vec<f64> = (0..=56).map(|i| 0.3 + 0.025 * i as f64).collect();
    let opts = StabilityOptions::default();
    kinds
        .iter()
        .map(|&kind| {
            let radius = alpha
                .iter()
                .map(|&a| {
                    StabilityProblem {
                        robot,
                        kind: kind.base(),
                        settings: mpc,
                        baselines,
                        q0,
                        options: &opts,
                    }
                    .spectral_radius(a)
                })
                .collect::<Result<Vec<f64>, _>>()?;
            Ok(RadiusCurve {
                kind,
                alpha: alpha.clone(),
                radius,
            })
        })
        .collect()
}

/// The weights `Q_Δy` of the robust tuning's grid.
pub const TUNING_Q_DY: [f64; 3] = [0.1, 0.5, 2.0];
/// The weights `Q_Δu` of the robust tuning's grid.
pub const TUNING_Q_DU: [f64; 5] = [1e-5, 1e-4, 1e-3, 1e-2, 1e-1];
/// Model payloads tried per weight pair (evenly over the range).
const MODEL_GRID: usize = 13;

/// One tuning of the robust tuning's grid.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Candidate {
    /// Output-increment weight (times I).
    pub q_dy: f64,
    /// Input-increment weight (times I).
    pub q_du: f64,
    /// Per-joint weights: `Q_Δy` and `Q_Δu` of the wrist (the last three
    /// joints of an arm with at least four) are these times the scalar ones
    /// (1: the scalar tuning).
    pub wrist_scale: f64,
    /// The payload the model assumes (kg).
    pub model_payload_kg: f64,
    /// `min(ln(α_min/lo), ln(hi/α_max))` over the range: positive = inside every
    /// controller's interval.
    pub margin: f64,
    /// Worst RMS Cartesian error (mm) of the simulated runs; NaN when not simulated.
    pub rms_mm: f64,
    /// Whether every simulated run completed without steady error.
    pub offset_free: bool,
    /// Its runs were stopped early because it could no longer win: the
    /// worst RMS error of the runs made already exceeded that of a
    /// candidate simulated completely and offset-free (branch and bound;
    /// `rms_mm` is then that partial worst, `offset_free` false).
    pub pruned: bool,
}

/// What [`robust_tuning`] found.
#[derive(Debug, Clone)]
pub struct Tuning {
    /// Every weight pair with its best model payload (simulated when its margin is positive).
    pub candidates: Vec<Candidate>,
    /// The offset-free candidate with the least worst RMS error.
    pub chosen: Candidate,
    /// The payloads simulated (the range's ends and middle, kg).
    pub simulated_kg: [f64; 3],
    /// The scenario with the chosen tuning: the base scenario's file, these controllers,
    /// five payloads over the range.
    pub file: ScenarioFile,
    /// The controllers the scenario runs: the requested ones, or their
    /// adaptive variants when no plain tuning holds the range
    /// ([`Tuning::adaptive`]).
    pub controllers: Vec<ControllerKind>,
    /// No plain tuning (scalar or per-joint) held the range: the scenario
    /// runs the adaptive variants with the paper's tuning, which held it in
    /// simulation; `chosen` then describes that tuning (its margin: the α
    /// interval's distance from α = 1, the exact model they identify).
    pub adaptive: bool,
}

/// Per-joint weight scales of the wrist tried when no scalar tuning holds
/// the range (a light wrist needs heavier increment weights than the arm).
pub const TUNING_WRIST_SCALES: [f64; 3] = [10.0, 100.0, 0.1];

/// The paper's tuning with `Q_Δy`, `Q_Δu` (times I) and the model payload.
pub fn tuning_settings(q_dy: f64, q_du: f64, model_payload_kg: f64) -> MpcSettings {
    MpcSettings {
        q_dy: Weight::Scalar(q_dy),
        q_du: Weight::Scalar(q_du),
        model_payload_kg,
        ..MpcSettings::default()
    }
}

/// [`tuning_settings`] for `n` joints with the wrist's weights (the last
/// three joints when `n ≥ 4`) scaled by `wrist_scale` (per-joint weights;
/// scalar when the scale is 1).
pub fn candidate_settings(c: &Candidate, n: usize) -> MpcSettings {
    let mut s = tuning_settings(c.q_dy, c.q_du, c.model_payload_kg);
    if c.wrist_scale != 1.0 && n >= 4 {
        let diag = |w: f64| {
            Weight::Diagonal(
                (0..n)
                    .map(|i| if i + 3 >= n { w * c.wrist_scale } else { w })
                    .collect(),
            )
        };
        s.q_dy = diag(c.q_dy);
        s.q_du = diag(c.q_du);
    }
    s
}

/// Robust tuning of the non-adaptive controllers `kinds` over the point payloads
/// `lo_kg..=hi_kg` on the robot and program of `base`:
///
/// 1. For each weight pair `(Q_Δy, Q_Δu)` of a grid (`Q_yw = I`, `Q_u` as
///    given) and each controller, the α interval near rest at the program's
///    first point ([`ofmpc::analysis::StabilityProblem::alpha_interval`]).
/// 2. For each pair, the payload the model should assume: on a grid over the
///    range, the one whose inertia ratios along the program, for the lightest
///    and the heaviest payload, stay inside every controller's interval with
///    the largest margin `min(ln(α_min/lo), ln(hi/α_max))`.
/// 3. The candidates with a positive margin are simulated along the program
///    at the range's ends and middle; the tuning with the least worst RMS
///    Cartesian error among the runs that completed offset-free wins. The
///    simulation is a branch and bound (the likeliest winner first; a
///    candidate that can no longer win is stopped, [`Candidate::pruned`]):
///    the same choice as simulating every candidate fully.
pub fn robust_tuning(
    base: &Scenario,
    lo_kg: f64,
    hi_kg: f64,
    kinds: &[ControllerKind],
) -> Result<Tuning, ScenarioError> {
    if !(lo_kg >= 0.0 && hi_kg >= lo_kg) {
        return Err(ScenarioError::PayloadRange {
            lo: lo_kg,
            hi: hi_kg,
        });
    }
    if let Some(&kind) = kinds.iter().find(|k| k.is_adaptive()) {
        return Err(ScenarioError::AdaptiveTuning { kind });
    }
    // The search per family of controllers: the incremental MPC (and the
    // usual one) here; other families add their own search beside it.
    let ranges = model_ratio_ranges(&base.experiment, (lo_kg, hi_kg), &program_poses(base))?;
    let mut candidates = mpc_candidates(base, (lo_kg, hi_kg), &ranges, kinds, &[1.0])?;
    let masses = [lo_kg, 0.5 * (lo_kg + hi_kg), hi_kg];
    let best = |cs: &[Candidate]| {
        cs.iter()
            .filter(|c| c.offset_free)
            .min_by(|a, b| a.rms_mm.total_cmp(&b.rms_mm))
            .cloned()
    };
    let mut chosen = best(&candidates);
    if chosen.is_none() && base.experiment.robot.dof() >= 4 {
        // Per-joint weights: the wrist weighted apart from the arm.
        let more = mpc_candidates(base, (lo_kg, hi_kg), &ranges, kinds, &TUNING_WRIST_SCALES)?;
        chosen = best(&more);
        candidates.extend(more);
    }
    let controllers_text = || kinds.iter().map(|k| k.name()).collect::<Vec<_>>().join(",");
    let (chosen, controllers, adaptive) = match chosen {
        Some(c) => (c, kinds.to_vec(), false),
        None => {
            let (c, adaptive_kinds) =
                adaptive_fallback(base, kinds, &masses)?.ok_or_else(|| {
                    ScenarioError::NoRobustTuning {
                        controllers: controllers_text(),
                        lo: lo_kg,
                        hi: hi_kg,
                    }
                })?;
            (c, adaptive_kinds, true)
        }
    };
    let file = tuned_file(base, &chosen, &controllers, adaptive, (lo_kg, hi_kg), kinds);
    Ok(Tuning {
        candidates,
        chosen,
        simulated_kg: masses,
        file,
        controllers,
        adaptive,
    })
}

/// The scenario file of a tuning: `base`'s with the chosen controllers and weights, a title
/// saying how they hold the payload range `(lo_kg, hi_kg)` and five payloads across it.
fn tuned_file(
    base: &Scenario,
    chosen: &Candidate,
    controllers: &[ControllerKind],
    adaptive: bool,
    (lo_kg, hi_kg): (f64, f64),
    kinds: &[ControllerKind],
) -> ScenarioFile {
    let names = kinds.iter().map(|k| k.name()).collect::<Vec<_>>().join(",");
    let mut file = base.file.clone();
    file.title = if adaptive {
        format!(
            "Payload range {lo_kg}..{hi_kg} kg: no plain tuning of {} holds it; the adaptive variants \
             (online identification) with the paper's tuning do",
            names
        )
    } else {
        format!(
            "Robust tuning for {lo_kg}..{hi_kg} kg: Q_Δy = {}, Q_Δu = {}, model payload {} kg{}",
            chosen.q_dy,
            chosen.q_du,
            chosen.model_payload_kg,
            if chosen.wrist_scale != 1.0 {
                format!(", wrist weights × {}", chosen.wrist_scale)
            } else {
                String::new()
            }
        )
    };
    file.controllers = controllers.to_vec();
    file.mpc = candidate_settings(chosen, base.experiment.robot.dof());
    file.payload.masses_kg = (0..=4)
        .map(|i| lo_kg + (hi_kg - lo_kg) * i as f64 / 4.0)
        .collect();
    file
}

/// The grid of weight pairs (`TUNING_Q_DY` × `TUNING_Q_DU`) for each wrist scale, as
/// candidates not yet analysed.
fn weight_grid(scales: &[f64]) -> Vec<Candidate> {
    scales
        .iter()
        .flat_map(|&w| {
            TUNING_Q_DY.iter().flat_map(move |&d| {
                TUNING_Q_DU.iter().map(move |&u| Candidate {
                    q_dy: d,
                    q_du: u,
                    wrist_scale: w,
                    model_payload_kg: 0.0,
                    margin: f64::NAN,
                    rms_mm: f64::NAN,
                    offset_free: false,
                    pruned: false,
                })
            })
        })
        .collect()
}

/// The intersection over the controllers `kinds` of their stable `α` intervals with
/// `settings` near rest at `q0`; `None` when one fails or the intersection's span hi/lo
/// falls to `span` or below (early rejection: no model payload fits the range).
fn common_interval(
    exp: &ofmpc::sim::Experiment,
    kinds: &[ControllerKind],
    settings: &MpcSettings,
    q0: &[f64],
    options: &StabilityOptions,
    span: f64,
) -> Option<(f64, f64)> {
    let mut iv = (0.0f64, f64::INFINITY);
    for &kind in kinds {
        let problem = StabilityProblem {
            robot: &exp.robot,
            kind,
            settings,
            baselines: &exp.baselines,
            q0,
            options,
        };
        let (lo, hi) = problem.alpha_interval().ok()?;
        iv = (iv.0.max(lo), iv.1.min(hi));
        if iv.1 / iv.0 <= span {
            return None;
        }
    }
    Some(iv)
}

/// Steps 1–3 of [`robust_tuning`] for the MPC controllers `kinds` with the
/// wrist scales `scales` ([`Candidate::wrist_scale`]): every weight pair of
/// the grid with its best model payload, the stable ones simulated.
/// `ranges`: [`model_ratio_ranges`] of the range.
fn mpc_candidates(
    base: &Scenario,
    (lo_kg, hi_kg): (f64, f64),
    ranges: &[(f64, f64)],
    kinds: &[ControllerKind],
    scales: &[f64],
) -> Result<Vec<Candidate>, ScenarioError> {
    let exp = &base.experiment;
    let n = exp.robot.dof();
    let q0 = exp.reference.q(0).to_vec();
    let opts = StabilityOptions {
        tolerance: 4e-3,
        ..Default::default()
    };
    // The smallest span hi/lo of α any model payload needs over the range:
    // a pair whose interval is narrower is rejected before its other
    // controllers are analysed (and never simulated).
    let span = (ranges.iter())
        .map(|(amin, amax)| amax / amin)
        .fold(f64::INFINITY, f64::min);
    let grid = weight_grid(scales);
    // 1. Intervals per weight pair (the intersection over the controllers).
    let intervals: Vec<Option<(f64, f64)>> = grid
        .par_iter()
        .map(|c| common_interval(exp, kinds, &candidate_settings(c, n), &q0, &opts, span))
        .collect();
    // 2. The model payload with the largest margin per pair.
    let mut candidates = Vec::new();
    for (c, iv) in grid.into_iter().zip(&intervals) {
        let Some(interval) = *iv else { continue };
        if let Some((m, margin)) = best_model_payload(interval, (lo_kg, hi_kg), ranges) {
            candidates.push(Candidate {
                model_payload_kg: m,
                margin,
                ..c
            });
        }
    }
    // 3. Simulate the stable candidates at the range's ends and middle.
    let masses = [lo_kg, 0.5 * (lo_kg + hi_kg), hi_kg];
    simulate_bounded(exp, &mut candidates, kinds, &masses);
    Ok(candidates)
}

/// [`model_ratio_range`] of every point of the model-payload grid (computed
/// once per tuning: they depend on the range, not on the weights). The
/// smallest `max α / min α` among them is what a stable interval must span
/// at least.
fn model_ratio_ranges(
    exp: &ofmpc::sim::Experiment,
    (lo_kg, hi_kg): (f64, f64),
    poses: &[&[f64]],
) -> Result<Vec<(f64, f64)>, ScenarioError> {
    (0..MODEL_GRID)
        .map(|i| model_ratio_range(exp, i, (lo_kg, hi_kg), poses))
        .collect()
}

/// The inertia-ratio range over the poses, for the lightest and the
/// heaviest payload, of grid point `i` of the model payload.
fn model_ratio_range(
    exp: &ofmpc::sim::Experiment,
    i: usize,
    (lo_kg, hi_kg): (f64, f64),
    poses: &[&[f64]],
) -> Result<(f64, f64), ScenarioError> {
    let m = model_grid_kg(i, (lo_kg, hi_kg));
    let mut model = exp.robot.clone();
    if m > 0.0 {
        model.set_payload(Some(Payload::point_mass(m)))?;
    }
    let mut amin = f64::INFINITY;
    let mut amax = f64::NEG_INFINITY;
    for p in [lo_kg, hi_kg] {
        let (a0, a1) = inertia_ratio_range(&model, &Payload::point_mass(p), poses)?;
        amin = amin.min(a0);
        amax = amax.max(a1);
    }
    Ok((amin, amax))
}

/// Grid point `i` of the model payload over the range (kg).
fn model_grid_kg(i: usize, (lo_kg, hi_kg): (f64, f64)) -> f64 {
    lo_kg + (hi_kg - lo_kg) * i as f64 / (MODEL_GRID - 1) as f64
}

/// When no plain tuning holds the range: the adaptive variants of `kinds`
/// with the paper's tuning, simulated at `masses`; the candidate (its
/// margin: `min(ln(1/lo), ln(hi))` of the plain controllers' α interval,
/// the distance of the exact model that identification restores from the
/// interval's ends) and the variants, when every run completed
/// offset-free.
fn adaptive_fallback(
    base: &Scenario,
    kinds: &[ControllerKind],
    masses: &[f64],
) -> Result<Option<(Candidate, Vec<ControllerKind>)>, ScenarioError> {
    let exp = &base.experiment;
    let mut adaptive: Vec<ControllerKind> = kinds
        .iter()
        .filter_map(|k| match k {
            ControllerKind::First => Some(ControllerKind::FirstAdaptive),
            ControllerKind::Second => Some(ControllerKind::SecondAdaptive),
            _ => None,
        })
        .collect();
    adaptive.dedup();
    if adaptive.is_empty() {
        return Ok(None);
    }
    let d = MpcSettings::default();
    let (Weight::Scalar(q_dy), Weight::Scalar(q_du)) = (&d.q_dy, &d.q_du) else {
        return Ok(None);
    };
    let mut c = Candidate {
        q_dy: *q_dy,
        q_du: *q_du,
        wrist_scale: 1.0,
        model_payload_kg: 0.0,
        margin: f64::NAN,
        rms_mm: f64::NAN,
        offset_free: false,
        pruned: false,
    };
    let q0 = exp.reference.q(0);
    let opts = StabilityOptions::default();
    let mut margin = f64::INFINITY;
    for k in &adaptive {
        let (lo, hi) = StabilityProblem {
            robot: &exp.robot,
            kind: k.base(),
            settings: &d,
            baselines: &exp.baselines,
            q0,
            options: &opts,
        }
        .alpha_interval()
        .map_err(|source| ScenarioError::Stability {
            kind: *k,
            source: Box::new(source),
        })?;
        margin = margin.min((1.0 / lo).ln().min(hi.ln()));
    }
    c.margin = margin;
    simulate_candidate(exp, &mut c, &adaptive, masses, f64::INFINITY);
    Ok(c.offset_free.then_some((c, adaptive)))
}

/// The model payload on a grid over `[lo_kg, hi_kg]` whose inertia-ratio
/// range over the poses (`ranges`, [`model_ratio_ranges`]) keeps the largest
/// logarithmic margin inside the stable `interval` of α, with that margin
/// (`None` without a grid point).
fn best_model_payload(
    (lo, hi): (f64, f64),
    (lo_kg, hi_kg): (f64, f64),
    ranges: &[(f64, f64)],
) -> Option<(f64, f64)> {
    let mut best: Option<(f64, f64)> = None;
    for (i, &(amin, amax)) in ranges.iter().enumerate() {
        let m = model_grid_kg(i, (lo_kg, hi_kg));
        let margin = (amin / lo).ln().min((hi / amax).ln());
        if !matches!(best, Some((_, b)) if b >= margin) {
            best = Some((m, margin));
        }
    }
    best
}

/// Steady joint error (rad) below which a run counts as offset-free.
pub(crate) const OFFSET_FREE_RAD: f64 = 1e-9;

/// Runs `e` with each controller of `kinds` at each payload of `masses` (in that order) and
/// returns whether every run completed offset-free (steady joint error ≤ [`OFFSET_FREE_RAD`])
/// and the worst Cartesian RMS error (mm) of the runs made: after the first run that does
/// not hold, the others are skipped (the candidate cannot be chosen any more).
pub(crate) fn runs_hold<'a>(
    e: &ofmpc::sim::Experiment,
    kinds: &[ControllerKind],
    masses: impl Iterator<Item = &'a f64> + Clone,
) -> (bool, f64) {
    let mut worst = 0.0f64;
    for &k in kinds {
        for &m in masses.clone() {
            let Ok((r, metrics)) = e.run(k, &Payload::point_mass(m), &mut |_, _| {}) else {
                return (false, worst);
            };
            worst = worst.max(metrics.cartesian_error_rms_mm);
            let steady =
                (metrics.steady_joint_error_max_rad.iter()).fold(0.0, |a: f64, &b| a.max(b));
            if !(r.outcome.is_completed() && steady <= OFFSET_FREE_RAD) {
                return (false, worst);
            }
        }
    }
    (true, worst)
}

/// Simulates the candidates with a positive margin, branch and bound.
///
/// The winner is the offset-free candidate with the least worst RMS error
/// (the first in grid order on equal RMS), so a candidate one of whose runs
/// already has a larger RMS error than the best candidate simulated
/// completely cannot win: its other runs are stopped ([`Candidate::pruned`]).
/// The candidates are simulated one after another, the likeliest winner
/// first ([`simulation_order`]), each one's runs in parallel; the bound
/// changes only between candidates, so the chosen candidate is the one an
/// exhaustive simulation chooses and does not depend on thread timing.
fn simulate_bounded(
    exp: &ofmpc::sim::Experiment,
    candidates: &mut [Candidate],
    kinds: &[ControllerKind],
    masses: &[f64],
) {
    let order = simulation_order(candidates);
    simulate_in_order(exp, candidates, &order, kinds, masses);
}

/// [`simulate_bounded`] in the given order of the candidates' indices.
fn simulate_in_order(
    exp: &ofmpc::sim::Experiment,
    candidates: &mut [Candidate],
    order: &[usize],
    kinds: &[ControllerKind],
    masses: &[f64],
) {
    let mut bound = f64::INFINITY;
    for &i in order {
        let c = &mut candidates[i];
        simulate_candidate(exp, c, kinds, masses, bound);
        if c.offset_free {
            bound = bound.min(c.rms_mm);
        }
    }
}

/// The indices of the candidates with a positive margin in the order
/// [`simulate_bounded`] simulates them: the likeliest winner first, so that
/// the bound is tight early (any order gives the same choice). The lightest
/// increment weights first (`Q_Δu`, then `Q_Δy`; grid order among equal
/// weights): the cost weighs the tracking error against the increments, so
/// among the stable candidates the lightest increment weights usually track
/// closest (a heuristic: it orders the work, not the choice).
fn simulation_order(candidates: &[Candidate]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..candidates.len())
        .filter(|&i| candidates[i].margin > 0.0)
        .collect();
    order.sort_by(|&a, &b| {
        let (ca, cb) = (&candidates[a], &candidates[b]);
        (ca.q_du.total_cmp(&cb.q_du)).then(ca.q_dy.total_cmp(&cb.q_dy))
    });
    order
}

/// What became of one run of a candidate ([`simulate_candidate`]).
#[derive(Debug, Clone, Copy)]
enum RunVerdict {
    /// Completed offset-free with this RMS Cartesian error (mm).
    Holds(f64),
    /// Diverged, failed or kept a steady error (its RMS error in mm; NaN
    /// without a result).
    Fails(f64),
    /// Ended early: another run of the candidate decided its fate.
    Cancelled,
}

/// One run of `e` with controller `kind` and a point payload of `mass` kg,
/// ended early when `stop` becomes true.
fn run_verdict(
    e: &ofmpc::sim::Experiment,
    kind: ControllerKind,
    mass: f64,
    stop: &AtomicBool,
) -> RunVerdict {
    match e.run_cancellable(kind, &Payload::point_mass(mass), &mut |_, _| {}, stop) {
        Err(ofmpc::sim::ExperimentError::Interrupted { .. }) => RunVerdict::Cancelled,
        Err(_) => RunVerdict::Fails(f64::NAN),
        Ok((r, metrics)) => {
            let rms = metrics.cartesian_error_rms_mm;
            let steady =
                (metrics.steady_joint_error_max_rad.iter()).fold(0.0, |a: f64, &b| a.max(b));
            if r.outcome.is_completed() && steady <= OFFSET_FREE_RAD {
                RunVerdict::Holds(rms)
            } else {
                RunVerdict::Fails(rms)
            }
        }
    }
}

/// Simulates candidate `c` for every controller of `kinds` at the payloads
/// `masses` (each controller's heaviest payload first: the likeliest to
/// fail), the runs in parallel. A run that fails, or holds with an RMS error
/// above `bound` (the best complete candidate's), ends the candidate: its
/// other runs stop. `c.offset_free` when every run held within the bound;
/// `c.pruned` when a run exceeded the bound and none of those made failed;
/// `c.rms_mm` the worst RMS error of the runs made.
fn simulate_candidate(
    exp: &ofmpc::sim::Experiment,
    c: &mut Candidate,
    kinds: &[ControllerKind],
    masses: &[f64],
    bound: f64,
) {
    let mut e = exp.clone();
    e.mpc = candidate_settings(c, exp.robot.dof());
    let runs: Vec<(ControllerKind, f64)> = (kinds.iter())
        .flat_map(|&k| masses.iter().rev().map(move |&m| (k, m)))
        .collect();
    let stop = AtomicBool::new(false);
    let verdicts: Vec<RunVerdict> = runs
        .par_iter()
        .map(|&(k, m)| {
            if stop.load(Ordering::Relaxed) {
                return RunVerdict::Cancelled;
            }
            let v = run_verdict(&e, k, m, &stop);
            // A run that held within the bound (or without an RMS to compare) decides nothing.
            let decides = match v {
                RunVerdict::Holds(rms) => rms > bound,
                RunVerdict::Fails(_) => true,
                RunVerdict::Cancelled => false,
            };
            if decides {
                stop.store(true, Ordering::Relaxed);
            }
            v
        })
        .collect();
    let rms_of = |v: &RunVerdict| match *v {
        RunVerdict::Holds(r) | RunVerdict::Fails(r) => Some(r),
        RunVerdict::Cancelled => None,
    };
    c.rms_mm = verdicts.iter().filter_map(rms_of).fold(0.0, f64::max);
    let failed = verdicts.iter().any(|v| matches!(v, RunVerdict::Fails(_)));
    c.offset_free = !stop.load(Ordering::Relaxed);
    c.pruned = !c.offset_free && !failed;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chosen candidate: the offset-free one with the least worst RMS
    /// error, the first in grid order on equal RMS (as [`robust_tuning`]).
    fn chosen(cs: &[Candidate]) -> Option<usize> {
        (0..cs.len())
            .filter(|&i| cs[i].offset_free)
            .min_by(|&a, &b| cs[a].rms_mm.total_cmp(&cs[b].rms_mm))
    }

    /// Branch and bound chooses what simulating every candidate fully
    /// chooses, in any order of simulation: a pruned candidate's runs
    /// already exceed the chosen one's worst RMS, and every candidate not
    /// pruned has the verdict and RMS of its full simulation.
    #[test]
    fn branch_and_bound_chooses_as_the_exhaustive_search() {
        let base = Scenario::resolve(&ScenarioFile::default()).unwrap();
        let exp = &base.experiment;
        let kinds = [ControllerKind::First, ControllerKind::Second];
        let masses = [0.0, 1.5, 3.0];
        let grid: Vec<Candidate> = [(0.1, 1e-3), (0.5, 1e-2), (0.1, 1e-4), (2.0, 1e-1)]
            .iter()
            .map(|&(q_dy, q_du)| Candidate {
                q_dy,
                q_du,
                wrist_scale: 1.0,
                model_payload_kg: 1.5,
                margin: 1.0,
                rms_mm: f64::NAN,
                offset_free: false,
                pruned: false,
            })
            .collect();
        let mut full = grid.clone();
        for c in &mut full {
            simulate_candidate(exp, c, &kinds, &masses, f64::INFINITY);
            assert!(!c.pruned);
        }
        let want = chosen(&full).expect("an offset-free candidate");
        assert!(full.iter().filter(|c| c.offset_free).count() >= 2);
        let n = grid.len();
        for order in [(0..n).collect::<Vec<_>>(), (0..n).rev().collect()] {
            let mut cs = grid.clone();
            simulate_in_order(exp, &mut cs, &order, &kinds, &masses);
            assert_eq!(chosen(&cs), Some(want), "order {order:?}");
            for (c, f) in cs.iter().zip(&full) {
                if c.pruned {
                    assert!(c.rms_mm > full[want].rms_mm, "order {order:?}: {c:?}");
                    assert!(!c.offset_free);
                } else {
                    assert_eq!(c.offset_free, f.offset_free, "order {order:?}: {c:?}");
                    if c.offset_free {
                        assert_eq!(c.rms_mm, f.rms_mm, "order {order:?}: {c:?}");
                    }
                }
            }
        }
    }
}
