//! Generates a dataset of (maze, goal, exact distance field) samples, prints how long it took, and
//! optionally saves it as `.npy` files.
//!
//! ```text
//! cargo run --release --example make_dataset -- --size 28 --samples 10000
//! cargo run --release --example make_dataset -- --generator crossings --size 11 --samples 2000 --out data/crossings11
//! ```

use anyhow::Result;
use clap::Parser;
use envfield::mazes::{Dataset, DatasetConfig, GeneratorKind, MazeGenerator, TargetKind};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser)]
#[command(about = "Generate a maze dataset and time it")]
struct Args {
    /// gridworld, crossings, rooms or perfect.
    #[arg(long, default_value = "gridworld")]
    generator: GeneratorKind,
    /// Maze side.
    #[arg(long, default_value_t = 28)]
    size: usize,
    /// Number of samples (mazes x goals per maze).
    #[arg(long, default_value_t = 10_000)]
    samples: usize,
    /// Goals per maze.
    #[arg(long, default_value_t = 1)]
    goals_per_maze: usize,
    /// Target: fmm1, fmm2, strict or vin (graph distance under that rule).
    #[arg(long, default_value = "vin")]
    target: TargetKind,
    /// Fraction of free cells turned into extra obstacles.
    #[arg(long, default_value_t = 0.0)]
    extra_obstacles: f32,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Save the dataset into this folder.
    #[arg(long)]
    out: Option<PathBuf>,
}

fn main() -> Result<()> {
    let args = Args::parse();
    let cfg = DatasetConfig {
        generator: MazeGenerator::new(args.generator, args.size)?,
        mazes: args.samples.div_ceil(args.goals_per_maze.max(1)),
        goals_per_maze: args.goals_per_maze,
        target: args.target,
        extra_obstacles: args.extra_obstacles,
        seed: args.seed,
    };
    let t = Instant::now();
    let ds = Dataset::generate(&cfg)?;
    let secs = t.elapsed().as_secs_f64();
    println!(
        "{{\"samples\":{},\"size\":{},\"threads\":{},\"seconds\":{:.3}}}",
        ds.samples.len(),
        args.size,
        rayon::current_num_threads(),
        secs
    );
    if let Some(out) = &args.out {
        ds.save(out)?;
        eprintln!("saved to {}", out.display());
    }
    Ok(())
}
