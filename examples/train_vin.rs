//! Trains the VIN baseline on generated gridworld mazes (imitation of optimal actions under
//! the `vin` rule), checkpointing as it goes, and reports its success on held-out mazes.
//!
//! ```text
//! cargo run --release --example train_vin -- --size 28 --steps 3000 --out models/vin_28.safetensors
//! cargo run --release --example train_vin -- --size 28 --steps 5000 --resume models/vin_28.safetensors.ckpt --out models/vin_28.safetensors
//! ```

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::grid::MoveRule;
use envfield::mazes::{GeneratorKind, MazeGenerator};
use envfield::nets::{vin_examples, Vin, VinConfig, VinTrainConfig, VinTrainer};
use envfield::plan::{evaluate, EvalConfig, PolicyWalk};
use std::path::PathBuf;
use std::time::Instant;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "Train the VIN baseline on generated mazes")]
struct Args {
    /// Maze side (K = 10, 20, 36 for 8, 16, 28).
    #[arg(long, default_value_t = 28)]
    size: usize,
    /// gridworld, crossings, rooms or perfect.
    #[arg(long, default_value = "gridworld")]
    generator: GeneratorKind,
    /// Training mazes (VIN used 5000 per size).
    #[arg(long, default_value_t = 5000)]
    mazes: usize,
    /// Optimiser steps in total.
    #[arg(long, default_value_t = 3000)]
    steps: u64,
    /// Mazes per step.
    #[arg(long, default_value_t = 32)]
    batch: usize,
    /// Labelled states per maze per step.
    #[arg(long, default_value_t = 10)]
    states: usize,
    /// Learning rate (Adam).
    #[arg(long, default_value_t = 2e-3)]
    lr: f64,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Final weights (the checkpoint goes to OUT.ckpt).
    #[arg(long, default_value = "out/vin.safetensors")]
    out: PathBuf,
    /// Resume from this checkpoint.
    #[arg(long)]
    resume: Option<PathBuf>,
    /// Held-out mazes for the success check.
    #[arg(long, default_value_t = 200)]
    eval_mazes: usize,
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.resume.is_none() && args.steps == 0 {
        bail!(
            "--steps 0 trains nothing: a fresh run takes at least one step ({} is left as it is)",
            args.out.display()
        );
    }
    if args.mazes == 0 {
        bail!("--mazes must be at least 1: there is nothing to train on");
    }
    // The outputs are checked before any work.
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let ckpt = PathBuf::from(format!("{}.ckpt", args.out.display()));
    envfield::grid::check_writable(&args.out)?;
    envfield::grid::check_writable(&ckpt)?;
    let generator = MazeGenerator::new(args.generator, args.size)?;
    let mazes = generator.generate_many(args.mazes, args.seed)?;
    let examples = vin_examples(&mazes, MoveRule::Vin, args.seed)?;
    let cfg = VinTrainConfig {
        lr: args.lr,
        batch_mazes: args.batch,
        states_per_maze: args.states,
        steps: args.steps,
        seed: args.seed,
    };
    let mut trainer = match &args.resume {
        Some(p) => {
            let t = VinTrainer::resume(p, cfg)?;
            // K is set by the maze size: a checkpoint of another size is another network.
            let want = VinConfig::for_size(args.size).iterations;
            let k = t.net().config().iterations;
            if k != want {
                bail!(
                    "{} is a VIN with K = {k} iterations, not the K = {want} of --size {}: resume \
                     it with the size it was trained for",
                    p.display(),
                    args.size
                );
            }
            t
        }
        None => VinTrainer::new(Vin::new(VinConfig::for_size(args.size), args.seed)?, cfg)?,
    };
    eprintln!(
        "VIN K={} {} parameters, {} examples, from step {}",
        trainer.net().config().iterations,
        trainer.net().parameter_count(),
        examples.len(),
        trainer.step()
    );
    let start = Instant::now();
    let first = trainer.step();
    let mut recent = 0f32;
    while trainer.step() < args.steps {
        let loss = trainer.train_step(&examples)?;
        recent = if trainer.step() == first + 1 {
            loss
        } else {
            0.98 * recent + 0.02 * loss
        };
        if trainer.step() % 250 == 0 || trainer.step() == args.steps {
            trainer.save_checkpoint(&ckpt)?;
            eprintln!(
                "step {}/{} loss {:.4} {:.2} steps/s",
                trainer.step(),
                args.steps,
                recent,
                (trainer.step() - first) as f64 / start.elapsed().as_secs_f64()
            );
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    let net = trainer.into_net();
    net.save(&args.out)?;
    let held_out = generator.generate_many(args.eval_mazes, args.seed + 1_000_003)?;
    let eval = EvalConfig {
        rule: MoveRule::Vin,
        pairs_per_maze: 1,
        seed: 7,
    };
    let report = evaluate(&PolicyWalk(&net), &held_out, &eval, &mut |_, _| {})?;
    // No pair has no success rate, and a ratio without a success is null (JSON has no NaN).
    let s = &report.summary;
    let line = serde_json::json!({
        "size": args.size,
        "steps": args.steps,
        "seconds": seconds,
        "loss": recent,
        "success_rate": (s.pairs > 0).then_some(s.success_rate),
        "path_ratio": s.path_ratio.is_finite().then_some(s.path_ratio),
        "ms_per_path": (s.pairs > 0).then_some(s.ms_per_path),
    });
    println!("{line}");
    Ok(())
}
