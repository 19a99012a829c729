//! Training: L1 on the paper's target encoding, AdamW, seeded batches, atomic checkpoints that
//! resume exactly.

use crate::model::{read_config, Batch, FieldNet, TargetEncoding};
use crate::params::{ema_name, AdamW, TensorFile, META_STEP};
use crate::{NetsError, Result};
use candle_core::{Device, Tensor};
use envfield_grid::synth::SplitMix64;
use envfield_grid::{Cell2, Grid2, MoveRule, DIRECTIONS_8};
use envfield_mazes::{Dataset, Sample};
use envfield_plan::is_wrong_move;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::Path;
use std::time::{Duration, Instant};

const META_TRAIN: &str = "envfield.train";
const META_DATA: &str = "envfield.data";

/// Queries per group of the descent loss: an anchor cell and its 8 neighbours.
const GROUP: usize = 9;

/// How to train. Serialised into every checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TrainConfig {
    /// Peak learning rate (the paper: 5e-5).
    pub lr: f64,
    /// The learning rate decays along a cosine to `lr * final_lr_fraction` at `steps`
    /// (1 keeps it constant).
    pub final_lr_fraction: f64,
    /// Adam's betas.
    pub betas: (f64, f64),
    /// Adam's epsilon.
    pub eps: f64,
    /// Decoupled weight decay (AdamW); 0 is Adam.
    pub weight_decay: f64,
    /// (maze, goal) samples per step.
    pub batch_items: usize,
    /// Query cells per sample per step (drawn uniformly, obstacles included: the network
    /// learns the blocked value too).
    pub queries_per_item: usize,
    /// Total steps.
    pub steps: u64,
    /// Seed of the batch sampler (the network's seed is separate).
    pub seed: u64,
    /// Save a checkpoint every this many steps (0: only at the end).
    pub checkpoint_every: u64,
    /// Validate every this many steps (0: only at the end).
    pub validate_every: u64,
    /// At most this many validation samples are used.
    pub validation_samples: usize,
    /// Weight of the neighbour-difference loss: queries come in pairs of a cell and one of its
    /// 8 neighbours, and the L1 error of the predicted difference between them (where both are
    /// reachable) is added with this weight. Descent compares neighbours, so this trains the
    /// field's local slope directly. 0 disables it (plain L1).
    #[serde(default)]
    pub neighbour_weight: f64,
    /// Fraction of the (anchor) queries drawn from *detour cells*: reachable cells whose
    /// distance exceeds the octile distance to the goal by more than half a cell, where the
    /// path must bend around obstacles and descent is most often misled. The rest are uniform
    /// over the grid. 0 (the default) samples uniformly.
    #[serde(default)]
    pub detour_fraction: f64,
    /// Fraction of the anchor queries drawn from *far cells*: reachable cells at least half
    /// the maze's largest reachable distance from the goal. Far cells are few (about 2% of a
    /// 28x28 maze's cells lie 30 or more cells from its goal) but that is where descent fails
    /// most. Drawn first; the rest follow `detour_fraction`. 0 (the default) draws none
    /// specially. Not used with `dense`.
    #[serde(default)]
    pub far_fraction: f64,
    /// Fraction of the anchor queries drawn from *hard cells*: reachable cells where the
    /// network being trained, as it stands at this step, makes a wrong descent move (under
    /// `descent_rule`, its move's true distance exceeds the best move's). Finding them costs
    /// one whole-field prediction per sampled maze and step (the inference path: about 2 ms
    /// for a 28x28 maze), and aims the losses at the decisions that are wrong now rather
    /// than at a fixed guess of where they will be. Drawn first; the rest follow
    /// `far_fraction`, then `detour_fraction`. 0 (the default) finds none. Only for networks
    /// that read the grid (context, hyper); not used with `dense`.
    #[serde(default)]
    pub hard_fraction: f64,
    /// Weight of the descent loss. Queries then come in groups of nine: an anchor cell and its
    /// 8 neighbours (a neighbour that is not a move under `descent_rule` is replaced by the
    /// anchor and left out). Descent steps to the neighbour of best output, so each neighbour
    /// that is not among the best moves (least true distance) should score below the best of
    /// the best moves by at least `descent_margin` (or by its true gap, when smaller); the loss
    /// is the hinge `max(0, margin - (best - other))` summed over those neighbours and averaged
    /// over the groups. It trains the decision the planner makes, and the exact field scores
    /// zero on it, so it does not pull against the L1 loss. The neighbour-difference loss
    /// (between the anchor and each neighbour in this mode) still applies. Needs
    /// `queries_per_item` divisible by 9. 0 disables it.
    pub descent_weight: f64,
    /// The margin of the descent loss, in output units: under the linear encoding `1 - d/100`
    /// one cell is 0.01, so the default 0.005 is half a cell.
    pub descent_margin: f64,
    /// The move rule of the descent loss (which neighbours are moves).
    pub descent_rule: MoveRule,
    /// Dense queries: every cell of each sampled maze is a query (`queries_per_item` is then
    /// unused), and the neighbour-difference and descent losses run over every reachable cell
    /// with its 8 neighbours, gathered from the one field prediction; `detour_fraction` is
    /// then the share of each maze's weight in those losses that its detour cells carry. One
    /// whole field gives a decision per reachable cell, where groups of nine queries give one
    /// per group: on a 28x28 maze about 500 decisions for 784 queries against 42 for 378.
    /// Needs nothing of the network (the reachable cells come from the targets). In this
    /// project's runs it trained worse decisions than the sampled groups (models/README.md).
    #[serde(default)]
    pub dense: bool,
    /// Decay of an exponential moving average of the weights, updated after every step
    /// (`ema = decay * ema + (1 - decay) * weights`, starting from the weights where it is
    /// switched on); 0 keeps none. [`Trainer::averaged_net`] gives the averaged network, and
    /// checkpoints carry the average so a resumed run continues it. An average over the last
    /// `1 / (1 - decay)` steps smooths the step-to-step swings of the decisions descent
    /// makes, which single checkpoints show.
    #[serde(default)]
    pub ema_decay: f64,
}

impl Default for TrainConfig {
    fn default() -> Self {
        Self {
            lr: 5e-5,
            final_lr_fraction: 1.0,
            betas: (0.9, 0.999),
            eps: 1e-8,
            weight_decay: 0.0,
            batch_items: 32,
            queries_per_item: 256,
            steps: 10_000,
            seed: 0,
            checkpoint_every: 500,
            validate_every: 500,
            validation_samples: 256,
            neighbour_weight: 0.0,
            detour_fraction: 0.0,
            far_fraction: 0.0,
            hard_fraction: 0.0,
            descent_weight: 0.0,
            descent_margin: 0.005,
            descent_rule: MoveRule::Strict,
            dense: false,
            ema_decay: 0.0,
        }
    }
}

impl TrainConfig {
    /// Checks every setting.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] naming the setting.
    pub fn validate(&self) -> Result<()> {
        let ok = self.lr.is_finite()
            && self.lr > 0.0
            && (0.0..=1.0).contains(&self.final_lr_fraction)
            && (0.0..1.0).contains(&self.betas.0)
            && (0.0..1.0).contains(&self.betas.1)
            && self.eps > 0.0
            && self.weight_decay >= 0.0
            && self.batch_items > 0
            && self.queries_per_item > 0
            && self.validation_samples > 0
            && self.neighbour_weight >= 0.0
            && (self.neighbour_weight == 0.0
                || self.dense
                || self.grouped()
                || self.queries_per_item % 2 == 0)
            && (0.0..=1.0).contains(&self.detour_fraction)
            && (0.0..=1.0).contains(&self.far_fraction)
            && (0.0..=1.0).contains(&self.hard_fraction)
            && self.descent_weight >= 0.0
            && (self.descent_weight == 0.0 || self.dense || self.queries_per_item % GROUP == 0)
            && self.descent_margin > 0.0
            && (0.0..1.0).contains(&self.ema_decay);
        if ok {
            Ok(())
        } else {
            Err(NetsError::InvalidConfig(format!(
                "training: need lr > 0, final_lr_fraction in [0, 1], betas in [0, 1), eps > 0, \
                 weight_decay >= 0, batch_items, queries_per_item and validation_samples >= 1, \
                 neighbour_weight >= 0 with an even queries_per_item (unless grouped), detour_fraction, far_fraction and hard_fraction in [0, 1], \
                 descent_weight >= 0 with queries_per_item a multiple of 9 (unless dense), \
                 descent_margin > 0, ema_decay in [0, 1) (got {self:?})"
            )))
        }
    }

    /// Whether queries come in groups of an anchor and its 8 neighbours.
    fn grouped(&self) -> bool {
        self.descent_weight > 0.0
    }

    /// The learning rate at `step` (0-based).
    pub fn lr_at(&self, step: u64) -> f64 {
        let low = self.lr * self.final_lr_fraction;
        let t = (step as f64 / self.steps.max(1) as f64).min(1.0);
        low + 0.5 * (self.lr - low) * (1.0 + (std::f64::consts::PI * t).cos())
    }
}

/// What the trainer reports after each step.
#[derive(Clone, Debug, PartialEq)]
pub struct Progress {
    /// Steps done (this one included).
    pub step: u64,
    /// Total steps.
    pub steps: u64,
    /// This step's training loss (mean absolute error of the encoded target).
    pub loss: f32,
    /// The validation loss, on steps where it was measured.
    pub validation: Option<f32>,
    /// Whether a checkpoint was written after this step.
    pub checkpointed: bool,
    /// Wall time since this run started (a resumed run starts at zero).
    pub elapsed: Duration,
    /// Steps per second over this run so far.
    pub steps_per_second: f64,
}

/// What a finished run measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrainSummary {
    /// Steps done in total (across resumes).
    pub step: u64,
    /// Mean training loss over the last 100 steps of this run.
    pub loss: f32,
    /// The final validation loss, when there was a validation set.
    pub validation: Option<f32>,
    /// Seconds this run took.
    pub seconds: f64,
    /// Steps per second in this run.
    pub steps_per_second: f64,
    /// Training samples (maze-goal pairs) per second.
    pub items_per_second: f64,
    /// Query points per second.
    pub queries_per_second: f64,
}

/// Trains a [`FieldNet`] on [`Dataset`]s.
#[derive(Debug)]
pub struct Trainer {
    net: FieldNet,
    optimiser: AdamW,
    config: TrainConfig,
    /// The moving average of the weights (see [`TrainConfig::ema_decay`]), one tensor per
    /// parameter in the store's order.
    ema: Option<Vec<Tensor>>,
    /// What the caller says the training data is (see [`Trainer::set_data_description`]).
    data: Option<String>,
}

impl Trainer {
    /// A trainer for `net` at step 0.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] for a bad config, or a `hard_fraction` above 0 for a
    /// network that does not read the grid.
    pub fn new(net: FieldNet, config: TrainConfig) -> Result<Self> {
        config.validate()?;
        check_hard(&net, &config)?;
        let optimiser = AdamW::new(
            net.vars(),
            config.lr,
            config.betas,
            config.eps,
            config.weight_decay,
        )?;
        let ema = (config.ema_decay > 0.0)
            .then(|| weights(&net))
            .transpose()?;
        Ok(Self {
            net,
            optimiser,
            config,
            ema,
            data: None,
        })
    }

    /// Resumes from a checkpoint written by [`Trainer::save_checkpoint`]: the network, the
    /// optimiser's moments, the step and the training config.
    ///
    /// # Errors
    /// [`NetsError::Checkpoint`] and the weight errors of [`FieldNet::load_weights`].
    pub fn resume(path: impl AsRef<Path>) -> Result<Self> {
        Self::resume_on(path, &Device::Cpu)
    }

    /// As [`Trainer::resume`] on `device`.
    ///
    /// # Errors
    /// As [`Trainer::resume`].
    pub fn resume_on(path: impl AsRef<Path>, device: &Device) -> Result<Self> {
        let path = path.as_ref();
        let mut file = TensorFile::read(path)?;
        let bad = |reason: String| NetsError::Checkpoint {
            path: path.to_path_buf(),
            reason,
        };
        let step: u64 = file
            .metadata
            .get(META_STEP)
            .ok_or_else(|| {
                bad(format!(
                    "no `{META_STEP}`: a weight file, not a training checkpoint"
                ))
            })?
            .parse()
            .map_err(|e| bad(format!("bad step: {e}")))?;
        let config: TrainConfig = serde_json::from_str(
            file.metadata
                .get(META_TRAIN)
                .ok_or_else(|| bad(format!("no `{META_TRAIN}` metadata")))?,
        )
        .map_err(|e| bad(format!("bad training config: {e}")))?;
        let model = read_config(path, &file)?;
        let mut net = FieldNet::new_on(model, 0, device)?;
        let (m, v) = file.take_moments(path, net.store(), device)?;
        let ema = file.take_average(path, net.store(), device, config.ema_decay > 0.0)?;
        net.take_weights(path, &mut file)?;
        let mut trainer = Self::new(net, config)?;
        trainer.optimiser.set_moments(m, v, step);
        trainer.ema = ema;
        trainer.data = file.metadata.get(META_DATA).cloned();
        Ok(trainer)
    }

    /// Records what the training data is (the datasets are the caller's, so a checkpoint
    /// cannot hold them): checkpoints carry the text, and [`Trainer::data_description`] on a
    /// resumed trainer gives it back, so a caller can refuse to go on with other data.
    pub fn set_data_description(&mut self, description: impl Into<String>) {
        self.data = Some(description.into());
    }

    /// The data description set on this trainer or read from its checkpoint, if any.
    pub fn data_description(&self) -> Option<&str> {
        self.data.as_deref()
    }

    /// Steps done so far.
    pub fn step(&self) -> u64 {
        self.optimiser.step
    }

    /// The network.
    pub fn net(&self) -> &FieldNet {
        &self.net
    }

    /// The network, consuming the trainer.
    pub fn into_net(self) -> FieldNet {
        self.net
    }

    /// A copy of the network with the moving average of the weights (see
    /// [`TrainConfig::ema_decay`]), or with the current weights when no average is kept.
    ///
    /// # Errors
    /// Tensor errors from copying the weights.
    pub fn averaged_net(&self) -> Result<FieldNet> {
        let net = FieldNet::new_on(self.net.config().clone(), 0, self.net.device())?;
        let source = match &self.ema {
            Some(ema) => ema.clone(),
            None => weights(&self.net)?,
        };
        for (var, t) in net.vars().iter().zip(&source) {
            var.set(t)?;
        }
        Ok(net)
    }

    /// Switches the moving average of the weights on (starting from the current weights, or
    /// continuing the one kept) with `decay`, or off with 0 (see [`TrainConfig::ema_decay`]).
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] for a decay outside `[0, 1)`.
    pub fn set_ema_decay(&mut self, decay: f64) -> Result<()> {
        self.update_config(|c| c.ema_decay = decay)?;
        if decay == 0.0 {
            self.ema = None;
        } else if self.ema.is_none() {
            self.ema = Some(weights(&self.net)?);
        }
        Ok(())
    }

    /// The training config.
    pub fn config(&self) -> &TrainConfig {
        &self.config
    }

    /// Sets the neighbour-difference weight (see [`TrainConfig::neighbour_weight`]), for
    /// example to fine-tune a resumed run with it.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] for a negative weight or an odd `queries_per_item`.
    pub fn set_neighbour_weight(&mut self, weight: f64) -> Result<()> {
        self.update_config(|c| c.neighbour_weight = weight)
    }

    /// Applies `change` to a copy of the config and keeps it if it validates.
    fn update_config(&mut self, change: impl FnOnce(&mut TrainConfig)) -> Result<()> {
        let mut config = self.config.clone();
        change(&mut config);
        config.validate()?;
        check_hard(&self.net, &config)?;
        self.config = config;
        Ok(())
    }

    /// Sets the fraction of queries drawn from detour cells (see
    /// [`TrainConfig::detour_fraction`]), for example to fine-tune a resumed run.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] for a fraction outside `[0, 1]`.
    pub fn set_detour_fraction(&mut self, fraction: f64) -> Result<()> {
        self.update_config(|c| c.detour_fraction = fraction)
    }

    /// Sets the fraction of anchor queries drawn from far cells (see
    /// [`TrainConfig::far_fraction`]).
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] for a fraction outside `[0, 1]`.
    pub fn set_far_fraction(&mut self, fraction: f64) -> Result<()> {
        self.update_config(|c| c.far_fraction = fraction)
    }

    /// Sets the fraction of anchor queries drawn from the cells where the network's descent
    /// move is wrong (see [`TrainConfig::hard_fraction`]).
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] for a fraction outside `[0, 1]`, or above 0 for a network
    /// that does not read the grid.
    pub fn set_hard_fraction(&mut self, fraction: f64) -> Result<()> {
        self.update_config(|c| c.hard_fraction = fraction)
    }

    /// Sets the descent loss (see [`TrainConfig::descent_weight`]): its weight, margin and
    /// move rule, for example to fine-tune a resumed run with it.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] for a negative weight, a margin that is not positive, or
    /// `queries_per_item` not divisible by 9.
    pub fn set_descent(&mut self, weight: f64, margin: f64, rule: MoveRule) -> Result<()> {
        self.update_config(|c| {
            c.descent_weight = weight;
            c.descent_margin = margin;
            c.descent_rule = rule;
        })
    }

    /// Switches dense queries (see [`TrainConfig::dense`]) on or off, for example to
    /// fine-tune a resumed run with them.
    pub fn set_dense(&mut self, dense: bool) {
        self.config.dense = dense;
    }

    /// Sets the total number of steps (to train a resumed run further).
    pub fn set_steps(&mut self, steps: u64) {
        self.config.steps = steps;
    }

    /// Writes a checkpoint (weights, config, optimiser moments, step, training config) to
    /// `path` atomically: a reader sees the old file or the new one, never a partial one.
    ///
    /// # Errors
    /// I/O errors naming the file.
    pub fn save_checkpoint(&self, path: impl AsRef<Path>) -> Result<()> {
        let mut extra = self.optimiser.state_tensors(self.net.param_names());
        if let Some(ema) = &self.ema {
            let names = self.net.param_names().iter().map(|n| ema_name(n));
            extra.extend(names.zip(ema.iter().cloned()));
        }
        let mut meta = HashMap::new();
        meta.insert(META_STEP.to_string(), self.step().to_string());
        let train = serde_json::to_string(&self.config).map_err(|e| {
            NetsError::InvalidConfig(format!("cannot serialise the training config: {e}"))
        })?;
        meta.insert(META_TRAIN.to_string(), train);
        if let Some(data) = &self.data {
            meta.insert(META_DATA.to_string(), data.clone());
        }
        self.net.write_file(path.as_ref(), extra, meta)
    }

    /// One optimiser step on `batch` with `targets` (one encoded target per query); returns
    /// the loss before the step. With a neighbour weight, consecutive queries are taken as
    /// (cell, neighbour) pairs.
    ///
    /// # Errors
    /// [`NetsError::InvalidInput`] for mismatched targets; [`NetsError::Diverged`] for a loss
    /// that is not finite.
    pub fn train_batch(&mut self, batch: &Batch, targets: &[f32]) -> Result<f32> {
        if targets.len() != batch.len() {
            return Err(NetsError::InvalidInput(format!(
                "{} targets for {} queries",
                targets.len(),
                batch.len()
            )));
        }
        let pred = self.net.forward(batch)?;
        let target = Tensor::from_vec(targets.to_vec(), targets.len(), self.net.device())?;
        let mut loss = (&pred - &target)?.abs()?.mean_all()?;
        let margin = self.config.descent_margin as f32;
        let groups = if self.config.dense
            && (self.config.neighbour_weight > 0.0 || self.config.descent_weight > 0.0)
        {
            let encoding = self.net.config().encoding();
            let (groups, index) = Groups::dense(
                batch,
                targets,
                self.config.descent_rule,
                margin,
                self.config.detour_fraction as f32,
                |t| encoding.decode(t),
            )?;
            let index = Tensor::from_vec(index, groups.count * GROUP, pred.device())?;
            Some((groups, pred.index_select(&index, 0)?))
        } else if self.config.grouped() {
            Some((Groups::new(batch, targets, margin)?, pred.clone()))
        } else {
            None
        };
        if let Some((groups, pred)) = groups {
            if self.config.neighbour_weight > 0.0 && groups.count > 0 {
                let slope = groups.slope_loss(&pred)?;
                loss = (loss + (slope * self.config.neighbour_weight)?)?;
            }
            if let Some(descent) = groups.descent_loss(&pred)? {
                loss = (loss + (descent * self.config.descent_weight)?)?;
            }
        } else if self.config.neighbour_weight > 0.0 && batch.len() % 2 == 0 {
            // (cell, neighbour) pairs: groups of two.
            let (rise, valid): (Vec<f32>, Vec<f32>) = targets
                .chunks_exact(2)
                .map(|t| (t[1] - t[0], (t[0] >= 0.0 && t[1] >= 0.0) as u8 as f32))
                .unzip();
            let slope = rise_loss(&pred, 2, rise, valid)?;
            loss = (loss + (slope * self.config.neighbour_weight)?)?;
        }
        let value = loss.to_scalar::<f32>()?;
        if !value.is_finite() {
            return Err(NetsError::Diverged {
                step: self.step(),
                loss: value,
            });
        }
        self.optimiser.lr = self.config.lr_at(self.step());
        self.optimiser.backward_step(self.net.vars(), &loss)?;
        if let Some(ema) = &mut self.ema {
            let d = self.config.ema_decay;
            for (avg, var) in ema.iter_mut().zip(self.net.vars()) {
                *avg = ((&*avg * d)? + (var.as_tensor().detach() * (1.0 - d))?)?;
            }
        }
        Ok(value)
    }

    /// The training batch of step `step` from `data` and its targets (in the network's
    /// encoding): `batch_items` random samples, `queries_per_item` random cells each, seeded by
    /// the config's seed and the step, so a resumed run draws the same batches as an
    /// uninterrupted one.
    ///
    /// # Errors
    /// [`NetsError::InvalidInput`] for an empty dataset.
    pub fn sample_batch(&self, data: &Dataset, step: u64) -> Result<(Batch, Vec<f32>)> {
        if data.samples.is_empty() {
            return Err(NetsError::InvalidInput("empty dataset".into()));
        }
        let mut rng = SplitMix64::new(
            self.config
                .seed
                .wrapping_mul(0x9E37_79B9)
                .wrapping_add(step),
        );
        let first = &data.samples[0];
        let (rows, cols) = (first.grid.rows(), first.grid.cols());
        let b = self.config.batch_items;
        let q = if self.config.dense {
            rows * cols
        } else {
            self.config.queries_per_item
        };
        let reads_grid = self.net.config().reads_grid();
        let encoding = self.net.config().encoding();
        let mut batch = Batch {
            extent: vec![rows, cols],
            items: b,
            obstacles: Vec::with_capacity(if reads_grid { b * rows * cols } else { 0 }),
            goals: Vec::with_capacity(2 * b),
            per_item: q,
            queries: Vec::with_capacity(2 * b * q),
        };
        let mut targets = Vec::with_capacity(b * q);
        for _ in 0..b {
            let s = &data.samples[rng.below(data.samples.len())];
            if reads_grid {
                batch
                    .obstacles
                    .extend(s.grid.obstacles().iter().map(|&o| o as u8 as f32));
            }
            batch.goals.extend([s.goal.row as f32, s.goal.col as f32]);
            let pairs = self.config.neighbour_weight > 0.0;
            let detours = if self.config.detour_fraction > 0.0 && !self.config.dense {
                detour_cells(s)
            } else {
                Vec::new()
            };
            let far = if self.config.far_fraction > 0.0 && !self.config.dense {
                far_cells(s)
            } else {
                Vec::new()
            };
            let hard = if self.config.hard_fraction > 0.0 && !self.config.dense {
                self.hard_cells(s)?
            } else {
                Vec::new()
            };
            let anchor = |rng: &mut SplitMix64| {
                if !hard.is_empty() && rng.next_f64() < self.config.hard_fraction {
                    hard[rng.below(hard.len())]
                } else if !far.is_empty() && rng.next_f64() < self.config.far_fraction {
                    far[rng.below(far.len())]
                } else if !detours.is_empty() && rng.next_f64() < self.config.detour_fraction {
                    detours[rng.below(detours.len())]
                } else {
                    rng.below(rows * cols)
                }
            };
            let mut cells = Vec::with_capacity(q);
            if self.config.dense {
                cells.extend(0..q);
            } else if self.config.grouped() {
                // An anchor, then its 8 neighbours in `DIRECTIONS_8` order; the anchor again
                // where a neighbour is not a move.
                let rule = self.config.descent_rule;
                for _ in 0..q / GROUP {
                    let i = anchor(&mut rng);
                    let from = Cell2::new(i / cols, i % cols);
                    cells.push(i);
                    cells.extend(DIRECTIONS_8.iter().map(|&(dr, dc)| {
                        if rule.allows(&s.grid, from, dr, dc) {
                            (i as isize + dr * cols as isize + dc) as usize
                        } else {
                            i
                        }
                    }));
                }
            } else {
                for k in 0..q {
                    cells.push(if pairs && k % 2 == 1 {
                        // A random in-bounds neighbour of the previous query.
                        let (r, c) = (cells[k - 1] / cols, cells[k - 1] % cols);
                        loop {
                            let (dr, dc) = DIRECTIONS_8[rng.below(8)];
                            let (nr, nc) = (r as isize + dr, c as isize + dc);
                            if nr >= 0 && nc >= 0 && (nr as usize) < rows && (nc as usize) < cols {
                                break nr as usize * cols + nc as usize;
                            }
                        }
                    } else {
                        anchor(&mut rng)
                    });
                }
            }
            for i in cells {
                batch.queries.extend([(i / cols) as f32, (i % cols) as f32]);
                targets.push(reencode(encoding, s.target[i]));
            }
        }
        Ok((batch, targets))
    }

    /// The reachable cells of `s` (the goal excluded) where descent on the network's current
    /// field takes a move whose true distance exceeds the best move's.
    fn hard_cells(&self, s: &Sample) -> Result<Vec<usize>> {
        let field = self.net.field(&s.grid, s.goal)?;
        let rule = self.config.descent_rule;
        let cols = s.grid.cols();
        let distance = |c: Cell2| envfield_mazes::decode_target(s.target[c.row * cols + c.col]);
        Ok(s.grid
            .free_cells()
            .filter(|&c| c != s.goal && distance(c).is_finite())
            .filter(|&c| is_wrong_move(&s.grid, &field, rule, c, distance))
            .map(|c| c.row * cols + c.col)
            .collect())
    }

    /// Mean absolute error of the encoded target over every cell of (up to
    /// `validation_samples`) samples of `data`.
    ///
    /// # Errors
    /// As [`FieldNet::forward`].
    pub fn validate(&self, data: &Dataset) -> Result<f32> {
        validation_loss(&self.net, data, self.config.validation_samples)
    }

    /// Trains until `config.steps` (from the current step), drawing each step's batch from
    /// `datasets[step % datasets.len()]` (one dataset per maze size trains one model for all
    /// sizes), validating on `validation`, checkpointing to `checkpoint`, and calling
    /// `on_progress` after every step. Returning `false` from it stops early (with a
    /// checkpoint).
    ///
    /// # Errors
    /// [`NetsError::InvalidInput`] for an empty or mixed-size dataset; training errors.
    pub fn run(
        &mut self,
        datasets: &[Dataset],
        validation: Option<&Dataset>,
        checkpoint: Option<&Path>,
        mut on_progress: impl FnMut(&Progress) -> bool,
    ) -> Result<TrainSummary> {
        if datasets.is_empty() {
            return Err(NetsError::InvalidInput("no training dataset".into()));
        }
        for (k, d) in datasets.iter().chain(validation).enumerate() {
            check_single_size(d, k)?;
        }
        let start = Instant::now();
        let first = self.step();
        let mut recent: Vec<f32> = Vec::new();
        let mut last_validation = None;
        let mut queries = 0usize;
        while self.step() < self.config.steps {
            let step = self.step();
            let data = &datasets[(step % datasets.len() as u64) as usize];
            let (batch, targets) = self.sample_batch(data, step)?;
            let loss = self.train_batch(&batch, &targets)?;
            queries += batch.len();
            recent.push(loss);
            if recent.len() > 100 {
                recent.remove(0);
            }
            let done = self.step();
            let finished = done >= self.config.steps;
            let every = |n: u64| n > 0 && done % n == 0;
            let validation_now = match validation {
                Some(v) if finished || every(self.config.validate_every) => Some(self.validate(v)?),
                _ => None,
            };
            if validation_now.is_some() {
                last_validation = validation_now;
            }
            let checkpointed = match checkpoint {
                Some(p) if finished || every(self.config.checkpoint_every) => {
                    self.save_checkpoint(p)?;
                    true
                }
                _ => false,
            };
            let elapsed = start.elapsed();
            let progress = Progress {
                step: done,
                steps: self.config.steps,
                loss,
                validation: validation_now,
                checkpointed,
                elapsed,
                steps_per_second: (done - first) as f64 / elapsed.as_secs_f64().max(1e-9),
            };
            if !on_progress(&progress) {
                if let (Some(p), false) = (checkpoint, checkpointed) {
                    self.save_checkpoint(p)?;
                }
                break;
            }
        }
        let seconds = start.elapsed().as_secs_f64();
        let steps = (self.step() - first) as f64;
        let rate = steps / seconds.max(1e-9);
        Ok(TrainSummary {
            step: self.step(),
            loss: recent.iter().sum::<f32>() / recent.len().max(1) as f32,
            validation: last_validation,
            seconds,
            steps_per_second: rate,
            items_per_second: rate * self.config.batch_items as f64,
            queries_per_second: queries as f64 / seconds.max(1e-9),
        })
    }
}

/// The groups of a batch sampled for the descent loss (anchor, then 8 neighbours), read back
/// from the queries and targets, each as (groups, 8) masks and values: which neighbours are
/// moves, how much each should rise above the anchor, which are the best moves, and by how much
/// each other move should score below them.
struct Groups {
    count: usize,
    /// 1 where neighbour `j` of group `g` (at `g * 8 + j`) is a reachable move.
    valid: Vec<f32>,
    /// True encoded output of the neighbour minus the anchor's.
    rise: Vec<f32>,
    /// 1 for the best moves (least true distance), in groups with a decision to make.
    winner: Vec<f32>,
    /// 1 for the other moves of those groups.
    other: Vec<f32>,
    /// The margin each other move should keep below the best: `margin.min(true gap)`.
    margin: Vec<f32>,
    /// Groups whose anchor is reachable, not the goal, and has a move.
    decisions: usize,
    /// Total weight of those groups (each group's weight scales its moves in `valid` and
    /// `other`).
    decision_weight: f32,
}

impl Groups {
    /// The groups of a batch sampled in groups of nine queries.
    fn new(batch: &Batch, targets: &[f32], margin: f32) -> Result<Self> {
        if batch.len() % GROUP != 0 || batch.per_item % GROUP != 0 {
            return Err(NetsError::InvalidInput(format!(
                "the descent loss needs queries in groups of {GROUP} per item (got {} per item)",
                batch.per_item
            )));
        }
        let count = batch.len() / GROUP;
        let mut moved = Vec::with_capacity(count * (GROUP - 1));
        let mut at_goal = Vec::with_capacity(count);
        for g in 0..count {
            let q = &batch.queries[2 * g * GROUP..][..2 * GROUP];
            let item = g * GROUP / batch.per_item;
            at_goal.push(q[..2] == batch.goals[2 * item..][..2]);
            moved.extend((1..GROUP).map(|j| q[2 * j..][..2] != q[..2]));
        }
        let weight = vec![1.0; count];
        Ok(Self::from_parts(targets, &moved, &at_goal, &weight, margin))
    }

    /// The groups of a dense batch (every cell of each item, row-major): one per reachable
    /// cell, with the indices into the batch's outputs that lay them out as groups of nine
    /// (a neighbour that is not a move under `rule` is the anchor again). Reachability comes
    /// from the targets (negative = blocked), which is all `rule` needs: a free cell next to a
    /// reachable one is reachable.
    ///
    /// With `detour_share` > 0, the groups of each item's detour cells (see
    /// [`TrainConfig::detour_fraction`]; `distance` decodes a target into cells) carry that
    /// share of the item's weight, the rest the other cells.
    fn dense(
        batch: &Batch,
        targets: &[f32],
        rule: MoveRule,
        margin: f32,
        detour_share: f32,
        distance: impl Fn(f32) -> f32,
    ) -> Result<(Self, Vec<u32>)> {
        let (rows, cols) = match batch.extent[..] {
            [rows, cols] if rows * cols == batch.per_item => (rows, cols),
            _ => {
                return Err(NetsError::InvalidInput(format!(
                    "dense training needs every cell of a 2D grid per item ({:?} cells, {} \
                     queries per item)",
                    batch.extent, batch.per_item
                )))
            }
        };
        let cells = rows * cols;
        let mut index = Vec::new();
        let mut grouped = Vec::new();
        let mut moved = Vec::new();
        let mut at_goal = Vec::new();
        let mut weight = Vec::new();
        for (item, t) in targets.chunks_exact(cells).enumerate() {
            let blocked = t.iter().map(|&v| v < 0.0).collect();
            let grid = Grid2::from_obstacles(rows, cols, blocked)?;
            let goal = &batch.goals[2 * item..][..2];
            let base = item * cells;
            let detour: Vec<bool> = (0..cells)
                .map(|i| {
                    let dr = ((i / cols) as f32 - goal[0]).abs();
                    let dc = ((i % cols) as f32 - goal[1]).abs();
                    t[i] >= 0.0 && is_detour(distance(t[i]), dr, dc)
                })
                .collect();
            let detours = detour.iter().filter(|&&d| d).count();
            let plain = (0..cells).filter(|&i| t[i] >= 0.0).count() - detours;
            let (w_detour, w_plain) = if detour_share > 0.0 && detours > 0 && plain > 0 {
                let total = (detours + plain) as f32;
                (
                    detour_share * total / detours as f32,
                    (1.0 - detour_share) * total / plain as f32,
                )
            } else {
                (1.0, 1.0)
            };
            for i in (0..cells).filter(|&i| t[i] >= 0.0) {
                let from = Cell2::new(i / cols, i % cols);
                at_goal.push(goal == [from.row as f32, from.col as f32]);
                weight.push(if detour[i] { w_detour } else { w_plain });
                index.push((base + i) as u32);
                grouped.push(t[i]);
                for &(dr, dc) in &DIRECTIONS_8 {
                    let allowed = rule.allows(&grid, from, dr, dc);
                    let j = if allowed {
                        (i as isize + dr * cols as isize + dc) as usize
                    } else {
                        i
                    };
                    index.push((base + j) as u32);
                    grouped.push(t[j]);
                    moved.push(allowed);
                }
            }
        }
        let groups = Self::from_parts(&grouped, &moved, &at_goal, &weight, margin);
        Ok((groups, index))
    }

    /// Groups from their targets (nine per group: anchor first), whether each neighbour is a
    /// move (eight per group), whether each anchor is the goal, and each group's weight.
    fn from_parts(
        targets: &[f32],
        moved: &[bool],
        at_goal: &[bool],
        weight: &[f32],
        margin: f32,
    ) -> Self {
        let count = at_goal.len();
        let n = GROUP - 1;
        let zeros = || vec![0f32; count * n];
        let mut groups = Self {
            count,
            valid: zeros(),
            rise: zeros(),
            winner: zeros(),
            other: zeros(),
            margin: zeros(),
            decisions: 0,
            decision_weight: 0.0,
        };
        for g in 0..count {
            let t = &targets[g * GROUP..][..GROUP];
            let row = g * n..(g + 1) * n;
            let valid = &mut groups.valid[row.clone()];
            for j in 0..n {
                if t[0] >= 0.0 && t[j + 1] >= 0.0 && moved[g * n + j] {
                    valid[j] = weight[g];
                    groups.rise[g * n + j] = t[j + 1] - t[0];
                }
            }
            let best = (0..n)
                .filter(|&j| valid[j] > 0.0)
                .map(|j| t[j + 1])
                .fold(f32::NEG_INFINITY, f32::max);
            if best == f32::NEG_INFINITY || at_goal[g] {
                continue;
            }
            for j in (0..n).filter(|&j| valid[j] > 0.0) {
                // Ties within float noise of the encoding are all best moves.
                let gap = best - t[j + 1];
                if gap <= 1e-6 {
                    groups.winner[g * n + j] = 1.0;
                } else {
                    groups.other[g * n + j] = weight[g];
                    groups.margin[g * n + j] = gap.min(margin);
                }
            }
            groups.decisions += 1;
            groups.decision_weight += weight[g];
        }
        groups
    }

    /// (groups, 8) values as a tensor on `device`.
    fn tensor(&self, values: &[f32], device: &Device) -> Result<Tensor> {
        Ok(Tensor::from_vec(
            values.to_vec(),
            (self.count, GROUP - 1),
            device,
        )?)
    }

    /// The anchor's and the neighbours' outputs, (groups, 1) and (groups, 8), of the batch's
    /// outputs `pred` (one per query).
    fn split(&self, pred: &Tensor) -> Result<(Tensor, Tensor)> {
        let pred = pred.reshape((self.count, GROUP))?;
        Ok((pred.narrow(1, 0, 1)?, pred.narrow(1, 1, GROUP - 1)?))
    }

    /// Mean L1 error of each move's predicted rise above its anchor.
    fn slope_loss(&self, pred: &Tensor) -> Result<Tensor> {
        rise_loss(pred, GROUP, self.rise.clone(), self.valid.clone())
    }

    /// The descent hinge (see [`TrainConfig::descent_weight`]) averaged over the groups with a
    /// decision; `None` when no group has one.
    fn descent_loss(&self, pred: &Tensor) -> Result<Option<Tensor>> {
        if self.decisions == 0 {
            return Ok(None);
        }
        let device = pred.device();
        let (_, neighbours) = self.split(pred)?;
        // The best output among the best moves (others pushed far below), then each other
        // move's shortfall from the margin.
        let shut = ((self.tensor(&self.winner, device)? - 1.0)? * 1e4)?;
        let best = (&neighbours + shut)?.max_keepdim(1)?;
        let gap = best.broadcast_sub(&neighbours)?;
        let hinge = (self.tensor(&self.margin, device)? - gap)?.relu()?;
        let others = self.tensor(&self.other, device)?;
        Ok(Some(
            ((hinge * others)?.sum_all()? / self.decision_weight as f64)?,
        ))
    }
}

/// The neighbour-difference loss on outputs `pred` laid out in groups of `size` (an anchor,
/// then `size - 1` others): the L1 error of each other output's rise above its anchor against
/// the true `rise`, averaged over the pairs with the weights in `valid` (0 leaves a pair out;
/// 1 for a plain mean). `rise` and `valid` hold
/// (groups, size - 1) values.
fn rise_loss(pred: &Tensor, size: usize, rise: Vec<f32>, valid: Vec<f32>) -> Result<Tensor> {
    let groups = pred.elem_count() / size;
    let pred = pred.reshape((groups, size))?;
    let (anchor, others) = (pred.narrow(1, 0, 1)?, pred.narrow(1, 1, size - 1)?);
    let pairs = valid.iter().sum::<f32>().max(1.0);
    let shape = (groups, size - 1);
    let truth = Tensor::from_vec(rise, shape, pred.device())?;
    let valid = Tensor::from_vec(valid, shape, pred.device())?;
    let err = (others.broadcast_sub(&anchor)? - truth)?.abs()?;
    Ok(((err * valid)?.sum_all()? / pairs as f64)?)
}

/// Hard cells need a field of each training maze: only networks that read the grid give one.
fn check_hard(net: &FieldNet, config: &TrainConfig) -> Result<()> {
    if config.hard_fraction > 0.0 && !net.config().reads_grid() {
        return Err(NetsError::InvalidConfig(format!(
            "hard_fraction {} needs a network that reads the grid (context or hyper), not {}",
            config.hard_fraction,
            net.config().arch()
        )));
    }
    Ok(())
}

/// The reachable cells of `s` whose distance exceeds the octile distance to the goal by more
/// than half a cell.
fn detour_cells(s: &Sample) -> Vec<usize> {
    let cols = s.grid.cols();
    s.target
        .iter()
        .enumerate()
        .filter_map(|(i, &t)| {
            let d = envfield_mazes::decode_target(t);
            let dr = (i / cols).abs_diff(s.goal.row) as f32;
            let dc = (i % cols).abs_diff(s.goal.col) as f32;
            is_detour(d, dr, dc).then_some(i)
        })
        .collect()
}

/// The reachable cells of `s` at least half its largest reachable distance from the goal
/// (none when the goal reaches nothing).
fn far_cells(s: &Sample) -> Vec<usize> {
    let distance: Vec<f32> = s
        .target
        .iter()
        .map(|&t| envfield_mazes::decode_target(t))
        .collect();
    let max = distance
        .iter()
        .filter(|d| d.is_finite())
        .fold(0.0f32, |m, &d| m.max(d));
    if max <= 0.0 {
        return Vec::new();
    }
    (0..distance.len())
        .filter(|&i| distance[i].is_finite() && distance[i] >= 0.5 * max)
        .collect()
}

/// Whether a cell at true distance `distance` (infinite: unreachable) and `(dr, dc)` cells
/// from the goal is a detour cell: its distance exceeds the octile distance by more than half
/// a cell.
fn is_detour(distance: f32, dr: f32, dc: f32) -> bool {
    let octile = dr.max(dc) + (std::f32::consts::SQRT_2 - 1.0) * dr.min(dc);
    distance.is_finite() && distance > octile + 0.5
}

/// Copies of the network's weights in storage of their own (a detached tensor would share the
/// variable's storage, which each optimiser step overwrites).
fn weights(net: &FieldNet) -> Result<Vec<Tensor>> {
    Ok(net
        .vars()
        .iter()
        .map(|v| v.as_tensor().detach().copy())
        .collect::<candle_core::Result<_>>()?)
}

/// Dataset targets are in the paper's encoding; the network may use another.
fn reencode(encoding: TargetEncoding, paper: f32) -> f32 {
    match encoding {
        TargetEncoding::Reciprocal => paper,
        other => other.encode(envfield_mazes::decode_target(paper)),
    }
}

fn check_single_size(data: &Dataset, k: usize) -> Result<()> {
    let first: &Sample = data
        .samples
        .first()
        .ok_or_else(|| NetsError::InvalidInput(format!("dataset {k} is empty")))?;
    let shape = (first.grid.rows(), first.grid.cols());
    if let Some(s) = data
        .samples
        .iter()
        .find(|s| (s.grid.rows(), s.grid.cols()) != shape)
    {
        return Err(NetsError::InvalidInput(format!(
            "dataset {k} mixes grid sizes {:?} and {:?} (give one dataset per size)",
            shape,
            (s.grid.rows(), s.grid.cols())
        )));
    }
    Ok(())
}

/// Mean absolute error of `net`'s encoded output (in its own [`TargetEncoding`]) over every
/// cell of up to `limit` samples.
///
/// # Errors
/// As [`FieldNet::forward`].
pub fn validation_loss(net: &FieldNet, data: &Dataset, limit: usize) -> Result<f32> {
    let mut total = 0f64;
    let mut count = 0usize;
    let encoding = net.config().encoding();
    for s in data.samples.iter().take(limit) {
        let pred = net.predict_encoded(&Batch::whole_grid(&s.grid, s.goal))?;
        total += pred
            .iter()
            .zip(&s.target)
            .map(|(p, &t)| (p - reencode(encoding, t)).abs() as f64)
            .sum::<f64>();
        count += pred.len();
    }
    Ok((total / count.max(1) as f64) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3x3 room, goal in the top-right corner, one group anchored at the centre under the
    /// linear encoding `1 - d/100`: slot 2 (left) is not a move (the anchor again), slot 4
    /// (top-left) is blocked, slot 5 (top-right) is the goal and the only best move.
    fn one_group(anchor_at_goal: bool) -> (Batch, Vec<f32>) {
        let t = |d: f32| 1.0 - d / 100.0;
        let s2 = std::f32::consts::SQRT_2;
        let mut queries = vec![1.0, 1.0, 0.0, 1.0, 2.0, 1.0, 1.0, 1.0, 1.0, 2.0];
        queries.extend([0.0, 0.0, 0.0, 2.0, 2.0, 0.0, 2.0, 2.0]);
        let targets = vec![
            t(s2),
            t(1.0),
            t(1.0 + s2),
            t(s2),
            t(1.0),
            -1.0,
            t(0.0),
            t(2.0 * s2),
            t(2.0),
        ];
        let goal = if anchor_at_goal {
            [1.0, 1.0]
        } else {
            [0.0, 2.0]
        };
        let batch = Batch {
            extent: vec![3, 3],
            items: 1,
            obstacles: vec![0.0; 9],
            goals: goal.to_vec(),
            per_item: GROUP,
            queries,
        };
        (batch, targets)
    }

    #[test]
    fn groups_read_back_moves_best_moves_and_margins() {
        let (batch, targets) = one_group(false);
        let g = Groups::new(&batch, &targets, 0.005).unwrap();
        assert_eq!(g.decisions, 1);
        assert_eq!(g.valid, [1.0, 1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0]);
        assert_eq!(g.winner, [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
        assert_eq!(g.other, [1.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0]);
        for (j, &m) in g.margin.iter().enumerate() {
            assert_eq!(m, if g.other[j] > 0.0 { 0.005 } else { 0.0 }, "slot {j}");
        }
        // Standing on the goal there is no decision.
        let (batch, targets) = one_group(true);
        assert_eq!(Groups::new(&batch, &targets, 0.005).unwrap().decisions, 0);
    }

    #[test]
    fn the_exact_field_scores_zero_and_a_wrong_ranking_pays_its_shortfall() {
        let (batch, targets) = one_group(false);
        let g = Groups::new(&batch, &targets, 0.005).unwrap();
        let loss = |pred: &[f32]| -> (f32, f32) {
            let pred = Tensor::from_vec(pred.to_vec(), pred.len(), &Device::Cpu).unwrap();
            let descent = g.descent_loss(&pred).unwrap().unwrap();
            let slope = g.slope_loss(&pred).unwrap();
            (
                descent.to_scalar::<f32>().unwrap(),
                slope.to_scalar::<f32>().unwrap(),
            )
        };
        assert_eq!(loss(&targets), (0.0, 0.0));
        // The top neighbour (slot 0) now scores 0.001 above the goal: a shortfall of 0.006.
        let mut wrong = targets.clone();
        wrong[1] = targets[6] + 0.001;
        let (descent, slope) = loss(&wrong);
        assert!((descent - 0.006).abs() < 1e-6, "{descent}");
        // Its rise above the anchor is off by the same change, over 6 moves.
        let change = wrong[1] - targets[1];
        assert!((slope - change / 6.0).abs() < 1e-6, "{slope}");
    }

    /// A dense 3x3 batch: walls at (0,1) and (1,1), goal (0,2), exact `vin`-rule distances
    /// under `1 - d/100`. Cells (0,0), (1,0) and (2,0) are detour cells.
    fn dense_room() -> (Batch, Vec<f32>) {
        let s2 = std::f32::consts::SQRT_2;
        let d = [
            2.0 + 2.0 * s2,
            f32::INFINITY,
            0.0,
            1.0 + 2.0 * s2,
            f32::INFINITY,
            1.0,
            2.0 + s2,
            1.0 + s2,
            2.0,
        ];
        let targets = d
            .iter()
            .map(|&d| TargetEncoding::Linear { scale: 100.0 }.encode(d));
        let queries = (0..9)
            .flat_map(|i| [(i / 3) as f32, (i % 3) as f32])
            .collect();
        let batch = Batch {
            extent: vec![3, 3],
            items: 1,
            obstacles: Vec::new(),
            goals: vec![0.0, 2.0],
            per_item: 9,
            queries,
        };
        (batch, targets.collect())
    }

    #[test]
    fn dense_groups_gather_every_reachable_cell_with_its_moves() {
        let (batch, targets) = dense_room();
        let decode = |t: f32| TargetEncoding::Linear { scale: 100.0 }.decode(t);
        let (g, index) =
            Groups::dense(&batch, &targets, MoveRule::Vin, 0.005, 0.0, decode).unwrap();
        // Seven reachable cells, six decisions (none on the goal).
        assert_eq!((g.count, g.decisions), (7, 6));
        // The group of (2,1), the sixth reachable cell: up and down-left/right are not moves
        // (the anchor again); up-left (1,0) and up-right (1,2) are, under the vin rule.
        assert_eq!(index[5 * GROUP..6 * GROUP], [7, 7, 7, 6, 8, 3, 5, 7, 7]);
        let (_, strict) =
            Groups::dense(&batch, &targets, MoveRule::Strict, 0.005, 0.0, decode).unwrap();
        assert_eq!(strict[5 * GROUP..6 * GROUP], [7, 7, 7, 6, 8, 7, 7, 7, 7]);
        // The exact field scores zero; gathered outputs are read through `index`.
        let pred = Tensor::from_vec(targets.clone(), 9, &Device::Cpu).unwrap();
        let idx = Tensor::from_vec(index, g.count * GROUP, &Device::Cpu).unwrap();
        let gathered = pred.index_select(&idx, 0).unwrap();
        let descent = g.descent_loss(&gathered).unwrap().unwrap();
        assert_eq!(descent.to_scalar::<f32>().unwrap(), 0.0);
        assert_eq!(
            g.slope_loss(&gathered).unwrap().to_scalar::<f32>().unwrap(),
            0.0
        );
        // Detour share 0.5: the three detour cells weigh 7/6 each, the four others 7/8.
        let (w, _) = Groups::dense(&batch, &targets, MoveRule::Vin, 0.005, 0.5, decode).unwrap();
        let expected = 3.0 * 7.0 / 6.0 + 3.0 * 7.0 / 8.0;
        assert!(
            (w.decision_weight - expected).abs() < 1e-5,
            "{}",
            w.decision_weight
        );
    }

    #[test]
    fn the_weight_average_resumes_and_loads_from_a_checkpoint() {
        use crate::model::{ContextConfig, ModelConfig};
        let dir = std::env::temp_dir().join(format!("envfield-ema-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (batch, targets) = dense_room();
        let mut obstacles = vec![0.0; 9];
        (obstacles[1], obstacles[4]) = (1.0, 1.0);
        let batch = Batch { obstacles, ..batch };
        let model = ModelConfig::Context(ContextConfig::default());
        let config = TrainConfig {
            lr: 1e-2,
            ema_decay: 0.5,
            dense: true,
            descent_weight: 1.0,
            ..TrainConfig::default()
        };
        let mut a = Trainer::new(FieldNet::new(model, 3).unwrap(), config).unwrap();
        let raw = |t: &Trainer| t.net().forward(&batch).unwrap().to_vec1::<f32>().unwrap();
        let averaged = |t: &Trainer| {
            let net = t.averaged_net().unwrap();
            net.forward(&batch).unwrap().to_vec1::<f32>().unwrap()
        };
        for _ in 0..3 {
            a.train_batch(&batch, &targets).unwrap();
        }
        assert_ne!(raw(&a), averaged(&a), "the average lags the weights");
        let path = dir.join("ema.ckpt");
        a.save_checkpoint(&path).unwrap();
        // Loading a checkpoint as a network gives the average.
        let loaded = FieldNet::load(&path).unwrap();
        assert_eq!(
            loaded.forward(&batch).unwrap().to_vec1::<f32>().unwrap(),
            averaged(&a)
        );
        // A resumed run continues the same average.
        let mut b = Trainer::resume(&path).unwrap();
        a.train_batch(&batch, &targets).unwrap();
        b.train_batch(&batch, &targets).unwrap();
        assert_eq!(averaged(&a), averaged(&b));
        std::fs::remove_dir_all(&dir).ok();
    }
}
