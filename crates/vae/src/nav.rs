//! The accessible region and a pose sequence as the free space and the step filters of the 3D
//! planners in envfield-plan ([`FieldSearch3`](envfield_plan::FieldSearch3), RRT, RRT*, PRM).

use crate::AccessibleRegion;
use envfield_affordance::{check_pose, AffordanceConfig, PoseSequence};
use envfield_grid::{Cell3, Point3m, SplitMix64};
use envfield_plan::{PlanError, Space3, StepFilter};
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::Scene;

/// The region's free space: a torso is allowed in an accessible voxel. Samples are uniform
/// over the accessible voxels, each jittered within its voxel.
impl Space3 for AccessibleRegion {
    fn is_free(&self, p: Point3m) -> bool {
        self.contains(p)
    }

    fn sample(&self, rng: &mut SplitMix64) -> Point3m {
        let free = self.free_indices();
        let i = free[rng.below(free.len())];
        let [_, ny, nz] = self.frame.shape;
        let c = self
            .frame
            .center(Cell3::new(i / (ny * nz), (i / nz) % ny, i % nz));
        let h = 0.499 * self.frame.voxel;
        let mut j = || (2.0 * rng.next_f32() - 1.0) * h;
        [c.x + j(), c.y + j(), c.z + j()]
    }
}

/// Without affordance: a candidate is allowed when it lies in the accessible region.
impl StepFilter for AccessibleRegion {
    fn keep(
        &self,
        _: usize,
        _: Point3m,
        candidates: &[Point3m],
    ) -> envfield_plan::Result<Vec<bool>> {
        Ok(candidates.iter().map(|&c| self.contains(c)).collect())
    }
}

/// With affordance: a candidate is allowed when it lies in the accessible region and the
/// sequence's pose for that step, turned to face the move (about the vertical) and moved so
/// its torso is on the candidate, is supported and collision-free.
#[derive(Debug)]
pub struct PoseFilter<'a> {
    /// The scene the poses are checked in.
    pub scene: &'a Scene,
    /// The accessible region.
    pub region: &'a AccessibleRegion,
    /// The pose sequence; step `k` uses frame `k % len` when `repeat` (a gait cycle), else
    /// frame `min(k, len - 1)` (a sit-down that ends seated).
    pub sequence: &'a PoseSequence,
    /// Whether the sequence repeats.
    pub repeat: bool,
    /// The checks' tolerances.
    pub affordance: AffordanceConfig,
}

impl PoseFilter<'_> {
    /// Step `step`'s frame placed with its torso at `to`, facing from `from` to `to` (its
    /// own heading when the move is vertical).
    pub fn placed(&self, step: usize, from: Point3m, to: Point3m) -> envfield_affordance::Pose {
        let n = self.sequence.frames.len();
        let k = if self.repeat {
            step % n
        } else {
            step.min(n - 1)
        };
        let frame = &self.sequence.frames[k];
        let torso = frame.torso();
        let facing = frame.facing();
        let (dx, dy) = (to[0] - from[0], to[1] - from[1]);
        let turn = if dx.hypot(dy) > 1e-6 {
            dy.atan2(dx) - facing.y.atan2(facing.x)
        } else {
            0.0
        };
        frame
            .rotated_about_z(turn, &torso)
            .translated(&(Point3::new(to[0], to[1], to[2]) - torso))
    }
}

impl StepFilter for PoseFilter<'_> {
    fn keep(
        &self,
        step: usize,
        from: Point3m,
        candidates: &[Point3m],
    ) -> envfield_plan::Result<Vec<bool>> {
        let support = {
            let n = self.sequence.supports.len();
            self.sequence.supports[if self.repeat {
                step % n
            } else {
                step.min(n - 1)
            }]
        };
        candidates
            .iter()
            .map(|&c| {
                if !self.region.contains(c) {
                    return Ok(false);
                }
                let pose = self.placed(step, from, c);
                check_pose(self.scene, &pose, support, &self.affordance)
                    .map(|r| r.valid())
                    .map_err(|e| PlanError::Invalid(format!("pose check: {e}")))
            })
            .collect()
    }
}

/// `p` as a point.
pub fn point(p: Point3m) -> Point3<f32> {
    Point3::new(p[0], p[1], p[2])
}

/// A point moved by `v`.
pub fn offset(p: Point3m, v: Vector3<f32>) -> Point3m {
    [p[0] + v.x, p[1] + v.y, p[2] + v.z]
}
