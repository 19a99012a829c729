//! Several people sitting down together ([`plan_party`]): N people walk in from different
//! rooms and each sits on a different chair of one dining table, or, where the region reaches
//! too few of its chairs, on a different seat of one room. Each walk is planned alone (ours on
//! the exact field, to where the seat's sit-down starts) and the sit-down played after it;
//! then the guests go one after another, each waiting at its start until its whole motion
//! overlaps no body already placed at any frame (people walking through meanwhile placed
//! first). A body is its bones as capsules ([`BONE_RADIUS`]); every pair of people is checked
//! at every frame, a waiting person and a seated one included.

use crate::harness::{run_pair, standing_places, Pair, RoomContext, RoomPlanner, Run, RunSettings};
use crate::region::sit_down_to;
use crate::{AccessibleRegion, RegionConfig, Result, RoomsError, SitDown};
use envfield_affordance::{
    check_sequence, sit_on, walk, AffordanceConfig, Joint, Pose, PoseSequence, WalkConfig,
};
use envfield_grid::{Point3m, SplitMix64};
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::{ObjectKind, Room, Scene};
use std::time::Instant;

/// The radius of a bone's capsule in the body-overlap check, metres: two people overlap at a
/// frame when any bone of one comes within twice this of any bone of the other. Limbs are
/// thinner, the trunk wider; 6 cm around the bone lines (12 cm apart) is a thigh's or upper
/// arm's half-width.
pub const BONE_RADIUS: f32 = 0.06;

/// What [`plan_party`] plans.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PartyConfig {
    /// People, one per chair (at most the table's chairs the region's sit-downs reach).
    pub people: usize,
    /// A guest waits at its start in steps of this many frames.
    pub wait_step: usize,
    /// The longest wait, frames, before a guest is given up (not seated).
    pub max_wait: usize,
    /// The seed of the starts and the gait.
    pub seed: u64,
    /// People walking through meanwhile, not sitting: half from the party's room to another,
    /// half between other rooms; they go first and the guests wait for them too.
    pub passers: usize,
}

impl Default for PartyConfig {
    fn default() -> Self {
        Self {
            passers: 0,
            people: 4,
            wait_step: 10,
            max_wait: 3000,
            seed: 0,
        }
    }
}

/// One person of a party.
#[derive(Clone, Debug)]
pub struct Guest {
    /// Where they start, standing (torso, metres), and the room they start in (an index of
    /// the rooms given, `None` without rooms).
    pub start: Point3m,
    /// The room they start in.
    pub room: Option<usize>,
    /// Where they end seated (torso, metres).
    pub seat: Point3m,
    /// Their motion: the walk, then the sit-down, without the wait.
    pub motion: PoseSequence,
    /// Frames they wait at the start before moving.
    pub wait: usize,
    /// Whether they sat down: their walk reached the sit-down's start and a wait was found.
    pub seated: bool,
    /// Share of their motion's frames whose pose is supported and collision-free, percent.
    pub valid_pct: f64,
}

impl Guest {
    /// Their pose at frame `t` of the party: the start pose while waiting, the last (seated)
    /// pose once their motion is over.
    pub fn pose_at(&self, t: usize) -> &Pose {
        let frames = &self.motion.frames;
        let i = t.saturating_sub(self.wait).min(frames.len() - 1);
        &frames[i]
    }

    /// Frames until they are seated (their wait and their motion).
    pub fn end(&self) -> usize {
        self.wait + self.motion.frames.len()
    }
}

/// A party planned: its guests and what was measured.
#[derive(Clone, Debug)]
pub struct Party {
    /// The guests, in the order they were placed.
    pub guests: Vec<Guest>,
    /// The people walking through ([`PartyConfig::passers`]): `seat` is where they walk to,
    /// `seated` whether they got there.
    pub passers: Vec<Guest>,
    /// The seats the region's sit-downs reach where the party sits.
    pub chairs: usize,
    /// Where the party sits.
    pub at: Gathering,
    /// Frames until the last guest is seated.
    pub frames: usize,
    /// Frames at which two seated-or-walking guests' bodies overlap, counted per pair of
    /// guests, recomputed over the whole party (0 when the schedule holds).
    pub overlaps: usize,
    /// Seconds the plan took (walks, sit-downs, schedule, checks).
    pub seconds: f64,
}

impl Party {
    /// The party as one sequence per person on the common timeline (the wait at the start,
    /// the motion, then seated, or standing at the goal, to the end), the guests then the
    /// people walking through: what a viewer plays.
    ///
    /// # Errors
    /// As [`PoseSequence::new`].
    pub fn timelines(&self) -> Result<Vec<PoseSequence>> {
        self.guests
            .iter()
            .chain(&self.passers)
            .map(|g| {
                let frames: Vec<Pose> = (0..self.frames).map(|t| *g.pose_at(t)).collect();
                let supports = (0..self.frames)
                    .map(|t| {
                        let i = t.saturating_sub(g.wait).min(g.motion.supports.len() - 1);
                        g.motion.supports[i]
                    })
                    .collect();
                Ok(PoseSequence::new(
                    g.motion.fps,
                    g.motion.activity,
                    frames,
                    supports,
                )?)
            })
            .collect()
    }
}

/// The chairs around the room's dining table (their indices in [`Room::furniture`]): the
/// table (kind [`ObjectKind::Table`]) with the most chairs whose footprint's centre lies
/// within 0.9 m of its footprint, and those chairs; empty without a table with chairs.
pub fn dining_chairs(room: &Room) -> Vec<usize> {
    let near = |table: &envfield_scene::Furniture, chair: &envfield_scene::Furniture| {
        let (s, c) = table.yaw.sin_cos();
        let (dx, dy) = (
            chair.center[0] - table.center[0],
            chair.center[1] - table.center[1],
        );
        let (lx, ly) = (c * dx + s * dy, -s * dx + c * dy);
        let out_x = (lx.abs() - table.size[0] / 2.0).max(0.0);
        let out_y = (ly.abs() - table.size[1] / 2.0).max(0.0);
        out_x.hypot(out_y) <= 0.9
    };
    room.furniture
        .iter()
        .filter(|t| t.kind == ObjectKind::Table)
        .map(|t| {
            room.furniture
                .iter()
                .enumerate()
                .filter(|(_, c)| c.kind == ObjectKind::Chair && near(t, c))
                .map(|(i, _)| i)
                .collect::<Vec<usize>>()
        })
        .max_by_key(Vec::len)
        .unwrap_or_default()
}

/// What a pulled-out chair leaves between its footprint and its table's edge, metres: room to
/// stand in front of the seat and sit down, as a person pulls a chair out before sitting.
pub const PULL_ROOM: f32 = 0.35;

/// How close a moved chair's surface may come to anything else (metres) in [`lay_table`].
pub const PULL_CLEAR: f32 = 0.01;

/// The room with its dining table laid for a party: each chair of `chairs` (indices in
/// [`Room::furniture`], as [`dining_chairs`] gives them) is pulled straight back from the
/// table it faces until [`PULL_ROOM`] lies between its footprint and the table's, or, where a
/// wall or other furniture is in the way, as far back as it goes clear of them (in 5 cm
/// steps, its surface [`PULL_CLEAR`] from everything but its table at each, or no nearer
/// than it was where it already touched; it slides away from the table).
/// A chair with that room already stays. Chairs are moved one after another, each clear of
/// those moved before. Returns the laid room (scene and furniture list) and how far each
/// chair moved (metres, in the order of `chairs`).
///
/// The generator tucks chairs 5-15 cm under their table, and no sit-down onto them is valid
/// from any heading (a person's knees meet the table's edge): people pull the chair out first.
/// The pulling itself is not animated: the party starts at a laid table.
///
/// # Errors
/// [`RoomsError::InvalidInput`] for a chair index past the furniture or not a chair; errors of
/// moving the scene's objects.
pub fn lay_table(room: &Room, chairs: &[usize]) -> Result<(Room, Vec<f32>)> {
    let mut laid = room.clone();
    let mut moved = Vec::with_capacity(chairs.len());
    for &i in chairs {
        let chair = laid.furniture.get(i).cloned().ok_or_else(|| {
            RoomsError::InvalidInput(format!(
                "chair {i} to pull out: the room has {} pieces",
                laid.furniture.len()
            ))
        })?;
        if chair.kind != ObjectKind::Chair {
            return Err(RoomsError::InvalidInput(format!(
                "piece {i} to pull out is a {:?}, not a chair",
                chair.kind
            )));
        }
        let front = Vector3::new(-chair.yaw.sin(), chair.yaw.cos(), 0.0);
        let Some((gap, table)) = table_ahead(&laid, &chair).filter(|g| g.0 < PULL_ROOM) else {
            moved.push(0.0);
            continue;
        };
        let pulled = pull_back(&laid.scene, chair.object, table, -front, PULL_ROOM - gap)
            .map_err(|e| RoomsError::InvalidInput(format!("chair {i}: {e}")))?;
        if pulled > 0.0 {
            let by = envfield_scene::nalgebra::Isometry3::translation(
                -front.x * pulled,
                -front.y * pulled,
                0.0,
            );
            laid.scene = laid.scene.with_moved(chair.object, &by)?;
            laid.furniture[i].center = [
                chair.center[0] - front.x * pulled,
                chair.center[1] - front.y * pulled,
            ];
        }
        moved.push(pulled);
    }
    Ok((laid, moved))
}

/// The table across `chair`'s front (the chair faces `(-sin yaw, cos yaw)`; the table's
/// footprint spans the chair's centre sideways and lies ahead of its back): the gap from the
/// chair's footprint to the table's near edge (negative when tucked under it) and the table's
/// scene object. The nearest such table, `None` without one.
fn table_ahead(room: &Room, chair: &envfield_scene::Furniture) -> Option<(f32, usize)> {
    let (s, c) = chair.yaw.sin_cos();
    // Along the way the chair faces, and across it.
    let along = |(x, y): (f32, f32)| -s * x + c * y;
    let across = |(x, y): (f32, f32)| c * x + s * y;
    let centre = (chair.center[0], chair.center[1]);
    let edge = along(centre) + chair.size[1] / 2.0;
    room.furniture
        .iter()
        .filter(|t| t.kind == ObjectKind::Table)
        .filter_map(|t| {
            let f = t.footprint();
            let corners = [(f[0], f[1]), (f[2], f[1]), (f[0], f[3]), (f[2], f[3])];
            let near = corners.map(along).into_iter().fold(f32::INFINITY, f32::min);
            let sideways = corners.map(across);
            let lo = sideways.into_iter().fold(f32::INFINITY, f32::min);
            let hi = sideways.into_iter().fold(f32::NEG_INFINITY, f32::max);
            (near > edge - chair.size[1] && (lo..=hi).contains(&across(centre)))
                .then_some((near - edge, t.object))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// How far (metres, up to `want`) scene object `object` slides along the unit `way` in 5 cm
/// steps (the last one to `want`), stopping before the first step that brings its surface
/// (off the floor) within [`PULL_CLEAR`] of anything but itself and object `table`; a contact
/// it already has may stay, not grow. A step at a time, it cannot pass through a wall; out of
/// `table`, which a tucked chair may start inside (the generator overlaps footprints, not
/// shapes), it slides.
///
/// # Errors
/// `object` or `table` not in `scene`; errors of the scene's queries.
fn pull_back(
    scene: &Scene,
    object: usize,
    table: usize,
    way: Vector3<f32>,
    want: f32,
) -> Result<f32> {
    let rest = scene
        .without(object)
        .and_then(|s| s.without(if table > object { table - 1 } else { table }))
        .ok_or_else(|| {
            RoomsError::InvalidInput(format!(
                "objects {object} and {table} are not both in the scene"
            ))
        })?;
    let surface: Vec<Point3<f32>> = scene.objects()[object]
        .parts()
        .iter()
        .flat_map(|p| p.to_mesh().vertices)
        .filter(|v| v.z > 0.03)
        .collect();
    let before = rest.signed_distances(&surface)?;
    let mut pulled = 0.0;
    for k in 1..=(want / 0.05).ceil() as usize {
        let step = (k as f32 * 0.05).min(want);
        let there: Vec<Point3<f32>> = surface.iter().map(|v| v + way * step).collect();
        let clear = rest
            .signed_distances(&there)?
            .into_iter()
            .zip(&before)
            .all(|(d, &b)| d >= PULL_CLEAR.min(b - 1e-4));
        if !clear {
            break;
        }
        pulled = step;
    }
    Ok(pulled)
}

/// Ours on the exact field walking from `start` to `goal` in `region` (its checks asking the
/// scene), `gait` repeated along the path: its run, poses fitted.
///
/// # Errors
/// As [`run_pair`].
fn walk_exact(
    scene: &Scene,
    region: &AccessibleRegion,
    start: Point3m,
    goal: Point3m,
    gait: &PoseSequence,
) -> Result<Run> {
    let pair = Pair::walking(start, goal, gait.clone());
    run_pair(
        &RoomContext::bare(scene, region),
        &pair,
        &[RoomPlanner::OursExact],
        &RunSettings::default(),
    )?
    .pop()
    .ok_or_else(|| RoomsError::InvalidInput("the planner ran on no pair".into()))
}

/// Whether `p` lies in the region or beside it (one of its 26 neighbour voxels accessible).
fn beside(region: &AccessibleRegion, p: &Point3<f32>) -> bool {
    let grid = &region.grid;
    let Some(i) = region.frame.cell_of(p).and_then(|c| grid.index(c)) else {
        return false;
    };
    let free = |j: usize| grid.is_free(grid.cell(j));
    let mut near = free(i);
    grid.around(i, |j| near |= free(j));
    near
}

/// Each chair's sit-down: of the region's sit-downs ending over the chair, the one ending
/// nearest its middle; where none does (a chair tucked under the table, whose voxels the
/// region joined to the floor's without a sit-down), one made for it as the region makes
/// them ([`RegionConfig`]'s headings, every pose valid and plausible), ending seated where
/// the chair's own sit-down ends and starting in or beside the region.
///
/// # Errors
/// Errors of placing and checking the sit-downs.
fn chair_sit_downs(
    scene: &Scene,
    room: &Room,
    region: &AccessibleRegion,
    chairs: &[usize],
) -> Result<Vec<SitDown>> {
    let config = RegionConfig::default();
    let mut out = Vec::new();
    for &i in chairs {
        let f = &room.furniture[i];
        let found = region
            .sit_downs
            .iter()
            .filter(|s| f.covers(s.seated[0], s.seated[1]))
            .min_by(|a, b| {
                let d = |s: &&SitDown| (s.seated[0] - f.center[0]).hypot(s.seated[1] - f.center[1]);
                d(a).total_cmp(&d(b))
            })
            .copied();
        let made = match found {
            Some(s) => Some(s),
            None => match sit_on(f)?.and_then(|s| s.frames.last().map(|p| p.torso())) {
                Some(middle) => sit_down_to(scene, middle.into(), &config, &|p| beside(region, p))?,
                None => None,
            },
        };
        if let Some(sit) = made {
            if room_for(&out, &sit)? {
                out.push(sit);
            }
        }
    }
    Ok(out)
}

/// Where a party sits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Gathering {
    /// On chairs of the dining table.
    Table,
    /// On the seats (chairs, sofas, armchairs) of one room: the region's sit-downs reach too
    /// few of the table's chairs.
    Room,
}

/// Seats of a party apart from each other by this much at least (seated torsos, metres): two
/// people side by side on a sofa.
pub const SEAT_SPACING: f32 = 0.55;

/// The seats of the room holding the most: the region's sit-downs ending over a chair or a
/// sofa (not a bed), each leaving room for every one taken before ([`room_for`]), grouped by
/// the room (of `room_of`) they end in.
///
/// # Errors
/// As [`SitDown::sequence`].
fn room_seats(
    room: &Room,
    region: &AccessibleRegion,
    room_of: &dyn Fn(Point3m) -> Option<usize>,
) -> Result<Vec<SitDown>> {
    let mut groups: std::collections::BTreeMap<Option<usize>, Vec<SitDown>> =
        std::collections::BTreeMap::new();
    for sit in &region.sit_downs {
        let on_seat = room.furniture.iter().any(|f| {
            matches!(f.kind, ObjectKind::Chair | ObjectKind::Sofa)
                && f.covers(sit.seated[0], sit.seated[1])
        });
        if !on_seat {
            continue;
        }
        let group = groups.entry(room_of(sit.seated)).or_default();
        if room_for(group, sit)? {
            group.push(*sit);
        }
    }
    Ok(groups
        .into_values()
        .max_by_key(Vec::len)
        .unwrap_or_default())
}

/// Whether `sit`'s seated body leaves room for everyone seated by `taken`: its seated torso
/// [`SEAT_SPACING`] or more from theirs and its seated body overlapping none of theirs.
///
/// # Errors
/// As [`SitDown::sequence`].
fn room_for(taken: &[SitDown], sit: &SitDown) -> Result<bool> {
    let last = |s: &SitDown| -> Result<Pose> {
        let seq = s.sequence()?;
        Ok(seq.frames[seq.frames.len() - 1])
    };
    let mine = last(sit)?;
    for t in taken {
        let apart = (Point3::from(t.seated) - Point3::from(sit.seated)).norm() >= SEAT_SPACING;
        if !apart || bodies_overlap(&mine, &last(t)?) {
            return Ok(false);
        }
    }
    Ok(true)
}

/// Starts for `n` guests among the region's standing places: round the rooms other than
/// the table's (the table's own last), a place drawn in each, at least 1.5 m from every
/// start taken. Seeded.
fn starts(
    places: &[Point3m],
    rooms: &[[f32; 4]],
    table_room: Option<usize>,
    n: usize,
    seed: u64,
) -> Vec<(Point3m, Option<usize>)> {
    let room_of = |p: &Point3m| {
        rooms
            .iter()
            .position(|r| p[0] >= r[0] && p[0] <= r[2] && p[1] >= r[1] && p[1] <= r[3])
    };
    let mut order: Vec<Option<usize>> = (0..rooms.len())
        .filter(|&r| Some(r) != table_room)
        .map(Some)
        .collect();
    order.push(table_room);
    if rooms.is_empty() {
        order = vec![None];
    }
    let mut rng = SplitMix64::new(seed ^ 0x9A27);
    let mut out: Vec<(Point3m, Option<usize>)> = Vec::new();
    for k in 0..n * 50 {
        if out.len() == n {
            break;
        }
        let want = order[out.len() % order.len()];
        let apart = |p: &Point3m| {
            out.iter()
                .all(|(q, _)| (Point3::from(*p) - Point3::from(*q)).norm() >= 1.5)
        };
        // Past 25 tries a guest, any room will do.
        let candidates: Vec<&Point3m> = places
            .iter()
            .filter(|p| (k >= 25 * n || rooms.is_empty() || room_of(p) == want) && apart(p))
            .collect();
        if candidates.is_empty() {
            continue;
        }
        let p = *candidates[rng.below(candidates.len())];
        out.push((p, room_of(&p)));
    }
    out
}

/// The bones of a pose as segments: each joint to its parent.
fn bones(pose: &Pose) -> Vec<(Point3<f32>, Point3<f32>)> {
    Joint::ALL
        .iter()
        .filter_map(|&j| j.parent().map(|p| (pose.joint(j), pose.joint(p))))
        .collect()
}

/// The least distance between segments `a` and `b`.
fn segment_distance(a: (Point3<f32>, Point3<f32>), b: (Point3<f32>, Point3<f32>)) -> f32 {
    let (p1, q1, p2, q2) = (a.0, a.1, b.0, b.1);
    let (d1, d2, r): (Vector3<f32>, Vector3<f32>, Vector3<f32>) = (q1 - p1, q2 - p2, p1 - p2);
    let (aa, ee, f) = (d1.dot(&d1), d2.dot(&d2), d2.dot(&r));
    let (s, t) = if aa <= 1e-12 && ee <= 1e-12 {
        (0.0, 0.0)
    } else if aa <= 1e-12 {
        (0.0, (f / ee).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if ee <= 1e-12 {
            ((-c / aa).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = aa * ee - b * b;
            let mut s = if denom > 1e-12 {
                ((b * f - c * ee) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / ee;
            if t < 0.0 {
                t = 0.0;
                s = (-c / aa).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / aa).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    ((p1 + d1 * s) - (p2 + d2 * t)).norm()
}

/// Whether two poses' bodies overlap: any bone of one within twice [`BONE_RADIUS`] of any
/// bone of the other.
pub fn bodies_overlap(a: &Pose, b: &Pose) -> bool {
    // Far apart torsos cannot touch: a body reaches about a metre from its torso.
    if (a.torso() - b.torso()).norm() > 2.2 {
        return false;
    }
    let (ba, bb) = (bones(a), bones(b));
    ba.iter().any(|&x| {
        bb.iter()
            .any(|&y| segment_distance(x, y) < 2.0 * BONE_RADIUS)
    })
}

/// Whether `guest` overlaps any of `placed` at any frame up to when all of them are seated.
fn overlaps_any(guest: &Guest, placed: &[Guest]) -> bool {
    let end = placed
        .iter()
        .map(Guest::end)
        .chain([guest.end()])
        .max()
        .unwrap_or(0);
    (0..end).any(|t| {
        placed
            .iter()
            .any(|p| bodies_overlap(guest.pose_at(t), p.pose_at(t)))
    })
}

/// A guest's motion from `start`: ours on the exact field of `region` to the sit-down's
/// start, then the sit-down; and whether the walk reached it.
fn motion(
    scene: &Scene,
    region: &AccessibleRegion,
    start: Point3m,
    sit: &SitDown,
    gait: &PoseSequence,
) -> Result<(PoseSequence, bool)> {
    let run = walk_exact(scene, region, start, sit.start, gait)?;
    let sit_down = sit.sequence()?;
    let mut frames = run.poses.frames;
    let mut supports = run.poses.supports;
    frames.extend(sit_down.frames.iter().copied());
    supports.extend(sit_down.supports.iter().copied());
    Ok((
        PoseSequence::new(gait.fps, sit_down.activity, frames, supports)?,
        run.outcome.reached,
    ))
}

/// People walking through the apartment while the party sits down ([`PartyConfig::passers`]):
/// passer `i` starts in the party's room when `i` is even, in another room when odd, and walks
/// to a standing place of a room other than its start's, 1.5 m or more from every start and
/// goal taken and from `avoid` (the guests' starts and sit-downs); each placed after those
/// before with a wait at its start. A passer whose walk
/// does not arrive, or that finds no wait, is left out (`seated` false, not in the schedule).
///
/// # Errors
/// Errors of the planner and the pose checks.
#[allow(clippy::too_many_arguments)]
fn walk_through(
    scene: &Scene,
    region: &AccessibleRegion,
    places: &[Point3m],
    avoid: &[Point3m],
    rooms: &[[f32; 4]],
    party_room: Option<usize>,
    gait: &PoseSequence,
    config: &PartyConfig,
) -> Result<Vec<Guest>> {
    let room_of = |p: &Point3m| {
        rooms
            .iter()
            .position(|r| p[0] >= r[0] && p[0] <= r[2] && p[1] >= r[1] && p[1] <= r[3])
    };
    let mut rng = SplitMix64::new(config.seed ^ 0x7A55);
    let mut taken: Vec<Point3m> = avoid.to_vec();
    let mut out: Vec<Guest> = Vec::new();
    let check = AffordanceConfig::default();
    for i in 0..config.passers {
        let free = |p: &&Point3m, taken: &[Point3m]| {
            taken
                .iter()
                .all(|q| (Point3::from(**p) - Point3::from(*q)).norm() >= 1.5)
        };
        let from: Vec<&Point3m> = places
            .iter()
            .filter(|p| (room_of(p) == party_room) == (i % 2 == 0) && free(p, &taken))
            .collect();
        if from.is_empty() {
            continue;
        }
        let start = *from[rng.below(from.len())];
        let to: Vec<&Point3m> = places
            .iter()
            .filter(|p| room_of(p) != room_of(&start) && room_of(p) != party_room)
            .filter(|p| free(p, &taken) && (Point3::from(**p) - Point3::from(start)).norm() >= 1.5)
            .collect();
        if to.is_empty() {
            continue;
        }
        let goal = *to[rng.below(to.len())];
        taken.extend([start, goal]);
        let run = walk_exact(scene, region, start, goal, gait)?;
        let reports = check_sequence(scene, &run.poses, &check)?;
        let valid = reports.iter().filter(|r| r.valid()).count();
        let mut passer = Guest {
            start,
            room: room_of(&start),
            seat: goal,
            valid_pct: 100.0 * valid as f64 / reports.len().max(1) as f64,
            motion: run.poses,
            wait: 0,
            seated: run.outcome.reached,
        };
        if !passer.seated {
            continue;
        }
        let step = config.wait_step.max(1);
        let wait = (0..=config.max_wait / step).find_map(|w| {
            passer.wait = w * step;
            (!overlaps_any(&passer, &out)).then_some(passer.wait)
        });
        if let Some(w) = wait {
            passer.wait = w;
            out.push(passer);
        }
    }
    Ok(out)
}

/// Up to `cap` orders of `items` (their permutations, in lexicographic order of positions)
/// appended to `out`.
fn permutations(items: &[usize], prefix: &mut Vec<usize>, out: &mut Vec<Vec<usize>>, cap: usize) {
    if out.len() >= cap {
        return;
    }
    if prefix.len() == items.len() {
        out.push(prefix.clone());
        return;
    }
    for &i in items {
        if !prefix.contains(&i) {
            prefix.push(i);
            permutations(items, prefix, out, cap);
            prefix.pop();
        }
    }
}

/// Other places a guest blocked where it waits tries, in its own room.
const RESTARTS: usize = 6;

/// How far (metres, across the floor) another's walk keeps from each joint of a seated
/// guest: a walking body reaches about this far from its torso's line.
const SEATED_CLEARANCE: f32 = 0.35;

/// `region` without the voxels within [`SEATED_CLEARANCE`] across the floor of a joint of
/// the `seated` bodies (up to a metre above or below it), unless that would take `keep`'s
/// voxels; `None` then.
fn without(
    region: &AccessibleRegion,
    seated: &[Pose],
    keep: &[Point3m],
) -> Option<AccessibleRegion> {
    let joints: Vec<Point3<f32>> = seated
        .iter()
        .flat_map(|p| Joint::ALL.iter().map(|&j| p.joint(j)))
        .collect();
    let mut obstacles = region.grid.obstacles().to_vec();
    for &i in region.free_indices() {
        let c = region.frame.center(region.grid.cell(i));
        obstacles[i] |= joints
            .iter()
            .any(|j| (c.x - j.x).hypot(c.y - j.y) < SEATED_CLEARANCE && (c.z - j.z).abs() < 1.0);
    }
    let grid = envfield_grid::Grid3::from_obstacles(region.frame.shape, obstacles).ok()?;
    let around = AccessibleRegion::new(region.frame, grid, region.samples.clone(), 1).ok()?;
    keep.iter().all(|&p| around.contains(p)).then_some(around)
}

/// Plans a party in `room` (a generated room or an apartment's home, whose furniture is
/// known), `rooms` its rooms' interiors (`[x_min, y_min, x_max, y_max]`, empty for one room):
/// [`PartyConfig::people`] guests, each from a start in another room to a different chair of
/// the dining table (the table with the most chairs around it) or, where the region's
/// sit-downs reach too few of its chairs, to a different seat of the room with the most
/// ([`Gathering::Room`]), as the module describes.
/// Guests whose walk does not reach their chair's sit-down, or who find no wait within
/// [`PartyConfig::max_wait`], are not seated, and their bodies leave the party.
///
/// # Errors
/// [`RoomsError::InvalidInput`] when the room has no table with chairs the region's
/// sit-downs reach, or fewer standing places than guests; errors of the planner and the
/// pose checks.
pub fn plan_party(
    scene: &Scene,
    region: &AccessibleRegion,
    room: &Room,
    rooms: &[[f32; 4]],
    config: &PartyConfig,
) -> Result<Party> {
    let t0 = Instant::now();
    let chairs = dining_chairs(room);
    let at_table = chair_sit_downs(scene, room, region, &chairs)?;
    let room_of = |p: Point3m| {
        rooms
            .iter()
            .position(|r| p[0] >= r[0] && p[0] <= r[2] && p[1] >= r[1] && p[1] <= r[3])
    };
    // The table's chairs when the region's sit-downs reach a chair for everyone; the seats of
    // the room with the most otherwise.
    let (sits, at) = if at_table.len() >= config.people {
        (at_table, Gathering::Table)
    } else {
        (room_seats(room, region, &room_of)?, Gathering::Room)
    };
    if sits.is_empty() {
        return Err(RoomsError::InvalidInput(format!(
            "no seat is reached by the region's sit-downs ({} chairs at the dining table)",
            chairs.len()
        )));
    }
    let n = config.people.min(sits.len());
    let table_room = room_of(sits[0].seated);
    let places = standing_places(scene, region);
    let starts = starts(&places, rooms, table_room, n, config.seed);
    if starts.len() < n {
        return Err(RoomsError::InvalidInput(format!(
            "{} standing places 1.5 m apart for {n} guests",
            starts.len()
        )));
    }
    let gait = walk(&WalkConfig::default(), config.seed)?;
    let check = AffordanceConfig::default();
    let mut plans: Vec<SitDown> = Vec::with_capacity(n);
    // Each guest's motion alone: the walk to the sit-down's start, then the sit-down.
    let mut guests = Vec::with_capacity(n);
    for (k, &(start, start_room)) in starts.iter().enumerate() {
        let (motion, reached) = motion(scene, region, start, &sits[k], &gait)?;
        let reports = check_sequence(scene, &motion, &check)?;
        let valid = reports.iter().filter(|r| r.valid()).count();
        guests.push(Guest {
            start,
            room: start_room,
            seat: sits[k].seated,
            valid_pct: 100.0 * valid as f64 / reports.len().max(1) as f64,
            motion,
            wait: 0,
            seated: reached,
        });
        plans.push(sits[k]);
    }
    // The people walking through, first, each waiting for those before.
    let avoid: Vec<Point3m> = starts
        .iter()
        .map(|s| s.0)
        .chain(plans.iter().map(|p| p.start))
        .collect();
    let passers = walk_through(
        scene, region, &places, &avoid, rooms, table_room, &gait, config,
    )?;
    // Then the guests one after another, each waiting until it meets nobody placed. The
    // order: of every order of the guests (up to 24 of them, those of the longest walks
    // first first), the one seating the most with waits alone, then the soonest done.
    let wait_for = |guest: &mut Guest, placed: &[Guest]| {
        let step = config.wait_step.max(1);
        (0..=config.max_wait / step).find_map(|w| {
            guest.wait = w * step;
            (!overlaps_any(guest, placed)).then_some(guest.wait)
        })
    };
    let waits_only = |order: &[usize]| {
        let mut placed: Vec<Guest> = passers.clone();
        for &k in order {
            let mut guest = guests[k].clone();
            if guest.seated && wait_for(&mut guest, &placed).is_some() {
                placed.push(guest);
            }
        }
        let end = placed.iter().map(Guest::end).max().unwrap_or(0);
        (placed.len() - passers.len(), std::cmp::Reverse(end))
    };
    let mut first: Vec<usize> = (0..guests.len()).collect();
    first.sort_by_key(|&k| std::cmp::Reverse(guests[k].motion.frames.len()));
    let mut orders = vec![first.clone()];
    permutations(&first, &mut Vec::new(), &mut orders, 24);
    let order = orders
        .iter()
        .max_by_key(|o| waits_only(o))
        .cloned()
        .unwrap_or(first);
    let mut placed: Vec<Guest> = passers.clone();
    let mut left: Vec<Guest> = Vec::new();
    let mut rng = SplitMix64::new(config.seed ^ 0x5EA7);
    for k in order {
        let mut guest = guests[k].clone();
        let mut found = if guest.seated {
            wait_for(&mut guest, &placed)
        } else {
            None
        };
        if found.is_none() && placed.len() > passers.len() {
            // Blocked for good (by someone seated on the way, say): walk again around the
            // seated, then wait.
            let seated: Vec<Pose> = placed[passers.len()..]
                .iter()
                .map(|g| g.motion.frames[g.motion.frames.len() - 1])
                .collect();
            if let Some(around) = without(region, &seated, &[guest.start, plans[k].start]) {
                let (motion, reached) = motion(scene, &around, guest.start, &plans[k], &gait)?;
                if reached {
                    let reports = check_sequence(scene, &motion, &check)?;
                    let valid = reports.iter().filter(|r| r.valid()).count();
                    guest.valid_pct = 100.0 * valid as f64 / reports.len().max(1) as f64;
                    guest.motion = motion;
                    guest.seated = true;
                    found = wait_for(&mut guest, &placed);
                }
            }
        }
        // Still blocked: someone's way passes where this guest waits. Wait elsewhere in the
        // same room (up to RESTARTS other places, drawn).
        let mut tries = 0;
        while found.is_none() && tries < RESTARTS {
            tries += 1;
            let taken: Vec<Point3m> = guests
                .iter()
                .chain(&passers)
                .flat_map(|g| [g.start, g.seat])
                .collect();
            let elsewhere: Vec<&Point3m> = places
                .iter()
                .filter(|p| room_of(**p) == guest.room)
                .filter(|p| {
                    taken
                        .iter()
                        .all(|q| (Point3::from(**p) - Point3::from(*q)).norm() >= 1.5)
                })
                .collect();
            if elsewhere.is_empty() {
                break;
            }
            let start = *elsewhere[rng.below(elsewhere.len())];
            let (motion, reached) = motion(scene, region, start, &plans[k], &gait)?;
            if !reached {
                continue;
            }
            let mut moved = Guest {
                start,
                motion,
                seated: true,
                ..guest.clone()
            };
            if let Some(wait) = wait_for(&mut moved, &placed) {
                let reports = check_sequence(scene, &moved.motion, &check)?;
                let valid = reports.iter().filter(|r| r.valid()).count();
                moved.valid_pct = 100.0 * valid as f64 / reports.len().max(1) as f64;
                guest = moved;
                found = Some(wait);
            }
        }
        match found {
            Some(wait) => {
                guest.wait = wait;
                placed.push(guest);
            }
            None => {
                guest.seated = false;
                guest.wait = 0;
                left.push(guest);
            }
        }
    }
    let frames = placed.iter().map(Guest::end).max().unwrap_or(0);
    // The measure, recomputed over the whole party: every pair, every frame.
    let mut overlaps = 0;
    for i in 0..placed.len() {
        for j in i + 1..placed.len() {
            overlaps += (0..frames)
                .filter(|&t| bodies_overlap(placed[i].pose_at(t), placed[j].pose_at(t)))
                .count();
        }
    }
    let passers: Vec<Guest> = placed.drain(..passers.len()).collect();
    placed.extend(left);
    Ok(Party {
        guests: placed,
        passers,
        chairs: sits.len(),
        at,
        frames,
        overlaps,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 x 4 m room: a floor, a table (1.2 x 0.8 m top at 0.75 m on a central block) and
    /// two chairs (0.45 x 0.45 x 0.9 m blocks) tucked 0.1 m under its long sides, facing it;
    /// the north chair with a wall `wall` metres behind its back (none when `None`).
    fn tucked_room(wall: Option<f32>) -> Room {
        use envfield_scene::nalgebra::Isometry3;
        use envfield_scene::{Furniture, Primitive, SceneObject};
        let mut scene = Scene::new();
        let mut add = |name: &str, kind: ObjectKind, half: [f32; 3], at: [f32; 3]| {
            let object = SceneObject::new(name, kind)
                .with(
                    Primitive::cuboid([2.0 * half[0], 2.0 * half[1], 2.0 * half[2]]),
                    Isometry3::translation(at[0], at[1], at[2]),
                )
                .expect("box");
            scene.add(object).expect("add")
        };
        add(
            "floor",
            ObjectKind::Floor,
            [2.0, 2.0, 0.05],
            [2.0, 2.0, -0.05],
        );
        let table = add(
            "table",
            ObjectKind::Table,
            [0.6, 0.4, 0.375],
            [2.0, 2.0, 0.375],
        );
        // The chairs' centres: 0.4 + 0.225 - 0.1 from the table's.
        let off = 0.4 + 0.225 - 0.1;
        let south = add(
            "south",
            ObjectKind::Chair,
            [0.225, 0.225, 0.45],
            [2.0, 2.0 - off, 0.45],
        );
        let north = add(
            "north",
            ObjectKind::Chair,
            [0.225, 0.225, 0.45],
            [2.0, 2.0 + off, 0.45],
        );
        if let Some(gap) = wall {
            let y = 2.0 + off + 0.225 + gap + 0.05;
            add("wall", ObjectKind::Wall, [2.0, 0.05, 1.25], [2.0, y, 1.25]);
        }
        let piece = |kind, object, center: [f32; 2], yaw: f32, size: [f32; 3]| Furniture {
            kind,
            object,
            center,
            yaw,
            size,
            seat_height: (kind == ObjectKind::Chair).then_some(0.45),
            seat_forward: None,
        };
        Room {
            scene,
            size: [4.0, 4.0],
            furniture: vec![
                piece(ObjectKind::Table, table, [2.0, 2.0], 0.0, [1.2, 0.8, 0.75]),
                // The south chair faces +y (yaw 0), the north one -y.
                piece(
                    ObjectKind::Chair,
                    south,
                    [2.0, 2.0 - off],
                    0.0,
                    [0.45, 0.45, 0.9],
                ),
                piece(
                    ObjectKind::Chair,
                    north,
                    [2.0, 2.0 + off],
                    std::f32::consts::PI,
                    [0.45, 0.45, 0.9],
                ),
            ],
        }
    }

    #[test]
    fn a_laid_table_has_its_chairs_pulled_out_as_far_as_the_room_allows() {
        let room = tucked_room(None);
        let chairs = dining_chairs(&room);
        assert_eq!(chairs, vec![1, 2]);
        let (laid, moved) = lay_table(&room, &chairs).expect("laid");
        // Tucked 0.1 m under: pulled PULL_ROOM + 0.1 back (to within the 5 cm steps' rounding).
        for (k, &m) in moved.iter().enumerate() {
            assert!((m - (PULL_ROOM + 0.1)).abs() < 1e-4, "chair {k}: {m}");
        }
        let south = &laid.furniture[1];
        assert!((south.center[1] - (2.0 - 0.525 - PULL_ROOM - 0.1)).abs() < 1e-4);
        // The scene moved with the list: the chair's old place is air, its new one solid.
        let at = |y: f32| {
            laid.scene
                .signed_distance(&Point3::new(2.0, y, 0.45))
                .unwrap()
        };
        assert!(at(2.0 - 0.525 - 0.2) > 0.0);
        assert!(at(south.center[1]) < 0.0);
        // A wall 0.2 m behind the north chair: it goes back 0.15 m (the 5 cm steps, clear of
        // the wall by 1 cm), the south chair all the way; nothing else moves.
        let (laid, moved) = lay_table(&tucked_room(Some(0.2)), &chairs).expect("laid");
        assert!((moved[0] - (PULL_ROOM + 0.1)).abs() < 1e-4, "{moved:?}");
        assert!(moved[1] > 0.1 && moved[1] <= 0.2 - PULL_CLEAR, "{moved:?}");
        assert_eq!(laid.furniture[0], room.furniture[0]);
        // Not a chair, or past the list: refused.
        assert!(lay_table(&room, &[0]).is_err());
        assert!(lay_table(&room, &[7]).is_err());
    }

    #[test]
    fn segments_measure_their_least_distance() {
        let p = |x: f32, y: f32, z: f32| Point3::new(x, y, z);
        // Crossing at right angles 0.3 apart in z.
        let d = segment_distance(
            (p(-1., 0., 0.), p(1., 0., 0.)),
            (p(0., -1., 0.3), p(0., 1., 0.3)),
        );
        assert!((d - 0.3).abs() < 1e-6, "{d}");
        // Parallel, offset, overlapping in x.
        let d = segment_distance(
            (p(0., 0., 0.), p(1., 0., 0.)),
            (p(0.5, 0.2, 0.), p(2., 0.2, 0.)),
        );
        assert!((d - 0.2).abs() < 1e-6, "{d}");
        // End to end along a line, 0.5 apart.
        let d = segment_distance(
            (p(0., 0., 0.), p(1., 0., 0.)),
            (p(1.5, 0., 0.), p(2., 0., 0.)),
        );
        assert!((d - 0.5).abs() < 1e-6, "{d}");
        // A point against a segment.
        let d = segment_distance(
            (p(0.5, 0.4, 0.), p(0.5, 0.4, 0.)),
            (p(0., 0., 0.), p(1., 0., 0.)),
        );
        assert!((d - 0.4).abs() < 1e-6, "{d}");
    }

    #[test]
    fn two_bodies_in_one_place_overlap_and_a_metre_apart_do_not() {
        let gait = walk(&WalkConfig::default(), 0).unwrap();
        let a = gait.frames[0];
        assert!(bodies_overlap(&a, &a));
        let b = a.translated(&Vector3::new(0.8, 0.0, 0.0));
        assert!(!bodies_overlap(&a, &b));
        let c = a.translated(&Vector3::new(0.1, 0.0, 0.0));
        assert!(bodies_overlap(&a, &c));
    }
}
