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
//! go from in front of a seat to seated. The first pair's scene, region, paths, poses and
//! pictures (`top.png`, `room.png`) go to `--out`; the last line is JSON (`--json`).
use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::affordance::{walk, WalkConfig};
use envfield::nets::{FieldNet, ModelConfig};
use envfield::plan::space3::SamplingConfig;
use envfield::rooms::harness::{
    pairs, run_pair, FieldKind, PairKind, PlannerKind, RoomContext, RunSettings,
};
use envfield::rooms::pictures::write_run_files;
use envfield::rooms::tables::{finite_mean, Tally};
use envfield::rooms::{
    check_sample_density, region_key, sample_region, train_field3, AccessibleRegion, Field3Config,
};
use envfield::scene::{
    catalogue_room, generate_room, read_scene, Catalogue, ImportConfig, RoomConfig, Units, UpAxis,
};
use envfield::vae::Cvae;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[path = "shared/navmesh.rs"]
mod navmesh;
use envfield::rooms::harness::FloorPlanner;
use navmesh::Navmesh;

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
    /// Furnish the rooms with Sweet Home 3D's furniture models instead of the generator's
    /// boxes (scripts/fetch_sweethome3d.sh fetches them).
    #[arg(long)]
    catalogue: bool,
    /// Seed of the generated room (10000 and up were never seen by the VAE).
    #[arg(long, default_value_t = SHIPPED_ROOM)]
    seed: u64,
    /// Evaluate this many rooms (seeds from --seed on).
    #[arg(long, default_value_t = 1)]
    rooms: u64,
    /// Walking pairs per room (sit-down pairs: one per reachable seat).
    #[arg(long, default_value_t = 4)]
    pairs: usize,
    /// The VAE's weights (default: the shipped gated VAE, `models/vae_gated.safetensors`,
    /// whose regions hold the seats; `models/vae.safetensors` is the paper's).
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
    /// accessible region and the training's settings, and the training steps) and load it
    /// from there on the next run, so a
    /// second run of the tables skips the training.
    #[arg(long)]
    fields: Option<PathBuf>,
    /// RRT* budget of the second row (raised until its path ratio matches ours).
    #[arg(long, default_value_t = 5000)]
    big_budget: usize,
    /// Ours' budget: expansions per step of the shortest walk (plus 200); past it, ours falls
    /// back to the region alone. A learned field's hollow takes many expansions to fill: at 5,
    /// 2-3% of the walks stopped in one.
    #[arg(long, default_value_t = 50.0)]
    budget: f64,
    /// The same for sit-down pairs: the steps must match the sequence's frames to the seat,
    /// which takes search too.
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
    /// Only these planners, comma separated (ours, ours_raw, ours_noaff, ours_exact, rrt,
    /// rrtstar, rrtstar_big, prm, line, navmesh); every one by default.
    #[arg(long, value_delimiter = ',')]
    planners: Option<Vec<PlannerKind>>,
    /// Write one JSON line per pair and planner here (room, pair, kind, planner, seconds,
    /// its goal's seconds, reached, relaxed, valid share, path ratio, distance left): where a
    /// mean's time goes, walk by walk.
    #[arg(long)]
    walks_out: Option<PathBuf>,
}

/// Sweet Home 3D's catalogue, fetched by scripts/fetch_sweethome3d.sh.
fn open_catalogue() -> Result<Catalogue> {
    let dir = Catalogue::find().context("no catalogue: run scripts/fetch_sweethome3d.sh")?;
    Ok(Catalogue::read(dir)?)
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
    let mut cfg = Field3Config::default();
    (cfg.steps, cfg.seed) = (args.field_steps, seed);
    // The region and the training's settings but its steps (which the key names apart): a
    // field kept under another of either is not this one.
    let settings = Field3Config {
        steps: 0,
        ..cfg.clone()
    };
    let fingerprint = format!("{:016x}{:08x}", region_key(region), settings.key() as u32);
    let key = format!("{fingerprint}_{}", args.field_steps);
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
        .or_else(|| Some(shipped).filter(|p| generated && !args.catalogue && p.is_file()));
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
        // A field that carries its region's fingerprint (a kept one, or the shipped one made
        // from it) fits only that region; one without, any region on a lattice of its shape.
        let tagged = FieldNet::read_tags(&f, REGION_TAG)?;
        let same_region = tagged
            .as_deref()
            .is_none_or(|t| t.split('_').next() == Some(fingerprint.as_str()));
        let fits = same_region
            && matches!(net.config(), ModelConfig::Goal(c) if c.extent == region.frame.shape.to_vec());
        if fits {
            return Ok((net, None));
        }
        // A field the user named must fit; the shipped one is trained again when it does not.
        if args.field.is_some() || cached.as_ref() == Some(&f) {
            bail!(
                "{}: this field was trained on another region (the VAE or the room changed); \
                 train it again with --field-steps",
                f.display()
            );
        }
        eprintln!(
            "room {seed}: the shipped field {} was trained on another region or otherwise; \
             training one",
            f.display()
        );
    }
    let style = ProgressStyle::with_template("{msg:>24} {bar:30} {pos}/{len} (eta {eta})")?;
    let bar = ProgressBar::new(args.field_steps).with_style(style);
    bar.set_message(format!("room {seed}: 3D field"));
    let (net, report) = train_field3(region, &cfg, None, |s, _, _| bar.set_position(s))?;
    bar.finish_and_clear();
    eprintln!(
        "room {seed}: learned field, median error {:.3} m, p95 {:.3} m, {:.0} s",
        report.median_err_m, report.p95_err_m, report.train_s
    );
    // Saved with its region's fingerprint, so a later run knows which region it fits.
    if let (Some(p), 1) = (&args.save_field, args.rooms) {
        net.save_tagged(p, &[(REGION_TAG, key.clone())])?;
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
        .unwrap_or_else(|| root().join("models/vae_gated.safetensors"));
    let vae =
        Cvae::load(&vae_file).with_context(|| format!("loading the VAE {}", vae_file.display()))?;
    let catalogue = args.catalogue.then(open_catalogue).transpose()?;
    let planners: Vec<PlannerKind> = match &args.planners {
        Some(p) if p.is_empty() => bail!("--planners: name one planner at least"),
        Some(p) => PlannerKind::ALL
            .into_iter()
            .filter(|k| p.contains(k))
            .collect(),
        None => PlannerKind::ALL.to_vec(),
    };
    let needs_net = planners.iter().any(|p| {
        matches!(
            p.field(),
            Some(FieldKind::Learned | FieldKind::LearnedTable)
        )
    });
    let mut walks_out = args
        .walks_out
        .as_ref()
        .map(|p| {
            std::fs::File::create(p)
                .map(std::io::BufWriter::new)
                .with_context(|| format!("--walks-out: creating {}", p.display()))
        })
        .transpose()?;
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
                let r = match &catalogue {
                    Some(c) => catalogue_room(c, &RoomConfig::catalogue(), seed)?,
                    None => generate_room(&RoomConfig::default(), seed)?,
                };
                (r.scene.clone(), Some(r))
            }
        };
        let t = Instant::now();
        let region = sample_region(&vae, &scene, args.samples, seed)?;
        region_s.push(t.elapsed().as_secs_f64());
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
        let room_planners: Vec<PlannerKind> = planners
            .iter()
            .copied()
            .filter(|&p| p != PlannerKind::Navmesh || mesh.is_some())
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
        let ps = pairs(generated.as_ref(), &scene, &region, args.pairs, seed)?;
        for (i, pair) in ps.iter().enumerate() {
            let budget = match pair.kind {
                PairKind::Walk => args.budget,
                PairKind::Sit => args.sit_budget,
            };
            let settings = RunSettings {
                budget,
                big_budget: args.big_budget,
                sampler_budget: SamplingConfig::default().budget,
                seed: seed + i as u64,
            };
            let runs = run_pair(&room, pair, &room_planners, &settings)?;
            if k == 0 && i == 0 {
                write_run_files(&args.out, &scene, &region, &runs)?;
            }
            if let Some(w) = walks_out.as_mut() {
                for r in &runs {
                    let o = &r.outcome;
                    let line = serde_json::json!({
                        "room": seed, "pair": i, "kind": pair.kind.name(),
                        "planner": r.planner.name(), "seconds": o.seconds,
                        "goal_seconds": o.goal_seconds, "reached": o.reached,
                        "relaxed": o.relaxed, "valid": o.poses.valid,
                        "path_ratio": o.path_ratio, "dist_m": o.dist_m,
                    });
                    writeln!(w, "{line}").context("--walks-out: writing")?;
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
    for (j, (name, _)) in memory.first().into_iter().flatten().enumerate() {
        let v: Vec<f64> = memory.iter().map(|m| m[j].1 as f64).collect();
        line[format!("{name}_per_room")] = finite_mean(&v).into();
    }
    if !args.json {
        println!("Table 3: {} pairs in {} room(s)", tally.pairs(), args.rooms);
        print!("{table3}");
        println!("\nTable 4: aligned poses, percent supported / collision-free / valid");
        print!("{table4}");
    }
    if let Some(mut w) = walks_out {
        w.flush().context("--walks-out: writing")?;
    }
    println!("{line}");
    Ok(())
}
