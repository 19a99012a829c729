//! People walking through a game level: where a body can stand, and walks that climb from one
//! level to another. Recast's demo levels (`scripts/fetch_recast_levels.sh` fetches them into
//! `data/recast/`) are 75 x 100 m and y up: far too large to draw a region from the VAE's
//! samples, so the region here is built from the level's own surfaces
//! ([`AccessibleRegion::standing`]: a standing torso over every surface that faces up, judged
//! by the region's filter).
//!
//! ```text
//! scripts/fetch_recast_levels.sh
//! cargo run --release --example level                                   # dungeon.obj, y up
//! cargo run --release --example level -- --scene data/recast/nav_test.obj --json
//! cargo run --release --example level -- --scene my_level.obj --up z --units cm
//! ```
//!
//! Walking pairs join standing places whose torsos differ in height by at least `--rise`
//! metres. Ours searches the exact field (fast marching over the region, once per goal) under
//! the walking poses, its checks reading the scene itself; PRM, RRT and the straight line share
//! the region. No learned field is trained for a level, and the navigation mesh of the room
//! tables walks one floor only, so neither has a row. Writes `scene.obj`, `region.ply` and
//! `top.png` (the region from above, coloured by height, with the first pair's paths) to
//! `--out`; the last line is JSON.
use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::affordance::{Actor, PoseSequence};
use envfield::rooms::harness::{
    pairs, run_pair, PairOptions, RoomContext, RoomPlanner, RunSettings,
};
use envfield::rooms::pictures::height_view;
use envfield::rooms::tables::{finite_mean, Tally};
use envfield::rooms::{standing_torsos, AccessibleRegion, RegionConfig};
use envfield::scene::{read_scene, ImportConfig, Units, UpAxis};
use envfield_examples::MotionArgs;
use std::path::PathBuf;
use std::time::Instant;

/// The most columns `level` builds a region from (at 0.25 m, 500 x 500 m).
const MAX_COLUMNS: f64 = 4.0e6;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "Walk people through a game level: the standing region and level-changing walks")]
struct Args {
    /// The level: a triangle mesh as OBJ or PLY.
    #[arg(long, default_value = "data/recast/dungeon.obj")]
    scene: PathBuf,
    /// The file's up axis: y (Recast's levels, glTF, most game engines) or z.
    #[arg(long, default_value = "y")]
    up: UpAxis,
    /// The file's units: m, cm, mm, or metres per unit.
    #[arg(long, default_value = "m")]
    units: Units,
    /// Voxel side of the region, metres (its columns are this far apart).
    #[arg(long, default_value_t = 0.25)]
    voxel: f32,
    /// Walking pairs.
    #[arg(long, default_value_t = 20)]
    pairs: usize,
    /// Goals the pairs share (each costs a fast marching over the region).
    #[arg(long, default_value_t = 5)]
    goals: usize,
    /// How much higher or lower than the goal a start's torso stands, at least, metres.
    #[arg(long, default_value_t = 1.0)]
    rise: f32,
    /// Ours' budget: expansions per step of the shortest walk (plus 200).
    #[arg(long, default_value_t = 50.0)]
    budget: f64,
    /// RRT's iterations and PRM's roadmap samples (the paper gives a room 500; a level is
    /// a hundred rooms).
    #[arg(long, default_value_t = 50_000)]
    sampler_budget: usize,
    /// Seed of the pairs and the samplers.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output folder.
    #[arg(long, default_value = "out/level")]
    out: PathBuf,
    /// The summary as one JSON line only.
    #[arg(long)]
    json: bool,
    /// Ours' people (one per pair) out for a viewer: --gltf, --bvh, --html.
    #[command(flatten)]
    motion: MotionArgs,
}

/// The planners of a level: ours on the exact field, PRM, RRT and the line.
const PLANNERS: [RoomPlanner; 4] = [
    RoomPlanner::OursExact,
    RoomPlanner::Prm,
    RoomPlanner::Rrt,
    RoomPlanner::Line,
];

fn main() -> Result<()> {
    let args = Args::parse();
    if !(1..=1000).contains(&args.pairs) || !(1..=args.pairs).contains(&args.goals) {
        bail!(
            "--pairs must be in 1..=1000 and --goals in 1..=--pairs (got {} and {})",
            args.pairs,
            args.goals
        );
    }
    if !(args.rise.is_finite() && args.rise >= 0.0) {
        bail!("--rise must be a height of 0 m or more (got {})", args.rise);
    }
    if !(1..=10_000_000).contains(&args.sampler_budget) {
        bail!(
            "--sampler-budget must be in 1..=10000000 (got {})",
            args.sampler_budget
        );
    }
    if !(args.budget.is_finite() && args.budget > 0.0 && args.budget <= 10_000.0) {
        bail!("--budget must be in (0, 10000] (got {})", args.budget);
    }
    if !(args.voxel.is_finite() && (0.05..=2.0).contains(&args.voxel)) {
        bail!(
            "--voxel must be in [0.05, 2] m (got {}): a body is about 0.5 m wide",
            args.voxel
        );
    }
    if !args.scene.is_file() {
        bail!(
            "{}: no such level (scripts/fetch_recast_levels.sh fetches Recast's demo levels)",
            args.scene.display()
        );
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    // Nothing this run writes may replace the level (`--out` holding its scene.obj).
    envfield::grid::protect_input(&args.scene);
    envfield::grid::check_writable(args.out.join("top.png"))?;
    envfield::grid::check_writable(args.out.join("scene.obj")).with_context(|| {
        format!(
            "--out {}: the scene is written there as scene.obj",
            args.out.display()
        )
    })?;
    args.motion.check(&[args.scene.as_path()])?;

    let (scene, report) = read_scene(&args.scene, &ImportConfig::new(args.up, args.units))?;
    eprintln!("{}: {report}", args.scene.display());
    scene.to_mesh().write(args.out.join("scene.obj"))?;

    // One column a voxel: past a few million the region takes many minutes, as a level read
    // in the wrong units does (an 8 m apartment in centimetres is 800 m wide).
    if let Some(b) = scene.aabb() {
        let (w, d) = (b.maxs.x - b.mins.x, b.maxs.y - b.mins.y);
        let columns = (w / args.voxel).ceil() as f64 * (d / args.voxel).ceil() as f64;
        if columns > MAX_COLUMNS {
            bail!(
                "the level is {w:.0} x {d:.0} m: {columns:.1e} columns of --voxel {} m, more than \
                 the {MAX_COLUMNS:.0e} a region is built from in minutes. Is it in centimetres \
                 (--units cm) or millimetres (--units mm)? Otherwise raise --voxel.",
                args.voxel
            );
        }
    }
    // The region: standing torsos over every up-facing surface, judged by the filter.
    let config = RegionConfig {
        voxel: args.voxel,
        ..RegionConfig::default()
    };
    let t = Instant::now();
    let torsos = standing_torsos(&scene, config.voxel)?;
    let torsos_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let region = AccessibleRegion::from_drawn(&scene, &torsos, &config.in_place())?;
    let region_s = torsos_s + t.elapsed().as_secs_f64();
    let voxels = region.grid.free_count();
    // The kept torsos inside the region: the standing places the pairs are drawn from.
    let standing: Vec<[f32; 3]> = region
        .samples
        .iter()
        .copied()
        .filter(|s| region.contains(*s))
        .collect();
    let centres = region.voxel_centres();
    let (zlo, zhi) = centres
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), c| {
            (a.min(c[2]), b.max(c[2]))
        });
    eprintln!(
        "region: {} torsos over up-facing surfaces, {} kept, {voxels} voxels of {} m \
         ({:.0} m² of standing room) in the largest of {} sets, torso heights {zlo:.1} to \
         {zhi:.1} m; {:.1} s",
        torsos.len(),
        region.samples.len(),
        config.voxel,
        // One voxel a column: a standing torso spans one or two voxels in height.
        standing.len() as f32 * config.voxel * config.voxel,
        region.components,
        region_s
    );
    if let Some(w) = region.left_out_warning() {
        eprintln!("warning: {w}");
    }
    region.write_ply(args.out.join("region.ply"))?;

    // Pairs: goals at standing places, starts at least --rise above or below them.
    let options = PairOptions {
        walks: args.pairs,
        min_distance: 0.0,
        goals: Some(args.goals),
        rise: args.rise,
        sit_downs: false,
        lie_downs: false,
        seed: args.seed,
        ..PairOptions::default()
    };
    let pairs = pairs(None, &scene, &region, &options)?;
    if pairs.is_empty() {
        bail!(
            "no two standing places of the region differ by --rise {} m in height: the level \
             has one floor, or its levels are not joined",
            args.rise
        );
    }
    if pairs.len() < args.pairs {
        eprintln!(
            "warning: {} pairs found of the {} asked for",
            pairs.len(),
            args.pairs
        );
    }

    let room = RoomContext::bare(&scene, &region);
    let mut tally = Tally::default();
    // Ours' path of every pair, and every planner's of the first.
    let mut drawn = Vec::new();
    let mut people: Vec<(String, PoseSequence)> = Vec::new();
    for (i, pair) in pairs.iter().enumerate() {
        let settings = RunSettings {
            budget: args.budget,
            big_budget: 0,
            sampler_budget: args.sampler_budget,
            seed: args.seed + i as u64,
            // A level's strict searches near a goal run longer than a room's: no limit.
            near_stall: 0,
            ..RunSettings::default()
        };
        let runs = run_pair(&room, pair, &PLANNERS, &settings)?;
        for r in &runs {
            if i == 0 && r.planner != RoomPlanner::OursExact && r.planner != RoomPlanner::Line {
                drawn.push((r.planner, r.path.clone()));
            }
        }
        for r in runs.iter().filter(|r| r.planner == RoomPlanner::OursExact) {
            drawn.push((r.planner, r.path.clone()));
            people.push((format!("walk {i}"), r.poses.clone()));
            if !r.outcome.reached {
                eprintln!(
                    "pair {i}: ours stopped {:.2} m from the goal{}",
                    r.outcome.dist_m,
                    if r.outcome.no_route {
                        " (no route)"
                    } else {
                        ""
                    }
                );
            }
        }
        tally.add(pair.kind, &runs);
    }
    height_view(&region, 3, &drawn).write_png(args.out.join("top.png"))?;
    if args.motion.any() {
        let actors: Vec<Actor> = people
            .iter()
            .map(|(name, poses)| Actor { name, poses })
            .collect();
        let points: Vec<_> = centres.iter().map(|&p| p.into()).collect();
        let title = args.scene.display().to_string();
        for f in args
            .motion
            .write(&scene.to_mesh(), &points, &actors, &title, false)?
        {
            eprintln!("wrote {}", f.display());
        }
    }

    let rises: Vec<f64> = pairs
        .iter()
        .map(|p| (p.start[2] - p.goal[2]).abs() as f64)
        .collect();
    let mut line = serde_json::json!({
        "scene": args.scene.display().to_string(),
        "pairs": tally.pairs(),
        "rise_m_mean": finite_mean(&rises),
        "region_voxels": voxels,
        "region_s": region_s,
        "torsos": torsos.len(),
        "kept": region.samples.len(),
    });
    let table3 = tally.table3(&PLANNERS, &mut line);
    let table4 = tally.table4(&PLANNERS, &mut line);
    if !args.json {
        println!(
            "{} walking pairs, each changing height by {:.1} m on average",
            tally.pairs(),
            finite_mean(&rises).unwrap_or(f64::NAN)
        );
        print!("{table3}");
        println!("\naligned poses, percent supported / collision-free / valid");
        print!("{table4}");
    }
    println!("{line}");
    Ok(())
}
