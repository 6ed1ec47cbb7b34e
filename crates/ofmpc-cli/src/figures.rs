//! The figures of a run, after the paper's: Fig. 5 (q and τ per joint),
//! Fig. 6/7 (joint errors of the three controllers, without and with
//! payload), the Cartesian errors, the path, and the payload sweep.

use crate::output::plot::{
    controller_color, Figure, Panel, Series, Series3d, COLOR_REFERENCE, COLOR_SECOND, COLOR_USUAL,
};
use ofmpc::motion::JointReference;
use ofmpc::motion::{CartesianSample, CartesianTrajectory};
use ofmpc::sim::{Record, RunMetrics};

/// Palette indices for joints 1..6 (no yellow: it vanishes on white).
const JOINT_COLORS: [usize; 6] = [1, 2, 3, 4, 5, 6];

/// Floor of the error plots' log axes: |e| below it (exact zeros) is drawn at it.
pub const ERROR_FLOOR_RAD: f64 = 1e-15;
/// Floor of the Cartesian error plots' log axes (mm).
pub const ERROR_FLOOR_MM: f64 = 1e-12;

/// A marker at the last sample of each run that ended before the longest one (it stopped),
/// labelled with the time of the stop.
fn stop_markers(p: &mut Panel, runs: &[(&str, &Record)], y: &dyn Fn(&Record, usize) -> f64) {
    let longest = runs.iter().map(|(_, r)| r.len()).max().unwrap_or(0);
    for (name, rec) in runs {
        if rec.len() < longest && !rec.is_empty() {
            let k = rec.len() - 1;
            p.series.push(Series::markers(
                format!("{name} stopped at {:.2} s", rec.t[k]),
                vec![rec.t[k]],
                vec![y(rec, k)],
                controller_color(name),
            ));
        }
    }
}

fn column(rec: &Record, v: &[f64], i: usize) -> Vec<f64> {
    (0..rec.len()).map(|k| v[k * rec.n + i]).collect()
}

/// Fig. 5: joint coordinates (with the reference) and torques, one row per joint.
pub fn joints_and_torques(title: &str, rec: &Record) -> Figure {
    let mut f = Figure::new(title, 2);
    for i in 0..rec.n {
        let mut p = Panel::new(
            format!("joint {}", i + 1),
            "t (s)",
            format!("q{} (rad)", i + 1),
        );
        // q first, the reference dashed on top of it: visible where they coincide.
        p.series.push(Series::line(
            "q",
            rec.t.clone(),
            column(rec, &rec.q, i),
            COLOR_SECOND,
        ));
        p.series.push(Series::dashed(
            "reference",
            rec.t.clone(),
            column(rec, &rec.q_ref, i),
            COLOR_REFERENCE,
        ));
        f.panels.push(p);
        let mut p = Panel::new(
            format!("joint {}", i + 1),
            "t (s)",
            format!("τ{} (N·m)", i + 1),
        );
        p.series.push(Series::line(
            "τ",
            rec.t.clone(),
            column(rec, &rec.tau, i),
            COLOR_USUAL,
        ));
        f.panels.push(p);
    }
    f
}

/// Drive load: `|τ_i| / τmax_i` of several runs against time, one panel per
/// joint with the limit (1) dashed; joints without a finite limit are left out.
pub fn torque_ratios(title: &str, runs: &[(&str, &Record)], limits: &[f64]) -> Figure {
    let mut f = Figure::new(title, 2);
    for (i, &lim) in limits.iter().enumerate() {
        if !(lim.is_finite() && lim > 0.0) {
            continue;
        }
        let mut p = Panel::new(
            format!("joint {}", i + 1),
            "t (s)",
            format!("|τ{}| / τmax", i + 1),
        );
        if let Some((_, rec)) = runs.first() {
            let t = rec.t.clone();
            let ones = vec![1.0; t.len()];
            p.series
                .push(Series::dashed("limit", t, ones, COLOR_REFERENCE));
        }
        for (name, rec) in runs {
            let r = (0..rec.len())
                .map(|k| rec.tau[k * rec.n + i].abs() / lim)
                .collect();
            p.series.push(Series::line(
                *name,
                rec.t.clone(),
                r,
                controller_color(name),
            ));
        }
        // The applied torque stops at the limit; what the controller commanded can be far
        // above it (max |τ|/τmax of the table, over all joints): drawn as a level so that the
        // axis reaches the true maximum.
        for (name, rec) in runs {
            if rec.max_torque_ratio > 1.0 + 1e-9 && rec.max_torque_ratio.is_finite() {
                let (t0, t1) = (
                    rec.t.first().copied().unwrap_or(0.0),
                    rec.t.last().copied().unwrap_or(0.0),
                );
                p.series.push(Series::dashed(
                    format!(
                        "{name}: largest commanded, any joint = {:.3}",
                        rec.max_torque_ratio
                    ),
                    vec![t0, t1],
                    vec![rec.max_torque_ratio; 2],
                    controller_color(name),
                ));
            }
        }
        f.panels.push(p);
    }
    f
}

/// What the controller was given minus the true position, per joint (gaps:
/// lost or invalid measurements).
pub fn measurement_errors(title: &str, rec: &Record) -> Figure {
    let mut f = Figure::new(title, 2);
    for i in 0..rec.n {
        let mut p = Panel::new(
            format!("joint {}", i + 1),
            "t (s)",
            format!("q_meas{0} − q{0} (rad)", i + 1),
        );
        let d = (0..rec.len())
            .map(|k| rec.q_meas[k * rec.n + i] - rec.q[k * rec.n + i])
            .collect();
        p.series.push(Series::line(
            "measured − true",
            rec.t.clone(),
            d,
            JOINT_COLORS[i % JOINT_COLORS.len()],
        ));
        f.panels.push(p);
    }
    f
}

/// Fig. 6/7: joint errors |e_i| = |w_i − q_i| of several runs, one panel per joint, on a log
/// axis (the errors span decades: ≈ 1e-4 rad for the usual MPC under a payload, round-off for
/// the incremental algorithms); exact zeros are drawn at [`ERROR_FLOOR_RAD`]. A run that
/// stopped ends with a marker.
pub fn joint_errors(title: &str, runs: &[(&str, &Record)]) -> Figure {
    let n = runs.first().map_or(0, |(_, r)| r.n);
    let mut f = Figure::new(title, 2);
    for i in 0..n {
        let mut p = Panel::new(
            format!("joint {}", i + 1),
            "t (s)",
            format!("|e{}| (rad, log)", i + 1),
        );
        p.log_y = true;
        let y = |rec: &Record, k: usize| rec.joint_error(k, i).abs().max(ERROR_FLOOR_RAD);
        for (name, rec) in runs {
            let e = (0..rec.len()).map(|k| y(rec, k)).collect();
            p.series.push(Series::line(
                *name,
                rec.t.clone(),
                e,
                controller_color(name),
            ));
        }
        stop_markers(&mut p, runs, &y);
        f.panels.push(p);
    }
    f
}

/// Cartesian errors |x|, |y|, |z| (mm, log axis, floor [`ERROR_FLOOR_MM`]) of several runs; a
/// run that stopped ends with a marker.
pub fn cartesian_errors(title: &str, runs: &[(&str, &Record)]) -> Figure {
    let mut f = Figure::new(title, 3);
    for (c, axis) in ["x", "y", "z"].iter().enumerate() {
        let mut p = Panel::new(
            format!("{axis} error"),
            "t (s)",
            format!("|e_{axis}| (mm, log)"),
        );
        p.log_y = true;
        let y =
            |rec: &Record, k: usize| (rec.cartesian_error(k)[c] * 1e3).abs().max(ERROR_FLOOR_MM);
        for (name, rec) in runs {
            let e = (0..rec.len()).map(|k| y(rec, k)).collect();
            p.series.push(Series::line(
                *name,
                rec.t.clone(),
                e,
                controller_color(name),
            ));
        }
        stop_markers(&mut p, runs, &y);
        f.panels.push(p);
    }
    f
}

/// The path of the flange in the base frame (mm): top view XY and side view XZ, both with equal
/// axis scales, a 3-D view, and the joint reference q(t) of every joint; the start point is
/// marked in each view of the path.
pub fn path(title: &str, reference: &JointReference) -> Figure {
    let k = reference.len();
    let p: Vec<[f64; 3]> = (0..k).map(|s| reference.position(s)).collect();
    let mm = |c: usize| p.iter().map(|q| q[c] * 1e3).collect::<Vec<f64>>();
    let (x, y, z) = (mm(0), mm(1), mm(2));
    let start = |v: &[f64]| v.first().map(|&a| vec![a]).unwrap_or_default();
    let mut f = Figure::new(title, 2);
    f.panel_size = (600, 440);
    let view2d = |name: &str, h: &[f64], hl: &str, v: &[f64], vl: &str| {
        let mut panel = Panel::new(name, hl, vl);
        panel.equal_aspect = true;
        panel.series.push(Series::line(
            "flange path",
            h.to_vec(),
            v.to_vec(),
            COLOR_REFERENCE,
        ));
        panel
            .series
            .push(Series::markers("start", start(h), start(v), COLOR_USUAL));
        panel
    };
    f.panels
        .push(view2d("top view (XY)", &x, "x (mm)", &y, "y (mm)"));
    let mut iso = Panel::new_3d("3-D view", "x (mm)", "y (mm)", "z (mm)");
    iso.series_3d().push(Series3d::line(
        "flange path",
        x.clone(),
        y.clone(),
        z.clone(),
        COLOR_REFERENCE,
    ));
    iso.series_3d().push(Series3d::markers(
        "start",
        start(&x),
        start(&y),
        start(&z),
        COLOR_USUAL,
    ));
    f.panels.push(iso);
    f.panels
        .push(view2d("side view (XZ)", &x, "x (mm)", &z, "z (mm)"));
    let t: Vec<f64> = (0..k).map(|s| s as f64 * reference.ts()).collect();
    let mut qp = Panel::new("joint reference", "t (s)", "q (rad)");
    for i in 0..reference.dof() {
        qp.series.push(Series::line(
            format!("q{}", i + 1),
            t.clone(),
            (0..k).map(|s| reference.q(s)[i]).collect(),
            JOINT_COLORS[i % JOINT_COLORS.len()],
        ));
    }
    f.panels.push(qp);
    f
}

/// Steady and RMS Cartesian error against payload, per controller; diverged
/// runs as markers at the error they had reached when stopped.
pub fn payload_sweep(title: &str, runs: &[RunMetrics]) -> Figure {
    let mut f = Figure::new(title, 2);
    let mut steady = Panel::new(
        "steady Cartesian error (last 0.5 s of the hold)",
        "payload (kg)",
        "error (mm)",
    );
    let mut rms = Panel::new("RMS Cartesian error", "payload (kg)", "error (mm)");
    steady.log_y = true;
    rms.log_y = true;
    let mut names: Vec<&str> = runs.iter().map(|m| m.controller.as_str()).collect();
    names.dedup();
    names.sort();
    names.dedup();
    for name in names {
        let mine: Vec<&RunMetrics> = runs.iter().filter(|m| m.controller == name).collect();
        let ok: Vec<&&RunMetrics> = mine.iter().filter(|m| !m.diverged).collect();
        let bad: Vec<&&RunMetrics> = mine.iter().filter(|m| m.diverged).collect();
        let color = controller_color(name);
        // A zero steady error cannot be drawn on a log axis: floor at 1e-12 mm.
        steady.series.push(Series::line(
            name,
            ok.iter().map(|m| m.payload_kg).collect(),
            ok.iter()
                .map(|m| m.steady_cartesian_error_mm.max(1e-12))
                .collect(),
            color,
        ));
        rms.series.push(Series::line(
            name,
            ok.iter().map(|m| m.payload_kg).collect(),
            ok.iter().map(|m| m.cartesian_error_rms_mm).collect(),
            color,
        ));
        if !bad.is_empty() {
            let x: Vec<f64> = bad.iter().map(|m| m.payload_kg).collect();
            let y: Vec<f64> = bad
                .iter()
                .map(|m| m.cartesian_error_max_to_stop_mm)
                .collect();
            steady.series.push(Series::markers(
                format!("{name} diverged (error at stop)"),
                x.clone(),
                y.clone(),
                color,
            ));
            rms.series.push(Series::markers(
                format!("{name} diverged (error at stop)"),
                x,
                y,
                color,
            ));
        }
    }
    f.panels.push(steady);
    f.panels.push(rms);
    f
}

/// The paper's Fig. 4: the timed Cartesian reference — position, velocity and
/// acceleration of the flange along x, y, z, sampled every `ts`.
pub fn cartesian_reference(title: &str, trajectory: &CartesianTrajectory, ts: f64) -> Figure {
    let k = (trajectory.duration() / ts).ceil() as usize + 1;
    let t: Vec<f64> = (0..k)
        .map(|s| (s as f64 * ts).min(trajectory.duration()))
        .collect();
    let samples: Vec<_> = t.iter().map(|&t| trajectory.sample(t)).collect();
    let mut f = Figure::new(title, 1);
    type Get = fn(&CartesianSample) -> nalgebra::Vector3<f64>;
    let quantities: [(&str, &str, Get); 3] = [
        ("position", "mm", |s| s.position),
        ("velocity", "mm/s", |s| s.velocity),
        ("acceleration", "mm/s²", |s| s.acceleration),
    ];
    for (name, unit, get) in quantities {
        let mut p = Panel::new(name, "t (s)", format!("{name} ({unit})"));
        for (c, axis) in ["x", "y", "z"].iter().enumerate() {
            let y = samples.iter().map(|s| get(s)[c] * 1e3).collect();
            p.series
                .push(Series::line(*axis, t.clone(), y, JOINT_COLORS[c]));
        }
        f.panels.push(p);
    }
    f
}

/// Online identification: the Cartesian error norm of every run (log scale)
/// and the mass estimate of the adaptive ones against time, with the mass the
/// plant carries (`true_mass(t)`, e.g. 0 before a pick-up).
pub fn identification(
    title: &str,
    runs: &[(&str, &Record)],
    true_mass: &dyn Fn(f64) -> f64,
) -> Figure {
    let mut f = Figure::new(title, 1);
    let mut err = Panel::new("Cartesian error |p_ref − p|", "t (s)", "error (mm)");
    err.log_y = true;
    let mut mass = Panel::new(
        "payload mass: identified online and true",
        "t (s)",
        "mass (kg)",
    );
    let mut t_all: Vec<f64> = Vec::new();
    for (name, rec) in runs {
        let e: Vec<f64> = (0..rec.len())
            .map(|k| {
                let c = rec.cartesian_error(k);
                ((c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() * 1e3).max(1e-9)
            })
            .collect();
        err.series.push(Series::line(
            *name,
            rec.t.clone(),
            e,
            controller_color(name),
        ));
        if rec.payload_mass_est.len() == rec.len() && !rec.is_empty() {
            mass.series.push(Series::line(
                format!("{name}: estimate"),
                rec.t.clone(),
                rec.payload_mass_est.clone(),
                controller_color(name),
            ));
        }
        if rec.t.len() > t_all.len() {
            t_all = rec.t.clone();
        }
    }
    let truth: Vec<f64> = t_all.iter().map(|&t| true_mass(t)).collect();
    mass.series
        .push(Series::dashed("true", t_all, truth, COLOR_REFERENCE));
    f.panels.push(err);
    f.panels.push(mass);
    f
}

/// The motion as the planner timed it: top view of the flange path, path speed against
/// time, and each joint's speed as a fraction of its limit (`limits`, rad/s; the dashed
/// line at 1 is the limit).
pub fn motion_profile(title: &str, reference: &JointReference, limits: &[f64]) -> Figure {
    let k = reference.len();
    let ts = reference.ts();
    let t: Vec<f64> = (0..k).map(|s| s as f64 * ts).collect();
    let p: Vec<[f64; 3]> = (0..k).map(|s| reference.position(s)).collect();
    let mut f = Figure::new(title, 3);
    let mut top = Panel::new("top view (XY)", "x (mm)", "y (mm)");
    top.equal_aspect = true;
    top.series.push(Series::line(
        "flange path",
        p.iter().map(|q| q[0] * 1e3).collect(),
        p.iter().map(|q| q[1] * 1e3).collect(),
        COLOR_REFERENCE,
    ));
    f.panels.push(top);
    let speed: Vec<f64> = (0..k)
        .map(|s| {
            let (a, b) = (p[s.saturating_sub(1)], p[(s + 1).min(k - 1)]);
            let dt = ts * ((s + 1).min(k - 1) - s.saturating_sub(1)).max(1) as f64;
            ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt() / dt
                * 1e3
        })
        .collect();
    let mut sp = Panel::new("path speed", "t (s)", "speed (mm/s)");
    sp.series
        .push(Series::line("|v|", t.clone(), speed, COLOR_REFERENCE));
    f.panels.push(sp);
    let mut jv = Panel::new("joint speed / limit", "t (s)", "|q̇ᵢ| / q̇ᵢ,max");
    for (i, lim) in limits.iter().enumerate().take(reference.dof()) {
        let y = (0..k).map(|s| reference.qd(s)[i].abs() / lim).collect();
        jv.series.push(Series::line(
            format!("q{}", i + 1),
            t.clone(),
            y,
            JOINT_COLORS[i % JOINT_COLORS.len()],
        ));
    }
    let t_end = t.last().copied().unwrap_or(0.0);
    jv.series.push(Series::dashed(
        "limit",
        vec![0.0, t_end],
        vec![1.0, 1.0],
        COLOR_REFERENCE,
    ));
    f.panels.push(jv);
    f
}
