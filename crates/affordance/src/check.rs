//! Support and collision checks of poses against a scene (paper section 4.2, "path
//! optimization by affordance").

use envfield_scene::{Scene, SignedDistance};
use nalgebra::Point3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{AffordanceError, Result};
use crate::skeleton::{Joint, Pose, PoseSequence, Support, JOINT_COUNT};

/// Tolerances of the affordance checks, in metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AffordanceConfig {
    /// A support joint counts as resting on a surface when its signed distance is at most
    /// this and a surface facing up lies straight beneath it within this (a foot beside a
    /// box's side does not rest on the box). Skeleton joints sit inside the body (SMPL's hips
    /// and pelvis are 5-10 cm above the skin a seat touches), so the default is 0.12.
    pub contact_tolerance: f32,
    /// A support joint deeper than this inside geometry is sunk, not supported.
    pub max_penetration: f32,
    /// Any other joint collides when its signed distance is below `-collision_margin`.
    pub collision_margin: f32,
}

impl Default for AffordanceConfig {
    fn default() -> Self {
        Self {
            contact_tolerance: 0.12,
            max_penetration: 0.10,
            collision_margin: 0.0,
        }
    }
}

impl AffordanceConfig {
    /// A support joint at signed distance `d` rests on a surface.
    fn rests(&self, d: f32) -> bool {
        d <= self.contact_tolerance && d >= -self.max_penetration
    }

    /// Any other joint at signed distance `d` is inside geometry.
    fn collides(&self, d: f32) -> bool {
        d < -self.collision_margin
    }

    fn validate(&self) -> Result<()> {
        let ok = |v: f32| v.is_finite() && v >= 0.0;
        if ok(self.contact_tolerance) && ok(self.max_penetration) && ok(self.collision_margin) {
            Ok(())
        } else {
            Err(AffordanceError::InvalidInput(format!(
                "affordance tolerances must be finite and >= 0, got {self:?}"
            )))
        }
    }
}

/// The outcome of checking one pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AffordanceReport {
    /// The support checked.
    pub support: Support,
    /// Signed distance of every joint (SMPL order).
    pub distances: [f32; JOINT_COUNT],
    /// Support joints resting on a surface.
    pub supported_joints: usize,
    /// Non-support joints inside geometry.
    pub colliding_joints: usize,
    /// The support holds (standing: at least one foot; otherwise every support joint).
    pub supported: bool,
    /// No non-support joint is inside geometry.
    pub collision_free: bool,
}

impl AffordanceReport {
    /// Supported and collision-free.
    pub fn valid(&self) -> bool {
        self.supported && self.collision_free
    }

    /// Supported support joints plus collision-free other joints: the score the alignment
    /// search maximises.
    pub fn good_joints(&self) -> usize {
        let others = JOINT_COUNT - self.support.joints().len();
        self.supported_joints + others - self.colliding_joints
    }
}

/// Checks one pose: 22 signed-distance queries. Only joints are tested, as in the paper, so
/// geometry thinner than the gap between two joints (a 4 cm table top between knee and hip)
/// can pass between them unseen.
///
/// # Errors
/// [`AffordanceError::InvalidInput`] for a non-finite joint or bad tolerances.
///
/// `scene` is any [`SignedDistance`]: the [`Scene`] itself, or a
/// [`DistanceGrid`](envfield_scene::DistanceGrid) sampled from it for fast approximate checks.
pub fn check_pose<S: SignedDistance + ?Sized>(
    scene: &S,
    pose: &Pose,
    support: Support,
    config: &AffordanceConfig,
) -> Result<AffordanceReport> {
    config.validate()?;
    pose.validate()?;
    let mut distances = [0.0; JOINT_COUNT];
    for (d, p) in distances.iter_mut().zip(&pose.joints) {
        *d = scene.distance_at(p)?;
    }
    let mut resting = [false; JOINT_COUNT];
    for j in support.joints() {
        let i = j.index();
        resting[i] = rests_on(scene, &pose.joints[i], distances[i], config)?;
    }
    Ok(report(distances, resting, support, config))
}

/// Whether a support joint at `p`, its signed distance `d`, rests on a surface: within the
/// tolerances of one, and that surface lies beneath it. The distance alone cannot say what
/// the nearest surface is: a foot beside a box touches its side, not its top, and a body
/// "stands" in the air beside a wall. So the vertical line down from the joint is followed,
/// by its distance to the nearest surface, for as far as the contact tolerance reaches; a
/// surface met there holds the joint if the distance grows upwards from it (the surface faces
/// up within 53 degrees), not if the line only grazes a wall.
fn rests_on<S: SignedDistance + ?Sized>(
    scene: &S,
    p: &Point3<f32>,
    d: f32,
    config: &AffordanceConfig,
) -> Result<bool> {
    if !config.rests(d) {
        return Ok(false);
    }
    let reach = config.contact_tolerance.max(0.0) + MEETS;
    let (mut t, mut here) = (0.0f32, d);
    loop {
        // Only upwards: below a surface the distance may be unsigned (an open sheet, a
        // coarse inside), so it need not fall on through the surface.
        if here <= MEETS {
            let up = scene.distance_at(&Point3::new(p.x, p.y, p.z - t + MEETS))?;
            if up - here >= FACES_UP * MEETS {
                return Ok(true);
            }
        }
        t += here.max(MEETS);
        if t > reach {
            return Ok(false);
        }
        here = scene.distance_at(&Point3::new(p.x, p.y, p.z - t))?;
    }
}

/// How close the line down from a support joint comes to a surface to meet it, metres; the
/// slope test at the meeting point looks this far up.
const MEETS: f32 = 0.02;

/// The least the distance grows per unit height above a surface met, for the surface to face
/// up (0.6: within 53 degrees of level).
const FACES_UP: f32 = 0.6;

/// Whether `pose` is supported and collision-free: [`check_pose`]'s
/// [`AffordanceReport::valid`], stopping at the first joint that decides it. A search asks
/// this of thousands of candidates, most of them refused by one joint inside geometry.
///
/// # Errors
/// As [`check_pose`].
pub fn pose_valid<S: SignedDistance + ?Sized>(
    scene: &S,
    pose: &Pose,
    support: Support,
    config: &AffordanceConfig,
) -> Result<bool> {
    config.validate()?;
    pose.validate()?;
    let support_joints = support.joints();
    for j in Joint::ALL.iter().filter(|j| !support_joints.contains(j)) {
        if config.collides(scene.distance_at(&pose.joints[j.index()])?) {
            return Ok(false);
        }
    }
    pose_supported(scene, pose, support, config)
}

/// Whether `pose` is supported: [`check_pose`]'s [`AffordanceReport::supported`], reading
/// the support joints alone (two to five of the 22) and stopping at the first that decides
/// it. The torso filter asks this first of each of its 32 tries, most of them in the air.
///
/// # Errors
/// As [`check_pose`].
pub fn pose_supported<S: SignedDistance + ?Sized>(
    scene: &S,
    pose: &Pose,
    support: Support,
    config: &AffordanceConfig,
) -> Result<bool> {
    config.validate()?;
    pose.validate()?;
    // One resting joint decides "any suffices"; one that does not rest decides "all".
    let any = support.any_joint_suffices();
    for j in support.joints() {
        let p = &pose.joints[j.index()];
        if rests_on(scene, p, scene.distance_at(p)?, config)? == any {
            return Ok(any);
        }
    }
    Ok(!any)
}

/// Whether every bone of `pose` (the segment from each joint to its parent) keeps its
/// distance from geometry along its whole length, not only at its joints: a thigh can pass
/// through a table top between a hip above it and a knee below it while every joint is clear.
/// A bone ending at one of `support`'s joints may sink as deep as a support joint may
/// (`max_penetration`); any other keeps at least `clearance` from every surface, a limb's
/// thickness around its bone, so a zero-thickness sheet (which has no inside) is caught too.
/// Each bone is walked from one end by its distance to the nearest surface (at least
/// `min_step`), so free space costs a few reads.
///
/// # Errors
/// As [`check_pose`]; [`AffordanceError::InvalidInput`] for a `min_step` that is not positive
/// or a `clearance` that is negative or not finite.
pub fn bones_clear<S: SignedDistance + ?Sized>(
    scene: &S,
    pose: &Pose,
    support: Support,
    config: &AffordanceConfig,
    clearance: f32,
    min_step: f32,
) -> Result<bool> {
    config.validate()?;
    pose.validate()?;
    if !(min_step.is_finite() && min_step > 0.0 && clearance.is_finite() && clearance >= 0.0) {
        return Err(AffordanceError::InvalidInput(format!(
            "bones_clear: a positive min_step and a clearance >= 0, got {min_step} and \
             {clearance}"
        )));
    }
    let support_joints = support.joints();
    for joint in Joint::ALL {
        let Some(parent) = joint.parent() else {
            continue;
        };
        let a = pose.joints[parent.index()];
        let b = pose.joints[joint.index()];
        let floor = if support_joints.contains(&joint) || support_joints.contains(&parent) {
            -config.max_penetration
        } else {
            clearance
        };
        let length = (b - a).norm();
        let mut t = 0.0;
        while t <= length {
            let d = scene.distance_at(&(a + (b - a) * (t / length.max(1e-9))))?;
            if d < floor {
                return Ok(false);
            }
            t += (d - floor).max(min_step);
        }
    }
    Ok(true)
}

fn report(
    distances: [f32; JOINT_COUNT],
    resting: [bool; JOINT_COUNT],
    support: Support,
    config: &AffordanceConfig,
) -> AffordanceReport {
    let support_joints = support.joints();
    let supported_joints = support_joints.iter().filter(|j| resting[j.index()]).count();
    let colliding_joints = Joint::ALL
        .iter()
        .filter(|j| !support_joints.contains(j))
        .filter(|j| config.collides(distances[j.index()]))
        .count();
    let supported = if support.any_joint_suffices() {
        supported_joints > 0
    } else {
        supported_joints == support_joints.len()
    };
    AffordanceReport {
        support,
        distances,
        supported_joints,
        colliding_joints,
        supported,
        collision_free: colliding_joints == 0,
    }
}

/// Checks every frame of a sequence against its own support, in parallel.
///
/// # Errors
/// As [`check_pose`], naming the frame.
pub fn check_sequence(
    scene: &Scene,
    sequence: &PoseSequence,
    config: &AffordanceConfig,
) -> Result<Vec<AffordanceReport>> {
    sequence
        .frames
        .par_iter()
        .zip(&sequence.supports)
        .enumerate()
        .map(|(i, (pose, support))| {
            check_pose(scene, pose, *support, config)
                .map_err(|e| AffordanceError::InvalidInput(format!("frame {i}: {e}")))
        })
        .collect()
}
