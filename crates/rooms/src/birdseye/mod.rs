//! Several people on one floor, seen from above (paper section 4.1): the bird's-eye protocol
//! the crowd table and the bird's-eye field's training share. Floor maps of 0.1 m cells padded
//! to 64 x 64, bodies of 0.25 m, maps changed the way other people change them, each
//! person's walking sequence aligned to their path and checked in the scene, the tallies of
//! the crowd table and the pictures of a run.

mod data;
mod picture;
mod tally;

pub use data::{changed_map, goal_cell, training_maps, walkable_map};
pub use picture::crowd_frames;
pub use tally::CrowdTally;

use crate::{Result, RoomsError};
use envfield_affordance::{walk_along, AffordanceReport, PoseSequence};
use envfield_grid::{Grid2, Point2};
use envfield_plan::crowd::CrowdRun;
use envfield_scene::nalgebra::Point3;
use envfield_scene::{floor_map, FloorMap, FloorMapConfig, Scene};

/// Floor-map cell side, metres.
pub const RESOLUTION: f32 = 0.1;
/// Body radius, metres (0.25 m: shoulders about 0.5 m wide).
pub const BODY: f32 = 0.25;
/// The map side generated rooms are padded to.
pub const SIDE: usize = 64;
/// The longest map side [`Floor::new`] takes (25.6 m at [`RESOLUTION`]): every person's
/// field is predicted on the whole map at every time step, which past this size takes
/// seconds a step.
pub const MAX_SIDE: usize = 256;

/// A room's scene, floor map and walkable map (padded to 64 x 64 when it fits).
#[derive(Clone, Debug)]
pub struct Floor {
    /// The scene.
    pub scene: Scene,
    /// Its floor map at [`RESOLUTION`].
    pub map: FloorMap,
    /// Where a body's centre may stand.
    pub walkable: Grid2,
}

impl Floor {
    /// The floor of `scene` for bodies of `body_radius` metres.
    ///
    /// # Errors
    /// Errors of the floor map (an empty scene, no floor); [`RoomsError::InvalidInput`] for a
    /// scene wider than [`MAX_SIDE`] cells.
    pub fn new(scene: Scene, body_radius: f32) -> Result<Self> {
        if let Some(aabb) = scene.aabb() {
            let extent = aabb.maxs - aabb.mins;
            let cells = (extent.x.max(extent.y) / RESOLUTION).ceil();
            if cells.is_nan() || cells > MAX_SIDE as f32 {
                return Err(RoomsError::InvalidInput(format!(
                    "the scene is {:.1} x {:.1} m: its floor map would be {cells} cells a side at \
                     {RESOLUTION} m, more than {MAX_SIDE} (is it in centimetres or millimetres? \
                     scale it to metres)",
                    extent.x, extent.y
                )));
            }
        }
        let map = floor_map(
            &scene,
            &FloorMapConfig {
                resolution: RESOLUTION,
                ..FloorMapConfig::default()
            },
        )?;
        let fits = map.grid.rows() <= SIDE && map.grid.cols() <= SIDE;
        let walkable = map.walkable(body_radius, fits.then_some([SIDE, SIDE]))?;
        Ok(Self {
            scene,
            map,
            walkable,
        })
    }

    /// World `(x, y, floor height)` of a map point (cell centres at integer coordinates).
    pub fn world(&self, p: Point2) -> Point3<f32> {
        let f = &self.map.frame;
        Point3::new(
            f.origin[0] + (p.col + 0.5) * f.resolution,
            f.origin[1] + (p.row + 0.5) * f.resolution,
            self.map.floor_height,
        )
    }

    /// Person `i`'s walking sequence `gait` aligned to their path in `run`, and each frame's
    /// support and collision check in the scene.
    ///
    /// # Errors
    /// Errors of the resampling, the alignment and the checks.
    pub fn aligned_walk(
        &self,
        run: &CrowdRun,
        i: usize,
        gait: &PoseSequence,
    ) -> Result<(PoseSequence, Vec<AffordanceReport>)> {
        let path: Vec<Point3<f32>> = run.path(i).iter().map(|&p| self.world(p)).collect();
        Ok(walk_along(&self.scene, gait, &path, gait.step_length())?)
    }

    /// [`Floor::aligned_walk`] on the run's clock: a frame every `1 / gait.fps` seconds, a
    /// time step lasting `step_s` seconds, each frame the aligned pose nearest to where the
    /// run has person `i` then (a person who waits keeps their pose; one who has arrived
    /// stands at their goal from then on). Everyone's sequences of one run play together, as
    /// the run had them move; with their checks.
    ///
    /// # Errors
    /// As [`Floor::aligned_walk`]; a `step_s` that is not positive.
    pub fn timed_walk(
        &self,
        run: &CrowdRun,
        i: usize,
        gait: &PoseSequence,
        step_s: f32,
    ) -> Result<(PoseSequence, Vec<AffordanceReport>)> {
        if !(step_s.is_finite() && step_s > 0.0) {
            return Err(RoomsError::InvalidInput(format!(
                "a time step's seconds must be positive, got {step_s}"
            )));
        }
        let (aligned, reports) = self.aligned_walk(run, i, gait)?;
        let path: Vec<Point3<f32>> = run.path(i).iter().map(|&p| self.world(p)).collect();
        let mut arc = vec![0.0f32];
        for w in path.windows(2) {
            arc.push(arc[arc.len() - 1] + (w[1] - w[0]).norm());
        }
        let steps = path.len() - 1;
        let per_frame = gait.step_length().max(1e-6);
        let count = (steps as f32 * step_s * gait.fps).ceil() as usize + 1;
        let (mut frames, mut supports, mut checks) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..count {
            let u = k as f32 / gait.fps / step_s;
            let t = (u.floor() as usize).min(steps.saturating_sub(1));
            let s = match steps {
                0 => 0.0,
                _ => arc[t] + (u - t as f32).clamp(0.0, 1.0) * (arc[t + 1] - arc[t]),
            };
            let j = ((s / per_frame).round() as usize).min(aligned.frames.len() - 1);
            frames.push(aligned.frames[j]);
            supports.push(aligned.supports[j]);
            checks.push(reports[j]);
        }
        let timed = PoseSequence::new(gait.fps, aligned.activity, frames, supports)?;
        Ok((timed, checks))
    }
}
