//! Where people can be in a room (paper section 4.2): a conditional VAE of human torso
//! locations given the scene's point cloud, the accessible region its samples give, and the
//! exact and learned 3D environment fields over that region.
//!
//! - [`Cvae`]: a PointNet scene encoder (a shared per-point MLP and a max pool, so the feature
//!   does not depend on the points' order) and a conditional VAE: [`Cvae::encode`] maps
//!   (scene, torso xyz) to a diagonal Gaussian, [`Cvae::decode`] maps (z, scene) back to a
//!   torso xyz, [`Cvae::sample`] draws seeded samples. Weights are safetensors files with
//!   their [`VaeConfig`] in the metadata, written atomically.
//! - [`VaeTrainer`]: reconstruction plus KL with the cyclical annealing schedule of Fu et al.
//!   (NAACL 2019), Adam at the paper's 5e-5 by default, seeded batches, checkpoints that
//!   resume exactly.
//! - Training data made here ([`room_torsos`]): torso locations of valid poses along walks
//!   on exact floor paths, sitting down on every seat, lying down on beds and sofas, and every
//!   supported, collision-free standing pose on a floor grid (the paper's augmentation).
//! - [`AccessibleRegion`]: samples kept by what a torso can afford (see [`region`]),
//!   voxelised into one connected set, written as PLY and PNG; [`region_quality`] judges a
//!   set of samples by the share that affords a pose and by floor and seat coverage.
//! - [`ExactField3`] (fast marching over the accessible voxels, metres) and
//!   [`LearnedField3`] (the goal-conditioned network of envfield-nets, trained per scene by
//!   [`train_field3`]) are both [`ContinuousField3`](envfield_grid::ContinuousField3)s, so a
//!   planner treats them alike.
//!
//! ```
//! use envfield_vae::{Cvae, VaeConfig};
//!
//! let vae = Cvae::new(VaeConfig::default(), 7)?;
//! let cloud: Vec<[f32; 3]> = (0..64).map(|i| [i as f32 * 0.1, 1.0, 0.0]).collect();
//! let torsos = vae.sample(&cloud, 5, 1)?; // untrained, but any cloud works
//! assert_eq!(torsos.len(), 5);
//! assert!(vae.sample(&[], 5, 1).is_err()); // an empty cloud is refused
//! # Ok::<(), envfield_vae::VaeError>(())
//! ```

mod config;
mod data;
mod error;
mod field3;
mod model;
mod nav;
pub mod region;
mod train;

pub use config::{GateConfig, LocalConfig, VaeConfig, VaeTrainConfig};
pub use data::{
    lie_on, room_torsos, rooms_torsos, seat_grid, seat_torsos, sit_on, standing_floor, RoomTorsos,
    TorsoDataConfig, TorsoSource,
};
pub use error::{Result, VaeError};
pub use field3::{train_field3, ExactField3, Field3Config, Field3Report, LearnedField3};
pub use model::{normals, Cvae};
pub use nav::{offset, point, PoseFilter};
pub use region::{
    afford, afford_all, covered_pct, region_quality, uniform_in_room, AccessibleRegion, Afford,
    RegionConfig, RegionQuality,
};
pub use train::{VaeProgress, VaeTrainer};
