//! The report's verdict: a few sentences in words computed from the runs' metrics (the numbers
//! of `metrics.json`), never fixed text: which controller is offset-free under the payload, which
//! keeps an offset and how large, which has the smallest error, which runs stopped and why, and
//! what the payload did.

use ofmpc::sim::{mass_label, RunMetrics, RunStatus};

/// A steady Cartesian error below this (mm, i.e. 1 nm) is round-off: the controller is
/// offset-free. The paper's incremental algorithms reach ≈ 1e-12 mm; the usual MPC keeps
/// ≈ 0.1 mm at 0.25 kg (README, "What it shows").
pub const OFFSET_FREE_MM: f64 = 1e-6;

/// A length in mm with three significant digits in words ("0.0867 mm", "1.2e-12 mm").
pub fn mm(v: f64) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    format!("{} mm", number(v))
}

/// The report's one number format (issue #38: one number appeared as 0.00189, 0.0019 and
/// 1.89e-3): three significant digits, trailing zeros dropped ("0.0019", "0.69", "309"),
/// and `1.89e-4` below 0.001 or from 10 000.
pub fn number(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !v.is_finite() {
        format!("{v}")
    } else if !(1e-3..1e4).contains(&a) {
        let s = format!("{v:.2e}");
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        }
    } else {
        let digits = (2 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    }
}

/// Controller names in order of first appearance.
fn controllers(runs: &[RunMetrics]) -> Vec<&str> {
    let mut v: Vec<&str> = Vec::new();
    for m in runs {
        if !v.contains(&m.controller.as_str()) {
            v.push(&m.controller);
        }
    }
    v
}

/// "a", "a and b", "a, b and c".
pub fn and_list(items: &[String]) -> String {
    match items.split_last() {
        None => String::new(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
    }
}

fn kg(m: f64) -> String {
    format!("{} kg", mass_label(m))
}

/// The verdict's sentences, in reading order (empty when nothing ran).
pub fn verdict(runs: &[RunMetrics]) -> Vec<String> {
    let mut out = Vec::new();
    if runs.is_empty() {
        return out;
    }
    let names = controllers(runs);
    out.extend(offset_sentences(runs, &names));
    out.extend(smallest_error_sentence(runs, &names));
    out.extend(stopped_sentences(runs, &names));
    out.extend(payload_sentence(runs, &names));
    out
}

/// Offset-free controllers and those that keep a steady offset under a payload.
fn offset_sentences(runs: &[RunMetrics], names: &[&str]) -> Vec<String> {
    let mut free: Vec<(String, f64, f64)> = Vec::new();
    let mut offset = Vec::new();
    for &c in names {
        let loaded: Vec<&RunMetrics> = runs
            .iter()
            .filter(|m| m.controller == c && m.payload_kg > 0.0 && m.status == RunStatus::Ok)
            .filter(|m| m.steady_cartesian_error_mm.is_finite())
            .collect();
        let worst = loaded.iter().copied().max_by(|a, b| {
            a.steady_cartesian_error_mm
                .total_cmp(&b.steady_cartesian_error_mm)
        });
        let Some(worst) = worst else { continue };
        if worst.steady_cartesian_error_mm < OFFSET_FREE_MM {
            let heaviest = loaded.iter().map(|m| m.payload_kg).fold(0.0, f64::max);
            free.push((c.to_string(), worst.steady_cartesian_error_mm, heaviest));
        } else {
            offset.push(offset_phrase(c, &loaded, worst));
        }
    }
    let mut v = Vec::new();
    if !offset.is_empty() {
        v.push(format!(
            "Under a payload the model does not know, {}.",
            and_list(&offset)
        ));
    }
    if !free.is_empty() {
        v.push(offset_free_sentence(&free));
    }
    v
}

/// "first and second are offset-free: their steady errors (at most … up to … kg and …) are
/// round-off, below 1e-6 mm." for `(controller, largest steady error, heaviest payload)`.
fn offset_free_sentence(free: &[(String, f64, f64)]) -> String {
    let names: Vec<String> = free.iter().map(|(c, _, _)| c.clone()).collect();
    let numbers: Vec<String> = free
        .iter()
        .map(|(c, e, p)| {
            let whose = if free.len() > 1 {
                format!(" for {c}")
            } else {
                String::new()
            };
            format!("at most {}{whose} up to {}", mm(*e), kg(*p))
        })
        .collect();
    let (verb, their, errors) = if free.len() == 1 {
        ("is", "its", "steady error")
    } else {
        ("are", "their", "steady errors")
    };
    format!(
        "{} {verb} offset-free: {their} {errors} ({}) {} round-off, below {}.",
        and_list(&names),
        and_list(&numbers),
        if free.len() == 1 { "is" } else { "are" },
        mm(OFFSET_FREE_MM)
    )
}

/// "`c` keeps a steady offset of … at <the lightest payload with an offset>", with the
/// `worst` run's offset after it when that is another payload.
fn offset_phrase(c: &str, loaded: &[&RunMetrics], worst: &RunMetrics) -> String {
    let first = loaded
        .iter()
        .filter(|m| m.steady_cartesian_error_mm >= OFFSET_FREE_MM)
        .min_by(|a, b| a.payload_kg.total_cmp(&b.payload_kg))
        .copied()
        .unwrap_or(worst);
    let mut s = format!(
        "{c} keeps a steady offset of {} at {}",
        mm(first.steady_cartesian_error_mm),
        kg(first.payload_kg)
    );
    if worst.payload_kg != first.payload_kg {
        s.push_str(&format!(
            " ({} at {})",
            mm(worst.steady_cartesian_error_mm),
            kg(worst.payload_kg)
        ));
    }
    s
}

/// The controller with the smallest RMS Cartesian error at each payload (ok runs only).
fn smallest_error_sentence(runs: &[RunMetrics], names: &[&str]) -> Option<String> {
    if names.len() < 2 {
        let m = runs.iter().find(|m| m.status == RunStatus::Ok)?;
        return Some(format!(
            "{}: RMS Cartesian error {} at {}.",
            m.controller,
            mm(m.cartesian_error_rms_mm),
            kg(m.payload_kg)
        ));
    }
    let mut masses: Vec<f64> = runs.iter().map(|m| m.payload_kg).collect();
    masses.sort_by(f64::total_cmp);
    masses.dedup();
    let mut best: Vec<(f64, &RunMetrics)> = Vec::new();
    for &p in &masses {
        let b = runs
            .iter()
            .filter(|m| m.payload_kg == p && m.status == RunStatus::Ok)
            .filter(|m| m.cartesian_error_rms_mm.is_finite())
            .min_by(|a, b| {
                a.cartesian_error_rms_mm
                    .total_cmp(&b.cartesian_error_rms_mm)
            });
        if let Some(b) = b {
            best.push((p, b));
        }
    }
    let first = best.first()?.1.controller.clone();
    if best.iter().all(|(_, m)| m.controller == first) {
        let at: Vec<String> = best
            .iter()
            .map(|(p, m)| format!("{} at {}", mm(m.cartesian_error_rms_mm), kg(*p)))
            .collect();
        let every = if best.len() > 1 {
            " at every payload"
        } else {
            ""
        };
        Some(format!(
            "{first} has the smallest RMS Cartesian error{every}: {}.",
            and_list(&at)
        ))
    } else {
        let at: Vec<String> = best
            .iter()
            .map(|(p, m)| {
                format!(
                    "{} at {} ({})",
                    m.controller,
                    kg(*p),
                    mm(m.cartesian_error_rms_mm)
                )
            })
            .collect();
        Some(format!(
            "The smallest RMS Cartesian error: {}.",
            and_list(&at)
        ))
    }
}

/// Runs that did not go through: per controller, the payloads and the reason in words.
fn stopped_sentences(runs: &[RunMetrics], names: &[&str]) -> Vec<String> {
    let mut v = Vec::new();
    for &c in names {
        let bad: Vec<&RunMetrics> = runs
            .iter()
            .filter(|m| m.controller == c && m.status != RunStatus::Ok)
            .collect();
        if bad.is_empty() {
            continue;
        }
        let mut by_status: Vec<(String, Vec<&RunMetrics>)> = Vec::new();
        for m in bad {
            let s = m.status.to_string();
            match by_status.iter_mut().find(|(k, _)| *k == s) {
                Some((_, list)) => list.push(m),
                None => by_status.push((s, vec![m])),
            }
        }
        for (status, list) in by_status {
            let at: Vec<String> = list
                .iter()
                .map(|m| match m.stopped_at_s {
                    Some(t) => format!("{} (at t = {t:.2} s)", kg(m.payload_kg)),
                    None => kg(m.payload_kg),
                })
                .collect();
            let reason = &list[0].reason;
            let why = if reason.is_empty() {
                String::new()
            } else {
                format!(": {reason}")
            };
            v.push(format!("{c} {status} with {}{why}.", and_list(&at)));
        }
    }
    v
}

/// What the payload did: how the worst-affected controller's RMS error grew from the lightest
/// to the heaviest payload it ran through.
fn payload_sentence(runs: &[RunMetrics], names: &[&str]) -> Option<String> {
    let mut growth: Vec<(f64, String)> = Vec::new();
    for &c in names {
        let mut ok: Vec<&RunMetrics> = runs
            .iter()
            .filter(|m| m.controller == c && m.status == RunStatus::Ok)
            .filter(|m| m.cartesian_error_rms_mm.is_finite())
            .collect();
        ok.sort_by(|a, b| a.payload_kg.total_cmp(&b.payload_kg));
        let (Some(lo), Some(hi)) = (ok.first(), ok.last()) else {
            continue;
        };
        if hi.payload_kg <= lo.payload_kg || lo.cartesian_error_rms_mm <= 0.0 {
            continue;
        }
        let ratio = hi.cartesian_error_rms_mm / lo.cartesian_error_rms_mm;
        growth.push((
            ratio,
            format!(
                "{c}'s RMS error goes from {} at {} to {} at {} (× {})",
                mm(lo.cartesian_error_rms_mm),
                kg(lo.payload_kg),
                mm(hi.cartesian_error_rms_mm),
                kg(hi.payload_kg),
                if ratio >= 10.0 {
                    format!("{ratio:.0}")
                } else {
                    format!("{ratio:.2}")
                }
            ),
        ));
    }
    if growth.is_empty() {
        return None;
    }
    growth.sort_by(|a, b| b.0.total_cmp(&a.0));
    let parts: Vec<String> = growth.into_iter().map(|(_, s)| s).collect();
    Some(format!("The payload: {}.", parts.join("; ")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use ofmpc::sim::StepTime;

    fn run(c: &str, p: f64, rms: f64, steady: f64, status: RunStatus) -> RunMetrics {
        RunMetrics {
            name: format!("{c}_m{}", mass_label(p)),
            controller: c.into(),
            payload_kg: p,
            joint_error_rms_rad: vec![0.0; 6],
            joint_error_max_rad: vec![0.0; 6],
            steady_joint_error_max_rad: vec![0.0; 6],
            cartesian_error_rms_mm: rms,
            cartesian_error_max_mm: rms * 3.0,
            cartesian_error_rms_to_stop_mm: rms,
            cartesian_error_max_to_stop_mm: rms * 3.0,
            steady_cartesian_error_mm: steady,
            torque_max_nm: vec![0.0; 6],
            telemetry: Default::default(),
            torque_step_max_nm: 0.0,
            hold_error_pp_counts: None,
            pre_roll_peak_joint_rad: 0.0,
            servo: None,
            step_time_us: StepTime {
                median: 1.0,
                p99: 1.0,
                max: 1.0,
                deadline_misses: 0,
            },
            wall_s: 0.1,
            diverged: status == RunStatus::Diverged,
            diverged_at_s: (status == RunStatus::Diverged).then_some(3.5),
            status,
            reason: if status == RunStatus::Ok {
                String::new()
            } else {
                "joint 2 error 0.52 rad passed the divergence threshold 0.5 rad".into()
            },
            stopped_at_s: (status != RunStatus::Ok).then_some(3.5),
            payload_estimate_kg: None,
            faults: 0,
            saturated_samples: 0,
            max_torque_ratio: 0.5,
        }
    }

    /// The README's table: 0 and 0.25 kg, and the second diverging at 2 kg.
    fn paper() -> Vec<RunMetrics> {
        use RunStatus::*;
        vec![
            run("usual", 0.0, 0.0019, 7e-13, Ok),
            run("first", 0.0, 0.0233, 5e-13, Ok),
            run("second", 0.0, 0.00014, 5e-13, Ok),
            run("usual", 0.25, 0.0789, 0.0867, Ok),
            run("first", 0.25, 0.0233, 5e-13, Ok),
            run("second", 0.25, 0.00099, 9e-13, Ok),
            run("usual", 2.0, 0.63, 0.69, Ok),
            run("first", 2.0, 0.024, 7e-13, Ok),
            run("second", 2.0, 40.0, f64::NAN, Diverged),
        ]
    }

    #[test]
    fn the_verdict_says_the_papers_claims_from_the_numbers() {
        let v = verdict(&paper()).join(" ");
        assert!(
            v.contains("usual keeps a steady offset of 0.0867 mm at 0.25 kg (0.69 mm at 2 kg)"),
            "{v}"
        );
        assert!(
            v.contains(
                "first and second are offset-free: their steady errors (at most 7e-13 mm for \
                 first up to 2 kg and at most 9e-13 mm for second up to 0.25 kg) are \
                 round-off, below 1e-6 mm."
            ),
            "{v}"
        );
        assert!(
            v.contains("second diverged with 2 kg (at t = 3.50 s): joint 2 error"),
            "{v}"
        );
        assert!(
            v.contains("The smallest RMS Cartesian error: second at 0 kg (1.4e-4 mm), second at 0.25 kg (9.9e-4 mm) and first at 2 kg (0.024 mm)"),
            "{v}"
        );
        assert!(
            v.contains("usual's RMS error goes from 0.0019 mm at 0 kg to 0.63 mm at 2 kg"),
            "{v}"
        );
    }

    #[test]
    fn a_changed_metric_changes_the_sentence() {
        let mut runs = paper();
        let before = verdict(&runs).join(" ");
        // The usual MPC's offset at 0.25 kg doubles: the sentence says the new number.
        runs[3].steady_cartesian_error_mm = 0.1734;
        let after = verdict(&runs).join(" ");
        assert!(before.contains("0.0867 mm at 0.25 kg"));
        assert!(
            after.contains("0.173 mm at 0.25 kg") && !after.contains("0.0867"),
            "{after}"
        );
        // The first algorithm keeps an offset: no longer called offset-free.
        runs[4].steady_cartesian_error_mm = 0.01;
        let after = verdict(&runs).join(" ");
        assert!(
            after.contains("first keeps a steady offset of 0.01 mm at 0.25 kg"),
            "{after}"
        );
        assert!(
            after.contains("second is offset-free: its steady error"),
            "{after}"
        );
        assert!(
            !after.contains("first and second are offset-free"),
            "{after}"
        );
        // The second algorithm no longer diverges: no stopped sentence, and it is the best at 2 kg.
        runs[8] = run("second", 2.0, 0.006, 1e-12, RunStatus::Ok);
        let after = verdict(&runs).join(" ");
        assert!(!after.contains("diverged"), "{after}");
        assert!(
            after.contains("second has the smallest RMS Cartesian error at every payload"),
            "{after}"
        );
    }

    #[test]
    fn lengths_in_words() {
        assert_eq!(mm(0.08671), "0.0867 mm");
        assert_eq!(mm(309.2), "309 mm");
        assert_eq!(mm(5e-13), "5e-13 mm");
        assert_eq!(mm(f64::NAN), "n/a");
        assert_eq!(mm(0.00189), "0.00189 mm");
        assert_eq!(mm(0.0019), "0.0019 mm");
        assert_eq!(mm(0.69), "0.69 mm");
        assert_eq!(number(1.89e-4), "1.89e-4");
        assert_eq!(number(1.4e-4), "1.4e-4");
        assert_eq!(number(0.25), "0.25");
        assert!(verdict(&[]).is_empty());
    }
}
