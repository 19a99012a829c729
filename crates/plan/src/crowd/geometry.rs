//! The geometry the crowd loops share: people's discs on a map, step candidates, swept steps
//! and closest approaches, field values at points.

use crate::Result;
use envfield_grid::{Cell2, Field2, FieldModel, Grid2, Point2};

/// The fields of `goals` on `maps`, `None` where the goal is covered on its map (someone
/// stands on it): one [`FieldModel::predict_many`] call for the rest.
pub(crate) fn predict_where_free(
    model: &impl FieldModel,
    maps: &[Grid2],
    goals: impl Iterator<Item = Cell2>,
) -> Result<Vec<Option<Field2>>> {
    let goals: Vec<Cell2> = goals.collect();
    let asked: Vec<(&Grid2, Cell2)> = maps
        .iter()
        .zip(&goals)
        .filter(|(m, &g)| m.is_free(g))
        .map(|(m, &g)| (m, g))
        .collect();
    let mut fields = model.predict_many(&asked)?.into_iter();
    Ok(maps
        .iter()
        .zip(&goals)
        .map(|(m, &g)| m.is_free(g).then(|| fields.next()).flatten())
        .collect())
}

/// `grid` with every cell whose centre is closer than `radius` cells to one of `centres`
/// blocked: other people on a person's map (at twice the body radius, in centre space).
///
/// # Errors
/// None in practice (the grid keeps its valid shape).
pub fn mark_discs(
    grid: &Grid2,
    centres: impl Iterator<Item = Point2>,
    radius: f32,
) -> Result<Grid2> {
    let (rows, cols) = (grid.rows(), grid.cols());
    let mut obstacles = grid.obstacles().to_vec();
    for p in centres {
        let r0 = (p.row - radius).floor().max(0.0) as usize;
        let c0 = (p.col - radius).floor().max(0.0) as usize;
        let r1 = ((p.row + radius).ceil().max(0.0) as usize).min(rows.saturating_sub(1));
        let c1 = ((p.col + radius).ceil().max(0.0) as usize).min(cols.saturating_sub(1));
        for r in r0..=r1 {
            for c in c0..=c1 {
                if Point2::new(r as f32, c as f32).distance(p) < radius {
                    obstacles[r * cols + c] = true;
                }
            }
        }
    }
    Ok(Grid2::from_obstacles(rows, cols, obstacles)?)
}

/// The points a step from `at` may end at: `directions` evenly spaced headings (the first
/// along -row) at the step length, half of it and one cell, and the goal itself when it is
/// within a step.
pub(crate) fn candidates(at: Point2, goal: Point2, step: f32, directions: usize) -> Vec<Point2> {
    let mut out: Vec<Point2> = [step, 0.5 * step, 1.0]
        .iter()
        .flat_map(|&len| {
            (0..directions).map(move |k| {
                let a = std::f32::consts::TAU * k as f32 / directions as f32;
                Point2::new(at.row - len * a.cos(), at.col + len * a.sin())
            })
        })
        .collect();
    if at.distance(goal) <= step {
        out.push(goal);
    }
    out
}

/// Whether the straight step from `a` to `b`, sampled every quarter cell, stays on free cells.
pub(crate) fn segment_clear(grid: &Grid2, a: Point2, b: Point2) -> bool {
    let n = (a.distance(b) / 0.25).ceil().max(1.0) as usize;
    (0..=n).all(|k| {
        let s = k as f32 / n as f32;
        Point2::new(a.row + s * (b.row - a.row), a.col + s * (b.col - a.col))
            .round()
            .is_some_and(|c| grid.contains(c) && grid.is_free(c))
    })
}

/// The smallest distance between two points moving in straight lines at constant speed over
/// the same time step, `a0 -> a1` and `b0 -> b1`.
pub fn closest_approach(a0: Point2, a1: Point2, b0: Point2, b1: Point2) -> f32 {
    let (dr, dc) = (a0.row - b0.row, a0.col - b0.col);
    let (vr, vc) = (
        (a1.row - a0.row) - (b1.row - b0.row),
        (a1.col - a0.col) - (b1.col - b0.col),
    );
    let vv = vr * vr + vc * vc;
    let s = match vv > 0.0 {
        true => (-(dr * vr + dc * vc) / vv).clamp(0.0, 1.0),
        false => 0.0,
    };
    (dr + s * vr).hypot(dc + s * vc)
}

/// The field's value at the cell under `p`, infinite off the grid.
pub(crate) fn value_at(field: &Field2, p: Point2) -> f32 {
    p.round().map_or(f32::INFINITY, |c| value(field, c))
}

pub(crate) fn value(field: &Field2, c: Cell2) -> f32 {
    field.get(c).unwrap_or(f32::INFINITY)
}

pub(crate) fn point(c: Cell2) -> Point2 {
    Point2::new(c.row as f32, c.col as f32)
}
