//! The program as read, as JSON (`ofmpc inspect program`): units mm,
//! machine coordinates (the programmed point plus the active work and G92 offsets: where the
//! tool tip goes).

use nalgebra::Vector3;
use ofmpc::gcode::{MoveKind, Program};
use ofmpc::geometry::Segment;
use serde_json::{json, Value};

fn mm(v: Vector3<f64>) -> [f64; 3] {
    [v.x * 1e3, v.y * 1e3, v.z * 1e3]
}

/// `{"units": "mm", "start", "tool_length_mm", "moves", "events", "messages", "warnings"}`.
///
/// `from` is where the tool was before the program (m): when the program's start point
/// differs, the first move is a rapid from there to it (as a CNC's first `G00`), so that the
/// moves compare one for one with another interpreter's.
pub fn program_json(p: &Program, from: Vector3<f64>) -> Value {
    program_json_with_tool_axis(p, from, None)
}

/// [`program_json`] for a program read with [`ofmpc::gcode::ParseOptions::tool_axis`]
/// `tool_axis` (`None`: −Z, LinuxCNC's): before the first motion the tip is the tool length
/// then in force along that axis beyond `from`, and the first move is a rapid only when the
/// start point differs from there (a `G43` moves no axis).
pub fn program_json_with_tool_axis(
    p: &Program,
    from: Vector3<f64>,
    tool_axis: Option<Vector3<f64>>,
) -> Value {
    let mut moves = Vec::with_capacity(p.moves.len() + 1);
    let tip = from + p.start_tool_length * tool_axis.unwrap_or(-Vector3::z());
    if (p.start - tip).norm() > 0.0 {
        moves.push(json!({"line": p.start_line, "kind": "rapid", "end": mm(p.start)}));
    }
    for m in &p.moves {
        moves.push(match &m.kind {
            MoveKind::Dwell { seconds } => json!({"line": m.line, "kind": "dwell", "seconds": seconds}),
            MoveKind::Path { segment, feed, .. } => {
                let mut o = json!({
                    "line": m.line,
                    "kind": if feed.is_none() && matches!(segment, Segment::Line { .. }) { "rapid" } else { "feed" },
                    "end": mm(segment.end()),
                    "feed_mm_s": feed.map(|f| f * 1e3),
                });
                if let Segment::Arc { center, plane, sweep, .. } = segment {
                    o["kind"] = json!("arc");
                    o["center"] = json!(mm(*center));
                    let (_, _, w) = plane.basis();
                    o["normal"] = json!([w.x, w.y, w.z]);
                    o["turns"] = json!(sweep / std::f64::consts::TAU);
                }
                o
            }
        });
    }
    let events: Vec<Value> = p
        .events
        .iter()
        .map(|e| {
            let words: serde_json::Map<String, Value> = e
                .words
                .iter()
                .map(|(c, v)| (c.to_string(), json!(v)))
                .collect();
            json!({"line": e.line, "code": e.code, "words": words, "after_moves": e.after_moves})
        })
        .collect();
    let messages: Vec<Value> = p
        .messages
        .iter()
        .map(|m| json!({"line": m.line, "kind": m.kind, "text": m.text}))
        .collect();
    let warnings: Vec<String> = p.warnings.iter().map(|w| w.to_string()).collect();
    json!({
        "units": "mm",
        "start": mm(from),
        "tool_length_mm": p.tool_length * 1e3,
        "moves": moves,
        "events": events,
        "messages": messages,
        "warnings": warnings,
    })
}
