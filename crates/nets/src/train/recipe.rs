//! The maze training recipe the examples share: the training and held-out datasets of every
//! maze size for an architecture, and a resumed trainer checked against its data.

use crate::{
    parse_convs, Arch, DataCheck, ModelConfig, PathConfig, PropagationConfig, Result, TrainConfig,
    Trainer,
};
use envfield_grid::MoveRule;
use envfield_mazes::{Dataset, DatasetConfig, GeneratorKind, MazeGenerator, TargetKind};
use std::path::Path;

/// The data of a maze training run: what [`MazeRecipe::datasets`] makes for each maze size.
#[derive(Clone, Debug, PartialEq)]
pub struct MazeRecipe {
    /// The network the data is for: plain and goal-conditioned fields learn one maze.
    pub arch: Arch,
    /// The layout family.
    pub generator: GeneratorKind,
    /// Maze sides, one dataset each.
    pub sizes: Vec<usize>,
    /// Training mazes per size (one for plain and goal-conditioned fields).
    pub mazes: usize,
    /// Goals per training maze (at least 64 for a goal-conditioned field's one maze).
    pub goals_per_maze: usize,
    /// The target field.
    pub target: TargetKind,
    /// Seed of the training mazes; the held-out ones use other seeds.
    pub seed: u64,
}

impl MazeRecipe {
    /// Maze sides from a comma-separated list such as `8,16,28`.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`](crate::NetsError) naming the entry that is not a number.
    pub fn parse_sizes(list: &str) -> Result<Vec<usize>> {
        list.split(',')
            .map(|s| {
                s.trim().parse().map_err(|_| {
                    crate::NetsError::InvalidConfig(format!("bad size entry `{s}` in `{list}`"))
                })
            })
            .collect()
    }

    /// An error naming the first setting that cannot work: no maze or goal, more than 10
    /// million samples per size, no size, or several sizes for a field that learns one maze.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`](crate::NetsError).
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(crate::NetsError::InvalidConfig(m));
        if self.mazes == 0 || self.goals_per_maze == 0 {
            return bad(
                "mazes and goals per maze must be at least 1: there is nothing to \
                        train on"
                    .into(),
            );
        }
        if self.mazes.saturating_mul(self.goals_per_maze) > 10_000_000 {
            return bad(format!(
                "{} mazes x {} goals per maze is more than 10,000,000 samples per size",
                self.mazes, self.goals_per_maze
            ));
        }
        if self.sizes.is_empty() || (self.arch.learns_one_scene() && self.sizes.len() > 1) {
            return bad(format!(
                "a {} network learns one maze: give one size",
                self.arch
            ));
        }
        Ok(())
    }

    /// Held-out mazes of `size` for the navigation check after training: `count` generated
    /// mazes of a seed the training never used, or for a field that learns one maze, that
    /// maze with its goal (`first`, a training sample).
    ///
    /// # Errors
    /// Errors of the generator.
    pub fn check_mazes(
        &self,
        size: usize,
        count: usize,
        first: &envfield_mazes::Sample,
    ) -> Result<Vec<envfield_grid::Maze>> {
        if self.arch.learns_one_scene() {
            return Ok(vec![envfield_grid::Maze {
                grid: first.grid.clone(),
                start: None,
                goal: Some(first.goal),
            }]);
        }
        Ok(
            MazeGenerator::new(self.generator, size)?
                .generate_many(count, self.seed + 1_000_003)?,
        )
    }

    /// A description of the data, recorded in checkpoints so a resumed run is checked
    /// against it.
    pub fn describe(&self) -> String {
        let sizes: Vec<String> = self.sizes.iter().map(|s| s.to_string()).collect();
        format!(
            "generator {}, sizes {}, {} mazes x {} goals per size, target {}, seed {}",
            self.generator,
            sizes.join(","),
            self.mazes,
            self.goals_per_maze,
            self.target,
            self.seed
        )
    }

    /// The training and held-out datasets, one of each per size. Held out: 64 mazes of
    /// another seed with one goal each, or for a field that learns one maze, up to 16 other
    /// goals on that maze.
    ///
    /// # Errors
    /// Errors of the generators and fields.
    pub fn datasets(&self) -> Result<(Vec<Dataset>, Vec<Dataset>)> {
        let single = self.arch.learns_one_scene();
        let (mut train, mut held) = (Vec::new(), Vec::new());
        for &size in &self.sizes {
            let (mazes, goals) = match self.arch {
                Arch::Plain => (1, 1),
                Arch::Goal => (1, self.goals_per_maze.max(64)),
                Arch::Context | Arch::Hyper => (self.mazes, self.goals_per_maze),
            };
            let cfg = DatasetConfig {
                generator: MazeGenerator::new(self.generator, size)?,
                mazes,
                goals_per_maze: goals,
                target: self.target,
                extra_obstacles: 0.0,
                seed: self.seed,
            };
            train.push(Dataset::generate(&cfg)?);
            held.push(match single {
                true => Dataset::generate(&DatasetConfig {
                    goals_per_maze: goals.min(16),
                    seed: self.seed ^ 0x51,
                    ..cfg
                })?,
                false => Dataset::generate(&DatasetConfig {
                    mazes: 64,
                    goals_per_maze: 1,
                    seed: self.seed + 1_000_003,
                    ..cfg
                })?,
            });
        }
        Ok((train, held))
    }
}

/// The trainer of checkpoint `path`, checked against the data it continues on (`data`, a
/// [`MazeRecipe::describe`]): other data is refused unless `new_data`; the second value says
/// what was accepted, for the caller to print (`None` for the same data).
///
/// # Errors
/// Errors of reading the checkpoint; [`NetsError::DataMismatch`](crate::NetsError) for other
/// data without `new_data`.
pub fn resume_on(path: &Path, data: &str, new_data: bool) -> Result<(Trainer, Option<String>)> {
    let mut t = Trainer::resume(path)?;
    let note = match t.continue_with_data(data, new_data) {
        Ok(DataCheck::Same) => None,
        Ok(DataCheck::Changed { recorded }) => Some(format!(
            "new data: {} was trained on {recorded}; going on with {data}",
            path.display()
        )),
        Ok(DataCheck::Unrecorded) => Some(format!(
            "warning: {} does not record its training data (an older checkpoint); going on \
             with {data}",
            path.display()
        )),
        Err(e) => return Err(e),
    };
    Ok((t, note))
}

/// The loss-shaping settings a run may change, each left as it is when `None` (`dense` only
/// switches dense queries on): what a resumed run takes from its flags.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LossShaping {
    /// [`TrainConfig::neighbour_weight`].
    pub neighbour_weight: Option<f64>,
    /// [`TrainConfig::detour_fraction`].
    pub detour_fraction: Option<f64>,
    /// [`TrainConfig::far_fraction`].
    pub far_fraction: Option<f64>,
    /// [`TrainConfig::hard_fraction`].
    pub hard_fraction: Option<f64>,
    /// [`TrainConfig::descent_weight`], with its margin and rule.
    pub descent: Option<(f64, f64, MoveRule)>,
    /// [`TrainConfig::dense`], switched on.
    pub dense: bool,
    /// [`TrainConfig::ema_decay`].
    pub ema_decay: Option<f64>,
}

impl LossShaping {
    /// `config` with these settings applied.
    pub fn apply(&self, mut config: TrainConfig) -> TrainConfig {
        let set = |v: &mut f64, o: Option<f64>| *v = o.unwrap_or(*v);
        set(&mut config.neighbour_weight, self.neighbour_weight);
        set(&mut config.detour_fraction, self.detour_fraction);
        set(&mut config.far_fraction, self.far_fraction);
        set(&mut config.hard_fraction, self.hard_fraction);
        set(&mut config.ema_decay, self.ema_decay);
        if let Some((w, margin, rule)) = self.descent {
            (
                config.descent_weight,
                config.descent_margin,
                config.descent_rule,
            ) = (w, margin, rule);
        }
        config.dense |= self.dense;
        config
    }
}

/// Changes to a context network's preset: what `train_maze`'s architecture flags set.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContextOptions {
    /// Residual convolutions.
    pub residual: bool,
    /// The encoder as `CHANNELS:DILATION,...` ([`parse_convs`]), or the preset's.
    pub encoder: Option<String>,
    /// The shortest-path readout in place of the MLP (no goal channel then).
    pub path: Option<PathConfig>,
    /// Value-iteration layers.
    pub propagation: Option<PropagationConfig>,
    /// The MLP's hidden width and layers.
    pub mlp: Option<(usize, usize)>,
}

impl ContextOptions {
    /// `model` with these changes when it is a context network; other networks as they are.
    ///
    /// # Errors
    /// A bad encoder spec.
    pub fn apply(&self, mut model: ModelConfig) -> Result<ModelConfig> {
        if let ModelConfig::Context(c) = &mut model {
            c.residual = self.residual;
            if let Some(spec) = &self.encoder {
                c.encoder = parse_convs(spec)?;
            }
            if let Some(path) = self.path {
                (c.path, c.goal_channel) = (Some(path), false);
            }
            if self.propagation.is_some() {
                c.propagation = self.propagation;
            }
            if let Some((hidden, layers)) = self.mlp {
                (c.mlp.hidden, c.mlp.layers) = (hidden, layers);
            }
        }
        Ok(model)
    }
}
