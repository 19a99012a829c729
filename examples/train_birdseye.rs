//! Trains the bird's-eye field: the shortest-path context network on the walkable floor maps
//! of generated rooms (0.1 m cells, 64x64), each sample changed the way other people change a
//! map: random free cells turned into obstacles and discs where people stand (paper section
//! 4.1). Then measures it on rooms it never saw, one person at a time: plain descent against
//! the exact field, the octile control and the untrained twin, on the empty maps and on maps
//! with people's discs.
//!
//! `cargo run --release --example train_birdseye -- --out models/birdseye.safetensors`
//!
//! Resumes from `OUT.ckpt` with `--resume`. Prints one JSON line per evaluation set.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::eikonal::FastMarching;
use envfield::grid::{Maze, MoveRule, SplitMix64};
use envfield::nets::{
    parse_convs, Arch, DataCheck, FieldNet, ModelConfig, PathConfig, TargetEncoding, TrainConfig,
    Trainer,
};
use envfield::plan::{evaluate, EvalConfig, FieldDescent, Octile};
use envfield::rooms::birdseye::{changed_map, training_maps, walkable_map, BODY, RESOLUTION, SIDE};
use indicatif::{ProgressBar, ProgressStyle};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "Train the bird's-eye field on changed floor maps of generated rooms")]
struct Args {
    /// Training rooms (seeds 0..rooms).
    #[arg(long, default_value_t = 1500)]
    rooms: usize,
    /// Changed maps (random obstacles and people) with a goal each, per room.
    #[arg(long, default_value_t = 4)]
    goals_per_room: usize,
    /// Held-out rooms for the evaluation (seeds from 1,000,000).
    #[arg(long, default_value_t = 200)]
    eval_rooms: usize,
    /// Optimiser steps.
    #[arg(long, default_value_t = 3000)]
    steps: u64,
    /// Maps per step.
    #[arg(long, default_value_t = 16)]
    batch: usize,
    /// Peak learning rate.
    #[arg(long, default_value_t = 3e-3)]
    lr: f64,
    /// Where the weights go (the checkpoint to OUT.ckpt).
    #[arg(long, default_value = "out/birdseye.safetensors")]
    out: PathBuf,
    /// Resume from OUT.ckpt.
    #[arg(long)]
    resume: bool,
    /// Only evaluate the weights at --out.
    #[arg(long)]
    eval_only: bool,
    /// Checkpoint every N steps (an interrupted run loses at most that many).
    #[arg(long, default_value_t = 100)]
    every: u64,
    /// Seed of the augmentation, the weights and the batches.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

fn train(args: &Args) -> Result<()> {
    let ckpt = PathBuf::from(format!("{}.ckpt", args.out.display()));
    if args.resume && !ckpt.is_file() {
        bail!(
            "--resume: no checkpoint at {} (a run without --resume starts from step 0)",
            ckpt.display()
        );
    }
    let t0 = std::time::Instant::now();
    let data = training_maps(0..args.rooms as u64, args.goals_per_room, args.seed)?;
    let validation = training_maps(2_000_000..2_000_064, 1, args.seed)?;
    eprintln!(
        "{} training maps from {} rooms in {:.1} s",
        data.samples.len(),
        args.rooms,
        t0.elapsed().as_secs_f64()
    );
    // What the checkpoint records of the data, to refuse resuming on other data.
    let described = format!(
        "birdseye rooms {} x {} goals, seed {}, resolution {RESOLUTION} m, body {BODY} m",
        args.rooms, args.goals_per_room, args.seed
    );
    let mut trainer = match args.resume {
        true => {
            let mut t = Trainer::resume(&ckpt)?;
            if let DataCheck::Unrecorded = t.continue_with_data(described, false)? {
                eprintln!("{} recorded no data description", ckpt.display());
            }
            eprintln!("resumed {} at step {}", ckpt.display(), t.step());
            t
        }
        false => {
            let encoding = TargetEncoding::Linear { scale: 100.0 };
            let mut model = Arch::Context.preset(SIDE, SIDE, [0, 0], encoding);
            if let ModelConfig::Context(c) = &mut model {
                c.encoder = parse_convs("16:1,16:1,16:1")?;
                c.path = Some(PathConfig {
                    min_cost: 0.05,
                    rule: MoveRule::Strict,
                });
                c.goal_channel = false;
            }
            let config = TrainConfig {
                lr: args.lr,
                batch_items: args.batch,
                queries_per_item: 256,
                steps: args.steps,
                seed: args.seed,
                checkpoint_every: args.every,
                validate_every: 500,
                validation_samples: 64,
                ema_decay: 0.99,
                ..TrainConfig::default()
            };
            let mut t = Trainer::new(FieldNet::new(model, args.seed)?, config)?;
            t.continue_with_data(described, false)?;
            t
        }
    };
    let bar = ProgressBar::new(trainer.config().steps);
    bar.set_style(ProgressStyle::with_template(
        "{bar:30} {pos}/{len} steps {elapsed_precise} (eta {eta}) {msg}",
    )?);
    bar.set_position(trainer.step());
    let summary = trainer.run(&[data], Some(&validation), Some(&ckpt), |p| {
        bar.set_position(p.step);
        if let Some(v) = p.validation {
            bar.set_message(format!("loss {:.4} val {v:.4}", p.loss));
            if bar.is_hidden() {
                eprintln!("step {}/{} loss {:.4} val {v:.4}", p.step, p.steps, p.loss);
            }
        }
        true
    })?;
    bar.finish();
    trainer.averaged_net()?.save(&args.out)?;
    eprintln!(
        "saved {} (checkpoint {})",
        args.out.display(),
        ckpt.display()
    );
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}

fn eval(args: &Args) -> Result<()> {
    let net =
        FieldNet::load(&args.out).with_context(|| format!("loading {}", args.out.display()))?;
    let mut untrained = FieldNet::new(net.config().clone(), 12345)?;
    untrained.set_rule(net.rule());
    let rule = MoveRule::Strict;
    let rooms = 1_000_000..1_000_000 + args.eval_rooms as u64;
    for people in [0usize, 7] {
        let mazes: Vec<Maze> = rooms
            .clone()
            .map(|room| {
                let grid = walkable_map(room)?;
                let mut rng = SplitMix64::new(room ^ 0xB1BD);
                let grid = match people {
                    0 => grid,
                    n => changed_map(&grid, &mut rng, n, 0.0)?,
                };
                Ok(Maze {
                    grid,
                    start: None,
                    goal: None,
                })
            })
            .collect::<Result<_>>()?;
        let cfg = EvalConfig {
            rule,
            pairs_per_maze: 4,
            seed: 7,
        };
        let mut row = serde_json::json!({ "rooms": args.eval_rooms, "people_discs_up_to": people });
        let learned = FieldDescent::new(&net, rule);
        let twin = FieldDescent::new(&untrained, rule);
        let octile = FieldDescent::new(Octile, rule);
        let exact = FieldDescent::new(FastMarching::default(), rule);
        for (name, planner) in [
            ("field", &learned as &dyn envfield::plan::Planner),
            ("untrained", &twin),
            ("octile", &octile),
            ("exact", &exact),
        ] {
            let report = evaluate(planner, &mazes, &cfg, &mut |_, _| {})?;
            let s = &report.summary;
            row[name] = serde_json::json!({
                "success_pct": s.success_rate,
                "path_ratio": s.path_ratio,
                "pairs": s.pairs,
                "ms_per_path": s.ms_per_path,
            });
        }
        let costs = net.move_costs(&mazes[0].grid)?;
        let free: Vec<usize> = (0..mazes[0].grid.len())
            .filter(|&i| !mazes[0].grid.obstacles()[i])
            .collect();
        let mean = |k: usize| free.iter().map(|&i| costs[i][k]).sum::<f32>() / free.len() as f32;
        row["learned_costs"] = serde_json::json!({
            "orthogonal": (0..4).map(mean).sum::<f32>() / 4.0,
            "diagonal": (4..8).map(mean).sum::<f32>() / 4.0,
        });
        println!("{row}");
    }
    Ok(())
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.rooms == 0 || args.rooms > 100_000 || args.eval_rooms == 0 || args.eval_rooms > 100_000
    {
        bail!(
            "--rooms and --eval-rooms must be in 1..=100000 (got {} and {})",
            args.rooms,
            args.eval_rooms
        );
    }
    if args.goals_per_room == 0 || args.goals_per_room > 1000 {
        bail!(
            "--goals-per-room must be in 1..=1000 (got {})",
            args.goals_per_room
        );
    }
    // A run that would take no step writes no weights: a user's trained file stays as it is.
    if !args.eval_only && args.steps == 0 {
        bail!(
            "--steps 0 trains nothing ({} is left as it is; --eval-only measures it)",
            args.out.display()
        );
    }
    envfield::grid::check_writable(&args.out)?;
    if !args.eval_only {
        train(&args)?;
    }
    eval(&args)
}
