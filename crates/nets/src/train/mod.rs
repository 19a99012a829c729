//! [`Trainer`]: L1 on the network's target encoding plus the neighbour-difference and descent
//! losses, AdamW, seeded batches, atomic checkpoints that resume exactly.

mod checkpoint;
mod config;
pub(crate) mod loss;
mod recipe;
mod sampler;

pub use checkpoint::DataCheck;
pub use config::{Progress, TrainConfig, TrainSummary};
pub use recipe::{resume_on, ContextOptions, LossShaping, MazeRecipe};

use crate::params::AdamW;
use crate::{Batch, FieldNet, NetsError, Result};
use candle_core::Tensor;
use envfield_mazes::{Dataset, Sample};
use loss::{rise_loss, Groups, GROUP};
use std::path::Path;
use std::time::Instant;

/// Trains a [`FieldNet`] on [`Dataset`]s.
#[derive(Debug)]
pub struct Trainer {
    net: FieldNet,
    optimiser: AdamW,
    config: TrainConfig,
    /// The moving average of the weights (see [`TrainConfig::ema_decay`]), one tensor per
    /// parameter in the store's order.
    ema: Option<Vec<Tensor>>,
    /// What the caller says the training data is (see [`Trainer::continue_with_data`]).
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
    /// The training config.
    pub fn config(&self) -> &TrainConfig {
        &self.config
    }

    /// Replaces the training config, for example to train a resumed run further or to
    /// fine-tune it with other losses. Switching [`TrainConfig::ema_decay`] on starts the
    /// moving average from the current weights (a kept average goes on); 0 drops it.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] naming the setting that is wrong, or a `hard_fraction`
    /// above 0 for a network that does not read the grid; the trainer is then unchanged.
    pub fn set_config(&mut self, config: TrainConfig) -> Result<()> {
        config.validate()?;
        check_hard(&self.net, &config)?;
        if config.ema_decay == 0.0 {
            self.ema = None;
        } else if self.ema.is_none() {
            self.ema = Some(weights(&self.net)?);
        }
        self.config = config;
        Ok(())
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
/// Copies of the network's weights in storage of their own (a detached tensor would share the
/// variable's storage, which each optimiser step overwrites).
fn weights(net: &FieldNet) -> Result<Vec<Tensor>> {
    Ok(net
        .vars()
        .iter()
        .map(|v| v.as_tensor().detach().copy())
        .collect::<candle_core::Result<_>>()?)
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
/// Mean absolute error of `net`'s encoded output (in its own [`crate::TargetEncoding`]) over every
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
            .zip(&s.distance)
            .map(|(p, &d)| (p - encoding.encode(d)).abs() as f64)
            .sum::<f64>();
        count += pred.len();
    }
    Ok((total / count.max(1) as f64) as f32)
}
