//! Human poses in 3D scenes: the SMPL 22-joint skeleton, pose sequences, procedural motions,
//! and the affordance checks of paper section 4.2 and appendix A.2 (a pose is *supported*
//! when its support joints rest on a surface, *collision-free* when no other joint is inside
//! geometry, *valid* when both hold).
//!
//! - [`Joint`], [`Pose`], [`PoseSequence`] (JSON in and out), [`Support`], [`Activity`].
//! - Procedural, seeded motions so nothing needs motion capture: [`walk`], [`sit_down`],
//!   [`get_up`], [`lie_down`], [`standing_pose`]. Bodies face +x, metres, z up.
//! - [`check_pose`] / [`check_sequence`] against an [`envfield_scene::Scene`].
//! - [`sit_on`] and [`lie_on`]: those motions placed on a piece of furniture.
//! - The torso filter an accessible region is made with ([`afford`], [`afford_all`],
//!   [`FilterConfig`]): whether some supported, [`plausible`] pose has its torso at a point.
//! - [`align_to_trajectory`] and [`align_in_scene`] (with the +-6 degree search the paper uses
//!   for getting up); [`PoseSequence::step_length`] for the 3D planner's step.
//!
//! ```
//! use envfield_affordance::{check_pose, standing_pose, AffordanceConfig, Support};
//! use envfield_scene::{generate_room, RoomConfig};
//! use nalgebra::Vector3;
//!
//! let room = generate_room(&RoomConfig::default(), 3)?;
//! // Stand on a free cell of the room's bird's-eye floor map.
//! let map = envfield_scene::floor_map(&room.scene, &Default::default())?;
//! let cell = map.grid.free_cells().nth(map.grid.free_count() / 2).unwrap();
//! let [x, y] = map.frame.center(cell);
//! let pose = standing_pose().translated(&Vector3::new(x, y, 0.0));
//! let report = check_pose(&room.scene, &pose, Support::Standing, &AffordanceConfig::default())?;
//! assert!(report.supported);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod align;
mod bvh;
mod check;
mod error;
mod filter;
mod gltf_out;
mod motion;
mod place;
mod skeleton;

pub use align::{align_in_scene, align_to_trajectory, resample_path, walk_along, AlignConfig};
pub use bvh::{bvh_order, bvh_text, write_bvh};
pub use check::{
    bones_clear, check_pose, check_sequence, pose_supported, pose_valid, AffordanceConfig,
    AffordanceReport,
};
pub use error::{AffordanceError, Result};
pub use filter::{afford, afford_all, plausible, Afford, FilterConfig, MAX_TORSO_RADIUS};
pub use gltf_out::{glb_bytes, write_glb, Actor};
pub use motion::{
    get_up, lie_down, sit_down, standing_pose, walk, LieConfig, SitConfig, WalkConfig,
};
pub use place::{lie_on, sit_on};
pub use skeleton::{Activity, Joint, Pose, PoseSequence, Support, JOINT_COUNT};
