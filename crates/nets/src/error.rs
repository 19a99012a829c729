//! The error type of envfield-nets.

use std::path::PathBuf;

/// Everything that can go wrong building, running, training, saving or loading a network.
#[derive(Debug, thiserror::Error)]
pub enum NetsError {
    /// A configuration value is out of range or inconsistent.
    #[error("invalid config: {0}")]
    InvalidConfig(String),
    /// An input does not fit the network (wrong grid size, wrong dimension, a NaN coordinate).
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A checkpoint or weight file cannot be read or is not a valid envfield-nets file.
    #[error("checkpoint {path}: {reason}")]
    Checkpoint {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A weight file lacks a tensor the network needs.
    #[error("weights {path}: missing tensor `{name}`")]
    MissingWeight {
        /// The file.
        path: PathBuf,
        /// The missing tensor.
        name: String,
    },
    /// A weight file holds a tensor of another shape than the network's.
    #[error(
        "weights {path}: tensor `{name}` has shape {found:?}, the network expects {expected:?}"
    )]
    ShapeMismatch {
        /// The file.
        path: PathBuf,
        /// The tensor.
        name: String,
        /// The network's shape.
        expected: Vec<usize>,
        /// The file's shape.
        found: Vec<usize>,
    },
    /// A weight file holds a tensor the network does not have.
    #[error("weights {path}: unexpected tensor `{name}` (not a parameter of this network)")]
    UnexpectedWeight {
        /// The file.
        path: PathBuf,
        /// The tensor.
        name: String,
    },
    /// No weight file of a model family for a maze size (see [`crate::model_file`]).
    #[error("no {name} model for {size}x{size} mazes: looked for {}", display_paths(.looked))]
    ModelNotFound {
        /// The model family.
        name: String,
        /// The maze side.
        size: usize,
        /// The files looked for, in order.
        looked: Vec<PathBuf>,
    },
    /// A resumed run was given other training data than its checkpoint records (see
    /// [`crate::Trainer::continue_with_data`]).
    #[error("the checkpoint was trained on data ({recorded}) other than the data given ({given})")]
    DataMismatch {
        /// What the checkpoint records.
        recorded: String,
        /// What the caller gave.
        given: String,
    },
    /// Training diverged (a loss that is not finite).
    #[error("training diverged at step {step}: loss {loss}")]
    Diverged {
        /// The step.
        step: u64,
        /// The loss.
        loss: f32,
    },
    /// A tensor operation failed inside candle.
    #[error("candle: {0}")]
    Candle(#[from] candle_core::Error),
    /// From envfield-grid (a goal on an obstacle, writing a file).
    #[error(transparent)]
    Grid(#[from] envfield_grid::GridError),
    /// From envfield-mazes (datasets).
    #[error(transparent)]
    Maze(#[from] envfield_mazes::MazeError),
}

/// The result type of envfield-nets.
pub type Result<T, E = NetsError> = std::result::Result<T, E>;

fn display_paths(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(" and ")
}
