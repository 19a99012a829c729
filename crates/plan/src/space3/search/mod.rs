//! [`FieldSearch3`]: the pose-dependent search on a continuous 3D field (paper section 4.2,
//! "Pose-dependent trajectory"): from the start, step `s` towards each of the 26 directions of
//! `{-1, 0, 1}^3 \ {0}`, normalised so every candidate lies exactly `s` away; ask the field at
//! all candidates in one batch, keep the ones a [`StepFilter`] allows (the pose of this step
//! supported and collision-free, or simply inside the accessible region), and move to the
//! smallest value; where the filter leaves no way down, go on from the best point left
//! (greedy best-first, [`FieldSearch3::search`]). [`FieldSearch3::shortcut`] then straightens
//! the path where the filter allows a straight cut.

mod open;
mod shortcut;
#[cfg(test)]
mod tests;

use super::{directions26, distance, Path3, StepFilter};
use crate::{PlanError, Result};
use envfield_grid::{ContinuousField3, Point3m};
#[cfg(test)]
use open::{lattice_key, pack_open, unpack_open};
use open::{OpenList, Opened};
use serde::{Deserialize, Serialize};

/// The pose-dependent search's settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FieldSearch3 {
    /// Step length `s`, metres (the pose sequence's `step_length`).
    pub step: f32,
    /// The search stops when the torso is this close to the goal, metres.
    pub tolerance: f32,
    /// Expansions at most (each one batched field query).
    pub max_steps: usize,
    /// Filter calls at most (a pose check each, refused or not), 0 for no limit. Where the
    /// filter refuses nearly everything (a pocket the poses cannot leave) a search spends its
    /// expansions slowly and its checks fast; this stops it there.
    #[serde(default)]
    pub max_checks: usize,
    /// Filter calls at most without coming nearer the goal, once the search has opened a
    /// point within two steps of it; 0 for no limit. A goal that a body fits only at a few
    /// frames of its gait and headings is come close to early and never landed on; past
    /// this many refusals in a row near it, the search ends there rather than spend its
    /// budget on the rest of the room.
    #[serde(default)]
    pub near_stall: usize,
}

/// A point the search opened.
#[derive(Clone, Copy, Debug)]
struct Node {
    at: Point3m,
    parent: usize,
    depth: usize,
}

/// Where a search stands: its opened points, the nearest to the goal so far, its counts.
struct Progress {
    nodes: Vec<Node>,
    /// The distance to the goal of the nearest opened point, and that point.
    nearest: (f32, usize),
    /// The filter calls made when the search last came nearer the goal.
    nearer_at: usize,
    expanded: usize,
    checks: usize,
}

impl Progress {
    /// Opens `at` (from `parent`, at `depth` along its chain) `d` from the goal; its index.
    fn open(&mut self, at: Point3m, parent: usize, depth: usize, d: f32) -> usize {
        self.nodes.push(Node { at, parent, depth });
        let n = self.nodes.len() - 1;
        if d < self.nearest.0 {
            self.nearest = (d, n);
            self.nearer_at = self.checks;
        }
        n
    }

    /// The chain of opened points from the start to `end`.
    fn chain(&self, end: usize) -> Vec<Point3m> {
        let mut chain = Vec::new();
        let mut at = end;
        while at != usize::MAX {
            chain.push(self.nodes[at].at);
            at = self.nodes[at].parent;
        }
        chain.reverse();
        chain
    }
}

impl FieldSearch3 {
    /// Searches from `start` to `goal` on `field`, each step's candidates filtered by
    /// `filter`: greedy best-first on the field's values. Each expansion asks the field at
    /// the 26 candidates of the point it expands in one batch and puts them on the open list;
    /// the point of least value comes off the list next, and the filter is asked about it
    /// then (lazily: a clear descent checks one pose per step, not 26). A point within `s / 2`
    /// of one already opened is not opened again. Where the field has no local minimum under
    /// the filter this is exactly the paper's descent, moving to the smallest allowed
    /// candidate at every step; where the filter blocks that descent (the pose of the best
    /// step would collide), the search goes on from the best point left instead of stopping.
    /// When the goal lies within `s` and the filter allows it, the path lands on it. The path
    /// is the chain of steps from the start to the point it ends on: the goal, or after
    /// `max_steps` expansions (or `max_checks` filter calls, or `near_stall` of them near the
    /// goal without coming nearer) the opened point nearest the goal (then `reached` is
    /// false). A step's filter call gets the step's index along that chain.
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
        self.validate(start, goal)?;
        let dirs = directions26();
        let s = self.step;
        let mut opened = Opened::new(0.5 * s);
        let mut open = OpenList::default();
        let mut progress = Progress {
            nodes: Vec::new(),
            nearest: (f32::INFINITY, 0),
            nearer_at: 0,
            expanded: 0,
            checks: 0,
        };
        let (mut end, mut exhausted) = (None, false);
        let mut candidates = [[0.0f32; 3]; 26];
        let mut next = Some((start, usize::MAX));
        loop {
            // The next point: the start first, then the best candidate on the list.
            let Some((here, parent)) = next.take().or_else(|| open.pop()) else {
                exhausted = true;
                break;
            };
            if opened.contains(here) {
                continue;
            }
            let depth = if parent == usize::MAX {
                0
            } else {
                progress.nodes[parent].depth + 1
            };
            // Lazy: a candidate's pose is checked when it comes off the list, so a clear
            // descent checks one pose per step rather than all 26. The start needs no check.
            if parent != usize::MAX {
                if self.out_of_checks(&progress) {
                    break;
                }
                progress.checks += 1;
                if !filter.keep_one(depth - 1, progress.nodes[parent].at, here)? {
                    continue;
                }
            }
            opened.insert(here);
            let d = distance(here, goal);
            let n = progress.open(here, parent, depth, d);
            if d <= self.tolerance {
                end = Some(n);
                break;
            }
            if d <= s && filter.keep_one(depth, here, goal)? {
                end = Some(progress.open(goal, n, depth + 1, 0.0));
                break;
            }
            if progress.expanded == self.max_steps {
                break;
            }
            progress.expanded += 1;
            for (c, v) in candidates.iter_mut().zip(&dirs) {
                *c = [here[0] + s * v[0], here[1] + s * v[1], here[2] + s * v[2]];
            }
            open.push(n, &candidates, values_or_infinity(field, &candidates));
        }
        let chain = progress.chain(end.unwrap_or(progress.nearest.1));
        Ok(Path3 {
            exhausted,
            ..Path3::ending(chain, goal, self.tolerance)
        })
    }

    /// A positive step, a tolerance of 0 or more, and finite ends.
    fn validate(&self, start: Point3m, goal: Point3m) -> Result<()> {
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
        Ok(())
    }

    /// Whether the search has spent its filter calls: `max_checks` of them, or `near_stall`
    /// since it last came nearer a goal it is within two steps of.
    fn out_of_checks(&self, progress: &Progress) -> bool {
        let spent = self.max_checks > 0 && progress.checks == self.max_checks;
        let stalled = self.near_stall > 0
            && progress.nearest.0 <= 2.0 * self.step
            && progress.checks - progress.nearer_at >= self.near_stall;
        spent || stalled
    }

    /// [`FieldSearch3::search`] under `filter`; where that does not reach the goal, again
    /// under `fallback` (a looser filter, such as the accessible region alone), so a route is
    /// found wherever the looser filter has one. Either path is then straightened by
    /// [`FieldSearch3::shortcut`] under `filter`. `relaxed` says whether the fallback was
    /// taken, `exhausted` whether the strict search opened every point it allows.
    ///
    /// # Errors
    /// As [`FieldSearch3::search`].
    pub fn search_relaxed<F, S, L>(
        &self,
        field: &F,
        filter: &S,
        fallback: &L,
        start: Point3m,
        goal: Point3m,
    ) -> Result<Path3>
    where
        F: ContinuousField3 + ?Sized,
        S: StepFilter + ?Sized,
        L: StepFilter + ?Sized,
    {
        let strict = self.search(field, filter, start, goal)?;
        if strict.reached {
            return self.shortcut(filter, &strict, goal);
        }
        let loose = self.search(field, fallback, start, goal)?;
        let path = Path3 {
            relaxed: true,
            exhausted: strict.exhausted,
            ..loose
        };
        self.shortcut(filter, &path, goal)
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
