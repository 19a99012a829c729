//! [`VaeError`]: everything that can go wrong in envfield-vae.

use std::path::PathBuf;

/// An error of envfield-vae.
#[derive(Debug, thiserror::Error)]
pub enum VaeError {
    /// A setting that cannot work, named.
    #[error("invalid config: {0}")]
    InvalidConfig(String),
    /// Input that cannot be used (an empty cloud, a NaN coordinate, a torso without a kind),
    /// with what is wrong and where.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A weight file or checkpoint that does not fit.
    #[error("{path}: {reason}")]
    Checkpoint {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// Training produced a loss that is not finite.
    #[error("training diverged at step {step} (loss {loss})")]
    Diverged {
        /// The step.
        step: u64,
        /// The loss.
        loss: f32,
    },
    /// From envfield-nets.
    #[error(transparent)]
    Nets(#[from] envfield_nets::NetsError),
    /// From envfield-grid.
    #[error(transparent)]
    Grid(#[from] envfield_grid::GridError),
    /// From candle.
    #[error(transparent)]
    Candle(#[from] candle_core::Error),
}

/// The result type of envfield-vae.
pub type Result<T> = std::result::Result<T, VaeError>;
