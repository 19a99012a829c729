//! 3D environment fields over an accessible region: the exact one (fast marching over the
//! accessible voxels, in metres) and the learned one (the goal-conditioned network, trained
//! per scene as in the paper), both behind [`ContinuousField3`].

use crate::{AccessibleRegion, Result, RoomsError};
use envfield_eikonal::{FastMarching, Order};
use envfield_grid::{Cell3, ContinuousField3, Field3, Point3, Point3m, SplitMix64};
use envfield_nets::{
    Batch, FieldNet, GoalConfig, MlpConfig, ModelConfig, TargetEncoding, TrainConfig, Trainer,
    BLOCKED,
};
use envfield_scene::VoxelFrame;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// A point in metres as continuous voxel coordinates (voxel centres at integers), checked to
/// lie within the lattice's box.
fn to_voxel(frame: &VoxelFrame, p: Point3m) -> envfield_grid::Result<Point3> {
    if !p.iter().all(|v| v.is_finite()) {
        return Err(envfield_grid::GridError::Invalid(format!(
            "point {p:?} is not finite"
        )));
    }
    let q: [f32; 3] = std::array::from_fn(|a| (p[a] - frame.origin[a]) / frame.voxel - 0.5);
    for a in 0..3 {
        let n = frame.shape[a] as f32;
        if q[a] < -0.5 || q[a] > n - 0.5 {
            return Err(envfield_grid::GridError::Invalid(format!(
                "point {p:?} is outside the field's box"
            )));
        }
    }
    let clamp = |v: f32, a: usize| v.clamp(0.0, (frame.shape[a] - 1) as f32);
    Ok(Point3::new(clamp(q[0], 0), clamp(q[1], 1), clamp(q[2], 2)))
}

/// The exact 3D field of an accessible region for one goal: fast marching over the accessible
/// voxels (second order, 6 neighbours), in metres. Between voxel centres it is trilinear over
/// the accessible corners (their weights renormalised), so it is finite everywhere in an
/// accessible voxel, right up to the region's faces, and infinite in an inaccessible one.
#[derive(Clone, Debug)]
pub struct ExactField3 {
    metres: Field3,
    frame: VoxelFrame,
    goal: Cell3,
}

impl ExactField3 {
    /// The field of `region` for the goal at `goal` (metres).
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] for a goal outside the accessible region.
    pub fn new(region: &AccessibleRegion, goal: [f32; 3]) -> Result<Self> {
        let cell = region.cell(goal, "goal")?;
        Self::at_cell(region, cell)
    }

    /// The field for the goal voxel `goal`.
    ///
    /// # Errors
    /// As [`ExactField3::new`].
    pub fn at_cell(region: &AccessibleRegion, goal: Cell3) -> Result<Self> {
        if !region.grid.is_free(goal) {
            return Err(RoomsError::InvalidInput(format!(
                "goal voxel {goal:?} is outside the accessible region"
            )));
        }
        let cells = FastMarching::with_order(Order::Second).solve3(&region.grid, &[goal])?;
        let v = region.frame.voxel;
        let metres = Field3::new(
            cells.shape(),
            cells.values().iter().map(|d| d * v).collect(),
        )?;
        Ok(Self {
            metres,
            frame: region.frame,
            goal,
        })
    }

    /// The values at voxel centres, metres.
    pub fn voxels(&self) -> &Field3 {
        &self.metres
    }

    /// The goal voxel.
    pub fn goal(&self) -> Cell3 {
        self.goal
    }
}

impl ContinuousField3 for ExactField3 {
    fn value(&self, p: Point3m) -> envfield_grid::Result<f32> {
        // Over the accessible corners: plain trilinear weighting would make every point within
        // half a voxel of the region's faces infinite, and a torso standing in an accessible
        // voxel near a wall could neither be reached nor left.
        self.metres.sample_finite(to_voxel(&self.frame, p)?)
    }

    /// Central differences of the trilinear interpolant over half a voxel.
    fn gradient(&self, p: Point3m) -> envfield_grid::Result<Option<Point3m>> {
        self.value(p)?;
        let h = 0.5 * self.frame.voxel;
        let mut g = [0.0; 3];
        for a in 0..3 {
            let (mut lo, mut hi) = (p, p);
            lo[a] -= h;
            hi[a] += h;
            let (Ok(vl), Ok(vh)) = (self.value(lo), self.value(hi)) else {
                return Ok(None);
            };
            if !(vl.is_finite() && vh.is_finite()) {
                return Ok(None);
            }
            g[a] = (vh - vl) / (2.0 * h);
        }
        Ok(Some(g))
    }
}

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
    /// Seed of goals, batches and weights.
    pub seed: u64,
}

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
    if config.goals == 0 || config.goals_per_step == 0 || config.queries_per_goal == 0 {
        return Err(RoomsError::InvalidConfig(
            "field3: goals, goals_per_step and queries_per_goal must be at least 1".into(),
        ));
    }
    if !(0.0..1.0).contains(&config.blocked_fraction) {
        return Err(RoomsError::InvalidConfig(format!(
            "field3: blocked_fraction in [0, 1) (got {})",
            config.blocked_fraction
        )));
    }
    let shape = region.frame.shape;
    let n = shape[0] * shape[1] * shape[2];
    let cell = |i: usize| {
        Cell3::new(
            i / (shape[1] * shape[2]),
            (i / shape[2]) % shape[1],
            i % shape[2],
        )
    };
    let free: Vec<Cell3> = (0..n)
        .filter(|&i| !region.grid.obstacles()[i])
        .map(cell)
        .collect();
    let blocked: Vec<Cell3> = (0..n)
        .filter(|&i| region.grid.obstacles()[i])
        .map(cell)
        .collect();
    if free.len() < 2 {
        return Err(RoomsError::InvalidInput(format!(
            "the accessible region has {} voxel(s): nothing to learn",
            free.len()
        )));
    }
    let mut rng = SplitMix64::new(config.seed ^ 0xF13D);
    let goals = pick_cells(&free, config.goals, &mut rng);
    let fmm = FastMarching::with_order(Order::Second);
    let fields = fmm.solve3_many(&region.grid, &goals)?;
    let longest = fields
        .iter()
        .flat_map(|f| f.values().iter().copied().filter(|v| v.is_finite()))
        .fold(1.0f32, f32::max);
    let encoding = TargetEncoding::Linear {
        scale: (longest * 1.25).ceil(),
    };
    let model = ModelConfig::Goal(GoalConfig {
        extent: shape.to_vec(),
        mlp: config.mlp,
        encoding,
        detour: config.detour,
    });
    let train = TrainConfig {
        lr: config.lr,
        final_lr_fraction: 0.05,
        batch_items: config.goals_per_step,
        queries_per_item: config.queries_per_goal,
        steps: config.steps,
        seed: config.seed,
        ..TrainConfig::default()
    };
    let mut trainer = match checkpoint.filter(|p| p.is_file()) {
        Some(p) => {
            let t = Trainer::resume(p)?;
            if t.net().config() != &model {
                return Err(RoomsError::Checkpoint {
                    path: p.to_path_buf(),
                    reason: "a checkpoint of another region or network; remove it to start over"
                        .into(),
                });
            }
            t
        }
        None => Trainer::new(FieldNet::new(model, config.seed)?, train)?,
    };
    let start = Instant::now();
    let (g, q) = (config.goals_per_step, config.queries_per_goal);
    while trainer.step() < config.steps {
        let step = trainer.step();
        let mut r = SplitMix64::new(config.seed ^ step.wrapping_mul(0x2545_F491_4F6C_DD1D));
        let mut batch_goals = Vec::with_capacity(3 * g);
        let mut queries = Vec::with_capacity(3 * g * q);
        let mut targets = Vec::with_capacity(g * q);
        for _ in 0..g {
            let k = r.below(goals.len());
            let goal = goals[k];
            batch_goals.extend([goal.x as f32, goal.y as f32, goal.z as f32]);
            for _ in 0..q {
                let on_blocked = !blocked.is_empty() && r.next_f32() < config.blocked_fraction;
                let c = if on_blocked {
                    blocked[r.below(blocked.len())]
                } else {
                    free[r.below(free.len())]
                };
                queries.extend([c.x as f32, c.y as f32, c.z as f32]);
                targets.push(match fields[k].get(c) {
                    Some(d) if d.is_finite() => encoding.encode(d),
                    _ => BLOCKED,
                });
            }
        }
        let batch = Batch {
            extent: shape.to_vec(),
            items: g,
            obstacles: Vec::new(),
            goals: batch_goals,
            per_item: q,
            queries,
        };
        let loss = trainer.train_batch(&batch, &targets)?;
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
    // Held-out goals: not among the training goals.
    let trained: std::collections::HashSet<Cell3> = goals.iter().copied().collect();
    let candidates: Vec<Cell3> = free
        .iter()
        .copied()
        .filter(|c| !trained.contains(c))
        .collect();
    let held: Vec<Cell3> = pick_cells(&candidates, config.held_out_goals, &mut rng);
    let mut errors = Vec::new();
    let mut wrongly_blocked = 0usize;
    for goal in held {
        let exact = ExactField3::at_cell(region, goal)?;
        let learned = LearnedField3::new(&net, region, goal)?;
        let queries: Vec<Cell3> = pick_cells(&free, 500, &mut rng);
        let points: Vec<Point3m> = queries
            .iter()
            .map(|&c| {
                let m = region.frame.center(c);
                [m.x, m.y, m.z]
            })
            .collect();
        let predicted = learned.values(&points)?;
        for (c, p) in queries.iter().zip(predicted) {
            let e = exact.voxels().get(*c).unwrap_or(f32::INFINITY);
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
    let report = Field3Report {
        pairs: errors.len(),
        median_err_m: quantile(0.5),
        p95_err_m: quantile(0.95),
        blocked_pct: 100.0 * wrongly_blocked as f64 / errors.len().max(1) as f64,
        train_s,
    };
    Ok((net, report))
}

/// A learned 3D field bound to one region's lattice and goal, in metres.
#[derive(Debug)]
pub struct LearnedField3<'a> {
    net: &'a FieldNet,
    frame: VoxelFrame,
    goal: Cell3,
}

impl<'a> LearnedField3<'a> {
    /// `net` (a goal-conditioned network over `region`'s lattice) for the goal voxel `goal`.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] for a network of another lattice or a goal outside the
    /// region.
    pub fn new(net: &'a FieldNet, region: &AccessibleRegion, goal: Cell3) -> Result<Self> {
        match net.config() {
            ModelConfig::Goal(c) if c.extent == region.frame.shape.to_vec() => {}
            other => {
                return Err(RoomsError::InvalidInput(format!(
                    "a 3D field needs a goal-conditioned network over the region's {:?} voxels, \
                     not a {} network{}",
                    region.frame.shape,
                    other.arch(),
                    match other {
                        ModelConfig::Goal(c) => format!(" over {:?}", c.extent),
                        _ => String::new(),
                    }
                )))
            }
        }
        if !region.grid.is_free(goal) {
            return Err(RoomsError::InvalidInput(format!(
                "goal voxel {goal:?} is outside the accessible region"
            )));
        }
        Ok(Self {
            net,
            frame: region.frame,
            goal,
        })
    }

    fn batch(&self, points: &[Point3m]) -> envfield_grid::Result<Batch> {
        let mut queries = Vec::with_capacity(3 * points.len());
        for &p in points {
            let q = to_voxel(&self.frame, p)?;
            queries.extend([q.x, q.y, q.z]);
        }
        Ok(Batch {
            extent: self.frame.shape.to_vec(),
            items: 1,
            obstacles: Vec::new(),
            goals: vec![self.goal.x as f32, self.goal.y as f32, self.goal.z as f32],
            per_item: points.len(),
            queries,
        })
    }
}

fn model_error(e: envfield_nets::NetsError) -> envfield_grid::GridError {
    envfield_grid::GridError::Model {
        model: "field3".into(),
        source: Box::new(e),
    }
}

impl ContinuousField3 for LearnedField3<'_> {
    fn value(&self, p: Point3m) -> envfield_grid::Result<f32> {
        Ok(self.values(&[p])?[0])
    }

    /// One network pass for all the points.
    fn values(&self, points: &[Point3m]) -> envfield_grid::Result<Vec<f32>> {
        if points.is_empty() {
            return Ok(Vec::new());
        }
        let raw = self
            .net
            .predict_encoded(&self.batch(points)?)
            .map_err(model_error)?;
        let encoding = self.net.config().encoding();
        let v = self.frame.voxel;
        Ok(raw.iter().map(|&t| encoding.decode(t) * v).collect())
    }

    fn gradient(&self, p: Point3m) -> envfield_grid::Result<Option<Point3m>> {
        let (raw, grad) = self
            .net
            .predict_with_gradient(&self.batch(&[p])?)
            .map_err(model_error)?;
        let encoding = self.net.config().encoding();
        if !encoding.decode(raw[0]).is_finite() {
            return Ok(None);
        }
        // d metres / d metres: the output's slope per voxel unit, in metres per voxel, over
        // metres per voxel.
        let slope = encoding.slope(raw[0]);
        Ok(Some([slope * grad[0], slope * grad[1], slope * grad[2]]))
    }
}
