//! STL files, binary and ASCII (the format of 3D Systems, 1989: "StereoLithography Interface
//! Specification"). Binary: an 80-byte header, a little-endian `u32` triangle count, then
//! 50 bytes a triangle (normal, three vertices as `f32`, a 2-byte attribute). ASCII:
//! `solid … facet normal … outer loop vertex x y z (×3) endloop endfacet … endsolid`.
//! A file is binary when its size is `84 + 50·count` (binary files may also start with
//! `solid`); the normals are not read (the page computes per-face normals).

use super::tri_mesh::{MeshError, TriMesh, MAX_TRIANGLES};

/// Parses an STL file's bytes (`name`: the file, for messages).
pub fn parse(bytes: &[u8], name: &str) -> Result<TriMesh, MeshError> {
    let binary_count = (bytes.len() >= 84)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize);
    match binary_count {
        Some(n) if 84 + 50 * n as u64 == bytes.len() as u64 && n <= MAX_TRIANGLES => {
            Ok(binary(bytes, n))
        }
        _ if bytes.trim_ascii_start().starts_with(b"solid") => ascii(bytes, name),
        _ => Err(MeshError::Malformed {
            path: name.to_string(),
            what: format!(
                "neither a binary STL (size {} is not 84 + 50 × the triangle count {}) nor an \
                 ASCII one (it does not start with \"solid\")",
                bytes.len(),
                binary_count.unwrap_or(0)
            ),
        }),
    }
}

fn binary(bytes: &[u8], n: usize) -> TriMesh {
    let mut m = TriMesh {
        positions: Vec::with_capacity(3 * n),
        triangles: Vec::with_capacity(n),
    };
    let f = |o: usize| {
        f64::from(f32::from_le_bytes([
            bytes[o],
            bytes[o + 1],
            bytes[o + 2],
            bytes[o + 3],
        ]))
    };
    for t in 0..n {
        let o = 84 + 50 * t + 12;
        let base = m.positions.len() as u32;
        for v in 0..3 {
            let p = o + 12 * v;
            m.positions.push([f(p), f(p + 4), f(p + 8)]);
        }
        m.triangles.push([base, base + 1, base + 2]);
    }
    m
}

fn ascii(bytes: &[u8], name: &str) -> Result<TriMesh, MeshError> {
    let text = String::from_utf8_lossy(bytes);
    let mut m = TriMesh::default();
    let mut loop_start = 0usize;
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("outer") => loop_start = m.positions.len(),
            Some("vertex") => {
                let mut p = [0.0; 3];
                for c in &mut p {
                    *c = words
                        .next()
                        .and_then(|w| w.parse::<f64>().ok())
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| MeshError::Malformed {
                            path: name.to_string(),
                            what: format!(
                                "line {}: expected \"vertex x y z\" with three numbers, found {:?}",
                                i + 1,
                                line.trim()
                            ),
                        })?;
                }
                m.positions.push(p);
            }
            Some("endloop") => {
                // A loop of k ≥ 3 vertices: a fan of k − 2 triangles.
                let k = m.positions.len() - loop_start;
                for j in 1..k.saturating_sub(1) {
                    let a = loop_start as u32;
                    m.triangles.push([a, a + j as u32, a + j as u32 + 1]);
                }
                if m.triangles.len() > MAX_TRIANGLES {
                    return Err(MeshError::Malformed {
                        path: name.to_string(),
                        what: format!("more than {MAX_TRIANGLES} triangles"),
                    });
                }
            }
            _ => {}
        }
    }
    Ok(m)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The 12 triangles of the cube `[0, s]³` (two a face), as (a, b, c) corners.
    pub(crate) fn cube(s: f64) -> Vec<[[f64; 3]; 3]> {
        let faces: [[usize; 4]; 6] = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let corner = |i: usize| {
            [
                s * (i & 1) as f64,
                s * ((i >> 1) & 1) as f64,
                s * ((i >> 2) & 1) as f64,
            ]
        };
        faces
            .iter()
            .flat_map(|f| {
                [
                    [corner(f[0]), corner(f[1]), corner(f[2])],
                    [corner(f[0]), corner(f[2]), corner(f[3])],
                ]
            })
            .collect()
    }

    /// A binary STL of the triangles.
    pub(crate) fn binary_stl(tris: &[[[f64; 3]; 3]]) -> Vec<u8> {
        let mut b = b"solid but binary: the header may say so".to_vec();
        b.resize(80, b' ');
        b.extend_from_slice(&(tris.len() as u32).to_le_bytes());
        for t in tris {
            b.extend_from_slice(&[0u8; 12]);
            for v in t {
                for c in v {
                    b.extend_from_slice(&(*c as f32).to_le_bytes());
                }
            }
            b.extend_from_slice(&[0u8; 2]);
        }
        b
    }

    /// An ASCII STL of the triangles.
    pub(crate) fn ascii_stl(tris: &[[[f64; 3]; 3]]) -> String {
        let mut s = String::from("solid cube\n");
        for t in tris {
            s.push_str("  facet normal 0 0 0\n    outer loop\n");
            for v in t {
                s.push_str(&format!("      vertex {:e} {} {}\n", v[0], v[1], v[2]));
            }
            s.push_str("    endloop\n  endfacet\n");
        }
        s.push_str("endsolid cube\n");
        s
    }

    #[test]
    fn binary_and_ascii_cubes_read_alike() {
        let tris = cube(0.25);
        for m in [
            parse(&binary_stl(&tris), "b.stl").unwrap(),
            parse(ascii_stl(&tris).as_bytes(), "a.stl").unwrap(),
        ] {
            assert_eq!(m.triangles.len(), 12);
            assert_eq!(m.positions.len(), 36);
            assert_eq!(m.bounds(), Some(([0.0; 3], [0.25; 3])));
            for (t, want) in m.triangles.iter().zip(&tris) {
                for c in 0..3 {
                    assert_eq!(m.positions[t[c] as usize], want[c]);
                }
            }
        }
    }

    #[test]
    fn truncated_or_garbled_files_are_errors_with_their_place() {
        let mut b = binary_stl(&cube(1.0));
        b.truncate(b.len() - 7);
        b[0] = b'x';
        let e = parse(&b, "t.stl").unwrap_err();
        assert!(e.to_string().contains("not 84 + 50"), "{e}");
        let e = parse(b"solid x\nfacet\nouter loop\nvertex 1 2 nope\n", "g.stl").unwrap_err();
        assert!(e.to_string().contains("line 4"), "{e}");
    }
}
