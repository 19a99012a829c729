//! Eikonal solvers and exact graph distances on occupancy grids.
//!
//! The reaching-distance fields envfield learns (paper section 3.3, "the ground truth is
//! computed by the fast marching method") come from here, and so do the oracles that planners
//! and benchmarks compare learned models with.
//!
//! - [`FastMarching`]: first- or second-order fast marching in 2D and 3D, on unit speed
//!   (distance) or a speed map (travel time), several sources, grid spacing, an early stop, and
//!   exact initialisation around point sources (a diagonal neighbour is sqrt 2, not the 1.707 of
//!   scikit-fmm, its issue #47).
//! - [`dijkstra2`], [`dijkstra3`], [`bfs2`], [`bfs3`]: exact shortest paths on the move graph
//!   of a [`Neighbourhood2`](envfield_grid::Neighbourhood2) / `Neighbourhood3`.
//! - [`level_set`]: marching from the zero contour of a level-set function on grids of 1 to
//!   12 axes (signed distance, travel time, extension velocities; narrow band, periodic axes,
//!   masks), with scikit-fmm's semantics; [`level_set::descend`] walks back down a field.
//! - Many goals at once: [`FastMarching::solve2_many`], [`FastMarching::solve2_batch`],
//!   [`GraphDistance::solve_many`] (rayon).
//! - [`FastMarching`] and [`GraphDistance`] implement [`FieldModel`](envfield_grid::FieldModel).
//!
//! ```
//! use envfield_eikonal::{bfs2, FastMarching, Order};
//! use envfield_grid::{parse_mazes, Cell2, Neighbourhood2};
//!
//! let maze = &parse_mazes("#######\n#S#...#\n#.#.#.#\n#...#G#\n#######\n")?[0];
//! let goal = maze.goal.unwrap();
//! let field = FastMarching::with_order(Order::Second).solve2(&maze.grid, &[goal])?;
//! let start = maze.start.unwrap();
//! // The corridor from S to G is 10 steps long; fast marching agrees within a cell.
//! let steps = bfs2(&maze.grid, &[goal], Neighbourhood2::Four)?;
//! assert_eq!(steps.get(start), Some(10.0));
//! assert!((field.get(start).unwrap() - 10.0).abs() < 1.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod error;
mod fmm;
mod free;
mod graph;
mod heap;
pub mod level_set;
mod march;
mod sources;

pub use error::{EikonalError, Result};
pub use fmm::{FastMarching, Order, SolveOptions2, SolveOptions3};
pub use free::FreeCells3;
pub use graph::{bfs2, bfs3, dijkstra2, dijkstra3, GraphDistance};
