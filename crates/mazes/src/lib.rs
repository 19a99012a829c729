//! Maze worlds for envfield: seeded generators, datasets of exact distance fields, evaluation
//! pairs.
//!
//! - [`MazeGenerator`] with [`GeneratorKind`]: `gridworld` (the VIN benchmark's generator,
//!   [`Gridworld`]), `crossings` (Minigrid SimpleCrossing style), `rooms` (FourRooms /
//!   MultiRoom style), `perfect` (recursive backtracker), any size, seeded.
//! - [`Dataset`]: (maze, goal, exact distance field) samples, generated in parallel, with
//!   optional extra obstacles, a split by maze, and `.npy` save/load. The distances are
//!   encoded for training by the network's own encoding (`envfield_nets::TargetEncoding`).
//! - [`evaluation_pairs`]: the pairs the evaluation protocol runs on (`docs/evaluation.md` in
//!   the repository).
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
mod suite;

pub use dataset::{target_field, Dataset, DatasetConfig, Sample, TargetKind};
pub use error::{MazeError, Result};
pub use generators::{GeneratorKind, Gridworld, MazeGenerator};
pub use pairs::{evaluation_pairs, Pair};
pub use suite::{suite_sets, MazeSet};
