//! Where one's own robot runs the paper's program ([`place_paper_program`]): a start pose
//! inside the limits and away from singularities, the program's work offset moved to where
//! that pose reaches, the tool held as at the start pose, and a path speed the joints'
//! speed limits allow. What `ofmpc init robot` writes, so that its scenario runs at once.

use crate::error::ScenarioError;
use crate::file::ScenarioFile;
use crate::resolve::{load_robot_section, Scenario};
use nalgebra::{Rotation3, Vector3};
use ofmpc::dynamics::{flange_jacobian, Workspace};
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::robot::Robot;

/// The work-offset line of the built-in paper program, replaced by the placement's.
const PAPER_OFFSET_LINE: &str = "G10 L2 P1 X150 Y0 Z-250";
/// The centre of the paper program's arcs (program coordinates, mm): placed at the start
/// pose's tool position.
const PAPER_CENTRE_MM: [f64; 3] = [430.0, 0.0, 400.0];
/// Start poses scored (deterministic samples within the limits).
const SAMPLES: usize = 600;
/// Best-scored start poses planned in full before giving up.
const TRIED: usize = 16;
/// Path speeds (m/s) tried in turn for each start pose, fastest first.
const SPEEDS_M_S: [f64; 3] = [0.5, 0.25, 0.1];

/// The paper's program placed for a robot: `start_q` (`[robot] start_q`), `max_speed_m_s`
/// (`[timing] max_speed_m_s`) and `program`, the paper's program with its work offset
/// `offset_mm` (written as a file beside the scenario). The tool keeps the start pose's
/// orientation (`rpy_deg`), the default of `[orientation]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// Start pose (rad; m for a prismatic joint).
    pub start_q: Vec<f64>,
    /// Tool orientation held along the path: roll, pitch, yaw (degrees, base frame).
    pub rpy_deg: [f64; 3],
    /// The program's G54 work offset (mm, base frame).
    pub offset_mm: [f64; 3],
    /// Path speed of the program's moves (m/s).
    pub max_speed_m_s: f64,
    /// The program text: the paper's, with the work offset `offset_mm`.
    pub program: String,
    /// Whether the paper's own work offset and start pose already run (then `program`
    /// is the paper's text unchanged, `start_q` is the robot's default start pose).
    pub as_published: bool,
}

/// The paper's program text with the work offset `offset_mm` (mm) and its path scaled by
/// `scale` about the centre of its arcs (1: as published, a 400 mm circle).
pub fn paper_program_at(offset_mm: [f64; 3], scale: f64) -> String {
    let [x, y, z] = offset_mm.map(|v| (v * 10.0).round() / 10.0);
    let note = if scale == 1.0 {
        String::new()
    } else {
        format!("\n(The path is the paper's scaled by {scale} about the centre of its arcs: this arm reaches it.)")
    };
    let placed = PAPER_TABLE1.replace(
        PAPER_OFFSET_LINE,
        &format!("G10 L2 P1 X{x} Y{y} Z{z} (placed by `ofmpc init robot` for this robot){note}"),
    );
    if scale == 1.0 {
        return placed;
    }
    let mut out = String::new();
    for line in placed.lines() {
        if line.starts_with('N') && line.contains('X') {
            out.push_str(&scaled_line(line, scale));
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    out
}

/// A motion line of the paper's program with X, Y, Z scaled by `scale` about
/// [`PAPER_CENTRE_MM`] and I, J, K (arc centre offsets) by `scale`; a comment kept as is.
fn scaled_line(line: &str, scale: f64) -> String {
    let (code, comment) = line.split_at(line.find('(').unwrap_or(line.len()));
    let words: Vec<String> = code
        .split_whitespace()
        .map(|w| {
            let (letter, number) = w.split_at(1);
            let centre = match letter {
                "X" => PAPER_CENTRE_MM[0],
                "Y" => PAPER_CENTRE_MM[1],
                "Z" => PAPER_CENTRE_MM[2],
                "I" | "J" | "K" => 0.0,
                _ => return w.to_string(),
            };
            match number.parse::<f64>() {
                Ok(v) => format!("{letter}{}", centre + scale * (v - centre)),
                Err(_) => w.to_string(),
            }
        })
        .collect();
    let mut s = words.join(" ");
    if !comment.is_empty() {
        s.push(' ');
        s.push_str(comment);
    }
    s
}

/// Places the paper's program for the robot of `base` (its `[robot]` section: model,
/// drives, tip, tool centre point; the rest as in `base`): as published when the robot's own
/// start pose runs it and is not singular; else from the best-scored start poses (far from
/// singularities and limits), with the program's arcs centred near the start pose's tool
/// position and the tool held as there, at the fastest of 0.5, 0.25, 0.1 m/s the joint
/// limits allow, at full size or, for an arm too short, at half size. Each candidate is
/// resolved as a run resolves it, so the placement returned runs; one the joint limits slow
/// to more than [`SLOW_FACTOR`] times the paper's duration is kept only when no other runs.
/// The error is the last candidate's when none runs.
pub fn place_paper_program(base: &ScenarioFile) -> Result<Placement, ScenarioError> {
    let (robot, _) = load_robot_section(&base.robot)?;
    let name = "paper-table1.gcode (built in)".to_string();
    // As published: the robot's own start pose, the paper's work offset and speed.
    let (published, mut last) = match Scenario::resolve_program(base, name, PAPER_TABLE1) {
        Ok(s) => {
            let p = Placement {
                start_q: robot.start_q().to_vec(),
                rpy_deg: [0.0; 3],
                offset_mm: [150.0, 0.0, -250.0],
                max_speed_m_s: s.file.timing.max_speed_m_s,
                program: PAPER_TABLE1.to_string(),
                as_published: true,
            };
            if not_singular(&robot, robot.start_q()) {
                return Ok(p);
            }
            (Some(p), None)
        }
        Err(e) => (None, Some(e)),
    };
    let candidates = start_candidates(&robot);
    let mut slow: Option<(f64, Placement)> = None;
    for scale in SCALES {
        for q in &candidates {
            for reach in CENTRE_REACH {
                let Some(p) = placement_at(&robot, q, reach, scale) else {
                    continue;
                };
                for speed in SPEEDS_M_S {
                    let placed = Placement {
                        max_speed_m_s: speed,
                        ..p.clone()
                    };
                    match resolve_placed(base, &placed) {
                        Ok(d) if d <= SLOW_FACTOR * PAPER_DURATION_S * 0.5 / speed => {
                            return Ok(placed)
                        }
                        Ok(d) => {
                            if slow.as_ref().is_none_or(|(best, _)| d < *best) {
                                slow = Some((d, placed));
                            }
                        }
                        Err(e) => last = Some(e),
                    }
                }
            }
        }
        if let Some((_, p)) = slow {
            return Ok(p);
        }
    }
    match (published, last) {
        (Some(p), _) => Ok(p),
        (None, Some(e)) => Err(e),
        (None, None) => Err(ScenarioError::NoControllers),
    }
}

/// Path scales tried in turn: as published, then half size.
const SCALES: [f64; 2] = [1.0, 0.5];
/// Duration (s) of the paper's program at 0.5 m/s on the IRB 140.
const PAPER_DURATION_S: f64 = 11.6;
/// A placement whose joint limits stretch the path's duration beyond this factor of
/// `PAPER_DURATION_S` (at the same speed) is kept only when no other runs.
pub const SLOW_FACTOR: f64 = 1.5;

/// Whether the Jacobian at `q` has full rank, its smallest singular value at least 0.01.
fn not_singular(robot: &Robot, q: &[f64]) -> bool {
    let mut ws = Workspace::new(robot);
    flange_jacobian(robot, &mut ws, q)
        .map(|j| j.clone().svd(false, false).singular_values.min() >= 0.01)
        .unwrap_or(false)
}

/// Resolves `base` with the placement `p` as a run would; the path's duration (s).
fn resolve_placed(base: &ScenarioFile, p: &Placement) -> Result<f64, ScenarioError> {
    let mut f = base.clone();
    f.robot.start_q = Some(p.start_q.clone());
    f.timing.max_speed_m_s = p.max_speed_m_s;
    Scenario::resolve_program(&f, "paper-table1.gcode (placed)".into(), &p.program)
        .map(|s| s.experiment.reference.duration())
}

/// Where the program's arcs are centred, as a fraction of the horizontal distance of the
/// start pose's tool from the base axis (same height): at the tool, then nearer the base
/// (a short arm reaches the program's 400 mm square only there).
const CENTRE_REACH: [f64; 3] = [1.0, 0.75, 0.5];

/// The placement of the program's arcs at the tool position of `q`, its horizontal distance
/// from the base axis scaled by `reach`, the tool held as at `q`, the path scaled by `scale`.
fn placement_at(robot: &Robot, q: &[f64], reach: f64, scale: f64) -> Option<Placement> {
    let mut ws = Workspace::new(robot);
    flange_jacobian(robot, &mut ws, q).ok()?;
    let pose = ws.flange;
    let (r, p, y) = Rotation3::from_matrix_unchecked(pose.rot).euler_angles();
    let centre = Vector3::from(PAPER_CENTRE_MM);
    let at = Vector3::new(pose.pos.x * reach, pose.pos.y * reach, pose.pos.z);
    let offset = at * 1e3 - centre;
    let offset_mm = [offset.x, offset.y, offset.z];
    Some(Placement {
        start_q: q.to_vec(),
        rpy_deg: [r.to_degrees(), p.to_degrees(), y.to_degrees()],
        offset_mm,
        max_speed_m_s: SPEEDS_M_S[0],
        program: paper_program_at(offset_mm, scale),
        as_published: false,
    })
}

/// Start poses worth planning, best first: `SAMPLES` deterministic points within the
/// limits (a joint without limits within ±π; 4 decimals) scored by `score`, the best
/// `TRIED`.
pub fn start_candidates(robot: &Robot) -> Vec<Vec<f64>> {
    let (lo, hi) = (robot.lower_limits(), robot.upper_limits());
    let n = robot.dof();
    let mut ws = Workspace::new(robot);
    let mut scored: Vec<(f64, Vec<f64>)> = (0..SAMPLES)
        .filter_map(|k| {
            let q: Vec<f64> = (0..n)
                .map(|j| {
                    let (a, b) = (
                        lo[j].max(-std::f64::consts::PI),
                        hi[j].min(std::f64::consts::PI),
                    );
                    // Halton-like: the k-th point of a radical inverse in base prime(j),
                    // shrunk to the middle 80 % of the range.
                    let v = a
                        + (b - a) * (0.1 + 0.8 * radical_inverse(k + 1, PRIMES[j % PRIMES.len()]));
                    // Rounded as a scenario file writes it, so the pose tried is the pose run.
                    (v * 1e4).round() / 1e4
                })
                .collect();
            score(robot, &mut ws, &q, &lo, &hi).map(|s| (s, q))
        })
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    scored.into_iter().take(TRIED).map(|(_, q)| q).collect()
}

/// Bases of the start-pose samples.
const PRIMES: [usize; 8] = [2, 3, 5, 7, 11, 13, 17, 19];

/// The radical inverse of `k` in `base`, in [0, 1).
fn radical_inverse(mut k: usize, base: usize) -> f64 {
    let (mut inv, mut f) = (0.0, 1.0 / base as f64);
    while k > 0 {
        inv += f * (k % base) as f64;
        k /= base;
        f /= base as f64;
    }
    inv
}

/// The score of a start pose (larger is better): the smallest singular value of the
/// Jacobian (distance from a singularity) times the smallest distance from a joint limit (as a
/// fraction of the range, at most 0.25), for poses whose tool is above the base and at least
/// 0.2 m from its vertical axis (where the program's square fits beside the arm); `None` for
/// others.
fn score(robot: &Robot, ws: &mut Workspace, q: &[f64], lo: &[f64], hi: &[f64]) -> Option<f64> {
    let j = flange_jacobian(robot, ws, q).ok()?.clone();
    let p = ws.flange.pos;
    if p.z < 0.0 || p.xy().norm() < 0.2 {
        return None;
    }
    let sigma = j.svd(false, false).singular_values.min();
    let margin = q
        .iter()
        .zip(lo.iter().zip(hi))
        .map(|(&v, (&a, &b))| {
            if a.is_finite() && b.is_finite() && b > a {
                ((v - a).min(b - v) / (b - a)).min(0.25)
            } else {
                0.25
            }
        })
        .fold(f64::INFINITY, f64::min);
    Some(sigma * margin)
}
