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
use envfield_scene::{DistanceGrid, Scene, SurfaceColumns, SurfacesBeneath, MAX_DISTANCE_SAMPLES};

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

    fn keep_one(&self, _: usize, _: Point3m, c: Point3m) -> envfield_plan::Result<bool> {
        Ok(self.contains(c))
    }

    fn may_keep(&self, p: Point3m) -> bool {
        self.contains(p)
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
    /// A standing step must have no surface straight beneath its pelvis above its higher
    /// foot ([`clear_beneath`]): nothing between the legs. The region's voxels passed the
    /// filter at their centres; a torso elsewhere in a voxel beside a table may stand with
    /// its pelvis over the table's edge, every joint clear.
    pub clear_beneath: bool,
    /// Whether the sequence is recorded where it is played (a sit-down made for its seat, as
    /// [`SitDown::sequence`](crate::SitDown::sequence) gives it): each point then wears the
    /// frame whose torso lies nearest to it, so its poses follow where the torso is rather
    /// than how many steps it took to get there. A path shorter than the recording (a chord
    /// across the arc a body's pelvis takes onto a seat) reaches the seat seated, not still
    /// lowering; a torso off the recording's path wears the nearest frame moved onto it, and
    /// its checks say whether that stands.
    pub in_place: bool,
    /// The scene sampled once per room: when set, the search's checks ([`StepFilter::keep`])
    /// read it instead of the scene, a few lookups per joint instead of a pass over the
    /// scene's parts. [`PoseFilter::poses_along`], which scores a path, always checks against
    /// the scene itself.
    pub tables: Option<&'a SceneTables>,
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

    /// The frame of step `step` landing on `at`: by the step's index, or where the torso is
    /// ([`PoseFilter::in_place`]).
    fn frame_at(&self, step: usize, at: Point3m) -> usize {
        if !self.in_place {
            return self.frame_of(step);
        }
        let at = point(at);
        let frames = &self.sequence.frames;
        (0..frames.len())
            .min_by(|&a, &b| {
                let d = |f: usize| (frames[f].torso() - at).norm_squared();
                d(a).total_cmp(&d(b))
            })
            .unwrap_or(0)
    }

    /// Step `step`'s frame placed with its torso at `to`, facing from `from` to `to` (its
    /// own heading when the move is vertical, or always unless
    /// [`PoseFilter::face_the_move`]).
    pub fn placed(&self, step: usize, from: Point3m, to: Point3m) -> envfield_affordance::Pose {
        self.frame_placed(self.frame_at(step, to), from, to)
    }

    /// Frame `f` placed with its torso at `to`, facing as [`PoseFilter::placed`] says.
    fn frame_placed(&self, f: usize, from: Point3m, to: Point3m) -> envfield_affordance::Pose {
        let frame = &self.sequence.frames[f];
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
                // Point 0 wears frame 0 (or the frame nearest it, in place): placed as the step
                // "before" the first.
                let f = self.frame_at(0, path[0]);
                let frame = &self.sequence.frames[f];
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
                (p, self.sequence.supports[f])
            } else {
                let f = self.frame_at(i - 1, path[i]);
                (
                    self.frame_placed(f, path[i - 1], path[i]),
                    self.sequence.supports[f],
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
        candidates
            .iter()
            .map(|&c| self.keep_one(step, from, c))
            .collect()
    }

    fn keep_one(&self, step: usize, from: Point3m, c: Point3m) -> envfield_plan::Result<bool> {
        if !self.region.contains(c) {
            return Ok(false);
        }
        let f = self.frame_at(step, c);
        let support = self.sequence.supports[f];
        let pose = self.frame_placed(f, from, c);
        let valid = match self.tables {
            Some(t) => pose_valid(&t.distances, &pose, support, &self.affordance),
            None => pose_valid(self.scene, &pose, support, &self.affordance),
        }
        .map_err(|e| PlanError::Invalid(format!("pose check: {e}")))?;
        if !(valid && self.clear_beneath && support == Support::Standing) {
            return Ok(valid);
        }
        match self.tables {
            Some(t) => clear_beneath(&t.beneath, &pose),
            None => clear_beneath(self.scene, &pose),
        }
        .map_err(|e| PlanError::Invalid(format!("pose check: {e}")))
    }

    fn may_keep(&self, p: Point3m) -> bool {
        self.region.contains(p)
    }
}

/// Whether no surface lies straight beneath `pose`'s pelvis down to 5 cm above the sole of
/// its higher foot: what a standing body has between its legs is no higher than what its feet
/// stand on, neither a table's edge nor a chair's seat or crossbar. On a stair the tread
/// beneath the pelvis lies at or below the higher foot's, so climbing stays clear. Asked of
/// the scene, the answer is one exact ray; of [`SurfaceColumns`], a surface within one of its
/// cells (horizontally) counts.
///
/// # Errors
/// Errors of `beneath` (a non-finite pose).
pub fn clear_beneath<B: SurfacesBeneath + ?Sized>(
    beneath: &B,
    pose: &Pose,
) -> envfield_scene::Result<bool> {
    let pelvis = pose.joints[Joint::Pelvis.index()];
    let sole = |ankle: Joint, foot: Joint| {
        pose.joints[ankle.index()]
            .z
            .min(pose.joints[foot.index()].z)
    };
    let higher =
        sole(Joint::LeftAnkle, Joint::LeftFoot).max(sole(Joint::RightAnkle, Joint::RightFoot));
    Ok(!beneath.any_between(pelvis.x, pelvis.y, higher + ABOVE_SOLE, pelvis.z)?)
}

/// How far above the higher sole [`clear_beneath`] stops looking, metres: a foot's joints
/// lie within the contact tolerance of what they stand on.
const ABOVE_SOLE: f32 = 0.05;

/// The spacing of the distance grid ours' pose checks read, metres: fine enough that a check
/// on it agrees with the scene's own on nearly every pose (the tables score every path's
/// poses against the scene itself).
pub const DISTANCE_CELL: f32 = 0.03;

/// How far (metres) [`SceneTables`] reach beyond the scene's box.
pub const TABLE_MARGIN: f32 = 0.2;

/// The spacing of the surface columns [`clear_beneath`] reads, metres.
pub const BENEATH_CELL: f32 = 0.02;

/// The scene sampled once per room for ours' pose checks: its signed distances (every
/// joint's and bone's clearance and support) and its surfaces along vertical lines (what lies
/// beneath a pelvis, which the distances cannot tell near a thin top).
#[derive(Clone, Debug)]
pub struct SceneTables {
    /// The signed distances at [`DISTANCE_CELL`].
    pub distances: DistanceGrid,
    /// The surfaces beneath every point, at [`BENEATH_CELL`].
    pub beneath: SurfaceColumns,
}

impl SceneTables {
    /// Whether `scene`'s tables fit in memory, before any work: a scene too large for them is
    /// refused naming its size and what to do (a scene in centimetres read as metres, a
    /// warehouse or a level larger than a home).
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`](crate::RoomsError::InvalidInput) for an empty scene or one whose signed distances every
    /// [`DISTANCE_CELL`] would be more than [`MAX_DISTANCE_SAMPLES`].
    pub fn check(scene: &Scene) -> crate::Result<()> {
        let aabb = scene
            .aabb()
            .ok_or_else(|| crate::RoomsError::InvalidInput("the scene is empty".into()))?;
        let size = aabb.maxs - aabb.mins;
        let samples = (0..3)
            .map(|a| ((size[a] + 2.0 * TABLE_MARGIN) / DISTANCE_CELL).ceil() as f64 + 1.0)
            .product::<f64>();
        if samples <= MAX_DISTANCE_SAMPLES as f64 {
            return Ok(());
        }
        // The floor those samples hold at this scene's height.
        let layers = (size.z + 2.0 * TABLE_MARGIN) / DISTANCE_CELL + 1.0;
        let area = MAX_DISTANCE_SAMPLES as f32 / layers * DISTANCE_CELL * DISTANCE_CELL;
        Err(crate::RoomsError::InvalidInput(format!(
            "the scene is {:.1} x {:.1} x {:.1} m: the pose tables (signed distances every {} \
             cm) would hold {samples:.1e} samples, more than the {MAX_DISTANCE_SAMPLES:.1e} they \
             may; at this height about {area:.0} m2 of floor fits. Is it in centimetres \
             (--units cm) or millimetres (--units mm)? A larger scene: plan it room by room, or \
             walk it with the `level` example",
            size.x,
            size.y,
            size.z,
            DISTANCE_CELL * 100.0
        )))
    }

    /// Both tables over `scene`'s bounding box grown by 0.2 m.
    ///
    /// # Errors
    /// Errors of [`DistanceGrid::around`] and [`SurfaceColumns::around`] (an empty scene, one
    /// too large to sample).
    pub fn of(scene: &Scene) -> envfield_scene::Result<Self> {
        Ok(Self {
            distances: DistanceGrid::around(scene, TABLE_MARGIN, DISTANCE_CELL)?,
            beneath: SurfaceColumns::around(scene, TABLE_MARGIN, BENEATH_CELL)?,
        })
    }

    /// Bytes of both tables.
    pub fn bytes(&self) -> usize {
        self.distances.bytes() + self.beneath.bytes()
    }
}

/// `p` as a point.
pub fn point(p: Point3m) -> Point3<f32> {
    Point3::from(p)
}

/// A point moved by `v`.
pub fn offset(p: Point3m, v: Vector3<f32>) -> Point3m {
    [p[0] + v.x, p[1] + v.y, p[2] + v.z]
}

#[cfg(test)]
mod tests {
    use super::*;
    use envfield_scene::nalgebra::Isometry3;
    use envfield_scene::{ObjectKind, Primitive, SceneObject};

    fn floor(size: [f32; 2]) -> Scene {
        let mut scene = Scene::new();
        let slab = SceneObject::new("floor", ObjectKind::Floor)
            .with(
                Primitive::cuboid([size[0], size[1], 0.1]),
                Isometry3::translation(size[0] / 2.0, size[1] / 2.0, -0.05),
            )
            .unwrap();
        scene.add(slab).unwrap();
        let wall = SceneObject::new("wall", ObjectKind::Wall)
            .with(
                Primitive::cuboid([size[0], 0.1, 2.5]),
                Isometry3::translation(size[0] / 2.0, -0.05, 1.25),
            )
            .unwrap();
        scene.add(wall).unwrap();
        scene
    }

    /// Issue 56: a 50 m warehouse is refused before any work, naming its size, `--units` and
    /// the `level` example (it failed after its region, 19 s, with "use a larger cell", which
    /// no flag sets); an apartment's size passes.
    #[test]
    fn a_scene_too_large_for_the_tables_is_refused_at_once() {
        let e = SceneTables::check(&floor([50.0, 50.0]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("50.0 x 50.1 x 2.6 m"), "{e}");
        assert!(e.contains("--units cm") && e.contains("`level`"), "{e}");
        SceneTables::check(&floor([10.0, 8.0])).unwrap();
    }
}
