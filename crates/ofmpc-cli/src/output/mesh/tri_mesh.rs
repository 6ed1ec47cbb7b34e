//! The shared types of the mesh readers: the triangle mesh they produce, their error and
//! their limits (a leaf: the readers and `mod.rs` import it, it imports none of them).

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
