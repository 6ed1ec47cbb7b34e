//! `ofmpc analyze stability`: the inertia-ratio interval of each controller
//! near rest (from its real step, linearized by perturbation), the largest
//! point payload that keeps the ratio inside it along the program, and the
//! spectral radius against α as a figure.

use crate::args::SetupArgs;
use crate::cli::StabilityArgs;
use crate::output::console;
use crate::output::plot::{render_both, Figure, Panel, Series, COLOR_REFERENCE};
use anyhow::Context;
use ofmpc::control::{ControllerKind, MpcSettings};
use ofmpc_scenario::analysis::{margin, model_robot, radius_curves, Margin, RadiusCurve};
use ofmpc_scenario::{Scenario, ScenarioFile};
use std::io::IsTerminal;
use std::path::PathBuf;

/// A progress line on stderr, when stderr is a terminal (scripts read stdout; a log stays clean).
pub(crate) fn progress(text: &str) {
    if std::io::stderr().is_terminal() {
        crate::output::console::note(text);
    }
}

/// The margins of `analyze stability` in words: per controller its α interval and payload,
/// and what the payload means for a controller without an integrator (`usual`: stable far
/// beyond, but with a steady offset that grows with the payload).
pub fn stability_words(margins: &[(ControllerKind, Margin)], figure: &std::path::Path) -> String {
    let mut s = String::from(
        "Stability near rest against a model that is wrong (α = H_model / H_plant: the inertia \
         the controller assumes over the real robot's):\n",
    );
    for (k, m) in margins {
        let [lo, hi] = m.alpha_interval;
        s.push_str(&format!(
            "  {:<8} stable for α in {lo:.3}–{hi:.3}; an unknown point payload at the flange \
             up to {:.2} kg keeps it stable along the program",
            k.name(),
            m.max_payload_kg
        ));
        if *k == ControllerKind::Usual {
            s.push_str(
                ", but it has no integrator: under any unknown payload it keeps a steady \
                 offset that grows with the payload (stable is not offset-free)",
            );
        } else {
            s.push_str("; offset-free inside it, diverges beyond");
        }
        s.push_str(".\n");
    }
    s.push_str(&format!(
        "Figure: {} (spectral radius against α, and against the payload in kg; ρ < 1 is stable). `--json` prints the numbers.",
        figure.display()
    ));
    s
}

/// The scenario file of a setup and tuning (resolved like `ofmpc run`'s).
pub fn scenario_file(setup: &SetupArgs, mpc: MpcSettings) -> anyhow::Result<ScenarioFile> {
    let mut f = ScenarioFile::default();
    f.robot.model = setup.robot.clone();
    f.robot.drives = setup.drives.clone();
    f.program.file = setup.program.clone();
    if let Some(o) = &setup.origin {
        let v = super::robot::parse_fixed(
            "--origin",
            o,
            3,
            "x,y,z of the work offset in mm",
            "450,0,400",
        )?;
        f.program.origin_mm = Some([v[0], v[1], v[2]]);
    }
    if let Some(r) = &setup.rpy {
        let v = super::robot::parse_fixed("--rpy", r, 3, "roll,pitch,yaw in degrees", "180,0,0")?;
        f.orientation.rpy_deg = Some([v[0], v[1], v[2]]);
    }
    setup.chain.apply(&mut f.robot)?;
    f.mpc = mpc;
    Ok(f)
}

/// Payloads of the stability figure's kg axis: 0 to 6 kg (the paper's range) in 0.5 kg steps.
const PAYLOAD_AXIS_KG: [f64; 13] = [
    0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0, 5.5, 6.0,
];

/// Largest ρ drawn: beyond it the curves are flattened (and their legend says so).
const RADIUS_CAP: f64 = 3.0;

/// The spectral radius against the payload (kg) of each controller: for a point payload `m`
/// at the flange unknown to the model, the inertia ratios along the program span
/// `[α_lo(m), α_hi(m)]` (the eigenvalues of `H_plant⁻¹ H_model`,
/// [`ofmpc::analysis::inertia_ratio_range`], as `max_payload_kg` uses them), and the radius is
/// the larger of ρ(α_lo) and ρ(α_hi) near rest at `q0` ([`spectral_radius`]): the worst pose.
fn payload_curves(
    model: &ofmpc::robot::Robot,
    mpc: &MpcSettings,
    baselines: &ofmpc::control::BaselineSettings,
    q0: &[f64],
    poses: &[&[f64]],
    kinds: &[ControllerKind],
) -> anyhow::Result<Vec<Vec<f64>>> {
    use ofmpc::analysis::{inertia_ratio_range, StabilityOptions, StabilityProblem};
    use rayon::prelude::*;
    let opts = StabilityOptions::default();
    let ranges = PAYLOAD_AXIS_KG
        .par_iter()
        .map(|&m| inertia_ratio_range(model, &ofmpc::robot::Payload::point_mass(m), poses))
        .collect::<Result<Vec<_>, _>>()?;
    kinds
        .iter()
        .map(|k| {
            ranges
                .par_iter()
                .map(|&(lo, hi)| {
                    let problem = StabilityProblem {
                        robot: model,
                        kind: k.base(),
                        settings: mpc,
                        baselines,
                        q0,
                        options: &opts,
                    };
                    let a = problem.spectral_radius(lo)?;
                    let b = problem.spectral_radius(hi)?;
                    Ok(a.max(b))
                })
                .collect::<anyhow::Result<Vec<f64>>>()
        })
        .collect()
}

/// A curve's legend entry: its controller, and that ρ above [`RADIUS_CAP`] is drawn at it.
fn capped(kind: ControllerKind, radius: &[f64]) -> String {
    if radius.iter().any(|&r| r > RADIUS_CAP) {
        format!("{} (ρ > {RADIUS_CAP} drawn at {RADIUS_CAP})", kind.name())
    } else {
        kind.name().to_string()
    }
}

/// The spectral radius against α and against the payload in kg for each controller, as a
/// figure of two panels.
fn radius_figure(curves: &[RadiusCurve], by_payload: &[Vec<f64>]) -> Figure {
    let mut f = radius_alpha_figure(curves);
    let mut p = Panel::new(
        "the same against the payload the model does not know (worst pose of the program)",
        "payload at the flange (kg)",
        "spectral radius ρ",
    );
    for (c, radius) in curves.iter().zip(by_payload) {
        p.series.push(Series::line(
            capped(c.kind, radius),
            PAYLOAD_AXIS_KG.to_vec(),
            radius.iter().map(|r| r.min(RADIUS_CAP)).collect(),
            crate::output::plot::controller_color(c.kind.name()),
        ));
    }
    p.series.push(Series::dashed(
        "ρ = 1 (stability limit)",
        vec![
            PAYLOAD_AXIS_KG[0],
            PAYLOAD_AXIS_KG[PAYLOAD_AXIS_KG.len() - 1],
        ],
        vec![1.0, 1.0],
        COLOR_REFERENCE,
    ));
    f.columns = 2;
    f.panels.push(p);
    f
}

/// The spectral radius against α for each controller, as a figure.
fn radius_alpha_figure(curves: &[RadiusCurve]) -> Figure {
    let mut p = Panel::new(
        "closed loop near rest: spectral radius against the inertia ratio",
        "α = H_model / H_plant",
        "spectral radius ρ",
    );
    for c in curves {
        p.series.push(Series::line(
            capped(c.kind, &c.radius),
            c.alpha.clone(),
            c.radius.iter().map(|r| r.min(RADIUS_CAP)).collect(),
            crate::output::plot::controller_color(c.kind.name()),
        ));
    }
    if let Some(alphas) = curves.first().map(|c| &c.alpha) {
        p.series.push(Series::dashed(
            "ρ = 1 (stability limit)",
            vec![alphas[0], alphas[alphas.len() - 1]],
            vec![1.0, 1.0],
            COLOR_REFERENCE,
        ));
    }
    let mut f = Figure::new("Stability margin against model mismatch", 1);
    f.panels.push(p);
    f
}

/// The files `analyze stability` writes into `--out`.
const STABILITY: [&str; 2] = ["stability.png", "stability.svg"];

/// Runs `ofmpc analyze stability`.
pub fn stability(a: &StabilityArgs) -> anyhow::Result<()> {
    let kinds = super::values::parse_controllers("--controllers", &a.controllers)?;
    if let Some(k) = kinds.iter().find(|k| k.is_adaptive()) {
        anyhow::bail!(
            "--controllers {k}: the adaptive variants identify the payload, so no fixed margin applies; analyse {} instead",
            k.base()
        );
    }
    let file = scenario_file(&a.setup, a.tuning.settings())?;
    let scenario = Scenario::resolve(&file)?;
    // The same staged, input-checked output as `run`: checked before the analysis, moved into
    // place only when both files are written.
    let planned: Vec<PathBuf> = STABILITY.iter().map(PathBuf::from).collect();
    let mut dir = super::experiment::open_output(
        &a.out,
        super::experiment::inputs(&scenario, None),
        &planned,
    )?;
    let mut out = serde_json::Map::new();
    let mut margins = Vec::new();
    for (i, &k) in kinds.iter().enumerate() {
        progress(&format!("the margin of {k} ({} of {})", i + 1, kinds.len()));
        let m = margin(&scenario, k)?;
        out.insert(k.name().to_string(), serde_json::to_value(m)?);
        margins.push((k, m));
    }
    progress("the spectral radius against α (the figure)");
    let exp = &scenario.experiment;
    let robot = model_robot(&scenario)?;
    let curves = radius_curves(&robot, &exp.mpc, &exp.baselines, exp.reference.q(0), &kinds)?;
    progress("the spectral radius against the payload (the figure's kg axis)");
    let poses = ofmpc_scenario::analysis::program_poses(&scenario);
    let by_payload = payload_curves(
        &robot,
        &exp.mpc,
        &exp.baselines,
        exp.reference.q(0),
        &poses,
        &kinds,
    )
    .context("the spectral radius against the payload")?;
    let fig = radius_figure(&curves, &by_payload);
    let r = render_both(&fig).context("rendering the stability figure")?;
    dir.write(STABILITY[0], &r.png)?;
    dir.write(STABILITY[1], r.svg.as_bytes())?;
    dir.commit()
        .with_context(|| format!("moving the results into {}", a.out.display()))?;
    let text = if a.format.json() {
        serde_json::to_string_pretty(&serde_json::Value::Object(out))?
    } else {
        stability_words(&margins, &a.out.join("stability.png"))
    };
    console::println(&text)?;
    Ok(())
}
