//! The meshes in the page: decimated by vertex clustering and quantized to 16 bits.
//!
//! Vertex clustering (Rossignac and Borrel, "Multi-resolution 3D approximations for rendering
//! complex scenes", 1993): the mesh's bounding box is cut into a grid of cubic cells, the
//! vertices of a cell merge into their mean, and triangles whose corners fall into fewer than
//! three cells vanish. The grid is coarsened until the mesh has at most its share of
//! [`TOTAL_TRIANGLES`] and fewer than 65 536 vertices (16-bit indices). Positions are then
//! quantized to 16 bits per axis in the mesh's bounding box (at most `extent / 65 535`, a few
//! µm on an arm's link) and base64-encoded; the page computes per-face normals.

use super::tri_mesh::TriMesh;
use super::visuals::Visuals;
use crate::output::report::base64;
use serde_json::{json, Value};
use std::collections::{HashMap, HashSet};

/// Triangles of all the robot's meshes together in the page: about 9 bytes each (three 16-bit
/// indices and half a vertex), ≈ 130 KB of base64 for the UR5; 24 000 halved the UR5's
/// frame rate in headless Chromium (SwiftShader: 30 against 60 fps) for no visible gain.
pub const TOTAL_TRIANGLES: usize = 12_000;

/// Fewest triangles a mesh keeps when the budget is shared (a small link stays recognisable).
pub const MIN_TRIANGLES: usize = 300;

/// Largest number of vertices of one mesh (16-bit indices).
pub const MAX_VERTICES: usize = 65_535;

/// The mesh after vertex clustering on a grid of cubic cells of edge `cell` from `lo`.
pub fn cluster(m: &TriMesh, lo: [f64; 3], cell: f64) -> TriMesh {
    let mut cells: HashMap<[i64; 3], u32> = HashMap::new();
    let mut sums: Vec<([f64; 3], f64)> = Vec::new();
    let mut id = vec![u32::MAX; m.positions.len()];
    for t in &m.triangles {
        for &v in t {
            let v = v as usize;
            if id[v] != u32::MAX {
                continue;
            }
            let p = m.positions[v];
            let key = [0, 1, 2].map(|c| ((p[c] - lo[c]) / cell).floor() as i64);
            let k = *cells.entry(key).or_insert_with(|| {
                sums.push(([0.0; 3], 0.0));
                (sums.len() - 1) as u32
            });
            let s = &mut sums[k as usize];
            for (sum, x) in s.0.iter_mut().zip(p) {
                *sum += x;
            }
            s.1 += 1.0;
            id[v] = k;
        }
    }
    let mut seen = HashSet::new();
    let mut triangles = Vec::new();
    for t in &m.triangles {
        let [a, b, c] = t.map(|v| id[v as usize]);
        if a == b || b == c || a == c {
            continue;
        }
        // The same triangle twice (same orientation): once.
        let r = if a < b && a < c {
            [a, b, c]
        } else if b < c {
            [b, c, a]
        } else {
            [c, a, b]
        };
        if seen.insert(r) {
            triangles.push([a, b, c]);
        }
    }
    TriMesh {
        positions: sums
            .iter()
            .map(|(s, n)| [s[0] / n, s[1] / n, s[2] / n])
            .collect(),
        triangles,
    }
}

/// The mesh with at most `budget` triangles and [`MAX_VERTICES`] vertices: clustered on the
/// 16-bit grid first (merges coincident corners, e.g. of an STL's separate triangles), then
/// on coarser grids until it fits.
pub fn decimate(m: &TriMesh, budget: usize) -> TriMesh {
    let Some((lo, hi)) = m.bounds() else {
        return TriMesh::default();
    };
    let extent = (0..3).map(|c| hi[c] - lo[c]).fold(0.0, f64::max);
    if extent <= 0.0 {
        return TriMesh::default();
    }
    let mut cells = 65_535.0f64;
    let mut out = cluster(m, lo, extent / cells);
    while (out.triangles.len() > budget || out.positions.len() > MAX_VERTICES) && cells > 2.0 {
        // A surface's triangles grow as the square of the grid's resolution.
        let shrink = (budget as f64 / out.triangles.len().max(1) as f64)
            .sqrt()
            .clamp(0.3, 0.9);
        cells = (cells.min(2048.0) * shrink).max(2.0);
        out = cluster(m, lo, extent / cells);
    }
    // Only the vertices that triangles use.
    let mut used = vec![u32::MAX; out.positions.len()];
    let mut positions = Vec::new();
    for t in &mut out.triangles {
        for v in t.iter_mut() {
            if used[*v as usize] == u32::MAX {
                used[*v as usize] = positions.len() as u32;
                positions.push(out.positions[*v as usize]);
            }
            *v = used[*v as usize];
        }
    }
    out.positions = positions;
    out
}

/// The page's meshes: per body mesh `{"body", "color", "lo", "hi", "v", "i", "source"}` with
/// `v` the base64 of little-endian 16-bit positions (`lo + (hi − lo) · k / 65535` per axis)
/// and `i` of 16-bit triangle corners; `source` the triangle count before decimation.
pub fn meshes_json(v: &Visuals) -> Value {
    let total: usize = v.meshes.iter().map(|m| m.mesh.triangles.len()).sum();
    let meshes: Vec<Value> = v
        .meshes
        .iter()
        .filter_map(|bm| {
            let n = bm.mesh.triangles.len();
            let share = (TOTAL_TRIANGLES as f64 * n as f64 / total.max(1) as f64) as usize;
            let budget = if total <= TOTAL_TRIANGLES {
                n
            } else {
                share.max(MIN_TRIANGLES)
            };
            let d = decimate(&bm.mesh, budget);
            let (lo, hi) = d.bounds()?;
            let mut vb = Vec::with_capacity(6 * d.positions.len());
            for p in &d.positions {
                for c in 0..3 {
                    let span = hi[c] - lo[c];
                    let k = if span > 0.0 {
                        ((p[c] - lo[c]) / span * 65_535.0)
                            .round()
                            .clamp(0.0, 65_535.0) as u16
                    } else {
                        0
                    };
                    vb.extend_from_slice(&k.to_le_bytes());
                }
            }
            let ib: Vec<u8> = d
                .triangles
                .iter()
                .flatten()
                .flat_map(|&i| (i as u16).to_le_bytes())
                .collect();
            Some(json!({
                "body": bm.body,
                "color": bm.color,
                "lo": lo,
                "hi": hi,
                "v": base64(&vb),
                "i": base64(&ib),
                "source": n,
            }))
        })
        .collect();
    json!(meshes)
}

#[cfg(test)]
mod tests {
    use super::super::visuals::{cuboid, sphere};
    use super::*;

    #[test]
    fn clustering_meets_the_budget_and_keeps_the_bounds() {
        // A fine sphere: 24 × 12 × 2 triangles, then 4 of them merged.
        let mut s = sphere(0.1, 0.0);
        for _ in 0..3 {
            let more = s.clone();
            s.append(&more);
        }
        let d = decimate(&s, 100_000);
        // Coincident corners merge, duplicate triangles go, the poles' slivers vanish.
        assert!(d.triangles.len() < 24 * 12 * 2, "{}", d.triangles.len());
        assert!(d.triangles.len() >= 24 * 10 * 2, "{}", d.triangles.len());
        for budget in [200, 60] {
            let d = decimate(&s, budget);
            assert!(
                d.triangles.len() <= budget,
                "{budget}: {}",
                d.triangles.len()
            );
            assert!(d.triangles.len() >= 8, "{budget}: {}", d.triangles.len());
            let (lo, hi) = d.bounds().unwrap();
            // Cluster means lie inside the sphere's box and span most of it.
            for c in 0..3 {
                assert!(lo[c] >= -0.1 - 1e-12 && hi[c] <= 0.1 + 1e-12);
                assert!(hi[c] - lo[c] > 0.1, "{budget}: axis {c} collapsed");
            }
        }
        // A box survives whole: its 8 corners are in 8 cells.
        let b = decimate(&cuboid([0.1, 0.2, 0.3]), 12);
        assert_eq!((b.positions.len(), b.triangles.len()), (8, 12));
    }
}
