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

use anyhow::{Context, Result};
use clap::Parser;
use envfield::eikonal::FastMarching;
use envfield::grid::{Cell2, Grid2, Maze, MoveRule, Point2, SplitMix64};
use envfield::mazes::{target_field, Dataset, Sample, TargetKind};
use envfield::nets::{
    parse_convs, Arch, DataCheck, FieldNet, ModelConfig, PathConfig, TargetEncoding, TrainConfig,
    Trainer,
};
use envfield::plan::{evaluate, mark_discs, EvalConfig, FieldDescent, Octile};
use envfield::scene::{floor_map, generate_room, FloorMapConfig, RoomConfig};
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
    /// Seed of the augmentation, the weights and the batches.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

/// Floor-map cell side, metres.
const RESOLUTION: f32 = 0.1;
/// Body radius, metres (0.25 m: shoulders about 0.5 m wide).
const BODY: f32 = 0.25;
/// The map side every room is padded to.
const SIDE: usize = 64;

/// The walkable 64x64 map of room `seed`.
fn walkable(seed: u64) -> Result<Grid2> {
    let room = generate_room(&RoomConfig::birdseye(), seed)?;
    let map = floor_map(
        &room.scene,
        &FloorMapConfig {
            resolution: RESOLUTION,
            ..FloorMapConfig::default()
        },
    )?;
    Ok(map.walkable(BODY, Some([SIDE, SIDE]))?)
}

/// `grid` changed as other people change it: up to `max_people` discs (two body radii, in
/// centre space) at random free cells and a random fraction below `max_extra` of the free
/// cells turned into obstacles.
fn changed(grid: &Grid2, rng: &mut SplitMix64, max_people: usize, max_extra: f32) -> Result<Grid2> {
    let free: Vec<Cell2> = grid.free_cells().collect();
    let people = rng.below(max_people + 1);
    let centres: Vec<Point2> = (0..people)
        .map(|_| {
            let c = free[rng.below(free.len())];
            Point2::new(c.row as f32, c.col as f32)
        })
        .collect();
    let mut out = mark_discs(grid, centres.into_iter(), 2.0 * BODY / RESOLUTION)?;
    let extra = rng.next_f32() * max_extra;
    for &c in &free {
        if rng.next_f32() < extra {
            out.set_obstacle(c, true)?;
        }
    }
    Ok(out)
}

/// A random free cell of `grid` in its largest connected region (8-connected, strict).
fn goal_cell(grid: &Grid2, rng: &mut SplitMix64) -> Option<Cell2> {
    let (labels, sizes) = envfield::scene::free_components(grid);
    let largest = (0..sizes.len()).max_by_key(|&k| sizes[k])?;
    let cells: Vec<usize> = (0..labels.len())
        .filter(|&i| labels[i] == largest)
        .collect();
    Some(grid.cell(cells[rng.below(cells.len())]))
}

fn dataset(rooms: std::ops::Range<u64>, goals: usize, seed: u64) -> Result<Dataset> {
    let target = TargetKind::Graph(MoveRule::Strict);
    let mut samples = Vec::new();
    for (k, room) in rooms.enumerate() {
        let grid = walkable(room)?;
        let mut rng = SplitMix64::new(seed ^ room.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        for _ in 0..goals {
            let map = changed(&grid, &mut rng, 7, 0.08)?;
            let Some(goal) = goal_cell(&map, &mut rng) else {
                continue;
            };
            let distance = target_field(&map, goal, target)?.into_values();
            samples.push(Sample {
                maze: k,
                grid: map,
                goal,
                distance,
            });
        }
    }
    Ok(Dataset { samples })
}

fn train(args: &Args) -> Result<()> {
    let ckpt = PathBuf::from(format!("{}.ckpt", args.out.display()));
    let t0 = std::time::Instant::now();
    let data = dataset(0..args.rooms as u64, args.goals_per_room, args.seed)?;
    let validation = dataset(2_000_000..2_000_064, 1, args.seed)?;
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
    let mut trainer = match args.resume && ckpt.exists() {
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
                checkpoint_every: 500,
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
                let grid = walkable(room)?;
                let mut rng = SplitMix64::new(room ^ 0xB1BD);
                let grid = match people {
                    0 => grid,
                    n => changed(&grid, &mut rng, n, 0.0)?,
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
    envfield::grid::check_writable(&args.out)?;
    if !args.eval_only {
        train(&args)?;
    }
    eval(&args)
}
