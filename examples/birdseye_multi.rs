//! Several people walking through a room at once, seen from above: our step rule (priority
//! inheritance with backtracking over the bird's-eye field's steps), the paper's Algorithm 1
//! (section 4.1: each person's field on the floor map the others change, one batched pass per
//! time step), each on the learned and the exact field, ORCA, and PIBT on a lattice of one
//! body per cell as multi-agent path finding writes it.
//!
//! `cargo run --release --example birdseye_multi -- --people 4 --seed 3` writes
//! `out/birdseye/crowd.gif` (the floor map, each person's field contours, positions and
//! trails), `crowd.json` (every loop's figures, and the first loop's paths in metres, arrival
//! steps and pose checks) and each person's aligned walking sequence `walk_N.json`, and prints
//! a JSON summary (`--json`: the figures only).
//!
//! `--rooms 100 --people 16 --json` runs a batch on generated rooms and prints, as its last
//! line, one JSON object with each loop's figures under its name (`ours_reach_pct`,
//! `alg1_exact_person_collisions`, ...). A room too small for that many people is counted
//! apart (`rooms_too_small`) and the batch goes on. `--loops ours,orca` runs some loops only.
//!
//! `--scene FILE.obj|ply|gltf|glb` reads a scene instead of generating one.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::affordance::{walk, Actor, WalkConfig};
use envfield::eikonal::FastMarching;
use envfield::grid::Grid2;
use envfield::grid::{Canvas, Point2};
use envfield::nets::FieldNet;
use envfield::plan::crowd::{
    grid_pibt, lacam_crowd, orca_crowd, pibt_crowd, plan_crowd, random_trips, shortest_lengths,
    walk_crowd, CrowdConfig, CrowdRun, OrcaConfig, Trip,
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
    /// Print only the figures, as one JSON object.
    #[arg(long)]
    json: bool,
    /// The loops to run, comma-separated (by default ours, ours_exact, pibt, alg1,
    /// alg1_exact, orca, grid_pibt; the first is the one drawn and written out for one room).
    #[arg(long, value_enum, value_delimiter = ',')]
    loops: Vec<Loop>,
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

impl Args {
    /// The loops asked for, each once, in the order given; all of them by default.
    fn loops(&self) -> Vec<Loop> {
        let mut loops: Vec<Loop> = Vec::new();
        for &l in &self.loops {
            if !loops.contains(&l) {
                loops.push(l);
            }
        }
        match loops.is_empty() {
            true => Loop::DEFAULT.to_vec(),
            false => loops,
        }
    }
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

/// The crowd loops this example can run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
#[value(rename_all = "snake_case")]
enum Loop {
    /// Ours (`plan_crowd`): PIBT over the shipped bird's-eye field's steps, and the LaCAM
    /// search where PIBT leaves someone short.
    Ours,
    /// The same on the exact field (fast marching).
    OursExact,
    /// PIBT over the shipped field's steps alone (`pibt_crowd`).
    Pibt,
    /// The same on the exact field.
    PibtExact,
    /// The LaCAM search alone (`lacam_crowd`) on the shipped field.
    Lacam,
    /// The same on the exact field.
    LacamExact,
    /// The paper's Algorithm 1 on the shipped field (`walk_crowd`).
    Alg1,
    /// Algorithm 1 on the exact field.
    Alg1Exact,
    /// ORCA (`orca_crowd`).
    Orca,
    /// PIBT on a lattice of one body per cell, as multi-agent path finding writes it.
    GridPibt,
}

impl Loop {
    /// The loops run when `--loops` names none.
    const DEFAULT: [Loop; 7] = [
        Loop::Ours,
        Loop::OursExact,
        Loop::Pibt,
        Loop::Alg1,
        Loop::Alg1Exact,
        Loop::Orca,
        Loop::GridPibt,
    ];

    /// The loop's name in the JSON keys.
    fn name(self) -> &'static str {
        match self {
            Loop::Ours => "ours",
            Loop::OursExact => "ours_exact",
            Loop::Pibt => "pibt",
            Loop::PibtExact => "pibt_exact",
            Loop::Alg1 => "alg1",
            Loop::Alg1Exact => "alg1_exact",
            Loop::Orca => "orca",
            Loop::GridPibt => "grid_pibt",
            Loop::Lacam => "lacam",
            Loop::LacamExact => "lacam_exact",
        }
    }

    /// Runs the loop on `trips`, with its time in seconds.
    fn run(
        self,
        walkable: &Grid2,
        trips: &[Trip],
        model: &FieldNet,
        config: &CrowdConfig,
        seed: u64,
    ) -> Result<(CrowdRun, f64)> {
        let exact = FastMarching::default();
        let t = Instant::now();
        let run = match self {
            Loop::Ours => plan_crowd(walkable, trips, model, config)?,
            Loop::OursExact => plan_crowd(walkable, trips, &exact, config)?,
            Loop::Pibt => pibt_crowd(walkable, trips, model, config)?,
            Loop::PibtExact => pibt_crowd(walkable, trips, &exact, config)?,
            Loop::Alg1 => walk_crowd(walkable, trips, model, config)?,
            Loop::Alg1Exact => walk_crowd(walkable, trips, &exact, config)?,
            Loop::Orca => orca_crowd(walkable, trips, config, &OrcaConfig::default())?,
            Loop::GridPibt => grid_pibt(walkable, trips, config, seed)?,
            Loop::Lacam => lacam_crowd(walkable, trips, model, config)?,
            Loop::LacamExact => lacam_crowd(walkable, trips, &exact, config)?,
        };
        Ok((run, t.elapsed().as_secs_f64()))
    }
}

/// Bodies' area over the free floor's (the floor map's free cells).
fn density(floor: &Floor, people: usize, body_radius_m: f32) -> f64 {
    let free = floor.map.grid.free_count() as f64 * (RESOLUTION as f64).powi(2);
    people as f64 * std::f64::consts::PI * (body_radius_m as f64).powi(2) / free.max(1e-9)
}

fn batch(args: &Args, rooms: usize, model: &FieldNet, config: &CrowdConfig) -> Result<()> {
    let loops = args.loops();
    let mut tallies = vec![CrowdTally::default(); loops.len()];
    let gait = walk(&WalkConfig::default(), args.seed)?;
    let maker = args.scene.rooms(RoomConfig::birdseye())?;
    let (mut too_small, mut why_small, mut densities) = (Vec::new(), None, Vec::new());
    for room in args.seed..args.seed + rooms as u64 {
        let scene = maker.room(room)?.scene;
        let floor = Floor::new(scene, args.body_radius)?;
        // A room too small for this many people is counted apart, and the batch goes on.
        let trips = match random_trips(&floor.walkable, args.people, config, 1.0 / RESOLUTION, room)
        {
            Ok(trips) => trips,
            Err(e) => {
                too_small.push(room);
                why_small.get_or_insert_with(|| format!("room {room}: {e}"));
                continue;
            }
        };
        densities.push(density(&floor, args.people, args.body_radius));
        let shortest = shortest_lengths(&floor.walkable, &trips)?;
        let mut line = format!("room {room}:");
        for (kind, tally) in loops.iter().zip(&mut tallies) {
            let (run, seconds) = kind.run(&floor.walkable, &trips, model, config, room)?;
            tally.add(&run, &shortest, &floor, config, seconds, &gait)?;
            line.push_str(&format!(
                " {} {}/{}",
                kind.name(),
                tally.reached,
                tally.people
            ));
        }
        if !args.json {
            eprintln!("{line}");
        }
    }
    if densities.is_empty() {
        bail!(
            "no room of the {rooms} held {} people: {}",
            args.people,
            why_small.unwrap_or_default()
        );
    }
    let mut out = serde_json::Map::new();
    out.insert("rooms".into(), rooms.into());
    out.insert("rooms_run".into(), densities.len().into());
    out.insert("rooms_too_small".into(), too_small.into());
    if let Some(why) = why_small {
        out.insert("first_too_small".into(), why.into());
    }
    out.insert("people".into(), args.people.into());
    out.insert(
        "density".into(),
        (densities.iter().sum::<f64>() / densities.len() as f64).into(),
    );
    out.insert("body_radius_m".into(), args.body_radius.into());
    out.insert("step_length_m".into(), args.step_length.into());
    for (kind, tally) in loops.iter().zip(&tallies) {
        tally.json(&format!("{}_", kind.name()), &mut out);
    }
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
    let gait = walk(&WalkConfig::default(), args.seed)?;
    // Every loop on the same trips; the first one's people are written out and drawn.
    let loops = args.loops();
    let mut figures = serde_json::Map::new();
    let mut shown = None;
    for &kind in &loops {
        let (run, seconds) = kind.run(&floor.walkable, &trips, model, config, args.seed)?;
        let mut tally = CrowdTally::default();
        tally.add(&run, &shortest, &floor, config, seconds, &gait)?;
        tally.json(&format!("{}_", kind.name()), &mut figures);
        figures.insert(
            format!("{}_ending", kind.name()),
            serde_json::to_value(run.ending)?,
        );
        shown.get_or_insert((kind, run));
    }
    let Some((kind, run)) = shown else {
        bail!("--loops named no loop");
    };

    // Each person's walk, aligned to their path and checked in the scene.
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
    let mut summary = serde_json::json!({
        "seed": args.seed,
        "floor_map": [floor.walkable.rows(), floor.walkable.cols()],
        "people_count": args.people,
        "density": density(&floor, args.people, args.body_radius),
        "drawn": kind.name(),
        "people": people,
    });
    for (k, v) in figures {
        summary[k] = v;
    }
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
    summary.as_object_mut().map(|o| o.remove("people"));
    summary["out"] = serde_json::json!(args.out);
    println!("{summary}");
    Ok(())
}

/// A map cell's centre as a point.
fn point(c: envfield::grid::Cell2) -> Point2 {
    Point2::new(c.row as f32, c.col as f32)
}
