//! [`RoomsError`]: everything that can go wrong in envfield-rooms.

use std::path::PathBuf;

/// An error of envfield-rooms.
#[derive(Debug, thiserror::Error)]
pub enum RoomsError {
    /// A setting that cannot work, named.
    #[error("invalid config: {0}")]
    InvalidConfig(String),
    /// Input that cannot be used (no samples, a NaN coordinate, a goal outside the region),
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
    /// From envfield-vae.
    #[error(transparent)]
    Vae(#[from] envfield_vae::VaeError),
    /// From envfield-nets.
    #[error(transparent)]
    Nets(#[from] envfield_nets::NetsError),
    /// From envfield-scene.
    #[error(transparent)]
    Scene(#[from] envfield_scene::SceneError),
    /// From envfield-affordance.
    #[error(transparent)]
    Affordance(#[from] envfield_affordance::AffordanceError),
    /// From envfield-grid.
    #[error(transparent)]
    Grid(#[from] envfield_grid::GridError),
    /// From envfield-eikonal.
    #[error(transparent)]
    Eikonal(#[from] envfield_eikonal::EikonalError),
    /// From envfield-mazes.
    #[error(transparent)]
    Mazes(#[from] envfield_mazes::MazeError),
    /// From envfield-plan.
    #[error(transparent)]
    Plan(#[from] envfield_plan::PlanError),
}

/// The result type of envfield-rooms.
pub type Result<T> = std::result::Result<T, RoomsError>;
