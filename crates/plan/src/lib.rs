//! Planning on environment fields, and the evaluation harness.
//!
//! - [`Planner`]: plan from a start to a goal on a grid; [`PlanOutcome`] holds the path.
//! - [`FieldDescent`]: predict the whole field once with any
//!   [`FieldModel`](envfield_grid::FieldModel), then step to the best neighbour under a
//!   [`MoveRule`](envfield_grid::MoveRule) (paper section 4.1).
//! - [`RelayDescent`]: descent that, when its walk fails, plans again through a relay cell
//!   found from the start's and the goal's fields, so no leg relies on a field far from its
//!   goal.
//! - [`gradient_descent`]: fixed-length steps against the gradient of a continuous field
//!   (paper Fig. 3c).
//! - [`AStar`]: octile A* under either move rule.
//! - [`evaluate`]: the maze evaluation protocol (`docs/evaluation.md` in the repository:
//!   success within 2 x the fewest path cells, path ratio over successes, milliseconds per
//!   path), rechecking every path itself.
//! - [`PolicyWalk`]: a planner for any [`Policy`](envfield_grid::Policy) (one decision per
//!   step, as VIN makes them).
//! - [`space3`]: the pose-dependent search on a continuous 3D field (paper section 4.2,
//!   [`space3::FieldSearch3`]), each step's 26 candidates asked in one batch and filtered by a
//!   [`space3::StepFilter`]; and the sampling baselines RRT, RRT* and PRM on any
//!   [`space3::Space3`].
//! - [`crowd`]: several people on one floor map at once (paper Algorithm 1,
//!   [`crowd::walk_crowd`]), each person's field on the map the others change, one batched
//!   prediction per time step; and [`crowd::orca_crowd`], the ORCA crowd loop beside it.
//! - [`PlannerKind`]: planners by name (`field`, `relay`, `octile`, `fmm`, `astar`, ...), the
//!   names the examples and benchmarks take.
//!
//! ```
//! use envfield_eikonal::FastMarching;
//! use envfield_grid::{parse_mazes, MoveRule};
//! use envfield_plan::{evaluate, AStar, EvalConfig, FieldDescent};
//!
//! let mazes = parse_mazes("#######\n#S#...#\n#.#.#.#\n#...#G#\n#######\n")?;
//! let cfg = EvalConfig { rule: MoveRule::Strict, pairs_per_maze: 1, seed: 0 };
//! let fmm = FieldDescent::new(FastMarching::default(), MoveRule::Strict);
//! let report = evaluate(&fmm, &mazes, &cfg, &mut |_, _| {})?;
//! assert_eq!(report.summary.success_rate, 100.0);
//! let astar = evaluate(&AStar { rule: MoveRule::Strict }, &mazes, &cfg, &mut |_, _| {})?;
//! assert!((astar.summary.path_ratio - 1.0).abs() < 1e-6);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod astar;
pub mod crowd;
mod descent;
mod error;
mod gradient;
mod harness;
mod named;
mod planner;
mod policy;
mod profile;
mod relay;
pub mod space3;

pub use astar::{AStar, Octile};
pub use descent::{descend, FieldDescent};
pub use error::{PlanError, Result};
pub use gradient::{gradient_descent, ContinuousPath, GradientDescentConfig};
pub use harness::{
    evaluate, evaluate_pairs, is_legal_walk, summary_table, EvalConfig, PairResult, Report, Summary,
};
pub use named::{BoxedField, BoxedPolicy, Learned, NamedPlanner, PlannerKind, PlannerOptions};
pub use planner::{path_length, PlanOutcome, Planner};
pub use policy::PolicyWalk;
pub use profile::{Band, DecisionProfile};
pub use relay::{relay_cells, remove_loops, RelayDescent};
