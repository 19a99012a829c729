//! `train_maze`'s flags.

use clap::Parser;
use envfield::mazes::{GeneratorKind, TargetKind};
use envfield::nets::{Arch, TargetEncoding};
use std::path::PathBuf;

#[derive(Parser)]
#[command(about = "Train an environment-field network on generated mazes")]
pub struct Args {
    /// plain, goal, context or hyper.
    #[arg(long, default_value = "context")]
    pub arch: Arch,
    /// gridworld, crossings, rooms or perfect.
    #[arg(long, default_value = "gridworld")]
    pub generator: GeneratorKind,
    /// Maze side, or several separated by commas (one model for all).
    #[arg(long, default_value = "28")]
    pub size: String,
    /// Training mazes per size (plain and goal use one maze).
    #[arg(long, default_value_t = 5000)]
    pub mazes: usize,
    /// Goals per training maze.
    #[arg(long, default_value_t = 4)]
    pub goals_per_maze: usize,
    /// Target field: vin or strict (graph distance under that rule), fmm1 or fmm2.
    #[arg(long, default_value = "vin")]
    pub target: TargetKind,
    /// Total optimiser steps.
    #[arg(long, default_value_t = 20_000)]
    pub steps: u64,
    /// Mazes (with one goal each) per step.
    #[arg(long, default_value_t = 32)]
    pub batch: usize,
    /// Query cells per maze per step.
    #[arg(long, default_value_t = 256)]
    pub queries: usize,
    /// Peak learning rate (the paper's 5e-5 is the library default; larger trains faster here).
    #[arg(long, default_value_t = 1e-3)]
    pub lr: f64,
    /// Final learning rate as a fraction of the peak (cosine decay).
    #[arg(long, default_value_t = 0.05)]
    pub final_lr: f64,
    /// Seed of the data, the weights and the batches.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Where the final weights go (a checkpoint with optimiser state goes to OUT.ckpt).
    #[arg(long, default_value = "out/field.safetensors")]
    pub out: PathBuf,
    /// Resume from this checkpoint (its model and training configs win over the flags,
    /// except --steps and the flags that say they apply to a resumed run). The data flags
    /// (--generator, --size, --mazes, --goals-per-maze, --target, --seed) must be the ones of
    /// the run it continues: the checkpoint records them and other ones are an error (unless
    /// --new-data).
    #[arg(long)]
    pub resume: Option<PathBuf>,
    /// With --resume: continue on purpose on data other than the checkpoint's (fine-tuning,
    /// a curriculum); these data flags replace the recorded ones.
    #[arg(long)]
    pub new_data: bool,
    /// Held-out mazes for the navigation check at the end.
    #[arg(long, default_value_t = 200)]
    pub eval_mazes: usize,
    /// Output encoding: `reciprocal` (the paper's 1/(1+d)) or `linear:SCALE` (1 - d/SCALE).
    #[arg(long, default_value = "reciprocal")]
    pub encoding: TargetEncoding,
    /// Context encoder convolutions as CHANNELS:DILATION, comma-separated, `Nx[...]` repeating
    /// a group (`16:1,8x[16:1,16:2,16:4,16:8],32:1`: 34 convolutions). Default: the library's
    /// 11-layer dilated encoder.
    #[arg(long)]
    pub encoder: Option<String>,
    /// Residual context encoder: each convolution that keeps the channel count adds its input
    /// (`relu(x + conv(x))`), for encoders deeper than the default.
    #[arg(long)]
    pub residual: bool,
    /// Add value-iteration layers with this many Q channels to the context encoder (0: none).
    #[arg(long, default_value_t = 0)]
    pub propagation: usize,
    /// Value iterations per cell of the maze's longer side (with --propagation); paths longer
    /// than the iterations reach get no value from the goal.
    #[arg(long, default_value_t = 1.3)]
    pub propagation_iterations: f32,
    /// The shortest-path readout in place of the context network's MLP: the encoder gives
    /// eight move costs per cell and the field is the min-plus fixed point over them
    /// (`envfield_nets::PathConfig`), under the --target's rule. No goal channel.
    #[arg(long)]
    pub path: bool,
    /// With --path: the least cost of a move, in cells.
    #[arg(long, default_value_t = 0.05)]
    pub min_cost: f32,
    /// MLP hidden width and layers of the context network, as WIDTH:LAYERS.
    #[arg(long, default_value = "64:3")]
    pub mlp: String,
    /// Weight of the neighbour-difference loss (0: plain L1). Also applies to a resumed run.
    #[arg(long)]
    pub neighbour_weight: Option<f64>,
    /// Fraction of queries drawn from detour cells (distance above the octile distance to the
    /// goal: the path bends around obstacles). Also applies to a resumed run.
    #[arg(long)]
    pub detour_fraction: Option<f64>,
    /// Fraction of anchor queries drawn from far cells (at least half the maze's largest
    /// reachable distance from the goal), before --detour-fraction applies. Also applies to a
    /// resumed run.
    #[arg(long)]
    pub far_fraction: Option<f64>,
    /// Fraction of anchor queries drawn from the cells where the network's descent move is
    /// wrong at this step (one whole-field prediction per sampled maze and step; context and
    /// hyper networks). Also applies to a resumed run.
    #[arg(long)]
    pub hard_fraction: Option<f64>,
    /// Weight of the descent loss (0: off): queries in groups of a cell and its 8 neighbours;
    /// each move other than the best ones should score below the best by --descent-margin
    /// (hinge). Needs --queries divisible by 9. Also applies to a resumed run.
    #[arg(long)]
    pub descent_weight: Option<f64>,
    /// Margin of the descent loss in output units (linear:100 -> 0.01 per cell)
    #[arg(long, default_value_t = 0.005)]
    pub descent_margin: f64,
    /// Dense queries: every cell of each maze, and the neighbour-difference and descent losses
    /// over every reachable cell (--queries is then unused, and --detour-fraction is the share
    /// of those losses' weight on detour cells). Also switches a resumed run to dense queries.
    #[arg(long)]
    pub dense: bool,
    /// Keep a moving average of the weights with this decay (0.999: about the last 1000
    /// steps) and export it; checkpoints carry it. Also applies to a resumed run.
    #[arg(long)]
    pub ema: Option<f64>,
    /// Stop (with a checkpoint) at this step, before --steps; the learning-rate schedule still
    /// follows --steps, so a later --resume continues the same run.
    #[arg(long)]
    pub stop_at: Option<u64>,
    /// Checkpoint and validate every N steps.
    #[arg(long, default_value_t = 500)]
    pub every: u64,
}
