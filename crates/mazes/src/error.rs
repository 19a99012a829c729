use envfield_eikonal::EikonalError;
use envfield_grid::GridError;

/// Everything that can go wrong in `envfield-mazes`.
#[derive(Debug, thiserror::Error)]
pub enum MazeError {
    /// From the grid types (I/O, shapes, cells).
    #[error(transparent)]
    Grid(#[from] GridError),
    /// From the solvers.
    #[error(transparent)]
    Eikonal(#[from] EikonalError),
    /// A generator or dataset setting is out of range.
    #[error("invalid setting: {0}")]
    InvalidConfig(String),
    /// A saved dataset is inconsistent.
    #[error("dataset {path}: {message}")]
    Dataset {
        /// The dataset's folder.
        path: String,
        /// What is wrong.
        message: String,
    },
}

/// `Result` with [`MazeError`].
pub type Result<T, E = MazeError> = std::result::Result<T, E>;
