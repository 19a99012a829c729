//! Trains the VIN baseline as its paper and code do: VIN's data (5000 generated gridworlds
//! of one size, 7 shortest-path trajectories each, under the `vin` rule), rows of 10 states
//! sharing a map, 12 rows per step, RMSProp at 2e-3, 30 epochs. It checkpoints as it goes
//! (`OUT.ckpt`, resumable), and reports success on held-out mazes and, with `--test`, success
//! and per-state action accuracy on a test set (VIN's own).
//!
//! ```text
//! cargo run --release --example train_vin -- --size 28 --out models/vin_28.safetensors --test ../shared/data/vin/vin_test_28.txt
//! cargo run --release --example train_vin -- --size 28 --resume models/vin_28.safetensors.ckpt --out models/vin_28.safetensors
//! ```

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::grid::{read_mazes, Maze, MoveRule};
use envfield::mazes::{GeneratorKind, MazeGenerator};
use envfield::nets::{Vin, VinConfig, VinData, VinTrainConfig, VinTrainer};
use envfield::plan::{evaluate, EvalConfig, PolicyWalk};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "Train the VIN baseline as VIN's paper does")]
struct Args {
    /// Maze side (K = 10, 20, 36 for 8, 16, 28).
    #[arg(long, default_value_t = 28)]
    size: usize,
    /// gridworld (VIN's domain), crossings, rooms or perfect.
    #[arg(long, default_value = "gridworld")]
    generator: GeneratorKind,
    /// Training mazes (VIN used 5000 per size).
    #[arg(long, default_value_t = 5000)]
    mazes: usize,
    /// Shortest-path trajectories per maze (VIN used 7).
    #[arg(long, default_value_t = 7)]
    trajectories: usize,
    /// Passes over the data (VIN used 30).
    #[arg(long, default_value_t = 30)]
    epochs: u64,
    /// Stop after this many steps in all, short of the epochs (for timing runs).
    #[arg(long)]
    max_steps: Option<u64>,
    /// Rows of 10 states per step (VIN's batch size, 12).
    #[arg(long, default_value_t = 12)]
    batch: usize,
    /// Learning rate (RMSProp, VIN's 2e-3).
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
    /// Steps between checkpoints.
    #[arg(long, default_value_t = 500)]
    every: u64,
    /// Held-out generated mazes for the success check.
    #[arg(long, default_value_t = 200)]
    eval_mazes: usize,
    /// A test set to report success and action accuracy on (VIN's `vin_test_<size>.txt`).
    #[arg(long)]
    test: Option<PathBuf>,
}

/// Rollout success (one pair per maze, the maze's own start and goal when it marks them) and
/// VIN's per-state action accuracy along the optimal trajectory from each start.
fn score(net: &Vin, mazes: &[Maze]) -> Result<serde_json::Value> {
    let eval = EvalConfig {
        rule: MoveRule::Vin,
        pairs_per_maze: 1,
        seed: 7,
    };
    let report = evaluate(&PolicyWalk(net), mazes, &eval, &mut |_, _| {})?;
    let s = &report.summary;
    let accuracy = VinData::generate(mazes, MoveRule::Vin, 1, 7)?.action_accuracy(net);
    // No pair has no success rate, and a ratio without a success is null (JSON has no NaN).
    Ok(serde_json::json!({
        "mazes": mazes.len(),
        "success_rate": (s.pairs > 0).then_some(s.success_rate),
        "action_accuracy": accuracy.map(|a| 100.0 * a),
        "path_ratio": s.path_ratio.is_finite().then_some(s.path_ratio),
    }))
}

fn trainer(args: &Args, cfg: VinTrainConfig) -> Result<VinTrainer> {
    let Some(p) = &args.resume else {
        return Ok(VinTrainer::new(
            Vin::new(VinConfig::for_size(args.size), args.seed)?,
            cfg,
        )?);
    };
    let t = VinTrainer::resume(p, cfg)?;
    // K is set by the maze size: a checkpoint of another size is another network.
    let want = VinConfig::for_size(args.size).iterations;
    let k = t.net().config().iterations;
    if k != want {
        bail!(
            "{} is a VIN with K = {k} iterations, not the K = {want} of --size {}: resume it \
             with the size it was trained for",
            p.display(),
            args.size
        );
    }
    Ok(t)
}

fn read_test(path: &Path, size: usize) -> Result<Vec<Maze>> {
    let mazes = read_mazes(path).with_context(|| format!("reading {}", path.display()))?;
    if let Some(m) = mazes
        .iter()
        .find(|m| m.grid.rows() != size || m.grid.cols() != size)
    {
        bail!(
            "{} holds a {}x{} maze: give the test set of --size {size}",
            path.display(),
            m.grid.rows(),
            m.grid.cols()
        );
    }
    Ok(mazes)
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.resume.is_none() && (args.epochs == 0 || args.max_steps == Some(0)) {
        bail!(
            "--epochs 0 or --max-steps 0 trains nothing: a fresh run takes at least one step \
             ({} is left as it is)",
            args.out.display()
        );
    }
    if args.mazes == 0 || args.trajectories == 0 {
        bail!("--mazes and --trajectories must be at least 1: there is nothing to train on");
    }
    if args.mazes > 1_000_000 || args.trajectories > 1000 || args.every == 0 {
        bail!("--mazes is at most 1000000, --trajectories at most 1000, --every at least 1");
    }
    if args.eval_mazes > 100_000 {
        bail!(
            "--eval-mazes is at most 100000 (got {}): the held-out mazes are made before training",
            args.eval_mazes
        );
    }
    // The outputs and the test set are checked before any work.
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let ckpt = PathBuf::from(format!("{}.ckpt", args.out.display()));
    envfield::grid::check_writable(&args.out)?;
    envfield::grid::check_writable(&ckpt)?;
    let test = match &args.test {
        Some(p) => Some(read_test(p, args.size)?),
        None => None,
    };
    let generator = MazeGenerator::new(args.generator, args.size)?;
    let mazes = generator.generate_many(args.mazes, args.seed)?;
    let data = VinData::generate(&mazes, MoveRule::Vin, args.trajectories, args.seed)?;
    let cfg = VinTrainConfig {
        lr: args.lr,
        batch_rows: args.batch,
        epochs: args.epochs,
        seed: args.seed,
        ..VinTrainConfig::default()
    };
    let mut trainer = trainer(&args, cfg)?;
    let total = trainer.total_steps(&data);
    let last = args.max_steps.map_or(total, |m| m.min(total));
    if let (Some(p), true) = (&args.resume, last <= trainer.step()) {
        bail!(
            "--max-steps {last} trains nothing: {} is at step {} already ({} is left as it is)",
            p.display(),
            trainer.step(),
            args.out.display()
        );
    }
    eprintln!(
        "VIN K={} {} parameters: {} maps, {} rows, {} states; {} steps per epoch, from step {} \
         to {last}",
        trainer.net().config().iterations,
        trainer.net().parameter_count(),
        data.maps(),
        data.rows(),
        data.states(),
        trainer.steps_per_epoch(&data),
        trainer.step()
    );
    let bar = ProgressBar::new(last).with_position(trainer.step());
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} steps {msg} [{elapsed} < {eta}]")
            .context("progress template")?,
    );
    let start = Instant::now();
    let (mut recent, mut states) = (f32::NAN, 0usize);
    while trainer.step() < last {
        let step = trainer.train_step(&data)?;
        states += step.states;
        recent = if recent.is_nan() {
            step.loss
        } else {
            0.98 * recent + 0.02 * step.loss
        };
        bar.inc(1);
        if trainer.step() % args.every == 0 || trainer.step() == last {
            trainer.save_checkpoint(&ckpt)?;
            let rate = states as f64 / start.elapsed().as_secs_f64();
            bar.set_message(format!("loss {recent:.4} {rate:.0} states/s"));
        }
    }
    bar.finish();
    let seconds = start.elapsed().as_secs_f64();
    let net = trainer.into_net();
    net.save(&args.out)?;
    let held_out = generator.generate_many(args.eval_mazes, args.seed + 1_000_003)?;
    let line = serde_json::json!({
        "size": args.size,
        "steps": last,
        "seconds": seconds,
        "states_per_s": states as f64 / seconds,
        "loss": recent.is_finite().then_some(recent),
        "held_out": score(&net, &held_out)?,
        "test": test.map(|t| score(&net, &t)).transpose()?,
    });
    println!("{line}");
    Ok(())
}
