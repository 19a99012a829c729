//! Training VIN as Tamar et al. did: imitation of the actions of shortest-path trajectories
//! (cross-entropy), RMSProp, epochs over rows of states that share one map and goal.

use super::kernel::{self, Weights};
use super::{map_input, Vin};
use crate::{NetsError, Result};
use envfield_eikonal::dijkstra2;
use envfield_grid::{Cell2, Grid2, Maze, MoveRule, Neighbourhood2, SplitMix64, DIRECTIONS_8};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The optimal actions at every free reachable cell (a bit per index into DIRECTIONS_8, 0 at
/// the goal and at cells that cannot reach it).
fn optimal_actions(grid: &Grid2, goal: Cell2, rule: MoveRule) -> Result<Vec<u8>> {
    let nb = Neighbourhood2::Eight(rule);
    let d = dijkstra2(grid, &[goal], nb, std::f32::consts::SQRT_2)
        .map_err(|e| NetsError::InvalidInput(e.to_string()))?;
    Ok((0..grid.len())
        .map(|i| {
            let c = grid.cell(i);
            let Some(here) = d.get(c).filter(|h| h.is_finite() && c != goal) else {
                return 0;
            };
            let mut mask = 0u8;
            for (k, &(dr, dc)) in DIRECTIONS_8.iter().enumerate() {
                if !rule.allows(grid, c, dr, dc) {
                    continue;
                }
                let Some(to) = c.offset(dr, dc) else { continue };
                let cost = if dr != 0 && dc != 0 {
                    std::f32::consts::SQRT_2
                } else {
                    1.0
                };
                if (cost + d.get(to).unwrap_or(f32::INFINITY) - here).abs() < 1e-3 {
                    mask |= 1 << k;
                }
            }
            mask
        })
        .collect())
}

/// One map of the data: its maze, its goal's flat index and every cell's optimal actions.
#[derive(Clone, Debug)]
struct DataMap {
    grid: Grid2,
    goal: usize,
}

/// One state of a trajectory: its cell, the action taken (the label) and every optimal action
/// there (bits of DIRECTIONS_8), which the accuracy counts as right.
#[derive(Clone, Copy, Debug)]
struct State {
    cell: usize,
    label: u8,
    optimal: u8,
}

/// Up to [`VinData::STATES_PER_ROW`] states of one map: one value-iteration pass serves them.
#[derive(Clone, Debug)]
struct Row {
    map: usize,
    states: Vec<State>,
}

/// VIN's training data for one maze size, made as VIN's scripts make it: for each map, its
/// goal and trajectories from random starts along shortest paths under the move rule, every
/// state labelled with the action taken; the states of a map in rows of 10 (VIN's
/// `statebatchsize`), each row one value-iteration pass.
#[derive(Clone, Debug)]
pub struct VinData {
    maps: Vec<DataMap>,
    rows: Vec<Row>,
}

impl VinData {
    /// States per row (VIN's `statebatchsize`).
    pub const STATES_PER_ROW: usize = 10;

    /// `trajectories` shortest-path trajectories per maze (VIN used 7) from random reachable
    /// starts to the maze's goal (or a random free cell when it marks none); a maze's own
    /// start, when it marks one, begins its first trajectory. Mazes whose goal reaches no
    /// other cell are left out.
    ///
    /// # Errors
    /// [`NetsError::InvalidInput`] for mazes of different sizes or a marked goal or start on an
    /// obstacle.
    pub fn generate(
        mazes: &[Maze],
        rule: MoveRule,
        trajectories: usize,
        seed: u64,
    ) -> Result<Self> {
        if let Some(m) = mazes.iter().find(|m| {
            (m.grid.rows(), m.grid.cols()) != (mazes[0].grid.rows(), mazes[0].grid.cols())
        }) {
            return Err(NetsError::InvalidInput(format!(
                "VIN data mixes maze sizes: {}x{} and {}x{}",
                mazes[0].grid.rows(),
                mazes[0].grid.cols(),
                m.grid.rows(),
                m.grid.cols()
            )));
        }
        let per_map: Vec<Option<(DataMap, Vec<State>)>> = mazes
            .par_iter()
            .enumerate()
            .map(|(i, m)| Self::trajectories(m, rule, trajectories, seed, i))
            .collect::<Result<_>>()?;
        let mut data = Self {
            maps: Vec::new(),
            rows: Vec::new(),
        };
        for (map, states) in per_map.into_iter().flatten() {
            let index = data.maps.len();
            data.maps.push(map);
            for chunk in states.chunks(Self::STATES_PER_ROW) {
                data.rows.push(Row {
                    map: index,
                    states: chunk.to_vec(),
                });
            }
        }
        Ok(data)
    }

    fn trajectories(
        m: &Maze,
        rule: MoveRule,
        count: usize,
        seed: u64,
        i: usize,
    ) -> Result<Option<(DataMap, Vec<State>)>> {
        let free: Vec<Cell2> = m.grid.free_cells().collect();
        if free.is_empty() {
            return Ok(None);
        }
        let mut rng = SplitMix64::new(seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let goal = match m.goal {
            Some(g) => g,
            None => free[rng.below(free.len())],
        };
        let goal_index = m.grid.check_free(goal, "goal")?;
        let optimal = optimal_actions(&m.grid, goal, rule)?;
        let starts: Vec<usize> = (0..m.grid.len()).filter(|&c| optimal[c] != 0).collect();
        if starts.is_empty() {
            return Ok(None);
        }
        let mut states = Vec::new();
        for t in 0..count {
            let mut cell = match (t, m.start) {
                (0, Some(s)) => m.grid.check_free(s, "start")?,
                _ => starts[rng.below(starts.len())],
            };
            // Each step lowers the distance, so a trajectory ends within the map's cells.
            while optimal[cell] != 0 && states.len() < (t + 1) * m.grid.len() {
                let label = optimal[cell].trailing_zeros() as u8;
                states.push(State {
                    cell,
                    label,
                    optimal: optimal[cell],
                });
                let (dr, dc) = DIRECTIONS_8[label as usize];
                let next = m.grid.cell(cell).offset(dr, dc);
                let Some(next) = next.and_then(|c| m.grid.index(c)) else {
                    break;
                };
                cell = next;
            }
        }
        let map = DataMap {
            grid: m.grid.clone(),
            goal: goal_index,
        };
        Ok(Some((map, states)))
    }

    /// Maps (mazes with a goal that reaches somewhere).
    pub fn maps(&self) -> usize {
        self.maps.len()
    }

    /// Rows (one value-iteration pass each in an epoch).
    pub fn rows(&self) -> usize {
        self.rows.len()
    }

    /// Labelled states.
    pub fn states(&self) -> usize {
        self.rows.iter().map(|r| r.states.len()).sum()
    }

    /// The share of states (0 to 1) where `vin`'s highest logit is an optimal action: VIN's
    /// per-state accuracy, on these trajectories. `None` without states.
    pub fn action_accuracy(&self, vin: &Vin) -> Option<f64> {
        let right: usize = self
            .rows
            .par_iter()
            .map(|row| {
                let map = &self.maps[row.map];
                let input = map_input(&map.grid, map.goal);
                let wt = vin.weights();
                let fwd = kernel::forward(wt, input, vin.config().iterations, false);
                row.states
                    .iter()
                    .filter(|s| {
                        let z = kernel::logits(wt, &fwd.q, map.grid.len(), s.cell);
                        let best = (0..z.len()).fold(0, |b, k| if z[k] > z[b] { k } else { b });
                        s.optimal & (1 << best) != 0
                    })
                    .count()
            })
            .sum();
        let n = self.states();
        (n > 0).then(|| right as f64 / n as f64)
    }
}

/// How to train VIN: VIN's published settings by default (RMSProp at 2e-3, 12 rows of 10
/// states per step, 30 epochs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VinTrainConfig {
    /// Learning rate.
    pub lr: f64,
    /// RMSProp's decay of the mean square (VIN's 0.9).
    pub rho: f64,
    /// Added to the mean square under the root (VIN's 1e-6).
    pub eps: f64,
    /// Rows per step (VIN's `batchsize`, 12).
    pub batch_rows: usize,
    /// Passes over the data.
    pub epochs: u64,
    /// Seed of the epochs' orders.
    pub seed: u64,
}

impl Default for VinTrainConfig {
    fn default() -> Self {
        Self {
            lr: 2e-3,
            rho: 0.9,
            eps: 1e-6,
            batch_rows: 12,
            epochs: 30,
            seed: 0,
        }
    }
}

/// Trains a [`Vin`] on [`VinData`], a step being one batch of rows in a seeded order per
/// epoch; checkpoints resume exactly (weights, RMSProp's mean squares, step).
#[derive(Debug)]
pub struct VinTrainer {
    net: Vin,
    squares: Weights,
    step: u64,
    config: VinTrainConfig,
    order: Option<(u64, Vec<u32>)>,
}

/// What one step saw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VinStep {
    /// The mean cross-entropy over the batch's states.
    pub loss: f32,
    /// States in the batch.
    pub states: usize,
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
        if !(config.rho.is_finite() && (0.0..1.0).contains(&config.rho)) {
            return bad("rho", "must be in [0, 1)", config.rho.to_string());
        }
        if !(config.eps.is_finite() && config.eps > 0.0) {
            return bad("eps", "must be positive and finite", config.eps.to_string());
        }
        if !(1..=4096).contains(&config.batch_rows) {
            return bad(
                "batch_rows",
                "must be in 1..=4096",
                config.batch_rows.to_string(),
            );
        }
        let squares = net.weights().zeros_like();
        Ok(Self {
            net,
            squares,
            step: 0,
            config,
            order: None,
        })
    }

    /// Resumes from a checkpoint of [`VinTrainer::save_checkpoint`] with `config`.
    ///
    /// # Errors
    /// As [`Vin::load`]; a weight file without optimiser state.
    pub fn resume(path: impl AsRef<Path>, config: VinTrainConfig) -> Result<Self> {
        let path = path.as_ref();
        let (net, state) = Vin::load_with_state(path)?;
        let (squares, step) = state.ok_or_else(|| NetsError::Checkpoint {
            path: path.to_path_buf(),
            reason: "a weight file, not a training checkpoint".into(),
        })?;
        let mut t = Self::new(net, config)?;
        t.squares = squares;
        t.step = step;
        Ok(t)
    }

    /// Steps done.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// Steps in one epoch over `data`.
    pub fn steps_per_epoch(&self, data: &VinData) -> u64 {
        data.rows().div_ceil(self.config.batch_rows) as u64
    }

    /// All the steps of the configured epochs over `data`.
    pub fn total_steps(&self, data: &VinData) -> u64 {
        self.steps_per_epoch(data)
            .saturating_mul(self.config.epochs)
    }

    /// The network.
    pub fn net(&self) -> &Vin {
        &self.net
    }

    /// The network, consuming the trainer.
    pub fn into_net(self) -> Vin {
        self.net
    }

    /// Writes weights, config, RMSProp's mean squares and the step atomically.
    ///
    /// # Errors
    /// I/O errors naming the file.
    pub fn save_checkpoint(&self, path: impl AsRef<Path>) -> Result<()> {
        self.net
            .write(path.as_ref(), Some((&self.squares, self.step)))
    }

    /// The rows of the current step: the next slice of this epoch's seeded order.
    fn batch(&mut self, data: &VinData) -> Vec<u32> {
        let per_epoch = self.steps_per_epoch(data);
        let epoch = self.step / per_epoch;
        if self.order.as_ref().is_none_or(|(e, _)| *e != epoch) {
            let mut rng = SplitMix64::new(
                self.config
                    .seed
                    .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                    .wrapping_add(epoch),
            );
            let mut order: Vec<u32> = (0..data.rows() as u32).collect();
            for i in (1..order.len()).rev() {
                order.swap(i, rng.below(i + 1));
            }
            self.order = Some((epoch, order));
        }
        let order = self.order.as_ref().map_or(&[][..], |(_, o)| &o[..]);
        let at = ((self.step % per_epoch) as usize) * self.config.batch_rows;
        order[at..(at + self.config.batch_rows).min(order.len())].to_vec()
    }

    /// One RMSProp step on the next batch of `data`'s rows.
    ///
    /// # Errors
    /// [`NetsError::InvalidInput`] for no data or data of another size than the last;
    /// [`NetsError::Diverged`] for a non-finite loss.
    pub fn train_step(&mut self, data: &VinData) -> Result<VinStep> {
        if data.rows.is_empty() {
            return Err(NetsError::InvalidInput("no VIN training rows".into()));
        }
        let batch = self.batch(data);
        let iterations = self.net.config().iterations;
        let wt = self.net.weights();
        let zero = || (wt.zeros_like(), 0f32, 0usize);
        let (mut grad, loss, states) = batch
            .par_iter()
            .fold(zero, |(mut g, loss, n), &r| {
                let row = &data.rows[r as usize];
                let map = &data.maps[row.map];
                let input = map_input(&map.grid, map.goal);
                let fwd = kernel::forward(wt, input, iterations, true);
                let labelled: Vec<(usize, u8)> =
                    row.states.iter().map(|s| (s.cell, s.label)).collect();
                let l = kernel::backward(wt, &fwd, &labelled, &mut g);
                (g, loss + l, n + labelled.len())
            })
            .reduce(zero, |(mut g, l1, n1), (h, l2, n2)| {
                g.add(&h);
                (g, l1 + l2, n1 + n2)
            });
        let mean = loss / states.max(1) as f32;
        if !mean.is_finite() {
            return Err(NetsError::Diverged {
                step: self.step,
                loss: mean,
            });
        }
        let scale = 1.0 / states.max(1) as f32;
        let (lr, rho, eps) = (
            self.config.lr as f32,
            self.config.rho as f32,
            self.config.eps as f32,
        );
        let weights = self.net.weights_mut();
        for ((w, s), g) in weights
            .parts_mut()
            .into_iter()
            .zip(self.squares.parts_mut())
            .zip(grad.parts_mut())
        {
            for ((w, s), g) in w.iter_mut().zip(s.iter_mut()).zip(g.iter_mut()) {
                let g = *g * scale;
                *s = rho * *s + (1.0 - rho) * g * g;
                *w -= lr * g / (*s + eps).sqrt();
            }
        }
        self.step += 1;
        Ok(VinStep { loss: mean, states })
    }
}
