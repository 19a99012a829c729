//! [`TrainConfig`]: how to train, and what a run reports.

use super::loss::GROUP;
use crate::{NetsError, Result};
use envfield_grid::MoveRule;
use serde::{Deserialize, Serialize};
use std::time::Duration;

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
    /// Needs nothing of the network (the reachable cells come from the targets).
    #[serde(default)]
    pub dense: bool,
    /// Decay of an exponential moving average of the weights, updated after every step
    /// (`ema = decay * ema + (1 - decay) * weights`, starting from the weights where it is
    /// switched on); 0 keeps none. [`crate::Trainer::averaged_net`] gives the averaged network, and
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

/// Queries in one training step beyond which a config is refused: a typo, not a batch that
/// fits in memory.
const MAX_QUERIES_PER_STEP: usize = 1 << 22;

impl TrainConfig {
    /// Checks every setting, in the order of the fields, and names the first that is wrong.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] naming the field, its rule and its value.
    pub fn validate(&self) -> Result<()> {
        let unit = |x: f64| (0.0..=1.0).contains(&x);
        let below_one = |x: f64| (0.0..1.0).contains(&x);
        let pairs = self.neighbour_weight == 0.0
            || self.dense
            || self.grouped()
            || self.queries_per_item % 2 == 0;
        let groups = self.descent_weight == 0.0 || self.dense || self.queries_per_item % GROUP == 0;
        let per_step = self.batch_items.saturating_mul(self.queries_per_item);
        let checks: [(bool, &str, &str, String); 19] = [
            (self.lr.is_finite() && self.lr > 0.0, "lr", "must be positive and finite", self.lr.to_string()),
            (unit(self.final_lr_fraction), "final_lr_fraction", "must be in [0, 1]", self.final_lr_fraction.to_string()),
            (below_one(self.betas.0), "betas.0", "must be in [0, 1)", self.betas.0.to_string()),
            (below_one(self.betas.1), "betas.1", "must be in [0, 1)", self.betas.1.to_string()),
            (self.eps > 0.0, "eps", "must be positive", self.eps.to_string()),
            (self.weight_decay >= 0.0, "weight_decay", "must be >= 0", self.weight_decay.to_string()),
            (self.batch_items > 0, "batch_items", "must be >= 1", self.batch_items.to_string()),
            (self.queries_per_item > 0, "queries_per_item", "must be >= 1", self.queries_per_item.to_string()),
            (per_step <= MAX_QUERIES_PER_STEP, "batch_items x queries_per_item", "must be at most 4194304 queries per step", per_step.to_string()),
            (self.validation_samples > 0, "validation_samples", "must be >= 1", self.validation_samples.to_string()),
            (self.neighbour_weight >= 0.0, "neighbour_weight", "must be >= 0", self.neighbour_weight.to_string()),
            (pairs, "queries_per_item", "must be even with a neighbour_weight (queries come in pairs)", self.queries_per_item.to_string()),
            (unit(self.detour_fraction), "detour_fraction", "must be in [0, 1]", self.detour_fraction.to_string()),
            (unit(self.far_fraction), "far_fraction", "must be in [0, 1]", self.far_fraction.to_string()),
            (unit(self.hard_fraction), "hard_fraction", "must be in [0, 1]", self.hard_fraction.to_string()),
            (self.descent_weight >= 0.0, "descent_weight", "must be >= 0", self.descent_weight.to_string()),
            (groups, "queries_per_item", "must be a multiple of 9 with a descent_weight (groups of a cell and its 8 neighbours)", self.queries_per_item.to_string()),
            (self.descent_margin > 0.0, "descent_margin", "must be positive", self.descent_margin.to_string()),
            (below_one(self.ema_decay), "ema_decay", "must be in [0, 1)", self.ema_decay.to_string()),
        ];
        match checks.into_iter().find(|c| !c.0) {
            Some((_, field, rule, value)) => Err(NetsError::InvalidConfig(format!(
                "training: {field} {rule} (got {value})"
            ))),
            None => Ok(()),
        }
    }

    /// Whether queries come in groups of an anchor and its 8 neighbours.
    pub(crate) fn grouped(&self) -> bool {
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
