//! The VAE's training data type: one room's surface cloud and the torso locations of people in
//! it. Building it from rooms (walks, seats, beds, the floor grid) is envfield-rooms' job.

use serde::{Deserialize, Serialize};

/// Where a torso location came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TorsoSource {
    /// A frame of a walk along an exact floor path.
    Walk,
    /// A frame of sitting down onto a seat.
    Sit,
    /// A frame of lying down on a bed or sofa.
    Lie,
    /// A standing pose on the floor grid (the augmentation).
    Stand,
}

/// The pose a torso location affords: the classes of a VAE's pose-kind head, in its output
/// order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseKind {
    /// On the feet.
    Standing,
    /// On a seat.
    Sitting,
    /// On the back.
    Lying,
}

impl PoseKind {
    /// The three kinds in the head's output order.
    pub const ALL: [PoseKind; 3] = [PoseKind::Standing, PoseKind::Sitting, PoseKind::Lying];

    /// This kind's index among the head's outputs.
    pub fn index(self) -> usize {
        self as usize
    }
}

/// One room's training data: its surface cloud and the torso locations of valid poses in it.
#[derive(Clone, Debug, PartialEq)]
pub struct RoomTorsos {
    /// Surface points of the room, metres.
    pub cloud: Vec<[f32; 3]>,
    /// Torso (pelvis) locations, metres.
    pub torsos: Vec<[f32; 3]>,
    /// Where each torso location came from.
    pub sources: Vec<TorsoSource>,
    /// The pose each torso location affords (the first supported and collision-free one of
    /// standing, sitting and lying), `None` for none. A VAE with pose kinds trains only on
    /// torsos that have one.
    pub kinds: Vec<Option<PoseKind>>,
}
