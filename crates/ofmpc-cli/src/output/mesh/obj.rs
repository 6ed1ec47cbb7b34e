//! Wavefront OBJ files: `v x y z` vertices and `f a b c …` faces (indices from 1, negative
//! ones counted back from the last vertex, `a/t/n` forms; polygons split into fans). Other
//! statements (normals, texture coordinates, groups, materials) are skipped.

use super::tri_mesh::{MeshError, TriMesh, MAX_TRIANGLES};

/// Parses an OBJ document (`name`: the file, for messages).
pub fn parse(text: &str, name: &str) -> Result<TriMesh, MeshError> {
    let mut m = TriMesh::default();
    for (i, line) in text.lines().enumerate() {
        let bad = |what: &str| MeshError::Malformed {
            path: name.to_string(),
            what: format!(
                "line {}: {what}: {:?}",
                i + 1,
                ofmpc::input::quote(line.trim(), ofmpc::input::QUOTE_CHARS)
            ),
        };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let v: Vec<f64> = words
                    .take(3)
                    .map(|w| w.parse::<f64>().ok().filter(|x| x.is_finite()))
                    .collect::<Option<_>>()
                    .ok_or_else(|| bad("a vertex is \"v x y z\""))?;
                let [x, y, z] = v[..] else {
                    return Err(bad("a vertex is \"v x y z\""));
                };
                m.positions.push([x, y, z]);
            }
            Some("f") => {
                let n = m.positions.len() as i64;
                let idx: Vec<u32> = words
                    .map(|w| {
                        let k: i64 = w.split('/').next()?.parse().ok()?;
                        let k = if k < 0 { n + k } else { k - 1 };
                        (0..n).contains(&k).then_some(k as u32)
                    })
                    .collect::<Option<_>>()
                    .ok_or_else(|| bad("a face's index is not a vertex defined above"))?;
                for j in 1..idx.len().saturating_sub(1) {
                    m.triangles.push([idx[0], idx[j], idx[j + 1]]);
                }
                if m.triangles.len() > MAX_TRIANGLES {
                    return Err(bad("too many triangles"));
                }
            }
            _ => {}
        }
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quads_split_and_negative_indices_count_back() {
        let m = parse(
            "# a quad\nv 0 0 0\nv 1 0 0\nv 1 2 0\nv 0 2 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\nf -4 -3 -2\n",
            "q.obj",
        )
        .unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 1, 2]]);
        assert_eq!(m.bounds(), Some(([0.0; 3], [1.0, 2.0, 0.0])));
        let e = parse("v 0 0 0\nf 1 2 3\n", "bad.obj").unwrap_err();
        assert!(e.to_string().contains("line 2"), "{e}");
        // A huge bad line is quoted by its first few dozen characters only (issue #36).
        let long = format!("v 0 0 0\nf {}\n", "9".repeat(100_000));
        let e = parse(&long, "long.obj").unwrap_err().to_string();
        assert!(e.len() < 200 && e.contains("(100002 characters)"), "{e}");
    }
}
