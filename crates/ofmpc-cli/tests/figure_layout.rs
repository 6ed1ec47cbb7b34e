//! Every figure the `ofmpc` binary writes, checked for clipped text and legends over data
//! (issue #9, item 20; issue #25: every figure kind). A quick run with a payload sweep, three
//! controllers and the drives' effects writes the path, Cartesian reference, joint and
//! Cartesian errors per payload, payload sweep, torque ratios, measurement errors, and per run
//! joints/torques and Cartesian error; `trajectory` writes its three; a second run (an adaptive
//! variant and a baseline) the identification and the comparison; `analyze stability` and
//! `tune` their figures; then:
//!
//! * nothing is drawn within 3 px of a panel cell's edges, nor of the canvas edge (panel
//!   content is inset by margins of 10 px or more, so ink there is text cut at the edge), in the
//!   PNG;
//! * each figure title in the SVG is the whole title (one or two lines, never shortened);
//! * in every 2-D panel, every data point lies below the legend rows of that panel (the legend
//!   is laid out above the plot, never over it).

use ofmpc_cli::output;

mod common;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_ofmpc");

/// Height of the figure title band (`plot::TITLE_HEIGHT`).
const TITLE_BAND: u32 = 44;

fn all_files(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    for e in fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            all_files(&p, ext, out);
        } else if p.extension().is_some_and(|x| x == ext) {
            out.push(p);
        }
    }
}

/// One `<text>` of an SVG: position, anchor and content.
#[derive(Debug)]
struct SvgText {
    x: f64,
    y: f64,
    anchor: String,
    text: String,
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let start = tag.find(&format!(" {name}=\""))? + name.len() + 3;
    Some(tag[start..].split('"').next()?.to_string())
}

fn texts_of(svg: &str) -> Vec<SvgText> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let (tag, rest) = t.split_once('>')?;
            Some(SvgText {
                x: attr(tag, "x")?.parse().ok()?,
                y: attr(tag, "y")?.parse().ok()?,
                anchor: attr(tag, "text-anchor").unwrap_or_default(),
                text: rest.split('<').next()?.trim().to_string(),
            })
        })
        .collect()
}

/// Points of the data polylines (three points or more; legend samples have two) and data
/// markers (circles not on a legend row) of an SVG.
fn data_points(svg: &str, legend_rows: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut pts = Vec::new();
    for p in svg.split("<polyline").skip(1) {
        let tag = p.split("/>").next().unwrap();
        let stroke = attr(tag, "stroke").unwrap_or_default();
        // Series colours only (the grid and axes are grey or black with width 1).
        if attr(tag, "stroke-width").as_deref() != Some("2") || stroke.is_empty() {
            continue;
        }
        let points: Vec<(f64, f64)> = attr(tag, "points")
            .unwrap()
            .split_whitespace()
            .filter_map(|xy| {
                let (x, y) = xy.split_once(',')?;
                Some((x.parse().ok()?, y.parse().ok()?))
            })
            .collect();
        if points.len() >= 3 {
            pts.extend(points);
        }
    }
    for c in svg.split("<circle").skip(1) {
        let tag = c.split("/>").next().unwrap();
        let (Some(x), Some(y)) = (attr(tag, "cx"), attr(tag, "cy")) else {
            continue;
        };
        let (x, y): (f64, f64) = (x.parse().unwrap(), y.parse().unwrap());
        // A legend marker sits on a legend row, 16 px before its text.
        let is_sample = legend_rows
            .iter()
            .any(|&(lx, ly)| (ly - y).abs() < 1.0 && lx > x && lx - x < 30.0);
        if !is_sample {
            pts.push((x, y));
        }
    }
    pts
}

#[test]
fn no_figure_has_clipped_text_or_a_legend_over_data() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // Long titles on purpose: payloads with many digits, the longest controller name.
    fs::write(
        d.join("s.toml"),
        "title = \"Layout check\"\n[payload]\nmasses_kg = [0.0, 0.30000000000000004, 6.0]\n\
         [simulation]\nhold_s = 0.3\nsteady_window_s = 0.1\n\
         [plant]\ntorque_limits = true\n[faults]\nnan_at_s = [0.5]\n",
    )
    .unwrap();
    let run = |args: &[&str]| {
        let o = Command::new(BIN)
            .args(args)
            .current_dir(d)
            .stdin(Stdio::null())
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    run(&["run", "s.toml", "--out", "o"]);
    run(&[
        "trajectory",
        "paper",
        "--ts",
        "0.05",
        "--out",
        "o/traj/reference.csv",
    ]);
    // The figure kinds the first run does not draw: the identification of an adaptive
    // variant and the comparison with a baseline (a second run), the stability figure of
    // `analyze stability` and the trade-off of `tune`.
    fs::write(
        d.join("s2.toml"),
        "title = \"Layout check, adaptive and baseline\"\n\
         controllers = [\"second-adaptive\", \"pid\"]\n[payload]\nmasses_kg = [0.5]\n\
         [simulation]\nhold_s = 0.3\nsteady_window_s = 0.1\n",
    )
    .unwrap();
    run(&["run", "s2.toml", "--out", "o2"]);
    run(&[
        "analyze",
        "stability",
        "--controllers",
        "usual,first,second",
        "--json",
        "--out",
        "o3",
    ]);
    run(&[
        "tune",
        "--payload-range",
        "0,1",
        "--controllers",
        "second",
        "--json",
        "--out",
        "o4/t.toml",
    ]);

    let mut svgs = Vec::new();
    all_files(&d.join("o"), "svg", &mut svgs);
    // 2 + 2 per payload + sweep + 2 per run + 3 of trajectory, and the
    // drives section: torque ratios per payload, measurement error per run.
    assert_eq!(svgs.len(), 2 + 2 * 3 + 1 + 2 * 9 + 3 + 3 + 9, "{svgs:?}");
    let first = svgs.len();
    for o in ["o2", "o3", "o4"] {
        all_files(&d.join(o), "svg", &mut svgs);
    }
    // The second run: 2 + 2 + identification + comparison + 2 per run; stability; trade-off.
    assert_eq!(
        svgs.len() - first,
        2 + 2 + 1 + 1 + 2 * 2 + 1 + 1,
        "{svgs:?}"
    );
    svgs.sort();
    // Every kind of figure the binary writes is among them.
    for kind in [
        "path",
        "cartesian_reference",
        "joint_errors_m",
        "cartesian_errors_m",
        "payload_sweep",
        "joints_torques",
        "cartesian_error",
        "torque_ratios_m",
        "measurement_error",
        "reference_path",
        "reference_cartesian",
        "reference_speed",
        "identification_m",
        "controllers_compared",
        "stability",
        "t_tradeoff",
    ] {
        assert!(
            svgs.iter()
                .any(|p| p.file_name().unwrap().to_string_lossy().starts_with(kind)),
            "no {kind} figure among {svgs:?}"
        );
    }
    let mut checked_legends = 0;
    let mut checked_title = false;
    for svg_path in &svgs {
        let name = svg_path.strip_prefix(d).unwrap().display().to_string();
        let svg = fs::read_to_string(svg_path).unwrap();
        let png = common::decode_png(&fs::read(svg_path.with_extension("png")).unwrap());
        let (w, h) = (png.width, png.height);
        // Panel width: 560 px by default, 600 for the path figure.
        let cell = if w % 560 == 0 { 560 } else { 600 };
        assert_eq!(
            w % cell,
            0,
            "{name}: canvas {w} px is not a whole number of panels"
        );

        // 1. Nothing within 3 px of a cell edge (the title band spans the cells: there only
        //    the canvas edges count).
        let ink = |x: u32, y: u32| png.pixel(x, y) != [255, 255, 255];
        for edge in (0..=w).step_by(cell as usize) {
            let xs = edge.saturating_sub(3)..(edge + 3).min(w);
            let y0 = if edge == 0 || edge == w {
                0
            } else {
                TITLE_BAND
            };
            for x in xs {
                for y in y0..h {
                    assert!(
                        !ink(x, y),
                        "{name}: ink at ({x}, {y}), at a panel edge: clipped text?"
                    );
                }
            }
        }

        //    Likewise at the top and bottom of every panel row.
        let body = h - TITLE_BAND;
        let row_h = if body / 340 * 340 == body { 340 } else { 440 };
        assert_eq!(body % row_h, 0, "{name}: canvas height {h}");
        for edge in (TITLE_BAND..=h).step_by(row_h as usize) {
            for y in edge.saturating_sub(3)..(edge + 3).min(h) {
                for x in 0..w {
                    assert!(
                        !ink(x, y),
                        "{name}: ink at ({x}, {y}), at a panel row edge: clipped text?"
                    );
                }
            }
        }

        // 2. The figure title is there, whole: one or two lines centred at the top.
        let texts = texts_of(&svg);
        let title: Vec<&str> = texts
            .iter()
            .filter(|t| t.y < f64::from(TITLE_BAND) && t.anchor == "middle")
            .map(|t| t.text.as_str())
            .collect();
        let joined = title.join(" ");
        assert!(!joined.contains('…'), "{name}: title shortened: {joined}");
        let expected_start = if name.contains("traj") {
            "paper-table1"
        } else {
            ""
        };
        assert!(
            joined.starts_with(expected_start) && joined.len() > 10,
            "{name}: {joined}"
        );
        if name.ends_with("cartesian_errors_m0.3.svg") {
            checked_title = true;
            assert_eq!(
                joined,
                "Cartesian errors (reference − flange), payload 0.3 kg unknown to the model"
            );
        }

        // 3. Legends above data: per cell column, the legend entries of 2-D panels (the
        //    start-anchored texts that are not numbers: tick labels are numbers) are above
        //    every data point below the title of that row. The 3-D panel's legend stands
        //    beside its box; it is left out.
        let is_number = |t: &str| t.replace('−', "-").parse::<f64>().is_ok();
        let legend: Vec<(f64, f64)> = texts
            .iter()
            .filter(|t| t.anchor == "start" && !is_number(&t.text))
            .filter(|t| !(name.ends_with("path.svg") && t.x as u32 / cell == 1 && t.y < 484.0))
            .map(|t| (t.x, t.y))
            .collect();
        let points = data_points(&svg, &legend);
        for &(lx, ly) in &legend {
            let col = (lx as u32) / cell;
            let below_in_cell = points.iter().filter(|&&(px, py)| {
                (px as u32) / cell == col && py > ly - 40.0 && py < ly + 400.0
            });
            for &(px, py) in below_in_cell {
                assert!(
                    py > ly + 7.0,
                    "{name}: data point ({px}, {py}) at the height of the legend row y = {ly}"
                );
            }
            checked_legends += 1;
        }
    }
    assert!(
        checked_legends > 50,
        "only {checked_legends} legend entries found"
    );
    assert!(checked_title, "the 0.3 kg figure's title was not checked");
}
