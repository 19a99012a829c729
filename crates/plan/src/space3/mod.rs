//! Planning in 3D among obstacles (paper section 4.2): the pose-dependent search on a
//! continuous field ([`FieldSearch3`], each step's 26 candidates asked in one batch and filtered
//! by a [`StepFilter`]) and the sampling baselines [`rrt`], [`rrt_star`] and [`prm`] on any
//! [`Space3`], all giving a [`Path3`].

mod sampling;
mod search;

pub use sampling::{edge_free, prm, rrt, rrt_star, SamplingConfig, Space3};
pub use search::FieldSearch3;

use crate::{PlanError, Result};
use envfield_grid::Point3m;
use serde::{Deserialize, Serialize};

/// Which candidate torso locations a step may move to.
pub trait StepFilter {
    /// For step `step` (0 for the first move) from `from`: whether each of `candidates` is
    /// allowed.
    ///
    /// # Errors
    /// When the check itself fails (a bad point, a failing scene query).
    fn keep(&self, step: usize, from: Point3m, candidates: &[Point3m]) -> Result<Vec<bool>>;

    /// [`StepFilter::keep`] of one candidate, `to`: what a search asks of each step it takes.
    /// A filter may answer it without the list's allocation.
    ///
    /// # Errors
    /// As [`StepFilter::keep`].
    fn keep_one(&self, step: usize, from: Point3m, to: Point3m) -> Result<bool> {
        Ok(self.keep(step, from, &[to])?[0])
    }

    /// Whether `p` could be allowed at all, whatever the step: a cheap necessary condition
    /// (the free space alone, before any pose), which a caller with many points to check
    /// asks of them all first. Every point, unless the filter says otherwise.
    fn may_keep(&self, _p: Point3m) -> bool {
        true
    }
}

/// Every candidate is allowed.
#[derive(Clone, Copy, Debug, Default)]
pub struct AnyStep;

impl StepFilter for AnyStep {
    fn keep(&self, _: usize, _: Point3m, candidates: &[Point3m]) -> Result<Vec<bool>> {
        Ok(vec![true; candidates.len()])
    }
}

/// A path in 3D and how it ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Path3 {
    /// The torso locations, start first.
    pub points: Vec<Point3m>,
    /// The last point lies within the tolerance of the goal.
    pub reached: bool,
    /// Distance from the last point to the goal, metres.
    pub final_distance: f32,
    /// The search opened every point its filter allows before reaching the goal or spending
    /// its budget: no allowed route to the goal exists on its lattice. Only
    /// [`FieldSearch3::search`] sets it.
    #[serde(default)]
    pub exhausted: bool,
    /// Some steps passed only the looser filter of [`FieldSearch3::search_relaxed`]: the
    /// strict filter allowed no route within the budget.
    #[serde(default)]
    pub relaxed: bool,
}

impl Path3 {
    /// A path of `points` judged against `goal` with `tolerance`.
    pub fn ending(points: Vec<Point3m>, goal: Point3m, tolerance: f32) -> Self {
        let last = *points.last().unwrap_or(&[f32::INFINITY; 3]);
        let d = distance(last, goal);
        Self {
            points,
            reached: d <= tolerance,
            final_distance: d,
            exhausted: false,
            relaxed: false,
        }
    }

    /// The polyline's length, metres.
    pub fn length(&self) -> f32 {
        self.points.windows(2).map(|w| distance(w[0], w[1])).sum()
    }
}

/// Euclidean distance.
pub fn distance(a: Point3m, b: Point3m) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The 26 unit directions of `{-1, 0, 1}^3 \ {0}`.
pub fn directions26() -> [Point3m; 26] {
    let mut out = [[0.0; 3]; 26];
    let mut k = 0;
    for x in -1i32..=1 {
        for y in -1i32..=1 {
            for z in -1i32..=1 {
                if (x, y, z) == (0, 0, 0) {
                    continue;
                }
                let n = ((x * x + y * y + z * z) as f32).sqrt();
                out[k] = [x as f32 / n, y as f32 / n, z as f32 / n];
                k += 1;
            }
        }
    }
    out
}

/// The straight line from `start` to `goal` at `step` metres per point, the goal last: the
/// no-learning floor of the 3D tables.
///
/// # Errors
/// [`PlanError::Invalid`] for a step that is not positive or a point that is not finite.
pub fn straight_line(start: Point3m, goal: Point3m, step: f32) -> Result<Vec<Point3m>> {
    if !(step.is_finite() && step > 0.0 && start.iter().chain(&goal).all(|v| v.is_finite())) {
        return Err(PlanError::Invalid(format!(
            "straight line: a positive step and finite ends (got {step}, {start:?}, {goal:?})"
        )));
    }
    let d = distance(start, goal);
    let n = (d / step).ceil().max(1.0) as usize;
    Ok((0..=n)
        .map(|i| {
            let t = i as f32 / n as f32;
            std::array::from_fn(|a| start[a] + t * (goal[a] - start[a]))
        })
        .collect())
}
