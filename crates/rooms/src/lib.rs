//! People in furnished rooms (paper sections 4.1 and 4.2): where a person can be, how far
//! every place is from a goal, and how a body walks, sits and lies there.
//!
//! Three ways in, from the least to the most:
//!
//! 1. **A field.** [`AccessibleRegion`] is where a torso can be: samples (a VAE's through
//!    [`sample_region`] and [`draw_torsos`], a level's own surfaces through
//!    [`standing_torsos`], or any you have) kept by the torso filter of
//!    [`envfield_affordance::afford`], voxelised into one connected set with the sit-downs
//!    that join its seats. [`ExactField3`] (fast marching over its voxels, metres) and
//!    [`LearnedField3`] (the goal-conditioned network, trained per scene by [`train_field3`],
//!    kept on disk by [`FieldStore`]) are both
//!    [`ContinuousField3`](envfield_grid::ContinuousField3)s; either becomes a
//!    [`VoxelField3`] once per goal.
//! 2. **A 2D path.** [`birdseye`]: several people on one floor, the bird's-eye field's
//!    training maps and the crowd table's tallies (the planners themselves are
//!    `envfield_plan`'s).
//! 3. **A region and a 3D path.** [`harness`]: pairs of a start and a goal with the pose
//!    sequence a body follows ([`harness::pairs`]), and every planner on them with its poses
//!    fitted and checked ([`harness::run_pair`]): ours (the pose-dependent search on either
//!    field, under [`PoseFilter`]), RRT, RRT*, PRM, the line, a navigation mesh.
//!
//! The rest: [`quality`] (how good a region is, the held-out protocol), [`torsos`] (the VAE's
//! training data), [`sampling`] (VAE samples and their density), [`nav`] (the filters and the
//! scene's tables), [`tables`] and [`pictures`] (the room tables and their pictures).
//!
//! A standing body's walk across a generated room, on the exact field, every pose checked:
//!
//! ```
//! use envfield_rooms::harness::{pairs, run_pair, PairOptions, RoomPlanner, RoomContext};
//! use envfield_rooms::{standing_torsos, AccessibleRegion, RegionConfig};
//! use envfield_scene::{generate_room, RoomConfig};
//!
//! let room = generate_room(&RoomConfig::default(), 3)?;
//! // A standing torso over every floor column 0.2 m apart, kept by the torso filter.
//! let config = RegionConfig { voxel: 0.2, ..RegionConfig::default() };
//! let torsos = standing_torsos(&room.scene, config.voxel)?;
//! let region = AccessibleRegion::from_drawn(&room.scene, &torsos, &config.in_place())?;
//! let options = PairOptions { walks: 1, min_distance: 2.0, sit_downs: false, lie_downs: false, ..PairOptions::default() };
//! let pair = &pairs(None, &room.scene, &region, &options)?[0];
//! let runs = run_pair(
//!     &RoomContext::bare(&room.scene, &region),
//!     pair,
//!     &[RoomPlanner::OursExact],
//!     &Default::default(),
//! )?;
//! let ours = &runs[0].outcome;
//! assert!(ours.reached && ours.path_ratio < 1.5);
//! println!("{} steps, {:.0}% of the poses valid", runs[0].path.len(), ours.poses.valid);
//! # Ok::<(), envfield_rooms::RoomsError>(())
//! ```

pub mod birdseye;
mod error;
pub mod field3;
pub mod field3_store;
mod field3_train;
pub mod harness;
pub mod nav;
pub mod party;
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
pub use region::{
    AccessibleRegion, BuildTimes, LeftOut, LieDown, RegionConfig, SitDown, LEFT_OUT_LEVEL_M,
    LEFT_OUT_NAMED_M2, LEFT_OUT_STOREY_M2, LIE_LIFT, LIE_ROOM, LIE_SLIDES, LIE_TURNS,
    PASSAGE_CLEARANCE,
};
pub use sampling::{draw_torsos, sample_region};
pub use surfaces::standing_torsos;
