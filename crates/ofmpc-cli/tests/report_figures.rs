//! Figure rendering: PNG and SVG output, embedded font, data edge cases, atomic files.

// The binary crate has no library target; the output layer is compiled into this test directly.
use ofmpc_cli::output;

mod common;

use common::{decode_png, edge_case_figure, errors_figure, keep_artifact, svg_texts, Rgb};
use output::plot::{self, color, PlotError, COLOR_FIRST, COLOR_SECOND, COLOR_USUAL};

/// Pixels inside the rectangle [x0, x1) × [y0, y1) that satisfy `pred`.
fn count(
    img: &Rgb,
    (x0, y0, x1, y1): (u32, u32, u32, u32),
    pred: impl Fn([u8; 3]) -> bool,
) -> usize {
    let mut n = 0;
    for y in y0..y1.min(img.height) {
        for x in x0..x1.min(img.width) {
            if pred(img.pixel(x, y)) {
                n += 1;
            }
        }
    }
    n
}

fn dark(p: [u8; 3]) -> bool {
    p.iter().map(|&c| u32::from(c)).sum::<u32>() < 3 * 100
}

#[test]
fn png_has_canvas_size_title_text_and_every_series_in_every_panel() {
    let fig = errors_figure();
    let png = plot::render_png(&fig).unwrap();
    keep_artifact("errors.png", &png);
    let img = decode_png(&png);
    let (w, h) = fig.canvas_size();
    assert_eq!((img.width, img.height), (w, h));
    // Only glyphs can be dark in the title band: the embedded font was used.
    let title_px = count(&img, (0, 0, w, 44), dark);
    assert!(title_px > 300, "title text missing: {title_px} dark pixels");
    // The same band of a figure without title is empty.
    let mut untitled = fig.clone();
    untitled.title.clear();
    let img2 = decode_png(&plot::render_png(&untitled).unwrap());
    let blank = count(&img2, (0, 0, w, 8), |p| p != [255, 255, 255]);
    assert_eq!(blank, 0);
    // Every panel cell shows all three controller colours.
    let (pw, ph) = fig.panel_size;
    for (i, _) in fig.panels.iter().enumerate() {
        let (r, c) = ((i / fig.columns) as u32, (i % fig.columns) as u32);
        let cell = (c * pw, 44 + r * ph, (c + 1) * pw, 44 + (r + 1) * ph);
        for k in [COLOR_USUAL, COLOR_FIRST, COLOR_SECOND] {
            let RgbColor(rr, gg, bb) = color(k);
            let n = count(&img, cell, |p| p == [rr, gg, bb]);
            assert!(n > 200, "panel {i}: colour {k} has only {n} pixels");
        }
        // Axis tick labels and descriptions: dark pixels left of the plot.
        let left = (cell.0, cell.1 + 30, cell.0 + 90, cell.3 - 50);
        assert!(count(&img, left, dark) > 100, "panel {i}: y labels missing");
    }
}

use plotters::style::RGBColor as RgbColor;

#[test]
fn svg_has_labels_and_reduced_polylines() {
    let fig = errors_figure();
    let svg = plot::render_svg(&fig).unwrap();
    let (w, h) = fig.canvas_size();
    assert!(svg.starts_with(&format!("<svg width=\"{w}\" height=\"{h}\"")));
    assert!(svg.trim_end().ends_with("</svg>"));
    let texts = svg_texts(&svg);
    for text in [
        "Control errors (appropriate model)",
        "Joint 6",
        "t (s)",
        "e3 (rad)",
        "usual",
        "first",
        "second",
    ] {
        assert!(texts.iter().any(|t| t == text), "missing {text:?}");
    }
    // 5001 samples per series, but at most 4 points per pixel column are drawn.
    let max_points = svg
        .split("<polyline")
        .skip(1)
        .map(|p| {
            p.split("points=\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap()
                .split_whitespace()
                .count()
        })
        .max()
        .unwrap();
    assert!(max_points > 100, "lines drawn: {max_points}");
    assert!(
        max_points <= 4 * fig.panel_size.0 as usize,
        "not reduced: {max_points}"
    );
    assert!(svg.len() < 1_500_000, "SVG too large: {} bytes", svg.len());
}

#[test]
fn edge_cases_render() {
    let fig = edge_case_figure();
    let r = plot::render_both(&fig).unwrap();
    keep_artifact("edge_cases.png", &r.png);
    keep_artifact("edge_cases.svg", r.svg.as_bytes());
    let img = decode_png(&r.png);
    assert_eq!((img.width, img.height), fig.canvas_size());
    // An empty series keeps its legend entry, marked.
    let texts = svg_texts(&r.svg);
    assert!(
        texts.iter().any(|t| t == "empty (no data)"),
        "no-data legend"
    );
    // NaN breaks the line: the "gappy" series (colour FIRST) is drawn as two polylines.
    let RgbColor(rr, gg, bb) = color(COLOR_FIRST);
    let first_hex = format!("stroke=\"#{rr:02X}{gg:02X}{bb:02X}\"");
    let n_first_lines = r
        .svg
        .split("<polyline")
        .skip(1)
        .filter(|p| p.split("/>").next().unwrap().contains(&first_hex))
        .count();
    // Two runs in the gappy panel, plus the legend sample.
    assert_eq!(n_first_lines, 3, "{first_hex}");
    // No coordinate is NaN or infinite in the SVG.
    // No coordinate is NaN or infinite: every polyline point is a pair of integers.
    for poly in r.svg.split("<polyline").skip(1) {
        let pts = poly
            .split("points=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        for pair in pts.split_whitespace() {
            let (x, y) = pair.split_once(',').unwrap();
            assert!(
                x.parse::<i32>().is_ok() && y.parse::<i32>().is_ok(),
                "{pair}"
            );
        }
    }
    // The constant panel (q = 1.5) got a real range with ticks on both sides.
    for v in ["1.4", "1.5", "1.6"] {
        assert!(
            texts.iter().any(|t| t == v),
            "constant panel tick {v} missing in {texts:?}"
        );
    }
}

#[test]
fn rendering_is_deterministic() {
    let fig = edge_case_figure();
    assert_eq!(
        plot::render_png(&fig).unwrap(),
        plot::render_png(&fig).unwrap()
    );
    assert_eq!(
        plot::render_svg(&fig).unwrap(),
        plot::render_svg(&fig).unwrap()
    );
}

#[test]
fn render_writes_both_files_or_neither() {
    let tmp = tempfile::tempdir().unwrap();
    let png = tmp.path().join("fig6.png");
    let svg = tmp.path().join("fig6.svg");
    let fig = edge_case_figure();
    let r = plot::render(&fig, &png, &svg).unwrap();
    assert_eq!(std::fs::read(&png).unwrap(), r.png);
    assert_eq!(std::fs::read_to_string(&svg).unwrap(), r.svg);
    // A bad figure fails before anything is written.
    let mut bad = fig.clone();
    bad.panels[0].series[0].y.pop();
    let png2 = tmp.path().join("bad.png");
    let svg2 = tmp.path().join("bad.svg");
    assert!(matches!(
        plot::render(&bad, &png2, &svg2),
        Err(PlotError::LengthMismatch { .. })
    ));
    assert!(!png2.exists() && !svg2.exists());
    // An unwritable target is an Io error naming the path; no temp files remain.
    let e = plot::render(&fig, &tmp.path().join("nope/a.png"), &svg2).unwrap_err();
    assert!(matches!(e, PlotError::Io { .. }));
    assert!(e.to_string().contains("nope"), "{e}");
    let mut names: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, vec!["fig6.png", "fig6.svg"]);
}

#[test]
fn extreme_values_render() {
    use output::plot::{Figure, Panel, Series};
    let cases: [(&str, Vec<f64>, Vec<f64>); 6] = [
        ("huge span", vec![0.0, 1.0], vec![-1e308, 1e308]),
        ("max span", vec![0.0, 1.0], vec![-f64::MAX, f64::MAX]),
        ("tiny values", vec![0.0, 1.0], vec![1e-308, 3e-308]),
        ("huge x", vec![-1e300, 1e300], vec![0.0, 1.0]),
        (
            "huge offset",
            vec![0.0, 1.0, 2.0],
            vec![1e12, 1e12 + 1e-3, 1e12 + 2e-3],
        ),
        ("all NaN", vec![f64::NAN, 1.0], vec![2.0, f64::NAN]),
    ];
    for (name, x, y) in cases {
        for log_y in [false, true] {
            let mut fig = Figure::new(name, 1);
            let mut p = Panel::new(name, "x", "y");
            p.log_y = log_y;
            p.series.push(Series::line("s", x.clone(), y.clone(), 1));
            p.series.push(Series::markers("m", x.clone(), y.clone(), 2));
            fig.panels.push(p);
            let r = plot::render_both(&fig).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(decode_png(&r.png).width, fig.canvas_size().0);
        }
    }
}
