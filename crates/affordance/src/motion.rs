//! Procedural pose sequences (walking, sitting down, getting up, lying down), seeded, so
//! everything works without motion capture. Bodies face +x (left is +y), feet on z = 0.
//!
//! The motions are plausible rather than physically exact: a sagittal-plane skeleton with
//! adult proportions (1.75 m tall, legs 0.90 m to the hip) driven by smooth joint-angle curves.

use std::f32::consts::{FRAC_PI_2, PI};

use envfield_grid::SplitMix64;
use nalgebra::{Point3, Rotation3, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::{AffordanceError, Result};
use crate::skeleton::{Activity, Joint, Pose, PoseSequence, Support, JOINT_COUNT};

const PELVIS_TO_HIP: f32 = 0.08;
const HIP_HALF_WIDTH: f32 = 0.09;
const THIGH: f32 = 0.40;
const SHANK: f32 = 0.42;
const ANKLE_HEIGHT: f32 = 0.08;
/// How far the straight legs are raised above level as they swing round onto a bed or sofa
/// ([`LieConfig::turn`]), radians at the middle of the swing: 20 degrees lift the feet about
/// 0.3 m, clear of the surface they swing over.
const SWING_RAISE: f32 = 0.35;
const UPPER_ARM: f32 = 0.27;
const FOREARM: f32 = 0.25;

/// Joint angles (radians) and root placement of the sagittal skeleton.
#[derive(Clone, Copy, Debug, Default)]
struct Gait {
    /// Pelvis position in the body frame.
    pelvis: Vector3<f32>,
    /// Torso pitch: positive leans forward, -pi/2 lies on the back.
    pitch: f32,
    /// Thigh angle from straight down, positive forward (left, right).
    hip: [f32; 2],
    /// Knee flexion (left, right), >= 0.
    knee: [f32; 2],
    /// Upper-arm angle from the torso's down axis, positive forward (left, right).
    shoulder: [f32; 2],
    /// Elbow flexion (left, right).
    elbow: [f32; 2],
}

/// Direction at angle `a` from straight down in the x-z plane, positive forward.
fn sagittal(a: f32) -> Vector3<f32> {
    Vector3::new(a.sin(), 0.0, -a.cos())
}

impl Gait {
    /// Hip-to-ankle vector of one leg.
    fn leg(&self, side: usize) -> Vector3<f32> {
        sagittal(self.hip[side]) * THIGH + sagittal(self.hip[side] - self.knee[side]) * SHANK
    }

    /// Places the pelvis so that the midpoint of the hips is at `hips`.
    fn set_hip_centre(&mut self, hips: Vector3<f32>) {
        let pelvis_to_hips = Rotation3::from_axis_angle(&Vector3::y_axis(), self.pitch)
            * Vector3::new(0.0, 0.0, -PELVIS_TO_HIP);
        self.pelvis = hips - pelvis_to_hips;
    }

    fn pose(&self) -> Pose {
        let torso = Rotation3::from_axis_angle(&Vector3::y_axis(), self.pitch);
        let pelvis = Point3::from(self.pelvis);
        let at = |v: Vector3<f32>| pelvis + torso * v;
        let mut j = [Point3::origin(); JOINT_COUNT];
        let mut set = |joint: Joint, p: Point3<f32>| j[joint.index()] = p;
        set(Joint::Pelvis, pelvis);
        set(Joint::Spine1, at(Vector3::new(-0.01, 0.0, 0.11)));
        set(Joint::Spine2, at(Vector3::new(-0.01, 0.0, 0.24)));
        set(Joint::Spine3, at(Vector3::new(0.0, 0.0, 0.30)));
        set(Joint::Neck, at(Vector3::new(0.01, 0.0, 0.51)));
        set(Joint::Head, at(Vector3::new(0.04, 0.0, 0.60)));
        for (side, sign) in [(0usize, 1.0f32), (1, -1.0)] {
            let left = side == 0;
            let pick = |l: Joint, r: Joint| if left { l } else { r };
            let hip = at(Vector3::new(0.0, sign * HIP_HALF_WIDTH, -PELVIS_TO_HIP));
            let knee = hip + sagittal(self.hip[side]) * THIGH;
            let shank_angle = self.hip[side] - self.knee[side];
            let ankle = knee + sagittal(shank_angle) * SHANK;
            // The foot joint sits forward of and below the ankle, turning with the shank.
            let foot = ankle
                + Vector3::new(shank_angle.cos(), 0.0, shank_angle.sin()) * 0.12
                + sagittal(shank_angle) * 0.05;
            set(pick(Joint::LeftHip, Joint::RightHip), hip);
            set(pick(Joint::LeftKnee, Joint::RightKnee), knee);
            set(pick(Joint::LeftAnkle, Joint::RightAnkle), ankle);
            set(pick(Joint::LeftFoot, Joint::RightFoot), foot);
            let collar = at(Vector3::new(0.0, sign * 0.07, 0.42));
            let shoulder = at(Vector3::new(0.0, sign * 0.18, 0.44));
            let elbow = shoulder + torso * sagittal(self.shoulder[side]) * UPPER_ARM;
            let wrist = elbow + torso * sagittal(self.shoulder[side] + self.elbow[side]) * FOREARM;
            set(pick(Joint::LeftCollar, Joint::RightCollar), collar);
            set(pick(Joint::LeftShoulder, Joint::RightShoulder), shoulder);
            set(pick(Joint::LeftElbow, Joint::RightElbow), elbow);
            set(pick(Joint::LeftWrist, Joint::RightWrist), wrist);
        }
        Pose { joints: j }
    }
}

/// A standing pose facing +x, feet on z = 0, pelvis above the origin.
pub fn standing_pose() -> Pose {
    let mut g = Gait {
        shoulder: [0.05, 0.05],
        elbow: [0.1, 0.1],
        ..Gait::default()
    };
    g.pelvis.z = ANKLE_HEIGHT - g.leg(0).z + PELVIS_TO_HIP;
    g.pose()
}

fn smoothstep(s: f32) -> f32 {
    let s = s.clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

fn check_positive(what: &str, v: f32) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(AffordanceError::InvalidInput(format!(
            "{what} must be positive, got {v}"
        )))
    }
}

/// A walking gait.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WalkConfig {
    /// Step length in metres (one foot ahead of the other), before the seeded variation.
    pub step_length: f32,
    /// Steps per second, before the seeded variation.
    pub cadence: f32,
    /// Gait cycles (two steps each).
    pub cycles: usize,
    /// Frames per second.
    pub fps: f32,
    /// Relative spread of the seeded variation of step length and cadence (0.1: +-10%).
    pub variation: f32,
}

impl Default for WalkConfig {
    fn default() -> Self {
        Self {
            step_length: 0.65,
            cadence: 1.8,
            cycles: 1,
            fps: 30.0,
            variation: 0.1,
        }
    }
}

/// Walking along +x: thighs swing sinusoidally, the swing knee bends, arms swing opposite, and
/// the pelvis rides at the height that keeps the lower foot on the floor. Seeded variation of
/// step length and cadence.
///
/// # Errors
/// [`AffordanceError::InvalidInput`] for non-positive sizes, rates or cycles, or a step longer
/// than the legs allow (1.2 m).
pub fn walk(config: &WalkConfig, seed: u64) -> Result<PoseSequence> {
    check_positive("step length", config.step_length)?;
    check_positive("cadence", config.cadence)?;
    check_positive("fps", config.fps)?;
    if config.cycles == 0 || config.step_length > 1.2 || !(0.0..0.5).contains(&config.variation) {
        return Err(AffordanceError::InvalidInput(format!(
            "walk: cycles >= 1, step length <= 1.2 m and variation in [0, 0.5) (got {config:?})"
        )));
    }
    let mut rng = SplitMix64::new(seed);
    let mut jitter = || 1.0 + config.variation * (2.0 * rng.next_f32() - 1.0);
    let step = config.step_length * jitter();
    let cadence = config.cadence * jitter();
    let period = 2.0 / cadence;
    let frames = ((config.cycles as f32 * period * config.fps).round() as usize).max(2);
    let amplitude = (step / 2.0 / (THIGH + SHANK)).asin();
    let speed = step * cadence;
    let poses = (0..frames)
        .map(|i| {
            let t = i as f32 / config.fps;
            let phase = 2.0 * PI * t / period;
            let mut g = Gait {
                pitch: 0.05,
                ..Gait::default()
            };
            for (side, offset) in [(0usize, 0.0f32), (1, PI)] {
                let p = phase + offset;
                g.hip[side] = amplitude * p.sin();
                // The leg swings forward while its thigh angle grows: bend the knee then.
                g.knee[side] = 0.08 + 0.9 * p.cos().max(0.0).powi(2);
                g.shoulder[side] = -0.35 * p.sin();
                g.elbow[side] = 0.25;
            }
            let lowest = g.leg(0).z.min(g.leg(1).z);
            g.pelvis = Vector3::new(speed * t, 0.0, ANKLE_HEIGHT - lowest + PELVIS_TO_HIP);
            g.pose()
        })
        .collect();
    PoseSequence::new(
        config.fps,
        Activity::Walk,
        poses,
        vec![Support::Standing; frames],
    )
}

/// Sitting down onto a seat.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SitConfig {
    /// Height of the seat surface above the floor, metres (0.3 to 0.75).
    pub seat_height: f32,
    /// Duration in seconds.
    pub duration: f32,
    /// Frames per second.
    pub fps: f32,
}

impl Default for SitConfig {
    fn default() -> Self {
        Self {
            seat_height: 0.45,
            duration: 2.0,
            fps: 30.0,
        }
    }
}

/// The angles of a seated body whose hips rest at `seat_height` with the feet on the floor.
fn seated(seat_height: f32) -> Gait {
    // Thighs level; the shank reaches forward and down to the floor. On a seat higher than
    // the shank is long (a bed's 0.55-0.75 m) the shank stands upright and the thighs slope
    // down from the hips to the knees, so the hips still rest on the seat.
    let reach = seat_height - ANKLE_HEIGHT;
    let drop = reach.clamp(0.0, SHANK);
    let shank = (drop / SHANK).acos();
    let tilt = ((reach - SHANK).max(0.0) / THIGH).min(1.0).asin();
    Gait {
        hip: [FRAC_PI_2 - tilt; 2],
        knee: [FRAC_PI_2 - tilt - shank; 2],
        shoulder: [0.35; 2],
        elbow: [0.9; 2],
        ..Gait::default()
    }
}

/// From standing to sitting: the feet stay planted, the hips fold back and down onto a seat
/// of `seat_height` while the torso leans forward and back up. The last frame's pelvis is above
/// the origin with the hips on the seat surface; its frames are [`Support::Standing`] until
/// the hips reach the seat, then [`Support::Sitting`].
///
/// # Errors
/// [`AffordanceError::InvalidInput`] for a seat outside 0.3-0.75 m or non-positive timing.
pub fn sit_down(config: &SitConfig) -> Result<PoseSequence> {
    check_positive("duration", config.duration)?;
    check_positive("fps", config.fps)?;
    if !(0.3..=0.75).contains(&config.seat_height) {
        return Err(AffordanceError::InvalidInput(format!(
            "seat height must be within 0.3-0.75 m, got {}",
            config.seat_height
        )));
    }
    let end = seated(config.seat_height);
    // Where the planted ankles are, relative to the seated pelvis.
    let ankle_x = end.leg(0).x;
    let frames = ((config.duration * config.fps).round() as usize).max(2);
    let mut poses = Vec::with_capacity(frames);
    let mut supports = Vec::with_capacity(frames);
    for i in 0..frames {
        let s = smoothstep(i as f32 / (frames - 1) as f32);
        let mut g = Gait {
            pitch: 0.6 * (PI * s).sin(),
            ..Gait::default()
        };
        for side in 0..2 {
            g.hip[side] = end.hip[side] * s;
            g.knee[side] = end.knee[side] * s;
            g.shoulder[side] = 0.05 + (end.shoulder[side] - 0.05) * s;
            g.elbow[side] = 0.1 + (end.elbow[side] - 0.1) * s;
        }
        // Keep the ankles where they are: the pelvis follows from the leg.
        let leg = g.leg(0);
        g.set_hip_centre(Vector3::new(ankle_x - leg.x, 0.0, ANKLE_HEIGHT - leg.z));
        supports.push(if s > 0.999 {
            Support::Sitting
        } else {
            Support::Standing
        });
        poses.push(g.pose());
    }
    PoseSequence::new(config.fps, Activity::SitDown, poses, supports)
}

/// Getting up from a seat: [`sit_down`] played backwards.
///
/// # Errors
/// As [`sit_down`].
pub fn get_up(config: &SitConfig) -> Result<PoseSequence> {
    let mut s = sit_down(config)?;
    s.frames.reverse();
    s.supports.reverse();
    s.activity = Activity::GetUp;
    Ok(s)
}

/// Lying down from sitting on the edge of a bed or sofa of `seat_height`: the torso tips back
/// to horizontal, the legs straighten onto the surface and the body slides back along -x by
/// `slide` metres. The body ends on its back along the x axis, head towards -x.
///
/// With `lift` 0 the knees straighten and the body slides together, over the whole
/// duration: the shanks still hang when the knees come over the edge, and on a surface
/// whose edge the hips sit near they sweep through it. With `lift` above 0 the legs come up
/// first (straight within that share of the duration, the torso tipping back meanwhile) and
/// the body slides back after, as a person swings the legs onto a bed before shuffling back.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LieConfig {
    /// Height of the lying surface, metres (0.3 to 0.75).
    pub seat_height: f32,
    /// How far the pelvis slides back from the edge, metres.
    pub slide: f32,
    /// Duration in seconds.
    pub duration: f32,
    /// Frames per second.
    pub fps: f32,
    /// The share of the duration (0 to below 1) in which the legs straighten before the body
    /// slides back; 0: both over the whole duration.
    #[serde(default)]
    pub lift: f32,
    /// How far the body turns about the vertical through the seated hips as the legs come up,
    /// radians (+ turns the legs to the left, -pi to pi): 0 lies straight back from the edge
    /// (a bed's foot end); a quarter turn swings the legs onto a bed or sofa from its side and
    /// lies along it.
    #[serde(default)]
    pub turn: f32,
}

impl Default for LieConfig {
    fn default() -> Self {
        Self {
            seat_height: 0.5,
            slide: 0.6,
            duration: 2.5,
            fps: 30.0,
            lift: 0.0,
            turn: 0.0,
        }
    }
}

/// See [`LieConfig`]. The first frame is seated at the origin ([`Support::Sitting`]), the
/// last lies on the back ([`Support::Lying`]); frames in between rest on the seat
/// ([`Support::Sitting`]).
///
/// # Errors
/// [`AffordanceError::InvalidInput`] for a surface outside 0.3-0.75 m, a negative slide,
/// a lift outside 0 to below 1, or non-positive timing.
pub fn lie_down(config: &LieConfig) -> Result<PoseSequence> {
    check_positive("duration", config.duration)?;
    check_positive("fps", config.fps)?;
    if !((0.3..=0.75).contains(&config.seat_height)
        && (0.0..3.0).contains(&config.slide)
        && (0.0..1.0).contains(&config.lift)
        && (-PI..=PI).contains(&config.turn))
    {
        return Err(AffordanceError::InvalidInput(format!(
            "lie down: surface height 0.3-0.75 m, slide 0-3 m, lift 0 to below 1 and turn \
             -pi to pi, got {config:?}"
        )));
    }
    let start = seated(config.seat_height);
    let frames = ((config.duration * config.fps).round() as usize).max(2);
    let mut poses = Vec::with_capacity(frames);
    let mut supports = Vec::with_capacity(frames);
    for i in 0..frames {
        let t = i as f32 / (frames - 1) as f32;
        let s = smoothstep(t);
        // The legs' progress and the slide's: together, or the legs first. With a turn the
        // legs straighten in the first half of the lift and swing round, raised clear of the
        // surface, in the second.
        let (legs, back) = if config.lift > 0.0 {
            let legs_span = if config.turn == 0.0 {
                config.lift
            } else {
                config.lift / 2.0
            };
            (
                smoothstep(t / legs_span),
                smoothstep((t - config.lift) / (1.0 - config.lift)),
            )
        } else {
            (s, s)
        };
        let swing = if config.lift > 0.0 {
            smoothstep((t - config.lift / 2.0) / (config.lift / 2.0))
        } else {
            legs
        };
        let raise = if config.turn == 0.0 {
            0.0
        } else {
            SWING_RAISE * (PI * swing).sin()
        };
        let mut g = Gait {
            pitch: -FRAC_PI_2 * s,
            ..Gait::default()
        };
        for side in 0..2 {
            g.hip[side] = start.hip[side] * (1.0 - legs) + FRAC_PI_2 * legs + raise;
            g.knee[side] = start.knee[side] * (1.0 - legs);
            g.shoulder[side] = start.shoulder[side] * (1.0 - s) + 0.1 * s;
            g.elbow[side] = start.elbow[side] * (1.0 - s) + 0.1 * s;
        }
        // The hips stay on the surface while the pelvis rolls back onto it; lying, the joints
        // sit 8 cm above the surface, inside the body as SMPL's do.
        g.set_hip_centre(Vector3::new(
            -config.slide * back,
            0.0,
            config.seat_height + 0.08 * s,
        ));
        // The head settles last: a frame a hair short of flat holds it just past the contact
        // tolerance, so with `lift` only the last frame lies (0 keeps the labels the shipped
        // models' training data was made with).
        let lies = if config.lift > 0.0 {
            i + 1 == frames
        } else {
            s > 0.999
        };
        supports.push(if lies {
            Support::Lying
        } else {
            Support::Sitting
        });
        // The turn swings the legs round with them, about the seated hips (the origin).
        let pose = g.pose();
        poses.push(if config.turn == 0.0 {
            pose
        } else {
            pose.rotated_about_z(config.turn * swing, &Point3::origin())
        });
    }
    PoseSequence::new(config.fps, Activity::LieDown, poses, supports)
}
