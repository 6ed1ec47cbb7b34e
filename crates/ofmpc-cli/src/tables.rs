//! Text outputs: CSV time series and the summary table.

use ofmpc::motion::JointReference;
use ofmpc::sim::{Record, RunMetrics, RunStatus};
use std::fmt::Write as _;

/// Writes `x` at full precision (it parses back to the same bits): plain
/// decimals for 1e-4 ≤ |x| < 1e15, exponent form otherwise.
fn num(s: &mut String, x: f64) {
    let a = x.abs();
    if x == 0.0 || (1e-4..1e15).contains(&a) || !x.is_finite() {
        let _ = write!(s, "{x}");
    } else {
        let _ = write!(s, "{x:e}");
    }
}

/// `timeseries.csv` of a run: `t`, `q1..qn`, `qd1..qdn`, `tau1..taun`,
/// `qref1..qrefn`, `e1..en` (= qref − q), `x,y,z` (true flange), `xref,yref,zref`,
/// `ex,ey,ez` (= ref − true), `payload_mass_est_kg` (adaptive controllers), and
/// when a measurement effect or fault is on `q_meas1..n`, `qd_meas1..n`: what
/// the controller was given (NaN where the measurement was invalid or
/// missing). SI units (s, rad, rad/s, N·m, m). Row k holds the plant's true
/// state at t_k and the torque applied over [t_k, t_k + Ts).
/// Numbers are printed at full precision (shortest round-trip form).
/// Runs of a controller that identifies the payload online (the adaptive
/// variants) have one more column, `payload_mass_est_kg`: the mass its model
/// carries after the step of that row.
///
/// Every `stride`-th row (rows 0, stride, 2·stride, …, and always
/// the last): `[output] timeseries = "decimated"`. A stride of 1 (or 0) writes every row.
pub fn timeseries_csv_every(rec: &Record, stride: usize) -> String {
    let stride = stride.max(1);
    let with_mass = !rec.payload_mass_est.is_empty() && rec.payload_mass_est.len() == rec.len();
    let n = rec.n;
    let rows = rec.len().div_ceil(stride) + 1;
    let mut s = String::with_capacity(rows * (6 * n + 9) * 20 + 256);
    s.push('t');
    for prefix in ["q", "qd", "tau", "qref", "e"] {
        for i in 1..=n {
            let _ = write!(s, ",{prefix}{i}");
        }
    }
    s.push_str(",x,y,z,xref,yref,zref,ex,ey,ez");
    if with_mass {
        s.push_str(",payload_mass_est_kg");
    }
    let with_meas = rec.has_measurement()
        && rec.q_meas.len() == rec.len() * n
        && rec.qd_meas.len() == rec.len() * n;
    if with_meas {
        for prefix in ["q_meas", "qd_meas"] {
            for i in 1..=n {
                let _ = write!(s, ",{prefix}{i}");
            }
        }
    }
    s.push('\n');
    let last = rec.len().checked_sub(1);
    for k in (0..rec.len()).filter(|k| k % stride == 0 || Some(*k) == last) {
        timeseries_row(&mut s, rec, k, with_mass, with_meas);
    }
    s
}

/// Row `k` of [`timeseries_csv_every`].
fn timeseries_row(s: &mut String, rec: &Record, k: usize, with_mass: bool, with_meas: bool) {
    let n = rec.n;
    num(s, rec.t[k]);
    for v in [&rec.q, &rec.qd, &rec.tau, &rec.q_ref] {
        for x in &v[k * n..(k + 1) * n] {
            s.push(',');
            num(s, *x);
        }
    }
    for i in 0..n {
        s.push(',');
        num(s, rec.joint_error(k, i));
    }
    let (p, r, e) = (rec.flange[k], rec.flange_ref[k], rec.cartesian_error(k));
    for x in p.iter().chain(&r).chain(&e) {
        s.push(',');
        num(s, *x);
    }
    if with_mass {
        s.push(',');
        num(s, rec.payload_mass_est[k]);
    }
    if with_meas {
        for v in [&rec.q_meas, &rec.qd_meas] {
            for x in &v[k * n..(k + 1) * n] {
                s.push(',');
                num(s, *x);
            }
        }
    }
    s.push('\n');
}

/// The bytes a row of a run's `timeseries.csv` takes, estimated (about 20 characters a
/// number) for a robot of `n` joints: for the size estimate before a run.
pub fn timeseries_bytes_per_row(n: usize) -> u64 {
    (7 * n as u64 + 12) * 20
}

/// The reference CSV of `ofmpc trajectory`: `t,x,y,z,q1..qn,qd1..qdn`
/// (s; flange position in the base frame, m; rad; rad/s).
pub fn reference_csv(reference: &JointReference) -> String {
    let n = reference.dof();
    let mut s = String::from("t,x,y,z");
    for prefix in ["q", "qd"] {
        for i in 1..=n {
            let _ = write!(s, ",{prefix}{i}");
        }
    }
    s.push('\n');
    for k in 0..reference.len() {
        let p = reference.position(k);
        let _ = write!(
            s,
            "{},{},{},{}",
            k as f64 * reference.ts(),
            p[0],
            p[1],
            p[2]
        );
        for x in reference.q(k).iter().chain(reference.qd(k)) {
            let _ = write!(s, ",{x}");
        }
        s.push('\n');
    }
    s
}

fn fmt_opt(v: f64, prec: usize) -> String {
    if v == 0.0 {
        "0".to_string()
    } else if v.is_finite() {
        if v.abs() < 1e-3 || v.abs() >= 1e5 {
            format!("{v:.2e}")
        } else {
            format!("{v:.prec$}")
        }
    } else {
        "—".to_string()
    }
}

/// Header of the summary table.
pub const SUMMARY_HEADER: [&str; 11] = [
    "run",
    "controller",
    "payload (kg)",
    "Cart. RMS (mm)",
    "Cart. max (mm)",
    "steady Cart. (mm)",
    "steady joint max (rad)",
    "step median (µs)",
    "step p99 (µs)",
    "deadline misses",
    "status",
];

/// One row per run, as strings.
pub fn summary_rows(runs: &[RunMetrics]) -> Vec<Vec<String>> {
    runs.iter()
        .map(|m| {
            let steady_joint = m
                .steady_joint_error_max_rad
                .iter()
                .copied()
                .fold(f64::NAN, f64::max);
            vec![
                m.name.clone(),
                m.controller.clone(),
                format!("{}", m.payload_kg),
                // Up to the stop: after a safe stop the robot brakes while the reference goes on.
                fmt_opt(m.cartesian_error_rms_to_stop_mm, 4),
                fmt_opt(m.cartesian_error_max_to_stop_mm, 4),
                fmt_opt(m.steady_cartesian_error_mm, 4),
                fmt_opt(steady_joint, 4),
                fmt_opt(m.step_time_us.median, 1),
                fmt_opt(m.step_time_us.p99, 1),
                m.step_time_us.deadline_misses.to_string(),
                match (m.status, m.stopped_at_s) {
                    (RunStatus::Ok, _) => "ok".into(),
                    (RunStatus::Diverged, Some(t)) => format!("DIVERGED at {t:.2} s"),
                    (RunStatus::Failed, Some(t)) => format!("FAILED at {t:.2} s"),
                    (RunStatus::Stopped, Some(t)) => format!("STOPPED at {t:.2} s"),
                    (RunStatus::FailedStop, Some(t)) => format!("STOP FAILED at {t:.2} s"),
                    (status, _) => status.to_string().to_uppercase(),
                },
            ]
        })
        .collect()
}

/// The summary table as aligned text for the terminal.
pub fn summary_text(runs: &[RunMetrics]) -> String {
    let rows = summary_rows(runs);
    let mut widths: Vec<usize> = SUMMARY_HEADER.iter().map(|h| h.chars().count()).collect();
    for r in &rows {
        for (w, c) in widths.iter_mut().zip(r) {
            *w = (*w).max(c.chars().count());
        }
    }
    let mut s = String::new();
    let line = |cells: Vec<String>, s: &mut String| {
        for (i, (c, w)) in cells.iter().zip(&widths).enumerate() {
            let pad = w - c.chars().count();
            if i < 2 || i == 8 {
                let _ = write!(s, "{c}{}  ", " ".repeat(pad));
            } else {
                let _ = write!(s, "{}{c}  ", " ".repeat(pad));
            }
        }
        s.truncate(s.trim_end().len());
        s.push('\n');
    };
    line(
        SUMMARY_HEADER.iter().map(|h| h.to_string()).collect(),
        &mut s,
    );
    for r in rows {
        line(r, &mut s);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip_exactly() {
        for x in [
            0.0,
            1.0,
            -0.1,
            1.0 / 3.0,
            3.0531133177191805e-16,
            1e300,
            -2.5e-5,
            123456.789,
            f64::MIN_POSITIVE,
        ] {
            let mut s = String::new();
            num(&mut s, x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
    }
}
