use std::path::PathBuf;

/// Everything that can go wrong in `envfield-grid`.
#[derive(Debug, thiserror::Error)]
pub enum GridError {
    /// A grid was asked for with a zero or overflowing size.
    #[error("invalid grid shape {shape:?}: {reason}")]
    InvalidShape {
        /// The shape that was asked for.
        shape: Vec<usize>,
        /// Why it is not acceptable.
        reason: String,
    },
    /// A data buffer does not have as many elements as the shape says.
    #[error("data length {len} does not match shape {shape:?} ({expected} elements)")]
    LengthMismatch {
        /// Elements given.
        len: usize,
        /// The shape.
        shape: Vec<usize>,
        /// Elements the shape needs.
        expected: usize,
    },
    /// A cell index outside the grid.
    #[error("cell {cell} is outside the {shape} grid")]
    OutOfBounds {
        /// The cell, formatted.
        cell: String,
        /// The grid's shape, formatted.
        shape: String,
    },
    /// A continuous coordinate that is NaN or infinite.
    #[error("coordinate {what} is not finite ({value})")]
    NotFinite {
        /// Which coordinate.
        what: &'static str,
        /// Its value.
        value: f32,
    },
    /// A syntax error in the maze text format.
    #[error("maze text, line {line}, column {column}: {message}")]
    MazeSyntax {
        /// 1-based line number.
        line: usize,
        /// 1-based column number (1 when the error concerns a whole line or the file).
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// A malformed `.npy` file or buffer.
    #[error("npy: {0}")]
    Npy(String),
    /// A PNG could not be decoded or encoded.
    #[error("png: {0}")]
    Image(#[from] image::ImageError),
    /// An I/O error, with the path it concerns.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A [`FieldModel`](crate::FieldModel) failed to predict a field.
    #[error("model {model}: {source}")]
    Model {
        /// The model's name.
        model: String,
        /// The underlying error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// Any other invalid argument.
    #[error("{0}")]
    Invalid(String),
}

impl GridError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        GridError::Io {
            path: path.into(),
            source,
        }
    }
}

/// `Result` with [`GridError`].
pub type Result<T, E = GridError> = std::result::Result<T, E>;
