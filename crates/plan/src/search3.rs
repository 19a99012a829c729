//! Pose-dependent search on a continuous 3D field (paper section 4.2, "Pose-dependent
//! trajectory"): from the start, step `s` towards each of the 26 directions of
//! `{-1, 0, 1}^3 \ {0}`, normalised so every candidate lies exactly `s` away; ask the field at
//! all candidates in one batch, keep the ones a [`StepFilter`] allows (the pose of this step
//! supported and collision-free, or simply inside the accessible region), and move to the
//! smallest value; where the filter leaves no way down, go on from the best point left
//! (greedy best-first, [`FieldSearch3::search`]).

use crate::{PlanError, Result};
use envfield_grid::{ContinuousField3, Point3m};
use serde::{Deserialize, Serialize};
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashSet};

/// Which candidate torso locations a step may move to.
pub trait StepFilter {
    /// For step `step` (0 for the first move) from `from`: whether each of `candidates` is
    /// allowed.
    ///
    /// # Errors
    /// When the check itself fails (a bad point, a failing scene query).
    fn keep(&self, step: usize, from: Point3m, candidates: &[Point3m]) -> Result<Vec<bool>>;
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

/// The pose-dependent search's settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FieldSearch3 {
    /// Step length `s`, metres (the pose sequence's `step_length`).
    pub step: f32,
    /// The search stops when the torso is this close to the goal, metres.
    pub tolerance: f32,
    /// Expansions at most (each one batched field query and one filter call).
    pub max_steps: usize,
}

impl FieldSearch3 {
    /// Searches from `start` to `goal` on `field`, each step's candidates filtered by
    /// `filter`: greedy best-first on the field's values. Each expansion takes the open point
    /// of least value, asks the field at its 26 candidates in one batch, and opens those the
    /// filter allows (a point within `s / 2` of one already opened is not opened again). Where
    /// the field has no local minimum under the filter this is exactly the paper's descent,
    /// moving to the smallest candidate at every step; where the filter blocks that descent
    /// (the pose of the best step would collide), the search goes on from the best point left
    /// instead of stopping. When the goal lies within `s` and the filter allows it, the path
    /// lands on it. The path is the chain of steps from the start to the point it ends on:
    /// the goal, or after `max_steps` expansions the opened point nearest the goal (then
    /// `reached` is false). A step's filter call gets the step's index along that chain.
    ///
    /// # Errors
    /// [`PlanError::Invalid`] for a step, tolerance or point that is not positive / finite;
    /// errors of the filter.
    pub fn search<F, S>(
        &self,
        field: &F,
        filter: &S,
        start: Point3m,
        goal: Point3m,
    ) -> Result<Path3>
    where
        F: ContinuousField3 + ?Sized,
        S: StepFilter + ?Sized,
    {
        let ok = self.step.is_finite()
            && self.step > 0.0
            && self.tolerance.is_finite()
            && self.tolerance >= 0.0;
        if !ok {
            return Err(PlanError::Invalid(format!(
                "3D search: a positive step and a tolerance >= 0 (got {} and {}); a pose \
                 sequence with no motion has step length 0",
                self.step, self.tolerance
            )));
        }
        for (what, p) in [("start", start), ("goal", goal)] {
            if !p.iter().all(|v| v.is_finite()) {
                return Err(PlanError::Invalid(format!(
                    "3D search: {what} {p:?} is not finite"
                )));
            }
        }
        let dirs = directions26();
        let s = self.step;
        let key = |p: Point3m| p.map(|v| (v / (0.5 * s)).round() as i64);
        // Opened points: position, parent, depth (the index along its chain).
        let mut nodes: Vec<(Point3m, usize, usize)> = vec![(start, usize::MAX, 0)];
        let mut opened = HashSet::from([key(start)]);
        let mut open = BinaryHeap::new();
        let start_value = values_or_infinity(field, &[start])[0];
        open.push(Reverse((Order(start_value), 0usize)));
        let mut nearest = (distance(start, goal), 0usize);
        let mut end = None;
        let mut exhausted = false;
        for _ in 0..self.max_steps {
            let Some(Reverse((_, n))) = open.pop() else {
                exhausted = true;
                break;
            };
            let (here, _, depth) = nodes[n];
            let d = distance(here, goal);
            if d <= self.tolerance {
                end = Some(n);
                break;
            }
            if d <= s && filter.keep(depth, here, &[goal])?[0] {
                nodes.push((goal, n, depth + 1));
                end = Some(nodes.len() - 1);
                break;
            }
            let candidates: Vec<Point3m> = dirs
                .iter()
                .map(|v| [here[0] + s * v[0], here[1] + s * v[1], here[2] + s * v[2]])
                .collect();
            let values = values_or_infinity(field, &candidates);
            let keep = filter.keep(depth, here, &candidates)?;
            for (i, c) in candidates.into_iter().enumerate() {
                if keep[i] && values[i].is_finite() && opened.insert(key(c)) {
                    nodes.push((c, n, depth + 1));
                    let id = nodes.len() - 1;
                    let dc = distance(c, goal);
                    if dc < nearest.0 {
                        nearest = (dc, id);
                    }
                    open.push(Reverse((Order(values[i]), id)));
                }
            }
        }
        let mut chain = Vec::new();
        let mut at = end.unwrap_or(nearest.1);
        while at != usize::MAX {
            chain.push(nodes[at].0);
            at = nodes[at].1;
        }
        chain.reverse();
        Ok(Path3 {
            exhausted,
            ..Path3::ending(chain, goal, self.tolerance)
        })
    }
}

/// An f32 ordered by `total_cmp`, for the open list.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Order(f32);

impl Eq for Order {}

impl PartialOrd for Order {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Order {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// The field at every candidate in one call; a batch that fails (a point outside the field's
/// box) is asked point by point, and the failing points are infinite.
fn values_or_infinity<F: ContinuousField3 + ?Sized>(field: &F, points: &[Point3m]) -> Vec<f32> {
    match field.values(points) {
        Ok(v) => v,
        Err(_) => points
            .iter()
            .map(|&p| field.value(p).unwrap_or(f32::INFINITY))
            .collect(),
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The distance to a goal point in open space.
    struct Cone(Point3m);

    impl ContinuousField3 for Cone {
        fn value(&self, p: Point3m) -> envfield_grid::Result<f32> {
            Ok(distance(p, self.0))
        }
        fn gradient(&self, _: Point3m) -> envfield_grid::Result<Option<Point3m>> {
            Ok(None)
        }
    }

    /// No candidate with z below 0.5 (a floor the torso must stay above).
    struct Above(f32);

    impl StepFilter for Above {
        fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
            Ok(c.iter().map(|p| p[2] >= self.0).collect())
        }
    }

    /// A walled-in start: the search opens every point of the box and says so.
    #[test]
    fn a_start_walled_in_by_the_filter_exhausts_the_search() {
        struct Cube;
        impl StepFilter for Cube {
            fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
                Ok(c.iter().map(|p| p.iter().all(|v| v.abs() <= 0.3)).collect())
            }
        }
        let goal = [1.0, 0.0, 0.0];
        let search = FieldSearch3 {
            step: 0.1,
            tolerance: 0.02,
            max_steps: 100_000,
        };
        let path = search.search(&Cone(goal), &Cube, [0.0; 3], goal).unwrap();
        assert!(!path.reached && path.exhausted, "{path:?}");
        assert!((path.final_distance - 0.7).abs() < 0.05, "{path:?}");
        let open = search
            .search(&Cone(goal), &AnyStep, [0.0; 3], goal)
            .unwrap();
        assert!(open.reached && !open.exhausted);
    }

    #[test]
    fn the_search_walks_a_cone_to_its_goal_near_the_straight_line() {
        let goal = [2.0, 1.0, 1.0];
        let search = FieldSearch3 {
            step: 0.1,
            tolerance: 0.02,
            max_steps: 200,
        };
        let path = search
            .search(&Cone(goal), &AnyStep, [0.0, 0.0, 1.0], goal)
            .unwrap();
        assert!(path.reached, "{path:?}");
        assert!(distance(*path.points.last().unwrap(), goal) <= 0.02);
        let straight = distance([0.0, 0.0, 1.0], goal);
        assert!(
            path.length() < 1.1 * straight,
            "{} against {straight}",
            path.length()
        );
        // Every step is s long but the last.
        for w in path.points[..path.points.len() - 1].windows(2) {
            assert!((distance(w[0], w[1]) - 0.1).abs() < 1e-5);
        }
    }

    #[test]
    fn the_filter_is_obeyed_and_a_dead_end_stops_the_walk() {
        let goal = [1.0, 0.0, 0.0];
        let search = FieldSearch3 {
            step: 0.1,
            tolerance: 0.02,
            max_steps: 100,
        };
        let path = search
            .search(&Cone(goal), &Above(0.5), [0.0, 0.0, 1.0], goal)
            .unwrap();
        assert!(!path.reached);
        assert!(
            !path.exhausted,
            "the half-space above z = 0.5 has points left to open"
        );
        assert!(path.points.iter().all(|p| p[2] >= 0.5 - 1e-6));
        assert!(path.final_distance > 0.4);
        let bad = FieldSearch3 {
            step: 0.0,
            ..search
        };
        let e = bad
            .search(&Cone(goal), &AnyStep, [0.0; 3], goal)
            .unwrap_err()
            .to_string();
        assert!(e.contains("step length 0"), "{e}");
        assert!(search
            .search(&Cone(goal), &AnyStep, [f32::NAN, 0.0, 0.0], goal)
            .is_err());
    }

    #[test]
    fn the_straight_line_ends_on_the_goal() {
        let line = straight_line([0.0; 3], [1.0, 0.0, 0.0], 0.3).unwrap();
        assert_eq!(line.len(), 5);
        assert_eq!(*line.last().unwrap(), [1.0, 0.0, 0.0]);
        assert!(straight_line([0.0; 3], [1.0; 3], 0.0).is_err());
    }
}
