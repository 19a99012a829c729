//! Training VIN by imitation of optimal actions (cross-entropy), as Tamar et al. did.

use super::Vin;
use crate::params::AdamW;
use crate::{NetsError, Result};
use candle_core::Tensor;
use envfield_eikonal::dijkstra2;
use envfield_grid::{Cell2, Grid2, Maze, MoveRule, Neighbourhood2, SplitMix64, DIRECTIONS_8};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The optimal action at every free reachable cell (index into DIRECTIONS_8), or None.
fn optimal_actions(grid: &Grid2, goal: Cell2, rule: MoveRule) -> Result<Vec<Option<u8>>> {
    let nb = Neighbourhood2::Eight(rule);
    let d = dijkstra2(grid, &[goal], nb, std::f32::consts::SQRT_2)
        .map_err(|e| NetsError::InvalidInput(e.to_string()))?;
    Ok((0..grid.len())
        .map(|i| {
            let c = grid.cell(i);
            let here = d.get(c)?;
            if c == goal || !here.is_finite() {
                return None;
            }
            let mut best: Option<(u8, f32)> = None;
            for (k, &(dr, dc)) in DIRECTIONS_8.iter().enumerate() {
                if !rule.allows(grid, c, dr, dc) {
                    continue;
                }
                let to = c.offset(dr, dc)?;
                let cost = if dr != 0 && dc != 0 {
                    std::f32::consts::SQRT_2
                } else {
                    1.0
                };
                let total = cost + d.get(to).unwrap_or(f32::INFINITY);
                if best.is_none_or(|(_, b)| total < b - 1e-4) {
                    best = Some((k as u8, total));
                }
            }
            best.map(|(k, _)| k)
        })
        .collect())
}

/// How to train VIN: imitation of optimal actions (cross-entropy), Adam.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VinTrainConfig {
    /// Learning rate (VIN used RMSProp at 2e-3; Adam at 2e-3 here).
    pub lr: f64,
    /// Mazes per step.
    pub batch_mazes: usize,
    /// States (free reachable cells with their optimal action) per maze per step.
    pub states_per_maze: usize,
    /// Total steps.
    pub steps: u64,
    /// Seed of the batches.
    pub seed: u64,
}

impl Default for VinTrainConfig {
    fn default() -> Self {
        Self {
            lr: 2e-3,
            batch_mazes: 32,
            states_per_maze: 10,
            steps: 5000,
            seed: 0,
        }
    }
}

/// Trains a [`Vin`] on (maze, goal) pairs, checkpointing and resuming like [`crate::Trainer`].
#[derive(Debug)]
pub struct VinTrainer {
    net: Vin,
    optimiser: AdamW,
    config: VinTrainConfig,
}

/// One VIN training example: a maze, a goal, and the optimal action of each cell.
#[derive(Clone, Debug)]
pub struct VinExample {
    grid: Grid2,
    goal: Cell2,
    actions: Vec<Option<u8>>,
    states: Vec<usize>,
}

/// Builds VIN examples from mazes: each maze's own goal (or a random free cell), labelled by
/// exact graph distances under `rule`. Mazes where the goal reaches no other cell are skipped.
///
/// # Errors
/// A marked goal on an obstacle.
pub fn vin_examples(mazes: &[Maze], rule: MoveRule, seed: u64) -> Result<Vec<VinExample>> {
    let out: Result<Vec<Option<VinExample>>> = mazes
        .par_iter()
        .enumerate()
        .map(|(i, m)| {
            let free: Vec<Cell2> = m.grid.free_cells().collect();
            if free.is_empty() {
                return Ok(None);
            }
            let mut rng = SplitMix64::new(seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
            let goal = m.goal.unwrap_or_else(|| free[rng.below(free.len())]);
            let actions = optimal_actions(&m.grid, goal, rule)?;
            let states: Vec<usize> = (0..actions.len())
                .filter(|&i| actions[i].is_some())
                .collect();
            Ok((!states.is_empty()).then(|| VinExample {
                grid: m.grid.clone(),
                goal,
                actions,
                states,
            }))
        })
        .collect();
    Ok(out?.into_iter().flatten().collect())
}

impl VinTrainer {
    /// A trainer at step 0.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`].
    pub fn new(net: Vin, config: VinTrainConfig) -> Result<Self> {
        let bad = |field: &str, rule: &str, value: String| {
            Err(NetsError::InvalidConfig(format!(
                "vin training: {field} {rule} (got {value})"
            )))
        };
        if !(config.lr.is_finite() && config.lr > 0.0) {
            return bad("lr", "must be positive and finite", config.lr.to_string());
        }
        if !(1..=4096).contains(&config.batch_mazes) {
            return bad(
                "batch_mazes",
                "must be in 1..=4096",
                config.batch_mazes.to_string(),
            );
        }
        if !(1..=4096).contains(&config.states_per_maze) {
            return bad(
                "states_per_maze",
                "must be in 1..=4096",
                config.states_per_maze.to_string(),
            );
        }
        let optimiser = AdamW::new(net.store.vars(), config.lr, (0.9, 0.999), 1e-8, 0.0)?;
        Ok(Self {
            net,
            optimiser,
            config,
        })
    }

    /// Resumes from a checkpoint of [`VinTrainer::save_checkpoint`] with `config`.
    ///
    /// # Errors
    /// As [`Vin::load`]; a weight file without optimiser state.
    pub fn resume(path: impl AsRef<Path>, config: VinTrainConfig) -> Result<Self> {
        let path = path.as_ref();
        let (net, state) = Vin::load_with_state(path)?;
        let (m, v, step) = state.ok_or_else(|| NetsError::Checkpoint {
            path: path.to_path_buf(),
            reason: "a weight file, not a training checkpoint".into(),
        })?;
        let mut t = Self::new(net, config)?;
        t.optimiser.set_moments(m, v, step);
        Ok(t)
    }

    /// Steps done.
    pub fn step(&self) -> u64 {
        self.optimiser.step
    }

    /// The network.
    pub fn net(&self) -> &Vin {
        &self.net
    }

    /// The network, consuming the trainer.
    pub fn into_net(self) -> Vin {
        self.net
    }

    /// Writes weights, config, optimiser moments and step atomically.
    ///
    /// # Errors
    /// I/O errors naming the file.
    pub fn save_checkpoint(&self, path: impl AsRef<Path>) -> Result<()> {
        self.net.write(path.as_ref(), Some(&self.optimiser))
    }

    /// One step on a seeded batch of `examples` (all of one size); returns the loss.
    ///
    /// # Errors
    /// [`NetsError::Diverged`]; [`NetsError::InvalidInput`] for no examples.
    pub fn train_step(&mut self, examples: &[VinExample]) -> Result<f32> {
        if examples.is_empty() {
            return Err(NetsError::InvalidInput("no VIN examples".into()));
        }
        let mut rng = SplitMix64::new(
            self.config
                .seed
                .wrapping_mul(0x9E37_79B9)
                .wrapping_add(self.step()),
        );
        let picks: Vec<&VinExample> = (0..self.config.batch_mazes)
            .map(|_| &examples[rng.below(examples.len())])
            .collect();
        let grids: Vec<&Grid2> = picks.iter().map(|e| &e.grid).collect();
        let goals: Vec<Cell2> = picks.iter().map(|e| e.goal).collect();
        let mut states = Vec::new();
        let mut labels = Vec::new();
        for (b, e) in picks.iter().enumerate() {
            for _ in 0..self.config.states_per_maze {
                let i = e.states[rng.below(e.states.len())];
                states.push((b, e.grid.cell(i)));
                labels.push(e.actions[i].unwrap_or(0) as u32);
            }
        }
        let (h, w) = (grids[0].rows(), grids[0].cols());
        let q = self.net.q_maps(&grids, &goals)?;
        let logits = self.net.logits(&q, w, h, &states)?;
        let n = labels.len();
        let labels = Tensor::from_vec(labels, n, &self.net.device)?;
        let loss = candle_nn::loss::cross_entropy(&logits, &labels)?;
        let value = loss.to_scalar::<f32>()?;
        if !value.is_finite() {
            return Err(NetsError::Diverged {
                step: self.step(),
                loss: value,
            });
        }
        self.optimiser.backward_step(self.net.store.vars(), &loss)?;
        Ok(value)
    }
}
