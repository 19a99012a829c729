//! The accessible region of a scene: torso samples filtered by what a torso can afford,
//! voxelised into one connected set, with the coverage figures that judge it.
//!
//! **The filter.** The paper drops samples whose bird's-eye projection falls on furniture or
//! walls; taken literally, that also drops a torso sitting on a sofa. Here a sample is kept
//! when
//! 1. a sphere of [`RegionConfig::torso_radius`] around it is clear of geometry (its signed
//!    distance is at least the radius), and
//! 2. some pose is *supported* with its torso there: the standing pose (feet on a surface), the
//!    seated pose (on a seat of 0.45 m or a low one of 0.32 m) or the lying pose, each tried at
//!    [`RegionConfig::yaws`] headings, and
//! 3. that pose is [`plausible`] ([`RegionConfig::plausible`], on by default): no bone passes
//!    through geometry or grazes it, and a seated body's feet reach a surface. Without rule 3,
//!    a body standing with a table top between its knees and hips, or sitting on a table top
//!    with its legs hanging, passes: every joint is clear. On rooms with known furniture
//!    [`implausible`] measures what slips through.
//!
//! A sample that fails is tried again lower down ([`RegionConfig::settle`]) and kept there if
//! it sits: the VAE places a seated torso at the height it learned above a seat, and a sofa's
//! cushion may be lower.
//!
//! Whether a kept sample *affords* a pose, i.e. some pose there is supported and free of
//! collisions (the check of `envfield_affordance::check_pose`), is the quality figure: the
//! filter does not ask for it.

use crate::torsos::seat_torsos;
use crate::{Result, RoomsError};
use envfield_affordance::{
    bones_clear, check_pose, lie_down, sit_down, standing_pose, AffordanceConfig, Joint, LieConfig,
    Pose, PoseSequence, SitConfig, Support,
};
use envfield_eikonal::FreeCells3;
use envfield_grid::{Cell3, Field2, Grid3, HeatMapStyle};
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::{ObjectKind, Room, Scene, SignedDistance, VoxelFrame};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// How samples are filtered and voxelised.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionConfig {
    /// Radius of the torso sphere that must be clear of geometry, metres. Small, since the
    /// pelvis joint of a seated body sits 5-10 cm above the seat.
    pub torso_radius: f32,
    /// Headings tried for each pose.
    pub yaws: usize,
    /// Voxel side of the region, metres.
    pub voxel: f32,
    /// The support and collision tolerances.
    pub affordance: AffordanceConfig,
    /// Keep only [`plausible`] poses (the module's filter, rule 3).
    #[serde(default)]
    pub plausible: bool,
    /// A sample no pose rests at is tried again up to this much lower (metres, in 5 cm
    /// steps), and kept where a pose first rests if that pose sits: a torso drawn a little
    /// above a seat settles onto it. 0 judges each sample where it was drawn.
    #[serde(default)]
    pub settle: f32,
}

impl Default for RegionConfig {
    fn default() -> Self {
        Self {
            torso_radius: 0.05,
            yaws: 8,
            voxel: 0.1,
            affordance: AffordanceConfig::default(),
            plausible: true,
            settle: 0.2,
        }
    }
}

impl RegionConfig {
    /// The same filter, each torso judged where it is (no settling).
    pub fn in_place(&self) -> Self {
        Self {
            settle: 0.0,
            ..*self
        }
    }

    fn validate(&self) -> Result<()> {
        let ok = self.torso_radius.is_finite()
            && self.torso_radius >= 0.0
            && (1..=360).contains(&self.yaws)
            && self.voxel.is_finite()
            && self.voxel >= 0.02
            && self.settle.is_finite()
            && (0.0..=2.0).contains(&self.settle);
        if ok {
            Ok(())
        } else {
            Err(RoomsError::InvalidConfig(format!(
                "region: torso_radius >= 0, 1 to 360 yaws, a voxel of at least 2 cm and a settle of \
                 0 to 2 m (got {self:?})"
            )))
        }
    }
}

/// The poses a sample is tried with, each with its torso at the origin's x and y.
#[derive(Clone, Debug)]
struct Kit {
    standing: Pose,
    sitting: Pose,
    /// Seated on a low seat (0.32 m: armchairs, low sofas), the knees bent further.
    sitting_low: Pose,
    lying: Pose,
}

impl Kit {
    fn new() -> Result<Self> {
        let centre = |p: Pose| {
            let t = p.torso();
            p.translated(&Vector3::new(-t.x, -t.y, -t.z))
        };
        let sit = sit_down(&SitConfig::default())?;
        let low = sit_down(&SitConfig {
            seat_height: 0.32,
            ..SitConfig::default()
        })?;
        let lie = lie_down(&LieConfig::default())?;
        Ok(Self {
            standing: centre(standing_pose()),
            sitting: centre(*sit.frames.last().expect("frames")),
            sitting_low: centre(*low.frames.last().expect("frames")),
            lying: centre(*lie.frames.last().expect("frames")),
        })
    }
}

/// What a torso location affords.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Afford {
    /// The torso sphere is clear of geometry.
    pub clear: bool,
    /// The first pose found supported there (standing, sitting, lying in that order).
    pub supported: Option<Support>,
    /// The first pose found supported and collision-free there.
    pub valid: Option<Support>,
    /// Where it was judged: the sample, or where it settled ([`RegionConfig::settle`]).
    pub at: [f32; 3],
}

impl Afford {
    /// Kept by the filter: clear and some pose supported.
    pub fn kept(&self) -> bool {
        self.clear && self.supported.is_some()
    }
}

/// What the torso location `p` affords in `scene` (see the module's filter).
///
/// # Errors
/// [`RoomsError::InvalidInput`] for a coordinate that is not finite.
pub fn afford(scene: &Scene, p: [f32; 3], config: &RegionConfig) -> Result<Afford> {
    config.validate()?;
    afford_with(scene, p, config, &Kit::new()?)
}

fn afford_with(scene: &Scene, p: [f32; 3], config: &RegionConfig, kit: &Kit) -> Result<Afford> {
    if !p.iter().all(|v| v.is_finite()) {
        return Err(RoomsError::InvalidInput(format!(
            "torso location {p:?} is not finite"
        )));
    }
    let first = afford_at(scene, p, config, kit)?;
    if first.kept() {
        return Ok(first);
    }
    // Settling: the same torso lower down, a step at a time, until it sits.
    let steps = (config.settle / SETTLE_STEP).round() as usize;
    for k in 1..=steps {
        let lower = [p[0], p[1], p[2] - k as f32 * SETTLE_STEP];
        let a = afford_at(scene, lower, config, kit)?;
        if a.kept() {
            return Ok(if a.supported == Some(Support::Sitting) {
                a
            } else {
                first
            });
        }
    }
    Ok(first)
}

/// The settling step, metres.
const SETTLE_STEP: f32 = 0.05;

fn afford_at(scene: &Scene, p: [f32; 3], config: &RegionConfig, kit: &Kit) -> Result<Afford> {
    let at = Point3::from(p);
    let clear = scene.signed_distance(&at)? >= config.torso_radius;
    let mut out = Afford {
        clear,
        supported: None,
        valid: None,
        at: p,
    };
    let to = at.coords;
    let tries = [
        (kit.standing, Support::Standing),
        (kit.sitting, Support::Sitting),
        (kit.sitting_low, Support::Sitting),
        (kit.lying, Support::Lying),
    ]
    .into_iter()
    .flat_map(|(pose, s)| {
        (0..config.yaws).map(move |k| {
            (
                pose,
                s,
                k as f32 * std::f32::consts::TAU / config.yaws as f32,
            )
        })
    });
    for (pose, support, yaw) in tries {
        let placed = pose.rotated_about_z(yaw, &Point3::origin()).translated(&to);
        let r = check_pose(scene, &placed, support, &config.affordance)?;
        if !r.supported
            || (config.plausible && !plausible(scene, &placed, support, &config.affordance)?)
        {
            continue;
        }
        if out.supported.is_none() {
            out.supported = Some(support);
        }
        if r.valid() {
            out.valid = Some(support);
            break;
        }
    }
    Ok(out)
}

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
fn sit_down_bridges(
    scene: &Scene,
    frame: &VoxelFrame,
    all: &Grid3,
    kept: &[[f32; 3]],
    config: &RegionConfig,
) -> Result<Vec<SitDown>> {
    let components = all.free_components();
    let Some(largest) = components.largest() else {
        return Ok(Vec::new());
    };
    // Each other set's samples (with their voxels), nearest the largest set first (in voxel
    // steps): a bed's edge, not its middle, is where a sit-down from the floor can end.
    let mut by_set = std::collections::BTreeMap::<usize, Vec<(usize, [f32; 3])>>::new();
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
    let tries: Vec<[f32; 3]> = by_set
        .into_values()
        .flat_map(|mut v| {
            v.sort_by_key(|&(i, _)| steps[i]);
            v.truncate(BRIDGE_NEAREST * BRIDGE_TRIES);
            let every = v.len().div_ceil(BRIDGE_TRIES);
            v.into_iter().step_by(every).map(|(_, p)| p)
        })
        .collect();
    // Where a seated body's torso and feet are, relative to its seat, from one sit-down.
    let probe = sit_down(&SitConfig::default())?;
    let seated = *probe.frames.last().expect("a sit-down has frames");
    let torso_above_seat = seated.torso().z - SitConfig::default().seat_height;
    let feet = (seated.joint(Joint::LeftAnkle).coords + seated.joint(Joint::RightAnkle).coords)
        / 2.0
        - seated.torso().coords;
    let chains = tries
        .par_iter()
        .map(|&s| -> Result<Option<SitDown>> {
            let at = Vector3::from(s);
            for k in 0..config.yaws {
                let yaw = k as f32 * std::f32::consts::TAU / config.yaws as f32;
                // The floor under the feet sets the seat's height: the sit-down ends with
                // the torso at the sample and the soles on that floor.
                let turn =
                    envfield_scene::nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
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
                if !beside_largest(&first.torso()) {
                    continue;
                }
                // Seated first: a heading that faces into the seat's back fails at once.
                let mut valid = true;
                for i in std::iter::once(seq.frames.len() - 1).chain(0..seq.frames.len() - 1) {
                    let (pose, support) = (&seq.frames[i], seq.supports[i]);
                    // The thighs near the seat as the hips arrive: a frame still standing
                    // may rest them there, as a seated one does.
                    let rests = |s| plausible(scene, pose, s, &config.affordance);
                    if !check_pose(scene, pose, support, &config.affordance)?.valid()
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
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(chains.into_iter().flatten().collect())
}

/// A sit-down the region found ([`AccessibleRegion::sit_downs`]): [`sit_down`] onto a seat of
/// `seat_height`, turned by `yaw` about the vertical and moved so that it ends seated with
/// the torso at `seated`; every pose of it valid and plausible where it was found.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SitDown {
    /// The torso where it starts, standing, metres.
    pub start: [f32; 3],
    /// The torso where it ends, seated, metres.
    pub seated: [f32; 3],
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

/// Sampling step along a bone, metres.
const BONE_STEP: f32 = 0.02;
/// What a limb keeps between its bone and any surface it does not rest on, metres.
const LIMB: f32 = 0.03;
/// How far above a surface a seated body's feet may hang, metres: the knees flex that much
/// (a seat of 0.3-0.6 m); a table top (0.74 m) leaves them hanging higher.
const FEET_REACH: f32 = 0.2;

/// Whether a supported `pose` is a plausible one: no bone passes through geometry or grazes
/// it (a limb's thickness, 3 cm, around each bone that does not rest on anything), and a
/// seated body's feet reach a surface too, within 0.2 m (a seat low enough to sit on, not a
/// table top with the legs hanging). Rule 3 of the module's filter, and what
/// [`standing_floor`](crate::standing_floor) asks of the floor it counts.
///
/// # Errors
/// As [`check_pose`].
pub fn plausible<S: SignedDistance + ?Sized>(
    scene: &S,
    pose: &Pose,
    support: Support,
    affordance: &AffordanceConfig,
) -> Result<bool> {
    if support == Support::Sitting {
        // A foot reaches down to a surface when some point of the 0.2 m beneath it is on or
        // in one (the table's own legs beside a hanging foot do not count).
        for foot in [Joint::LeftFoot, Joint::RightFoot] {
            let f = pose.joints[foot.index()];
            let mut reaches = false;
            for k in 0..=4 {
                let below = Point3::new(f.x, f.y, f.z - FEET_REACH * k as f32 / 4.0);
                if scene.distance_at(&below)? <= 0.01 {
                    reaches = true;
                    break;
                }
            }
            if !reaches {
                return Ok(false);
            }
        }
    }
    Ok(bones_clear(
        scene, pose, support, affordance, LIMB, BONE_STEP,
    )?)
}

/// What each of `samples` affords, in parallel.
///
/// # Errors
/// As [`afford`], naming the sample.
pub fn afford_all(
    scene: &Scene,
    samples: &[[f32; 3]],
    config: &RegionConfig,
) -> Result<Vec<Afford>> {
    config.validate()?;
    let kit = Kit::new()?;
    samples
        .par_iter()
        .enumerate()
        .map(|(i, &p)| {
            afford_with(scene, p, config, &kit).map_err(|e| match e {
                RoomsError::InvalidInput(m) => RoomsError::InvalidInput(format!("sample {i}: {m}")),
                other => other,
            })
        })
        .collect()
}

/// The accessible region of a scene: the voxels holding kept torso samples (and their six
/// neighbours, closing the gaps between samples), reduced to its largest 26-connected set.
#[derive(Clone, Debug)]
pub struct AccessibleRegion {
    /// The voxel lattice, metres.
    pub frame: VoxelFrame,
    /// Free voxels are accessible.
    pub grid: Grid3,
    /// The kept samples, metres.
    pub samples: Vec<[f32; 3]>,
    /// Connected sets before the largest was kept.
    pub components: usize,
    /// The sit-downs that joined seats to the floor's set ([`AccessibleRegion::from_kept`]),
    /// each ending seated in the region.
    pub sit_downs: Vec<SitDown>,
    /// The accessible voxels' indices, made on first use.
    free: std::sync::OnceLock<Vec<usize>>,
    /// The accessible voxels numbered and linked for fast marching, made on first use.
    cells: std::sync::OnceLock<std::sync::Arc<FreeCells3>>,
}

impl AccessibleRegion {
    /// A region from its parts: `grid`'s free voxels on `frame` are accessible.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] when the grid's shape is not the frame's or no voxel is
    /// free.
    pub fn new(
        frame: VoxelFrame,
        grid: Grid3,
        samples: Vec<[f32; 3]>,
        components: usize,
    ) -> Result<Self> {
        if grid.shape() != frame.shape {
            return Err(RoomsError::InvalidInput(format!(
                "a region's grid {:?} must have its frame's shape {:?}",
                grid.shape(),
                frame.shape
            )));
        }
        if grid.free_count() == 0 {
            return Err(RoomsError::InvalidInput(
                "a region needs an accessible voxel".into(),
            ));
        }
        Ok(Self {
            frame,
            grid,
            samples,
            components,
            sit_downs: Vec::new(),
            free: std::sync::OnceLock::new(),
            cells: std::sync::OnceLock::new(),
        })
    }

    /// The accessible voxels numbered in C order and linked to their neighbours, made once
    /// (on first use) and shared by every field of the region: fast marching over them
    /// ([`FastMarching::solve3_free`](envfield_eikonal::FastMarching::solve3_free)) costs
    /// the voxels it reaches, not the region's box, and a [`crate::VoxelField3`] keeps a
    /// value per accessible voxel alone.
    ///
    /// # Errors
    /// [`RoomsError::Eikonal`] for a lattice too large to march.
    pub fn free_cells(&self) -> Result<std::sync::Arc<FreeCells3>> {
        if let Some(cells) = self.cells.get() {
            return Ok(cells.clone());
        }
        let cells = std::sync::Arc::new(FreeCells3::new(&self.grid)?);
        Ok(self.cells.get_or_init(|| cells).clone())
    }

    /// The accessible voxels' indices (C order).
    pub fn free_indices(&self) -> &[usize] {
        self.free.get_or_init(|| {
            (0..self.grid.len())
                .filter(|&i| !self.grid.obstacles()[i])
                .collect()
        })
    }

    /// The region of drawn torso `samples` in `scene`: the filter ([`afford_all`], keeping
    /// what [`Afford::kept`] keeps), then [`AccessibleRegion::from_samples`] at the config's
    /// voxel.
    ///
    /// # Errors
    /// As [`afford_all`] and [`AccessibleRegion::from_samples`].
    pub fn from_drawn(scene: &Scene, samples: &[[f32; 3]], config: &RegionConfig) -> Result<Self> {
        let kept = afford_all(scene, samples, config)?
            .iter()
            .filter(|a| a.kept())
            .map(|a| a.at)
            .collect();
        Self::from_kept(scene, kept, config)
    }

    /// The region of `kept` samples (already filtered by `config`'s filter): as
    /// [`AccessibleRegion::from_samples`], except that with [`RegionConfig::plausible`] a
    /// neighbouring voxel joins only if a torso at its centre passes the filter too, so the
    /// gaps between samples close without the region spilling over a table's edge, and a set
    /// of voxels apart from the largest joins it through a sit-down that ends in it (every
    /// pose of it valid and plausible): a seat's voxels lie half a metre below the floor's.
    ///
    /// # Errors
    /// As [`afford_all`] and [`AccessibleRegion::from_samples`].
    pub fn from_kept(scene: &Scene, kept: Vec<[f32; 3]>, config: &RegionConfig) -> Result<Self> {
        if !config.plausible {
            return Self::from_samples(scene, kept, config.voxel);
        }
        let in_place = config.in_place();
        Self::build(
            scene,
            kept,
            config.voxel,
            |centres| {
                Ok(afford_all(scene, centres, &in_place)?
                    .iter()
                    .map(Afford::kept)
                    .collect())
            },
            |frame, all, kept| sit_down_bridges(scene, frame, all, kept, config),
        )
    }

    /// The region of `kept` samples (already filtered) on a lattice covering `scene`.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] for no samples (a scene with no floor keeps none) or an
    /// empty scene.
    pub fn from_samples(scene: &Scene, kept: Vec<[f32; 3]>, voxel: f32) -> Result<Self> {
        Self::build(
            scene,
            kept,
            voxel,
            |centres| Ok(vec![true; centres.len()]),
            |_, _, _| Ok(Vec::new()),
        )
    }

    /// The region of `kept`, each neighbour voxel of a sample's voxel joining when `joins`
    /// says so of its centre (asked once, for all of them), and the voxels along the torsos of
    /// each sit-down `links` gives (for the lattice, the voxels so far and the samples)
    /// joining too, before the largest connected set is kept; the sit-downs that end in it
    /// are the region's.
    fn build(
        scene: &Scene,
        kept: Vec<[f32; 3]>,
        voxel: f32,
        joins: impl FnOnce(&[[f32; 3]]) -> Result<Vec<bool>>,
        links: impl FnOnce(&VoxelFrame, &Grid3, &[[f32; 3]]) -> Result<Vec<SitDown>>,
    ) -> Result<Self> {
        if kept.is_empty() {
            return Err(RoomsError::InvalidInput(
                "no torso sample affords a pose here: the scene has no floor or seat the \
                 samples reach"
                    .into(),
            ));
        }
        let scene_box = scene
            .aabb()
            .ok_or_else(|| RoomsError::InvalidInput("the scene is empty".into()))?;
        // The lattice covers the scene and every kept sample, with a voxel to spare.
        let (mut lo, mut hi) = (scene_box.mins, scene_box.maxs);
        for p in &kept {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a] - voxel);
                hi[a] = hi[a].max(p[a] + voxel);
            }
        }
        let aabb = envfield_scene::parry3d::bounding_volume::Aabb::new(lo, hi);
        let frame = VoxelFrame::covering(&aabb, voxel)?;
        let [nx, ny, nz] = frame.shape;
        let mut on = vec![false; nx * ny * nz];
        let index = |c: Cell3| (c.x * ny + c.y) * nz + c.z;
        for p in &kept {
            if let Some(c) = frame.cell_of(&Point3::from(*p)) {
                on[index(c)] = true;
            }
        }
        // The six neighbours of every sample's voxel that hold no sample, asked once.
        let mut near = vec![false; nx * ny * nz];
        for p in &kept {
            if let Some(c) = frame.cell_of(&Point3::from(*p)) {
                for (dx, dy, dz) in [
                    (1, 0, 0),
                    (-1, 0, 0),
                    (0, 1, 0),
                    (0, -1, 0),
                    (0, 0, 1),
                    (0, 0, -1),
                ] {
                    let (x, y, z) = (c.x as isize + dx, c.y as isize + dy, c.z as isize + dz);
                    if x >= 0
                        && y >= 0
                        && z >= 0
                        && (x as usize) < nx
                        && (y as usize) < ny
                        && (z as usize) < nz
                    {
                        let i = index(Cell3::new(x as usize, y as usize, z as usize));
                        near[i] = !on[i];
                    }
                }
            }
        }
        let candidates: Vec<usize> = (0..near.len()).filter(|&i| near[i]).collect();
        let centres: Vec<[f32; 3]> = candidates
            .iter()
            .map(|&i| {
                let c = Cell3::new(i / (ny * nz), (i / nz) % ny, i % nz);
                frame.center(c).into()
            })
            .collect();
        for (i, join) in candidates.into_iter().zip(joins(&centres)?) {
            on[i] = join;
        }
        let all = Grid3::from_obstacles(frame.shape, on.iter().map(|&o| !o).collect())?;
        let sit_downs = links(&frame, &all, &kept)?;
        for sit in &sit_downs {
            let chain: Vec<Point3<f32>> = sit.sequence()?.frames.iter().map(Pose::torso).collect();
            for pair in chain.windows(2) {
                let (a, b) = (pair[0], pair[1]);
                // Steps of at most half a voxel, so the chain's voxels touch.
                let steps = ((b - a).norm() / (0.5 * voxel)).ceil().max(1.0) as usize;
                for k in 0..=steps {
                    let p = a + (b - a) * (k as f32 / steps as f32);
                    if let Some(c) = frame.cell_of(&p) {
                        on[index(c)] = true;
                    }
                }
            }
        }
        // The largest 26-connected set.
        let all = Grid3::from_obstacles(frame.shape, on.iter().map(|&o| !o).collect())?;
        let components = all.free_components();
        let largest = components.largest().unwrap_or(0);
        let obstacles = components.labels.iter().map(|&l| l != largest).collect();
        let grid = Grid3::from_obstacles(frame.shape, obstacles)?;
        if grid.free_count() == 0 {
            return Err(RoomsError::InvalidInput(
                "the kept samples all lie outside the scene's box".into(),
            ));
        }
        let mut region = Self::new(frame, grid, kept, components.count())?;
        region.sit_downs = sit_downs
            .into_iter()
            .filter(|s| region.contains(s.seated))
            .collect();
        Ok(region)
    }

    /// Whether `p` (metres) lies in an accessible voxel.
    pub fn contains(&self, p: [f32; 3]) -> bool {
        self.frame
            .cell_of(&Point3::from(p))
            .is_some_and(|c| self.grid.is_free(c))
    }

    /// The accessible voxels' centres, metres.
    pub fn voxel_centres(&self) -> Vec<[f32; 3]> {
        self.free_indices()
            .iter()
            .map(|&i| self.frame.center(self.grid.cell(i)).into())
            .collect()
    }

    /// Writes the kept samples as a PLY point cloud, atomically.
    ///
    /// # Errors
    /// I/O errors, naming the file.
    pub fn write_samples_ply(&self, path: impl AsRef<Path>) -> Result<()> {
        let kept: Vec<Point3<f32>> = self.samples.iter().map(|s| Point3::from(*s)).collect();
        Ok(envfield_scene::write_point_cloud(&kept, path)?)
    }

    /// Writes the accessible voxels' centres as an ASCII PLY point cloud coloured by height
    /// (blue low, yellow high), atomically.
    ///
    /// # Errors
    /// I/O errors, naming the file.
    pub fn write_ply(&self, path: impl AsRef<Path>) -> Result<()> {
        let points = self.voxel_centres();
        let (lo, hi) = points
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), p| {
                (a.min(p[2]), b.max(p[2]))
            });
        let mut text = format!(
            "ply\nformat ascii 1.0\ncomment envfield accessible region, coloured by height\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
            points.len()
        );
        for p in &points {
            let t = if hi > lo {
                (p[2] - lo) / (hi - lo)
            } else {
                0.0
            };
            let [r, g, b] = height_colour(t);
            text.push_str(&format!("{} {} {} {r} {g} {b}\n", p[0], p[1], p[2]));
        }
        envfield_grid::write_atomic(path.as_ref(), text.as_bytes())?;
        Ok(())
    }

    /// Writes a top-down PNG: each floor column coloured by the height of its highest
    /// accessible voxel (grey: none), north up, `scale` pixels per voxel.
    ///
    /// # Errors
    /// I/O errors, naming the file.
    pub fn write_png(&self, path: impl AsRef<Path>, scale: u32) -> Result<()> {
        let [nx, ny, nz] = self.frame.shape;
        let mut values = vec![f32::INFINITY; nx * ny];
        for x in 0..nx {
            for y in 0..ny {
                if let Some(z) = (0..nz)
                    .rev()
                    .find(|&z| self.grid.is_free(Cell3::new(x, y, z)))
                {
                    let h = self.frame.center(Cell3::new(x, y, z)).z;
                    values[(ny - 1 - y) * nx + x] = h;
                }
            }
        }
        let field = Field2::new(ny, nx, values)?;
        field.write_png(
            path,
            &HeatMapStyle {
                scale: scale.max(1),
                ..HeatMapStyle::default()
            },
        )?;
        Ok(())
    }

    /// The voxel of `p` when it is accessible.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] naming `what` for a point outside the region.
    pub fn cell(&self, p: [f32; 3], what: &str) -> Result<Cell3> {
        match self.frame.cell_of(&Point3::from(p)) {
            Some(c) if self.grid.is_free(c) => Ok(c),
            _ => Err(RoomsError::InvalidInput(format!(
                "{what} {p:?} is outside the accessible region"
            ))),
        }
    }
}

/// Blue to yellow through green, `t` in [0, 1].
fn height_colour(t: f32) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    let c = |a: f32, b: f32| ((a + (b - a) * t) * 255.0) as u8;
    [c(0.2, 1.0), c(0.2, 0.9), c(0.9, 0.1)]
}

/// The share (percent) of `targets` within `radius` of some point of `samples`; 100 for no
/// targets.
pub fn covered_pct(targets: &[[f32; 3]], samples: &[[f32; 3]], radius: f32) -> f64 {
    if targets.is_empty() {
        return 100.0;
    }
    let r2 = radius * radius;
    let hit = targets
        .par_iter()
        .filter(|t| {
            samples.iter().any(|s| {
                let d = [s[0] - t[0], s[1] - t[1], s[2] - t[2]];
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= r2
            })
        })
        .count();
    100.0 * hit as f64 / targets.len() as f64
}

/// How well a set of torso samples serves a generated room.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionQuality {
    /// Samples drawn.
    pub drawn: usize,
    /// Samples kept by the filter, percent of those drawn.
    pub kept_pct: f64,
    /// Kept samples where some pose is supported and collision-free, percent of those kept.
    pub affordable_pct: f64,
    /// Standing-affordable floor points (10 cm grid) within 0.2 m of a kept sample, percent.
    pub floor_coverage_pct: f64,
    /// Seats whose sitting torso location lies within [`SEAT_NEAR`] of a kept sample,
    /// percent.
    pub seat_coverage_pct: f64,
    /// Seats in the room.
    pub seats: usize,
    /// Seats whose sitting torso location lies within [`SEAT_NEAR`] of an accessible region voxel's
    /// centre, percent: the region keeps only its largest connected set of voxels, so a seat
    /// the samples cover may still be left out of it, and out of every planner's reach.
    #[serde(default)]
    pub region_seat_coverage_pct: f64,
    /// Kept samples that [`implausible`] finds on or inside furniture people do not use that
    /// way, percent of those kept.
    pub implausible_pct: f64,
    /// The accessible region's voxels whose centre [`implausible`] finds so, percent.
    pub region_implausible_pct: f64,
    /// The accessible region's voxels.
    pub region_voxels: usize,
}

impl RegionQuality {
    /// The mean of each percentage over `qualities` as JSON (`kept_pct`, `affordable_pct`,
    /// `floor_coverage_pct`, `seat_coverage_pct`), 0 for none.
    pub fn mean_json(qualities: &[RegionQuality]) -> serde_json::Value {
        let n = qualities.len().max(1) as f64;
        let m = |f: fn(&RegionQuality) -> f64| qualities.iter().map(f).sum::<f64>() / n;
        serde_json::json!({
            "kept_pct": m(|x| x.kept_pct),
            "affordable_pct": m(|x| x.affordable_pct),
            "floor_coverage_pct": m(|x| x.floor_coverage_pct),
            "seat_coverage_pct": m(|x| x.seat_coverage_pct),
            "region_seat_coverage_pct": m(|x| x.region_seat_coverage_pct),
            "implausible_pct": m(|x| x.implausible_pct),
            "region_implausible_pct": m(|x| x.region_implausible_pct),
        })
    }
}

impl RegionQuality {
    /// [`RegionQuality::mean_json`] with the least floor and seat coverage of any room
    /// (`min_floor_coverage_pct`, `min_seat_coverage_pct`).
    pub fn summary_json(qualities: &[RegionQuality]) -> serde_json::Value {
        let least =
            |f: fn(&RegionQuality) -> f64| qualities.iter().map(f).fold(f64::INFINITY, f64::min);
        let mut out = Self::mean_json(qualities);
        out["min_floor_coverage_pct"] = least(|q| q.floor_coverage_pct).into();
        out["min_seat_coverage_pct"] = least(|q| q.seat_coverage_pct).into();
        out["min_region_seat_coverage_pct"] = least(|q| q.region_seat_coverage_pct).into();
        let most = |f: fn(&RegionQuality) -> f64| qualities.iter().map(f).fold(0.0f64, f64::max);
        out["max_implausible_pct"] = most(|q| q.implausible_pct).into();
        out["max_region_implausible_pct"] = most(|q| q.region_implausible_pct).into();
        out
    }
}

/// What drawn torso samples are, before the filter: how many lie in each 0.1 m band of height
/// (keyed by the band's floor, `"0.9"`), and how many fall in each class of what they afford
/// (`"clear:first supported/first valid"`, such as `"true:Some(Standing)/None"`).
///
/// # Errors
/// As [`afford_all`].
pub fn drawn_summary(
    scene: &Scene,
    samples: &[[f32; 3]],
    config: &RegionConfig,
) -> Result<serde_json::Value> {
    Ok(summarise_drawn(
        samples,
        &afford_all(scene, samples, config)?,
    ))
}

/// [`drawn_summary`] of `samples` whose filter answers (as [`afford_all`] gives them, in
/// order) are `affords`.
pub fn summarise_drawn(samples: &[[f32; 3]], affords: &[Afford]) -> serde_json::Value {
    let mut heights = std::collections::BTreeMap::<i32, usize>::new();
    for s in samples {
        *heights.entry((s[2] * 10.0).floor() as i32).or_default() += 1;
    }
    let heights: serde_json::Map<String, serde_json::Value> = heights
        .into_iter()
        .map(|(k, v)| (format!("{:.1}", k as f32 / 10.0), v.into()))
        .collect();
    let mut kinds = std::collections::BTreeMap::<String, usize>::new();
    for a in affords {
        *kinds
            .entry(format!("{}:{:?}/{:?}", a.clear, a.supported, a.valid))
            .or_default() += 1;
    }
    serde_json::json!({"drawn_by_height_m": heights, "affords_clear_supported_valid": kinds})
}

/// Judges `samples` drawn for `room`: the filter's figures, floor coverage and seat coverage.
///
/// # Errors
/// As [`afford_all`]; [`RoomsError::InvalidInput`] for a room with no standing-affordable floor.
pub fn region_quality(
    room: &Room,
    samples: &[[f32; 3]],
    config: &RegionConfig,
) -> Result<RegionQuality> {
    let affords = afford_all(&room.scene, samples, config)?;
    let kept: Vec<[f32; 3]> = affords.iter().filter(|a| a.kept()).map(|a| a.at).collect();
    let region = if kept.is_empty() {
        None
    } else {
        Some(AccessibleRegion::from_kept(&room.scene, kept, config)?)
    };
    judge_region(room, &affords, region.as_ref())
}

/// [`region_quality`] of samples whose filter answers (as [`afford_all`] gives them) are
/// `affords` and whose region (made from the kept ones, `None` when none is kept) is
/// `region`: for a caller that has both already.
///
/// # Errors
/// As [`region_quality`].
pub fn judge_region(
    room: &Room,
    affords: &[Afford],
    region: Option<&AccessibleRegion>,
) -> Result<RegionQuality> {
    let kept: Vec<[f32; 3]> = affords.iter().filter(|a| a.kept()).map(|a| a.at).collect();
    let affordable = affords
        .iter()
        .filter(|a| a.kept() && a.valid.is_some())
        .count();
    let floor = crate::standing_floor(&room.scene, [0.0, 0.0, room.size[0], room.size[1]], 0.1)?;
    if floor.is_empty() {
        return Err(RoomsError::InvalidInput(
            "the room has no floor a standing pose is supported on".into(),
        ));
    }
    let seats = seat_torsos(room)?;
    let implausible_share = |points: &[[f32; 3]]| -> Result<f64> {
        let bad = points
            .par_iter()
            .map(|&p| implausible(room, p).map(|k| k.is_some()))
            .collect::<Result<Vec<bool>>>()?;
        Ok(100.0 * bad.iter().filter(|&&b| b).count() as f64 / points.len().max(1) as f64)
    };
    let (region_voxels, region_implausible_pct, region_seat_coverage_pct) = match region {
        None => (0, 0.0, 0.0),
        Some(region) => {
            let centres = region.voxel_centres();
            (
                centres.len(),
                implausible_share(&centres)?,
                covered_pct(&seats, &centres, SEAT_NEAR),
            )
        }
    };
    Ok(RegionQuality {
        implausible_pct: implausible_share(&kept)?,
        region_implausible_pct,
        region_voxels,
        drawn: affords.len(),
        kept_pct: 100.0 * kept.len() as f64 / affords.len().max(1) as f64,
        affordable_pct: if kept.is_empty() {
            0.0
        } else {
            100.0 * affordable as f64 / kept.len() as f64
        },
        floor_coverage_pct: covered_pct(&floor, &kept, 0.2),
        seat_coverage_pct: covered_pct(&seats, &kept, SEAT_NEAR),
        seats: seats.len(),
        region_seat_coverage_pct,
    })
}

/// How near a seat's seated torso location a sample or region voxel covers it, metres.
pub const SEAT_NEAR: f32 = 0.15;

/// A torso this far above a seat's surface stands on it.
const STANDING_ABOVE: f32 = 0.6;

/// What is implausible about a torso at `p` in `room`, judged by the room's known furniture
/// ([`Room::furniture`]): the kind of the piece it is inside (any furniture but a seat, whose
/// box holds the torso of whoever sits there), or of the first surface straight below it when
/// that is furniture people do not sit or lie on (a table, desk, cabinet, shelf or piano), or
/// a seat it stands on (more than 0.6 m above a surface of the seat at least half its seat
/// height up; over a chair's legs or base a body stands on the floor). `None` when it is
/// plausible: over the floor, or sitting or lying on a bed, sofa or chair.
///
/// The affordance figures cannot see this: a body lying on a table is supported and free of
/// collisions.
///
/// # Errors
/// [`RoomsError::InvalidInput`] for a point that is not finite.
pub fn implausible(room: &Room, p: [f32; 3]) -> Result<Option<ObjectKind>> {
    if !p.iter().all(|v| v.is_finite()) {
        return Err(RoomsError::InvalidInput(format!(
            "torso location {p:?} is not finite"
        )));
    }
    for f in &room.furniture {
        if f.kind.is_seat() {
            continue;
        }
        if f.covers(p[0], p[1]) && p[2] >= 0.0 && p[2] < f.size[2] {
            return Ok(Some(f.kind));
        }
    }
    let below = room
        .scene
        .cast_ray(&Point3::from(p), &-Vector3::z(), p[2].max(0.0) + 1.0)?;
    Ok(below.and_then(|hit| {
        let kind = room.scene.objects()[hit.object].kind;
        // Standing on a seat: high above a surface of it that is at least half the seat's
        // height up (its seat, arms or back), not above its legs or base beside the feet.
        let seat_top = room
            .furniture
            .iter()
            .find(|f| f.object == hit.object)
            .map_or(0.0, |f| f.seat_height.unwrap_or(f.size[2]));
        let stands_on = hit.distance > STANDING_ABOVE && hit.point.z >= SEAT_PART_SHARE * seat_top;
        let wrong = kind.is_furniture() && (!kind.is_seat() || stands_on);
        wrong.then_some(kind)
    }))
}

/// A surface of a seat at least this share of its seat height up counts as one a body could
/// stand on; lower parts (legs, a base, a stretcher) stand on the floor between the feet.
const SEAT_PART_SHARE: f32 = 0.5;

/// Uniform samples in the room's box (interior, floor to wall top): the no-learning control.
pub fn uniform_in_room(room: &Room, height: f32, n: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut rng = envfield_grid::SplitMix64::new(seed ^ 0x0F1F);
    (0..n)
        .map(|_| {
            [
                rng.next_f32() * room.size[0],
                rng.next_f32() * room.size[1],
                rng.next_f32() * height,
            ]
        })
        .collect()
}
