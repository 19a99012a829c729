use crate::{PlanError, Result};
use envfield_grid::{Cell2, Grid2};
use serde::{Deserialize, Serialize};

/// A planned path on a grid and its statistics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanOutcome {
    /// The cells visited in order, start first (empty when the planner found nothing).
    pub path: Vec<Cell2>,
    /// Whether the path ends on the goal.
    pub success: bool,
}

impl PlanOutcome {
    /// Number of moves (cells - 1).
    pub fn steps(&self) -> usize {
        self.path.len().saturating_sub(1)
    }

    /// Path length: orthogonal moves 1, diagonal moves sqrt 2.
    pub fn length(&self) -> f32 {
        path_length(&self.path)
    }
}

/// Length of a path of neighbouring cells (orthogonal 1, diagonal sqrt 2).
pub fn path_length(path: &[Cell2]) -> f32 {
    path.windows(2)
        .map(|w| {
            if w[0].row != w[1].row && w[0].col != w[1].col {
                std::f32::consts::SQRT_2
            } else {
                1.0
            }
        })
        .sum()
}

/// Plans a path from a start to a goal on a grid.
///
/// `max_steps` bounds the moves a planner may make (the harness passes the protocol's budget);
/// a planner that does not reach the goal within it returns `success: false` with the path it
/// walked. `Err` is for bad input (a start or goal outside the grid or on an obstacle) or a
/// broken model, never for "no path".
pub trait Planner {
    /// A short name for tables ("fmm", "astar", ...).
    fn name(&self) -> &str;

    /// Plans from `start` to `goal` in at most `max_steps` moves.
    ///
    /// # Errors
    /// Bad input or a failing model.
    fn plan(
        &self,
        grid: &Grid2,
        start: Cell2,
        goal: Cell2,
        max_steps: usize,
    ) -> Result<PlanOutcome>;
}

/// Checks that `start` and `goal` are free cells of `grid`.
pub(crate) fn check_query(grid: &Grid2, start: Cell2, goal: Cell2) -> Result<()> {
    grid.check_free(start, "start").map_err(PlanError::from)?;
    grid.check_free(goal, "goal").map_err(PlanError::from)?;
    Ok(())
}
