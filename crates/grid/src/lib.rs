//! Occupancy grids, scalar fields and the conventions every envfield crate shares.
//!
//! This is the core of envfield ("Learning Continuous Environment Fields via Implicit
//! Functions", ICLR 2022): the types the solvers, datasets, networks and planners exchange. It
//! pulls in nothing heavy (no tensor or geometry library).
//!
//! - [`Grid2`] / [`Grid3`]: occupancy grids indexed by [`Cell2`] `(row, col)` and
//!   [`Cell3`] `(x, y, z)`.
//! - [`Field2`] / [`Field3`]: f32 scalar fields with bilinear / trilinear sampling at
//!   [`Point2`] / [`Point3`]; `f32::INFINITY` marks unreachable cells.
//! - [`MoveRule`] (`strict`, `vin`) and [`Neighbourhood2`] / [`Neighbourhood3`]: who steps where.
//! - The maze text format ([`parse_mazes`], [`read_mazes`], [`write_mazes`]), PNG input and
//!   heat-map output ([`HeatMapStyle`]), `.npy` input/output ([`NpyArray`]), and
//!   [`Canvas`], the picture kit (dots, segments, discs; PNG and GIF).
//! - [`FieldModel`]: "the reaching-distance field of this grid for this goal", implemented by
//!   the exact solvers and by every learned model.
//! - [`Symmetry`]: the eight transposes and flips of a grid, under which both move rules look
//!   the same; [`Symmetric`] averages any [`FieldModel`] over several of them.
//! - What planners and learners share: [`descent_move`], [`is_wrong_move`],
//!   [`octile_distance`] and the [`Policy`] trait (one move at a time, as VIN decides).
//! - [`SplitMix64`], the seeded generator every crate draws from; [`synth`], random obstacle
//!   layouts for tests and benchmarks.
//!
//! ```
//! use envfield_grid::{parse_mazes, Cell2, MoveRule, Neighbourhood2};
//!
//! let mazes = parse_mazes("#####\n#S..#\n#.#G#\n#####\n")?;
//! let maze = &mazes[0];
//! assert_eq!(maze.goal, Some(Cell2::new(2, 3)));
//! let steps: Vec<_> = maze
//!     .grid
//!     .neighbours(Cell2::new(1, 2), Neighbourhood2::Eight(MoveRule::Strict))
//!     .map(|(cell, _len)| cell)
//!     .collect();
//! // Both diagonals below pass the wall at (2, 2), so under `strict` only the two orthogonal
//! // steps remain.
//! assert_eq!(steps, vec![Cell2::new(1, 1), Cell2::new(1, 3)]);
//! # Ok::<(), envfield_grid::GridError>(())
//! ```

mod canvas;
mod cell;
mod components;
mod ensemble;
mod error;
mod field;
mod grid;
mod io;
mod maze;
mod model;
mod moves;
mod npy;
mod png;
mod rng;
mod steps;
mod symmetry;
pub mod synth;

pub use canvas::{height_colour, tint, viridis, Canvas};
pub use cell::{Cell2, Cell3, Point2, Point3};
pub use components::Components;
pub use ensemble::Ensemble;
pub use error::{GridError, Result};
pub use field::{sample_finite_within, Field2, Field3};
pub use grid::{Grid2, Grid3};
pub use io::{check_writable, protect_input, write_atomic};
pub use maze::{format_mazes, parse_mazes, read_mazes, write_mazes, Maze};
pub use model::{ContinuousField2, ContinuousField3, FieldModel, Point3m};
pub use moves::{MoveRule, Neighbourhood2, Neighbourhood3, DIRECTIONS_8};
pub use npy::{NpyArray, NpyData};
pub use png::{HeatMapStyle, MAX_PNG_PIXELS, OBSTACLE_COLOR, UNREACHABLE_COLOR};
pub use rng::{normals, SplitMix64};
pub use steps::{descent_move, is_wrong_move, octile_distance, Policy};
pub use symmetry::{Symmetric, Symmetry};
