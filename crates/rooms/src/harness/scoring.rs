//! How a planner's path is scored: the pair's poses fitted along it and checked, and its
//! outcome.

use super::{PairKind, RoomPlanner};
use crate::nav::point;
use crate::{PoseFilter, Result};
use envfield_affordance::{resample_path, AffordanceReport, PoseSequence};
use envfield_grid::Point3m;
use envfield_scene::nalgebra::Point3;
use envfield_scene::Room;

/// The shares of a path's poses that are supported, collision-free and both, in percent.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseShares {
    /// Supported.
    pub support: f64,
    /// Collision-free.
    pub free: f64,
    /// Supported and collision-free.
    pub valid: f64,
    /// On or inside furniture people do not use that way ([`crate::quality::implausible`]); NaN until
    /// [`PoseShares::judge`] is told the room's furniture.
    pub implausible: f64,
}

impl PoseShares {
    /// Sets [`PoseShares::implausible`] from `poses` (their torsos) in `room`.
    ///
    /// # Errors
    /// As [`crate::quality::implausible`].
    pub fn judge(&mut self, poses: &PoseSequence, room: &Room) -> Result<()> {
        let mut bad = 0usize;
        for pose in &poses.frames {
            bad += usize::from(crate::quality::implausible(room, pose.torso().into())?.is_some());
        }
        self.implausible = 100.0 * bad as f64 / poses.frames.len().max(1) as f64;
        Ok(())
    }
}

/// The poses of the pair's sequence along `path` (resampled at the sequence's step when
/// `resample`), placed as the search places them ([`PoseFilter::poses_along`]): their shares
/// and the poses.
///
/// # Errors
/// Errors of the resampling and of the checks (an empty path).
pub fn fit(
    filter: &PoseFilter,
    path: &[Point3m],
    resample: bool,
) -> Result<(PoseShares, PoseSequence)> {
    let step = filter.sequence.step_length().max(1e-3);
    let traj: Vec<Point3m> = if resample && path.len() > 1 {
        let pts: Vec<Point3<f32>> = path.iter().map(|&p| point(p)).collect();
        resample_path(&pts, step)?
            .iter()
            .map(|p| Point3m::from(*p))
            .collect()
    } else {
        path.to_vec()
    };
    let (poses, reports) = filter.poses_along(&traj)?;
    let n = reports.len().max(1) as f64;
    let share = |f: &dyn Fn(&AffordanceReport) -> bool| {
        100.0 * reports.iter().filter(|r| f(r)).count() as f64 / n
    };
    Ok((
        PoseShares {
            support: share(&|r| r.supported),
            free: share(&|r| r.collision_free),
            valid: share(&|r| r.valid()),
            implausible: f64::NAN,
        },
        poses,
    ))
}

/// One planner's result on one pair.
#[derive(Clone, Debug, Default)]
pub struct Outcome {
    /// The path ends within 0.02 m of the goal.
    pub reached: bool,
    /// The search opened every allowed point: no allowed route on its lattice (ours only).
    pub no_route: bool,
    /// The pose filter allowed no route in the budget; ours took the region's (ours only).
    pub relaxed: bool,
    /// Distance from the path's end to the goal, metres.
    pub dist_m: f64,
    /// Seconds the planner took for this path (the fields it descends were made before).
    pub seconds: f64,
    /// Seconds of its work for this pair's goal: the exact field's fast marching, the learned
    /// field's batched pass (0 for planners without per-goal work).
    pub goal_seconds: f64,
    /// Seconds of its work for the room, before any goal: the distance grid of ours' checks,
    /// a navigation mesh's build (0 for planners without per-room work; PRM builds its
    /// roadmap inside each path, with the start and goal in it).
    pub room_seconds: f64,
    /// Path length over the exact field's distance, for a path that reached (NaN otherwise).
    pub path_ratio: f64,
    /// The shares of its fitted poses.
    pub poses: PoseShares,
}

/// One planner's run on one pair: its outcome, path and fitted poses.
#[derive(Clone, Debug)]
pub struct Run {
    /// The planner.
    pub planner: RoomPlanner,
    /// How it did.
    pub outcome: Outcome,
    /// Its path's torso locations.
    pub path: Vec<Point3m>,
    /// The pair's poses fitted to the path.
    pub poses: PoseSequence,
}

impl Run {
    /// One JSON record of this run on pair `pair` (of `kind`) of room `room`: its planner,
    /// seconds (per path and for its goal), whether it reached and fell back to the region,
    /// its valid poses' share, path ratio and the distance it stopped from the goal.
    pub fn record(&self, room: u64, pair: usize, kind: PairKind) -> serde_json::Value {
        let o = &self.outcome;
        serde_json::json!({
            "room": room, "pair": pair, "kind": kind.name(),
            "planner": self.planner.name(), "seconds": o.seconds,
            "goal_seconds": o.goal_seconds, "reached": o.reached,
            "relaxed": o.relaxed, "valid": o.poses.valid,
            "path_ratio": o.path_ratio, "dist_m": o.dist_m,
        })
    }
}
