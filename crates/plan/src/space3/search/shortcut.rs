//! [`FieldSearch3::shortcut`]: straight cuts the filter allows, after the search.

use super::super::{distance, Path3, StepFilter};
use super::FieldSearch3;
use crate::{PlanError, Result};
use envfield_grid::Point3m;

impl FieldSearch3 {
    /// Shortens `path` by straight cuts the filter allows (path optimisation after the
    /// search): from each kept point, the farthest later point of `path` (of 16 tried, evenly
    /// spaced) whose straight segment, walked in equal steps no longer than [`FieldSearch3::step`], passes `filter`
    /// at every step (with the steps' indices along the new path, so a gait keeps its
    /// rhythm), is joined to it. Where no cut from a point passes, the path's next point is
    /// kept as it is. The ends stay. A path that is not `relaxed` (every step passed the
    /// filter) comes back unchanged if a kept step fails under its new index, so the cut
    /// never makes its poses worse.
    ///
    /// # Errors
    /// [`PlanError::Invalid`] for a step that is not positive; errors of the filter.
    pub fn shortcut<S>(&self, filter: &S, path: &Path3, goal: Point3m) -> Result<Path3>
    where
        S: StepFilter + ?Sized,
    {
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err(PlanError::Invalid(format!(
                "shortcut: a positive step (got {})",
                self.step
            )));
        }
        let pts = &path.points;
        if pts.len() < 3 {
            return Ok(path.clone());
        }
        let mut out = vec![pts[0]];
        let mut i = 0;
        while i + 1 < pts.len() {
            let mut joined = false;
            // At most 16 cuts tried from each point (every stride-th later point, the
            // farthest first), so a long path costs O(length) checks per kept point.
            let stride = (pts.len() - 1 - i).div_ceil(16);
            let tries = (i + 1..pts.len())
                .rev()
                .step_by(stride)
                .chain(((pts.len() - 2 - i) % stride != 0).then_some(i + 1));
            for j in tries {
                if let Some(steps) = self.straight_steps(filter, &out, pts[j])? {
                    out.extend(steps);
                    i = j;
                    joined = true;
                    break;
                }
            }
            if !joined {
                if !path.relaxed {
                    return Ok(path.clone());
                }
                out.push(pts[i + 1]);
                i += 1;
            }
        }
        Ok(Path3 {
            exhausted: path.exhausted,
            relaxed: path.relaxed,
            ..Path3::ending(out, goal, self.tolerance)
        })
    }

    /// The steps from the last point of `so_far` to `to` along the straight line, or `None`
    /// when one fails `filter`.
    fn straight_steps<S>(
        &self,
        filter: &S,
        so_far: &[Point3m],
        to: Point3m,
    ) -> Result<Option<Vec<Point3m>>>
    where
        S: StepFilter + ?Sized,
    {
        let from = *so_far.last().expect("a start");
        let n = (distance(from, to) / self.step).ceil().max(1.0) as usize;
        let steps: Vec<Point3m> = (1..=n)
            .map(|k| {
                let t = k as f32 / n as f32;
                std::array::from_fn(|a| from[a] + t * (to[a] - from[a]))
            })
            .collect();
        // The cheap test of every step first: a cut that leaves the free space far along
        // costs no pose before it.
        if !steps.iter().all(|&p| filter.may_keep(p)) {
            return Ok(None);
        }
        let mut prev = from;
        for (k, &p) in steps.iter().enumerate() {
            if !filter.keep_one(so_far.len() - 1 + k, prev, p)? {
                return Ok(None);
            }
            prev = p;
        }
        Ok(Some(steps))
    }
}
