//! One room run: what a room gives every planner ([`RoomContext`]), the settings of a run
//! ([`RunSettings`]) and every planner on one pair ([`run_pair`]).

use super::{
    fit, learned_table, FieldKind, FloorPlanner, Outcome, Pair, PairKind, PairSetup, RoomPlanner,
    Run, EXACT_BAND,
};
use crate::{AccessibleRegion, ExactField3, LearnedField3, Result, SceneTables};
use envfield_grid::ContinuousField3;
use envfield_nets::FieldNet;
use envfield_plan::space3::SamplingConfig;
use envfield_scene::Scene;
use std::time::Instant;

/// How the planners are run on every pair of a room: what `room_nav`'s flags set and the
/// `room_planning` bench reads. The defaults are the room tables'.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSettings {
    /// Ours' expansions per step of the shortest walk, for a walking pair (plus 200); past
    /// them ours falls back to the region alone. A learned field's hollow takes many
    /// expansions to fill: at 5, 2-3% of the walks stopped in one.
    pub budget: f64,
    /// The same for a sit-down or lie-down pair: its steps must match the sequence's frames
    /// to the seat or bed, which takes search too.
    pub sit_budget: f64,
    /// RRT*'s second budget (`rrtstar_big`).
    pub big_budget: usize,
    /// RRT's and RRT*'s iterations and PRM's roadmap samples (the paper: 500, in a room).
    pub sampler_budget: usize,
    /// The samplers' seed.
    pub seed: u64,
    /// Ours' pose checks at most without coming nearer a walk's goal once within two steps
    /// of it ([`FieldSearch3::near_stall`](envfield_plan::space3::FieldSearch3::near_stall),
    /// 0 for no limit): [`NEAR_STALL`](super::NEAR_STALL) in rooms, where it was set; 0 on
    /// game levels, whose checks ask the scene itself and whose strict searches near a goal
    /// run longer (with the limit, 2 of the dungeon's 20 walks fell back to the region alone).
    pub near_stall: usize,
}

impl Default for RunSettings {
    fn default() -> Self {
        Self {
            budget: 50.0,
            sit_budget: 50.0,
            big_budget: 5000,
            sampler_budget: SamplingConfig::default().budget,
            seed: SamplingConfig::default().seed,
            near_stall: super::NEAR_STALL,
        }
    }
}

impl RunSettings {
    /// Ours' budget for a pair of `kind`.
    pub fn budget_for(&self, kind: PairKind) -> f64 {
        match kind {
            PairKind::Walk => self.budget,
            PairKind::Sit | PairKind::Lie => self.sit_budget,
        }
    }
}

/// What a room gives every planner, made once before any goal: the scene, the accessible
/// region, the learned field's network, the scene's tables that ours' pose checks read, and
/// a navigation mesh if the caller built one, with the seconds each took.
pub struct RoomContext<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The accessible region (the free space of every planner but the navigation mesh and
    /// the line).
    pub region: &'a AccessibleRegion,
    /// The room's learned 3D field; without one the planners that descend it cannot run (a
    /// scene no field was trained for).
    pub net: Option<&'a FieldNet>,
    /// The scene sampled for ours' pose checks ([`RoomContext::tables`]); without them ours'
    /// checks ask the scene itself (a scene too large to sample).
    pub tables: Option<&'a SceneTables>,
    /// Seconds the tables took.
    pub tables_s: f64,
    /// A navigation mesh of the scene and the seconds its build took.
    pub navmesh: Option<(&'a dyn FloorPlanner, f64)>,
}

impl<'a> RoomContext<'a> {
    /// A scene and its region alone: no learned field, no tables (ours' checks ask the
    /// scene), no navigation mesh. A game level too large to sample is run this way.
    pub fn bare(scene: &'a Scene, region: &'a AccessibleRegion) -> Self {
        Self {
            scene,
            region,
            net: None,
            tables: None,
            tables_s: 0.0,
            navmesh: None,
        }
    }

    /// The tables of `scene` for ours' checks ([`SceneTables::of`]), with the seconds they
    /// took.
    ///
    /// # Errors
    /// Errors of [`SceneTables::check`] and [`SceneTables::of`] (an empty scene, one too
    /// large).
    pub fn tables(scene: &Scene) -> Result<(SceneTables, f64)> {
        SceneTables::check(scene)?;
        let t = Instant::now();
        let tables = SceneTables::of(scene)?;
        Ok((tables, t.elapsed().as_secs_f64()))
    }

    /// The bytes ours and the navigation mesh keep for the room, by name: `region_bytes` (a
    /// byte a voxel of the region's box), `free_cells_bytes` (the accessible voxels numbered
    /// and linked for fast marching, [`AccessibleRegion::free_cells`]), `distances_bytes` (the
    /// distance grid), `beneath_bytes` (the surface columns), `field_per_goal_bytes` (one
    /// goal's field table, an f32 an accessible voxel) and `navmesh_bytes` (0 without one).
    ///
    /// # Errors
    /// As [`AccessibleRegion::free_cells`].
    pub fn bytes(&self) -> Result<[(&'static str, usize); 6]> {
        let cells = self.region.free_cells()?;
        Ok([
            ("region_bytes", self.region.grid.len()),
            ("free_cells_bytes", cells.bytes()),
            (
                "distances_bytes",
                self.tables.map_or(0, |t| t.distances.bytes()),
            ),
            (
                "beneath_bytes",
                self.tables.map_or(0, |t| t.beneath.bytes()),
            ),
            ("field_per_goal_bytes", 4 * cells.len()),
            ("navmesh_bytes", self.navmesh.map_or(0, |(m, _)| m.bytes())),
        ])
    }

    /// The seconds `planner` spent on the room before any goal.
    pub fn room_seconds(&self, planner: RoomPlanner) -> f64 {
        match planner {
            RoomPlanner::Ours | RoomPlanner::OursExact => self.tables_s,
            RoomPlanner::Navmesh => self.navmesh.map_or(0.0, |(_, s)| s),
            _ => 0.0,
        }
    }
}

/// Runs every planner of `planners` on one pair of the room, each timed on its own (per path,
/// and its per-goal and per-room work apart), its poses fitted and checked against the scene.
///
/// # Errors
/// [`RoomsError::InvalidInput`](crate::RoomsError::InvalidInput) for a start or goal outside the region, or the navigation
/// mesh asked for and not given; errors of the planners and fields.
pub fn run_pair(
    room: &RoomContext,
    pair: &Pair,
    planners: &[RoomPlanner],
    settings: &RunSettings,
) -> Result<Vec<Run>> {
    let region = room.region;
    let goal_cell = region.cell(pair.goal, "goal")?;
    region.cell(pair.start, "start")?;
    let t = Instant::now();
    let exact = ExactField3::toward(region, goal_cell, pair.start, EXACT_BAND)?;
    let exact_s = t.elapsed().as_secs_f64();
    let shortest = exact.value(pair.start)? as f64;
    let learned = room
        .net
        .map(|net| LearnedField3::new(net, region, goal_cell))
        .transpose()?;
    let table = match &learned {
        Some(learned)
            if planners
                .iter()
                .any(|p| p.field() == Some(FieldKind::LearnedTable)) =>
        {
            let t = Instant::now();
            let table = learned_table(learned, region)?;
            Some((table, t.elapsed().as_secs_f64()))
        }
        _ => None,
    };
    let mut setup = PairSetup::new(room.scene, region, room.tables, pair, shortest, settings);
    setup.navmesh = room.navmesh.map(|(m, _)| m);
    let mut out = Vec::with_capacity(planners.len());
    for &planner in planners {
        let (field, goal_seconds): (Option<&dyn ContinuousField3>, f64) = match planner.field() {
            Some(FieldKind::Learned) => (learned.as_ref().map(|l| l as &dyn ContinuousField3), 0.0),
            Some(FieldKind::LearnedTable) => match &table {
                Some((t, s)) => (Some(t), *s),
                None => (None, 0.0),
            },
            Some(FieldKind::Exact) => (Some(&exact), exact_s),
            None => (None, 0.0),
        };
        let t = Instant::now();
        let path = planner.plan(&setup, field, pair.start, pair.goal)?;
        let seconds = t.elapsed().as_secs_f64();
        let (poses, aligned) = fit(&setup.poses, &path.points, !planner.steps_are_points())?;
        let outcome = Outcome {
            reached: path.reached,
            no_route: path.exhausted,
            relaxed: path.relaxed,
            dist_m: path.final_distance as f64,
            seconds,
            goal_seconds,
            room_seconds: room.room_seconds(planner),
            path_ratio: if path.reached && shortest > 0.0 {
                path.length() as f64 / shortest
            } else {
                f64::NAN
            },
            poses,
        };
        out.push(Run {
            planner,
            outcome,
            path: path.points,
            poses: aligned,
        });
    }
    Ok(out)
}
