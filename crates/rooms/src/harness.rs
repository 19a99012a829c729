//! The room navigation harness (paper Tables 3 and 4): the planners by name, the walking and
//! sit-down pairs, one run of every planner on a pair with its poses fitted and checked, and
//! the tables' summary. `room_nav` and the `room_planning` bench both run it.
//!
//! Each planner's work is split as a navigation mesh splits it, and timed so: once per room
//! ([`RoomContext`]: the scene's distance grid ours' pose checks read, a navigation mesh's
//! build), once per goal (the exact field's fast marching, the learned field's one batched
//! pass over the region), and per path (the search, whose steps are lookups).

use crate::SceneTables;
use crate::{
    afford, point, sit_on, AccessibleRegion, ExactField3, PoseFilter, RegionConfig, SitDown,
};
use crate::{LearnedField3, Result, RoomsError, VoxelField3};
use envfield_affordance::{
    resample_path, walk, AffordanceReport, PoseSequence, Support, WalkConfig,
};
use envfield_grid::{ContinuousField3, Point3m, SplitMix64};
use envfield_nets::FieldNet;
use envfield_plan::space3::{
    prm, rrt, rrt_star, straight_line, FieldSearch3, Path3, SamplingConfig, StepFilter,
};
use envfield_scene::nalgebra::Point3;
use envfield_scene::{Room, Scene};
use std::fmt;
use std::str::FromStr;
use std::time::Instant;

/// The planners of the room tables, in the tables' order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PlannerKind {
    /// Ours: the search under the pose filter on the learned field, the region alone where
    /// that finds no route within the budget, then straight cuts the pose filter allows.
    Ours,
    /// The paper's search alone, on the learned field.
    OursRaw,
    /// The search and cuts under the region alone (no affordance), on the learned field.
    OursNoAff,
    /// Ours on the exact field.
    OursExact,
    /// RRT at the sampling config's budget.
    Rrt,
    /// RRT* at the sampling config's budget.
    RrtStar,
    /// RRT* at the harness's big budget.
    RrtStarBig,
    /// PRM, its roadmap included.
    Prm,
    /// The straight line (blind to the region).
    Line,
    /// A navigation mesh of the scene (the games' planner), given by the caller as a
    /// [`FloorPlanner`]: `room_nav` and the bench build one with Recast's Rust port.
    Navmesh,
}

impl PlannerKind {
    /// Every planner, in the tables' order.
    pub const ALL: [PlannerKind; 10] = [
        PlannerKind::Ours,
        PlannerKind::OursRaw,
        PlannerKind::OursNoAff,
        PlannerKind::OursExact,
        PlannerKind::Rrt,
        PlannerKind::RrtStar,
        PlannerKind::RrtStarBig,
        PlannerKind::Prm,
        PlannerKind::Line,
        PlannerKind::Navmesh,
    ];

    /// The planner's name in tables, JSON keys and file names.
    pub fn name(self) -> &'static str {
        match self {
            PlannerKind::Ours => "ours",
            PlannerKind::OursRaw => "ours_raw",
            PlannerKind::OursNoAff => "ours_noaff",
            PlannerKind::OursExact => "ours_exact",
            PlannerKind::Rrt => "rrt",
            PlannerKind::RrtStar => "rrtstar",
            PlannerKind::RrtStarBig => "rrtstar_big",
            PlannerKind::Prm => "prm",
            PlannerKind::Line => "line",
            PlannerKind::Navmesh => "navmesh",
        }
    }

    /// Which field the planner descends, if any.
    pub fn field(self) -> Option<FieldKind> {
        match self {
            PlannerKind::Ours | PlannerKind::OursNoAff => Some(FieldKind::LearnedTable),
            PlannerKind::OursRaw => Some(FieldKind::Learned),
            PlannerKind::OursExact => Some(FieldKind::Exact),
            _ => None,
        }
    }

    /// Whether its path's points are the walk's steps (ours), so its poses are placed on them
    /// as they are; the others' paths are resampled at the walk's step first.
    pub fn steps_are_points(self) -> bool {
        self.field().is_some()
    }

    /// One path from `start` to `goal`. `field` is the field of [`PlannerKind::field`]
    /// (ignored by the others).
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] when the planner needs a field and gets none; errors of
    /// the planners (a start or goal outside the region).
    pub fn plan(
        self,
        setup: &PairSetup,
        field: Option<&dyn ContinuousField3>,
        start: Point3m,
        goal: Point3m,
    ) -> Result<Path3> {
        let PairSetup {
            region,
            poses,
            search,
            sampling,
            big_budget,
            navmesh,
        } = setup;
        let field = || {
            field.ok_or_else(|| RoomsError::InvalidInput(format!("planner {self}: needs a field")))
        };
        let region = *region;
        Ok(match self {
            PlannerKind::Ours => search.search_relaxed(field()?, poses, region, start, goal)?,
            PlannerKind::OursRaw => {
                // The paper's search: its poses checked against the scene itself for support
                // and collisions only, no cap on the checks.
                let exact = PoseFilter {
                    tables: None,
                    clear_beneath: false,
                    ..*poses
                };
                let paper = FieldSearch3 {
                    max_checks: 0,
                    near_stall: 0,
                    ..*search
                };
                paper.search(field()?, &exact, start, goal)?
            }
            PlannerKind::OursNoAff => {
                let f = region as &dyn StepFilter;
                let raw = search.search(field()?, f, start, goal)?;
                search.shortcut(f, &raw, goal)?
            }
            PlannerKind::OursExact => {
                search.search_relaxed(field()?, poses, region, start, goal)?
            }
            PlannerKind::Rrt => rrt(region, start, goal, sampling)?,
            PlannerKind::RrtStar => rrt_star(region, start, goal, sampling)?,
            PlannerKind::RrtStarBig => rrt_star(
                region,
                start,
                goal,
                &SamplingConfig {
                    budget: *big_budget,
                    ..*sampling
                },
            )?,
            PlannerKind::Prm => prm(region, start, goal, sampling)?,
            PlannerKind::Line => {
                Path3::ending(straight_line(start, goal, search.step)?, goal, 0.02)
            }
            PlannerKind::Navmesh => {
                let mesh = navmesh.ok_or_else(|| {
                    RoomsError::InvalidInput(
                        "planner navmesh: no navigation mesh was given (RoomContext::navmesh)"
                            .into(),
                    )
                })?;
                let points = mesh.floor_path(start, goal)?.unwrap_or_else(|| vec![start]);
                Path3::ending(points, goal, 0.02)
            }
        })
    }
}

impl fmt::Display for PlannerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for PlannerKind {
    type Err = RoomsError;

    fn from_str(s: &str) -> Result<Self> {
        PlannerKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = PlannerKind::ALL.iter().map(|k| k.name()).collect();
                RoomsError::InvalidInput(format!(
                    "unknown planner `{s}` (one of {})",
                    names.join(", ")
                ))
            })
    }
}

/// The field a planner descends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldKind {
    /// The room's learned field ([`LearnedField3`]), one network pass per search step (the
    /// paper's way).
    Learned,
    /// The learned field tabulated over the region once per goal
    /// ([`LearnedField3::tabulate`]) and pinned to its goal within [`PIN_RADIUS`]
    /// ([`crate::VoxelField3::pinned`]), read by interpolation at every step.
    LearnedTable,
    /// The exact field ([`ExactField3`]), fast marching once per goal.
    Exact,
}

/// A planner of floor paths whose code lives outside this crate: the navigation mesh that
/// `room_nav` and the `room_planning` bench build (its crates are theirs, not the library's).
pub trait FloorPlanner: Sync {
    /// Torso locations from `start` to `goal`, or `None` when there is no path.
    ///
    /// # Errors
    /// Whatever stops it answering (a start off its mesh is `None`, not an error).
    fn floor_path(&self, start: Point3m, goal: Point3m) -> Result<Option<Vec<Point3m>>>;

    /// Bytes it keeps for the room.
    fn bytes(&self) -> usize;
}

/// What a pair is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PairKind {
    /// Walking between two standing places.
    Walk,
    /// Sitting down: from where the sit-down starts in front of a seat to seated.
    Sit,
}

impl PairKind {
    /// The kind's name in tables and JSON keys.
    pub fn name(self) -> &'static str {
        match self {
            PairKind::Walk => "walk",
            PairKind::Sit => "sit",
        }
    }
}

/// A start, a goal and the pose sequence a body follows between them.
#[derive(Clone, Debug)]
pub struct Pair {
    /// The start's torso location, metres.
    pub start: Point3m,
    /// The goal's torso location, metres.
    pub goal: Point3m,
    /// The poses: a gait repeated along the path, or a sit-down played once.
    pub sequence: PoseSequence,
    /// Whether the sequence repeats (a walk) or plays once (a sit-down).
    pub repeat: bool,
    /// What the pair is.
    pub kind: PairKind,
}

/// The region's standing places: its kept samples that lie in it and afford standing (a
/// standing pose there is supported and collision-free), in the samples' order.
pub fn standing_places(scene: &Scene, region: &AccessibleRegion) -> Vec<Point3m> {
    let config = RegionConfig::default();
    region
        .samples
        .iter()
        .copied()
        .filter(|&s| region.contains(s))
        .filter(|&s| afford(scene, s, &config).is_ok_and(|a| a.valid == Some(Support::Standing)))
        .collect()
}

/// Walking pairs between standing places of the region (kept samples that afford standing)
/// at least a metre apart along the exact field, `count` of them (fewer when 100 `count`
/// draws do not find them), then, for a `room` with known furniture, a sit-down pair at every
/// seat the region's sit-downs reach ([`AccessibleRegion::sit_downs`]): of those ending over
/// the seat, the one ending nearest the middle of its seat, from its standing start to seated.
/// Seeded.
///
/// # Errors
/// [`RoomsError::InvalidInput`] when the region holds fewer than two standing places; errors
/// of the exact field.
pub fn pairs(
    room: Option<&Room>,
    scene: &Scene,
    region: &AccessibleRegion,
    count: usize,
    seed: u64,
) -> Result<Vec<Pair>> {
    let standing = standing_places(scene, region);
    if standing.len() < 2 {
        return Err(RoomsError::InvalidInput(
            "fewer than two standing places in the accessible region".into(),
        ));
    }
    let gait = walk(&WalkConfig::default(), seed)?;
    let mut rng = SplitMix64::new(seed ^ 0x9A1B);
    let mut out = Vec::new();
    let mut tries = 0;
    while out
        .iter()
        .filter(|p: &&Pair| p.kind == PairKind::Walk)
        .count()
        < count
        && tries < 100 * count
    {
        tries += 1;
        let (a, b) = (
            standing[rng.below(standing.len())],
            standing[rng.below(standing.len())],
        );
        let exact = ExactField3::new(region, b)?;
        let d = exact.value(a)?;
        if d.is_finite() && d >= 1.0 {
            out.push(Pair {
                start: a,
                goal: b,
                sequence: gait.clone(),
                repeat: true,
                kind: PairKind::Walk,
            });
        }
    }
    if let Some(room) = room {
        for f in &room.furniture {
            // The region's own sit-down onto this seat: of those ending over it, the one
            // ending nearest where a body sits down on its middle.
            let Some(middle) = sit_on(f)?.and_then(|s| s.frames.last().map(|p| p.torso())) else {
                continue;
            };
            let nearest = region
                .sit_downs
                .iter()
                .filter(|s| f.covers(s.seated[0], s.seated[1]))
                .min_by(|a, b| {
                    let d = |s: &&SitDown| (Point3::from(s.seated) - middle).norm();
                    d(a).total_cmp(&d(b))
                });
            if let Some(sit) = nearest {
                out.push(Pair {
                    start: sit.start,
                    goal: sit.seated,
                    sequence: sit.sequence()?,
                    repeat: false,
                    kind: PairKind::Sit,
                });
            }
        }
    }
    Ok(out)
}

/// The shares of a path's poses that are supported, collision-free and both, in percent.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseShares {
    /// Supported.
    pub support: f64,
    /// Collision-free.
    pub free: f64,
    /// Supported and collision-free.
    pub valid: f64,
    /// On or inside furniture people do not use that way ([`crate::implausible`]); NaN until
    /// [`PoseShares::judge`] is told the room's furniture.
    pub implausible: f64,
}

impl PoseShares {
    /// Sets [`PoseShares::implausible`] from `poses` (their torsos) in `room`.
    ///
    /// # Errors
    /// As [`crate::implausible`].
    pub fn judge(&mut self, poses: &PoseSequence, room: &Room) -> Result<()> {
        let mut bad = 0usize;
        for pose in &poses.frames {
            bad += usize::from(crate::implausible(room, pose.torso().into())?.is_some());
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
            .map(|p| <[f32; 3]>::from(*p))
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
    pub planner: PlannerKind,
    /// How it did.
    pub outcome: Outcome,
    /// Its path's torso locations.
    pub path: Vec<Point3m>,
    /// The pair's poses fitted to the path.
    pub poses: PoseSequence,
}

/// What every planner shares on one pair: the region, the pose filter, the search's and the
/// samplers' settings.
pub struct PairSetup<'a> {
    /// The free space.
    pub region: &'a AccessibleRegion,
    /// The pair's pose filter.
    pub poses: PoseFilter<'a>,
    /// Ours' search.
    pub search: FieldSearch3,
    /// RRT's, RRT*'s and PRM's settings.
    pub sampling: SamplingConfig,
    /// RRT*'s second budget.
    pub big_budget: usize,
    /// The navigation mesh, if the caller built one.
    pub navmesh: Option<&'a dyn FloorPlanner>,
}

/// How the planners are run on every pair of a room.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSettings {
    /// Ours' expansions per step of the shortest walk.
    pub budget: f64,
    /// RRT*'s second budget (`rrtstar_big`).
    pub big_budget: usize,
    /// RRT's and RRT*'s iterations and PRM's roadmap samples (the paper: 500, in a room).
    pub sampler_budget: usize,
    /// The samplers' seed.
    pub seed: u64,
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
    /// Errors of [`SceneTables::of`] (an empty scene).
    pub fn tables(scene: &Scene) -> Result<(SceneTables, f64)> {
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
    pub fn room_seconds(&self, planner: PlannerKind) -> f64 {
        match planner {
            PlannerKind::Ours | PlannerKind::OursExact => self.tables_s,
            PlannerKind::Navmesh => self.navmesh.map_or(0.0, |(_, s)| s),
            _ => 0.0,
        }
    }
}

impl<'a> PairSetup<'a> {
    /// The setup of `pair` in the room: ours' budget is `budget` expansions per step of the
    /// `shortest` walk (metres) plus 200, the samplers step at the walk's step (at least
    /// 5 cm), seeded by `seed`. Ours' pose checks read `tables` when given (the scene
    /// otherwise).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        scene: &'a Scene,
        region: &'a AccessibleRegion,
        tables: Option<&'a SceneTables>,
        pair: &'a Pair,
        shortest: f64,
        budget: f64,
        big_budget: usize,
        seed: u64,
    ) -> Self {
        let step = pair.sequence.step_length();
        Self {
            region,
            poses: PoseFilter {
                scene,
                region,
                sequence: &pair.sequence,
                repeat: pair.repeat,
                // A walk faces where it goes; a sit-down keeps the heading made for its seat.
                face_the_move: pair.repeat,
                affordance: Default::default(),
                // Nothing between the legs is a walk's check: a sit-down lowers the pelvis
                // over the seat while its feet still bear the body.
                clear_beneath: pair.kind == PairKind::Walk,
                // A sit-down is made for its seat, where it is played: its poses follow where
                // the torso is.
                in_place: pair.kind == PairKind::Sit,
                tables,
            },
            search: {
                // A search that has not arrived by then is lost in a pocket the poses cannot
                // leave, and ours falls back to the region alone. In such a pocket nearly
                // every candidate's pose is refused: two checks per allowed expansion end it.
                let max_steps = (budget * shortest.max(0.5) / step as f64) as usize + 200;
                FieldSearch3 {
                    step,
                    tolerance: 0.02,
                    max_steps,
                    max_checks: 2 * max_steps,
                    // A sit-down wears the frame nearest its torso, not a gait's: its goal
                    // does not stand only at a few phases.
                    near_stall: if pair.kind == PairKind::Walk {
                        NEAR_STALL
                    } else {
                        0
                    },
                }
            },
            sampling: SamplingConfig {
                step: step.max(0.05),
                seed,
                ..SamplingConfig::default()
            },
            big_budget,
            navmesh: None,
        }
    }
}

/// Pose checks at most without coming nearer the goal once ours' strict search for a walk is
/// within two steps of it ([`FieldSearch3::near_stall`]), before ours falls back to the region
/// alone: a goal a body fits only at a few frames and headings is come close to early, and
/// the search would otherwise spend its whole budget on the rest of the room. Set above the
/// longest such run of any strict search that went on to land (`docs/performance.md`), so it
/// ends only searches that would have failed.
pub const NEAR_STALL: usize = 2500;

/// How far past a pair's start, and how much longer than the shortest way, ours' exact field
/// is marched, metres ([`ExactField3::toward`]): room for the search to go round what the
/// poses refuse, at a fraction of the whole region's march.
pub const EXACT_BAND: f32 = 1.0;

/// How far from its goal ours' learned table is pinned to it, metres
/// ([`VoxelField3::pinned`](crate::VoxelField3::pinned)): about the reach of a sit-down, whose
/// seated goal is where a room's network reads worst (the measurements, with and without it,
/// are in `docs/rooms.md`).
pub const PIN_RADIUS: f32 = 0.5;

/// Ours' table of the learned field for its goal: one batched pass over the region
/// ([`LearnedField3::tabulate`]), pinned to the goal within [`PIN_RADIUS`]
/// ([`VoxelField3::pinned`]).
///
/// # Errors
/// As [`LearnedField3::tabulate`].
pub fn learned_table(learned: &LearnedField3, region: &AccessibleRegion) -> Result<VoxelField3> {
    learned.tabulate(region)?.pinned(PIN_RADIUS)
}

/// Runs every planner of `planners` on one pair of the room, each timed on its own (per path,
/// and its per-goal and per-room work apart), its poses fitted and checked against the scene.
///
/// # Errors
/// [`RoomsError::InvalidInput`] for a start or goal outside the region, or the navigation
/// mesh asked for and not given; errors of the planners and fields.
pub fn run_pair(
    room: &RoomContext,
    pair: &Pair,
    planners: &[PlannerKind],
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
    let mut setup = PairSetup::new(
        room.scene,
        region,
        room.tables,
        pair,
        shortest,
        settings.budget,
        settings.big_budget,
        settings.seed,
    );
    setup.navmesh = room.navmesh.map(|(m, _)| m);
    setup.sampling.budget = settings.sampler_budget;
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
