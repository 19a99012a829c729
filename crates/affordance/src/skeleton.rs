//! The SMPL 22-joint skeleton, poses and pose sequences, and their JSON form.

use std::path::Path;

use nalgebra::{Point3, Rotation3, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::{AffordanceError, Result};

/// The 22 body joints of SMPL, in SMPL's order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum Joint {
    Pelvis,
    LeftHip,
    RightHip,
    Spine1,
    LeftKnee,
    RightKnee,
    Spine2,
    LeftAnkle,
    RightAnkle,
    Spine3,
    LeftFoot,
    RightFoot,
    Neck,
    LeftCollar,
    RightCollar,
    Head,
    LeftShoulder,
    RightShoulder,
    LeftElbow,
    RightElbow,
    LeftWrist,
    RightWrist,
}

/// Number of joints in a [`Pose`].
pub const JOINT_COUNT: usize = 22;

impl Joint {
    /// All joints in SMPL order (the index of a joint is its position here).
    pub const ALL: [Joint; JOINT_COUNT] = [
        Joint::Pelvis,
        Joint::LeftHip,
        Joint::RightHip,
        Joint::Spine1,
        Joint::LeftKnee,
        Joint::RightKnee,
        Joint::Spine2,
        Joint::LeftAnkle,
        Joint::RightAnkle,
        Joint::Spine3,
        Joint::LeftFoot,
        Joint::RightFoot,
        Joint::Neck,
        Joint::LeftCollar,
        Joint::RightCollar,
        Joint::Head,
        Joint::LeftShoulder,
        Joint::RightShoulder,
        Joint::LeftElbow,
        Joint::RightElbow,
        Joint::LeftWrist,
        Joint::RightWrist,
    ];

    /// Its SMPL index.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Its snake-case name (`"left_hip"`), as in the JSON files.
    pub fn name(self) -> &'static str {
        const NAMES: [&str; JOINT_COUNT] = [
            "pelvis",
            "left_hip",
            "right_hip",
            "spine1",
            "left_knee",
            "right_knee",
            "spine2",
            "left_ankle",
            "right_ankle",
            "spine3",
            "left_foot",
            "right_foot",
            "neck",
            "left_collar",
            "right_collar",
            "head",
            "left_shoulder",
            "right_shoulder",
            "left_elbow",
            "right_elbow",
            "left_wrist",
            "right_wrist",
        ];
        NAMES[self.index()]
    }

    /// The joint with this name.
    pub fn from_name(name: &str) -> Option<Joint> {
        Joint::ALL.into_iter().find(|j| j.name() == name)
    }

    /// Its children in SMPL's kinematic tree, in SMPL order (none for a hand, foot or head).
    pub fn children(self) -> impl Iterator<Item = Joint> {
        Joint::ALL
            .into_iter()
            .filter(move |c| c.parent() == Some(self))
    }

    /// Its parent in SMPL's kinematic tree (`None` for the pelvis, the root).
    pub fn parent(self) -> Option<Joint> {
        use Joint::*;
        Some(match self {
            Pelvis => return None,
            LeftHip | RightHip | Spine1 => Pelvis,
            LeftKnee => LeftHip,
            RightKnee => RightHip,
            Spine2 => Spine1,
            LeftAnkle => LeftKnee,
            RightAnkle => RightKnee,
            Spine3 => Spine2,
            LeftFoot => LeftAnkle,
            RightFoot => RightAnkle,
            Neck | LeftCollar | RightCollar => Spine3,
            Head => Neck,
            LeftShoulder => LeftCollar,
            RightShoulder => RightCollar,
            LeftElbow => LeftShoulder,
            RightElbow => RightShoulder,
            LeftWrist => LeftElbow,
            RightWrist => RightElbow,
        })
    }
}

/// Joint positions in metres (world frame, z up), indexed by [`Joint::index`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Positions in SMPL joint order.
    pub joints: [Point3<f32>; JOINT_COUNT],
}

impl Pose {
    /// The position of one joint.
    pub fn joint(&self, joint: Joint) -> Point3<f32> {
        self.joints[joint.index()]
    }

    /// The torso position the planners move (the pelvis).
    pub fn torso(&self) -> Point3<f32> {
        self.joint(Joint::Pelvis)
    }

    /// The height of its lowest joint: for a standing pose, the soles' level.
    pub fn lowest(&self) -> f32 {
        self.joints
            .iter()
            .map(|j| j.z)
            .fold(f32::INFINITY, f32::min)
    }

    /// The horizontal direction the body faces: perpendicular to the hip axis, pointing forward
    /// (for a body facing +x the left hip is at +y).
    pub fn facing(&self) -> Vector3<f32> {
        let across = self.joint(Joint::LeftHip) - self.joint(Joint::RightHip);
        let f = Vector3::new(across.y, -across.x, 0.0);
        f.try_normalize(1e-9).unwrap_or_else(Vector3::x)
    }

    /// Moved by `offset`.
    pub fn translated(&self, offset: &Vector3<f32>) -> Pose {
        Pose {
            joints: self.joints.map(|p| p + offset),
        }
    }

    /// Rotated by `angle` radians about the vertical axis through `pivot`.
    pub fn rotated_about_z(&self, angle: f32, pivot: &Point3<f32>) -> Pose {
        let r = Rotation3::from_axis_angle(&Vector3::z_axis(), angle);
        Pose {
            joints: self.joints.map(|p| pivot + r * (p - pivot)),
        }
    }

    /// Checks that every coordinate is finite.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidInput`] naming the first bad joint.
    pub fn validate(&self) -> Result<()> {
        match self
            .joints
            .iter()
            .position(|p| !p.iter().all(|v| v.is_finite()))
        {
            None => Ok(()),
            Some(i) => Err(AffordanceError::InvalidInput(format!(
                "joint {} is not finite: {:?}",
                Joint::ALL[i].name(),
                self.joints[i].coords.as_slice()
            ))),
        }
    }
}

/// What holds a body up: the joints a support check looks at.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Support {
    /// On the feet (either foot may be lifted, as in walking).
    Standing,
    /// On the torso and laps: pelvis and both hips (paper section 4.2).
    Sitting,
    /// On the back: pelvis, hips, spine and head.
    Lying,
}

impl Support {
    /// The support joints.
    pub fn joints(self) -> &'static [Joint] {
        match self {
            Support::Standing => &[Joint::LeftFoot, Joint::RightFoot],
            Support::Sitting => &[Joint::Pelvis, Joint::LeftHip, Joint::RightHip],
            Support::Lying => &[
                Joint::Pelvis,
                Joint::LeftHip,
                Joint::RightHip,
                Joint::Spine3,
                Joint::Head,
            ],
        }
    }

    /// Whether contact of any one support joint is enough (standing: one foot can swing).
    pub fn any_joint_suffices(self) -> bool {
        self == Support::Standing
    }
}

/// What a sequence shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Activity {
    /// A gait cycle, repeated along a path.
    Walk,
    /// From standing to sitting.
    SitDown,
    /// From sitting to standing.
    GetUp,
    /// From sitting on an edge to lying on the back.
    LieDown,
    /// Anything loaded from motion capture.
    Other,
}

/// Frames of poses at a frame rate, each with the support it relies on.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseSequence {
    /// Frames per second.
    pub fps: f32,
    /// What it shows.
    pub activity: Activity,
    /// The poses.
    pub frames: Vec<Pose>,
    /// The support of each frame (same length as `frames`).
    pub supports: Vec<Support>,
}

/// The JSON form: joint names once, then frames of `[x, y, z]` triples in that order.
#[derive(Serialize, Deserialize)]
struct SequenceFile {
    fps: f32,
    activity: Activity,
    joints: Vec<String>,
    frames: Vec<Vec<[f32; 3]>>,
    #[serde(default)]
    supports: Option<Vec<Support>>,
}

impl PoseSequence {
    /// A sequence, checked.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidInput`] for no frames, a non-positive frame rate, a support
    /// list of another length, or a non-finite joint (naming the frame and joint).
    pub fn new(
        fps: f32,
        activity: Activity,
        frames: Vec<Pose>,
        supports: Vec<Support>,
    ) -> Result<Self> {
        let s = Self {
            fps,
            activity,
            frames,
            supports,
        };
        s.validate()?;
        Ok(s)
    }

    /// The checks of [`PoseSequence::new`], for a sequence whose public fields may have been
    /// edited since.
    pub(crate) fn validate(&self) -> Result<()> {
        if !(self.fps.is_finite() && self.fps > 0.0) {
            return Err(AffordanceError::InvalidInput(format!(
                "frame rate must be positive, got {}",
                self.fps
            )));
        }
        if self.frames.is_empty() || self.frames.len() != self.supports.len() {
            return Err(AffordanceError::InvalidInput(format!(
                "a sequence needs frames and one support per frame, got {} frames and {} supports",
                self.frames.len(),
                self.supports.len()
            )));
        }
        for (i, f) in self.frames.iter().enumerate() {
            f.validate()
                .map_err(|e| AffordanceError::InvalidInput(format!("frame {i}: {e}")))?;
        }
        Ok(())
    }

    /// Mean distance between consecutive torso positions (metres per frame): how far the
    /// planner moves per frame when it follows this sequence. 0 for one frame.
    pub fn step_length(&self) -> f32 {
        let n = self.frames.len();
        if n < 2 {
            return 0.0;
        }
        let total: f32 = self
            .frames
            .windows(2)
            .map(|w| nalgebra::distance(&w[0].torso(), &w[1].torso()))
            .sum();
        total / (n - 1) as f32
    }

    /// Duration in seconds.
    pub fn duration(&self) -> f32 {
        self.frames.len() as f32 / self.fps
    }

    /// The JSON text: `{"fps", "activity", "joints": [22 names], "frames": [[[x, y, z] x 22]
    /// ...], "supports": [...]}`.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidInput`] when the sequence was edited into an invalid one
    /// (its fields are public): no frames, a support list of another length, a non-finite
    /// joint or frame rate.
    pub fn to_json(&self) -> Result<String> {
        self.validate()?;
        let file = SequenceFile {
            fps: self.fps,
            activity: self.activity,
            joints: Joint::ALL.iter().map(|j| j.name().to_string()).collect(),
            frames: self
                .frames
                .iter()
                .map(|f| f.joints.iter().map(|p| <[f32; 3]>::from(*p)).collect())
                .collect(),
            supports: Some(self.supports.clone()),
        };
        serde_json::to_string(&file)
            .map_err(|e| AffordanceError::InvalidInput(format!("pose sequence JSON: {e}")))
    }

    /// Parses the JSON form. Joints may come in any order (by name); `supports` may be left
    /// out (then every frame is [`Support::Standing`]).
    ///
    /// # Errors
    /// [`AffordanceError::InvalidInput`] for malformed JSON, unknown or missing joint names,
    /// a frame with the wrong number of joints, or non-finite values (naming frame and joint).
    pub fn from_json(text: &str) -> Result<Self> {
        let bad = |m: String| AffordanceError::InvalidInput(m);
        let file: SequenceFile =
            serde_json::from_str(text).map_err(|e| bad(format!("pose sequence JSON: {e}")))?;
        let mut order = Vec::with_capacity(file.joints.len());
        for name in &file.joints {
            order.push(
                Joint::from_name(name).ok_or_else(|| bad(format!("unknown joint `{name}`")))?,
            );
        }
        let mut sorted = order.clone();
        sorted.sort();
        sorted.dedup();
        if sorted.len() != JOINT_COUNT || order.len() != JOINT_COUNT {
            return Err(bad(format!(
                "`joints` must name each of the {JOINT_COUNT} SMPL joints once, got {} names",
                file.joints.len()
            )));
        }
        let mut frames = Vec::with_capacity(file.frames.len());
        for (i, f) in file.frames.iter().enumerate() {
            if f.len() != JOINT_COUNT {
                return Err(bad(format!(
                    "frame {i} has {} joints, not {JOINT_COUNT}",
                    f.len()
                )));
            }
            let mut joints = [Point3::origin(); JOINT_COUNT];
            for (p, j) in f.iter().zip(&order) {
                joints[j.index()] = Point3::from(*p);
            }
            frames.push(Pose { joints });
        }
        let supports = file
            .supports
            .unwrap_or_else(|| vec![Support::Standing; frames.len()]);
        Self::new(file.fps, file.activity, frames, supports)
    }

    /// Reads a JSON file.
    ///
    /// # Errors
    /// [`AffordanceError::Io`]; [`AffordanceError::Format`] for the errors of
    /// [`PoseSequence::from_json`].
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| AffordanceError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_json(&text).map_err(|e| AffordanceError::Format {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })
    }

    /// Writes the JSON file atomically.
    ///
    /// # Errors
    /// As [`PoseSequence::to_json`]; I/O errors.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        envfield_grid::write_atomic(path, self.to_json()?.as_bytes())
            .map_err(|e| AffordanceError::Scene(e.into()))
    }
}
