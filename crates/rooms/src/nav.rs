//! The accessible region and a pose sequence as the free space and the step filters of the 3D
//! planners in envfield-plan ([`FieldSearch3`](envfield_plan::space3::FieldSearch3), RRT, RRT*, PRM).

use crate::AccessibleRegion;
use envfield_affordance::{
    check_pose, pose_valid, AffordanceConfig, Joint, Pose, PoseSequence, Support,
};
use envfield_grid::{Point3m, SplitMix64};
use envfield_plan::space3::{Space3, StepFilter};
use envfield_plan::PlanError;
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::{DistanceGrid, Scene, SignedDistance};

/// The region's free space: a torso is allowed in an accessible voxel. Samples are uniform
/// over the accessible voxels, each jittered within its voxel.
impl Space3 for AccessibleRegion {
    fn is_free(&self, p: Point3m) -> bool {
        self.contains(p)
    }

    fn sample(&self, rng: &mut SplitMix64) -> Point3m {
        let free = self.free_indices();
        let i = free[rng.below(free.len())];
        let c = self.frame.center(self.grid.cell(i));
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
/// sequence's pose for that step, turned to face the move (about the vertical) unless it keeps
/// its recorded heading ([`PoseFilter::face_the_move`]) and moved so its torso is on the
/// candidate, is supported and collision-free.
#[derive(Debug)]
pub struct PoseFilter<'a> {
    /// The scene the poses are checked in.
    pub scene: &'a Scene,
    /// The accessible region.
    pub region: &'a AccessibleRegion,
    /// The pose sequence. Step `k` (it lands on the path's point `k + 1`; the start, point 0,
    /// wears frame 0 too) wears frame `k % len` when `repeat` (a gait cycle), else frame
    /// `min(k, len - 1)` (a sit-down that ends seated).
    pub sequence: &'a PoseSequence,
    /// Whether the sequence repeats.
    pub repeat: bool,
    /// Whether each pose is turned about the vertical to face its step's move (a walk), or
    /// keeps the heading it was recorded with (a sit-down made for its seat, whose torso moves
    /// backwards onto the seat: turned to face that move, the body would face the seat).
    pub face_the_move: bool,
    /// The checks' tolerances.
    pub affordance: AffordanceConfig,
    /// A standing step must have air straight beneath its pelvis down to its shins
    /// ([`clear_beneath`]): nothing between the legs. The region's voxels passed the
    /// filter at their centres; a torso elsewhere in a voxel beside a table may stand with
    /// its pelvis over the table's edge, every joint clear.
    pub clear_beneath: bool,
    /// The scene's distances sampled once per room: when set, the search's checks
    /// ([`StepFilter::keep`]) read them instead of the scene, a few lookups per joint instead
    /// of a pass over the scene's parts. [`PoseFilter::poses_along`], which scores a path,
    /// always checks against the scene itself.
    pub distances: Option<&'a DistanceGrid>,
}

impl PoseFilter<'_> {
    /// The frame step `step` wears on the point it lands on.
    fn frame_of(&self, step: usize) -> usize {
        let n = self.sequence.frames.len();
        if self.repeat {
            step % n
        } else {
            step.min(n - 1)
        }
    }

    /// Step `step`'s frame placed with its torso at `to`, facing from `from` to `to` (its
    /// own heading when the move is vertical, or always unless
    /// [`PoseFilter::face_the_move`]).
    pub fn placed(&self, step: usize, from: Point3m, to: Point3m) -> envfield_affordance::Pose {
        let frame = &self.sequence.frames[self.frame_of(step)];
        let torso = frame.torso();
        let facing = frame.facing();
        let (dx, dy) = (to[0] - from[0], to[1] - from[1]);
        let turn = if self.face_the_move && dx.hypot(dy) > 1e-6 {
            dy.atan2(dx) - facing.y.atan2(facing.x)
        } else {
            0.0
        };
        frame
            .rotated_about_z(turn, &torso)
            .translated(&(Point3::from(to) - torso))
    }
}

impl PoseFilter<'_> {
    /// The sequence's poses along `path` as the search places them: point `i` wears the frame
    /// of the step that lands on it, facing that step's move (point 0 faces the first move),
    /// each checked. Any planner's path gets its poses this way in the tables, so the
    /// planners differ only in their paths.
    ///
    /// # Errors
    /// [`PlanError::Invalid`] for an empty path; errors of the checks.
    pub fn poses_along(
        &self,
        path: &[Point3m],
    ) -> envfield_plan::Result<(PoseSequence, Vec<envfield_affordance::AffordanceReport>)> {
        if path.is_empty() {
            return Err(PlanError::Invalid("no path to place poses on".into()));
        }
        let mut frames = Vec::with_capacity(path.len());
        let mut supports = Vec::with_capacity(path.len());
        let mut reports = Vec::with_capacity(path.len());
        for i in 0..path.len() {
            let (pose, support) = if i == 0 {
                let next = path.get(1).copied().unwrap_or(path[0]);
                // Point 0 wears frame 0: placed as the step "before" the first.
                let frame = &self.sequence.frames[0];
                let torso = frame.torso();
                let facing = frame.facing();
                let (dx, dy) = (next[0] - path[0][0], next[1] - path[0][1]);
                let turn = if self.face_the_move && dx.hypot(dy) > 1e-6 {
                    dy.atan2(dx) - facing.y.atan2(facing.x)
                } else {
                    0.0
                };
                let p = frame
                    .rotated_about_z(turn, &torso)
                    .translated(&(point(path[0]) - torso));
                (p, self.sequence.supports[0])
            } else {
                let k = i - 1;
                (
                    self.placed(k, path[i - 1], path[i]),
                    self.sequence.supports[self.frame_of(k)],
                )
            };
            reports.push(
                check_pose(self.scene, &pose, support, &self.affordance)
                    .map_err(|e| PlanError::Invalid(format!("pose check: {e}")))?,
            );
            frames.push(pose);
            supports.push(support);
        }
        let seq = PoseSequence::new(self.sequence.fps, self.sequence.activity, frames, supports)
            .map_err(|e| PlanError::Invalid(format!("poses: {e}")))?;
        Ok((seq, reports))
    }
}

impl StepFilter for PoseFilter<'_> {
    fn keep(
        &self,
        step: usize,
        from: Point3m,
        candidates: &[Point3m],
    ) -> envfield_plan::Result<Vec<bool>> {
        let support = self.sequence.supports[self.frame_of(step)];
        candidates
            .iter()
            .map(|&c| {
                if !self.region.contains(c) {
                    return Ok(false);
                }
                let pose = self.placed(step, from, c);
                let valid = match self.distances {
                    Some(grid) => pose_valid(grid, &pose, support, &self.affordance),
                    None => pose_valid(self.scene, &pose, support, &self.affordance),
                }
                .map_err(|e| PlanError::Invalid(format!("pose check: {e}")))?;
                if !(valid && self.clear_beneath && support == Support::Standing) {
                    return Ok(valid);
                }
                match self.distances {
                    Some(grid) => clear_beneath(grid, &pose),
                    None => clear_beneath(self.scene, &pose),
                }
                .map_err(|e| PlanError::Invalid(format!("pose check: {e}")))
            })
            .collect()
    }
}

/// Whether the air straight beneath `pose`'s pelvis is clear (at least 1 cm from any
/// surface) down to halfway between its lower knee and that leg's ankle: a standing body has
/// nothing between its legs, neither a table's edge nor a chair's or a coffee table's (their
/// tops, 0.40-0.45 m, lie below the knees). Marched by the distance, so a thin top is not
/// stepped over.
///
/// # Errors
/// Errors of `scene`'s distances (a non-finite pose).
pub fn clear_beneath<S: SignedDistance + ?Sized>(
    scene: &S,
    pose: &Pose,
) -> envfield_scene::Result<bool> {
    let pelvis = pose.joints[Joint::Pelvis.index()];
    let shin = |knee: Joint, ankle: Joint| {
        0.5 * (pose.joints[knee.index()].z + pose.joints[ankle.index()].z)
    };
    let lowest =
        shin(Joint::LeftKnee, Joint::LeftAnkle).min(shin(Joint::RightKnee, Joint::RightAnkle));
    let mut z = pelvis.z;
    while z >= lowest {
        let d = scene.distance_at(&Point3::new(pelvis.x, pelvis.y, z))?;
        if d < CLEAR {
            return Ok(false);
        }
        z -= d.max(CLEAR);
    }
    Ok(true)
}

/// How far from any surface [`clear_beneath`] asks the air to be, metres.
const CLEAR: f32 = 0.01;

/// `p` as a point.
pub fn point(p: Point3m) -> Point3<f32> {
    Point3::from(p)
}

/// A point moved by `v`.
pub fn offset(p: Point3m, v: Vector3<f32>) -> Point3m {
    [p[0] + v.x, p[1] + v.y, p[2] + v.z]
}
