//! Human navigation in 3D rooms (paper section 4.2, Tables 3 and 4): the pose-dependent search
//! on the learned 3D field, with and without affordance, on the exact field, and RRT, RRT*,
//! PRM and the straight line on the same accessible region and collision test; every path is
//! fitted with the pose sequence and its poses checked.
//!
//! Ours (`ours`, `ours_exact`) is the search under the pose filter, then the region alone
//! where the poses allow no route within the budget (`--budget`, expansions per step of the
//! shortest walk; `FieldSearch3::search_relaxed`), then straight cuts the pose filter allows
//! (`FieldSearch3::shortcut`). Its field is made once per goal (fast marching, or the learned
//! field in one batched pass) and its pose checks read the scene's distances sampled once per
//! room, so each step is lookups. `ours_raw` is the paper's search alone (a network pass per
//! step, checks against the scene), and `ours_noaff` the search and cuts under the region
//! alone. `navmesh` is the games' planner: a navigation mesh of the floor (Recast's pipeline
//! in Rust) and Polyanya's shortest paths on it. Every planner's time is split per path
//! (`<planner>_s`), per goal (`_goal_s`) and per room (`_room_s`).
//!
//! ```text
//! cargo run --release --example room_nav                              # the shipped room, a few pairs
//! cargo run --release --example room_nav -- --rooms 5 --pairs 20 --json \
//!     --big-budget 20000 --fields out/fields                         # the tables
//! cargo run --release --example room_nav -- --scene room.obj          # a scene of your own
//! ```
//!
//! Walking pairs join two standing places of the accessible region at least a metre apart;
//! sit-down pairs start where the sit-down sequence starts in front of a seat and end seated.
//! Writes `scene.obj`, `region.ply`, `path_<planner>.obj`, `poses_<planner>.json` (the first
//! pair's aligned poses), `top.png` (every planner's first path over the floor) and `room.png`
//! (the room ray-cast from above one wall, the paths and five of ours' poses drawn) to `--out`.
//! The last line is one JSON object (`--json`).

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::affordance::{walk, WalkConfig};
use envfield::nets::{FieldNet, ModelConfig};
use envfield::rooms::harness::{
    pairs, run_pair, PairKind, PlannerKind, RoomContext, Run, RunSettings,
};
use envfield::rooms::pictures::{room_view, top_view};
use envfield::rooms::tables::{finite_mean, Tally};
use envfield::rooms::{
    check_sample_density, point, region_key, sample_region, train_field3, AccessibleRegion,
    Field3Config,
};
use envfield::scene::nalgebra::Point3;
use envfield::scene::{generate_room, read_scene, write_polyline_obj, ImportConfig, Units, UpAxis};
use envfield::vae::Cvae;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[path = "shared/navmesh.rs"]
mod navmesh;
use envfield::rooms::harness::FloorPlanner;
use navmesh::{Navmesh, NavmeshConfig};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The room whose learned field ships in `models/`.
const SHIPPED_ROOM: u64 = 10_000;

#[derive(Parser)]
#[command(
    about = "Navigate people through 3D rooms: ours against RRT, RRT*, PRM and the straight line"
)]
struct Args {
    /// A scene to read instead of a generated room (OBJ or PLY, metres, z up).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// The scene file's up axis: z, or y (glTF, game levels).
    #[arg(long, default_value = "z")]
    up: UpAxis,
    /// The scene file's units: m, cm, mm, or metres per unit.
    #[arg(long, default_value = "m")]
    units: Units,
    /// Seed of the generated room (10000 and up were never seen by the VAE).
    #[arg(long, default_value_t = SHIPPED_ROOM)]
    seed: u64,
    /// Evaluate this many rooms (seeds from --seed on).
    #[arg(long, default_value_t = 1)]
    rooms: u64,
    /// Walking pairs per room (sit-down pairs: one per reachable seat).
    #[arg(long, default_value_t = 4)]
    pairs: usize,
    /// The VAE's weights.
    #[arg(long)]
    vae: Option<PathBuf>,
    /// The learned field's weights for the room (default: models/room_field_<seed>.safetensors
    /// when it is there; otherwise the field is trained).
    #[arg(long)]
    field: Option<PathBuf>,
    /// Training steps of a room's learned field.
    #[arg(long, default_value_t = 3000)]
    field_steps: u64,
    /// Save a trained field here (for a single room).
    #[arg(long)]
    save_field: Option<PathBuf>,
    /// Keep every trained room field in this folder
    /// (`room_field_<seed>_<region>_<steps>.safetensors`: the room, a fingerprint of its
    /// accessible region and the training steps) and load it from there on the next run, so a
    /// second run of the tables skips the training.
    #[arg(long)]
    fields: Option<PathBuf>,
    /// RRT* budget of the second row (raised until its path ratio matches ours).
    #[arg(long, default_value_t = 5000)]
    big_budget: usize,
    /// Ours' budget: expansions per step of the shortest walk (plus 200); past it, ours falls
    /// back to the region alone.
    #[arg(long, default_value_t = 5.0)]
    budget: f64,
    /// The same for sit-down pairs: the steps must match the sequence's frames to the seat,
    /// which takes more search than a walk.
    #[arg(long, default_value_t = 50.0)]
    sit_budget: f64,
    /// Torso samples drawn for the accessible region.
    #[arg(long, default_value_t = 6000)]
    samples: usize,
    /// Output folder.
    #[arg(long, default_value = "out/room_nav")]
    out: PathBuf,
    /// The summary as one JSON line only.
    #[arg(long)]
    json: bool,
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The room's learned field: `--field`, a kept one in `--fields`, the shipped one, or one
/// trained now (kept in `--fields`, saved to `--save-field`); its training seconds when
/// trained.
/// The metadata key of a kept field's region fingerprint and training steps.
const REGION_TAG: &str = "room_nav.region";

fn room_field(
    args: &Args,
    k: u64,
    seed: u64,
    region: &AccessibleRegion,
) -> Result<(FieldNet, Option<f64>)> {
    let generated = args.scene.is_none();
    let key = format!("{:016x}_{}", region_key(region), args.field_steps);
    let cached = args
        .fields
        .as_ref()
        .filter(|_| generated)
        .map(|d| d.join(format!("room_field_{seed}_{key}.safetensors")));
    let shipped = root().join(format!("models/room_field_{seed}.safetensors"));
    let file = args
        .field
        .clone()
        .or_else(|| cached.clone().filter(|p| p.is_file()))
        .or_else(|| Some(shipped).filter(|p| generated && p.is_file()));
    if let Some(f) = file.filter(|_| k == 0 || args.field.is_none()) {
        // A kept field carries its region's fingerprint: a file planted or left under the
        // name is not taken for this region's.
        if cached.as_ref() == Some(&f) {
            if FieldNet::read_tags(&f, REGION_TAG)?.as_deref() != Some(&key) {
                bail!(
                    "{}: not a field of this region (no or another fingerprint); remove it",
                    f.display()
                );
            }
            eprintln!("room {seed}: field loaded from {}", f.display());
        }
        let net = FieldNet::load(&f)?;
        return match net.config() {
            ModelConfig::Goal(c) if c.extent == region.frame.shape.to_vec() => Ok((net, None)),
            _ => bail!(
                "{}: this field was trained on another region (the VAE or the room changed); \
                 train it again with --field-steps",
                f.display()
            ),
        };
    }
    let style = ProgressStyle::with_template("{msg:>24} {bar:30} {pos}/{len} (eta {eta})")?;
    let bar = ProgressBar::new(args.field_steps).with_style(style);
    bar.set_message(format!("room {seed}: 3D field"));
    let mut cfg = Field3Config::default();
    (cfg.steps, cfg.seed) = (args.field_steps, seed);
    let (net, report) = train_field3(region, &cfg, None, |s, _, _| bar.set_position(s))?;
    bar.finish_and_clear();
    eprintln!(
        "room {seed}: learned field, median error {:.3} m, p95 {:.3} m, {:.0} s",
        report.median_err_m, report.p95_err_m, report.train_s
    );
    if let (Some(p), 1) = (&args.save_field, args.rooms) {
        net.save(p)?;
    }
    if let Some(p) = &cached {
        let dir = p.parent().context("a folder")?;
        std::fs::create_dir_all(dir)
            .with_context(|| format!("--fields: creating {}", dir.display()))?;
        net.save_tagged(p, &[(REGION_TAG, key)])?;
        eprintln!("room {seed}: field kept in {}", p.display());
    }
    Ok((net, Some(report.train_s)))
}

/// The first pair's files: the scene, the region, every planner's path and poses, and the
/// two pictures.
fn write_first(out: &Path, room: &RoomContext, runs: &[Run]) -> Result<()> {
    room.scene.to_mesh().write(out.join("scene.obj"))?;
    room.region.write_ply(out.join("region.ply"))?;
    for run in runs {
        let line: Vec<Point3<f32>> = run.path.iter().map(|&p| point(p)).collect();
        if line.len() > 1 {
            write_polyline_obj(&line, out.join(format!("path_{}.obj", run.planner)))?;
        }
        run.poses
            .write(out.join(format!("poses_{}.json", run.planner)))?;
    }
    let drawn: Vec<_> = runs.iter().map(|r| (r.planner, r.path.clone())).collect();
    top_view(room.region, &drawn).write_png(out.join("top.png"))?;
    // A few of ours' poses, evenly along its path.
    let ours = &runs[0].poses.frames;
    let skeletons: Vec<_> = (0..5).map(|j| ours[j * (ours.len() - 1) / 4]).collect();
    room_view(room.scene, &drawn, &skeletons)?.write_png(out.join("room.png"))?;
    Ok(())
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.rooms == 0 || args.rooms > 1000 || args.pairs == 0 || args.pairs > 10_000 {
        bail!(
            "--rooms must be in 1..=1000 and --pairs in 1..=10000 (got {} and {})",
            args.rooms,
            args.pairs
        );
    }
    if args.samples == 0 || args.samples > 1_000_000 || args.seed.checked_add(args.rooms).is_none()
    {
        bail!("--samples must be in 1..=1000000 and --seed + --rooms fit in 64 bits");
    }
    if args.field_steps == 0 || args.field_steps > 10_000_000 {
        bail!(
            "--field-steps must be in 1..=10000000 (got {}): an untrained field is no field",
            args.field_steps
        );
    }
    for (flag, b) in [("--budget", args.budget), ("--sit-budget", args.sit_budget)] {
        if !(b.is_finite() && b > 0.0 && b <= 10_000.0) {
            bail!("{flag} must be in (0, 10000] (got {b})");
        }
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    envfield::grid::check_writable(args.out.join("top.png"))?;
    let vae_file = args
        .vae
        .clone()
        .unwrap_or_else(|| root().join("models/vae.safetensors"));
    let vae =
        Cvae::load(&vae_file).with_context(|| format!("loading the VAE {}", vae_file.display()))?;
    let planners = PlannerKind::ALL;
    let mut tally = Tally::default();
    let mut field_s = Vec::new();
    let (mut region_s, mut memory) = (Vec::new(), Vec::new());
    for k in 0..args.rooms {
        let seed = args.seed + k;
        let (scene, generated) = match &args.scene {
            Some(f) => (
                {
                    let import = ImportConfig::new(args.up, args.units);
                    let (scene, report) = read_scene(f, &import)?;
                    eprintln!("{}: {report}", f.display());
                    if let Some(w) = check_sample_density(&scene, args.samples)? {
                        eprintln!("warning: {w}");
                    }
                    scene
                },
                None,
            ),
            None => {
                let r = generate_room(&envfield::scene::RoomConfig::default(), seed)?;
                (r.scene.clone(), Some(r))
            }
        };
        let t = Instant::now();
        let region = sample_region(&vae, &scene, args.samples, seed)?;
        region_s.push(t.elapsed().as_secs_f64());
        let (net, trained_s) = room_field(&args, k, seed, &region)?;
        field_s.extend(trained_s);
        let (distances, distances_s) = RoomContext::distances(&scene)?;
        let gait = walk(&WalkConfig::default(), seed)?;
        let mesh = match Navmesh::build(&scene, &NavmeshConfig::for_gait(&gait)) {
            Ok(m) => {
                eprintln!(
                    "room {seed}: navigation mesh of {} polygons, {} vertices, {:.1} ms",
                    m.polygons,
                    m.vertices,
                    1e3 * m.build_s
                );
                Some(m)
            }
            Err(e) => {
                eprintln!("room {seed}: no navigation mesh, its row is left out: {e}");
                None
            }
        };
        memory.push([
            region.grid.len(),
            distances.bytes(),
            4 * region.grid.len(),
            mesh.as_ref().map_or(0, |m| m.bytes()),
        ]);
        let room_planners: Vec<PlannerKind> = planners
            .into_iter()
            .filter(|&p| p != PlannerKind::Navmesh || mesh.is_some())
            .collect();
        let room = RoomContext {
            scene: &scene,
            region: &region,
            net: &net,
            distances: &distances,
            distances_s,
            navmesh: mesh.as_ref().map(|m| (m as &dyn FloorPlanner, m.build_s)),
        };
        let ps = pairs(generated.as_ref(), &scene, &region, args.pairs, seed)?;
        for (i, pair) in ps.iter().enumerate() {
            let budget = match pair.kind {
                PairKind::Walk => args.budget,
                PairKind::Sit => args.sit_budget,
            };
            let settings = RunSettings {
                budget,
                big_budget: args.big_budget,
                seed: seed + i as u64,
            };
            let runs = run_pair(&room, pair, &room_planners, &settings)?;
            if k == 0 && i == 0 {
                write_first(&args.out, &room, &runs)?;
            }
            tally.add(pair.kind, &runs);
        }
    }
    // Summaries: per planner over all pairs (Table 3), and per kind (Table 4).
    let mut line = serde_json::json!({"rooms": args.rooms, "pairs": tally.pairs()});
    let table3 = tally.table3(&planners, &mut line);
    let table4 = tally.table4(&planners, &mut line);
    line["field_train_s_per_room"] = finite_mean(&field_s).into();
    line["region_s_per_room"] = finite_mean(&region_s).into();
    // Bytes per room: the region's voxels, the distance grid, one goal's field table, the
    // navigation mesh.
    let names = ["region", "distances", "field_per_goal", "navmesh"];
    for (j, name) in names.iter().enumerate() {
        let v: Vec<f64> = memory.iter().map(|m: &[usize; 4]| m[j] as f64).collect();
        line[format!("{name}_bytes_per_room")] = finite_mean(&v).into();
    }
    if !args.json {
        println!("Table 3: {} pairs in {} room(s)", tally.pairs(), args.rooms);
        print!("{table3}");
        println!("\nTable 4: aligned poses, percent supported / collision-free / valid");
        print!("{table4}");
    }
    println!("{line}");
    Ok(())
}
