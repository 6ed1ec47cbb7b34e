//! The one list of what `ofmpc run` and `ofmpc reproduce` write into their
//! output folder. [`RunFiles`] is computed from the scenario before anything
//! runs; it plans the destinations (checked before the runs), says which
//! figures to draw (the writer asks it), and recognizes what an earlier run
//! left that this one does not replace.
//!
//! It lives in the command's output layer, not in `ofmpc_scenario`: the files
//! (figures in PNG and SVG, the report) are the command's presentation of the
//! results; the scenario crate returns runs and metrics, which the Python
//! bindings return without writing a file.

use ofmpc::control::ControllerKind;
use ofmpc::robot::Payload;
use ofmpc::sim::{kind_name, mass_label, run_name};
use ofmpc_scenario::ScenarioFile;
use std::path::{Path, PathBuf};

/// Every controller a scenario can name (run folders are `<controller>_m<mass>/`).
const KINDS: [ControllerKind; 9] = ControllerKind::ALL;

/// The per-payload figures, by the prefix of their stem (`<prefix><mass label>`).
pub(crate) mod per_payload {
    /// Joint errors of every controller (the paper's Fig. 6 and 7).
    pub const JOINT_ERRORS: &str = "joint_errors_m";
    /// Cartesian errors of every controller.
    pub const CARTESIAN_ERRORS: &str = "cartesian_errors_m";
    /// Error and identified mass (adaptive controllers).
    pub const IDENTIFICATION: &str = "identification_m";
    /// Commanded torque relative to the limits (drive effects on).
    pub const TORQUE_RATIOS: &str = "torque_ratios_m";
    /// All of them.
    pub const ALL: [&str; 4] = [
        JOINT_ERRORS,
        CARTESIAN_ERRORS,
        IDENTIFICATION,
        TORQUE_RATIOS,
    ];
}

/// The per-run figures, by their stem inside the run folder.
pub(crate) mod per_run {
    /// Joints and torques (the paper's Fig. 5).
    pub const JOINTS_TORQUES: &str = "joints_torques";
    /// Cartesian error.
    pub const CARTESIAN_ERROR: &str = "cartesian_error";
    /// Measured minus true position (sensing or measurement faults on).
    pub const MEASUREMENT_ERROR: &str = "measurement_error";
}

/// The top-level figures.
pub(crate) const PATH: &str = "path";
/// The timed Cartesian reference (Fig. 4).
pub(crate) const CARTESIAN_REFERENCE: &str = "cartesian_reference";
/// Error against payload (three payloads or more).
pub(crate) const PAYLOAD_SWEEP: &str = "payload_sweep";
/// A run's time series, inside its folder.
pub(crate) const TIMESERIES: &str = "timeseries.csv";
/// The files every run writes at the top level.
pub(crate) const METRICS: &str = "metrics.json";
/// The effective scenario.
pub(crate) const SCENARIO: &str = "scenario.toml";
/// The report.
pub(crate) const REPORT: &str = "report.html";

/// What a run of a scenario writes: which optional figures, for which payloads and runs.
pub(crate) struct RunFiles {
    /// Mass labels of the payloads, in run order.
    masses: Vec<String>,
    /// Run names (`<controller>_m<mass>`), payloads outer, in run order.
    runs: Vec<String>,
    /// Identification figures (an adaptive controller runs).
    pub identification: bool,
    /// The payload sweep figure (three payloads or more).
    pub sweep: bool,
    /// The "Controllers compared" section and its figure (a baseline ran
    /// beside another controller, [`super::compare::wanted`]).
    pub compare: bool,
    /// The drives section: torque ratio figures (some drive, sensor or fault effect is on).
    pub drives: bool,
    /// Measurement error figures per run (the runs record the measurement apart).
    pub measurement: bool,
    /// Each run's `timeseries.csv` (`[output] timeseries` is not `"none"`).
    pub timeseries: bool,
}

impl RunFiles {
    /// The files of running `payloads` × `controllers` of the scenario `file`.
    pub fn new(file: &ScenarioFile, payloads: &[Payload], controllers: &[ControllerKind]) -> Self {
        let drives = !file.effects().is_empty();
        Self {
            masses: payloads.iter().map(|p| mass_label(p.mass)).collect(),
            runs: payloads
                .iter()
                .flat_map(|p| controllers.iter().map(move |k| run_name(*k, p)))
                .collect(),
            identification: controllers.iter().any(|k| k.is_adaptive()),
            sweep: payloads.len() >= 3,
            compare: super::compare::wanted(controllers),
            drives,
            measurement: drives && file.records_measurement(),
            timeseries: file.output.timeseries != ofmpc_scenario::TimeseriesOutput::None,
        }
    }

    /// Every figure's stem (relative to the output folder, without `.png`/`.svg`).
    pub fn figures(&self) -> Vec<String> {
        let mut v: Vec<String> = vec![PATH.into(), CARTESIAN_REFERENCE.into()];
        let per_mass = |v: &mut Vec<String>, prefix: &str| {
            v.extend(self.masses.iter().map(|m| format!("{prefix}{m}")));
        };
        per_mass(&mut v, per_payload::JOINT_ERRORS);
        per_mass(&mut v, per_payload::CARTESIAN_ERRORS);
        if self.identification {
            per_mass(&mut v, per_payload::IDENTIFICATION);
        }
        if self.drives {
            per_mass(&mut v, per_payload::TORQUE_RATIOS);
        }
        if self.sweep {
            v.push(PAYLOAD_SWEEP.into());
        }
        if self.compare {
            v.push(super::compare::COMPARE_FIGURE.into());
        }
        for r in &self.runs {
            v.push(format!("{r}/{}", per_run::JOINTS_TORQUES));
            v.push(format!("{r}/{}", per_run::CARTESIAN_ERROR));
            if self.measurement {
                v.push(format!("{r}/{}", per_run::MEASUREMENT_ERROR));
            }
        }
        v
    }

    /// Every file, relative to the output folder: the figures in PNG and SVG, each run's
    /// time series, `metrics.json`, `scenario.toml` and `report.html`.
    pub fn files(&self) -> Vec<PathBuf> {
        let mut v: Vec<String> = self
            .figures()
            .into_iter()
            .flat_map(|f| [format!("{f}.png"), format!("{f}.svg")])
            .collect();
        if self.timeseries {
            v.extend(self.runs.iter().map(|r| format!("{r}/{TIMESERIES}")));
        }
        v.extend([METRICS, SCENARIO, REPORT].map(String::from));
        v.into_iter().map(PathBuf::from).collect()
    }

    /// Entries of `out` written by an earlier run that this run does not replace: run folders
    /// (`<controller>_m<mass>/` with a time series, any controller) and per-payload or sweep
    /// figures.
    pub fn earlier_leftovers(&self, out: &Path) -> Vec<String> {
        let planned = self.files();
        let top: std::collections::HashSet<String> = planned
            .iter()
            .filter_map(|p| p.components().next())
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        let Ok(entries) = std::fs::read_dir(out) else {
            return Vec::new();
        };
        let mut found: Vec<String> = entries
            .flatten()
            .filter_map(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                if top.contains(&name) {
                    return None;
                }
                let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
                let run_dir = is_dir
                    && KINDS
                        .iter()
                        .any(|k| name.starts_with(&format!("{}_m", kind_name(*k))))
                    && e.path().join(TIMESERIES).is_file();
                let figure = !is_dir
                    && (name.ends_with(".png") || name.ends_with(".svg"))
                    && (per_payload::ALL.iter().any(|p| name.starts_with(p))
                        || name.starts_with(&format!("{PAYLOAD_SWEEP}.")));
                if run_dir {
                    Some(format!("{name}/"))
                } else if figure {
                    Some(name)
                } else {
                    None
                }
            })
            .collect();
        found.sort();
        found
    }
}

/// The controllers that ran, in the report's words: "the usual MPC (Eq. 43) and the second
/// incremental algorithm (Eq. 34/39)".
pub(crate) fn controllers_in_words(controllers: &[ControllerKind]) -> String {
    let words: Vec<&str> = controllers
        .iter()
        .map(|k| match k {
            ControllerKind::Usual => "the usual MPC (Eq. 43)",
            ControllerKind::First => "the first incremental algorithm (Eq. 32/37)",
            ControllerKind::Second => "the second incremental algorithm (Eq. 34/39)",
            ControllerKind::FirstAdaptive => {
                "the first algorithm with online payload identification (first-adaptive)"
            }
            _ => "the second algorithm with online payload identification (second-adaptive)",
        })
        .collect();
    match words.split_last() {
        None => String::new(),
        Some((last, [])) => last.to_string(),
        Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
    }
}

/// "the controller", "the two controllers", … "the five controllers".
pub(crate) fn the_controllers(n: usize) -> String {
    const NUMBERS: [&str; 6] = ["", "", "two", "three", "four", "five"];
    match n {
        1 => "the controller".into(),
        2..=5 => format!("the {} controllers", NUMBERS[n]),
        _ => format!("the {n} controllers"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One list for every kind of run: adaptive folders, the drive figures and the
    /// measurement figures are planned, and an earlier run's are recognized.
    #[test]
    fn the_list_holds_every_controller_and_figure_kind() {
        let mut file: ScenarioFile =
            toml::from_str("[faults]\nnan_at_s = [1.0]\n[plant]\ntorque_limits = true\n").unwrap();
        file.controllers = vec![ControllerKind::Usual, ControllerKind::SecondAdaptive];
        let payloads = [Payload::point_mass(0.25)];
        let files = RunFiles::new(&file, &payloads, &file.controllers);
        let names: Vec<String> = files
            .files()
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        for want in [
            "path.png",
            "identification_m0.25.svg",
            "torque_ratios_m0.25.png",
            "second-adaptive_m0.25/measurement_error.png",
            "second-adaptive_m0.25/timeseries.csv",
            "usual_m0.25/joints_torques.svg",
            "metrics.json",
            "report.html",
        ] {
            assert!(names.iter().any(|n| n == want), "{want} not in {names:?}");
        }
        assert!(!names.iter().any(|n| n.starts_with("payload_sweep")));

        let out = tempfile::tempdir().unwrap();
        for run in ["first-adaptive_m1", "usual_m0.25"] {
            std::fs::create_dir(out.path().join(run)).unwrap();
            std::fs::write(out.path().join(run).join(TIMESERIES), "").unwrap();
        }
        std::fs::write(out.path().join("torque_ratios_m1.png"), "").unwrap();
        assert_eq!(
            files.earlier_leftovers(out.path()),
            ["first-adaptive_m1/", "torque_ratios_m1.png"]
        );
        assert_eq!(
            controllers_in_words(&file.controllers),
            "the usual MPC (Eq. 43) and the second algorithm with online payload identification (second-adaptive)"
        );
        assert_eq!(the_controllers(2), "the two controllers");
    }
}
