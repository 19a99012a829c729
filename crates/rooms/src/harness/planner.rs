//! The planners of the room tables by name, the setup they share on one pair, and the fields
//! ours descends.

use super::{Pair, PairKind, RunSettings};
use crate::{
    AccessibleRegion, LearnedField3, PoseFilter, Result, RoomsError, SceneTables, VoxelField3,
};
use envfield_grid::{ContinuousField3, Point3m};
use envfield_plan::space3::{
    prm, rrt, rrt_star, straight_line, FieldSearch3, Path3, SamplingConfig, StepFilter,
};
use envfield_scene::Scene;
use std::fmt;
use std::str::FromStr;

/// The planners of the room tables, in the tables' order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RoomPlanner {
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

impl RoomPlanner {
    /// Every planner, in the tables' order.
    pub const ALL: [RoomPlanner; 10] = [
        RoomPlanner::Ours,
        RoomPlanner::OursRaw,
        RoomPlanner::OursNoAff,
        RoomPlanner::OursExact,
        RoomPlanner::Rrt,
        RoomPlanner::RrtStar,
        RoomPlanner::RrtStarBig,
        RoomPlanner::Prm,
        RoomPlanner::Line,
        RoomPlanner::Navmesh,
    ];

    /// The planner's name in tables, JSON keys and file names.
    pub fn name(self) -> &'static str {
        match self {
            RoomPlanner::Ours => "ours",
            RoomPlanner::OursRaw => "ours_raw",
            RoomPlanner::OursNoAff => "ours_noaff",
            RoomPlanner::OursExact => "ours_exact",
            RoomPlanner::Rrt => "rrt",
            RoomPlanner::RrtStar => "rrtstar",
            RoomPlanner::RrtStarBig => "rrtstar_big",
            RoomPlanner::Prm => "prm",
            RoomPlanner::Line => "line",
            RoomPlanner::Navmesh => "navmesh",
        }
    }

    /// The planners of `chosen`, in the tables' order; every one for `None`.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] for an empty choice.
    pub fn chosen(chosen: Option<&[RoomPlanner]>) -> Result<Vec<RoomPlanner>> {
        match chosen {
            Some([]) => Err(RoomsError::InvalidInput(
                "no planner chosen: name one at least".into(),
            )),
            Some(p) => Ok(RoomPlanner::ALL
                .into_iter()
                .filter(|k| p.contains(k))
                .collect()),
            None => Ok(RoomPlanner::ALL.to_vec()),
        }
    }

    /// Whether the planner reads the room's learned field (so the room needs one trained).
    pub fn learned(self) -> bool {
        matches!(
            self.field(),
            Some(FieldKind::Learned | FieldKind::LearnedTable)
        )
    }

    /// Which field the planner descends, if any.
    pub fn field(self) -> Option<FieldKind> {
        match self {
            RoomPlanner::Ours | RoomPlanner::OursNoAff => Some(FieldKind::LearnedTable),
            RoomPlanner::OursRaw => Some(FieldKind::Learned),
            RoomPlanner::OursExact => Some(FieldKind::Exact),
            _ => None,
        }
    }

    /// Whether its path's points are the walk's steps (ours), so its poses are placed on them
    /// as they are; the others' paths are resampled at the walk's step first.
    pub fn steps_are_points(self) -> bool {
        self.field().is_some()
    }

    /// One path from `start` to `goal`. `field` is the field of [`RoomPlanner::field`]
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
            RoomPlanner::Ours => search.search_relaxed(field()?, poses, region, start, goal)?,
            RoomPlanner::OursRaw => {
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
            RoomPlanner::OursNoAff => {
                let f = region as &dyn StepFilter;
                let raw = search.search(field()?, f, start, goal)?;
                search.shortcut(f, &raw, goal)?
            }
            RoomPlanner::OursExact => {
                search.search_relaxed(field()?, poses, region, start, goal)?
            }
            RoomPlanner::Rrt => rrt(region, start, goal, sampling)?,
            RoomPlanner::RrtStar => rrt_star(region, start, goal, sampling)?,
            RoomPlanner::RrtStarBig => rrt_star(
                region,
                start,
                goal,
                &SamplingConfig {
                    budget: *big_budget,
                    ..*sampling
                },
            )?,
            RoomPlanner::Prm => prm(region, start, goal, sampling)?,
            RoomPlanner::Line => {
                Path3::ending(straight_line(start, goal, search.step)?, goal, 0.02)
            }
            RoomPlanner::Navmesh => {
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

impl fmt::Display for RoomPlanner {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for RoomPlanner {
    type Err = RoomsError;

    fn from_str(s: &str) -> Result<Self> {
        RoomPlanner::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = RoomPlanner::ALL.iter().map(|k| k.name()).collect();
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
    /// ([`VoxelField3::pinned`]), read by interpolation at every step.
    LearnedTable,
    /// The exact field ([`ExactField3`](crate::ExactField3)), fast marching once per goal.
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

impl<'a> PairSetup<'a> {
    /// The setup of `pair` in the room: ours' budget is `settings`' budget for the pair's
    /// kind, in expansions per step of the `shortest` walk (metres), plus 200; RRT*'s second
    /// budget, the samplers' budget and seed are `settings`'; the samplers step at the walk's
    /// step (at least 5 cm). Ours' pose checks read `tables` when given (the scene otherwise).
    pub fn new(
        scene: &'a Scene,
        region: &'a AccessibleRegion,
        tables: Option<&'a SceneTables>,
        pair: &'a Pair,
        shortest: f64,
        settings: &RunSettings,
    ) -> Self {
        let budget = settings.budget_for(pair.kind);
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
                // A sit-down is made for its seat (a lie-down for its bed), where it is
                // played: its poses follow where the torso is.
                in_place: pair.kind != PairKind::Walk,
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
                        settings.near_stall
                    } else {
                        0
                    },
                }
            },
            sampling: SamplingConfig {
                step: step.max(0.05),
                seed: settings.seed,
                budget: settings.sampler_budget,
                ..SamplingConfig::default()
            },
            big_budget: settings.big_budget,
            navmesh: None,
        }
    }
}

/// Pose checks at most without coming nearer the goal once ours' strict search for a walk is
/// within two steps of it ([`FieldSearch3::near_stall`]), before ours falls back to the region
/// alone: a goal a body fits only at a few frames and headings is come close to early, and
/// the search would otherwise spend its whole budget on the rest of the room. Set above the
/// longest such run of any strict search in a room that went on to land
/// (`docs/notes/performance-history.md`), so there it ends only searches that would have
/// failed; on a game level it ended two that would have landed, and `level` runs without it
/// ([`RunSettings::near_stall`](super::RunSettings::near_stall)).
pub const NEAR_STALL: usize = 2500;

/// How far past a pair's start, and how much longer than the shortest way, ours' exact field
/// is marched, metres ([`ExactField3::toward`](crate::ExactField3::toward)): room for the search to go round what the
/// poses refuse, at a fraction of the whole region's march.
pub const EXACT_BAND: f32 = 1.0;

/// How far from its goal ours' learned table is pinned to it, metres
/// ([`VoxelField3::pinned`]): about the reach of a sit-down, whose
/// seated goal is where a room's network reads worst (the measurements, with and without it,
/// are in `docs/notes/rooms-history.md`).
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
