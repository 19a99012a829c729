//! Several people walking through a room at once, seen from above (paper section 4.1,
//! Algorithm 1): each person's field on the floor map the others change, predicted for all of
//! them in one batched pass per time step, against the same loop on the exact solver and
//! against ORCA.
//!
//! `cargo run --release --example birdseye_multi -- --people 4 --seed 3` writes
//! `out/birdseye/crowd.gif` (the floor map, each person's field contours, positions and
//! trails), `crowd.json` (paths in metres, arrival steps, pose checks) and each person's
//! aligned walking sequence `walk_N.json`, and prints a JSON summary.
//!
//! `--rooms 100 --people 4 --json` runs a batch on generated rooms and prints, as its last
//! line, one JSON object with the learned loop's figures and the same for the exact loop
//! (`exact_*`) and ORCA (`orca_*`).
//!
//! `--room FILE.obj|ply` reads a scene (metres, z up) instead of generating one.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::affordance::{walk, Actor, WalkConfig};
use envfield::eikonal::FastMarching;
use envfield::grid::{Canvas, Point2};
use envfield::nets::FieldNet;
use envfield::plan::crowd::{
    orca_crowd, random_trips, shortest_lengths, walk_crowd, CrowdConfig, OrcaConfig,
};
use envfield::rooms::birdseye::{crowd_frames, CrowdTally, Floor, RESOLUTION};
use envfield::scene::RoomConfig;
use envfield_examples::{MotionArgs, SceneArgs};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "Several people walking through a room at once (Algorithm 1) against ORCA")]
struct Args {
    /// People walking at once.
    #[arg(long, default_value_t = 4)]
    people: usize,
    /// Seed of the room and of the start/goal pairs.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    #[command(flatten)]
    scene: SceneArgs,
    /// Run a batch over this many generated rooms (seeds from --seed) and print the figures.
    #[arg(long)]
    rooms: Option<usize>,
    /// With --rooms: print the batch as one JSON object only.
    #[arg(long)]
    json: bool,
    /// The bird's-eye field.
    #[arg(long, default_value = "models/birdseye.safetensors")]
    model: PathBuf,
    /// Output folder.
    #[arg(long, default_value = "out/birdseye")]
    out: PathBuf,
    /// Write the frames as PNG files into this folder instead of an animated GIF.
    #[arg(long)]
    frames: Option<PathBuf>,
    /// Body radius, metres.
    #[arg(long, default_value_t = 0.25)]
    body_radius: f32,
    /// Step length, metres (one step per time step).
    #[arg(long, default_value_t = 0.5)]
    step_length: f32,
    /// Time steps a person held up by others waits for the way through them to clear.
    #[arg(long, default_value_t = 3)]
    patience: usize,
    /// Headings a step may take (8: the paper's).
    #[arg(long, default_value_t = 8)]
    directions: usize,
    /// Time steps before giving up.
    #[arg(long, default_value_t = 400)]
    max_steps: usize,
    /// Everyone's walk on the run's clock out for a viewer (one room only): --gltf, --bvh,
    /// --html.
    #[command(flatten)]
    motion: MotionArgs,
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.people == 0 || args.rooms == Some(0) {
        bail!("--people and --rooms must be at least 1");
    }
    if args.rooms.is_some_and(|r| r > 100_000) {
        bail!("--rooms: at most 100000");
    }
    if args.rooms.is_some() && args.scene.scene.is_some() {
        bail!("--rooms evaluates generated rooms and would never read --room/--scene: give one of them");
    }
    if args.rooms.is_some() && args.motion.any() {
        bail!("--gltf, --bvh and --html write one room's people: not with --rooms");
    }
    if args
        .seed
        .checked_add(args.rooms.unwrap_or(1) as u64)
        .is_none()
    {
        bail!("--seed {} + --rooms does not fit in 64 bits", args.seed);
    }
    if !(4..=64).contains(&args.directions) || args.max_steps == 0 || args.max_steps > 100_000 {
        bail!(
            "--directions must be in 4..=64 and --max-steps in 1..=100000 (got {} and {})",
            args.directions,
            args.max_steps
        );
    }
    if !(args.body_radius.is_finite() && args.body_radius > 0.0) {
        bail!(
            "--body-radius must be a positive number of metres, got {}",
            args.body_radius
        );
    }
    if !(args.step_length.is_finite() && args.step_length >= RESOLUTION) {
        bail!(
            "--step-length must be at least the map's {RESOLUTION} m cell, got {}",
            args.step_length
        );
    }
    let model = FieldNet::load(&args.model)
        .with_context(|| format!("loading the bird's-eye field {}", args.model.display()))?;
    let cells = |m: f32| m / RESOLUTION;
    let config = CrowdConfig {
        body_radius: cells(args.body_radius),
        step_length: cells(args.step_length),
        max_steps: args.max_steps,
        patience: args.patience,
        directions: args.directions,
    };
    match args.rooms {
        Some(rooms) => batch(&args, rooms, &model, &config),
        None => one_room(&args, &model, &config),
    }
}

fn batch(args: &Args, rooms: usize, model: &FieldNet, config: &CrowdConfig) -> Result<()> {
    let exact = FastMarching::default();
    let (mut learned, mut fmm, mut orca) = (
        CrowdTally::default(),
        CrowdTally::default(),
        CrowdTally::default(),
    );
    let gait = walk(&WalkConfig::default(), args.seed)?;
    let maker = args.scene.rooms(RoomConfig::birdseye())?;
    for room in args.seed..args.seed + rooms as u64 {
        let scene = maker.room(room)?.scene;
        let floor = Floor::new(scene, args.body_radius)?;
        let trips = random_trips(&floor.walkable, args.people, config, 1.0 / RESOLUTION, room)?;
        let shortest = shortest_lengths(&floor.walkable, &trips)?;
        let (w, r) = (&floor.walkable, config.body_radius);
        let t = Instant::now();
        let run = walk_crowd(w, &trips, model, config)?;
        let s = t.elapsed().as_secs_f64();
        learned.add(&run, &shortest, &floor, r, s, &gait)?;
        let t = Instant::now();
        let run = walk_crowd(w, &trips, &exact, config)?;
        let s = t.elapsed().as_secs_f64();
        fmm.add(&run, &shortest, &floor, r, s, &gait)?;
        let t = Instant::now();
        let run = orca_crowd(w, &trips, config, &OrcaConfig::default())?;
        let s = t.elapsed().as_secs_f64();
        orca.add(&run, &shortest, &floor, r, s, &gait)?;
        if !args.json {
            eprintln!(
                "room {room}: learned {}/{} exact {}/{} orca {}/{} reached",
                learned.reached, learned.people, fmm.reached, fmm.people, orca.reached, orca.people
            );
        }
    }
    let mut out = serde_json::Map::new();
    out.insert("rooms".into(), rooms.into());
    out.insert("people".into(), args.people.into());
    out.insert("body_radius_m".into(), args.body_radius.into());
    out.insert("step_length_m".into(), args.step_length.into());
    learned.json("", &mut out);
    fmm.json("exact_", &mut out);
    orca.json("orca_", &mut out);
    println!("{}", serde_json::Value::Object(out));
    Ok(())
}

fn one_room(args: &Args, model: &FieldNet, config: &CrowdConfig) -> Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    args.scene.protect();
    envfield::grid::check_writable(args.out.join("crowd.json"))?;
    let inputs: Vec<&std::path::Path> = args.scene.scene.iter().map(PathBuf::as_path).collect();
    args.motion.check(&inputs)?;
    let rooms = args.scene.rooms(RoomConfig::birdseye())?;
    let (scene, _) = args.scene.scene(&rooms, args.seed, None)?;
    let floor = Floor::new(scene, args.body_radius)?;
    let trips = random_trips(
        &floor.walkable,
        args.people,
        config,
        1.0 / RESOLUTION,
        args.seed,
    )?;
    let shortest = shortest_lengths(&floor.walkable, &trips)?;
    let t = Instant::now();
    let run = walk_crowd(&floor.walkable, &trips, model, config)?;
    let ms_per_step = 1e3 * t.elapsed().as_secs_f64() / run.steps().max(1) as f64;
    let exact = walk_crowd(&floor.walkable, &trips, &FastMarching::default(), config)?;
    let orca = orca_crowd(&floor.walkable, &trips, config, &OrcaConfig::default())?;

    // Each person's walk, aligned to their path and checked in the scene.
    let gait = walk(&WalkConfig::default(), args.seed)?;
    let mut people = Vec::new();
    // A time step's seconds at the gait's speed: the motion out plays on the run's clock.
    let step_s = config.step_length * RESOLUTION / (gait.step_length() * gait.fps);
    let mut timed = Vec::new();
    for (i, trip) in trips.iter().enumerate() {
        if args.motion.any() {
            timed.push(floor.timed_walk(&run, i, &gait, step_s)?.0);
        }
        let (aligned, reports) = floor.aligned_walk(&run, i, &gait)?;
        aligned.write(args.out.join(format!("walk_{i}.json")))?;
        let valid = reports.iter().filter(|r| r.valid()).count();
        people.push(serde_json::json!({
            "start_m": floor.world(point(trip.start)).coords.as_slice()[..2],
            "goal_m": floor.world(point(trip.goal)).coords.as_slice()[..2],
            "arrived_at_step": run.arrived_at[i],
            "path_m": run.path(i).iter().map(|&p| {
                let w = floor.world(p);
                [w.x, w.y]
            }).collect::<Vec<_>>(),
            "path_ratio": run.path_length(i) / shortest[i],
            "pose_frames": reports.len(),
            "pose_valid_pct": 100.0 * valid as f64 / reports.len().max(1) as f64,
        }));
    }
    let summary = serde_json::json!({
        "seed": args.seed,
        "floor_map": [floor.walkable.rows(), floor.walkable.cols()],
        "people": people,
        "steps": run.steps(),
        "ms_per_step": ms_per_step,
        "person_collisions": run.person_collisions(config.body_radius),
        "furniture_collisions": run.obstacle_collisions(&floor.walkable),
        "exact_arrived": exact.arrived_at.iter().flatten().count(),
        "orca_arrived": orca.arrived_at.iter().flatten().count(),
        "orca_person_collisions": orca.person_collisions(config.body_radius),
    });
    envfield::grid::write_atomic(
        args.out.join("crowd.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    if args.motion.any() {
        let names: Vec<String> = (0..timed.len()).map(|i| format!("person {i}")).collect();
        let actors: Vec<Actor> = names
            .iter()
            .zip(&timed)
            .map(|(name, poses)| Actor { name, poses })
            .collect();
        let title = format!("{} people, room {}", args.people, args.seed);
        for f in args
            .motion
            .write(&floor.scene.to_mesh(), &[], &actors, &title, true)?
        {
            eprintln!("wrote {}", f.display());
        }
    }
    let frames = crowd_frames(&floor.walkable, &trips, &run, model, config)?;
    match &args.frames {
        Some(dir) => {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            for (t, frame) in frames.iter().enumerate() {
                frame.write_png(dir.join(format!("frame_{t:04}.png")))?;
            }
        }
        None => Canvas::write_gif(&frames, 100, args.out.join("crowd.gif"))?,
    }
    let mut summary = summary;
    summary.as_object_mut().map(|o| o.remove("people"));
    summary["out"] = serde_json::json!(args.out);
    println!("{summary}");
    Ok(())
}

/// A map cell's centre as a point.
fn point(c: envfield::grid::Cell2) -> Point2 {
    Point2::new(c.row as f32, c.col as f32)
}
