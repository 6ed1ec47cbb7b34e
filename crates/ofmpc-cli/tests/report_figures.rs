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

/// Bounding box (x0, y0, x1, y1), inclusive, of the pixels of exactly colour `c`.
fn bbox(img: &Rgb, c: RgbColor) -> Option<(u32, u32, u32, u32)> {
    let RgbColor(r, g, b) = c;
    let mut out: Option<(u32, u32, u32, u32)> = None;
    for y in 0..img.height {
        for x in 0..img.width {
            if img.pixel(x, y) == [r, g, b] {
                out = Some(match out {
                    None => (x, y, x, y),
                    Some((x0, y0, x1, y1)) => (x0.min(x), y0.min(y), x1.max(x), y1.max(y)),
                });
            }
        }
    }
    out
}

/// An ellipse (cx + a cos θ, cy + b sin θ), 721 points, unlabelled (no legend sample).
fn ellipse(cx: f64, cy: f64, a: f64, b: f64) -> (Vec<f64>, Vec<f64>) {
    (0..=720)
        .map(|i| {
            let t = i as f64 * std::f64::consts::PI / 360.0;
            (cx + a * t.cos(), cy + b * t.sin())
        })
        .unzip()
}

/// Pixel width and height of the ellipse drawn in a one-panel figure.
fn drawn_ellipse(a: f64, b: f64, equal_aspect: bool, size: (u32, u32)) -> (f64, f64) {
    use output::plot::{Figure, Panel, Series};
    let (x, y) = ellipse(3.0, -1.0, a, b);
    let mut fig = Figure::new("", 1);
    fig.panel_size = size;
    let mut p = Panel::new("ellipse", "x (m)", "y (m)");
    p.equal_aspect = equal_aspect;
    p.series.push(Series::line("", x, y, COLOR_FIRST));
    fig.panels.push(p);
    let img = decode_png(&plot::render_png(&fig).unwrap());
    let (x0, y0, x1, y1) = bbox(&img, color(COLOR_FIRST)).expect("ellipse drawn");
    (f64::from(x1 - x0), f64::from(y1 - y0))
}

#[test]
fn equal_aspect_draws_a_circle_round() {
    // A circle is square in pixels (the 2 px line adds the same to both sides) in a wide and in
    // a tall panel; an ellipse keeps its 4:1 ratio.
    for size in [(560, 340), (300, 520), (900, 300)] {
        let (w, h) = drawn_ellipse(1.0, 1.0, true, size);
        assert!((w - h).abs() <= 3.0, "{size:?}: circle drawn {w} x {h} px");
        let (w, h) = drawn_ellipse(2.0, 0.5, true, size);
        assert!(
            ((w - 2.0) - 4.0 * (h - 2.0)).abs() <= 6.0,
            "{size:?}: ellipse 4:1 drawn {w} x {h} px"
        );
    }
    // Negative control: without equal_aspect the default panel stretches the circle.
    let (w, h) = drawn_ellipse(1.0, 1.0, false, (560, 340));
    assert!(w - h > 50.0, "free axes: circle drawn {w} x {h} px");
}

#[test]
fn equal_aspect_ranges_give_equal_units_per_pixel() {
    for (x, y, px) in [
        ((0.0, 10.0), (0.0, 1.0), (400.0, 300.0)),
        ((-1.0, 1.0), (-50.0, 50.0), (400.0, 300.0)),
        ((1e3, 1e3 + 1.0), (-2e-3, 5e-3), (123.0, 456.0)),
    ] {
        let ((x0, x1), (y0, y1)) = plot::equal_aspect_ranges(x, y, px);
        let (ux, uy) = ((x1 - x0) / px.0, (y1 - y0) / px.1);
        assert!((ux - uy).abs() <= 1e-12 * ux, "{ux} vs {uy}");
        // The data stays inside, centred, and one axis keeps its range.
        assert!(x0 <= x.0 && x1 >= x.1 && y0 <= y.0 && y1 >= y.1);
        assert!(((x0 + x1) - (x.0 + x.1)).abs() <= 1e-12 * (x1 - x0).max(x0.abs()));
        assert!(((y0 + y1) - (y.0 + y.1)).abs() <= 1e-12 * (y1 - y0).max(y0.abs()));
        assert!((x1 - x0 - (x.1 - x.0)).abs() < 1e-9 || (y1 - y0 - (y.1 - y.0)).abs() < 1e-9);
    }
}

/// One 3-D panel with the given series, seen from `view`.
fn figure_3d(series: Vec<output::plot::Series3d>, view: output::plot::View3d) -> plot::Figure {
    use output::plot::{Figure, Panel};
    let mut fig = Figure::new("3-D figure", 1);
    let mut p = Panel::new_3d("Helix", "x (mm)", "y (mm)", "z (mm)");
    if let Some(a) = p.three_d.as_mut() {
        a.view = view;
        a.series = series;
    }
    fig.panels.push(p);
    fig
}

fn helix() -> output::plot::Series3d {
    let n = 2000;
    let (mut x, mut y, mut z) = (vec![], vec![], vec![]);
    for i in 0..n {
        let t = i as f64 / (n - 1) as f64 * 6.0 * std::f64::consts::PI;
        x.push(500.0 + 100.0 * t.cos());
        y.push(-50.0 + 100.0 * t.sin());
        z.push(300.0 + 8.0 * t);
    }
    output::plot::Series3d::line("helix", x, y, z, COLOR_FIRST)
}

#[test]
fn panel_3d_renders_with_labels_in_png_and_svg() {
    use output::plot::{Series3d, View3d};
    let start = Series3d::markers("start", vec![600.0], vec![-50.0], vec![300.0], COLOR_USUAL);
    let fig = figure_3d(vec![helix(), start], View3d::default());
    let r = plot::render_both(&fig).unwrap();
    keep_artifact("panel_3d.png", &r.png);
    keep_artifact("panel_3d.svg", r.svg.as_bytes());
    let texts = svg_texts(&r.svg);
    for text in [
        "3-D figure",
        "Helix",
        "x (mm)",
        "y (mm)",
        "z (mm)",
        "helix",
        "start",
    ] {
        assert!(
            texts.iter().any(|t| t == text),
            "missing {text:?} in {texts:?}"
        );
    }
    // Tick labels of the three axes (data 400..600, -150..50, 300..450 mm).
    for tick in ["400", "500", "600", "0", "-100", "300", "400"] {
        assert!(
            texts.iter().any(|t| t == tick),
            "tick {tick} missing in {texts:?}"
        );
    }
    let img = decode_png(&r.png);
    assert_eq!((img.width, img.height), fig.canvas_size());
    let (w, h) = fig.canvas_size();
    let RgbColor(rr, gg, bb) = color(COLOR_FIRST);
    let n = count(&img, (0, 44, w, h), |p| p == [rr, gg, bb]);
    assert!(n > 1000, "helix has only {n} pixels");
    let RgbColor(rr, gg, bb) = color(COLOR_USUAL);
    let n = count(&img, (0, 44, w, h), |p| p == [rr, gg, bb]);
    assert!(n > 20, "start marker has only {n} pixels");
    // Axis descriptions are dark text left of and below the box.
    assert!(count(&img, (0, 44, w / 4, h), dark) > 100);
    assert!(count(&img, (0, h * 3 / 4, w, h), dark) > 100);
}

#[test]
fn panel_3d_has_equal_scales_on_all_axes() {
    use output::plot::{Series3d, View3d};
    // A circle of radius 20 mm in the xy plane seen from above, and one of radius 100 mm in the
    // xz plane seen from the front, in the same box: both are round in pixels, and the second
    // one is 5 times larger (the data spans differ, the scales do not).
    let small = {
        let (x, y) = ellipse(10.0, 0.0, 20.0, 20.0);
        Series3d::line("", x, y, vec![0.0; 721], COLOR_FIRST)
    };
    let big = {
        let (x, z) = ellipse(0.0, 0.0, 100.0, 100.0);
        Series3d::line("", x, vec![0.0; 721], z, COLOR_SECOND)
    };
    let top = View3d {
        yaw_deg: -90.0,
        pitch_deg: 90.0,
    };
    let front = View3d {
        yaw_deg: -90.0,
        pitch_deg: 0.0,
    };
    let size = |fig: &plot::Figure, c: usize| {
        let img = decode_png(&plot::render_png(fig).unwrap());
        let (x0, y0, x1, y1) = bbox(&img, color(c)).expect("drawn");
        (f64::from(x1 - x0), f64::from(y1 - y0))
    };
    let (w, h) = size(&figure_3d(vec![big.clone()], top), COLOR_SECOND);
    assert!(
        w > 100.0 && h <= 3.0,
        "xz circle from above is a line: {w} x {h}"
    );
    let (w, h) = size(&figure_3d(vec![big.clone()], front), COLOR_SECOND);
    assert!(
        w > 100.0 && (w - h).abs() <= 3.0,
        "xz circle from the front: {w} x {h}"
    );
    let (ws, hs) = size(
        &figure_3d(vec![small.clone(), big.clone()], top),
        COLOR_FIRST,
    );
    let (wb, _) = size(&figure_3d(vec![small, big.clone()], front), COLOR_SECOND);
    assert!((ws - hs).abs() <= 3.0, "xy circle from above: {ws} x {hs}");
    // Diameters without the 2 px line width.
    let ratio = (wb - 2.0) / (ws - 2.0);
    assert!(
        (ratio - 5.0).abs() < 0.25,
        "size ratio {ratio}: {wb} vs {ws}"
    );
}

#[test]
fn panel_3d_odd_data_renders_and_bad_input_is_an_error() {
    use output::plot::{Series3d, View3d};
    let nan = f64::NAN;
    let cases: Vec<(&str, Vec<Series3d>)> = vec![
        ("no series", vec![]),
        (
            "empty",
            vec![Series3d::line("e", vec![], vec![], vec![], 1)],
        ),
        (
            "all NaN",
            vec![Series3d::line(
                "n",
                vec![nan, 1.0],
                vec![2.0, nan],
                vec![nan; 2],
                1,
            )],
        ),
        (
            "single point",
            vec![Series3d::line("p", vec![0.3], vec![0.5], vec![0.1], 2)],
        ),
        (
            "zero span",
            vec![Series3d::line(
                "c",
                vec![1.0; 5],
                vec![2.0; 5],
                vec![3.0; 5],
                2,
            )],
        ),
        (
            "flat",
            vec![Series3d::dashed(
                "f",
                vec![0.0, 1.0, 2.0],
                vec![0.0; 3],
                vec![5.0; 3],
                3,
            )],
        ),
        (
            "huge and inf",
            vec![Series3d::markers(
                "h",
                vec![-1e300, 0.0, f64::INFINITY, 1e12],
                vec![0.0, 1e-300, 1.0, 1e12 + 1e-3],
                vec![f64::MAX, 0.0, 1.0, 1e12],
                1,
            )],
        ),
    ];
    for (name, series) in cases {
        for view in [
            View3d::default(),
            View3d {
                yaw_deg: 0.0,
                pitch_deg: 90.0,
            },
            View3d {
                yaw_deg: 720.0,
                pitch_deg: -45.0,
            },
        ] {
            let fig = figure_3d(series.clone(), view);
            let r = plot::render_both(&fig).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(decode_png(&r.png).width, fig.canvas_size().0);
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
        }
    }
    // Mismatched lengths, a mixed 2-D/3-D panel and a NaN view are errors naming the panel.
    let bad = figure_3d(
        vec![Series3d::line(
            "s",
            vec![0.0; 3],
            vec![0.0; 3],
            vec![0.0; 2],
            1,
        )],
        View3d::default(),
    );
    let e = plot::render_png(&bad).unwrap_err();
    assert!(
        matches!(e, PlotError::LengthMismatch3d { z_len: 2, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("Helix"), "{e}");
    let mut mixed = figure_3d(vec![helix()], View3d::default());
    mixed.panels[0]
        .series
        .push(output::plot::Series::line("2d", vec![0.0], vec![0.0], 1));
    assert!(matches!(
        plot::render_svg(&mixed),
        Err(PlotError::Mixed3d { .. })
    ));
    let nan_view = figure_3d(
        vec![helix()],
        View3d {
            yaw_deg: nan,
            pitch_deg: 0.0,
        },
    );
    assert!(matches!(
        plot::render_png(&nan_view),
        Err(PlotError::BadView { .. })
    ));
}
