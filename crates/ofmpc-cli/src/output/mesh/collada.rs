//! Collada (DAE) files: the triangles of `<library_geometries>` placed by the nodes of the
//! scene (COLLADA 1.4.1 specification, Khronos, 2008: ch. 5 `<mesh>`, `<vertices>`,
//! `<triangles>`, `<polylist>`, `<polygons>`; `<node>` transforms `<matrix>` (row-major),
//! `<translate>`, `<rotate>` (axis, degrees), `<scale>`, applied in the order written;
//! `<asset><unit meter>` and `<up_axis>`).
//!
//! The result is in metres with z up: positions are multiplied by `<unit meter>` and, for
//! `Y_UP` (`X_UP`), turned by +90° about x (−90° about y) so that the file's up axis becomes
//! z, as URDF viewers do. A file without a `<visual_scene>` contributes every geometry as
//! it stands. Materials and normals are not read (the page computes per-face normals).

use super::tri_mesh::{MeshError, TriMesh, MAX_TRIANGLES};
use nalgebra::{Matrix4, Rotation3, Unit, Vector3};
use quick_xml::events::{BytesStart, Event};
use std::collections::HashMap;

/// An element of the document: local name, attributes, text and children.
#[derive(Debug, Default)]
struct Element {
    name: String,
    attrs: Vec<(String, String)>,
    text: String,
    children: Vec<Element>,
}

impl Element {
    fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
    fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }
    fn all<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
}

fn element(e: &BytesStart<'_>) -> Element {
    Element {
        name: String::from_utf8_lossy(e.local_name().as_ref()).into_owned(),
        attrs: e
            .attributes()
            .flatten()
            .map(|a| {
                (
                    String::from_utf8_lossy(a.key.local_name().as_ref()).into_owned(),
                    String::from_utf8_lossy(&a.value).into_owned(),
                )
            })
            .collect(),
        ..Element::default()
    }
}

/// A malformed-document error for `name` at byte `pos` of `text`, said as its line.
fn malformed_at(text: &str, name: &str, pos: u64, what: String) -> MeshError {
    let pos = (pos as usize).min(text.len());
    let line = text.as_bytes()[..pos]
        .iter()
        .filter(|&&c| c == b'\n')
        .count()
        + 1;
    MeshError::Malformed {
        path: name.to_string(),
        what: format!("line {line}: {what}"),
    }
}

/// The most elements a Collada document may hold: far above any mesh file (the numbers
/// are text inside a few elements), far below what would exhaust memory (issue #36).
const MAX_ELEMENTS: usize = 1_000_000;

/// The `<COLLADA>` root of a document read to its end (`stack`: the open elements, only the
/// document's own left).
fn root(mut stack: Vec<Element>, text: &str, name: &str) -> Result<Element, MeshError> {
    let bad = |pos: u64, what: String| malformed_at(text, name, pos, what);
    let mut top = stack.pop().unwrap_or_default();
    if !stack.is_empty() {
        return Err(bad(
            text.len() as u64,
            "the document ends inside an element".into(),
        ));
    }
    top.children
        .pop()
        .filter(|c| c.name == "COLLADA")
        .ok_or_else(|| bad(0, "no <COLLADA> root element".into()))
}

/// The document's root element (an iterative build: no recursion on deep nesting, which is
/// refused past [`ofmpc::input::MAX_XML_DEPTH`] levels, as are more than [`MAX_ELEMENTS`]
/// elements; dropping the tree recurses, so its depth must be bounded).
fn document(text: &str, name: &str) -> Result<Element, MeshError> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut stack = vec![Element::default()];
    let bad = |pos: u64, what: String| malformed_at(text, name, pos, what);
    let mut elements = 0usize;
    loop {
        let ev = reader.read_event().map_err(|e| {
            bad(
                reader.buffer_position(),
                format!("not well-formed XML: {e}"),
            )
        })?;
        elements += usize::from(matches!(ev, Event::Start(_) | Event::Empty(_)));
        if elements > MAX_ELEMENTS {
            return Err(bad(
                reader.buffer_position(),
                format!("more than {MAX_ELEMENTS} elements: not a mesh file this reader takes"),
            ));
        }
        match ev {
            Event::Start(e) => {
                if stack.len() > ofmpc::input::MAX_XML_DEPTH {
                    return Err(bad(
                        reader.buffer_position(),
                        format!(
                            "elements nested more than {} deep (the limit): flatten the \
                             document's nodes",
                            ofmpc::input::MAX_XML_DEPTH
                        ),
                    ));
                }
                stack.push(element(&e));
            }
            Event::Empty(e) => {
                if let Some(top) = stack.last_mut() {
                    top.children.push(element(&e));
                }
            }
            Event::End(_) => {
                let done = stack.pop().filter(|_| !stack.is_empty()).ok_or_else(|| {
                    bad(
                        reader.buffer_position(),
                        "an end tag without its start".into(),
                    )
                })?;
                if let Some(top) = stack.last_mut() {
                    top.children.push(done);
                }
            }
            Event::Text(t) => {
                if let (Some(top), Ok(s)) = (stack.last_mut(), t.decode()) {
                    top.text.push_str(&s);
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    root(stack, text, name)
}

/// Numbers of a whitespace-separated list.
fn numbers<T: std::str::FromStr>(s: &str, what: &str, name: &str) -> Result<Vec<T>, MeshError> {
    s.split_ascii_whitespace()
        .map(|w| {
            w.parse().map_err(|_| MeshError::Malformed {
                path: name.to_string(),
                what: format!(
                    "<{what}>: {:?} is not a number",
                    ofmpc::input::quote(w, ofmpc::input::QUOTE_CHARS)
                ),
            })
        })
        .collect()
}

/// Parses a Collada document (`name`: the file, for messages).
pub fn parse(text: &str, name: &str) -> Result<TriMesh, MeshError> {
    let root = document(text, name)?;
    let mut geometries: HashMap<&str, &Element> = HashMap::new();
    for lib in root.all("library_geometries") {
        for g in lib.all("geometry") {
            if let (Some(id), Some(mesh)) = (g.attr("id"), g.child("mesh")) {
                geometries.insert(id, mesh);
            }
        }
    }
    let mut out = TriMesh::default();
    let mut cache: HashMap<&str, TriMesh> = HashMap::new();
    let mut place = |id: &str, m: &Matrix4<f64>, out: &mut TriMesh| -> Result<(), MeshError> {
        let Some((key, mesh)) = geometries.get_key_value(id) else {
            return Ok(());
        };
        if !cache.contains_key(key) {
            cache.insert(key, geometry(mesh, name)?);
        }
        let mut g = cache[key].clone();
        g.map(|p| {
            let v = m * nalgebra::Vector4::new(p[0], p[1], p[2], 1.0);
            [v[0], v[1], v[2]]
        });
        out.append(&g);
        if out.triangles.len() > MAX_TRIANGLES {
            return Err(MeshError::Malformed {
                path: name.to_string(),
                what: format!("more than {MAX_TRIANGLES} triangles"),
            });
        }
        Ok(())
    };
    match scene(&root) {
        Some(vs) => {
            let mut stack: Vec<(&Element, Matrix4<f64>)> =
                vs.all("node").map(|n| (n, Matrix4::identity())).collect();
            while let Some((node, parent)) = stack.pop() {
                let m = parent * node_transform(node, name)?;
                for ig in node.all("instance_geometry") {
                    if let Some(url) = ig.attr("url") {
                        place(url.trim_start_matches('#'), &m, &mut out)?;
                    }
                }
                stack.extend(node.all("node").map(|c| (c, m)));
            }
        }
        None => {
            let mut ids: Vec<&str> = geometries.keys().copied().collect();
            ids.sort_unstable();
            for id in ids {
                place(id, &Matrix4::identity(), &mut out)?;
            }
        }
    }
    to_metres_z_up(&root, &mut out);
    Ok(out)
}

/// The mesh in metres with z up: scaled by the document's `<asset><unit meter>` and turned
/// from its `<up_axis>` (default `Y_UP`).
fn to_metres_z_up(root: &Element, out: &mut TriMesh) {
    let asset = root.child("asset");
    let meter = asset
        .and_then(|a| a.child("unit"))
        .and_then(|u| u.attr("meter"))
        .and_then(|m| m.trim().parse::<f64>().ok())
        .filter(|m| m.is_finite() && *m > 0.0)
        .unwrap_or(1.0);
    let up = asset
        .and_then(|a| a.child("up_axis"))
        .map(|u| u.text.trim().to_ascii_uppercase())
        .unwrap_or_else(|| "Y_UP".into());
    // Units to metres, the up axis to z.
    let turn: [[f64; 3]; 3] = match up.as_str() {
        "X_UP" => [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
        "Z_UP" => [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        _ => [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
    };
    out.map(|p| {
        let r = |i: usize| meter * (turn[i][0] * p[0] + turn[i][1] * p[1] + turn[i][2] * p[2]);
        [r(0), r(1), r(2)]
    });
}

/// The visual scene drawn: the one `<scene><instance_visual_scene url>` names, else the first.
fn scene(root: &Element) -> Option<&Element> {
    let all: Vec<&Element> = root
        .all("library_visual_scenes")
        .flat_map(|l| l.all("visual_scene"))
        .collect();
    let wanted = root
        .child("scene")
        .and_then(|s| s.child("instance_visual_scene"))
        .and_then(|i| i.attr("url"))
        .map(|u| u.trim_start_matches('#'));
    wanted
        .and_then(|w| all.iter().find(|v| v.attr("id") == Some(w)).copied())
        .or_else(|| all.first().copied())
}

/// A node's transform: its transform elements multiplied in the order written.
fn node_transform(node: &Element, name: &str) -> Result<Matrix4<f64>, MeshError> {
    let mut m = Matrix4::identity();
    for c in &node.children {
        let v = || numbers::<f64>(&c.text, &c.name, name);
        let step = match c.name.as_str() {
            "matrix" => {
                let v = v()?;
                if v.len() != 16 {
                    return Err(MeshError::Malformed {
                        path: name.to_string(),
                        what: format!("<matrix> has {} numbers, not 16", v.len()),
                    });
                }
                Matrix4::from_row_slice(&v)
            }
            "translate" => match v()?.as_slice() {
                [x, y, z] => Matrix4::new_translation(&Vector3::new(*x, *y, *z)),
                _ => continue,
            },
            "scale" => match v()?.as_slice() {
                [x, y, z] => Matrix4::new_nonuniform_scaling(&Vector3::new(*x, *y, *z)),
                _ => continue,
            },
            "rotate" => match v()?.as_slice() {
                [x, y, z, deg] if Vector3::new(*x, *y, *z).norm() > 0.0 => {
                    Rotation3::from_axis_angle(
                        &Unit::new_normalize(Vector3::new(*x, *y, *z)),
                        deg.to_radians(),
                    )
                    .to_homogeneous()
                }
                _ => continue,
            },
            _ => continue,
        };
        m *= step;
    }
    Ok(m)
}

/// The positions a primitive's `VERTEX` input may name: each `<vertices id>` (its
/// `POSITION` input) and each `<source id>` of at least three values a point.
fn positions(mesh: &Element, name: &str) -> Result<HashMap<String, Vec<[f64; 3]>>, MeshError> {
    let mut sources: HashMap<String, Vec<[f64; 3]>> = HashMap::new();
    for s in mesh.all("source") {
        let (Some(id), Some(fa)) = (s.attr("id"), s.child("float_array")) else {
            continue;
        };
        let stride = s
            .child("technique_common")
            .and_then(|t| t.child("accessor"))
            .and_then(|a| a.attr("stride"))
            .and_then(|v| v.parse::<usize>().ok())
            .unwrap_or(3);
        if stride >= 3 {
            let v: Vec<f64> = numbers(&fa.text, "float_array", name)?;
            let p = v.chunks_exact(stride).map(|c| [c[0], c[1], c[2]]).collect();
            sources.insert(id.to_string(), p);
        }
    }
    let mut out = sources.clone();
    for v in mesh.all("vertices") {
        let pos = v
            .all("input")
            .find(|i| i.attr("semantic") == Some("POSITION"))
            .and_then(|i| i.attr("source"))
            .and_then(|s| sources.get(s.trim_start_matches('#')));
        if let (Some(id), Some(p)) = (v.attr("id"), pos) {
            out.insert(id.to_string(), p.clone());
        }
    }
    Ok(out)
}

/// The triangles of one `<mesh>`, in its own coordinates.
fn geometry(mesh: &Element, name: &str) -> Result<TriMesh, MeshError> {
    let positions = positions(mesh, name)?;
    let mut out = TriMesh::default();
    for prim in &mesh.children {
        if matches!(prim.name.as_str(), "triangles" | "polylist" | "polygons") {
            primitive(prim, &positions, name, &mut out)?;
        }
        if out.triangles.len() > MAX_TRIANGLES {
            return Err(MeshError::Malformed {
                path: name.to_string(),
                what: format!("more than {MAX_TRIANGLES} triangles"),
            });
        }
    }
    Ok(out)
}

/// The positions a primitive's `<input semantic="VERTEX">` names, with that input's offset and
/// the stride of the primitive's index lists (`(positions, offset, stride)`).
fn vertex_input<'p>(
    prim: &Element,
    positions: &'p HashMap<String, Vec<[f64; 3]>>,
    name: &str,
) -> Result<(&'p [[f64; 3]], usize, usize), MeshError> {
    let bad = |what: String| MeshError::Malformed {
        path: name.to_string(),
        what,
    };
    let inputs: Vec<&Element> = prim.all("input").collect();
    let offset = |i: &Element| {
        i.attr("offset")
            .and_then(|o| o.parse::<usize>().ok())
            .unwrap_or(0)
    };
    let stride = inputs.iter().map(|i| offset(i) + 1).max().unwrap_or(1);
    let Some(vin) = inputs.iter().find(|i| i.attr("semantic") == Some("VERTEX")) else {
        return Err(bad(format!(
            "<{}> without an <input semantic=\"VERTEX\">",
            prim.name
        )));
    };
    let src = vin.attr("source").unwrap_or("").trim_start_matches('#');
    let Some(pos) = positions.get(src) else {
        return Err(bad(format!(
            "<{}>: no positions for source {src:?}",
            prim.name
        )));
    };
    let voff = offset(vin);
    Ok((pos, voff, stride))
}

/// Appends the polygon `idx` (indices into the `count` positions appended at `base`) as a
/// triangle fan.
fn fan(
    idx: &[u32],
    base: u32,
    count: usize,
    prim: &Element,
    name: &str,
    out: &mut TriMesh,
) -> Result<(), MeshError> {
    if let Some(&i) = idx.iter().find(|&&i| i as usize >= count) {
        return Err(MeshError::Malformed {
            path: name.to_string(),
            what: format!(
                "<{}>: vertex index {i} but only {count} positions",
                prim.name
            ),
        });
    }
    for j in 1..idx.len().saturating_sub(1) {
        out.triangles
            .push([base + idx[0], base + idx[j], base + idx[j + 1]]);
    }
    Ok(())
}

/// Appends the triangles of a `<triangles>`, `<polylist>` or `<polygons>` element to `out`
/// (polygons as fans).
fn primitive(
    prim: &Element,
    positions: &HashMap<String, Vec<[f64; 3]>>,
    name: &str,
    out: &mut TriMesh,
) -> Result<(), MeshError> {
    let bad = |what: String| MeshError::Malformed {
        path: name.to_string(),
        what,
    };
    let (pos, voff, stride) = vertex_input(prim, positions, name)?;
    let base = out.positions.len() as u32;
    out.positions.extend_from_slice(pos);
    let fan = |idx: &[u32], out: &mut TriMesh| fan(idx, base, pos.len(), prim, name, out);
    let corners = |p: &Element| -> Result<Vec<u32>, MeshError> {
        let all: Vec<u32> = numbers(&p.text, "p", name)?;
        Ok(all.iter().skip(voff).step_by(stride).copied().collect())
    };
    match prim.name.as_str() {
        "polygons" => {
            for p in prim.all("p") {
                fan(&corners(p)?, out)?;
            }
        }
        "triangles" => {
            for p in prim.all("p") {
                for t in corners(p)?.chunks_exact(3) {
                    fan(t, out)?;
                }
            }
        }
        _ => {
            let counts: Vec<usize> = match prim.child("vcount") {
                Some(v) => numbers(&v.text, "vcount", name)?,
                None => Vec::new(),
            };
            let c = match prim.child("p") {
                Some(p) => corners(p)?,
                None => Vec::new(),
            };
            let mut at = 0usize;
            for &k in &counts {
                let Some(poly) = c.get(at..at.saturating_add(k)) else {
                    return Err(bad(format!(
                        "<polylist>: <vcount> asks for more corners than the {} of <p>",
                        c.len()
                    )));
                };
                fan(poly, out)?;
                at += k;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A Collada file of a unit square (two triangles, as a `<triangles>` and as a
    /// `<polylist>` quad) under a node that translates by (10, 0, 0) through a `<matrix>` and
    /// scales by 2, in centimetres, Y up.
    pub(crate) fn square_dae() -> String {
        r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="0.01"/><up_axis>Y_UP</up_axis></asset>
  <library_geometries>
    <geometry id="sq" name="sq"><mesh>
      <source id="sq-pos"><float_array id="sq-pos-array" count="12">0 0 0  1 0 0  1 1 0  0 1 0</float_array>
        <technique_common><accessor source="#sq-pos-array" count="4" stride="3"/></technique_common></source>
      <source id="sq-n"><float_array id="sq-n-array" count="3">0 0 1</float_array>
        <technique_common><accessor source="#sq-n-array" count="1" stride="3"/></technique_common></source>
      <vertices id="sq-v"><input semantic="POSITION" source="#sq-pos"/></vertices>
      <triangles count="2"><input semantic="VERTEX" source="#sq-v" offset="0"/>
        <input semantic="NORMAL" source="#sq-n" offset="1"/><p>0 0 1 0 2 0  0 0 2 0 3 0</p></triangles>
      <polylist count="1"><input semantic="VERTEX" source="#sq-v" offset="0"/><vcount>4</vcount><p>0 1 2 3</p></polylist>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes><visual_scene id="Scene">
    <node id="a"><matrix>1 0 0 10  0 1 0 0  0 0 1 0  0 0 0 1</matrix>
      <node id="b"><scale>2 2 2</scale><instance_geometry url="#sq"/></node>
    </node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#Scene"/></scene>
</COLLADA>"##
            .to_string()
    }

    #[test]
    fn node_matrix_unit_and_up_axis_place_the_triangles() {
        let m = parse(&square_dae(), "sq.dae").unwrap();
        assert_eq!(m.triangles.len(), 4, "two triangles and a quad");
        // In the file: x ∈ [10, 12], y ∈ [0, 2], z = 0 (cm, y up). In metres, z up:
        // (x, y, z) → (x, −z, y) · 0.01.
        let (lo, hi) = m.bounds().unwrap();
        let near = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() < 1e-12);
        assert!(near(lo, [0.10, 0.0, 0.0]), "{lo:?}");
        assert!(near(hi, [0.12, 0.0, 0.02]), "{hi:?}");
    }

    #[test]
    fn z_up_and_no_scene_take_the_geometry_as_it_stands() {
        let text = square_dae()
            .replace("Y_UP", "Z_UP")
            .replace("meter=\"0.01\"", "meter=\"1\"");
        let cut = text.find("<library_visual_scenes>").unwrap();
        let end = text.find("</scene>").unwrap() + "</scene>".len();
        let text = format!("{}{}", &text[..cut], &text[end..]);
        let m = parse(&text, "sq.dae").unwrap();
        assert_eq!(m.bounds(), Some(([0.0; 3], [1.0, 1.0, 0.0])));
    }

    #[test]
    fn deep_nesting_is_refused_with_its_limit_not_a_stack_overflow() {
        let deep = format!(
            "<COLLADA>{}{}</COLLADA>",
            "<node>".repeat(300_000),
            "</node>".repeat(300_000)
        );
        let e = parse(&deep, "deep.dae").unwrap_err().to_string();
        assert!(e.contains("nested more than 256 deep"), "{e}");
        let wide = format!("<COLLADA>{}</COLLADA>", "<a/>".repeat(1_000_001));
        let e = parse(&wide, "wide.dae").unwrap_err().to_string();
        assert!(e.contains("more than 1000000 elements"), "{e}");
    }

    #[test]
    fn bad_indices_and_broken_xml_are_errors() {
        let text = square_dae().replace("<p>0 1 2 3</p>", "<p>0 1 2 9</p>");
        let e = parse(&text, "sq.dae").unwrap_err();
        assert!(e.to_string().contains("vertex index 9"), "{e}");
        let e = parse("<COLLADA><asset></COLLADA>", "x.dae").unwrap_err();
        assert!(e.to_string().contains("x.dae: line 1"), "{e}");
    }
}
