//! Navigate mazes with planners and report the evaluation protocol's figures
//! (`docs/evaluation.md`).
//!
//! With no arguments it runs the shipped models: the learned field (`models/context.safetensors`)
//! and VIN (`models/vin_{8,16,28}.safetensors`: the maze's side, else the nearest trained side
//! with K set for the maze) beside A* and fast
//! marching, on VIN's test sets under the `vin` rule when `../shared/data/vin/` is there, and
//! on generated gridworlds otherwise.
//!
//! ```text
//! cargo run --release --example maze_nav                       # default suite, a table
//! cargo run --release --example maze_nav -- --mazes ../shared/data/vin/vin_test_28.txt --rule vin --planner graph --json
//! cargo run --release --example maze_nav -- --generator perfect --size 41 --count 50 --png out.png --paths paths.json
//! ```

use anyhow::{bail, Result};
use clap::Parser;
use envfield::grid::{write_atomic, Cell2, MoveRule};
use envfield::mazes::{GeneratorKind, MazeSet};
use envfield::models::ModelSource;
use envfield::nets::NetsError;
use envfield::plan::{
    evaluate, summary_table, DecisionProfile, EvalConfig, NamedPlanner, PlannerKind, PlannerOptions,
};
use std::path::{Path, PathBuf};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The shipped models.
fn models_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("models")
}

/// VIN's test sets, read from the shared data folder when it is there.
fn vin_test_sets() -> Option<Vec<PathBuf>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/vin");
    let files: Vec<PathBuf> = [8, 16, 28]
        .iter()
        .map(|s| dir.join(format!("vin_test_{s}.txt")))
        .collect();
    files.iter().all(|f| f.is_file()).then_some(files)
}

#[derive(Parser)]
#[command(about = "Navigate mazes with a planner; prints success rate, path ratio and ms per path")]
struct Args {
    /// Mazes in the text format (one or more per file). Without it, mazes are generated.
    #[arg(long)]
    mazes: Option<PathBuf>,
    /// Generator: gridworld, crossings, rooms or perfect.
    #[arg(long, default_value = "gridworld")]
    generator: GeneratorKind,
    /// Side of generated mazes. Without --mazes or --size, runs the default suite: VIN's test
    /// sets (8, 16, 28) when ../shared/data/vin is there, generated mazes of those sizes if not.
    #[arg(long)]
    size: Option<usize>,
    /// Number of generated mazes.
    #[arg(long, default_value_t = 200)]
    count: usize,
    /// Seed of generated mazes and random pairs.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Planners, comma-separated: field (the learned context-aligned field, descent), relay
    /// (the same field; a descent that fails is planned again through a relay cell: see
    /// --relays), octile and octile-relay (the octile distance, blind to walls: the control),
    /// hyper (the hypernetwork field), vin (the VIN baseline, one network pass per step), fmm
    /// (fast-marching field descent), graph (exact graph-distance field descent), astar.
    /// Default: field,relay,octile-relay,vin,astar,fmm, where a learned planner without a model
    /// for the maze size is left out with a note.
    #[arg(long, value_delimiter = ',')]
    planner: Option<Vec<PlannerKind>>,
    /// For `relay`: how many times a failing descent may be split in two at the cell where
    /// the start's and the goal's predicted fields meet (each split, one more prediction).
    #[arg(long, default_value_t = 1)]
    relays: usize,
    /// For `relay`: how many relay cells, best first, a failing descent tries with plain walks
    /// (no prediction) before the best one's legs are split again. More make the planner a
    /// search of its own (see `octile-relay`, the same planner on a field blind to walls).
    #[arg(long, default_value_t = 1)]
    candidates: usize,
    /// Weights for `field` or `hyper` (default: models/context.safetensors or
    /// models/hyper.safetensors; a file named <arch>_<size>.safetensors there wins for mazes of
    /// that size). VIN loads models/vin_<size>.safetensors (else the nearest trained side's, K
    /// set for the maze) unless this names a VIN file.
    /// Several files, comma-separated, make an ensemble: the mean of their fields.
    #[arg(long)]
    model: Option<PathBuf>,
    /// Average the learned field (`field`, `hyper`) over this many symmetric views of each maze
    /// (1 to 8: transposes and flips; test-time augmentation, one prediction per view).
    #[arg(long, default_value_t = 1)]
    views: usize,
    /// Move rule: strict or vin.
    #[arg(long, default_value = "vin")]
    rule: MoveRule,
    /// Random pairs per maze (mazes with both S and G use that pair).
    #[arg(long, default_value_t = 1)]
    pairs: usize,
    /// Draw the first pair's field, obstacles, path and optimal path to this PNG.
    #[arg(long)]
    png: Option<PathBuf>,
    /// Print one JSON summary line per planner (the last line is the last planner's).
    #[arg(long)]
    json: bool,
    /// For planners with a field (field, hyper, fmm, graph): descent from every reachable
    /// cell of each evaluated (maze, goal), by true distance to the goal in bands of 5
    /// cells: how often its move is not a shortest move and how often it fails.
    #[arg(long)]
    profile: bool,
    /// Write every planned path to this JSON file.
    #[arg(long)]
    paths: Option<PathBuf>,
}

/// Why a learned planner could not be built: its model, or the planner itself.
#[derive(Debug, thiserror::Error)]
enum LoadError {
    #[error(transparent)]
    Nets(#[from] NetsError),
    #[error(transparent)]
    Plan(#[from] envfield::plan::PlanError),
}

/// The planners of a run without `--planner`.
const DEFAULT_PLANNERS: [PlannerKind; 6] = [
    PlannerKind::Field,
    PlannerKind::Relay,
    PlannerKind::OctileRelay,
    PlannerKind::Vin,
    PlannerKind::AStar,
    PlannerKind::Fmm,
];

/// Generated mazes and random pairs per maze beyond which a run is refused: far more than any
/// table needs, and a typo past them would run for days.
const MAX_MAZES: usize = 1_000_000;
const MAX_PAIRS: usize = 100_000;
const MAX_EVALUATIONS: usize = 10_000_000;

fn main() -> Result<()> {
    let args = Args::parse();
    let (rule, kind) = (args.rule, args.generator);
    if args.count > MAX_MAZES || args.pairs > MAX_PAIRS {
        bail!(
            "--count {} or --pairs {} is more than this tool does (at most {MAX_MAZES} mazes \
             and {MAX_PAIRS} pairs per maze)",
            args.count,
            args.pairs
        );
    }
    if args.count.saturating_mul(args.pairs) > MAX_EVALUATIONS {
        bail!(
            "--count {} x --pairs {} is more than {MAX_EVALUATIONS} evaluations",
            args.count,
            args.pairs
        );
    }
    if args.count == 0 || args.pairs == 0 {
        bail!("--count and --pairs must be at least 1: zero pairs has no success rate");
    }
    // Output paths are checked before the work, not after it.
    for out in [&args.paths, &args.png].into_iter().flatten() {
        envfield::grid::check_writable(out)?;
    }
    let explicit_planners = args.planner.is_some();
    let planners = args.planner.clone().unwrap_or(DEFAULT_PLANNERS.to_vec());
    let sets: Vec<MazeSet> = match (&args.mazes, args.size) {
        (Some(file), _) => vec![MazeSet::read(file, rule)?],
        (None, Some(size)) => vec![MazeSet::generated(kind, size, args.count, args.seed, rule)?],
        (None, None) => match vin_test_sets() {
            Some(files) => files
                .iter()
                .map(|f| MazeSet::read(f, rule))
                .collect::<Result<_, _>>()?,
            None => [8usize, 16, 28]
                .into_iter()
                .map(|size| MazeSet::generated(kind, size, args.count, args.seed, rule))
                .collect::<Result<_, _>>()?,
        },
    };
    let options = PlannerOptions {
        rule,
        relays: args.relays,
        candidates: args.candidates,
    };
    let source = ModelSource {
        explicit: args.model.clone(),
        views: args.views,
        rule,
        ..ModelSource::new(models_dir())
    };
    let cfg = EvalConfig {
        rule,
        pairs_per_maze: args.pairs,
        seed: args.seed,
    };

    let mut all_paths = Vec::new();
    let mut lines = Vec::new();
    for suite in &sets {
        let size = suite
            .mazes
            .first()
            .map_or(0, |m| m.grid.rows().max(m.grid.cols()));
        let mut choices: Vec<NamedPlanner> = Vec::new();
        for kind in &planners {
            let built = kind.build(&options, |family| {
                let (file, model) = source.load(family, size)?;
                eprintln!("{} {kind}: {}", suite.label, file.display());
                Ok::<_, LoadError>(model)
            });
            match built {
                Ok(choice) => choices.push(choice),
                // A default run leaves out a learned planner that has no model for the size.
                Err(LoadError::Nets(NetsError::ModelNotFound { .. })) if !explicit_planners => {
                    eprintln!("{}: no {kind} model for size {size}; left out", suite.label)
                }
                Err(LoadError::Nets(e @ NetsError::ModelNotFound { .. })) => {
                    bail!("{e} (train one with the command in models/README.md, or pass --model)")
                }
                Err(e) => return Err(e.into()),
            }
        }
        for choice in &choices {
            let bar = indicatif::ProgressBar::new(0).with_message(format!(
                "{} {}",
                suite.label,
                choice.planner().name()
            ));
            bar.set_style(
                indicatif::ProgressStyle::with_template("{msg:>28} {bar:30} {pos}/{len} pairs")
                    .expect("valid template"),
            );
            let report = evaluate(choice.planner(), &suite.mazes, &cfg, &mut |done, total| {
                bar.set_length(total as u64);
                bar.set_position(done as u64);
            })?;
            bar.finish_and_clear();
            if report.summary.pairs == 0 {
                bail!(
                    "{}: no (start, goal) pair to evaluate: no maze has an S and a G, or two \
                     free cells that connect",
                    suite.label
                );
            }
            if let Some(png) = &args.png {
                if lines.is_empty() {
                    report.write_first_png(png, &suite.mazes, choice.field_model(), rule)?;
                    eprintln!(
                        "wrote {} (red: {} path, white: optimal path)",
                        png.display(),
                        choice.planner().name()
                    );
                }
            }
            let s = &report.summary;
            if let (true, Some(model)) = (args.profile, choice.field_model()) {
                let mut profile = DecisionProfile::new(5.0)?;
                for r in &report.results {
                    let grid = &suite.mazes[r.maze].grid;
                    profile.add(grid, rule, r.goal, &model.predict(grid, r.goal)?)?;
                }
                match args.json {
                    true => println!(
                        "{}",
                        serde_json::json!({"mazes": suite.label, "planner": s.planner, "profile": profile})
                    ),
                    false => print!("{}", profile.table(&suite.label, &s.planner)),
                }
            }
            lines.push((suite.label.clone(), s.clone()));
            if args.json {
                println!("{}", serde_json::to_string(s)?);
            }
            for r in &report.results {
                all_paths.push(serde_json::json!({
                    "mazes": suite.label, "planner": s.planner, "maze": r.maze,
                    "start": [r.start.row, r.start.col], "goal": [r.goal.row, r.goal.col],
                    "cells": r.path.iter().map(|c: &Cell2| [c.row, c.col]).collect::<Vec<_>>(),
                    "success": r.success,
                }));
            }
        }
    }
    if let Some(p) = &args.paths {
        write_atomic(p, serde_json::to_string(&all_paths)?.as_bytes())?;
        eprintln!("wrote {} paths to {}", all_paths.len(), p.display());
    }
    if !args.json {
        println!(
            "rule: {rule}, {} pair(s) per maze without S/G, seed {}",
            args.pairs, args.seed
        );
        print!("{}", summary_table(&lines));
    }
    Ok(())
}
