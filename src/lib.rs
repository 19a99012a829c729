//! envfield: learned continuous environment fields for navigation.
//!
//! One name for the whole workspace. Each crate is re-exported under a short module name:
//!
//! - [`grid`]: grids, fields, move rules, the maze text format, PNG/.npy I/O, `FieldModel`.
//! - [`eikonal`]: fast marching (2D/3D, first/second order) and exact graph distances.
//! - [`mazes`]: maze generators, datasets of target fields, evaluation pairs.
//! - [`nets`] (feature `nets`): implicit field networks (plain, goal, context-aligned,
//!   hypernetwork), VIN, training; [`models`] loads the weights planners by name need.
//! - [`plan`]: planners (field descent, relays, gradient descent, A*, any policy), planners by
//!   name, and the evaluation harness.
//! - [`scene`] (feature `scene`): signed-distance 3D scenes, OBJ/PLY, synthetic rooms, the
//!   bird's-eye floor map.
//! - [`affordance`] (feature `scene`): SMPL-layout poses and sequences, procedural motions,
//!   support and collision checks, alignment to trajectories.
//! - [`vae`] (feature `vae`): the conditional VAE of torso locations and its trainer.
//! - [`rooms`] (feature `rooms`): people in furnished rooms: accessible regions, exact and
//!   learned 3D fields, pose filters, the room navigation harness and the crowd protocol.
//!
//! Three ways in:
//!
//! 1. **A field**: `eikonal::FastMarching::solve2` / `solve3` on your grid (below), or a
//!    learned one, `nets::FieldNet::load`; both answer `grid::FieldModel`.
//! 2. **A 2D path**: `plan::FieldDescent::new(model, rule).plan(&grid, start, goal, steps)`
//!    on any `FieldModel`; several people at once with `plan::crowd`.
//! 3. **A region and a 3D path**: `rooms::sample_region` (or `rooms::standing_torsos` for a
//!    game level) gives a scene's accessible region, `rooms::ExactField3` its field, and
//!    `rooms::harness::run_pair` every planner's path with its poses checked; the
//!    `envfield-rooms` crate doc runs one on a generated room.
//!
//! The four features are on by default. With `default-features = false` envfield is grids, fast
//! marching, mazes and planners, and pulls in neither candle nor parry3d. The `cuda` feature
//! runs the networks on an NVIDIA GPU through candle.
//!
//! ```
//! use envfield::eikonal::FastMarching;
//! use envfield::grid::{Cell2, Grid2};
//!
//! let grid = Grid2::new(9, 9)?;
//! let field = FastMarching::default().solve2(&grid, &[Cell2::new(4, 4)])?;
//! assert_eq!(field.get(Cell2::new(4, 7)), Some(3.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#[cfg(feature = "nets")]
pub mod models;

#[cfg(feature = "scene")]
pub use envfield_affordance as affordance;
pub use envfield_eikonal as eikonal;
pub use envfield_grid as grid;
pub use envfield_mazes as mazes;
#[cfg(feature = "nets")]
pub use envfield_nets as nets;
pub use envfield_plan as plan;
#[cfg(feature = "rooms")]
pub use envfield_rooms as rooms;
#[cfg(feature = "scene")]
pub use envfield_scene as scene;
#[cfg(feature = "vae")]
pub use envfield_vae as vae;

// The README's Rust example runs as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
