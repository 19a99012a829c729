use envfield_grid::GridError;

/// Everything that can go wrong in `envfield-plan`.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// From the grid types or a field model.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// From the solvers.
    #[error(transparent)]
    Eikonal(#[from] envfield_eikonal::EikonalError),
    /// From the maze crate.
    #[error(transparent)]
    Maze(#[from] envfield_mazes::MazeError),
    /// A planner setting or query is invalid.
    #[error("{0}")]
    Invalid(String),
}

/// `Result` with [`PlanError`].
pub type Result<T, E = PlanError> = std::result::Result<T, E>;
