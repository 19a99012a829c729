//! The conditional VAE of human torso locations (paper section 4.2): given a scene's surface
//! points, where a person's torso can be.
//!
//! - [`Cvae`]: a PointNet scene encoder (a shared per-point MLP and a max pool, so the feature
//!   does not depend on the points' order) and a conditional VAE. [`Cvae::sample`] draws
//!   seeded torso locations with its [`SampleOptions`]. Three variants ([`VaeKind`]): the
//!   paper's VAE over the whole scene ([`VaeConfig::default`], whose encoder and decoder
//!   [`Cvae::as_whole`] gives), the local VAE reading the surface points around an anchor
//!   ([`VaeConfig::local`]; [`Cvae::as_local`] draws next to anchors of one's own), and the
//!   gated local VAE ([`VaeConfig::local_gated`]), whose occupancy head picks the anchors
//!   someone can be at ([`Cvae::as_gated`]) and whose pose-kind head picks standing, sitting
//!   or lying before the decoder places the torso. Weights are safetensors files with their
//!   [`VaeConfig`] in the metadata, written atomically.
//! - [`VaeTrainer`]: reconstruction plus KL with the cyclical annealing schedule of Fu et al.
//!   (NAACL 2019), Adam at the paper's 5e-5 by default, seeded batches, checkpoints that
//!   resume exactly.
//! - [`RoomTorsos`]: the training data, one room's cloud and its torso locations with where
//!   each came from and the pose it affords. envfield-rooms makes it from furnished rooms.
//!
//! ```
//! use envfield_vae::{Cvae, SampleOptions, VaeConfig};
//!
//! let vae = Cvae::new(VaeConfig::default(), 7)?;
//! let cloud: Vec<[f32; 3]> = (0..64).map(|i| [i as f32 * 0.1, 1.0, 0.0]).collect();
//! let torsos = vae.sample(&cloud, &SampleOptions::new(5, 1))?; // untrained, but any cloud works
//! assert_eq!(torsos.len(), 5);
//! assert!(vae.sample(&[], &SampleOptions::new(5, 1)).is_err()); // an empty cloud is refused
//! assert!(vae.as_local().is_none()); // the paper's VAE draws no anchors of yours
//! # Ok::<(), envfield_vae::VaeError>(())
//! ```

mod config;
mod data;
mod error;
mod file;
mod index;
mod loss;
mod model;
mod sample;
mod train;

pub use config::{GateConfig, LocalConfig, VaeConfig, VaeTrainConfig};
pub use data::{PoseKind, RoomTorsos, TorsoSource};
pub use error::{Result, VaeError};
pub use model::{Cvae, VaeKind, NORMAL_SALT};
pub use sample::{Gate, Gated, Neighbourhoods, SampleOptions, WholeScene};
pub use train::{VaeProgress, VaeTrainer};
