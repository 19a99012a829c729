//! Crowd problems: checking trips, drawing random ones, and each person's shortest path.

use super::geometry::{point, value};
use super::{CrowdConfig, Trip};
use crate::{PlanError, Result};
use envfield_eikonal::{FastMarching, Order};
use envfield_grid::{Cell2, Grid2, SplitMix64};

/// Checks a crowd problem: every start and goal on a free cell of `walkable`, starts at least
/// twice the body radius apart, no more people than fit on the free floor, and every goal
/// reachable from its start on the empty map.
///
/// # Errors
/// [`PlanError::Invalid`] naming the person and what is wrong.
pub fn check_trips(walkable: &Grid2, trips: &[Trip], config: &CrowdConfig) -> Result<()> {
    config.validate()?;
    if trips.is_empty() {
        return Err(PlanError::Invalid(
            "a crowd needs at least one person".into(),
        ));
    }
    let capacity = capacity(walkable, config);
    if trips.len() > capacity {
        return Err(PlanError::Invalid(format!(
            "{} people do not fit on {} free cells (at most {capacity} bodies of radius {} cells)",
            trips.len(),
            walkable.free_count(),
            config.body_radius
        )));
    }
    for (i, trip) in trips.iter().enumerate() {
        for (what, cell) in [("start", trip.start), ("goal", trip.goal)] {
            if !walkable.contains(cell) {
                return Err(PlanError::Invalid(format!(
                    "person {i}'s {what} {cell:?} is outside the {}x{} floor map",
                    walkable.rows(),
                    walkable.cols()
                )));
            }
            if walkable.is_obstacle(cell) {
                return Err(PlanError::Invalid(format!(
                    "person {i}'s {what} {cell:?} is on furniture, a wall or too close to one \
                     for a body of radius {} cells",
                    config.body_radius
                )));
            }
        }
        for (j, other) in trips.iter().enumerate().take(i) {
            let d = point(other.start).distance(point(trip.start));
            if d < 2.0 * config.body_radius {
                return Err(PlanError::Invalid(format!(
                    "persons {j} and {i} start {d:.2} cells apart, closer than two body radii \
                     ({:.2}): their bodies overlap",
                    2.0 * config.body_radius
                )));
            }
        }
    }
    let fields = FastMarching::default()
        .solve2_batch(&trips.iter().map(|t| (walkable, t.goal)).collect::<Vec<_>>())?;
    for (i, (trip, field)) in trips.iter().zip(&fields).enumerate() {
        if !value(field, trip.start).is_finite() {
            return Err(PlanError::Invalid(format!(
                "person {i}'s goal {:?} cannot be reached from their start {:?} on the floor map",
                trip.goal, trip.start
            )));
        }
    }
    Ok(())
}

/// `people` random trips on `walkable`, seeded: starts and goals on the largest 4-connected
/// free region, starts (and goals) at least two body radii and a cell apart, each goal at
/// least `min_length` cells in a straight line from its start.
///
/// # Errors
/// [`PlanError::Invalid`] when the map has no free cell or that many people cannot be placed
/// (after `2000 x people` draws).
pub fn random_trips(
    walkable: &Grid2,
    people: usize,
    config: &CrowdConfig,
    min_length: f32,
    seed: u64,
) -> Result<Vec<Trip>> {
    config.validate()?;
    let cells = largest_region(walkable);
    if cells.is_empty() {
        return Err(PlanError::Invalid(
            "the walkable map has no free cell".into(),
        ));
    }
    if people > capacity(walkable, config) {
        return Err(PlanError::Invalid(format!(
            "{people} people do not fit on {} free cells (at most {} bodies of radius {} cells)",
            walkable.free_count(),
            capacity(walkable, config),
            config.body_radius
        )));
    }
    let apart = 2.0 * config.body_radius + 1.0;
    let far = |a: Cell2, b: Cell2, d: f32| point(a).distance(point(b)) >= d;
    let mut rng = SplitMix64::new(seed ^ 0xC0_FFEE);
    let mut trips: Vec<Trip> = Vec::new();
    for _ in 0..people.saturating_mul(2000) {
        if trips.len() == people {
            break;
        }
        let (start, goal) = (cells[rng.below(cells.len())], cells[rng.below(cells.len())]);
        let separate = trips
            .iter()
            .all(|t| far(t.start, start, apart) && far(t.goal, goal, apart));
        if separate && far(start, goal, min_length) {
            trips.push(Trip { start, goal });
        }
    }
    if trips.len() < people {
        return Err(PlanError::Invalid(format!(
            "could not place {people} people with separate starts and goals on {} free cells \
             (placed {})",
            cells.len(),
            trips.len()
        )));
    }
    Ok(trips)
}

/// The cells of the largest 4-connected free region of `grid`.
fn largest_region(grid: &Grid2) -> Vec<Cell2> {
    let (rows, cols) = (grid.rows(), grid.cols());
    let mut seen = vec![false; grid.len()];
    let mut best: Vec<Cell2> = Vec::new();
    for first in 0..grid.len() {
        if seen[first] || grid.obstacles()[first] {
            continue;
        }
        seen[first] = true;
        let mut region = vec![grid.cell(first)];
        let mut k = 0;
        while k < region.len() {
            let c = region[k];
            k += 1;
            let next = [
                (c.row > 0).then(|| Cell2::new(c.row.wrapping_sub(1), c.col)),
                (c.row + 1 < rows).then(|| Cell2::new(c.row + 1, c.col)),
                (c.col > 0).then(|| Cell2::new(c.row, c.col.wrapping_sub(1))),
                (c.col + 1 < cols).then(|| Cell2::new(c.row, c.col + 1)),
            ];
            for n in next.into_iter().flatten() {
                let i = n.row * cols + n.col;
                if !seen[i] && !grid.obstacles()[i] {
                    seen[i] = true;
                    region.push(n);
                }
            }
        }
        if region.len() > best.len() {
            best = region;
        }
    }
    best
}

/// How many bodies fit on the free floor at most: discs of diameter two body radii packed in
/// squares (a generous bound; at least 1).
fn capacity(walkable: &Grid2, config: &CrowdConfig) -> usize {
    let side = 2.0 * config.body_radius;
    ((walkable.free_count() as f32 / (side * side)).floor() as usize).max(1)
}

/// Each person's shortest path length on the empty `walkable` map, in cells (second-order fast
/// marching): what path ratios divide by.
///
/// # Errors
/// As [`FastMarching::solve2`].
pub fn shortest_lengths(walkable: &Grid2, trips: &[Trip]) -> Result<Vec<f32>> {
    let fields = FastMarching::with_order(Order::Second)
        .solve2_batch(&trips.iter().map(|t| (walkable, t.goal)).collect::<Vec<_>>())?;
    Ok(trips
        .iter()
        .zip(&fields)
        .map(|(t, f)| value(f, t.start))
        .collect())
}
