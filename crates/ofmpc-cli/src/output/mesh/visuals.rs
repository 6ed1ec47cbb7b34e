//! The URDF's `<visual>` elements as triangle meshes in the frames of the robot's bodies.
//!
//! A visual's vertex `p` (in its mesh file's units, z up) is placed in the frame of the body
//! `b` that carries its link as `T_link · T_visual · diag(scale) · p` (URDF specification:
//! `<visual><origin>` is the visual's frame in the link's frame, `<mesh scale>` scales the
//! mesh along its own axes; `T_link` is the link's pose in its body, [`LinkFrame`]). The page
//! then draws the mesh at the body's forward-kinematics pose. Primitives follow the URDF
//! specification: `<box size>` centred on its frame, `<cylinder>` and `<capsule>` along z
//! centred, `<sphere>` centred.

use super::{read_limited, read_mesh, resolve, TriMesh};
use nalgebra::Vector3;
use ofmpc::robot::{LinkFrame, Robot};
use ofmpc::spatial::Transform;
use std::f64::consts::PI;
use std::path::Path;

/// Triangle meshes of one body, of one colour.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyMesh {
    /// The body: 0 for the base, `i + 1` for the body of joint `i` ([`Robot::joints`]).
    pub body: usize,
    /// RGB in 0..1 (the visual's `<material><color rgba>`, or a default grey).
    pub color: [f64; 3],
    /// The triangles in the body's frame (m).
    pub mesh: TriMesh,
}

/// The robot's visuals: meshes per body and what could not be drawn.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Visuals {
    /// Meshes, one per body and colour.
    pub meshes: Vec<BodyMesh>,
    /// Per body (`0..=n`): drawn as a capsule (no visual, or one could not be read).
    pub capsule: Vec<bool>,
    /// A sentence per visual that could not be used (the link, the file, why).
    pub warnings: Vec<String>,
}

/// Default colours of meshes without a material: two greys, alternating along the chain.
const GREYS: [[f64; 3]; 2] = [[0.80, 0.81, 0.84], [0.62, 0.64, 0.68]];

/// The URDF document at `urdf`, read with the library's size limit; the error in words.
fn read_urdf(urdf: &Path) -> Result<urdf_rs::Robot, String> {
    read_limited(urdf, ofmpc::robot::MAX_URDF_BYTES)
        .map_err(|e| e.to_string())
        .and_then(|b| String::from_utf8(b).map_err(|e| e.to_string()))
        .and_then(|t| {
            // The XML reader recurses on nesting: bounded first (issue #36).
            let limit = ofmpc::input::MAX_XML_DEPTH;
            match ofmpc::input::xml_too_deep(&t, limit) {
                Some((l, c)) => Err(format!(
                    "line {l}, column {c}: elements nested more than {limit} deep (the limit)"
                )),
                None => urdf_rs::read_from_string(&t).map_err(|e| e.to_string()),
            }
        })
}

/// The most triangles read for the whole robot's meshes, before decimation (issue #36): a
/// visual past it is drawn as a capsule (each file is read once however many visuals name
/// it).
pub const ROBOT_TRIANGLES: usize = 20_000_000;

/// The most bytes of mesh files read for the whole robot (each file counted once).
pub const ROBOT_MESH_BYTES: u64 = 256 << 20;

/// The largest coordinate (m) of a placed mesh: a visual reaching farther from its body's
/// frame is taken for a unit or scale error (1e38 m vertices, `<scale>1e308`) and refused.
pub const MAX_MESH_EXTENT: f64 = 1000.0;

/// What the robot's meshes have used of [`ROBOT_TRIANGLES`] and [`ROBOT_MESH_BYTES`], and
/// the meshes already read (by file).
#[derive(Default)]
struct Budget {
    triangles: usize,
    bytes: u64,
    read: std::collections::HashMap<std::path::PathBuf, TriMesh>,
}

impl Budget {
    /// The mesh of the file at `path`: from the files already read, else read if the file's
    /// size and the triangles left allow it.
    fn mesh(&mut self, path: &Path) -> Result<TriMesh, String> {
        if let Some(m) = self.read.get(path) {
            return self.take(m.clone());
        }
        let size = std::fs::metadata(path).map_or(0, |m| m.len());
        if self.bytes.saturating_add(size) > ROBOT_MESH_BYTES {
            return Err(format!(
                "{}: the robot's mesh files pass {} MiB together (the budget for the replay); \
                 decimate the meshes",
                path.display(),
                ROBOT_MESH_BYTES >> 20
            ));
        }
        self.bytes += size;
        let m = read_mesh(path).map_err(|e| e.to_string())?;
        self.read.insert(path.to_path_buf(), m.clone());
        self.take(m)
    }

    /// Counts `m`'s triangles against the budget.
    fn take(&mut self, m: TriMesh) -> Result<TriMesh, String> {
        self.triangles = self.triangles.saturating_add(m.triangles.len());
        if self.triangles > ROBOT_TRIANGLES {
            return Err(format!(
                "the robot's meshes pass {ROBOT_TRIANGLES} triangles together (the budget for \
                 the replay); decimate the meshes"
            ));
        }
        Ok(m)
    }
}

/// Ok when every coordinate of `m` is finite and within [`MAX_MESH_EXTENT`] of the frame.
fn check_extent(m: &TriMesh) -> Result<(), String> {
    let bad = m
        .positions
        .iter()
        .flatten()
        .find(|x| !(x.is_finite() && x.abs() <= MAX_MESH_EXTENT));
    match bad {
        None => Ok(()),
        Some(x) => Err(format!(
            "a vertex coordinate of {} m once placed (not finite, or past {MAX_MESH_EXTENT} m: \
             a unit, <scale> or <matrix> error?)",
            ofmpc::input::quote(&format!("{x:e}"), 24)
        )),
    }
}

impl Visuals {
    /// The warnings in one line (the terminal's and the report's): how many links are drawn
    /// as capsules because their meshes could not be used, the first reason, and the fix
    /// (`ROS_PACKAGE_PATH` when a mesh was not found). `None` when every visual was used.
    pub fn summary(&self) -> Option<String> {
        let first = self.warnings.first()?;
        let mut links: Vec<&str> = self
            .warnings
            .iter()
            .map(|w| w.split(':').next().unwrap_or(w))
            .collect();
        links.dedup();
        let n = links.len();
        let not_found = self.warnings.iter().any(|w| w.contains("not found"));
        let (links, cause) = if not_found {
            (
                "meshes not found",
                "; set ROS_PACKAGE_PATH to the folder holding the URDF's packages",
            )
        } else {
            ("meshes not readable", "")
        };
        let what = if n == 1 { "1 link" } else { "links" };
        let count = if n == 1 {
            String::new()
        } else {
            format!("{n} ")
        };
        Some(format!(
            "{count}{what} drawn as capsules: {links}{cause} (first: {})",
            first.trim_end_matches("; the link is drawn as a capsule")
        ))
    }

    /// Adds `mesh` to the body's mesh of that colour (a new one for a new colour).
    fn add(&mut self, body: usize, color: [f64; 3], mesh: TriMesh) {
        match self
            .meshes
            .iter_mut()
            .find(|m| m.body == body && m.color == color)
        {
            Some(m) => m.mesh.append(&mesh),
            None => self.meshes.push(BodyMesh { body, color, mesh }),
        }
    }
}

/// The visuals of the URDF file `urdf` from which `robot` was read (`ros_package_path`: the
/// `ROS_PACKAGE_PATH` variable). The URDF not readable again: no meshes, one warning.
pub fn load(urdf: &Path, robot: &Robot, ros_package_path: Option<&str>) -> Visuals {
    let n = robot.dof();
    let mut out = Visuals {
        capsule: vec![true; n + 1],
        ..Visuals::default()
    };
    let doc = match read_urdf(urdf) {
        Ok(d) => d,
        Err(e) => {
            out.warnings.push(format!("{}: {e}", urdf.display()));
            return out;
        }
    };
    let dir = urdf.parent().unwrap_or(Path::new("."));
    let frames: std::collections::HashMap<&str, &LinkFrame> = robot
        .link_frames()
        .iter()
        .map(|f| (f.name.as_str(), f))
        .collect();
    let mut has_mesh = vec![false; n + 1];
    let mut failed = vec![false; n + 1];
    let mut budget = Budget::default();
    for link in &doc.links {
        let Some(frame) = frames.get(link.name.as_str()) else {
            continue;
        };
        let body = frame.body.map_or(0, |i| i + 1);
        for v in &link.visual {
            let mesh = match placed(v, &frame.pose, dir, ros_package_path, &mut budget) {
                Ok(m) => m,
                Err(e) => {
                    out.warnings.push(format!(
                        "link {:?}: {e}; the link is drawn as a capsule",
                        ofmpc::input::quote(&link.name, 80)
                    ));
                    failed[body] = true;
                    continue;
                }
            };
            let color =
                material_color(v.material.as_ref(), &doc.materials).unwrap_or(GREYS[body % 2]);
            has_mesh[body] = true;
            out.add(body, color, mesh);
        }
    }
    out.capsule = (0..=n).map(|b| !has_mesh[b] || failed[b]).collect();
    out
}

/// A `<material>`'s colour: its own `<color rgba>`, else that of the robot-level material
/// of the same name.
fn material_color(m: Option<&urdf_rs::Material>, all: &[urdf_rs::Material]) -> Option<[f64; 3]> {
    let m = m?;
    let c = m.color.as_ref().or_else(|| {
        all.iter()
            .find(|g| g.name == m.name)
            .and_then(|g| g.color.as_ref())
    })?;
    let rgba = *c.rgba;
    rgba[..3]
        .iter()
        .all(|v| v.is_finite())
        .then(|| [rgba[0], rgba[1], rgba[2]].map(|v| v.clamp(0.0, 1.0)))
}

/// The visual `v`'s triangles in the frame of its body (`link_pose`: its link's pose there),
/// refused when a coordinate is not finite or past [`MAX_MESH_EXTENT`], before or after
/// placing (issue #36: such a link vanished from the replay or dwarfed the robot).
fn placed(
    v: &urdf_rs::Visual,
    link_pose: &Transform,
    dir: &Path,
    ros_package_path: Option<&str>,
    budget: &mut Budget,
) -> Result<TriMesh, String> {
    let named = |e: String| format!("{}: {e}", name_of(&v.geometry));
    let mut mesh = geometry(&v.geometry, dir, ros_package_path, budget)?;
    check_extent(&mesh).map_err(named)?;
    let t = link_pose.compose(&Transform::from_xyz_rpy(*v.origin.xyz, *v.origin.rpy));
    mesh.map(|p| {
        let q = t.apply_point(&Vector3::new(p[0], p[1], p[2]));
        [q[0], q[1], q[2]]
    });
    check_extent(&mesh).map_err(named)?;
    Ok(mesh)
}

/// A file name as a warning quotes it: whole when at most `max` characters, else its last
/// `max` characters after `…` and the length — the end of a path names the file, its start
/// only where the URDF sits (a long checkout path cut the file's name off).
fn path_tail(s: &str, max: usize) -> String {
    let n = s.chars().count();
    if n <= max {
        return s.to_string();
    }
    let tail: String = s.chars().skip(n - max).collect();
    format!("({n} characters) …{tail}")
}

/// The geometry named for a warning: the mesh's file (shortened), or the primitive.
fn name_of(g: &urdf_rs::Geometry) -> String {
    match g {
        urdf_rs::Geometry::Mesh { filename, .. } => format!("mesh {:?}", path_tail(filename, 80)),
        urdf_rs::Geometry::Box { .. } => "<box>".into(),
        urdf_rs::Geometry::Cylinder { .. } => "<cylinder>".into(),
        urdf_rs::Geometry::Sphere { .. } => "<sphere>".into(),
        urdf_rs::Geometry::Capsule { .. } => "<capsule>".into(),
    }
}

/// A `<geometry>` as triangles in the visual's frame (scale applied; mesh files read within
/// the robot's `budget`).
fn geometry(
    g: &urdf_rs::Geometry,
    dir: &Path,
    ros_package_path: Option<&str>,
    budget: &mut Budget,
) -> Result<TriMesh, String> {
    let check = |what: &str, v: &[f64]| {
        if v.iter().all(|x| x.is_finite() && *x >= 0.0) {
            Ok(())
        } else {
            Err(format!("<{what}> with {v:?}: sizes must be finite and ≥ 0"))
        }
    };
    match g {
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let s = scale.as_ref().map_or([1.0; 3], |s| **s);
            if !s.iter().all(|x| x.is_finite()) {
                return Err(format!(
                    "<mesh filename={filename:?}> scale {s:?} is not finite"
                ));
            }
            let path = resolve(filename, dir, ros_package_path).map_err(|e| e.to_string())?;
            let mut m = budget.mesh(&path)?;
            m.map(|p| [p[0] * s[0], p[1] * s[1], p[2] * s[2]]);
            Ok(m)
        }
        urdf_rs::Geometry::Box { size } => {
            check("box", &size[..])?;
            Ok(cuboid([size[0], size[1], size[2]]))
        }
        urdf_rs::Geometry::Cylinder { radius, length } => {
            check("cylinder", &[*radius, *length])?;
            Ok(cylinder(*radius, *length))
        }
        urdf_rs::Geometry::Sphere { radius } => {
            check("sphere", &[*radius])?;
            Ok(sphere(*radius, 0.0))
        }
        urdf_rs::Geometry::Capsule { radius, length } => {
            check("capsule", &[*radius, *length])?;
            let mut m = cylinder(*radius, *length);
            m.append(&sphere(*radius, length / 2.0));
            m.append(&sphere(*radius, -length / 2.0));
            Ok(m)
        }
    }
}

/// A box of the given edge lengths centred on the origin (12 triangles, outward).
pub fn cuboid(size: [f64; 3]) -> TriMesh {
    let h = size.map(|s| s / 2.0);
    let corner = |i: u32| {
        [
            if i & 1 == 0 { -h[0] } else { h[0] },
            if i & 2 == 0 { -h[1] } else { h[1] },
            if i & 4 == 0 { -h[2] } else { h[2] },
        ]
    };
    let faces: [[u32; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    TriMesh {
        positions: (0..8).map(corner).collect(),
        triangles: faces
            .iter()
            .flat_map(|f| [[f[0], f[1], f[2]], [f[0], f[2], f[3]]])
            .collect(),
    }
}

/// Segments around a cylinder or sphere.
const SEGMENTS: u32 = 24;

/// A closed cylinder along z, centred, of `radius` and `length`.
pub fn cylinder(radius: f64, length: f64) -> TriMesh {
    let s = SEGMENTS;
    let mut m = TriMesh::default();
    for z in [-length / 2.0, length / 2.0] {
        for i in 0..s {
            let a = 2.0 * PI * f64::from(i) / f64::from(s);
            m.positions.push([radius * a.cos(), radius * a.sin(), z]);
        }
        m.positions.push([0.0, 0.0, z]);
    }
    let top = s + 1;
    for i in 0..s {
        let j = (i + 1) % s;
        m.triangles.push([i, j, top + j]);
        m.triangles.push([i, top + j, top + i]);
        m.triangles.push([s, j, i]);
        m.triangles.push([top + s, top + i, top + j]);
    }
    m
}

/// A sphere of `radius` centred at `(0, 0, z)`.
pub fn sphere(radius: f64, z: f64) -> TriMesh {
    let (rings, s) = (SEGMENTS / 2, SEGMENTS);
    let mut m = TriMesh::default();
    for i in 0..=rings {
        let th = PI * f64::from(i) / f64::from(rings);
        for j in 0..s {
            let ph = 2.0 * PI * f64::from(j) / f64::from(s);
            m.positions.push([
                radius * th.sin() * ph.cos(),
                radius * th.sin() * ph.sin(),
                z + radius * th.cos(),
            ]);
        }
    }
    for i in 0..rings {
        for j in 0..s {
            let (a, b) = (i * s + j, i * s + (j + 1) % s);
            m.triangles.push([a, a + s, b + s]);
            m.triangles.push([a, b + s, b]);
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arm() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mesh_arm/urdf/mesh_arm.urdf")
    }

    /// The test arm's visuals land in their bodies' frames: each body's bounding box is the
    /// one worked out by hand from the mesh files (their units, node matrix, scale) and the
    /// URDF's visual and fixed-joint origins.
    #[test]
    fn the_test_arm_visuals_sit_in_their_bodies() {
        let robot = Robot::from_urdf_file(&arm()).unwrap();
        let v = load(&arm(), &robot, None);
        assert!(v.warnings.is_empty(), "{:?}", v.warnings);
        assert_eq!(v.capsule, vec![false; 7]);
        let want: [(usize, [f64; 3], [f64; 3], usize); 7] = [
            // Binary STL in mm, scale 0.001.
            (0, [-0.15, -0.15, 0.0], [0.15, 0.15, 0.2], 12),
            // ASCII STL.
            (1, [-0.08, -0.08, 0.2], [0.12, 0.08, 0.4], 12),
            // Collada in cm, node matrix +18 cm along z, through package://.
            (2, [-0.06, -0.09, 0.0], [0.06, -0.03, 0.36], 12),
            // OBJ along z turned onto x by rpy (0, π/2, 0): (x, y, z) → (z, y, −x).
            (3, [-0.03, -0.05, -0.05], [0.24, 0.05, 0.05], 12),
            // Cylinder along x, centred at x = 0.07.
            (
                4,
                [0.01, -0.045, -0.045],
                [0.13, 0.045, 0.045],
                4 * SEGMENTS as usize,
            ),
            (
                5,
                [-0.05; 3],
                [0.05; 3],
                2 * (SEGMENTS * SEGMENTS / 2) as usize,
            ),
            // The flange's box (z out of the flange) on body 6: flange rpy (0, π/2, 0).
            (6, [0.0, -0.035, -0.035], [0.02, 0.035, 0.035], 12),
        ];
        assert_eq!(v.meshes.len(), want.len());
        for (body, lo, hi, tris) in want {
            let m = v.meshes.iter().find(|m| m.body == body).unwrap();
            let (l, h) = m.mesh.bounds().unwrap();
            for c in 0..3 {
                assert!(
                    (l[c] - lo[c]).abs() < 1e-6 && (h[c] - hi[c]).abs() < 1e-6,
                    "body {body}: {l:?} {h:?}"
                );
            }
            assert_eq!(m.mesh.triangles.len(), tris, "body {body}");
        }
        let blue = [0.15, 0.35, 0.85];
        assert_eq!(v.meshes[0].color, blue, "the robot-level material by name");
        assert_eq!(
            v.meshes.iter().find(|m| m.body == 6).unwrap().color,
            [0.95, 0.45, 0.05]
        );
    }

    /// A missing mesh file: a warning naming the link and the file, that body drawn as a
    /// capsule, the others as meshes.
    #[test]
    fn a_missing_mesh_falls_back_to_the_capsule_with_a_warning() {
        let tmp = std::env::temp_dir().join(format!("ofmpc-visuals-{}", std::process::id()));
        std::fs::create_dir_all(&tmp).unwrap();
        let text = std::fs::read_to_string(arm())
            .unwrap()
            .replace("../meshes/link1.stl", "../meshes/nowhere.stl")
            .replace(
                "../meshes/",
                &format!("{}/", arm().parent().unwrap().join("../meshes").display()),
            );
        let urdf = tmp.join("arm.urdf");
        std::fs::write(&urdf, text).unwrap();
        let robot = Robot::from_urdf_file(&urdf).unwrap();
        let v = load(&urdf, &robot, None);
        assert_eq!(v.warnings.len(), 2, "{:?}", v.warnings);
        let summary = v.summary().expect("two warnings: a summary");
        assert!(
            summary.starts_with("2 links drawn as capsules: meshes ") && !summary.contains('\n'),
            "{summary}"
        );
        assert!(
            v.warnings[0].contains("link \"link_1\"") && v.warnings[0].contains("nowhere.stl"),
            "{:?}",
            v.warnings
        );
        // package://mesh_arm/ is not above the temporary folder.
        assert!(
            v.warnings[1].contains("link \"link_2\""),
            "{:?}",
            v.warnings
        );
        assert_eq!(
            v.capsule,
            vec![false, true, true, false, false, false, false]
        );
        assert_eq!(v.meshes.len(), 5);
        std::fs::remove_dir_all(&tmp).unwrap();
    }

    /// A mesh's long path is quoted by its end, where the file's name is (a checkout at a
    /// long path cut it off).
    #[test]
    fn a_long_mesh_path_is_quoted_by_its_end() {
        let long = format!("/{}/meshes/link3.obj", "deep/".repeat(40));
        let q = super::path_tail(&long, 80);
        assert!(
            q.ends_with("/meshes/link3.obj")
                && q.contains(&format!("({} characters)", long.chars().count())),
            "{q}"
        );
        assert_eq!(
            q.chars().count(),
            80 + format!("({} characters) …", long.chars().count())
                .chars()
                .count()
        );
        assert_eq!(super::path_tail("a/b.stl", 80), "a/b.stl");
    }

    /// Coordinates that are not finite or absurd (a `<matrix>` of NaN, `<scale>` 1e308,
    /// 1e38 m vertices) are refused per mesh with a warning naming the link and the file, and
    /// the link is drawn as a capsule (issue #36: it vanished or dwarfed the robot).
    #[test]
    fn absurd_coordinates_are_refused_per_mesh_with_the_link_and_the_file() {
        let tmp = std::env::temp_dir().join(format!("ofmpc-visuals-nan-{}", std::process::id()));
        std::fs::create_dir_all(&tmp).unwrap();
        let dae = super::super::collada::tests::square_dae()
            .replace("<matrix>1 0 0 10", "<matrix>NaN 0 0 10");
        std::fs::write(tmp.join("nan.dae"), &dae).unwrap();
        std::fs::write(
            tmp.join("far.obj"),
            "v 0 0 0\nv 1e38 0 0\nv 0 1 0\nf 1 2 3\n",
        )
        .unwrap();
        let meshes = arm().parent().unwrap().join("../meshes");
        let text = std::fs::read_to_string(arm())
            .unwrap()
            .replace(
                "../meshes/link1.stl",
                &tmp.join("far.obj").display().to_string(),
            )
            .replace(
                "package://mesh_arm/meshes/link2.dae",
                &tmp.join("nan.dae").display().to_string(),
            )
            .replace(
                "<mesh filename=\"../meshes/link3.obj\"/>",
                "<mesh filename=\"../meshes/link3.obj\" scale=\"1e308 1 1\"/>",
            )
            .replace("../meshes/", &format!("{}/", meshes.display()));
        let urdf = tmp.join("arm.urdf");
        std::fs::write(&urdf, text).unwrap();
        let robot = Robot::from_urdf_file(&urdf).unwrap();
        let v = load(&urdf, &robot, None);
        assert_eq!(v.warnings.len(), 3, "{:?}", v.warnings);
        for (w, link, file) in [
            (&v.warnings[0], "link_1", "far.obj"),
            (&v.warnings[1], "link_2", "nan.dae"),
            (&v.warnings[2], "link_3", "link3.obj"),
        ] {
            assert!(
                w.contains(&format!("link \"{link}\""))
                    && w.contains(file)
                    && w.contains("capsule"),
                "{w}"
            );
        }
        assert_eq!(
            v.capsule,
            vec![false, true, true, true, false, false, false]
        );
        std::fs::remove_dir_all(&tmp).unwrap();
    }

    /// Forty visuals naming one mesh read it once; past the robot's triangle budget the
    /// visuals are capsules with a warning naming the budget.
    #[test]
    fn the_robots_meshes_share_one_triangle_budget() {
        let mut b = Budget::default();
        let m = TriMesh {
            positions: vec![[0.0; 3]; 3],
            triangles: vec![[0, 1, 2]; ROBOT_TRIANGLES / 2],
        };
        assert!(b.take(m.clone()).is_ok());
        assert!(b.take(m.clone()).is_ok());
        let e = b.take(m).unwrap_err();
        assert!(e.contains("20000000 triangles together"), "{e}");
    }
}
