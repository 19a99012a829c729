//! What planners and learners both need to know about moving on a grid: the move descent
//! takes, whether it is a wrong one, the octile distance, and the shape of a policy.

use crate::{Cell2, Field2, Grid2, MoveRule, Neighbourhood2, Result};

/// The octile distance between two cells: the length of a shortest path with orthogonal steps
/// of 1 and diagonal steps of sqrt 2 on a grid without obstacles. It is blind to walls: the
/// wall-blind control for learned fields, and A*'s heuristic.
///
/// ```
/// use envfield_grid::{octile_distance, Cell2};
/// let d = octile_distance(Cell2::new(0, 0), Cell2::new(3, 1));
/// assert!((d - (2.0 + 2f32.sqrt())).abs() < 1e-6);
/// ```
pub fn octile_distance(a: Cell2, b: Cell2) -> f32 {
    let dr = a.row.abs_diff(b.row) as f32;
    let dc = a.col.abs_diff(b.col) as f32;
    dr.max(dc) + (std::f32::consts::SQRT_2 - 1.0) * dr.min(dc)
}

/// The move field descent takes from `cell`: the neighbour under `rule` of least finite value
/// in `field`, ties to the first direction in [`crate::DIRECTIONS_8`] order; `None` when every
/// neighbour is infinite (or `cell` is an obstacle). O(8).
pub fn descent_move(grid: &Grid2, field: &Field2, rule: MoveRule, cell: Cell2) -> Option<Cell2> {
    let mut best: Option<(Cell2, f32)> = None;
    for (next, _) in grid.neighbours(cell, Neighbourhood2::Eight(rule)) {
        let v = field.get(next).unwrap_or(f32::INFINITY);
        if v.is_finite() && best.is_none_or(|(_, b)| v < b) {
            best = Some((next, v));
        }
    }
    best.map(|(next, _)| next)
}

/// Whether descent's move from `cell` (see [`descent_move`]) is wrong: its true distance, by
/// `distance`, exceeds the best move's (up to a relative 1e-4), or there is no move at all.
pub fn is_wrong_move(
    grid: &Grid2,
    field: &Field2,
    rule: MoveRule,
    cell: Cell2,
    distance: impl Fn(Cell2) -> f32,
) -> bool {
    let best = grid
        .neighbours(cell, Neighbourhood2::Eight(rule))
        .map(|(n, _)| distance(n))
        .fold(f32::INFINITY, f32::min);
    descent_move(grid, field, rule, cell).is_none_or(|n| distance(n) > best + 1e-4 * best.max(1.0))
}

/// A policy on a grid: scores for the eight moves from a cell towards a goal, higher is
/// better, in [`crate::DIRECTIONS_8`] order. It is the shape of planners that decide one move
/// at a time, such as VIN; `envfield_plan::PolicyWalk` walks any policy.
pub trait Policy {
    /// A short name for tables ("vin", ...).
    fn name(&self) -> &str;

    /// The move rule the policy's moves follow.
    fn rule(&self) -> MoveRule;

    /// The scores of the eight moves from `state` towards `goal` on `grid`.
    ///
    /// # Errors
    /// A state or goal outside the grid or on an obstacle; a failing model
    /// ([`crate::GridError::Model`]).
    fn action_scores(&self, grid: &Grid2, goal: Cell2, state: Cell2) -> Result<[f32; 8]>;
}

impl<P: Policy + ?Sized> Policy for &P {
    fn name(&self) -> &str {
        (**self).name()
    }

    fn rule(&self) -> MoveRule {
        (**self).rule()
    }

    fn action_scores(&self, grid: &Grid2, goal: Cell2, state: Cell2) -> Result<[f32; 8]> {
        (**self).action_scores(grid, goal, state)
    }
}

impl<P: Policy + ?Sized> Policy for Box<P> {
    fn name(&self) -> &str {
        (**self).name()
    }

    fn rule(&self) -> MoveRule {
        (**self).rule()
    }

    fn action_scores(&self, grid: &Grid2, goal: Cell2, state: Cell2) -> Result<[f32; 8]> {
        (**self).action_scores(grid, goal, state)
    }
}
