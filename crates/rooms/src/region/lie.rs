//! The lie-downs that carry the region from the edge of a bed or sofa onto its length: a
//! sit-down onto the edge, then [`lie_down`] on the same surface, the legs coming up, the
//! torso tipping back and sliding onto it. Each sit-down the region found is tried as the
//! start of one ([`lie_down_from`]); lying places are tried as the end of one
//! ([`lie_down_to`]): the kept samples of the parts apart from the floor's, and the level tops
//! found on the scene's own columns ([`lying_places`]).

use super::bridges::{placed, sit_down_at};
use super::{RegionConfig, SitDown};
use crate::Result;
use envfield_affordance::{
    check_pose, lie_down, plausible, Joint, LieConfig, Pose, PoseSequence, Support,
};
use envfield_grid::Point3m;
use envfield_scene::nalgebra::{Point3, Rotation3, Vector3};
use envfield_scene::Scene;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// How far a lie-down slides the pelvis back from where it sat, metres, longest first (1.0 m
/// to 0.3 m, 5 cm apart): the first whose every pose holds is taken. A lie-down made to end at
/// a lying place must start seated on the edge, within a few centimetres of it on a bed
/// higher than the shank is long (the thighs slope down over the edge), so the slides are
/// close.
pub const LIE_SLIDES: [f32; 15] = [
    1.0, 0.95, 0.9, 0.85, 0.8, 0.75, 0.7, 0.65, 0.6, 0.55, 0.5, 0.45, 0.4, 0.35, 0.3,
];

/// The turns a lie-down is tried with, radians ([`LieConfig::turn`]): straight back from the
/// edge (a bed's foot end), or a quarter turn either way, the legs swung up onto a bed or sofa
/// sat on from its side (a bed against a wall, or with a footboard; a sofa, along its seat).
pub const LIE_TURNS: [f32; 3] = [
    0.0,
    std::f32::consts::FRAC_PI_2,
    -std::f32::consts::FRAC_PI_2,
];

/// The share of a lie-down's duration in which the legs come up onto the bed before the body
/// slides back ([`LieConfig::lift`]): with both together the shanks, still hanging as the
/// knees come over the edge, sweep through the bed's side.
pub const LIE_LIFT: f32 = 0.5;

/// How far beside the spine the surface a body lies on must reach at its pelvis and its chest,
/// metres (rays straight down from there meet it within the contact tolerance): a bed has room
/// beside a lying body; the top of a sideboard or a shelf, 0.3-0.5 m deep, does not. Set from
/// the body (shoulders about 0.4 m wide, and a hand's breadth beside them), not from any scene.
pub const LIE_ROOM: f32 = 0.3;

/// The joints of the legs that must lie on the surface too when the body lies: a bed holds
/// the whole body, a table or cabinet shorter than the body leaves the legs in the air.
const LYING_LEGS: [Joint; 4] = [
    Joint::LeftKnee,
    Joint::RightKnee,
    Joint::LeftAnkle,
    Joint::RightAnkle,
];

/// A lie-down the region found ([`AccessibleRegion::lie_downs`](super::AccessibleRegion::lie_downs)):
/// a sit-down onto the edge of a bed or sofa, then [`lie_down`] from that seated pose on the
/// same surface, the pelvis sliding `slide` metres back and the body turning by `turn`, every
/// pose valid and plausible where it was found, the last on a surface that holds the whole
/// body ([`LIE_ROOM`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LieDown {
    /// The sit-down onto the edge it starts from (standing beside the bed or sofa).
    pub sit: SitDown,
    /// How far the pelvis slides back as the body lies down, metres.
    pub slide: f32,
    /// How far the body turns as its legs come up, radians ([`LieConfig::turn`]): 0 lies
    /// straight back from the edge, a quarter turn lies along the bed or sofa sat on from its
    /// side.
    #[serde(default)]
    pub turn: f32,
    /// The torso where it ends, lying on the back, metres.
    pub lying: Point3m,
}

impl LieDown {
    /// From seated to lying: [`lie_down`] placed where its sit-down ends.
    ///
    /// # Errors
    /// As [`lie_down`] and [`SitDown::sequence`].
    pub fn lying_down(&self) -> Result<PoseSequence> {
        lying_part(&self.sit, self.slide, self.turn)
    }

    /// Its poses, placed: the sit-down from standing, then lying down (the seated frame once),
    /// each frame with its support.
    ///
    /// # Errors
    /// As [`LieDown::lying_down`].
    pub fn sequence(&self) -> Result<PoseSequence> {
        let sit = self.sit.sequence()?;
        let lie = self.lying_down()?;
        let mut frames = sit.frames;
        let mut supports = sit.supports;
        frames.extend(lie.frames.into_iter().skip(1));
        supports.extend(lie.supports.into_iter().skip(1));
        Ok(PoseSequence::new(lie.fps, lie.activity, frames, supports)?)
    }
}

/// [`lie_down`] onto `sit`'s seat, sliding `slide` metres and turning by `turn`, turned and
/// moved as `sit`'s poses are so that its seated first frame is `sit`'s last.
fn lying_part(sit: &SitDown, slide: f32, turn: f32) -> Result<PoseSequence> {
    let seq = lie_down(&LieConfig {
        seat_height: sit.seat_height,
        slide,
        turn,
        lift: LIE_LIFT,
        ..LieConfig::default()
    })?;
    placed(seq, 0, sit.yaw, sit.seated)
}

/// The lie-down that follows `sit`: the longest slide of [`LIE_SLIDES`] whose every pose is
/// valid and [`plausible`] (a frame still tipping back may rest its back on the surface, as a
/// lying one does) and whose last lies on a surface that holds the whole body (its legs, and
/// [`LIE_ROOM`] beside its spine); `None` where none holds (a chair: nothing bears the head; a
/// sideboard: too narrow).
///
/// # Errors
/// Errors of the scene's queries and of [`lie_down`].
pub(crate) fn lie_down_from(
    scene: &Scene,
    sit: &SitDown,
    ends: &LyingEnds,
    config: &RegionConfig,
) -> Result<Option<LieDown>> {
    let seated = Point3::from(sit.seated);
    let turn_by = |a: f32| Rotation3::from_axis_angle(&Vector3::z_axis(), a);
    for &(turn, slide, moved) in &ends.ends {
        // The lying pose alone first (rays and distances): most seats hold no lying body.
        let lying = seated + turn_by(sit.yaw) * moved;
        if !ends.holds(scene, sit.yaw + turn, lying, config)? {
            continue;
        }
        if let Some(lying) = lies(scene, sit, slide, turn, config)? {
            return Ok(Some(LieDown {
                sit: *sit,
                slide,
                turn,
                lying,
            }));
        }
    }
    Ok(None)
}

/// Where the torso ends lying, when every pose of lying down from `sit`, sliding `slide` and
/// turning `turn`, is valid and [`plausible`] (a frame still tipping back may rest its back on
/// the surface, as a lying one does) and the last lies on a surface that holds the whole body;
/// `None` otherwise. Lying first, so that on a chair or a stool, where nothing bears the head,
/// the try ends at once.
fn lies(
    scene: &Scene,
    sit: &SitDown,
    slide: f32,
    turn: f32,
    config: &RegionConfig,
) -> Result<Option<Point3m>> {
    let affordance = &config.filter.affordance;
    let seq = lying_part(sit, slide, turn)?;
    let n = seq.frames.len();
    if !whole_body_rests(scene, &seq.frames[n - 1], affordance.contact_tolerance)? {
        return Ok(None);
    }
    for i in std::iter::once(n - 1).chain(1..n - 1) {
        let (pose, support) = (&seq.frames[i], seq.supports[i]);
        let rests = |s| plausible(scene, pose, s, affordance);
        if !check_pose(scene, pose, support, affordance)?.valid()
            || !(rests(support)? || rests(Support::Lying)?)
        {
            return Ok(None);
        }
    }
    Ok(Some(seq.frames[n - 1].torso().into()))
}

/// Whether a lying `pose` lies on a surface that holds the whole body: one within `tolerance`
/// (plus 5 cm) straight below each joint of [`LYING_LEGS`], and below the points [`LIE_ROOM`]
/// to either side of the pelvis and the chest.
fn whole_body_rests(scene: &Scene, pose: &Pose, tolerance: f32) -> Result<bool> {
    let reach = tolerance + 0.05;
    let down = -Vector3::z();
    let meets =
        |p: Point3<f32>| -> Result<bool> { Ok(scene.cast_ray(&p, &down, reach)?.is_some()) };
    for j in LYING_LEGS {
        if !meets(pose.joint(j))? {
            return Ok(false);
        }
    }
    let along = pose.joint(Joint::Head) - pose.joint(Joint::Pelvis);
    let side = Vector3::new(-along.y, along.x, 0.0);
    let Some(side) = side.try_normalize(1e-6) else {
        return Ok(false);
    };
    for j in [Joint::Pelvis, Joint::Spine3] {
        for sign in [-1.0, 1.0] {
            if !meets(pose.joint(j) + side * (sign * LIE_ROOM))? {
                return Ok(false);
            }
        }
    }
    Ok(true)
}

/// The lie-downs from `sit_downs` ([`lie_down_from`] on each, in parallel), in their order.
///
/// # Errors
/// As [`lie_down_from`].
pub(super) fn lie_downs_from(
    scene: &Scene,
    sit_downs: &[SitDown],
    config: &RegionConfig,
) -> Result<Vec<LieDown>> {
    let ends = LyingEnds::new()?;
    let found = sit_downs
        .par_iter()
        .map(|s| lie_down_from(scene, s, &ends, config))
        .collect::<Result<Vec<_>>>()?;
    Ok(found.into_iter().flatten().collect())
}

/// A lie-down that ends lying with the torso at `p`: at each of the config's headings, the
/// lying pose at `p` first (a surface that holds the whole body, the pose valid: rays and
/// distances only), then at each slide of [`LIE_SLIDES`] the sit-down onto the edge it would
/// start from ([`sit_down_at`], its standing start accepted by `starts`) and its lying part
/// checked as [`lie_down_from`] checks it; the first that holds. A bed's lying set joins the
/// floor's this way where no sit-down onto its edge was found.
///
/// # Errors
/// Errors of the scene's queries, of [`lie_down`] and of [`sit_down`](envfield_affordance::sit_down).
pub(super) fn lie_down_to(
    scene: &Scene,
    p: Point3m,
    ends: &LyingEnds,
    config: &RegionConfig,
    starts: &(dyn Fn(&Point3<f32>) -> bool + Sync),
) -> Result<Option<LieDown>> {
    for k in 0..config.filter.yaws {
        let yaw = k as f32 * std::f32::consts::TAU / config.filter.yaws as f32;
        if !ends.holds(scene, yaw, Point3::from(p), config)? {
            continue;
        }
        for &(turn, slide, moved) in &ends.ends {
            // The sit-down's heading: the lying pose's less the turn.
            let sit_yaw = (yaw - turn).rem_euclid(std::f32::consts::TAU);
            let seated =
                Point3::from(p) - Rotation3::from_axis_angle(&Vector3::z_axis(), sit_yaw) * moved;
            let Some(sit) = sit_down_at(scene, seated.into(), sit_yaw, config, starts)? else {
                continue;
            };
            if let Some(lying) = lies(scene, &sit, slide, turn, config)? {
                return Ok(Some(LieDown {
                    sit,
                    slide,
                    turn,
                    lying,
                }));
            }
        }
    }
    Ok(None)
}

/// For each slide of [`LIE_SLIDES`], where a lie-down's torso ends relative to where it sat
/// (before turning), and the lying pose relative to its torso: the same for every surface
/// height, made once for all of [`lie_down_to`]'s tries.
pub(super) struct LyingEnds {
    /// Each turn and slide, and where the torso ends relative to where it sat.
    ends: Vec<(f32, f32, Vector3<f32>)>,
    /// The lying pose (no turn) relative to its torso.
    lying: Pose,
}

impl LyingEnds {
    /// The ends of [`lie_down`] at each turn of [`LIE_TURNS`] and slide of [`LIE_SLIDES`].
    ///
    /// # Errors
    /// As [`lie_down`].
    pub(super) fn new() -> Result<Self> {
        let mut ends = Vec::with_capacity(LIE_TURNS.len() * LIE_SLIDES.len());
        let mut lying = None;
        for turn in LIE_TURNS {
            for slide in LIE_SLIDES {
                let local = lie_down(&LieConfig {
                    slide,
                    turn,
                    lift: LIE_LIFT,
                    ..LieConfig::default()
                })?;
                let (Some(first), Some(last)) = (local.frames.first(), local.frames.last()) else {
                    continue;
                };
                ends.push((turn, slide, last.torso() - first.torso()));
                if turn == 0.0 {
                    lying.get_or_insert(last.translated(&-last.torso().coords));
                }
            }
        }
        let lying = lying
            .ok_or_else(|| crate::RoomsError::InvalidInput("a lie-down without frames".into()))?;
        Ok(Self { ends, lying })
    }

    /// Whether the lying pose turned to `heading` with its torso at `torso` holds: on a
    /// surface that holds the whole body, supported and collision-free.
    fn holds(
        &self,
        scene: &Scene,
        heading: f32,
        torso: Point3<f32>,
        config: &RegionConfig,
    ) -> Result<bool> {
        let affordance = &config.filter.affordance;
        let lying = self
            .lying
            .rotated_about_z(heading, &Point3::origin())
            .translated(&torso.coords);
        Ok(
            whole_body_rests(scene, &lying, affordance.contact_tolerance)?
                && check_pose(scene, &lying, Support::Lying, affordance)?.valid(),
        )
    }
}

/// The spacing of the columns [`lying_places`] looks down, metres.
pub const LIE_SPACING: f32 = 0.2;

/// [`lying_places`] looks over scenes of at most this many columns (1 600 m² at
/// [`LIE_SPACING`], a house's floor): a larger scene is a game level, whose region stands only
/// ([`AccessibleRegion::standing`](crate::AccessibleRegion::standing)).
pub const LIE_MAX_COLUMNS: usize = 40_000;

/// The heights a surface a body lies on stands above the floor, metres: a bed's or a sofa's
/// top stands 0.3-0.7 m high; a table's, 0.72 m or more, is left out. From the furniture
/// standards beds and tables are made to, not from any scene.
pub const LIE_HEIGHTS: (f32, f32) = (0.3, 0.7);

/// Where a body might lie in `scene`, found from its surfaces as a game level's standing
/// places are ([`standing_torsos`](crate::standing_torsos)): on columns [`LIE_SPACING`] apart,
/// the top surface of each column, when it is level within 10 degrees and stands
/// [`LIE_HEIGHTS`] above the next level surface at least 0.3 m below it (the floor, or a bed
/// frame's underside), with a lying torso's height added. The drawn samples seldom lie on a bed higher than the generated rooms' (0.5 m),
/// which the VAE learned on; these are tried as lie-downs' ends
/// ([`lie_down_to`]), never kept as samples themselves.
///
/// # Errors
/// Errors of the scene's queries; [`RoomsError::InvalidInput`](crate::RoomsError::InvalidInput)
/// for an empty scene.
pub(super) fn lying_places(scene: &Scene) -> Result<Vec<Point3m>> {
    let aabb = scene
        .aabb()
        .ok_or_else(|| crate::RoomsError::InvalidInput("the scene is empty".into()))?;
    let (lo, hi) = (aabb.mins, aabb.maxs);
    let count = |a: usize| ((hi[a] - lo[a]) / LIE_SPACING).ceil().max(1.0) as usize;
    let (nx, ny) = (count(0), count(1));
    if nx.saturating_mul(ny) > LIE_MAX_COLUMNS {
        return Ok(Vec::new());
    }
    // The lying torso's height over the surface it lies on.
    let lie = lie_down(&LieConfig::default())?;
    let above = lie.frames.last().map_or(0.0, |f| f.torso().z) - LieConfig::default().seat_height;
    let level = 10f32.to_radians().cos();
    let (top, range) = (hi.z + 0.1, hi.z - lo.z + 0.2);
    let down = -Vector3::z();
    let columns: Vec<Option<Point3m>> = (0..nx * ny)
        .into_par_iter()
        .map(|k| -> Result<Option<Point3m>> {
            let x = lo.x + ((k / ny) as f32 + 0.5) * LIE_SPACING;
            let y = lo.y + ((k % ny) as f32 + 0.5) * LIE_SPACING;
            let hits = scene.surfaces_along(&Point3::new(x, y, top), &down, range, 64)?;
            let flat = |h: &&envfield_scene::RayHit| h.normal.z.abs() >= level;
            let Some(first) = hits.first().filter(flat) else {
                return Ok(None);
            };
            // The floor: the highest level surface at least the lowest bed's height below
            // (a bed frame's underside, or the floor's top; not the floor slab's underside).
            let below = first.point.z - LIE_HEIGHTS.0;
            let Some(floor) = hits.iter().filter(flat).find(|h| h.point.z <= below) else {
                return Ok(None);
            };
            let height = first.point.z - floor.point.z;
            let holds = (LIE_HEIGHTS.0..=LIE_HEIGHTS.1).contains(&height);
            Ok(holds.then(|| [x, y, first.point.z + above]))
        })
        .collect::<Result<_>>()?;
    Ok(columns.into_iter().flatten().collect())
}
