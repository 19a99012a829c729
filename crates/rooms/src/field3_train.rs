//! Training a learned 3D field on one region (paper section 4.2: one network per scene), and
//! measuring it against the exact field on goals it never trained on.

use crate::{AccessibleRegion, ExactField3, LearnedField3, Result, RoomsError};
use envfield_eikonal::{FastMarching, Order};
use envfield_grid::{Cell3, ContinuousField3, Field3, Point3m, SplitMix64};
use envfield_nets::{
    Batch, FieldNet, GoalConfig, MlpConfig, ModelConfig, TargetEncoding, TrainConfig, Trainer,
    BLOCKED,
};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// How a learned 3D field is trained on one region.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Field3Config {
    /// Training goals (random accessible voxels), each with its exact field.
    pub goals: usize,
    /// Held-out goals for the error figures (never trained on).
    pub held_out_goals: usize,
    /// Optimiser steps.
    pub steps: u64,
    /// Goals per step.
    pub goals_per_step: usize,
    /// Queries per goal per step.
    pub queries_per_goal: usize,
    /// Share of queries on inaccessible voxels (target: blocked, "negative" in the paper).
    pub blocked_fraction: f32,
    /// Peak learning rate (cosine decay to 5% of it).
    pub lr: f64,
    /// The network.
    pub mlp: MlpConfig,
    /// The network predicts the detour over the straight line ([`GoalConfig::detour`]).
    pub detour: bool,
    /// Share of the training goals drawn from the voxels of the region's sit-downs
    /// ([`AccessibleRegion::sit_downs`]) rather than evenly: the seats are a few percent of a
    /// room's voxels, and a field that rarely trains on a seated goal does not learn where it
    /// ends.
    #[serde(default)]
    pub sit_goal_share: f32,
    /// Share of the queries drawn from the accessible voxels within 4 voxels of their goal
    /// (along each axis) rather than evenly: the last steps to a goal read the field there.
    #[serde(default)]
    pub near_query_share: f32,
    /// Seed of goals, batches and weights.
    pub seed: u64,
}

/// How far from its goal a near query lies, voxels (along each axis).
const NEAR_GOAL: usize = 4;

impl Default for Field3Config {
    fn default() -> Self {
        Self {
            goals: 256,
            held_out_goals: 16,
            steps: 3000,
            goals_per_step: 16,
            queries_per_goal: 256,
            blocked_fraction: 0.1,
            lr: 1e-3,
            mlp: MlpConfig {
                hidden: 128,
                layers: 4,
                fourier: 4,
                ..MlpConfig::default()
            },
            detour: true,
            sit_goal_share: 0.25,
            near_query_share: 0.25,
            seed: 0,
        }
    }
}

/// The errors of a learned field against the exact one, metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Field3Report {
    /// Held-out (goal, query) pairs measured.
    pub pairs: usize,
    /// Median absolute error.
    pub median_err_m: f64,
    /// 95th percentile of the absolute error.
    pub p95_err_m: f64,
    /// Pairs whose query the network calls blocked although it is accessible, percent.
    pub blocked_pct: f64,
    /// Training seconds.
    pub train_s: f64,
}

impl Field3Report {
    /// Reports of several rooms as JSON: `field_rooms`, the means `field_median_err_m`,
    /// `field_p95_err_m` and `train_s_per_room`, and `field_worst_p95_err_m` (null without a
    /// report).
    pub fn summary_json(reports: &[Field3Report]) -> serde_json::Value {
        let any = !reports.is_empty();
        let mean = |f: fn(&Field3Report) -> f64| {
            any.then(|| reports.iter().map(f).sum::<f64>() / reports.len() as f64)
        };
        let worst = reports.iter().map(|r| r.p95_err_m).reduce(f64::max);
        serde_json::json!({
            "field_rooms": reports.len(),
            "field_median_err_m": mean(|r| r.median_err_m),
            "field_p95_err_m": mean(|r| r.p95_err_m),
            "field_worst_p95_err_m": worst,
            "train_s_per_room": mean(|r| r.train_s),
        })
    }
}

/// Random distinct accessible voxels.
fn pick_cells(free: &[Cell3], n: usize, rng: &mut SplitMix64) -> Vec<Cell3> {
    (0..n.min(free.len()))
        .map(|_| free[rng.below(free.len())])
        .collect()
}

/// Trains the goal-conditioned field on `region` (the paper trains one per scene): batches of
/// (goal, query) voxel pairs with the exact distance (voxel units, `linear` encoding scaled to
/// the region's longest distance), blocked targets on inaccessible voxels; then measures it on
/// held-out goals. `on_step(step, steps, loss)` follows the run; `checkpoint` is written every
/// 500 steps and at the end, and a run resumes from it when it exists.
///
/// # Errors
/// [`RoomsError::InvalidConfig`] for a bad config; [`RoomsError::InvalidInput`] for a region of
/// fewer than two voxels; training errors.
pub fn train_field3(
    region: &AccessibleRegion,
    config: &Field3Config,
    checkpoint: Option<&Path>,
    mut on_step: impl FnMut(u64, u64, f32),
) -> Result<(FieldNet, Field3Report)> {
    config.validate()?;
    let voxels = Voxels::of(region)?;
    let mut rng = SplitMix64::new(config.seed ^ 0xF13D);
    let targets = Targets::new(region, &voxels, config, &mut rng)?;
    let mut trainer = trainer_for(config, &targets, checkpoint)?;
    let start = Instant::now();
    while trainer.step() < config.steps {
        let (batch, wanted) = targets.batch(region, &voxels, config, trainer.step());
        let loss = trainer.train_batch(&batch, &wanted)?;
        let done = trainer.step();
        on_step(done, config.steps, loss);
        if let Some(p) = checkpoint {
            if done % 500 == 0 || done == config.steps {
                trainer.save_checkpoint(p)?;
            }
        }
    }
    let train_s = start.elapsed().as_secs_f64();
    let net = trainer.into_net();
    let report = held_out_report(
        region,
        &net,
        &voxels,
        &targets.goals,
        config,
        &mut rng,
        train_s,
    )?;
    Ok((net, report))
}

impl Field3Config {
    /// A fingerprint of every setting (FNV-1a of its JSON): a field kept under it was trained
    /// this way, so a cache of fields can tell when the training changed.
    pub fn key(&self) -> u64 {
        crate::sampling::fnv1a(serde_json::to_string(self).unwrap_or_default().into_bytes())
    }

    /// An error naming the first setting that cannot work.
    fn validate(&self) -> Result<()> {
        if self.goals == 0 || self.goals_per_step == 0 || self.queries_per_goal == 0 {
            return Err(RoomsError::InvalidConfig(
                "field3: goals, goals_per_step and queries_per_goal must be at least 1".into(),
            ));
        }
        if !(0.0..1.0).contains(&self.blocked_fraction) {
            return Err(RoomsError::InvalidConfig(format!(
                "field3: blocked_fraction in [0, 1) (got {})",
                self.blocked_fraction
            )));
        }
        for (name, v) in [
            ("sit_goal_share", self.sit_goal_share),
            ("near_query_share", self.near_query_share),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(RoomsError::InvalidConfig(format!(
                    "field3: {name} in [0, 1] (got {v})"
                )));
            }
        }
        if self.blocked_fraction + self.near_query_share > 1.0 {
            return Err(RoomsError::InvalidConfig(format!(
                "field3: blocked_fraction + near_query_share at most 1 (got {} + {})",
                self.blocked_fraction, self.near_query_share
            )));
        }
        Ok(())
    }
}

/// The region's accessible and inaccessible voxels.
struct Voxels {
    free: Vec<Cell3>,
    blocked: Vec<Cell3>,
}

impl Voxels {
    fn of(region: &AccessibleRegion) -> Result<Self> {
        let grid = &region.grid;
        let n = grid.len();
        let free: Vec<Cell3> = (0..n)
            .filter(|&i| !grid.obstacles()[i])
            .map(|i| grid.cell(i))
            .collect();
        let blocked: Vec<Cell3> = (0..n)
            .filter(|&i| grid.obstacles()[i])
            .map(|i| grid.cell(i))
            .collect();
        if free.len() < 2 {
            return Err(RoomsError::InvalidInput(format!(
                "the accessible region has {} voxel(s): nothing to learn",
                free.len()
            )));
        }
        Ok(Self { free, blocked })
    }
}

/// The training goals, their exact fields and the encoding of the targets.
struct Targets {
    goals: Vec<Cell3>,
    fields: Vec<Field3>,
    encoding: TargetEncoding,
    model: ModelConfig,
}

impl Targets {
    /// `config.goals` goals drawn from the accessible voxels, their exact fields by fast
    /// marching, the linear encoding scaled a quarter past the longest distance, and the
    /// network's config.
    fn new(
        region: &AccessibleRegion,
        voxels: &Voxels,
        config: &Field3Config,
        rng: &mut SplitMix64,
    ) -> Result<Self> {
        // The voxels a sit-down passes through, each once: where seated goals lie.
        let mut sitting: Vec<Cell3> = Vec::new();
        for sit in &region.sit_downs {
            for pose in sit.sequence()?.frames {
                if let Some(c) = region.frame.cell_of(&pose.torso()) {
                    if region.grid.is_free(c) && !sitting.contains(&c) {
                        sitting.push(c);
                    }
                }
            }
        }
        let from_sits = if sitting.is_empty() {
            0
        } else {
            (config.sit_goal_share * config.goals as f32).round() as usize
        };
        let mut goals = pick_cells(&voxels.free, config.goals - from_sits, rng);
        goals.extend((0..from_sits).map(|_| sitting[rng.below(sitting.len())]));
        let fields = FastMarching::with_order(Order::Second).solve3_many(&region.grid, &goals)?;
        let longest = fields
            .iter()
            .flat_map(|f| f.values().iter().copied().filter(|v| v.is_finite()))
            .fold(1.0f32, f32::max);
        let encoding = TargetEncoding::Linear {
            scale: (longest * 1.25).ceil(),
        };
        let model = ModelConfig::Goal(GoalConfig {
            extent: region.frame.shape.to_vec(),
            mlp: config.mlp,
            encoding,
            detour: config.detour,
        });
        Ok(Self {
            goals,
            fields,
            encoding,
            model,
        })
    }

    /// The batch of training step `step` and its encoded targets: `goals_per_step` goals,
    /// each with `queries_per_goal` voxels (a `blocked_fraction` of them inaccessible), drawn
    /// from a generator seeded by the step, so a resumed run draws the same batches.
    fn batch(
        &self,
        region: &AccessibleRegion,
        voxels: &Voxels,
        config: &Field3Config,
        step: u64,
    ) -> (Batch, Vec<f32>) {
        let (g, q) = (config.goals_per_step, config.queries_per_goal);
        let mut r = SplitMix64::new(config.seed ^ step.wrapping_mul(0x2545_F491_4F6C_DD1D));
        let mut goals = Vec::with_capacity(3 * g);
        let mut queries = Vec::with_capacity(3 * g * q);
        let mut targets = Vec::with_capacity(g * q);
        for _ in 0..g {
            let k = r.below(self.goals.len());
            let goal = self.goals[k];
            goals.extend([goal.x as f32, goal.y as f32, goal.z as f32]);
            for _ in 0..q {
                let u = r.next_f32();
                let on_blocked = !voxels.blocked.is_empty() && u < config.blocked_fraction;
                let near = !on_blocked && u < config.blocked_fraction + config.near_query_share;
                let c = if on_blocked {
                    voxels.blocked[r.below(voxels.blocked.len())]
                } else if let Some(c) = near.then(|| near_free(region, goal, &mut r)).flatten() {
                    c
                } else {
                    voxels.free[r.below(voxels.free.len())]
                };
                queries.extend([c.x as f32, c.y as f32, c.z as f32]);
                targets.push(match self.fields[k].get(c) {
                    Some(d) if d.is_finite() => self.encoding.encode(d),
                    _ => BLOCKED,
                });
            }
        }
        let extent = match &self.model {
            ModelConfig::Goal(c) => c.extent.clone(),
            _ => Vec::new(),
        };
        let batch = Batch {
            extent,
            items: g,
            obstacles: Vec::new(),
            goals,
            per_item: q,
            queries,
        };
        (batch, targets)
    }
}

/// An accessible voxel within [`NEAR_GOAL`] voxels of `goal` (along each axis), of up to
/// eight drawn; `None` when none of them is accessible.
fn near_free(region: &AccessibleRegion, goal: Cell3, r: &mut SplitMix64) -> Option<Cell3> {
    let reach = 2 * NEAR_GOAL + 1;
    (0..8).find_map(|_| {
        let c = Cell3::new(
            (goal.x + r.below(reach)).checked_sub(NEAR_GOAL)?,
            (goal.y + r.below(reach)).checked_sub(NEAR_GOAL)?,
            (goal.z + r.below(reach)).checked_sub(NEAR_GOAL)?,
        );
        region.grid.is_free(c).then_some(c)
    })
}

/// A new trainer for the targets' network, or the one `checkpoint` holds when it exists
/// (refused when it belongs to another region or network).
fn trainer_for(
    config: &Field3Config,
    targets: &Targets,
    checkpoint: Option<&Path>,
) -> Result<Trainer> {
    if let Some(p) = checkpoint.filter(|p| p.is_file()) {
        let t = Trainer::resume(p)?;
        if t.net().config() != &targets.model {
            return Err(RoomsError::Checkpoint {
                path: p.to_path_buf(),
                reason: "a checkpoint of another region or network; remove it to start over".into(),
            });
        }
        return Ok(t);
    }
    let train = TrainConfig {
        lr: config.lr,
        final_lr_fraction: 0.05,
        batch_items: config.goals_per_step,
        queries_per_item: config.queries_per_goal,
        steps: config.steps,
        seed: config.seed,
        ..TrainConfig::default()
    };
    Ok(Trainer::new(
        FieldNet::new(targets.model.clone(), config.seed)?,
        train,
    )?)
}

/// The learned field against the exact one on `config.held_out_goals` goals it never trained
/// on, 500 accessible query voxels each.
fn held_out_report(
    region: &AccessibleRegion,
    net: &FieldNet,
    voxels: &Voxels,
    trained: &[Cell3],
    config: &Field3Config,
    rng: &mut SplitMix64,
    train_s: f64,
) -> Result<Field3Report> {
    let trained: std::collections::HashSet<Cell3> = trained.iter().copied().collect();
    let candidates: Vec<Cell3> = voxels
        .free
        .iter()
        .copied()
        .filter(|c| !trained.contains(c))
        .collect();
    let held: Vec<Cell3> = pick_cells(&candidates, config.held_out_goals, rng);
    let mut errors = Vec::new();
    let mut wrongly_blocked = 0usize;
    for goal in held {
        let exact = ExactField3::at_cell(region, goal)?;
        let learned = LearnedField3::new(net, region, goal)?;
        let queries: Vec<Cell3> = pick_cells(&voxels.free, 500, rng);
        let points: Vec<Point3m> = queries
            .iter()
            .map(|&c| {
                let m = region.frame.center(c);
                Point3m::from(m)
            })
            .collect();
        let predicted = learned.values(&points)?;
        for (c, p) in queries.iter().zip(predicted) {
            let e = exact.at(*c);
            if !e.is_finite() {
                continue;
            }
            if p.is_finite() {
                errors.push((p - e).abs() as f64);
            } else {
                wrongly_blocked += 1;
                errors.push(f64::INFINITY);
            }
        }
    }
    errors.sort_by(f64::total_cmp);
    let quantile = |q: f64| -> f64 {
        if errors.is_empty() {
            return f64::NAN;
        }
        errors[((errors.len() - 1) as f64 * q).round() as usize]
    };
    Ok(Field3Report {
        pairs: errors.len(),
        median_err_m: quantile(0.5),
        p95_err_m: quantile(0.95),
        blocked_pct: 100.0 * wrongly_blocked as f64 / errors.len().max(1) as f64,
        train_s,
    })
}
