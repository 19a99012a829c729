//! People in furnished rooms (paper sections 4.1 and 4.2): where a person can be, how far
//! every place is from a goal, and how a body walks, sits and lies there.
//!
//! - Training data for the VAE ([`room_torsos`]): torso locations of valid poses along walks
//!   on exact floor paths, sitting down on every seat, lying down on beds and sofas, and
//!   every supported, collision-free standing pose on a floor grid (the paper's
//!   augmentation), as the [`RoomTorsos`](envfield_vae::RoomTorsos) envfield-vae trains on.
//! - [`AccessibleRegion`]: torso samples kept by what a torso can afford (see [`region`]),
//!   voxelised into one connected set, written as PLY and PNG; [`region_quality`] judges a
//!   set of samples by the share that affords a pose and by floor and seat coverage.
//! - [`ExactField3`] (fast marching over the accessible voxels, metres) and
//!   [`LearnedField3`] (the goal-conditioned network of envfield-nets, trained per scene by
//!   [`train_field3`]) are both [`ContinuousField3`](envfield_grid::ContinuousField3)s, so a
//!   planner treats them alike. Either becomes a [`VoxelField3`] once per goal (the fast
//!   marching is one already; [`LearnedField3::tabulate`] is one batched network pass), so a
//!   search step reads it by interpolation.
//! - [`PoseFilter`] and the region as envfield-plan's [`StepFilter`](envfield_plan::space3::StepFilter)
//!   and [`Space3`](envfield_plan::space3::Space3): what the 3D planners may step to.
//! - [`harness`]: the room tables (paper Tables 3 and 4): planners by name
//!   ([`PlannerKind`](harness::PlannerKind)), walking and sit-down pairs, one run of every
//!   planner with its poses fitted and checked; [`tables`] sums them up; [`pictures`] draws
//!   them.
//! - [`birdseye`]: several people on one floor (section 4.1): floor maps, the bird's-eye
//!   field's training maps, the crowd table's tallies and the frames of a run.
//!
//! ```no_run
//! use envfield_rooms::{AccessibleRegion, ExactField3, RegionConfig};
//! use envfield_grid::ContinuousField3;
//! use envfield_scene::{generate_room, RoomConfig};
//!
//! let room = generate_room(&RoomConfig::default(), 3)?;
//! // Torso samples from anywhere (a VAE's, or a grid of your own), kept by the filter.
//! let samples: Vec<[f32; 3]> = (0..40)
//!     .flat_map(|i| (0..30).map(move |j| [0.1 + 0.1 * i as f32, 0.1 + 0.1 * j as f32, 0.93]))
//!     .collect();
//! let region = AccessibleRegion::from_drawn(&room.scene, &samples, &RegionConfig::default())?;
//! let field = ExactField3::new(&region, region.samples[0])?;
//! println!("{:.2} m", field.value(region.samples[1])?);
//! # Ok::<(), envfield_rooms::RoomsError>(())
//! ```

pub mod birdseye;
mod error;
pub mod field3;
pub mod field3_store;
mod field3_train;
pub mod harness;
pub mod nav;
pub mod pictures;
pub mod quality;
pub mod region;
pub mod sampling;
pub mod surfaces;
pub mod tables;
pub mod torsos;

pub use error::{Result, RoomsError};
pub use field3::{ExactField3, LearnedField3, VoxelField3};
pub use field3_store::FieldStore;
pub use field3_train::{train_field3, Field3Config, Field3Report};
pub use nav::{PoseFilter, SceneTables};
pub use region::{AccessibleRegion, RegionConfig, SitDown};
pub use sampling::{draw_torsos, sample_region};
pub use surfaces::standing_torsos;
