//! Maze worlds for envfield: seeded generators, datasets of target fields, evaluation pairs.
//!
//! - [`MazeGenerator`] with [`GeneratorKind`]: `gridworld` (the VIN benchmark's generator,
//!   [`Gridworld`]), `crossings` (Minigrid SimpleCrossing style), `rooms` (FourRooms /
//!   MultiRoom style), `perfect` (recursive backtracker), any size, seeded.
//! - [`Dataset`]: (maze, goal, target) samples in parallel, with the paper's target encoding
//!   ([`encode_target`], appendix A.4), optional extra obstacles, a split by maze, and
//!   `.npy` save/load.
//! - [`evaluation_pairs`]: the pairs DESIGN.md's evaluation protocol runs on.
//!
//! ```
//! use envfield_grid::MoveRule;
//! use envfield_mazes::{evaluation_pairs, GeneratorKind, MazeGenerator};
//!
//! let mazes = MazeGenerator::new(GeneratorKind::Rooms, 21)?.generate_many(5, 0)?;
//! let pairs = evaluation_pairs(&mazes, MoveRule::Strict, 3, 0)?;
//! assert_eq!(pairs.len(), 15);
//! # Ok::<(), envfield_mazes::MazeError>(())
//! ```

mod dataset;
mod error;
mod generators;
mod pairs;

pub use dataset::{
    decode_target, encode_target, target_field, Dataset, DatasetConfig, Sample, TargetKind,
    BLOCKED_TARGET,
};
pub use error::{MazeError, Result};
pub use generators::{GeneratorKind, Gridworld, MazeGenerator};
pub use pairs::{evaluation_pairs, Pair};
