//! `ofmpc analyze stability`: the inertia-ratio interval of each controller
//! near rest (from its real step, linearized by perturbation), the largest
//! point payload that keeps the ratio inside it along the program, and the
//! spectral radius against α as a figure.

use crate::output::console;
use crate::output::plot::{render_both, Figure, Panel, Series, COLOR_REFERENCE};
use anyhow::Context;
use clap::Args;
use ofmpc::control::{MpcSettings, Weight};
use ofmpc_scenario::analysis::{margin, model_robot, radius_curves, RadiusCurve};
use ofmpc_scenario::{Scenario, ScenarioFile};
use std::path::PathBuf;

/// Robot, program and tuning options shared by `analyze stability` and `tune`.
#[derive(Debug, Args, Clone)]
pub struct SetupArgs {
    /// `irb140` (built in, with its drives) or the path of a .urdf file.
    #[arg(long, default_value = "irb140")]
    pub robot: String,
    /// Drives file for a URDF robot.
    #[arg(long)]
    pub drives: Option<PathBuf>,
    /// G-code program (default: the paper's Table I, built in).
    #[arg(long)]
    pub program: Option<PathBuf>,
    /// G54 work offset X,Y,Z in mm, for programs that set none.
    #[arg(long, allow_hyphen_values = true)]
    pub origin: Option<String>,
}

/// Tuning options, as in `[mpc]` (default: the paper's).
#[derive(Debug, Args, Clone)]
pub struct TuningArgs {
    /// Sampling period Ts (s).
    #[arg(long)]
    pub ts: Option<f64>,
    /// Prediction horizon N (samples).
    #[arg(long)]
    pub horizon: Option<usize>,
    /// Output-error weight Q_yw (scalar, times I).
    #[arg(long)]
    pub q_yw: Option<f64>,
    /// Output-increment weight Q_Δy (scalar, times I).
    #[arg(long)]
    pub q_dy: Option<f64>,
    /// Input-increment weight Q_Δu (scalar, times I).
    #[arg(long)]
    pub q_du: Option<f64>,
    /// Input weight Q_u of the usual MPC (scalar, times I).
    #[arg(long)]
    pub q_u: Option<f64>,
    /// The payload the controllers' model assumes (kg, point mass at the flange).
    #[arg(long)]
    pub model_payload_kg: Option<f64>,
}

impl TuningArgs {
    /// The paper's tuning with these options applied.
    pub fn settings(&self) -> MpcSettings {
        let mut s = MpcSettings::default();
        if let Some(v) = self.ts {
            s.ts = v;
        }
        if let Some(v) = self.horizon {
            s.horizon = v;
        }
        for (w, v) in [
            (&mut s.q_yw, self.q_yw),
            (&mut s.q_dy, self.q_dy),
            (&mut s.q_du, self.q_du),
            (&mut s.q_u, self.q_u),
        ] {
            if let Some(v) = v {
                *w = Weight::Scalar(v);
            }
        }
        if let Some(v) = self.model_payload_kg {
            s.model_payload_kg = v;
        }
        s
    }
}

/// `ofmpc analyze stability`
#[derive(Debug, Args)]
pub struct StabilityArgs {
    /// Robot and program.
    #[command(flatten)]
    pub setup: SetupArgs,
    /// Controllers, comma-separated (usual, first, second).
    #[arg(long, default_value = "usual,first,second")]
    pub controllers: String,
    /// Tuning.
    #[command(flatten)]
    pub tuning: TuningArgs,
    /// Directory for the figure (`stability.png`, `stability.svg`).
    #[arg(long, default_value = "ofmpc-out")]
    pub out: PathBuf,
}

/// The scenario file of a setup and tuning (resolved like `ofmpc run`'s).
pub fn scenario_file(setup: &SetupArgs, mpc: MpcSettings) -> anyhow::Result<ScenarioFile> {
    let mut f = ScenarioFile::default();
    f.robot.model = setup.robot.clone();
    f.robot.drives = setup.drives.clone();
    f.program.file = setup.program.clone();
    if let Some(o) = &setup.origin {
        let v = super::parse_fixed(
            "--origin",
            o,
            3,
            "x,y,z of the work offset in mm",
            "450,0,400",
        )?;
        f.program.origin_mm = Some([v[0], v[1], v[2]]);
    }
    f.mpc = mpc;
    Ok(f)
}

/// The spectral radius against α for each controller, as a figure.
fn radius_figure(curves: &[RadiusCurve]) -> Figure {
    let mut p = Panel::new(
        "closed loop near rest: spectral radius against the inertia ratio",
        "α = H_model / H_plant",
        "spectral radius ρ",
    );
    for c in curves {
        p.series.push(Series::line(
            c.kind.name(),
            c.alpha.clone(),
            c.radius.iter().map(|r| r.min(3.0)).collect(),
            crate::figures::controller_color(c.kind.name()),
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
    let kinds = super::parse_controllers("--controllers", &a.controllers)?;
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
    for &k in &kinds {
        out.insert(
            k.name().to_string(),
            serde_json::to_value(margin(&scenario, k)?)?,
        );
    }
    let exp = &scenario.experiment;
    let robot = model_robot(&scenario)?;
    let fig = radius_figure(&radius_curves(
        &robot,
        &exp.mpc,
        exp.reference.q(0),
        &kinds,
    )?);
    let r = render_both(&fig).context("rendering the stability figure")?;
    dir.write(STABILITY[0], &r.png)?;
    dir.write(STABILITY[1], r.svg.as_bytes())?;
    dir.commit()
        .with_context(|| format!("moving the results into {}", a.out.display()))?;
    console::println(&serde_json::to_string_pretty(&serde_json::Value::Object(
        out,
    ))?)?;
    Ok(())
}
