//! Human navigation in 3D rooms (paper section 4.2, Tables 3 and 4). Ours (`ours`,
//! `ours_exact`): the pose-dependent search on the learned (or exact) 3D field under the pose
//! filter, the region alone where the poses allow no route within `--budget`, then straight
//! cuts the filter allows; its field is made once per goal and its checks read the scene's
//! distances and surface columns sampled once per room. `ours_raw` is the paper's search
//! alone, `ours_noaff` ours under the region alone; RRT, RRT*, PRM and the line share the
//! region and collision test; `navmesh` is a navigation mesh of the floor (Recast in Rust)
//! queried by Polyanya. Every path wears the same pose sequence, checked against the scene.
//! Times are split per path (`<planner>_s`), per goal (`_goal_s`) and per room (`_room_s`).
//!
//! ```text
//! cargo run --release --example room_nav                              # the shipped room, a few pairs
//! cargo run --release --example room_nav -- --rooms 5 --pairs 20 --json \
//!     --big-budget 20000 --fields out/fields                         # the tables
//! cargo run --release --example room_nav -- --scene room.obj          # a scene of your own
//! ```
//!
//! Walking pairs join standing places of the region at least a metre apart; sit-down pairs
//! go from in front of a seat to seated; lie-down pairs from beside a bed or sofa, through
//! sitting on its edge, to lying on it. The first pair's scene, region, paths, poses and
//! pictures (`top.png`, `room.png`) go to `--out`; the last line is JSON (`--json`).
use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::affordance::{walk, WalkConfig};
use envfield::affordance::{Actor, PoseSequence};
use envfield::nets::FieldNet;
use envfield::rooms::field3_store::{save_tagged, FieldOrigin, Obtained};
use envfield::rooms::harness::{
    pairs, run_pair, FloorPlanner, PairOptions, RoomContext, RoomPlanner, RunSettings,
};
use envfield::rooms::pictures::write_run_files;
use envfield::rooms::tables::{finite_mean, mean_bytes, Tally};
use envfield::rooms::{sample_region, AccessibleRegion, Field3Config, FieldStore, SceneTables};
use envfield::scene::RoomConfig;
use envfield::vae::Cvae;
use envfield_examples::{MotionArgs, Navmesh, SceneArgs};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The room whose learned field ships in `models/`.
const SHIPPED_ROOM: u64 = 10_000;

#[derive(Parser)]
#[command(
    about = "Navigate people through 3D rooms: ours against RRT, RRT*, PRM and the straight line"
)]
struct Args {
    #[command(flatten)]
    scene: SceneArgs,
    /// Seed of the generated room (10000 and up were never seen by the VAE).
    #[arg(long, default_value_t = SHIPPED_ROOM)]
    seed: u64,
    /// Evaluate this many rooms (seeds from --seed on).
    #[arg(long, default_value_t = 1)]
    rooms: u64,
    /// Walking pairs per room (sit-down pairs: one per reachable seat; lie-down pairs: one
    /// per reachable bed or sofa).
    #[arg(long, default_value_t = PairOptions::default().walks)]
    pairs: usize,
    /// The VAE's weights (default: the shipped gated VAE, `models/vae_gated.safetensors`,
    /// whose regions hold the seats; `models/vae.safetensors` is the paper's).
    #[arg(long)]
    vae: Option<PathBuf>,
    /// The learned field's weights for the first room (default: a kept one in --fields, or
    /// models/room_field_<seed>.safetensors when it fits; otherwise the field is trained).
    #[arg(long)]
    field: Option<PathBuf>,
    /// Training steps of a room's learned field.
    #[arg(long, default_value_t = 3000)]
    field_steps: u64,
    /// Save a trained field here (for a single room).
    #[arg(long)]
    save_field: Option<PathBuf>,
    /// Keep every trained room field in this folder (named for the room, a fingerprint of its
    /// region and the training's settings, and the steps) and load it from there on the next
    /// run, so a second run of the tables skips the training; a scene's (`--scene`) too.
    #[arg(long)]
    fields: Option<PathBuf>,
    /// RRT* budget of the second row (raised until its path ratio matches ours).
    #[arg(long, default_value_t = RunSettings::default().big_budget)]
    big_budget: usize,
    /// Ours' budget: expansions per step of the shortest walk (plus 200); past it, ours falls
    /// back to the region alone.
    #[arg(long, default_value_t = RunSettings::default().budget)]
    budget: f64,
    /// The same for sit-down and lie-down pairs.
    #[arg(long, default_value_t = RunSettings::default().sit_budget)]
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
    /// Only these planners, comma separated (ours, ours_raw, ours_noaff, ours_exact, rrt,
    /// rrtstar, rrtstar_big, prm, line, navmesh); every one by default.
    #[arg(long, value_delimiter = ',')]
    planners: Option<Vec<RoomPlanner>>,
    /// Write one JSON line per pair and planner here (room, pair, kind, planner, seconds,
    /// its goal's seconds, reached, relaxed, valid share, path ratio, distance left).
    #[arg(long)]
    walks_out: Option<PathBuf>,
    /// The first room's people (one per pair, the first planner's path) out for a viewer.
    #[command(flatten)]
    motion: MotionArgs,
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The room's learned field: `--field`, a kept one in `--fields`, the shipped one, or one
/// trained now (kept in `--fields`, saved to `--save-field`); its training seconds when
/// trained.
fn room_field(
    args: &Args,
    k: u64,
    seed: u64,
    region: &AccessibleRegion,
) -> Result<(FieldNet, Option<f64>)> {
    let generated = args.scene.scene.is_none();
    // A kept field's file carries its region's fingerprint in its name, so a scene's field is
    // kept and found again as a generated room's is (another scene is another region).
    let mut cfg = Field3Config::default();
    (cfg.steps, cfg.seed) = (args.field_steps, seed);
    let shipped = root().join(format!("models/room_field_{seed}.safetensors"));
    let store = FieldStore {
        named: args.field.clone().filter(|_| k == 0),
        kept: args.fields.clone(),
        shipped: Some(shipped)
            .filter(|_| generated && !args.scene.catalogue && !args.scene.apartment),
    };
    let style = ProgressStyle::with_template("{msg:>24} {bar:30} {pos}/{len} (eta {eta})")?;
    let bar = ProgressBar::new(args.field_steps).with_style(style);
    bar.set_message(format!("room {seed}: 3D field"));
    let (net, how) = store.load_or_train(region, &cfg, seed, |s, _, _| bar.set_position(s))?;
    bar.finish_and_clear();
    match how {
        Obtained::Loaded(FieldOrigin::Kept(f)) => {
            eprintln!("room {seed}: field loaded from {}", f.display())
        }
        Obtained::Loaded(_) => {}
        Obtained::Trained(report, kept) => {
            eprintln!(
                "room {seed}: learned field, median error {:.3} m, p95 {:.3} m, {:.0} s{}",
                report.median_err_m,
                report.p95_err_m,
                report.train_s,
                kept.map(|p| format!(", kept in {}", p.display()))
                    .unwrap_or_default()
            );
            if let (Some(p), 1) = (&args.save_field, args.rooms) {
                save_tagged(&net, p, region, &cfg)?;
            }
            return Ok((net, Some(report.train_s)));
        }
    }
    Ok((net, None))
}

fn check(args: &Args) -> Result<()> {
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
    if args.save_field.is_some() && args.rooms != 1 {
        bail!(
            "--save-field keeps one room's field: not with --rooms {} (--fields DIR keeps every \
             room's)",
            args.rooms
        );
    }
    // Where the fields go is checked before any field is trained (8 minutes a room).
    if let Some(dir) = &args.fields {
        if dir.exists() && !dir.is_dir() {
            bail!(
                "--fields {} is a file: it names the folder learned fields are kept in",
                dir.display()
            );
        }
        std::fs::create_dir_all(dir)
            .with_context(|| format!("--fields {}: creating the folder", dir.display()))?;
        envfield::grid::check_writable(dir.join("room_field.safetensors"))
            .with_context(|| format!("--fields {}", dir.display()))?;
    }
    if let Some(p) = &args.save_field {
        envfield::grid::check_writable(p)
            .with_context(|| format!("--save-field {}", p.display()))?;
    }
    if args.big_budget > 1_000_000 {
        bail!(
            "--big-budget is at most 1000000 RRT* iterations (got {}): the table's runs take \
             0.2 s per 20000",
            args.big_budget
        );
    }
    for (flag, b) in [("--budget", args.budget), ("--sit-budget", args.sit_budget)] {
        if !(b.is_finite() && b > 0.0 && b <= 10_000.0) {
            bail!("{flag} must be in (0, 10000] (got {b})");
        }
    }
    Ok(())
}

fn main() -> Result<()> {
    let args = Args::parse();
    check(&args)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    args.scene.protect();
    envfield::grid::check_writable(args.out.join("top.png"))?;
    envfield::grid::check_writable(args.out.join("scene.obj")).with_context(|| {
        format!(
            "--out {}: the scene is written there as scene.obj",
            args.out.display()
        )
    })?;
    let inputs: Vec<&Path> = args.scene.scene.iter().map(PathBuf::as_path).collect();
    args.motion.check(&inputs)?;
    let vae_file = args
        .vae
        .clone()
        .unwrap_or_else(|| root().join("models/vae_gated.safetensors"));
    let vae =
        Cvae::load(&vae_file).with_context(|| format!("loading the VAE {}", vae_file.display()))?;
    let rooms = args.scene.rooms(RoomConfig::default())?;
    let planners = RoomPlanner::chosen(args.planners.as_deref()).context("--planners")?;
    let needs_net = planners.iter().any(|p| p.learned());
    // The records are kept and written at the end, atomically: a run that fails leaves the
    // file as it was, and a link there is replaced, never written through.
    if let Some(p) = &args.walks_out {
        envfield::grid::check_writable(p)
            .with_context(|| format!("--walks-out {}", p.display()))?;
    }
    let mut walks_out = args.walks_out.as_ref().map(|_| String::new());
    let mut tally = Tally::default();
    // The first room's people, for --gltf, --bvh and --html: one per pair.
    let mut people: Vec<(String, PoseSequence)> = Vec::new();
    let mut first_room = None;
    let mut field_s = Vec::new();
    let (mut region_s, mut memory) = (Vec::new(), Vec::new());
    for k in 0..args.rooms {
        let seed = args.seed + k;
        let (scene, generated, zones) =
            args.scene
                .scene_in_rooms(&rooms, seed, Some(args.samples))?;
        // A scene too large for the pose tables is refused now, not after its region.
        SceneTables::check(&scene)?;
        let t = Instant::now();
        let region = sample_region(&vae, &scene, args.samples, seed)?;
        region_s.push(t.elapsed().as_secs_f64());
        eprintln!(
            "room {seed}: region of {} voxels, {} sit-downs, {} lie-downs, {:.1} s",
            region.free_indices().len(),
            region.sit_downs.len(),
            region.lie_downs.len(),
            t.elapsed().as_secs_f64()
        );
        if let Some(w) = region.left_out_warning() {
            eprintln!("warning: room {seed}: {w}");
        }
        // A learned field only for the planners that read one: `--planners ours_exact,prm`
        // runs on a room no field was trained for, without training one.
        let net = if needs_net {
            let (net, trained_s) = room_field(&args, k, seed, &region)?;
            field_s.extend(trained_s);
            Some(net)
        } else {
            None
        };
        let (tables, tables_s) = RoomContext::tables(&scene)?;
        let mesh = Navmesh::for_room(&scene, &walk(&WalkConfig::default(), seed)?, seed);
        let room_planners: Vec<RoomPlanner> = planners
            .iter()
            .copied()
            .filter(|&p| p != RoomPlanner::Navmesh || mesh.is_some())
            .collect();
        let room = RoomContext {
            scene: &scene,
            region: &region,
            net: net.as_ref(),
            tables: Some(&tables),
            tables_s,
            navmesh: mesh.as_ref().map(|m| (m as &dyn FloorPlanner, m.build_s)),
        };
        memory.push(room.bytes()?);
        if k == 0 && args.motion.any() {
            first_room = Some((scene.to_mesh(), region.voxel_centres()));
        }
        let options = PairOptions {
            walks: args.pairs,
            rooms: &zones,
            seed,
            ..PairOptions::default()
        };
        let ps = pairs(generated.as_ref(), &scene, &region, &options)?;
        for (i, pair) in ps.iter().enumerate() {
            let settings = RunSettings {
                budget: args.budget,
                sit_budget: args.sit_budget,
                big_budget: args.big_budget,
                seed: seed + i as u64,
                ..RunSettings::default()
            };
            let runs = run_pair(&room, pair, &room_planners, &settings)?;
            if k == 0 && i == 0 {
                write_run_files(&args.out, &scene, &region, &runs)?;
            }
            if let (0, Some(run)) = (k, runs.first()) {
                let name = format!("{} {i}: {}", pair.kind.name(), run.planner.name());
                people.push((name, run.poses.clone()));
            }
            if let Some(w) = walks_out.as_mut() {
                for r in &runs {
                    let line = r.record(seed, i, pair.kind);
                    w.push_str(&line.to_string());
                    w.push('\n');
                }
            }
            match &generated {
                Some(r) => tally.add_in(pair.kind, &runs, r)?,
                None => tally.add(pair.kind, &runs),
            }
        }
    }
    // Summaries: per planner over all pairs (Table 3), and per kind (Table 4).
    let mut line = serde_json::json!({"rooms": args.rooms, "pairs": tally.pairs()});
    let table3 = tally.table3(&planners, &mut line);
    let table4 = tally.table4(&planners, &mut line);
    line["field_train_s_per_room"] = finite_mean(&field_s).into();
    line["region_s_per_room"] = finite_mean(&region_s).into();
    mean_bytes(&memory, &mut line);
    if !args.json {
        println!("Table 3: {} pairs in {} room(s)", tally.pairs(), args.rooms);
        print!("{table3}");
        println!("\nTable 4: aligned poses, percent supported / collision-free / valid");
        print!("{table4}");
    }
    if let (Some(w), Some(p)) = (walks_out, &args.walks_out) {
        envfield::grid::write_atomic(p, w.as_bytes())
            .with_context(|| format!("--walks-out {}", p.display()))?;
    }
    if let Some((mesh, points)) = first_room {
        let actors: Vec<Actor> = people
            .iter()
            .map(|(name, poses)| Actor { name, poses })
            .collect();
        let points: Vec<_> = points.iter().map(|&p| p.into()).collect();
        for f in args.motion.write(
            &mesh,
            &points,
            &actors,
            &format!(
                "{} {}",
                if args.scene.apartment {
                    "apartment"
                } else {
                    "room"
                },
                args.seed
            ),
            true,
        )? {
            eprintln!("wrote {}", f.display());
        }
    }
    println!("{line}");
    Ok(())
}
