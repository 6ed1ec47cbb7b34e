//! The data of the report's 3-D replay (drawn by `assets/replay.js` with raw WebGL): the
//! robot's kinematics (each joint's placement in its parent body at q = 0 and its axis, the
//! flange offset; the page computes the joint frames by forward kinematics, Featherstone,
//! "Rigid Body Dynamics Algorithms", 2008, §4.1), the reference flange path, and per run the
//! joint angles and the Cartesian tracking error at most [`MAX_FRAMES`] samples apart, quantized
//! like the charts ([`super::chart::quantize`]).
//!
//! The controller's predicted horizon: the runs record, every few frames, the joint positions
//! the controller's model predicts over its horizon ([`ofmpc::sim::PredictedHorizons`], at the
//! samples of [`horizon_sampling`]); the page draws the latest one at or before the current
//! sample as a polyline in Cartesian space (forward kinematics of the predicted joints), from
//! the flange at its sample. The baselines without a horizon have none.

use super::chart::quantize;
use ofmpc::robot::{JointKind, Robot};
use ofmpc::sim::{HorizonSampling, Record};
use serde_json::{json, Value};

/// Most frames per run kept in the page: every `stride`-th sample of the record and its last.
pub const MAX_FRAMES: usize = 2000;

/// Frames of all runs together: with many runs each keeps fewer (at least [`MIN_FRAMES`]), so
/// a sweep's page stays small.
pub const TOTAL_FRAMES: usize = 12_000;

/// Fewest frames per run.
pub const MIN_FRAMES: usize = 400;

/// Predicted horizons of all runs together in the page (each has `N·n` values).
pub const TOTAL_HORIZONS: usize = 1500;

/// Most predicted horizons per run.
pub const MAX_HORIZONS: usize = 400;

/// Fewest predicted horizons per run.
pub const MIN_HORIZONS: usize = 40;

/// The samples at which each of `runs` runs of `samples` samples records its horizon: every
/// `m`-th frame of the page ([`frame_indices`]), at most [`MAX_HORIZONS`] per run and
/// [`TOTAL_HORIZONS`] in all (at least [`MIN_HORIZONS`] per run).
pub fn horizon_sampling(samples: usize, runs: usize) -> HorizonSampling {
    let stride = samples.div_ceil(frames_per_run(runs)).max(1);
    let per_run = (TOTAL_HORIZONS / runs.max(1)).clamp(MIN_HORIZONS, MAX_HORIZONS);
    let frames = samples.div_ceil(stride);
    HorizonSampling {
        every: stride * frames.div_ceil(per_run).max(1),
        max: per_run + 1,
    }
}

/// The predicted horizons of a record as JSON: the samples `k`, the horizon `N` and per joint
/// the predicted positions (quantized, horizon after horizon); `null` without any.
fn horizons_json(rec: &Record) -> Value {
    match &rec.horizons {
        Some(h) if !h.samples.is_empty() && h.horizon > 0 => {
            let per = h.n * h.horizon;
            let q: Vec<Value> = (0..h.n)
                .map(|i| {
                    quantize(
                        &h.q.chunks_exact(per)
                            .flat_map(|b| b.iter().skip(i).step_by(h.n).copied())
                            .collect::<Vec<_>>(),
                    )
                })
                .collect();
            json!({"k": h.samples, "n": h.horizon, "q": q})
        }
        _ => Value::Null,
    }
}

/// Frames per run for `runs` runs.
pub fn frames_per_run(runs: usize) -> usize {
    (TOTAL_FRAMES / runs.max(1)).clamp(MIN_FRAMES, MAX_FRAMES)
}

/// Row-major 3 × 3 rotation and position of a transform.
fn transform(t: &ofmpc::spatial::Transform) -> Value {
    let r = &t.rot;
    json!({
        "r": [r[(0, 0)], r[(0, 1)], r[(0, 2)], r[(1, 0)], r[(1, 1)], r[(1, 2)], r[(2, 0)], r[(2, 1)], r[(2, 2)]],
        "p": [t.pos[0], t.pos[1], t.pos[2]],
    })
}

/// The sample indices drawn of a record of `len` samples: `0, s, 2s, …` and the last.
pub fn frame_indices(len: usize, max_frames: usize) -> (usize, Vec<usize>) {
    if len == 0 {
        return (1, Vec::new());
    }
    let stride = len.div_ceil(max_frames.max(1)).max(1);
    let mut v: Vec<usize> = (0..len).step_by(stride).collect();
    if v.last() != Some(&(len - 1)) {
        v.push(len - 1);
    }
    (stride, v)
}

/// One run of the replay: name, status line, and the `(name, record)` it draws.
pub struct ReplayRun<'a> {
    /// Run name (its folder).
    pub name: &'a str,
    /// Status in words (`"ok"`, `"diverged at 3.2 s: …"`).
    pub status: String,
    /// The recorded time series.
    pub record: &'a Record,
}

/// The replay's data as JSON (the robot drawn as capsules).
pub fn replay_json(robot: &Robot, runs: &[ReplayRun<'_>]) -> String {
    replay_json_with(robot, runs, None)
}

/// The robot for the replay: its joints (placement, axis, kind), its flange and, when its
/// visuals have meshes, the meshes and which bodies are drawn as capsules.
fn robot_json(robot: &Robot, visuals: Option<&super::mesh::visuals::Visuals>) -> Value {
    let joints: Vec<Value> = robot
        .joints()
        .iter()
        .map(|j| {
            json!({
                "name": j.name,
                "t": transform(&j.placement),
                "axis": [j.axis[0], j.axis[1], j.axis[2]],
                "prismatic": j.kind == JointKind::Prismatic,
            })
        })
        .collect();
    let mut robot_json =
        json!({"name": robot.name(), "joints": joints, "flange": transform(robot.flange_offset())});
    if let Some(v) = visuals.filter(|v| !v.meshes.is_empty()) {
        robot_json["meshes"] = super::mesh::embed::meshes_json(v);
        robot_json["capsules"] = json!(v.capsule);
    }
    robot_json
}

/// The replay's data as JSON, with the robot's meshes when `visuals` has any
/// ([`super::mesh`]): `robot.meshes` (per body, [`super::mesh::embed::meshes_json`]) and
/// `robot.capsules` (per body 0..=n: drawn as a capsule).
pub fn replay_json_with(
    robot: &Robot,
    runs: &[ReplayRun<'_>],
    visuals: Option<&super::mesh::visuals::Visuals>,
) -> String {
    let mut reference = Value::Null;
    let mut out_runs = Vec::new();
    for run in runs {
        let rec = run.record;
        let (stride, idx) = frame_indices(rec.len(), frames_per_run(runs.len()));
        if reference.is_null() && !idx.is_empty() {
            let c = |i: usize| -> Vec<f64> { idx.iter().map(|&k| rec.flange_ref[k][i]).collect() };
            reference = json!([quantize(&c(0)), quantize(&c(1)), quantize(&c(2))]);
        }
        let q: Vec<Value> = (0..rec.n)
            .map(|i| {
                quantize(
                    &idx.iter()
                        .map(|&k| rec.q[k * rec.n + i])
                        .collect::<Vec<_>>(),
                )
            })
            .collect();
        // |e| in mm on a log scale (floor 1e-9 mm): the trace's colour.
        let err: Vec<f64> = idx
            .iter()
            .map(|&k| {
                let e = rec.cartesian_error(k);
                ((e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() * 1e3)
                    .max(1e-9)
                    .log10()
            })
            .collect();
        let t: Vec<f64> = idx.iter().map(|&k| rec.t[k]).collect();
        out_runs.push(json!({
            "name": run.name,
            "status": run.status,
            "len": rec.len(),
            "stride": stride,
            "t": quantize(&t),
            "q": q,
            "err": quantize(&err),
            "horizon": horizons_json(rec),
        }));
    }
    json!({
        "robot": robot_json(robot, visuals),
        "reference": reference,
        "runs": out_runs,
        "horizon_note": "Magenta: what the controller predicted over its horizon at the latest recorded sample (none for pid, ctc, ctc-adaptive).",
    })
    .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_cover_the_run_and_end_at_its_last_sample() {
        assert_eq!(frame_indices(0, MAX_FRAMES).1, Vec::<usize>::new());
        assert_eq!(frame_indices(5, MAX_FRAMES), (1, vec![0, 1, 2, 3, 4]));
        assert_eq!(frames_per_run(6), 2000);
        assert_eq!(frames_per_run(21), 571);
        let (s, v) = frame_indices(13_001, MAX_FRAMES);
        assert_eq!(s, 7);
        assert!(v.len() <= MAX_FRAMES + 1);
        assert_eq!(*v.last().unwrap(), 13_000);
        assert!(v.windows(2).all(|w| w[1] > w[0] && w[1] - w[0] <= s));
    }

    #[test]
    fn horizons_fall_on_frames_within_their_budget() {
        for (samples, runs) in [(13_624, 1), (1_400, 6), (1_400, 21), (5, 1)] {
            let h = horizon_sampling(samples, runs);
            let (stride, _) = frame_indices(samples, frames_per_run(runs));
            assert_eq!(
                h.every % stride,
                0,
                "{samples} {runs}: every frame of the page"
            );
            let recorded = samples.div_ceil(h.every);
            assert!(
                recorded <= h.max,
                "{samples} {runs}: {recorded} > {}",
                h.max
            );
            assert!(h.max <= MAX_HORIZONS + 1);
            assert!(runs * (h.max - 1) <= TOTAL_HORIZONS.max(runs * MIN_HORIZONS));
        }
    }
}
