//! The sit-downs that join a seat's voxels to the floor's: a seated torso lies about half a
//! metre below a standing one, so a seat's set of voxels does not touch the floor's.

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

/// The most samples of one connected set that [`sit_down_bridges`] tries (spread evenly over
/// the set's samples).
const BRIDGE_TRIES: usize = 24;

/// [`sit_down_bridges`] tries samples among this many times [`BRIDGE_TRIES`] of a set's
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

/// The sit-downs that join sets of voxels apart from the largest to it: a seated torso's
/// voxels lie about half a metre below a standing one's, so a seat's set does not touch the
/// floor's. For each of up to [`BRIDGE_TRIES`] kept samples of every other set (spread over
/// those nearest the largest set), a sit-down is placed to end seated there at each of the
/// config's headings, onto a seat as high above the surface under its feet as the sample
/// makes it (0.3-0.75 m); the first whose standing start lies in or beside the largest set
/// and whose every pose is valid and [`plausible`] (a frame still standing may rest its
/// thighs on the seat it nears, as a seated one does) joins its set. A set no sit-down
/// reaches (a table top, specks) stays apart and is dropped with the rest.
pub(super) fn sit_down_bridges(
    scene: &Scene,
    frame: &VoxelFrame,
    all: &Grid3,
    kept: &[Point3m],
    config: &RegionConfig,
) -> Result<Vec<SitDown>> {
    let components = all.free_components();
    let Some(largest) = components.largest() else {
        return Ok(Vec::new());
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
        return Ok(Vec::new());
    }
    let steps = steps_from(all, &components.labels, largest);
    // Whether `p`'s voxel or one of its 26 neighbours is in the largest set.
    let beside_largest = |p: &Point3<f32>| {
        frame
            .cell_of(p)
            .and_then(|c| all.index(c))
            .is_some_and(|i| steps[i] <= 1)
    };
    let tries: Vec<Point3m> = by_set
        .into_values()
        .flat_map(|mut v| {
            v.sort_by_key(|&(i, _)| steps[i]);
            v.truncate(BRIDGE_NEAREST * BRIDGE_TRIES);
            let every = v.len().div_ceil(BRIDGE_TRIES);
            v.into_iter().step_by(every).map(|(_, p)| p)
        })
        .collect();
    let chains = tries
        .par_iter()
        .map(|&s| sit_down_to(scene, s, config, &beside_largest))
        .collect::<Result<Vec<_>>>()?;
    Ok(chains.into_iter().flatten().collect())
}

/// A sit-down that ends seated with the torso at `s`: at each of the config's headings, onto
/// a seat as high above the surface under its feet as `s` makes it (0.3-0.75 m), the first
/// whose standing start `starts` accepts and whose every pose is valid and [`plausible`] (a
/// frame still standing may rest its thighs on the seat it nears, as a seated one does).
///
/// # Errors
/// Errors of the scene's queries and of [`sit_down`].
pub(crate) fn sit_down_to(
    scene: &Scene,
    s: Point3m,
    config: &RegionConfig,
    starts: &(dyn Fn(&Point3<f32>) -> bool + Sync),
) -> Result<Option<SitDown>> {
    // Where a seated body's torso and feet are, relative to its seat, from one sit-down.
    let probe = sit_down(&SitConfig::default())?;
    let seated = *probe.frames.last().expect("a sit-down has frames");
    let torso_above_seat = seated.torso().z - SitConfig::default().seat_height;
    let feet = (seated.joint(Joint::LeftAnkle).coords + seated.joint(Joint::RightAnkle).coords)
        / 2.0
        - seated.torso().coords;
    let at = Vector3::from(s);
    for k in 0..config.filter.yaws {
        let yaw = k as f32 * std::f32::consts::TAU / config.filter.yaws as f32;
        // The floor under the feet sets the seat's height: the sit-down ends with the torso
        // at `s` and the soles on that floor.
        let turn = envfield_scene::nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
        let foot = Point3::from(at + turn * Vector3::new(feet.x, feet.y, 0.0));
        let Some(floor) = scene.cast_ray(&foot, &-Vector3::z(), SEAT_RANGE.1 + 0.5)? else {
            continue;
        };
        let seat = s[2] - torso_above_seat - floor.point.z;
        if !(SEAT_RANGE.0..=SEAT_RANGE.1).contains(&seat) {
            continue;
        }
        let sit = SitDown {
            start: [0.0; 3],
            seated: s,
            seat_height: seat,
            yaw,
        };
        let seq = sit.sequence()?;
        let Some(first) = seq.frames.first() else {
            continue;
        };
        if !starts(&first.torso()) {
            continue;
        }
        // Seated first: a heading that faces into the seat's back fails at once.
        let mut valid = true;
        for i in std::iter::once(seq.frames.len() - 1).chain(0..seq.frames.len() - 1) {
            let (pose, support) = (&seq.frames[i], seq.supports[i]);
            // The thighs near the seat as the hips arrive: a frame still standing may rest
            // them there, as a seated one does.
            let rests = |s| plausible(scene, pose, s, &config.filter.affordance);
            if !check_pose(scene, pose, support, &config.filter.affordance)?.valid()
                || !(rests(support)? || rests(Support::Sitting)?)
            {
                valid = false;
                break;
            }
        }
        if valid {
            return Ok(Some(SitDown {
                start: first.torso().into(),
                ..sit
            }));
        }
    }
    Ok(None)
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
        let end = seq
            .frames
            .last()
            .map(|f| f.torso().coords)
            .unwrap_or_default();
        let to = Vector3::from(self.seated);
        let frames = seq
            .frames
            .iter()
            .map(|p| {
                p.translated(&-end)
                    .rotated_about_z(self.yaw, &Point3::origin())
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
}
