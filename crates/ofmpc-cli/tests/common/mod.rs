//! Fixtures shared by the report tests: sample figures and a PNG decoder.

#![allow(dead_code)]

use crate::output::plot::{
    Figure, Panel, Series, COLOR_FIRST, COLOR_REFERENCE, COLOR_SECOND, COLOR_USUAL,
};

/// A decoded 8-bit RGB image.
pub struct Rgb {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major RGB bytes.
    pub data: Vec<u8>,
}

impl Rgb {
    /// The pixel at (x, y).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }
}

/// Decodes a PNG (RGB or RGBA, 8 bit) into RGB.
pub fn decode_png(bytes: &[u8]) -> Rgb {
    let mut dec = png::Decoder::new(bytes);
    dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = dec.read_info().expect("valid PNG header");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("valid PNG data");
    buf.truncate(info.buffer_size());
    let data = match info.color_type {
        png::ColorType::Rgb => buf,
        png::ColorType::Rgba => buf.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect(),
        png::ColorType::Grayscale => buf.iter().flat_map(|&g| [g, g, g]).collect(),
        png::ColorType::GrayscaleAlpha => buf.chunks(2).flat_map(|p| [p[0], p[0], p[0]]).collect(),
        other => panic!("unexpected PNG colour type {other:?}"),
    };
    Rgb {
        width: info.width,
        height: info.height,
        data,
    }
}

/// Saves a test output for inspection when `OFMPC_TEST_ARTIFACTS` names a directory.
pub fn keep_artifact(name: &str, bytes: &[u8]) {
    if let Some(dir) = std::env::var_os("OFMPC_TEST_ARTIFACTS") {
        let dir = std::path::PathBuf::from(dir);
        std::fs::create_dir_all(&dir).expect("create OFMPC_TEST_ARTIFACTS");
        std::fs::write(dir.join(name), bytes).expect("write test artifact");
    }
}

/// The trimmed text content of every `<text>` element of an SVG document.
pub fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| Some(t.split_once('>')?.1.split('<').next()?.trim().to_string()))
        .collect()
}

/// Six panels of control errors of three controllers over 5 s at 1 ms, like Fig. 6 of the paper.
pub fn errors_figure() -> Figure {
    let n = 5001;
    let t: Vec<f64> = (0..n).map(|i| i as f64 * 1e-3).collect();
    let mut fig = Figure::new("Control errors (appropriate model)", 2);
    for j in 0..6 {
        let mut p = Panel::new(
            format!("Joint {}", j + 1),
            "t (s)",
            format!("e{} (rad)", j + 1),
        );
        let a = 1e-4 * (j as f64 + 1.0);
        let e = |k: f64| -> Vec<f64> {
            t.iter()
                .map(|&t| a * k * (-t).exp() * (7.0 * t).sin())
                .collect()
        };
        p.series
            .push(Series::line("usual", t.clone(), e(3.0), COLOR_USUAL));
        p.series
            .push(Series::line("first", t.clone(), e(2.0), COLOR_FIRST));
        p.series
            .push(Series::line("second", t.clone(), e(1.0), COLOR_SECOND));
        fig.panels.push(p);
    }
    fig
}

/// Panels with awkward data: NaN/inf gaps, an empty series, a constant signal, a log axis with
/// zeros and negatives, markers for a diverging run, a dashed reference and a single point.
pub fn edge_case_figure() -> Figure {
    let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.01).collect();
    let mut fig = Figure::new("Edge cases", 3);

    let mut gappy = Panel::new("NaN gap", "t (s)", "y (m)");
    let y: Vec<f64> = t
        .iter()
        .enumerate()
        .map(|(i, &t)| match i {
            90..=99 => f64::NAN,
            100 => f64::INFINITY,
            _ => t.sin(),
        })
        .collect();
    gappy
        .series
        .push(Series::line("gappy", t.clone(), y, COLOR_FIRST));
    gappy
        .series
        .push(Series::line("empty", vec![], vec![], COLOR_USUAL));
    fig.panels.push(gappy);

    let mut constant = Panel::new("Constant", "t (s)", "q (rad)");
    constant.series.push(Series::line(
        "q",
        t.clone(),
        vec![1.5; t.len()],
        COLOR_SECOND,
    ));
    fig.panels.push(constant);

    let mut log = Panel::new("Log axis", "t (s)", "|e| (rad)");
    log.log_y = true;
    let y: Vec<f64> = t
        .iter()
        .map(|&t| {
            if t < 0.1 {
                0.0
            } else {
                1e-3 * (-3.0 * t).exp()
            }
        })
        .collect();
    log.series
        .push(Series::line("decay", t.clone(), y, COLOR_SECOND));
    log.series.push(Series::line(
        "negative",
        t.clone(),
        vec![-1.0; t.len()],
        COLOR_USUAL,
    ));
    fig.panels.push(log);

    let mut diverged = Panel::new("Diverged run", "t (s)", "e (rad)");
    let y: Vec<f64> = t
        .iter()
        .map(|&t| {
            if t > 1.5 {
                f64::NAN
            } else {
                1e-3 * (4.0 * t).exp()
            }
        })
        .collect();
    diverged.series.push(Series::markers(
        "usual (diverged)",
        t.clone(),
        y,
        COLOR_USUAL,
    ));
    diverged.series.push(Series::dashed(
        "reference",
        t.clone(),
        vec![0.0; t.len()],
        COLOR_REFERENCE,
    ));
    fig.panels.push(diverged);

    let mut single = Panel::new("Single point", "x (m)", "z (m)");
    single
        .series
        .push(Series::line("point", vec![0.3], vec![0.5], COLOR_SECOND));
    fig.panels.push(single);
    fig
}
