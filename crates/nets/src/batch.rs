//! [`Batch`]: the queries a network answers in one pass.

use crate::{ModelConfig, NetsError, Result};
use envfield_grid::{Cell2, Grid2, Point2};

/// Queries for a network: `items` (scene, goal) pairs, each with `per_item` query points.
/// Coordinates are in cell units (`[row, col]` in 2D, `[x, y, z]` in 3D), continuous.
#[derive(Clone, Debug, PartialEq)]
pub struct Batch {
    /// Cells per axis of every item's domain.
    pub extent: Vec<usize>,
    /// Number of (scene, goal) items.
    pub items: usize,
    /// Obstacle maps, `items * rows * cols` values (1 = obstacle, 0 = free), row-major; empty
    /// for networks that do not read the grid.
    pub obstacles: Vec<f32>,
    /// Goals, `items * dims` coordinates.
    pub goals: Vec<f32>,
    /// Query points per item.
    pub per_item: usize,
    /// Queries, `items * per_item * dims` coordinates.
    pub queries: Vec<f32>,
}

impl Batch {
    /// Every cell of `grid` as a query for `goal` (row-major order).
    pub fn whole_grid(grid: &Grid2, goal: Cell2) -> Self {
        let queries = (0..grid.len()).map(|i| grid.cell(i));
        Self::on_grid(
            grid,
            goal,
            queries.flat_map(|c| [c.row as f32, c.col as f32]),
        )
    }

    /// Every free cell of `grid` as a query for `goal` (row-major order): what a field needs,
    /// since obstacles are infinite whatever the network says.
    pub fn free_cells(grid: &Grid2, goal: Cell2) -> Self {
        let queries = grid.free_cells();
        Self::on_grid(
            grid,
            goal,
            queries.flat_map(|c| [c.row as f32, c.col as f32]),
        )
    }

    /// Continuous points of one 2D grid and goal.
    pub fn points(grid: &Grid2, goal: Cell2, points: &[Point2]) -> Self {
        Self::on_grid(grid, goal, points.iter().flat_map(|p| [p.row, p.col]))
    }

    /// One item: `grid` and `goal` with the `(row, col)` query coordinates `queries`.
    fn on_grid(grid: &Grid2, goal: Cell2, queries: impl Iterator<Item = f32>) -> Self {
        let queries: Vec<f32> = queries.collect();
        Self {
            extent: vec![grid.rows(), grid.cols()],
            items: 1,
            obstacles: obstacle_map(grid),
            goals: vec![goal.row as f32, goal.col as f32],
            per_item: queries.len() / 2,
            queries,
        }
    }

    /// Number of query points.
    pub fn len(&self) -> usize {
        self.items * self.per_item
    }

    /// Whether there is no query.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub(crate) fn check(&self, cfg: &ModelConfig) -> Result<()> {
        let d = self.extent.len();
        let bad = |m: String| Err(NetsError::InvalidInput(m));
        if d != cfg.dims() {
            return bad(format!(
                "{}-axis queries for a {}-axis {} network",
                d,
                cfg.dims(),
                cfg.arch()
            ));
        }
        let cells: usize = self.extent.iter().product();
        if self.items == 0 || self.per_item == 0 {
            return bad("an empty batch".into());
        }
        if self.goals.len() != self.items * d || self.queries.len() != self.len() * d {
            return bad(format!(
                "batch of {} items x {} queries needs {} goal and {} query coordinates (got {}, {})",
                self.items,
                self.per_item,
                self.items * d,
                self.len() * d,
                self.goals.len(),
                self.queries.len()
            ));
        }
        if cfg.reads_grid() && self.obstacles.len() != self.items * cells {
            return bad(format!(
                "the {} network reads the grid: need {} obstacle values, got {}",
                cfg.arch(),
                self.items * cells,
                self.obstacles.len()
            ));
        }
        for (what, xs) in [("goal", &self.goals), ("query", &self.queries)] {
            if let Some(i) = xs.iter().position(|x| !x.is_finite()) {
                return bad(format!("{what} coordinate {i} is not finite ({})", xs[i]));
            }
            for (i, x) in xs.iter().enumerate() {
                let n = self.extent[i % d] as f32;
                if *x < 0.0 || *x > n - 1.0 {
                    return bad(format!(
                        "{what} {} lies outside the domain {:?} (axis {} value {x})",
                        i / d,
                        self.extent,
                        i % d
                    ));
                }
            }
        }
        Ok(())
    }
}

fn obstacle_map(grid: &Grid2) -> Vec<f32> {
    grid.obstacles().iter().map(|&o| o as u8 as f32).collect()
}
