//! The torso filter of an accessible region (paper section 4.2): whether a torso location
//! affords a pose a person would take there.
//!
//! A sample is kept when
//! 1. a sphere of [`FilterConfig::torso_radius`] around it is clear of geometry (its signed
//!    distance is at least the radius), and
//! 2. some pose is *supported* with its torso there: the standing pose (feet on a surface), the
//!    seated pose (on a seat of 0.45 m or a low one of 0.32 m) or the lying pose, each tried at
//!    [`FilterConfig::yaws`] headings, and
//! 3. that pose is [`plausible`] ([`FilterConfig::plausible`], on by default): no bone passes
//!    through geometry or grazes it, and a seated body's feet reach a surface. Without rule 3,
//!    a body standing with a table top between its knees and hips, or sitting on a table top
//!    with its legs hanging, passes: every joint is clear.
//!
//! A sample that fails is tried again lower down ([`FilterConfig::settle`]) and kept there if
//! it sits: a learned sampler places a seated torso at the height it learned above a seat, and
//! a sofa's cushion may be lower.
//!
//! Whether a kept sample *affords* a pose, i.e. some pose there is supported and free of
//! collisions (the check of [`check_pose`]), is the quality figure: the filter does not ask
//! for it.

use crate::{
    bones_clear, check_pose, lie_down, pose_supported, sit_down, standing_pose, AffordanceConfig,
    AffordanceError, Joint, LieConfig, Pose, Result, SitConfig, Support,
};
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::{Scene, SignedDistance};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The largest [`FilterConfig::torso_radius`] accepted, metres.
pub const MAX_TORSO_RADIUS: f32 = 0.5;

/// How torso samples are filtered (the module's rules).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FilterConfig {
    /// Radius of the torso sphere that must be clear of geometry, metres. Small, since the
    /// pelvis joint of a seated body sits 5-10 cm above the seat.
    pub torso_radius: f32,
    /// Headings tried for each pose.
    pub yaws: usize,
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

impl Default for FilterConfig {
    fn default() -> Self {
        Self {
            torso_radius: 0.05,
            yaws: 8,
            affordance: AffordanceConfig::default(),
            plausible: true,
            settle: 0.2,
        }
    }
}

impl FilterConfig {
    /// The same filter, each torso judged where it is (no settling).
    pub fn in_place(&self) -> Self {
        Self {
            settle: 0.0,
            ..*self
        }
    }

    /// Checks every field: the torso's radius at most [`MAX_TORSO_RADIUS`].
    ///
    /// # Errors
    /// [`AffordanceError::InvalidInput`] naming the settings that cannot work.
    pub fn validate(&self) -> Result<()> {
        let ok = (0.0..=MAX_TORSO_RADIUS).contains(&self.torso_radius)
            && (1..=360).contains(&self.yaws)
            && self.settle.is_finite()
            && (0.0..=2.0).contains(&self.settle);
        if ok {
            Ok(())
        } else {
            Err(AffordanceError::InvalidInput(format!(
                "torso filter: a torso_radius of 0 to {MAX_TORSO_RADIUS} m (the torso's \
                 clearance from the scene, 0.05 by default), 1 to 360 yaws and a settle of 0 to \
                 2 m (got {self:?})"
            )))
        }
    }
}

#[derive(Clone, Debug)]
struct Kit {
    standing: Pose,
    sitting: Pose,
    /// Seated on a low seat (0.32 m: armchairs, low sofas), the knees bent further.
    sitting_low: Pose,
    lying: Pose,
    /// Where each pose's support joints lie around the torso, in the order above.
    reach: [Reach; 4],
}

/// Where a pose's support joints lie around its torso, whatever its heading: each joint on
/// the circle of `radius` about the vertical line through the torso, `drop` below it.
#[derive(Clone, Debug)]
struct Reach {
    /// `(drop, radius)` of each support joint, metres.
    joints: Vec<(f32, f32)>,
    /// Whether one resting joint suffices (standing) or every one must rest.
    any: bool,
}

impl Reach {
    fn of(pose: &Pose, support: Support) -> Self {
        let t = pose.torso();
        Self {
            joints: support
                .joints()
                .iter()
                .map(|j| {
                    let p = pose.joints[j.index()];
                    (t.z - p.z, (p.x - t.x).hypot(p.y - t.y))
                })
                .collect(),
            any: support.any_joint_suffices(),
        }
    }

    /// Whether no heading of the pose can rest with its torso at `at`: a support joint rests
    /// only within the contact tolerance above a surface or the penetration below it, and the
    /// distance to the nearest surface changes no faster than the point moves, so a joint
    /// whose circle's centre lies farther than its radius plus both from every surface rests
    /// at no heading. One read per joint (one for the standing pose's feet, at the same
    /// drop), in place of eight headings' checks; the answer is the checks' own.
    fn out_of_reach<S: SignedDistance + ?Sized>(
        &self,
        scene: &S,
        at: &Point3<f32>,
        affordance: &AffordanceConfig,
    ) -> Result<bool> {
        let tolerance = affordance.contact_tolerance.max(affordance.max_penetration) + 1e-4;
        let mut read: Vec<(f32, f32)> = Vec::with_capacity(self.joints.len());
        for &(drop, radius) in &self.joints {
            let d = match read.iter().find(|(d0, _)| (d0 - drop).abs() < 1e-6) {
                Some(&(_, d)) => d,
                None => {
                    let d = scene.distance_at(&Point3::new(at.x, at.y, at.z - drop))?;
                    read.push((drop, d));
                    d
                }
            };
            let far = d.abs() > radius + tolerance;
            if far != self.any {
                // "All must rest": one joint out of reach decides; "any": one within does.
                return Ok(far);
            }
        }
        Ok(self.any)
    }
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
        let standing = centre(standing_pose());
        let sitting = centre(*sit.frames.last().expect("frames"));
        let sitting_low = centre(*low.frames.last().expect("frames"));
        let lying = centre(*lie.frames.last().expect("frames"));
        let reach = [
            Reach::of(&standing, Support::Standing),
            Reach::of(&sitting, Support::Sitting),
            Reach::of(&sitting_low, Support::Sitting),
            Reach::of(&lying, Support::Lying),
        ];
        Ok(Self {
            standing,
            sitting,
            sitting_low,
            lying,
            reach,
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
    /// Where it was judged: the sample, or where it settled ([`FilterConfig::settle`]).
    pub at: [f32; 3],
}

impl Afford {
    /// Kept by the filter: clear and some pose supported.
    pub fn kept(&self) -> bool {
        self.clear && self.supported.is_some()
    }
}

/// What the torso location `p` affords in `scene` (see the module's rules).
///
/// ```
/// use envfield_affordance::{afford, standing_pose, FilterConfig, Support};
/// use envfield_scene::{generate_room, RoomConfig};
///
/// let room = generate_room(&RoomConfig::default(), 3)?;
/// let map = envfield_scene::floor_map(&room.scene, &Default::default())?;
/// let cell = map.grid.free_cells().nth(map.grid.free_count() / 2).unwrap();
/// let [x, y] = map.frame.center(cell);
/// // A standing torso over open floor is kept; the same place 2 m up affords nothing.
/// let torso = standing_pose().torso().z;
/// let here = afford(&room.scene, [x, y, torso], &FilterConfig::default())?;
/// assert!(here.kept() && here.supported == Some(Support::Standing));
/// assert!(!afford(&room.scene, [x, y, torso + 2.0], &FilterConfig::default())?.kept());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`AffordanceError::InvalidInput`] for a coordinate that is not finite.
pub fn afford(scene: &Scene, p: [f32; 3], config: &FilterConfig) -> Result<Afford> {
    config.validate()?;
    afford_with(scene, p, config, &Kit::new()?)
}

fn afford_with(scene: &Scene, p: [f32; 3], config: &FilterConfig, kit: &Kit) -> Result<Afford> {
    if !p.iter().all(|v| v.is_finite()) {
        return Err(AffordanceError::InvalidInput(format!(
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

fn afford_at(scene: &Scene, p: [f32; 3], config: &FilterConfig, kit: &Kit) -> Result<Afford> {
    let at = Point3::from(p);
    let clear = scene.signed_distance(&at)? >= config.torso_radius;
    let mut out = Afford {
        clear,
        supported: None,
        valid: None,
        at: p,
    };
    let to = at.coords;
    // A pose kind none of whose headings can rest is skipped whole (see `Reach`).
    let mut out_of_reach = [false; 4];
    for (k, reach) in kit.reach.iter().enumerate() {
        out_of_reach[k] = reach.out_of_reach(scene, &at, &config.affordance)?;
    }
    let tries = [
        (kit.standing, Support::Standing),
        (kit.sitting, Support::Sitting),
        (kit.sitting_low, Support::Sitting),
        (kit.lying, Support::Lying),
    ]
    .into_iter()
    .zip(out_of_reach)
    .filter(|(_, far)| !far)
    .flat_map(|((pose, s), _)| {
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
        // The support joints alone first: most tries rest on nothing.
        if !pose_supported(scene, &placed, support, &config.affordance)? {
            continue;
        }
        let valid = if config.plausible && bones_decide(&config.affordance) {
            // Every joint but a support joint ends a bone the plausibility rule keeps at
            // least LIMB - BONE_STEP from geometry, so a plausible pose collides nowhere; a
            // lying body's neck alone lies between two support joints and is read.
            if !plausible(scene, &placed, support, &config.affordance)? {
                continue;
            }
            support != Support::Lying
                || scene.distance_at(&placed.joints[Joint::Neck.index()])?
                    >= -config.affordance.collision_margin
        } else {
            let r = check_pose(scene, &placed, support, &config.affordance)?;
            if !r.supported
                || (config.plausible && !plausible(scene, &placed, support, &config.affordance)?)
            {
                continue;
            }
            r.valid()
        };
        if out.supported.is_none() {
            out.supported = Some(support);
        }
        if valid {
            out.valid = Some(support);
            break;
        }
    }
    Ok(out)
}

/// Whether the plausibility rule's bones decide collisions under `affordance`: a joint is
/// in collision below `-collision_margin`, and a plausible pose keeps each joint that ends a
/// bone free of its support joints at least `LIMB - BONE_STEP` from every surface.
fn bones_decide(affordance: &AffordanceConfig) -> bool {
    -affordance.collision_margin <= LIMB - BONE_STEP
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
/// the standing floor of `envfield-rooms` asks of the floor it counts.
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
    bones_clear(scene, pose, support, affordance, LIMB, BONE_STEP)
}

/// What each of `samples` affords, in parallel.
///
/// # Errors
/// As [`afford`], naming the sample.
pub fn afford_all(
    scene: &Scene,
    samples: &[[f32; 3]],
    config: &FilterConfig,
) -> Result<Vec<Afford>> {
    config.validate()?;
    let kit = Kit::new()?;
    samples
        .par_iter()
        .enumerate()
        .map(|(i, &p)| {
            afford_with(scene, p, config, &kit).map_err(|e| match e {
                AffordanceError::InvalidInput(m) => {
                    AffordanceError::InvalidInput(format!("sample {i}: {m}"))
                }
                other => other,
            })
        })
        .collect()
}
