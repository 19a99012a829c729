//! The sit-downs that join a seat's voxels to the floor's: a seated torso lies about half a
//! metre below a standing one, so a seat's set of voxels does not touch the floor's.

use super::build::Links;
use super::lie::{lie_down_to, lie_downs_from, lying_places, LyingEnds};
use super::RegionConfig;
use crate::Result;
use envfield_affordance::{
    check_pose, plausible, sit_down, Joint, PoseSequence, SitConfig, Support,
};
use envfield_grid::Grid3;
use envfield_grid::Point3m;
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::{Scene, VoxelFrame};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The seat heights a sit-down is tried onto, metres ([`sit_down`]'s range).
const SEAT_RANGE: (f32, f32) = (0.3, 0.75);

/// The most samples of one connected set that [`links`] tries (spread evenly over
/// the set's samples).
const BRIDGE_TRIES: usize = 24;

/// The most samples of one connected set that [`links`] tries as a lie-down's end (spread
/// evenly over all of the set's samples): a lying end holds at few headings and slides, and
/// its tries end on a few rays.
const LIE_TRIES: usize = 96;

/// [`links`] tries samples among this many times [`BRIDGE_TRIES`] of a set's
/// nearest to the largest set.
const BRIDGE_NEAREST: usize = 4;

/// Each voxel's distance in 26-connected steps from the voxels labelled `from` (all of
/// `grid`'s voxels, free or not; `u32::MAX` where none is labelled so).
fn steps_from(grid: &Grid3, labels: &[usize], from: usize) -> Vec<u32> {
    let mut steps = vec![u32::MAX; labels.len()];
    let mut queue = std::collections::VecDeque::new();
    for (i, &l) in labels.iter().enumerate() {
        if l == from {
            steps[i] = 0;
            queue.push_back(i);
        }
    }
    while let Some(i) = queue.pop_front() {
        let next = steps[i] + 1;
        grid.around(i, |j| {
            if steps[j] == u32::MAX {
                steps[j] = next;
                queue.push_back(j);
            }
        });
    }
    steps
}

/// The sit-downs and lie-downs that join sets of voxels apart from the largest to it: a
/// seated torso's voxels lie about half a metre below a standing one's, so a seat's set does
/// not touch the floor's, nor does a bed's. For each of up to [`BRIDGE_TRIES`] kept samples
/// of every other set (spread over those nearest the largest set), a sit-down is placed to
/// end seated there ([`sit_down_to`]), and for each of up to [`LIE_TRIES`] spread over the
/// whole set a lie-down to end lying there ([`lie_down_to`](super::lie::lie_down_to)); the first of
/// each whose standing start lies in or beside the largest set and whose every pose is valid
/// and [`plausible`] joins its set; the places [`lying_places`] finds on the scene's surfaces
/// are tried as lie-downs' ends too.
/// Then every sit-down found is tried as the start of a lie-down
/// ([`lie_down_from`](super::lie::lie_down_from)). A set none reaches (a table top, specks)
/// stays apart and is dropped with the rest.
pub(super) fn links(
    scene: &Scene,
    frame: &VoxelFrame,
    all: &Grid3,
    kept: &[Point3m],
    config: &RegionConfig,
) -> Result<Links> {
    let none = Links {
        sit_downs: Vec::new(),
        lie_downs: Vec::new(),
        lie_downs_ms: 0.0,
    };
    let components = all.free_components();
    let Some(largest) = components.largest() else {
        return Ok(none);
    };
    // Each other set's samples (with their voxels), nearest the largest set first (in voxel
    // steps): a bed's edge, not its middle, is where a sit-down from the floor can end.
    let mut by_set = std::collections::BTreeMap::<usize, Vec<(usize, Point3m)>>::new();
    for p in kept {
        if let Some(i) = frame.cell_of(&Point3::from(*p)).and_then(|c| all.index(c)) {
            let l = components.labels[i];
            if l != largest && l != usize::MAX {
                by_set.entry(l).or_default().push((i, *p));
            }
        }
    }
    if by_set.is_empty() {
        return Ok(none);
    }
    let steps = steps_from(all, &components.labels, largest);
    // Whether `p`'s voxel or one of its 26 neighbours is in the largest set.
    let beside_largest = |p: &Point3<f32>| {
        frame
            .cell_of(p)
            .and_then(|c| all.index(c))
            .is_some_and(|i| steps[i] <= 1)
    };
    // A sit-down ends at a set's edge; a lie-down ends inside it, a body's length in: its
    // tries are spread over the whole set.
    let (mut tries, mut lie_tries) = (Vec::new(), Vec::new());
    for mut v in by_set.into_values() {
        let every = v.len().div_ceil(LIE_TRIES);
        lie_tries.extend(v.iter().step_by(every).map(|&(_, p)| p));
        v.sort_by_key(|&(i, _)| steps[i]);
        v.truncate(BRIDGE_NEAREST * BRIDGE_TRIES);
        let every = v.len().div_ceil(BRIDGE_TRIES);
        tries.extend(v.into_iter().step_by(every).map(|(_, p)| p));
    }
    let sit_downs: Vec<SitDown> = tries
        .par_iter()
        .map(|&s| sit_down_to(scene, s, config, &beside_largest))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect();
    let start = std::time::Instant::now();
    let mut lie_downs = lie_downs_from(scene, &sit_downs, config)?;
    lie_tries.extend(lying_places(scene)?);
    let ends = LyingEnds::new()?;
    lie_downs.extend(
        lie_tries
            .par_iter()
            .map(|&s| lie_down_to(scene, s, &ends, config, &beside_largest))
            .collect::<Result<Vec<_>>>()?
            .into_iter()
            .flatten(),
    );
    Ok(Links {
        sit_downs,
        lie_downs,
        lie_downs_ms: start.elapsed().as_secs_f64() * 1e3,
    })
}

/// A sit-down that ends seated with the torso at `s`: at each of the config's headings
/// ([`sit_down_at`]), the first that holds.
///
/// # Errors
/// Errors of the scene's queries and of [`sit_down`].
pub(crate) fn sit_down_to(
    scene: &Scene,
    s: Point3m,
    config: &RegionConfig,
    starts: &(dyn Fn(&Point3<f32>) -> bool + Sync),
) -> Result<Option<SitDown>> {
    for k in 0..config.filter.yaws {
        let yaw = k as f32 * std::f32::consts::TAU / config.filter.yaws as f32;
        if let Some(sit) = sit_down_at(scene, s, yaw, config, starts)? {
            return Ok(Some(sit));
        }
    }
    Ok(None)
}

/// Where a seated body's torso is above its seat and its feet are from its torso, from one
/// sit-down; made once.
static SEATED: std::sync::OnceLock<Option<(f32, Vector3<f32>)>> = std::sync::OnceLock::new();

/// See [`SEATED`] (`None` only if the default sit-down could not be made).
fn seated_body() -> Option<(f32, Vector3<f32>)> {
    let probe = sit_down(&SitConfig::default()).ok()?;
    let seated = *probe.frames.last()?;
    let torso_above_seat = seated.torso().z - SitConfig::default().seat_height;
    let feet = (seated.joint(Joint::LeftAnkle).coords + seated.joint(Joint::RightAnkle).coords)
        / 2.0
        - seated.torso().coords;
    Some((torso_above_seat, feet))
}

/// A sit-down that ends seated with the torso at `s`, turned by `yaw`: onto a seat as high
/// above the surface under its feet as `s` makes it (0.3-0.75 m), when its standing start
/// `starts` accepts and its every pose is valid and [`plausible`] (a frame still standing may
/// rest its thighs on the seat it nears, as a seated one does).
///
/// # Errors
/// Errors of the scene's queries and of [`sit_down`].
pub(super) fn sit_down_at(
    scene: &Scene,
    s: Point3m,
    yaw: f32,
    config: &RegionConfig,
    starts: &(dyn Fn(&Point3<f32>) -> bool + Sync),
) -> Result<Option<SitDown>> {
    let Some((torso_above_seat, feet)) = *SEATED.get_or_init(seated_body) else {
        return Ok(None);
    };
    let at = Vector3::from(s);
    // The floor under the feet sets the seat's height: the sit-down ends with the torso at
    // `s` and the soles on that floor.
    let turn = envfield_scene::nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
    let foot = Point3::from(at + turn * Vector3::new(feet.x, feet.y, 0.0));
    let Some(floor) = scene.cast_ray(&foot, &-Vector3::z(), SEAT_RANGE.1 + 0.5)? else {
        return Ok(None);
    };
    let seat = s[2] - torso_above_seat - floor.point.z;
    if !(SEAT_RANGE.0..=SEAT_RANGE.1).contains(&seat) {
        return Ok(None);
    }
    let sit = SitDown {
        start: [0.0; 3],
        seated: s,
        seat_height: seat,
        yaw,
    };
    let seq = sit.sequence()?;
    let Some(first) = seq.frames.first() else {
        return Ok(None);
    };
    if !starts(&first.torso()) {
        return Ok(None);
    }
    // Seated first: a heading that faces into the seat's back fails at once.
    for i in std::iter::once(seq.frames.len() - 1).chain(0..seq.frames.len() - 1) {
        let (pose, support) = (&seq.frames[i], seq.supports[i]);
        // The thighs near the seat as the hips arrive: a frame still standing may rest
        // them there, as a seated one does.
        let rests = |s| plausible(scene, pose, s, &config.filter.affordance);
        if !check_pose(scene, pose, support, &config.filter.affordance)?.valid()
            || !(rests(support)? || rests(Support::Sitting)?)
        {
            return Ok(None);
        }
    }
    Ok(Some(SitDown {
        start: first.torso().into(),
        ..sit
    }))
}

/// A sit-down the region found ([`AccessibleRegion::sit_downs`](super::AccessibleRegion::sit_downs)): [`sit_down`] onto a seat of
/// `seat_height`, turned by `yaw` about the vertical and moved so that it ends seated with
/// the torso at `seated`; every pose of it valid and plausible where it was found.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SitDown {
    /// The torso where it starts, standing, metres.
    pub start: Point3m,
    /// The torso where it ends, seated, metres.
    pub seated: Point3m,
    /// The seat's height above the surface under the feet, metres (0.3-0.75).
    pub seat_height: f32,
    /// The heading it is turned by, radians about +z.
    pub yaw: f32,
}

impl SitDown {
    /// Its poses, placed.
    ///
    /// # Errors
    /// As [`sit_down`] (a seat height outside 0.3-0.75 m); a non-finite place.
    pub fn sequence(&self) -> Result<PoseSequence> {
        let seq = sit_down(&SitConfig {
            seat_height: self.seat_height,
            ..SitConfig::default()
        })?;
        let end = seq.frames.len().saturating_sub(1);
        placed(seq, end, self.yaw, self.seated)
    }
}

/// `seq` (made at the origin) turned by `yaw` about the vertical and moved so that frame
/// `anchor`'s torso lies at `at`: a sit-down placed by where it ends seated, a lie-down by where
/// it starts seated.
///
/// # Errors
/// A non-finite place ([`PoseSequence::new`]).
pub(super) fn placed(
    seq: PoseSequence,
    anchor: usize,
    yaw: f32,
    at: Point3m,
) -> Result<PoseSequence> {
    let from = seq
        .frames
        .get(anchor)
        .map(|f| f.torso().coords)
        .unwrap_or_default();
    let to = Vector3::from(at);
    let frames = seq
        .frames
        .iter()
        .map(|p| {
            p.translated(&-from)
                .rotated_about_z(yaw, &Point3::origin())
                .translated(&to)
        })
        .collect();
    Ok(PoseSequence::new(
        seq.fps,
        seq.activity,
        frames,
        seq.supports,
    )?)
}
