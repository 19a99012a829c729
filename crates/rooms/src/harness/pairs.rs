//! The pairs every planner is run on: walks between standing places of the region (half of
//! them from one room to another where the scene's rooms are known), and a sit-down at every
//! seat the region's sit-downs reach, and a lie-down at every bed or sofa its lie-downs reach.
//! One generator with
//! options serves `room_nav`, the `room_planning` bench and `level`.

use crate::{AccessibleRegion, ExactField3, LieDown, Result, RoomsError, SitDown};
use envfield_affordance::{
    afford, lie_on, sit_on, FilterConfig, PoseSequence, Support, WalkConfig,
};
use envfield_grid::{ContinuousField3, Point3m, SplitMix64};
use envfield_scene::nalgebra::Point3;
use envfield_scene::{Room, Scene};

/// What a pair is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PairKind {
    /// Walking between two standing places.
    Walk,
    /// Sitting down: from where the sit-down starts in front of a seat to seated.
    Sit,
    /// Lying down: from standing beside a bed or sofa, through sitting on its edge, to lying
    /// on it.
    Lie,
}

impl PairKind {
    /// The kind's name in tables and JSON keys.
    pub fn name(self) -> &'static str {
        match self {
            PairKind::Walk => "walk",
            PairKind::Sit => "sit",
            PairKind::Lie => "lie",
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
    /// Whether the sequence repeats (a walk) or plays once (a sit-down, a lie-down).
    pub repeat: bool,
    /// What the pair is.
    pub kind: PairKind,
}

impl Pair {
    /// A walk from `start` to `goal`, `gait` repeated along the path.
    pub fn walking(start: Point3m, goal: Point3m, gait: PoseSequence) -> Self {
        Self {
            start,
            goal,
            sequence: gait,
            repeat: true,
            kind: PairKind::Walk,
        }
    }

    /// The pair a region's sit-down makes: from its standing start to seated, its poses played
    /// once.
    ///
    /// # Errors
    /// As [`SitDown::sequence`].
    pub fn sitting_down(sit: &SitDown) -> Result<Self> {
        Ok(Self {
            start: sit.start,
            goal: sit.seated,
            sequence: sit.sequence()?,
            repeat: false,
            kind: PairKind::Sit,
        })
    }

    /// The pair a region's lie-down makes: from its standing start to lying, its poses
    /// (sitting down, then lying down) played once.
    ///
    /// # Errors
    /// As [`LieDown::sequence`].
    pub fn lying_down(lie: &LieDown) -> Result<Self> {
        Ok(Self {
            start: lie.sit.start,
            goal: lie.lying,
            sequence: lie.sequence()?,
            repeat: false,
            kind: PairKind::Lie,
        })
    }
}

/// How [`pairs`] draws its pairs. The default is `room_nav`'s: 4 walks, each start and goal
/// drawn together, at least a metre apart along the exact field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairOptions<'a> {
    /// Walking pairs wanted (fewer come back when the draws do not find them).
    pub walks: usize,
    /// The least distance between a walk's start and goal along the exact field, metres.
    pub min_distance: f32,
    /// `None`: each walk draws its start and goal among the standing places ([`standing_places`],
    /// all judged first). `Some(g)`: `g` goals, each shared by `walks / g` (rounded up) walks
    /// whose starts are drawn for it; a place is judged only when it is drawn, so a game
    /// level's hundreds of thousands of places are not all judged.
    pub goals: Option<usize>,
    /// The least height between a walk's start and goal, metres: a level's walks from one
    /// floor to another.
    pub rise: f32,
    /// Add a sit-down pair at every seat the region's sit-downs reach: every seat of the
    /// room's known furniture, or, in a scene without a furniture list, every place the
    /// region's sit-downs end (those within [`SEAT_APART`] of each other one seat).
    pub sit_downs: bool,
    /// Add a lie-down pair at every bed or sofa the region's lie-downs reach: every bed and
    /// sofa of the room's known furniture, or, in a scene without a furniture list, every
    /// place the region's lie-downs end (those within [`LIE_APART`] of each other one bed's).
    pub lie_downs: bool,
    /// The scene's rooms (`[x_min, y_min, x_max, y_max]`, an apartment's): half of the walks
    /// start in one and end in another. Empty: walks are drawn anywhere.
    pub rooms: &'a [[f32; 4]],
    /// The seed of the draws and the gait.
    pub seed: u64,
}

impl Default for PairOptions<'_> {
    fn default() -> Self {
        Self {
            walks: 4,
            min_distance: 1.0,
            goals: None,
            rise: 0.0,
            sit_downs: true,
            lie_downs: true,
            rooms: &[],
            seed: 0,
        }
    }
}

/// Sit-downs of a scene without a furniture list that end within this of each other (metres,
/// seated torsos) are one seat's.
pub const SEAT_APART: f32 = 0.45;

/// Lie-downs of a scene without a furniture list that end within this of each other (metres,
/// lying torsos) are one bed's: two people lie side by side on a double bed closer than this,
/// and one body's lying places on a bed's length lie within it.
pub const LIE_APART: f32 = 1.0;

/// Whether a standing pose with its torso at `p` is supported and collision-free.
fn stands(scene: &Scene, p: Point3m) -> bool {
    afford(scene, p, &FilterConfig::default()).is_ok_and(|a| a.valid == Some(Support::Standing))
}

/// The region's standing places: its kept samples that lie in it and afford standing (a
/// standing pose there is supported and collision-free), in the samples' order.
pub fn standing_places(scene: &Scene, region: &AccessibleRegion) -> Vec<Point3m> {
    region
        .samples
        .iter()
        .copied()
        .filter(|&s| region.contains(s))
        .filter(|&s| stands(scene, s))
        .collect()
}

/// Walking pairs between standing places of the region (kept samples that afford standing),
/// drawn as `options` says, then, for a `room` with known furniture and
/// [`PairOptions::sit_downs`], a sit-down pair at every seat the region's sit-downs reach
/// ([`AccessibleRegion::sit_downs`]): of those ending over the seat, the one ending nearest
/// the middle of its seat, from its standing start to seated; then, with
/// [`PairOptions::lie_downs`], a lie-down pair at every bed and sofa the region's lie-downs
/// reach ([`AccessibleRegion::lie_downs`]) likewise. Seeded.
///
/// # Errors
/// [`RoomsError::InvalidInput`] when walks are asked for and the region holds fewer than two
/// standing places; errors of the exact field.
pub fn pairs(
    room: Option<&Room>,
    scene: &Scene,
    region: &AccessibleRegion,
    options: &PairOptions,
) -> Result<Vec<Pair>> {
    let gait = envfield_affordance::walk(&WalkConfig::default(), options.seed)?;
    let ends = if options.walks == 0 {
        Vec::new()
    } else {
        match options.goals {
            None => walks_apart(scene, region, options)?,
            Some(goals) => walks_to_goals(scene, region, goals, options)?,
        }
    };
    let mut out: Vec<Pair> = ends
        .into_iter()
        .map(|(start, goal)| Pair::walking(start, goal, gait.clone()))
        .collect();
    if options.sit_downs {
        out.extend(match room {
            Some(room) => sit_down_pairs(room, region)?,
            None => seat_pairs(region)?,
        });
    }
    if options.lie_downs {
        out.extend(match room {
            Some(room) => lie_down_pairs(room, region)?,
            None => bed_pairs(region)?,
        });
    }
    Ok(out)
}

/// Whether a walk from `start` to `goal`, `d` apart along the exact field, is one `options`
/// asks for.
fn wanted(options: &PairOptions, start: Point3m, goal: Point3m, d: f32) -> bool {
    d.is_finite() && d >= options.min_distance && (start[2] - goal[2]).abs() >= options.rise
}

/// Each walk's start and goal drawn together among the standing places (100 draws a walk at
/// most).
fn walks_apart(
    scene: &Scene,
    region: &AccessibleRegion,
    options: &PairOptions,
) -> Result<Vec<(Point3m, Point3m)>> {
    let standing = standing_places(scene, region);
    if standing.len() < 2 {
        return Err(RoomsError::InvalidInput(
            "fewer than two standing places in the accessible region".into(),
        ));
    }
    let count = options.walks;
    let mut rng = SplitMix64::new(options.seed ^ 0x9A1B);
    let room_of = |p: Point3m| {
        options
            .rooms
            .iter()
            .position(|r| p[0] >= r[0] && p[0] <= r[2] && p[1] >= r[1] && p[1] <= r[3])
    };
    let mut out = Vec::new();
    let mut tries = 0;
    while out.len() < count && tries < 100 * count {
        tries += 1;
        let (a, b) = (
            standing[rng.below(standing.len())],
            standing[rng.below(standing.len())],
        );
        // With rooms known, every other walk (the first included) goes from one to another.
        let between = !options.rooms.is_empty() && out.len() % 2 == 0;
        if between && (room_of(a).is_none() || room_of(a) == room_of(b)) {
            continue;
        }
        let d = ExactField3::new(region, b)?.value(a)?;
        if wanted(options, a, b, d) {
            out.push((a, b));
        }
    }
    Ok(out)
}

/// `goals` goals drawn among the region's kept samples, each judged standing when drawn, and
/// for each up to `walks / goals` (rounded up) starts drawn for it (200 draws a start at
/// most): one fast marching a goal.
fn walks_to_goals(
    scene: &Scene,
    region: &AccessibleRegion,
    goals: usize,
    options: &PairOptions,
) -> Result<Vec<(Point3m, Point3m)>> {
    let places: Vec<Point3m> = region
        .samples
        .iter()
        .copied()
        .filter(|s| region.contains(*s))
        .collect();
    if places.len() < 2 || goals == 0 {
        return Err(RoomsError::InvalidInput(
            "fewer than two standing places in the accessible region, or no goal".into(),
        ));
    }
    let count = options.walks;
    let mut rng = SplitMix64::new(options.seed ^ 0x1E7E1);
    let per_goal = count.div_ceil(goals);
    let mut out = Vec::new();
    let mut tries = 0;
    while out.len() < count && tries < 100 * goals {
        tries += 1;
        let goal = places[rng.below(places.len())];
        if !stands(scene, goal) {
            continue;
        }
        let field = ExactField3::new(region, goal)?;
        let mut found = 0;
        for _ in 0..200 * per_goal {
            if found == per_goal || out.len() == count {
                break;
            }
            let start = places[rng.below(places.len())];
            let d = field.value(start)?;
            if wanted(options, start, goal, d) && stands(scene, start) {
                out.push((start, goal));
                found += 1;
            }
        }
    }
    Ok(out)
}

/// A sit-down pair at every seat of `room` the region's sit-downs reach: of those ending over
/// the seat, the one ending nearest where a body sits down on its middle.
fn sit_down_pairs(room: &Room, region: &AccessibleRegion) -> Result<Vec<Pair>> {
    let mut out = Vec::new();
    for f in &room.furniture {
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
            out.push(Pair::sitting_down(sit)?);
        }
    }
    Ok(out)
}

/// A sit-down pair at every seat the region's sit-downs reach in a scene without a
/// furniture list: the sit-downs in the order found, each ending farther than [`SEAT_APART`]
/// from every one taken before.
fn seat_pairs(region: &AccessibleRegion) -> Result<Vec<Pair>> {
    let mut taken: Vec<Point3m> = Vec::new();
    let mut out = Vec::new();
    for sit in &region.sit_downs {
        let p = Point3::from(sit.seated);
        if taken
            .iter()
            .any(|t| (Point3::from(*t) - p).norm() <= SEAT_APART)
        {
            continue;
        }
        taken.push(sit.seated);
        out.push(Pair::sitting_down(sit)?);
    }
    Ok(out)
}

/// A lie-down pair at every bed and sofa of `room` the region's lie-downs reach: of those
/// ending over the piece, the one ending nearest where a body lies down on it from its front
/// ([`lie_on`]).
fn lie_down_pairs(room: &Room, region: &AccessibleRegion) -> Result<Vec<Pair>> {
    let mut out = Vec::new();
    for f in &room.furniture {
        let Some(middle) = lie_on(f)?.and_then(|s| s.frames.last().map(|p| p.torso())) else {
            continue;
        };
        let nearest = region
            .lie_downs
            .iter()
            .filter(|l| f.covers(l.lying[0], l.lying[1]))
            .min_by(|a, b| {
                let d = |l: &&LieDown| (Point3::from(l.lying) - middle).norm();
                d(a).total_cmp(&d(b))
            });
        if let Some(lie) = nearest {
            out.push(Pair::lying_down(lie)?);
        }
    }
    Ok(out)
}

/// A lie-down pair at every bed the region's lie-downs reach in a scene without a furniture
/// list: the lie-downs in the order found, each ending farther than [`LIE_APART`] from every
/// one taken before.
fn bed_pairs(region: &AccessibleRegion) -> Result<Vec<Pair>> {
    let mut taken: Vec<Point3<f32>> = Vec::new();
    let mut out = Vec::new();
    for lie in &region.lie_downs {
        let p = Point3::from(lie.lying);
        if taken.iter().any(|t| (t - p).norm() <= LIE_APART) {
            continue;
        }
        taken.push(p);
        out.push(Pair::lying_down(lie)?);
    }
    Ok(out)
}
