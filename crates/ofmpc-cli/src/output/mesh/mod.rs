//! The robot's meshes for the report's 3-D replay (issue #25 item 4): each URDF link's
//! `<visual>` geometry (STL, Collada DAE and OBJ mesh files, boxes, cylinders, spheres,
//! capsules), placed in the frame of the body that carries the link, decimated to a triangle
//! budget and quantized for the page ([`embed`]).
//!
//! * [`stl`], [`collada`], [`obj`]: the file readers, into a [`TriMesh`] in the file's units.
//! * [`visuals`]: the URDF's `<visual>` elements, file paths resolved (relative,
//!   `package://`, `file://`), each in its body's frame; a file that cannot be found or read
//!   is a warning and its link falls back to the capsules.
//! * [`embed`]: vertex clustering to a budget and the page's JSON.

pub mod collada;
pub mod embed;
pub mod obj;
pub mod stl;
pub mod visuals;

use std::path::{Path, PathBuf};

/// The largest mesh file read (bytes): 64 MiB, like the largest URDF
/// ([`ofmpc::robot::MAX_URDF_BYTES`]); a CAD export of a whole arm link is a few MiB.
pub const MAX_MESH_BYTES: u64 = 64 << 20;

/// Most triangles a mesh file may declare or hold (a binary STL's count is read before its
/// triangles): 20 million, far above any robot link.
pub const MAX_TRIANGLES: usize = 20_000_000;

/// A triangle mesh: positions and triangles (indices into them).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub positions: Vec<[f64; 3]>,
    /// Triangles, counter-clockwise seen from outside where the file says so.
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Appends `other` (its indices shifted).
    pub fn append(&mut self, other: &TriMesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }

    /// Every position mapped by `f`.
    pub fn map(&mut self, f: impl Fn([f64; 3]) -> [f64; 3]) {
        for p in &mut self.positions {
            *p = f(*p);
        }
    }

    /// Lower and upper corner of the positions used by triangles (`None` when empty).
    pub fn bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        let mut it = self
            .triangles
            .iter()
            .flatten()
            .map(|&i| self.positions[i as usize]);
        let first = it.next()?;
        Some(it.fold((first, first), |(mut lo, mut hi), p| {
            for c in 0..3 {
                lo[c] = lo[c].min(p[c]);
                hi[c] = hi[c].max(p[c]);
            }
            (lo, hi)
        }))
    }
}

/// Why a mesh file could not be used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The system's message.
        message: String,
    },
    /// The file is larger than [`MAX_MESH_BYTES`].
    #[error("{path} is larger than the limit of {} MB for a mesh; decimate it", limit / (1 << 20))]
    TooLarge {
        /// The file.
        path: String,
        /// The limit (bytes).
        limit: u64,
    },
    /// A mesh format this reader does not know (by the file's extension).
    #[error("{path}: unknown mesh format {extension:?}; use STL, DAE (Collada) or OBJ")]
    UnknownFormat {
        /// The file.
        path: String,
        /// Its extension.
        extension: String,
    },
    /// The file's content does not follow its format.
    #[error("{path}: {what}")]
    Malformed {
        /// The file.
        path: String,
        /// What is wrong, and where (byte offset or line).
        what: String,
    },
    /// The mesh has no triangle.
    #[error("{path}: no triangle")]
    Empty {
        /// The file.
        path: String,
    },
    /// A `<mesh filename>` that leads outside its package (`package://../x`, `package:///x`,
    /// a path or `file://` outside the folder holding the URDF's `package.xml`).
    #[error(
        "{filename}: leads outside the robot's package (a `package://` name with `..` or an \
         absolute path, or a path or `file://` outside the folder holding the URDF's \
         package.xml); copy the mesh into the package"
    )]
    Outside {
        /// The `<mesh filename>` as written (shortened).
        filename: String,
    },
    /// A `package://` or other URL whose file was not found.
    #[error(
        "{filename}: not found (looked in {tried}); put the package beside the URDF's folders \
         or on ROS_PACKAGE_PATH"
    )]
    NotFound {
        /// The `<mesh filename>` as written.
        filename: String,
        /// The places looked at.
        tried: String,
    },
}

/// Reads the file `path` whole, refusing more than `limit` bytes (reading stops one byte
/// past the limit, so a `/dev/zero` is never read whole).
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, MeshError> {
    let name = || path.display().to_string();
    let io = |e: std::io::Error| MeshError::Io {
        path: name(),
        message: e.to_string(),
    };
    ofmpc::input::read_limited(path, limit).map_err(|e| match e {
        ofmpc::input::ReadLimitedError::Io(e) => io(e),
        ofmpc::input::ReadLimitedError::TooLarge { .. } => MeshError::TooLarge {
            path: name(),
            limit,
        },
    })
}

/// Reads a mesh file by its extension (`.stl`, `.dae`, `.obj`, any case), in the file's
/// units (Collada: converted to metres and Z up, [`collada`]).
pub fn read_mesh(path: &Path) -> Result<TriMesh, MeshError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let name = path.display().to_string();
    let mesh = match ext.as_str() {
        "stl" => stl::parse(&read_limited(path, MAX_MESH_BYTES)?, &name)?,
        "dae" => collada::parse(&text(read_limited(path, MAX_MESH_BYTES)?, &name)?, &name)?,
        "obj" => obj::parse(&text(read_limited(path, MAX_MESH_BYTES)?, &name)?, &name)?,
        _ => {
            return Err(MeshError::UnknownFormat {
                path: name,
                extension: ext,
            })
        }
    };
    if mesh.triangles.is_empty() {
        return Err(MeshError::Empty { path: name });
    }
    Ok(mesh)
}

/// The bytes as UTF-8 text (a Collada or OBJ file).
fn text(bytes: Vec<u8>, name: &str) -> Result<String, MeshError> {
    String::from_utf8(bytes).map_err(|e| MeshError::Malformed {
        path: name.to_string(),
        what: format!(
            "not UTF-8 text (byte {} at offset {})",
            e.as_bytes()[e.utf8_error().valid_up_to()],
            e.utf8_error().valid_up_to()
        ),
    })
}

/// Where a `<mesh filename>` of the URDF in folder `urdf_dir` points: a path relative to
/// that folder or absolute; `file://PATH`; `package://PKG/REST`, looked up in the folders
/// above `urdf_dir` named `PKG` (nearest first) or holding a folder `PKG`, then on
/// `ros_package_path` (the `ROS_PACKAGE_PATH` variable: folders separated by `:`; each
/// entry is a package folder itself or holds one), as ROS's `resource_retriever` does.
pub fn resolve(
    filename: &str,
    urdf_dir: &Path,
    ros_package_path: Option<&str>,
) -> Result<PathBuf, MeshError> {
    let not_found = |tried: Vec<PathBuf>| MeshError::NotFound {
        filename: filename.to_string(),
        tried: tried
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
    };
    if let Some(rest) = filename.strip_prefix("package://") {
        let (pkg, rel) = rest.split_once('/').unwrap_or((rest, ""));
        if !plain_name(pkg) || !stays_inside(Path::new(rel)) {
            return Err(outside(filename));
        }
        let mut candidates: Vec<PathBuf> = Vec::new();
        for dir in urdf_dir.ancestors() {
            if dir.file_name().is_some_and(|n| n == pkg) {
                candidates.push(dir.join(rel));
            }
            candidates.push(dir.join(pkg).join(rel));
        }
        for entry in ros_package_path
            .unwrap_or("")
            .split(':')
            .filter(|e| !e.is_empty())
        {
            let e = Path::new(entry);
            if e.file_name().is_some_and(|n| n == pkg) {
                candidates.push(e.join(rel));
            }
            candidates.push(e.join(pkg).join(rel));
        }
        // A file first; else the first thing of that name (a folder, a pipe: the read says
        // what it is rather than "not found").
        if let Some(c) = candidates
            .iter()
            .find(|c| c.is_file())
            .or_else(|| candidates.iter().find(|c| c.exists()))
        {
            return Ok(c.clone());
        }
        candidates.truncate(6);
        return Err(not_found(candidates));
    }
    let p = match filename.strip_prefix("file://") {
        Some(abs) => PathBuf::from(abs),
        None => urdf_dir.join(filename),
    };
    let inside = match package_root(urdf_dir) {
        Some(root) => normalized(&p)
            .zip(normalized(&root))
            .is_some_and(|(p, r)| p.starts_with(r)),
        // Not in a package: a path of the user's own, nothing to confine it to.
        None => true,
    };
    if !inside {
        return Err(outside(filename));
    }
    if p.exists() {
        Ok(p)
    } else {
        Err(not_found(vec![p]))
    }
}

/// A package name: one path component, not `.` or `..`.
fn plain_name(s: &str) -> bool {
    !s.is_empty() && s != "." && s != ".." && !s.contains(['/', '\\'])
}

/// Whether a relative path stays below where it starts (no root, no `..`).
fn stays_inside(rel: &Path) -> bool {
    rel.components().all(|c| {
        matches!(
            c,
            std::path::Component::Normal(_) | std::path::Component::CurDir
        )
    })
}

/// The package a URDF in folder `urdf_dir` belongs to: the nearest folder above it (itself
/// included) holding a `package.xml`, if any. Mesh files named by a path or `file://` must
/// lie inside it.
fn package_root(urdf_dir: &Path) -> Option<PathBuf> {
    let dir = std::path::absolute(urdf_dir).unwrap_or_else(|_| urdf_dir.to_path_buf());
    dir.ancestors()
        .find(|d| d.join("package.xml").is_file())
        .map(Path::to_path_buf)
}

/// `p` made absolute with `.` and `..` resolved by the text (symbolic links are not
/// followed: a workspace installed with links stays readable).
fn normalized(p: &Path) -> Option<PathBuf> {
    let abs = std::path::absolute(p).ok()?;
    let mut out = PathBuf::new();
    for c in abs.components() {
        match c {
            std::path::Component::ParentDir => {
                out.pop();
            }
            std::path::Component::CurDir => {}
            c => out.push(c),
        }
    }
    Some(out)
}

/// The error for a mesh path that leaves its package.
fn outside(filename: &str) -> MeshError {
    MeshError::Outside {
        filename: ofmpc::input::quote(filename, 80),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn package_urls_resolve_by_walking_up_and_on_the_package_path() {
        let tmp = std::env::temp_dir().join(format!("ofmpc-mesh-resolve-{}", std::process::id()));
        let urdf_dir = tmp.join("ws/my_robot/urdf");
        std::fs::create_dir_all(&urdf_dir).unwrap();
        std::fs::create_dir_all(tmp.join("ws/my_robot/meshes")).unwrap();
        std::fs::create_dir_all(tmp.join("other/tools/meshes")).unwrap();
        std::fs::write(tmp.join("ws/my_robot/meshes/a.stl"), b"x").unwrap();
        std::fs::write(tmp.join("other/tools/meshes/b.stl"), b"x").unwrap();
        std::fs::write(urdf_dir.join("c.stl"), b"x").unwrap();
        assert_eq!(
            resolve("package://my_robot/meshes/a.stl", &urdf_dir, None).unwrap(),
            tmp.join("ws/my_robot/meshes/a.stl")
        );
        let path = tmp.join("other").display().to_string();
        assert_eq!(
            resolve("package://tools/meshes/b.stl", &urdf_dir, Some(&path)).unwrap(),
            tmp.join("other/tools/meshes/b.stl")
        );
        assert!(matches!(
            resolve("package://tools/meshes/b.stl", &urdf_dir, None),
            Err(MeshError::NotFound { .. })
        ));
        assert_eq!(
            resolve("c.stl", &urdf_dir, None).unwrap(),
            urdf_dir.join("c.stl")
        );
        let abs = format!("file://{}", urdf_dir.join("c.stl").display());
        assert_eq!(resolve(&abs, &tmp, None).unwrap(), urdf_dir.join("c.stl"));
        std::fs::remove_dir_all(&tmp).unwrap();
    }

    /// `package://../..`, `package:///abs` and, inside a package, a path or `file://` that
    /// leaves it are refused as such (issue #36); a FIFO is found, then refused by kind.
    #[test]
    fn mesh_paths_stay_inside_their_package() {
        let tmp = std::env::temp_dir().join(format!("ofmpc-mesh-confine-{}", std::process::id()));
        let pkg = tmp.join("ws/arm");
        std::fs::create_dir_all(pkg.join("urdf")).unwrap();
        std::fs::write(pkg.join("package.xml"), b"<package/>").unwrap();
        std::fs::write(tmp.join("secret.obj"), b"v 0 0 0").unwrap();
        let dir = pkg.join("urdf");
        for bad in [
            "package://../../secret.obj".to_string(),
            "package:///etc/passwd".to_string(),
            "package://arm/../../../secret.obj".to_string(),
            format!("file://{}", tmp.join("secret.obj").display()),
            "../../../secret.obj".to_string(),
        ] {
            let e = resolve(&bad, &dir, None).unwrap_err();
            assert!(matches!(e, MeshError::Outside { .. }), "{bad}: {e}");
            assert!(e.to_string().contains("leads outside"), "{e}");
        }
        #[cfg(unix)]
        {
            let fifo = pkg.join("fifo.stl");
            assert!(std::process::Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .unwrap()
                .success());
            let p = resolve("package://arm/fifo.stl", &dir, None).unwrap();
            let e = read_mesh(&p).unwrap_err().to_string();
            assert!(e.contains("a named pipe (FIFO)"), "{e}");
            let e = read_mesh(&pkg.join("urdf.stl")).unwrap_err().to_string();
            assert!(e.contains("not found") || e.contains("No such file"), "{e}");
            std::fs::create_dir_all(pkg.join("d.stl")).unwrap();
            let p = resolve("../d.stl", &dir, None).unwrap();
            let e = read_mesh(&p).unwrap_err().to_string();
            assert!(e.contains("a folder"), "{e}");
        }
        std::fs::remove_dir_all(&tmp).unwrap();
    }

    #[test]
    fn a_file_past_the_limit_is_refused() {
        if Path::new("/dev/zero").exists() {
            // A device is refused as what it is, never read (issue #36).
            let e = read_limited(Path::new("/dev/zero"), 1000).unwrap_err();
            assert!(e.to_string().contains("a character device"), "{e}");
        }
        assert!(matches!(
            read_mesh(Path::new("/nonexistent/x.stl")),
            Err(MeshError::Io { .. })
        ));
        assert!(matches!(
            read_mesh(Path::new("/nonexistent/x.ply")),
            Err(MeshError::UnknownFormat { .. })
        ));
    }
}
