use std::path::PathBuf;

/// Everything that can go wrong in envfield-scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A mesh, point or shape parameter is unusable (not finite, non-positive size, ...).
    #[error("invalid geometry: {0}")]
    InvalidGeometry(String),
    /// A query or configuration argument is out of range.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A mesh file could not be parsed.
    #[error("{path}, line {line}: {reason}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line (0 for binary data or the file as a whole).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A glTF file could not be read: the part of it named is wrong or not supported.
    #[error("{path}: {part}: {reason}")]
    Gltf {
        /// The file.
        path: PathBuf,
        /// Where in it: the document, a buffer, a mesh's primitive, a node.
        part: String,
        /// What is wrong.
        reason: String,
    },
    /// A mesh has no triangles.
    #[error("{0}: the mesh has no triangles")]
    EmptyMesh(String),
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// An error from envfield-grid (grid shapes, atomic writes).
    #[error(transparent)]
    Grid(#[from] envfield_grid::GridError),
}

/// `Result` with [`SceneError`].
pub type Result<T> = std::result::Result<T, SceneError>;

pub(crate) fn check_point(p: &nalgebra::Point3<f32>, what: &str) -> Result<()> {
    if p.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(SceneError::InvalidInput(format!(
            "{what} ({}, {}, {}) is not finite",
            p.x, p.y, p.z
        )))
    }
}
