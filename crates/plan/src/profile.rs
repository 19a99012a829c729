//! Where field descent goes wrong: its decisions and outcomes from every reachable cell,
//! grouped by the cell's true distance to the goal.

use crate::{descend, PlanError, Result};
use envfield_eikonal::{bfs2, dijkstra2};
use envfield_grid::is_wrong_move;
use envfield_grid::{Cell2, Field2, Grid2, MoveRule, Neighbourhood2};
use serde::{Deserialize, Serialize};

/// The cells of one distance band of a [`DecisionProfile`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Band {
    /// Reachable cells in the band (the goal excluded).
    pub cells: usize,
    /// Cells where descent's move (the move of least field value, ties to the first
    /// direction, as [`descend`] takes it) is not a shortest move: its true distance exceeds
    /// the best move's.
    pub wrong: usize,
    /// Cells from which descent does not reach the goal within the evaluation protocol's budget (twice the
    /// fewest cells on a path).
    pub failing: usize,
}

/// Decision quality of a field by true distance to the goal: every reachable cell of every
/// (grid, goal) added is a start. Success rates over random pairs hide where a learned field
/// errs; this shows it, for example that a network's mistakes grow with the distance it has
/// to reason over.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DecisionProfile {
    /// Width of each band in distance units (cells); band `k` holds distances in
    /// `[k * width, (k + 1) * width)`.
    pub width: f32,
    /// The bands, from the goal outwards.
    pub bands: Vec<Band>,
}

impl DecisionProfile {
    /// An empty profile with bands `width` cells wide.
    ///
    /// # Errors
    /// [`PlanError::Invalid`] for a width that is not finite and positive.
    pub fn new(width: f32) -> Result<Self> {
        if !(width.is_finite() && width > 0.0) {
            return Err(PlanError::Invalid(format!(
                "profile band width must be finite and positive, got {width}"
            )));
        }
        Ok(Self {
            width,
            bands: Vec::new(),
        })
    }

    /// Adds every reachable cell of `grid` for `goal`, with `field` the field descent walks
    /// down and `rule` the agent's move rule. Exact distances (orthogonal 1, diagonal
    /// sqrt 2) judge the moves.
    ///
    /// # Errors
    /// A goal outside `grid` or on an obstacle; [`PlanError::Invalid`] for a field of another
    /// shape.
    pub fn add(&mut self, grid: &Grid2, rule: MoveRule, goal: Cell2, field: &Field2) -> Result<()> {
        if (field.rows(), field.cols()) != (grid.rows(), grid.cols()) {
            return Err(PlanError::Invalid(format!(
                "field is {}x{}, grid {}x{}",
                field.rows(),
                field.cols(),
                grid.rows(),
                grid.cols()
            )));
        }
        grid.check_free(goal, "goal")?;
        let nb = Neighbourhood2::Eight(rule);
        let truth = dijkstra2(grid, &[goal], nb, std::f32::consts::SQRT_2)?;
        let steps = bfs2(grid, &[goal], nb)?;
        let dist = |c: Cell2| truth.get(c).unwrap_or(f32::INFINITY);
        for cell in grid.free_cells() {
            let d = dist(cell);
            if !d.is_finite() || cell == goal {
                continue;
            }
            let wrong = is_wrong_move(grid, field, rule, cell, dist);
            let budget = 2 * (steps.get(cell).unwrap_or(0.0) as usize + 1);
            let failing = !descend(grid, field, rule, cell, goal, budget).success;
            let k = (d / self.width) as usize;
            if self.bands.len() <= k {
                self.bands.resize(k + 1, Band::default());
            }
            let band = &mut self.bands[k];
            band.cells += 1;
            band.wrong += wrong as usize;
            band.failing += failing as usize;
        }
        Ok(())
    }

    /// The profile as a text table under a heading naming `label` and `planner`: per band of
    /// distance, the cells and the shares of wrong and failing moves, then all bands.
    pub fn table(&self, label: &str, planner: &str) -> String {
        use std::fmt::Write;
        let pct = |n: usize, of: usize| 100.0 * n as f64 / of.max(1) as f64;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{label}, {planner}: descent from every reachable cell, by distance to the goal"
        );
        let _ = writeln!(
            out,
            "{:>9} {:>8} {:>9} {:>10}",
            "distance", "cells", "wrong %", "failing %"
        );
        for (k, b) in self.bands.iter().enumerate().filter(|(_, b)| b.cells > 0) {
            let (lo, hi) = (k as f32 * self.width, (k + 1) as f32 * self.width);
            let band = format!("{lo}-{hi}");
            let (w, f) = (pct(b.wrong, b.cells), pct(b.failing, b.cells));
            let _ = writeln!(out, "{band:>9} {:>8} {w:>9.2} {f:>10.2}", b.cells);
        }
        let t = self.total();
        let (w, f) = (pct(t.wrong, t.cells), pct(t.failing, t.cells));
        let _ = writeln!(out, "{:>9} {:>8} {w:>9.2} {f:>10.2}", "all", t.cells);
        out
    }

    /// All bands together.
    pub fn total(&self) -> Band {
        self.bands.iter().fold(Band::default(), |a, b| Band {
            cells: a.cells + b.cells,
            wrong: a.wrong + b.wrong,
            failing: a.failing + b.failing,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 5x5 room with a wall across the middle row but for its last cell; goal top-left.
    fn room() -> (Grid2, Cell2) {
        let mut grid = Grid2::new(5, 5).unwrap();
        for c in 0..4 {
            grid.set_obstacle(Cell2::new(2, c), true).unwrap();
        }
        (grid, Cell2::new(0, 0))
    }

    #[test]
    fn the_exact_field_makes_no_mistake_and_a_pit_is_found() {
        let (grid, goal) = room();
        let nb = Neighbourhood2::Eight(MoveRule::Strict);
        let exact = dijkstra2(&grid, &[goal], nb, std::f32::consts::SQRT_2).unwrap();
        let mut p = DecisionProfile::new(2.0).unwrap();
        p.add(&grid, MoveRule::Strict, goal, &exact).unwrap();
        let total = p.total();
        assert_eq!(
            total,
            Band {
                cells: 20,
                wrong: 0,
                failing: 0
            }
        );
        // A pit at (4, 0), the farthest cell: its three neighbours step into it (wrong moves)
        // and their walks, like the pit's own, end in a loop; the rest of the room is fine.
        let mut pit = exact.clone();
        pit.values_mut()[4 * 5] = 0.0;
        let mut q = DecisionProfile::new(2.0).unwrap();
        q.add(&grid, MoveRule::Strict, goal, &pit).unwrap();
        assert_eq!(
            q.total(),
            Band {
                cells: 20,
                wrong: 3,
                failing: 4
            },
            "{:?}",
            q.bands
        );
        // The pit is the farthest cell, so its band is the last.
        let far = (dijkstra2(&grid, &[goal], nb, std::f32::consts::SQRT_2).unwrap())
            .get(Cell2::new(4, 0))
            .unwrap();
        assert_eq!(q.bands.len(), (far / 2.0) as usize + 1);
        assert!(q.bands.last().unwrap().failing >= 1);
    }

    #[test]
    fn bad_width_and_mismatched_field_are_errors() {
        assert!(DecisionProfile::new(0.0).is_err());
        assert!(DecisionProfile::new(f32::NAN).is_err());
        let (grid, goal) = room();
        let field = Field2::new(4, 5, vec![0.0; 20]).unwrap();
        let err = DecisionProfile::new(1.0)
            .unwrap()
            .add(&grid, MoveRule::Vin, goal, &field)
            .unwrap_err();
        assert!(err.to_string().contains("4x5"), "{err}");
    }
}
