//! Interactive figures for the HTML report: a [`Figure`] as compact data that the page draws
//! with the vendored uPlot (`assets/uplot/`, MIT): zoom (drag a box; double-click resets), pan
//! (shift + drag), zoom on the wheel, hover values in the legend. The PNG and SVG files of the
//! same figure are written beside the report for papers.
//!
//! Size: each group of series that share their abscissae is reduced to the points that keep its
//! shape at screen resolution — per bucket of the x range the first, last, lowest and highest
//! sample of every series (the M4 reduction of Jugel et al., "M4: A Visualization-Oriented Time
//! Series Data Aggregation", VLDB 2014) — and every value is quantized to 16 bits of its
//! series' range (log10 of the value on a log axis) and base64-encoded: 2.7 characters a value.
//! A 13 000-sample run draws from ≤ 4 × [`BUCKETS`] points per panel.

use super::plot::{color, Figure, SeriesStyle};
use super::report::base64;
use serde_json::{json, Value};

/// Buckets of the x range per panel (≈ 2–3 screen pixels each at the report's width).
pub const BUCKETS: usize = 220;

/// The quantization code of a missing value (NaN, infinite, or ≤ 0 on a log axis).
const GAP: u16 = u16::MAX;

/// Values quantized to 16 bits over `[lo, hi]` (`GAP` for a missing value), as
/// `{"lo","hi","d": base64 of little-endian u16}`. Decoding: `lo + (hi − lo) · k / 65534`.
pub fn quantize(values: &[f64]) -> Value {
    let finite = values.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 0.0) };
    let span = hi - lo;
    let mut bytes = Vec::with_capacity(values.len() * 2);
    for &v in values {
        let k = if !v.is_finite() {
            GAP
        } else if span > 0.0 {
            (((v - lo) / span) * f64::from(GAP - 1)).round() as u16
        } else {
            0
        };
        bytes.extend_from_slice(&k.to_le_bytes());
    }
    json!({"lo": lo, "hi": hi, "d": base64(&bytes)})
}

/// Indices of the M4 reduction of the series `ys` over the common abscissae `x`: per bucket
/// of the x range, the first, last, lowest and highest finite sample of each series; all of them
/// when there are few.
pub fn m4(x: &[f64], ys: &[&[f64]], buckets: usize) -> Vec<usize> {
    let n = x.len();
    if n <= 4 * buckets {
        return (0..n).collect();
    }
    let (x0, x1) = x
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let width = (x1 - x0).max(f64::MIN_POSITIVE);
    let bucket = |i: usize| -> usize {
        if x[i].is_finite() {
            (((x[i] - x0) / width) * buckets as f64).clamp(0.0, (buckets - 1) as f64) as usize
        } else {
            0
        }
    };
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[n - 1] = true;
    let bucket_of: Vec<usize> = (0..n).map(bucket).collect();
    for y in ys {
        keep_extremes(y, &bucket_of, &mut keep);
    }
    (0..n).filter(|&i| keep[i]).collect()
}

/// Marks in `keep` the samples of series `y` that M4 keeps: per bucket (`bucket_of[i]` is
/// sample `i`'s) its first, last, lowest and highest finite sample, and the edges of every
/// gap (non-finite samples).
fn keep_extremes(y: &[f64], bucket_of: &[usize], keep: &mut [bool]) {
    let n = bucket_of.len();
    // Per bucket: first, last, argmin, argmax.
    let mut b_cur = usize::MAX;
    let (mut lo_i, mut hi_i, mut last) = (0, 0, 0);
    for i in 0..n {
        let b = bucket_of[i];
        if b != b_cur {
            if b_cur != usize::MAX {
                keep[lo_i] = true;
                keep[hi_i] = true;
                keep[last] = true;
            }
            b_cur = b;
            keep[i] = true;
            lo_i = i;
            hi_i = i;
        }
        // A gap stays a gap: its first and last missing sample and the finite samples
        // beside them are kept.
        if !y[i].is_finite() {
            let prev_ok = i > 0 && y[i - 1].is_finite();
            let next_ok = i + 1 < n && y[i + 1].is_finite();
            if prev_ok || next_ok {
                keep[i] = true;
                keep[i.saturating_sub(1)] = true;
                keep[(i + 1).min(n - 1)] = true;
            }
            continue;
        }
        if !y[lo_i].is_finite() || y[i] < y[lo_i] {
            lo_i = i;
        }
        if !y[hi_i].is_finite() || y[i] > y[hi_i] {
            hi_i = i;
        }
        last = i;
    }
    keep[lo_i] = true;
    keep[hi_i] = true;
    keep[last] = true;
}

/// `#rrggbb` of a palette index.
pub fn hex(i: usize) -> String {
    let c = color(i);
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

/// The figure as the page's chart data, or `None` when a panel is 3-D (drawn as a picture).
pub fn chart_json(fig: &Figure) -> Option<String> {
    if fig.panels.iter().any(|p| p.three_d.is_some()) {
        return None;
    }
    let mut panels = Vec::new();
    for p in &fig.panels {
        // Groups of series with the same abscissae.
        let mut groups: Vec<(&[f64], Vec<usize>)> = Vec::new();
        for (si, s) in p.series.iter().enumerate() {
            match groups.iter_mut().find(|(x, _)| *x == s.x.as_slice()) {
                Some((_, v)) => v.push(si),
                None => groups.push((&s.x, vec![si])),
            }
        }
        let mut xs = Vec::new();
        let mut series = vec![Value::Null; p.series.len()];
        for (gi, (x, members)) in groups.iter().enumerate() {
            let ys: Vec<Vec<f64>> = members
                .iter()
                .map(|&si| {
                    let y = &p.series[si].y;
                    if p.log_y {
                        y.iter()
                            .map(|&v| if v > 0.0 { v.log10() } else { f64::NAN })
                            .collect()
                    } else {
                        y.clone()
                    }
                })
                .collect();
            let refs: Vec<&[f64]> = ys.iter().map(|v| v.as_slice()).collect();
            let keep = m4(x, &refs, BUCKETS);
            xs.push(quantize(&keep.iter().map(|&i| x[i]).collect::<Vec<_>>()));
            for (k, &si) in members.iter().enumerate() {
                let s = &p.series[si];
                let kind = match s.style {
                    SeriesStyle::Line => "l",
                    SeriesStyle::Dashed => "d",
                    SeriesStyle::Markers => "m",
                };
                series[si] = json!({
                    "l": s.label,
                    "c": hex(s.color),
                    "k": kind,
                    "g": gi,
                    "y": quantize(&keep.iter().map(|&i| ys[k][i]).collect::<Vec<_>>()),
                });
            }
        }
        panels.push(json!({
            "t": p.title, "xl": p.x_label, "yl": p.y_label,
            "log": p.log_y, "x": xs, "s": series,
        }));
    }
    let v = json!({"t": fig.title, "c": fig.grid().1, "p": panels});
    // `<` only occurs inside strings: escaped, the data cannot close its <script> element.
    Some(v.to_string().replace('<', "\\u003c"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::plot::{Panel, Series};

    fn decode(v: &Value) -> Vec<Option<f64>> {
        let (lo, hi) = (v["lo"].as_f64().unwrap(), v["hi"].as_f64().unwrap());
        let d = v["d"].as_str().unwrap();
        let val = |c: u8| {
            "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/"
                .find(char::from(c))
                .unwrap() as u32
        };
        let mut bytes = Vec::new();
        for q in d.as_bytes().chunks(4) {
            let k = q.iter().take_while(|&&c| c != b'=').count();
            let n = q[..k]
                .iter()
                .enumerate()
                .fold(0u32, |n, (j, &c)| n | (val(c) << (18 - 6 * j)));
            bytes.extend_from_slice(&[(n >> 16) as u8, (n >> 8) as u8, n as u8][..k - 1]);
        }
        bytes
            .chunks(2)
            .map(|b| {
                let k = u16::from_le_bytes([b[0], b[1]]);
                (k != GAP).then(|| lo + (hi - lo) * f64::from(k) / f64::from(GAP - 1))
            })
            .collect()
    }

    #[test]
    fn quantized_values_decode_within_half_a_step() {
        let v = [0.0, -1.5, 3.25, f64::NAN, 1e-3, 3.25];
        let d = decode(&quantize(&v));
        let step = 4.75 / 65534.0;
        for (a, b) in v.iter().zip(&d) {
            match b {
                Some(b) => assert!((a - b).abs() <= step / 2.0 + 1e-15, "{a} {b}"),
                None => assert!(a.is_nan()),
            }
        }
        // A constant series decodes exactly.
        assert_eq!(decode(&quantize(&[2.0, 2.0])), [Some(2.0), Some(2.0)]);
    }

    #[test]
    fn m4_keeps_extremes_of_every_bucket_and_gaps() {
        let n = 13_000;
        let x: Vec<f64> = (0..n).map(|i| i as f64 * 1e-3).collect();
        let mut y: Vec<f64> = x.iter().map(|t| (t * 7.0).sin()).collect();
        y[5000] = 40.0; // a spike
        y[9000] = f64::NAN; // a gap
        let keep = m4(&x, &[&y], 200);
        assert!(keep.len() <= 4 * 200 + 6, "{}", keep.len());
        assert!(keep.contains(&5000) && keep.contains(&9000));
        assert!(keep.contains(&0) && keep.contains(&(n - 1)));
        // Brute force: every bucket's max is kept.
        for b in 0..200 {
            let idx: Vec<usize> = (0..n)
                .filter(|&i| ((x[i] / x[n - 1]) * 200.0).min(199.0) as usize == b)
                .filter(|&i| y[i].is_finite())
                .collect();
            let mx = idx
                .iter()
                .copied()
                .max_by(|&a, &c| y[a].total_cmp(&y[c]))
                .unwrap();
            assert!(keep.iter().any(|&k| y[k] == y[mx]), "bucket {b}");
        }
    }

    #[test]
    fn chart_data_has_every_series_and_no_closing_tag() {
        let mut f = Figure::new("a </script> title", 2);
        let mut p = Panel::new("p", "t (s)", "|e| (rad)");
        p.log_y = true;
        let t: Vec<f64> = (0..5000).map(|i| f64::from(i) * 1e-3).collect();
        p.series.push(Series::line(
            "a",
            t.clone(),
            t.iter().map(|v| v + 1e-9).collect(),
            1,
        ));
        p.series
            .push(Series::dashed("b", t.clone(), vec![0.0; 5000], 2));
        p.series.push(Series::markers("c", vec![1.0], vec![2.0], 3));
        f.panels.push(p);
        let s = chart_json(&f).unwrap();
        assert!(!s.contains("</script"));
        let v: Value = serde_json::from_str(&s).unwrap();
        let p = &v["p"][0];
        assert_eq!(p["s"].as_array().unwrap().len(), 3);
        assert_eq!(
            p["x"].as_array().unwrap().len(),
            2,
            "two groups of abscissae"
        );
        // Zeros on a log axis are gaps.
        assert!(decode(&p["s"][1]["y"]).iter().all(|v| v.is_none()));
        let y = decode(&p["s"][0]["y"]);
        assert!(y.len() <= 4 * BUCKETS + 2);
        // log10 of the values: the last is log10(4.999 + 1e-9).
        assert!((y.last().unwrap().unwrap() - 4.999f64.log10()).abs() < 1e-4);
    }
}
