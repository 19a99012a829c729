//! Trains an environment-field network on generated mazes, checkpointing as it goes, and
//! reports the validation loss and the navigation success on held-out generated mazes.
//!
//! ```text
//! cargo run --release --example train_maze -- --arch context --size 28 --steps 20000 --out models/context_28.safetensors
//! cargo run --release --example train_maze -- --resume models/context_28.safetensors.ckpt --steps 30000 --out models/context_28.safetensors
//! cargo run --release --example train_maze -- --arch plain --size 8 --steps 2000 --lr 1e-3
//! ```
//!
//! `--size 8,16,28` trains one model on all three sizes (one dataset per size, taken in turn).

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::mazes::{Dataset, DatasetConfig, GeneratorKind, MazeGenerator, TargetKind};
use envfield::nets::{
    parse_convs, Arch, DataCheck, FieldNet, ModelConfig, PathConfig, PropagationConfig,
    TargetEncoding, TrainConfig, Trainer,
};
use envfield::plan::{evaluate, EvalConfig, FieldDescent};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "Train an environment-field network on generated mazes")]
struct Args {
    /// plain, goal, context or hyper.
    #[arg(long, default_value = "context")]
    arch: Arch,
    /// gridworld, crossings, rooms or perfect.
    #[arg(long, default_value = "gridworld")]
    generator: GeneratorKind,
    /// Maze side, or several separated by commas (one model for all).
    #[arg(long, default_value = "28")]
    size: String,
    /// Training mazes per size (plain and goal use one maze).
    #[arg(long, default_value_t = 5000)]
    mazes: usize,
    /// Goals per training maze.
    #[arg(long, default_value_t = 4)]
    goals_per_maze: usize,
    /// Target field: vin or strict (graph distance under that rule), fmm1 or fmm2.
    #[arg(long, default_value = "vin")]
    target: TargetKind,
    /// Total optimiser steps.
    #[arg(long, default_value_t = 20_000)]
    steps: u64,
    /// Mazes (with one goal each) per step.
    #[arg(long, default_value_t = 32)]
    batch: usize,
    /// Query cells per maze per step.
    #[arg(long, default_value_t = 256)]
    queries: usize,
    /// Peak learning rate (the paper's 5e-5 is the library default; larger trains faster here).
    #[arg(long, default_value_t = 1e-3)]
    lr: f64,
    /// Final learning rate as a fraction of the peak (cosine decay).
    #[arg(long, default_value_t = 0.05)]
    final_lr: f64,
    /// Seed of the data, the weights and the batches.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Where the final weights go (a checkpoint with optimiser state goes to OUT.ckpt).
    #[arg(long, default_value = "out/field.safetensors")]
    out: PathBuf,
    /// Resume from this checkpoint (its model and training configs win over the flags,
    /// except --steps and the flags that say they apply to a resumed run). The data flags
    /// (--generator, --size, --mazes, --goals-per-maze, --target, --seed) must be the ones of
    /// the run it continues: the checkpoint records them and other ones are an error (unless
    /// --new-data).
    #[arg(long)]
    resume: Option<PathBuf>,
    /// With --resume: continue on purpose on data other than the checkpoint's (fine-tuning,
    /// a curriculum); these data flags replace the recorded ones.
    #[arg(long)]
    new_data: bool,
    /// Held-out mazes for the navigation check at the end.
    #[arg(long, default_value_t = 200)]
    eval_mazes: usize,
    /// Output encoding: `reciprocal` (the paper's 1/(1+d)) or `linear:SCALE` (1 - d/SCALE).
    #[arg(long, default_value = "reciprocal")]
    encoding: TargetEncoding,
    /// Context encoder convolutions as CHANNELS:DILATION, comma-separated, `Nx[...]` repeating
    /// a group (`16:1,8x[16:1,16:2,16:4,16:8],32:1`: 34 convolutions). Default: the library's
    /// 11-layer dilated encoder.
    #[arg(long)]
    encoder: Option<String>,
    /// Residual context encoder: each convolution that keeps the channel count adds its input
    /// (`relu(x + conv(x))`), for encoders deeper than the default.
    #[arg(long)]
    residual: bool,
    /// Add value-iteration layers with this many Q channels to the context encoder (0: none).
    #[arg(long, default_value_t = 0)]
    propagation: usize,
    /// Value iterations per cell of the maze's longer side (with --propagation); paths longer
    /// than the iterations reach get no value from the goal.
    #[arg(long, default_value_t = 1.3)]
    propagation_iterations: f32,
    /// The shortest-path readout in place of the context network's MLP: the encoder gives
    /// eight move costs per cell and the field is the min-plus fixed point over them
    /// (`envfield_nets::PathConfig`), under the --target's rule. No goal channel.
    #[arg(long)]
    path: bool,
    /// With --path: the least cost of a move, in cells.
    #[arg(long, default_value_t = 0.05)]
    min_cost: f32,
    /// MLP hidden width and layers of the context network, as WIDTH:LAYERS.
    #[arg(long, default_value = "64:3")]
    mlp: String,
    /// Weight of the neighbour-difference loss (0: plain L1). Also applies to a resumed run.
    #[arg(long)]
    neighbour_weight: Option<f64>,
    /// Fraction of queries drawn from detour cells (distance above the octile distance to the
    /// goal: the path bends around obstacles). Also applies to a resumed run.
    #[arg(long)]
    detour_fraction: Option<f64>,
    /// Fraction of anchor queries drawn from far cells (at least half the maze's largest
    /// reachable distance from the goal), before --detour-fraction applies. Also applies to a
    /// resumed run.
    #[arg(long)]
    far_fraction: Option<f64>,
    /// Fraction of anchor queries drawn from the cells where the network's descent move is
    /// wrong at this step (one whole-field prediction per sampled maze and step; context and
    /// hyper networks). Also applies to a resumed run.
    #[arg(long)]
    hard_fraction: Option<f64>,
    /// Weight of the descent loss (0: off): queries in groups of a cell and its 8 neighbours;
    /// each move other than the best ones should score below the best by --descent-margin
    /// (hinge). Needs --queries divisible by 9. Also applies to a resumed run.
    #[arg(long)]
    descent_weight: Option<f64>,
    /// Margin of the descent loss in output units (linear:100 -> 0.01 per cell)
    #[arg(long, default_value_t = 0.005)]
    descent_margin: f64,
    /// Dense queries: every cell of each maze, and the neighbour-difference and descent losses
    /// over every reachable cell (--queries is then unused, and --detour-fraction is the share
    /// of those losses' weight on detour cells). Also switches a resumed run to dense queries.
    #[arg(long)]
    dense: bool,
    /// Keep a moving average of the weights with this decay (0.999: about the last 1000
    /// steps) and export it; checkpoints carry it. Also applies to a resumed run.
    #[arg(long)]
    ema: Option<f64>,
    /// Stop (with a checkpoint) at this step, before --steps; the learning-rate schedule still
    /// follows --steps, so a later --resume continues the same run.
    #[arg(long)]
    stop_at: Option<u64>,
    /// Checkpoint and validate every N steps.
    #[arg(long, default_value_t = 500)]
    every: u64,
}

fn main() -> Result<()> {
    let args = Args::parse();
    let (kind, target, encoding) = (args.generator, args.target, args.encoding);
    let sizes: Vec<usize> = args
        .size
        .split(',')
        .map(|s| {
            s.trim()
                .parse()
                .with_context(|| format!("bad --size entry `{s}`"))
        })
        .collect::<Result<_>>()?;
    let rule = target.rule();
    let single = args.arch.learns_one_scene();
    if args.mazes == 0 || args.goals_per_maze == 0 {
        bail!("--mazes and --goals-per-maze must be at least 1: there is nothing to train on");
    }
    if args.mazes.saturating_mul(args.goals_per_maze) > 10_000_000 {
        bail!(
            "--mazes {} x --goals-per-maze {} is more than 10,000,000 samples per size",
            args.mazes,
            args.goals_per_maze
        );
    }
    if args.resume.is_none() && (args.steps == 0 || args.stop_at == Some(0)) {
        bail!(
            "--steps 0 or --stop-at 0 trains nothing: a fresh run takes at least one step \
             ({} is left as it is)",
            args.out.display()
        );
    }
    // The outputs are checked before the data is made and the network trained.
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let ckpt = PathBuf::from(format!("{}.ckpt", args.out.display()));
    envfield::grid::check_writable(&args.out)?;
    envfield::grid::check_writable(&ckpt)?;
    if single && sizes.len() > 1 {
        bail!("--arch {} learns one maze: give one --size", args.arch);
    }
    // The data flags, recorded in every checkpoint: a resumed run must be given the same ones,
    // checked before the datasets are generated.
    let data = format!(
        "generator {}, sizes {}, {} mazes x {} goals per size, target {}, seed {}",
        kind, args.size, args.mazes, args.goals_per_maze, target, args.seed
    );
    if args.new_data && args.resume.is_none() {
        bail!("--new-data changes the data of a resumed run: give --resume too");
    }
    let resumed = match &args.resume {
        Some(path) => {
            let mut t = Trainer::resume(path)?;
            match t.continue_with_data(data.clone(), args.new_data) {
                Ok(DataCheck::Same) => {}
                Ok(DataCheck::Changed { recorded }) => eprintln!(
                    "--new-data: {} was trained on {recorded}; going on with {data}",
                    path.display()
                ),
                Ok(DataCheck::Unrecorded) => eprintln!(
                    "warning: {} does not record its training data (an older checkpoint); \
                     going on with {data}",
                    path.display()
                ),
                Err(e) => bail!(
                    "{}: {e}: pass the data flags of the run it continues, or --new-data to \
                     change them on purpose",
                    path.display()
                ),
            }
            eprintln!("resumed {} at step {}", path.display(), t.step());
            Some(t)
        }
        None => None,
    };
    // Training data: mazes 0..mazes of the seed; the held-out mazes use another seed.
    let mut datasets = Vec::new();
    let mut validation = Vec::new();
    for &size in &sizes {
        let generator = MazeGenerator::new(kind, size)?;
        let (mazes, goals) = match args.arch {
            Arch::Plain => (1, 1),
            Arch::Goal => (1, args.goals_per_maze.max(64)),
            Arch::Context | Arch::Hyper => (args.mazes, args.goals_per_maze),
        };
        let cfg = DatasetConfig {
            generator,
            mazes,
            goals_per_maze: goals,
            target,
            extra_obstacles: 0.0,
            seed: args.seed,
        };
        datasets.push(Dataset::generate(&cfg)?);
        let held_out = if single {
            Dataset::generate(&DatasetConfig {
                goals_per_maze: goals.min(16),
                seed: args.seed ^ 0x51,
                ..cfg
            })?
        } else {
            Dataset::generate(&DatasetConfig {
                mazes: 64,
                goals_per_maze: 1,
                seed: args.seed + 1_000_003,
                ..cfg
            })?
        };
        validation.push(held_out);
    }
    let first = datasets
        .first()
        .and_then(|d| d.samples.first())
        .context("the training data came out empty")?;
    let mut trainer = match resumed {
        Some(mut t) => {
            // The checkpoint's config, with the flags that apply to a resumed run.
            let mut c = t.config().clone();
            c.steps = args.steps;
            c.neighbour_weight = args.neighbour_weight.unwrap_or(c.neighbour_weight);
            c.detour_fraction = args.detour_fraction.unwrap_or(c.detour_fraction);
            c.far_fraction = args.far_fraction.unwrap_or(c.far_fraction);
            c.hard_fraction = args.hard_fraction.unwrap_or(c.hard_fraction);
            if let Some(w) = args.descent_weight {
                (c.descent_weight, c.descent_margin, c.descent_rule) =
                    (w, args.descent_margin, rule);
            }
            c.dense |= args.dense;
            c.ema_decay = args.ema.unwrap_or(c.ema_decay);
            t.set_config(c)?;
            t
        }
        None => {
            let goal = [first.goal.row, first.goal.col];
            let mut model = args
                .arch
                .preset(first.grid.rows(), first.grid.cols(), goal, encoding);
            if let ModelConfig::Context(c) = &mut model {
                c.residual = args.residual;
                if let Some(spec) = &args.encoder {
                    c.encoder = parse_convs(spec)?;
                }
                if args.path {
                    c.path = Some(PathConfig {
                        min_cost: args.min_cost,
                        rule,
                    });
                    c.goal_channel = false;
                }
                if args.propagation > 0 {
                    c.propagation = Some(PropagationConfig {
                        q_channels: args.propagation,
                        iterations_per_cell: args.propagation_iterations,
                    });
                }
                let (w, l) = args.mlp.split_once(':').context("--mlp WIDTH:LAYERS")?;
                c.mlp.hidden = w
                    .parse()
                    .with_context(|| format!("bad --mlp width `{w}`"))?;
                c.mlp.layers = l
                    .parse()
                    .with_context(|| format!("bad --mlp layers `{l}`"))?;
            }
            let train = TrainConfig {
                lr: args.lr,
                final_lr_fraction: args.final_lr,
                batch_items: if single { 1 } else { args.batch },
                queries_per_item: if args.arch == Arch::Plain {
                    first.grid.len()
                } else {
                    args.queries
                },
                steps: args.steps,
                seed: args.seed,
                checkpoint_every: args.every,
                validate_every: args.every,
                validation_samples: 64,
                neighbour_weight: args.neighbour_weight.unwrap_or(0.0),
                detour_fraction: args.detour_fraction.unwrap_or(0.0),
                far_fraction: args.far_fraction.unwrap_or(0.0),
                hard_fraction: args.hard_fraction.unwrap_or(0.0),
                descent_weight: args.descent_weight.unwrap_or(0.0),
                descent_margin: args.descent_margin,
                descent_rule: rule,
                dense: args.dense,
                ema_decay: args.ema.unwrap_or(0.0),
                ..TrainConfig::default()
            };
            let mut t = Trainer::new(FieldNet::new(model, args.seed)?, train)?;
            t.continue_with_data(data, false)?;
            t
        }
    };
    let net_info = format!(
        "{} network, {} parameters, sizes {:?}, {} samples per size",
        trainer.net().config().arch(),
        trainer.net().parameter_count(),
        sizes,
        datasets[0].samples.len()
    );
    eprintln!("{net_info}");
    let bar = ProgressBar::new(trainer.config().steps);
    bar.set_style(ProgressStyle::with_template(
        "{bar:30} {pos}/{len} steps {elapsed_precise} (eta {eta}) {msg}",
    )?);
    bar.set_position(trainer.step());
    let val_for_training = (sizes.len() == 1).then(|| &validation[0]);
    let mut last_val = None;
    // A run resumed at or past --stop-at only writes the weights out (no extra step).
    let stopped = args.stop_at.is_some_and(|stop| trainer.step() >= stop);
    let summary = (!stopped)
        .then(|| {
            trainer.run(&datasets, val_for_training, Some(&ckpt), |p| {
                bar.set_position(p.step);
                if let Some(v) = p.validation {
                    last_val = Some(v);
                }
                if bar.is_hidden() && (p.validation.is_some() || p.checkpointed) {
                    eprintln!(
                        "step {}/{} loss {:.4} val {} {:.2} steps/s {:.0} s",
                        p.step,
                        p.steps,
                        p.loss,
                        last_val.map_or("-".into(), |v| format!("{v:.4}")),
                        p.steps_per_second,
                        p.elapsed.as_secs_f64()
                    );
                }
                bar.set_message(format!(
                    "loss {:.4} val {} {:.2} steps/s",
                    p.loss,
                    last_val.map_or("-".into(), |v| format!("{v:.4}")),
                    p.steps_per_second
                ));
                args.stop_at.is_none_or(|stop| p.step < stop)
            })
        })
        .transpose()?;
    bar.finish();
    // The moving average of the weights when one is kept.
    let net = trainer.averaged_net()?;
    net.save(&args.out)?;
    match summary.is_some() {
        true => eprintln!(
            "saved {} (checkpoint {})",
            args.out.display(),
            ckpt.display()
        ),
        false => eprintln!(
            "saved {} (no step taken, no checkpoint written)",
            args.out.display()
        ),
    }
    if let Some(summary) = summary {
        println!("{}", serde_json::to_string(&summary)?);
    }
    // Navigation on held-out mazes (for plain/goal, the training maze itself).
    for (k, &size) in sizes.iter().enumerate() {
        let val_loss = envfield::nets::validation_loss(&net, &validation[k], 256)?;
        let mazes = if single {
            vec![envfield::grid::Maze {
                grid: first.grid.clone(),
                start: None,
                goal: Some(first.goal),
            }]
        } else {
            MazeGenerator::new(kind, size)?.generate_many(args.eval_mazes, args.seed + 1_000_003)?
        };
        let planner = FieldDescent::new(&net, rule);
        let eval = EvalConfig {
            rule,
            pairs_per_maze: if single { 64 } else { 1 },
            seed: 7,
        };
        let report = evaluate(&planner, &mazes, &eval, &mut |_, _| {})?;
        // No pair (--eval-mazes 0) has no success rate; a ratio without a success is null.
        let s = &report.summary;
        let finite = |x: f64| x.is_finite().then_some(x);
        let rate = (s.pairs > 0).then_some(s.success_rate);
        let line = serde_json::json!({
            "size": size,
            "validation_l1": val_loss,
            "success_rate": rate,
            "path_ratio": finite(s.path_ratio),
            "pairs": s.pairs,
            "ms_per_path": (s.pairs > 0).then_some(s.ms_per_path),
        });
        println!("{line}");
    }
    Ok(())
}
