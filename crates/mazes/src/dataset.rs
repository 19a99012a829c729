//! Datasets of (maze, goal, exact distance field) samples.

use crate::{MazeError, MazeGenerator, Result};
use envfield_eikonal::{dijkstra2, FastMarching, Order};
use envfield_grid::{
    Cell2, Field2, Grid2, MoveRule, Neighbourhood2, NpyArray, NpyData, SplitMix64,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Which exact field supervises the targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum TargetKind {
    /// Fast marching (the paper's choice); sees no diagonal gaps.
    FastMarching(Order),
    /// Exact graph distance under a move rule (orthogonal 1, diagonal sqrt 2).
    Graph(MoveRule),
}

impl std::str::FromStr for TargetKind {
    type Err = MazeError;

    /// `fmm1` or `fmm2` (fast marching of that order), or a move rule (`strict`, `vin`: the
    /// graph distance under it).
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "fmm1" => Ok(Self::FastMarching(Order::First)),
            "fmm2" => Ok(Self::FastMarching(Order::Second)),
            rule => rule.parse().map(Self::Graph).map_err(|_| {
                MazeError::InvalidConfig(format!(
                    "unknown target `{s}` (fmm1, fmm2, strict or vin)"
                ))
            }),
        }
    }
}

impl std::fmt::Display for TargetKind {
    /// The name [`TargetKind::from_str`](std::str::FromStr) reads: `fmm1`, `fmm2`, `strict`
    /// or `vin`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::FastMarching(Order::First) => f.write_str("fmm1"),
            Self::FastMarching(Order::Second) => f.write_str("fmm2"),
            Self::Graph(rule) => write!(f, "{rule}"),
        }
    }
}

impl TargetKind {
    /// The move rule the target's paths follow: the graph's rule, `strict` for fast marching
    /// (its 4-neighbour stencil cuts no corner).
    pub fn rule(self) -> MoveRule {
        match self {
            Self::Graph(rule) => rule,
            Self::FastMarching(_) => MoveRule::Strict,
        }
    }
}

/// How to build a dataset.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DatasetConfig {
    /// The maze generator.
    pub generator: MazeGenerator,
    /// Number of mazes.
    pub mazes: usize,
    /// Goals per maze (the maze's own goal first, then random free cells).
    pub goals_per_maze: usize,
    /// Target field.
    pub target: TargetKind,
    /// Fraction of free cells (other than the goal) turned into obstacles at random, the
    /// paper's stand-in for other agents; 0 disables it.
    pub extra_obstacles: f32,
    /// Seed of everything random.
    pub seed: u64,
}

/// One training sample: a grid, a goal and the exact reaching distance of every cell
/// (row-major). A network's target encoding (`envfield_nets::TargetEncoding`) turns the
/// distances into training targets.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// Index of the maze this sample was made from (for splitting by maze).
    pub maze: usize,
    /// The occupancy grid (with any extra obstacles).
    pub grid: Grid2,
    /// The goal.
    pub goal: Cell2,
    /// The exact field's distance in cells, one value per cell; `f32::INFINITY` on obstacles
    /// and unreachable cells.
    pub distance: Vec<f32>,
}

/// A set of samples of one grid size.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    /// The samples.
    pub samples: Vec<Sample>,
}

/// The exact field of `grid` for `goal` under `kind`.
///
/// # Errors
/// From the solvers (a goal on an obstacle, ...).
pub fn target_field(grid: &Grid2, goal: Cell2, kind: TargetKind) -> Result<Field2> {
    Ok(match kind {
        TargetKind::FastMarching(order) => FastMarching::with_order(order).solve2(grid, &[goal])?,
        TargetKind::Graph(rule) => dijkstra2(
            grid,
            &[goal],
            Neighbourhood2::Eight(rule),
            std::f32::consts::SQRT_2,
        )?,
    })
}

impl Dataset {
    /// Generates the dataset in parallel (rayon). Deterministic for a config.
    ///
    /// # Errors
    /// [`MazeError::InvalidConfig`] for an out-of-range setting; generator errors.
    pub fn generate(cfg: &DatasetConfig) -> Result<Self> {
        if cfg.mazes == 0 || cfg.goals_per_maze == 0 || !(0.0..0.9).contains(&cfg.extra_obstacles) {
            return Err(MazeError::InvalidConfig(format!(
                "a dataset needs mazes >= 1, goals_per_maze >= 1 and extra_obstacles in [0, 0.9) \
                 (got {}, {}, {})",
                cfg.mazes, cfg.goals_per_maze, cfg.extra_obstacles
            )));
        }
        let per_maze: Result<Vec<Vec<Sample>>> = (0..cfg.mazes)
            .into_par_iter()
            .map(|i| {
                let maze_seed = cfg.seed.wrapping_mul(1_000_003).wrapping_add(i as u64);
                let maze = cfg.generator.generate(maze_seed)?;
                let mut rng = SplitMix64::new(maze_seed ^ 0x5EED);
                let free: Vec<Cell2> = maze.grid.free_cells().collect();
                let mut out = Vec::with_capacity(cfg.goals_per_maze);
                for k in 0..cfg.goals_per_maze {
                    let goal = match (k, maze.goal) {
                        (0, Some(g)) => g,
                        _ => free[rng.below(free.len())],
                    };
                    let mut grid = maze.grid.clone();
                    if cfg.extra_obstacles > 0.0 {
                        for &c in &free {
                            if c != goal
                                && (rng.below(1 << 20) as f32)
                                    < cfg.extra_obstacles * (1 << 20) as f32
                            {
                                grid.set_obstacle(c, true)?;
                            }
                        }
                    }
                    let field = target_field(&grid, goal, cfg.target)?;
                    out.push(Sample {
                        maze: i,
                        grid,
                        goal,
                        distance: field.values().to_vec(),
                    });
                }
                Ok(out)
            })
            .collect();
        Ok(Self {
            samples: per_maze?.into_iter().flatten().collect(),
        })
    }

    /// Splits by maze: samples of mazes with index `< train_mazes` go to the first set, the
    /// rest to the second. No maze is in both.
    pub fn split_by_maze(self, train_mazes: usize) -> (Dataset, Dataset) {
        let (a, b): (Vec<Sample>, Vec<Sample>) =
            self.samples.into_iter().partition(|s| s.maze < train_mazes);
        (Dataset { samples: a }, Dataset { samples: b })
    }

    /// Saves the dataset as `.npy` files in folder `dir` (created if needed), each written
    /// atomically: `obstacles.npy` (N, H, W bool), `goals.npy` (N, 2 float64 row, col),
    /// `mazes.npy` (N float64 maze index), `distances.npy` (N, H, W float32, infinite where
    /// blocked).
    ///
    /// # Errors
    /// [`MazeError::Dataset`] when the samples differ in size or the set is empty; I/O errors.
    pub fn save(&self, dir: impl AsRef<Path>) -> Result<()> {
        let dir = dir.as_ref();
        let bad = |m: &str| MazeError::Dataset {
            path: dir.display().to_string(),
            message: m.into(),
        };
        let first = self
            .samples
            .first()
            .ok_or_else(|| bad("no samples to save"))?;
        let (h, w) = (first.grid.rows(), first.grid.cols());
        if self
            .samples
            .iter()
            .any(|s| (s.grid.rows(), s.grid.cols()) != (h, w))
        {
            return Err(bad("samples have different grid sizes"));
        }
        std::fs::create_dir_all(dir).map_err(|e| bad(&e.to_string()))?;
        let n = self.samples.len();
        let arr = |shape: Vec<usize>, data| NpyArray { shape, data };
        arr(
            vec![n, h, w],
            NpyData::Bool(
                self.samples
                    .iter()
                    .flat_map(|s| s.grid.obstacles().iter().copied())
                    .collect(),
            ),
        )
        .write(dir.join("obstacles.npy"))?;
        arr(
            vec![n, 2],
            NpyData::F64(
                self.samples
                    .iter()
                    .flat_map(|s| [s.goal.row as f64, s.goal.col as f64])
                    .collect(),
            ),
        )
        .write(dir.join("goals.npy"))?;
        arr(
            vec![n],
            NpyData::F64(self.samples.iter().map(|s| s.maze as f64).collect()),
        )
        .write(dir.join("mazes.npy"))?;
        arr(
            vec![n, h, w],
            NpyData::F32(
                self.samples
                    .iter()
                    .flat_map(|s| s.distance.iter().copied())
                    .collect(),
            ),
        )
        .write(dir.join("distances.npy"))?;
        Ok(())
    }

    /// Loads a dataset saved by [`Dataset::save`], checking that the files agree.
    ///
    /// # Errors
    /// [`MazeError::Dataset`] naming the inconsistency; I/O and format errors.
    pub fn load(dir: impl AsRef<Path>) -> Result<Self> {
        let dir = dir.as_ref();
        let bad = |m: String| MazeError::Dataset {
            path: dir.display().to_string(),
            message: m,
        };
        let obstacles = NpyArray::read(dir.join("obstacles.npy"))?;
        let goals = NpyArray::read(dir.join("goals.npy"))?;
        let mazes = NpyArray::read(dir.join("mazes.npy"))?;
        let distances = NpyArray::read(dir.join("distances.npy"))?;
        let [n, h, w] = obstacles.shape[..] else {
            return Err(bad(format!(
                "obstacles.npy has shape {:?}, expected (N, H, W)",
                obstacles.shape
            )));
        };
        if goals.shape != [n, 2] || mazes.shape != [n] || distances.shape != [n, h, w] {
            return Err(bad(format!(
                "shapes disagree: obstacles {:?}, goals {:?}, mazes {:?}, distances {:?}",
                obstacles.shape, goals.shape, mazes.shape, distances.shape
            )));
        }
        let (NpyData::Bool(obs), NpyData::F64(goals), NpyData::F64(ids), NpyData::F32(distances)) =
            (obstacles.data, goals.data, mazes.data, distances.data)
        else {
            return Err(bad(
                "unexpected dtypes (bool, float64, float64, float32 expected)".into(),
            ));
        };
        let cells = h * w;
        let mut samples = Vec::with_capacity(n);
        for i in 0..n {
            let grid = Grid2::from_obstacles(h, w, obs[i * cells..(i + 1) * cells].to_vec())?;
            let goal = Cell2::new(goals[2 * i] as usize, goals[2 * i + 1] as usize);
            grid.check_free(goal, "goal")
                .map_err(|e| bad(format!("sample {i}: {e}")))?;
            samples.push(Sample {
                maze: ids[i] as usize,
                grid,
                goal,
                distance: distances[i * cells..(i + 1) * cells].to_vec(),
            });
        }
        Ok(Self { samples })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::GeneratorKind;

    #[test]
    fn save_load_round_trip_and_split() {
        let cfg = DatasetConfig {
            generator: MazeGenerator::new(GeneratorKind::Gridworld, 8).unwrap(),
            mazes: 6,
            goals_per_maze: 2,
            target: TargetKind::Graph(MoveRule::Vin),
            extra_obstacles: 0.05,
            seed: 3,
        };
        let ds = Dataset::generate(&cfg).unwrap();
        assert_eq!(ds.samples.len(), 12);
        let none = DatasetConfig { mazes: 0, ..cfg };
        assert!(Dataset::generate(&none)
            .unwrap_err()
            .to_string()
            .contains("mazes >= 1"));
        assert_eq!(ds, Dataset::generate(&cfg).unwrap());
        for s in &ds.samples {
            let gi = s.grid.index(s.goal).unwrap();
            assert_eq!(s.distance[gi], 0.0);
            for (i, &d) in s.distance.iter().enumerate() {
                // Obstacles are infinite; free cells may be too (cut off from the goal).
                assert!(!s.grid.obstacles()[i] || d.is_infinite());
            }
        }
        let dir = std::env::temp_dir().join(format!("envfield-ds-{}", std::process::id()));
        ds.save(&dir).unwrap();
        let back = Dataset::load(&dir).unwrap();
        assert_eq!(back, ds);
        std::fs::remove_file(dir.join("goals.npy")).unwrap();
        assert!(Dataset::load(&dir).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
        let (train, val) = ds.split_by_maze(4);
        assert!(
            train.samples.iter().all(|s| s.maze < 4) && val.samples.iter().all(|s| s.maze >= 4)
        );
        assert_eq!(train.samples.len() + val.samples.len(), 12);
    }
}
