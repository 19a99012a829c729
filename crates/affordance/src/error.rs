use std::path::PathBuf;

/// Everything that can go wrong in envfield-affordance.
#[derive(Debug, thiserror::Error)]
pub enum AffordanceError {
    /// A pose, sequence, trajectory or config is unusable; the message says which and where.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A pose-sequence JSON file is malformed.
    #[error("{path}: {reason}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong (frame and joint where it applies).
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A scene query failed.
    #[error(transparent)]
    Scene(#[from] envfield_scene::SceneError),
}

impl AffordanceError {
    /// The error with `what` before an invalid input's message (`"walker: frame 4: ..."`).
    pub(crate) fn within(self, what: &str) -> Self {
        match self {
            Self::InvalidInput(m) => Self::InvalidInput(format!("{what}: {m}")),
            e => e,
        }
    }
}

/// `Result` with [`AffordanceError`].
pub type Result<T> = std::result::Result<T, AffordanceError>;
