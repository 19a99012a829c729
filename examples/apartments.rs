//! Apartments of 2 to 4 rooms furnished with models by other modellers than the default
//! catalogue's: the held-out table of the accessible region (training models against
//! evaluation models, the split of `crates/scene/src/model_split.tsv`), or one apartment to
//! files.
//!
//! ```text
//! bash scripts/fetch_sweethome3d_contrib.sh                         # the models (CC-BY, CC0)
//! cargo run --release --example apartments -- --count 20 --json     # 20 of each half
//! cargo run --release --example apartments -- --one 30000           # one, to out/apartments
//! ```
//!
//! Each apartment (seeds from 30000) is judged three ways on the same furniture, as the room
//! table is: ours (the shipped VAE's samples, 240 per m² of floor), its untrained twin's and
//! uniform samples in the apartment's box. Each is also written as one OBJ, read back as a
//! user's file would be, and its region built again from that file, timed step by step. The
//! last line is one JSON object.

use anyhow::{bail, Context, Result};
use clap::{Parser, ValueEnum};
use envfield::rooms::pictures::room_view;
use envfield::rooms::quality::{rooms_reached, uniform_in_room, HeldOut};
use envfield::rooms::sampling::SAMPLES_PER_M2;
use envfield::rooms::{draw_torsos, AccessibleRegion, RegionConfig};
use envfield::scene::{
    apartment, read_scene, Apartment, ApartmentConfig, Catalogue, Half, ImportConfig, Scene,
};
use envfield::vae::{Cvae, Gate, SampleOptions};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Clone, Copy, Debug, PartialEq, ValueEnum)]
enum Which {
    Training,
    Evaluation,
    Both,
}

#[derive(Parser)]
#[command(
    about = "Apartments furnished by other modellers: the accessible region's held-out table"
)]
struct Args {
    /// The contributed furniture libraries (default: data/sweethome3d-contrib, fetched by
    /// scripts/fetch_sweethome3d_contrib.sh).
    #[arg(long)]
    furniture: Option<PathBuf>,
    /// Apartments of each half.
    #[arg(long, default_value_t = 20)]
    count: u64,
    /// Which half of the model split furnishes them.
    #[arg(long, value_enum, default_value_t = Which::Both)]
    half: Which,
    /// The first apartment's seed.
    #[arg(long, default_value_t = 30_000)]
    first_seed: u64,
    /// The VAE's weights (default: the shipped gated VAE).
    #[arg(long)]
    vae: Option<PathBuf>,
    /// Write apartment SEED (evaluation models) to --out instead of the table.
    #[arg(long)]
    one: Option<u64>,
    /// Output folder of --one.
    #[arg(long, default_value = "out/apartments")]
    out: PathBuf,
    /// Print only the last line, one JSON object.
    #[arg(long)]
    json: bool,
    /// Only time each apartment's region from its file (no controls, no figures): for a
    /// quiet machine.
    #[arg(long)]
    timing: bool,
}

/// Torso samples for an apartment's floor, at the shipped density.
fn samples_for(apt: &Apartment) -> usize {
    (apt.home.size[0] * apt.home.size[1] * SAMPLES_PER_M2).round() as usize
}

fn draw(vae: &Cvae, scene: &Scene, n: usize, seed: u64, gate: Gate) -> Result<Vec<[f32; 3]>> {
    let options = SampleOptions::new(n, seed).with_gate(gate);
    Ok(draw_torsos(vae, scene, &options, None)?)
}

/// The apartment written as one OBJ, read back as a user's file, and its region built from
/// it: the time of each step, milliseconds.
fn from_file(apt: &Apartment, vae: &Cvae, seed: u64, dir: &Path) -> Result<serde_json::Value> {
    let file = dir.join(format!("apartment_{seed}.obj"));
    apt.home.scene.to_mesh().write(&file)?;
    let t = Instant::now();
    let (scene, _) = read_scene(&file, &ImportConfig::default())?;
    let import_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let drawn = draw(vae, &scene, samples_for(apt), seed, Gate::Trained)?;
    let sample_ms = t.elapsed().as_secs_f64() * 1e3;
    let region = AccessibleRegion::from_drawn(&scene, &drawn, &RegionConfig::default())?;
    std::fs::remove_file(&file).ok();
    let r = region.times;
    let total = import_ms
        + sample_ms
        + r.filter_ms
        + r.gaps_ms
        + r.sit_downs_ms
        + r.lie_downs_ms
        + r.voxels_ms;
    Ok(serde_json::json!({
        "import_ms": import_ms, "sample_ms": sample_ms, "filter_ms": r.filter_ms,
        "gaps_ms": r.gaps_ms, "sit_downs_ms": r.sit_downs_ms, "lie_downs_ms": r.lie_downs_ms,
        "voxels_ms": r.voxels_ms, "total_ms": total, "voxels": region.grid.free_count(),
        "sit_downs": region.sit_downs.len(), "lie_downs": region.lie_downs.len(),
    }))
}

fn table(args: &Args, vae: &Cvae, catalogue: &Catalogue) -> Result<()> {
    let halves: &[Half] = match args.half {
        Which::Training => &[Half::Training],
        Which::Evaluation => &[Half::Evaluation],
        Which::Both => &[Half::Evaluation, Half::Training],
    };
    let untrained = Cvae::new(vae.config().clone(), 1)?;
    let config = RegionConfig::default();
    let scratch = tempfile::tempdir()?;
    let mut line = serde_json::json!({"first_seed": args.first_seed, "count": args.count});
    for &half in halves {
        let models = catalogue.only(half);
        let style =
            ProgressStyle::with_template("{msg:>24} {bar:30} {pos}/{len} {elapsed_precise}")?;
        let bar = ProgressBar::new(args.count)
            .with_style(style)
            .with_message(format!("{half:?} apartments"));
        let mut held_out = HeldOut::default();
        let mut extra = Vec::new();
        for k in 0..args.count {
            let seed = args.first_seed + k;
            let apt = apartment(&models, &ApartmentConfig::default(), seed)?;
            let triangles = apt.home.scene.to_mesh().triangles.len();
            if args.timing {
                let file = from_file(&apt, vae, seed, scratch.path())?;
                extra.push(serde_json::json!({"seed": seed, "from_file": file,
                    "triangles": triangles,
                    "area_m2": apt.home.size[0] * apt.home.size[1]}));
                bar.inc(1);
                continue;
            }
            let n = samples_for(&apt);
            let drawn = draw(vae, &apt.home.scene, n, seed, Gate::Trained)?;
            let twin = draw(&untrained, &apt.home.scene, n, seed, Gate::Off)?;
            let uniform = uniform_in_room(&apt.home, 2.5, n, seed);
            let region = held_out.add(&apt.home, &drawn, &twin, &uniform, &config)?;
            let reached = region
                .as_ref()
                .map(|r| rooms_reached(&apt, r))
                .unwrap_or_default();
            let file = from_file(&apt, vae, seed, scratch.path())?;
            let q = held_out.ours.last().expect("just added");
            if !args.json {
                bar.println(format!(
                    "{seed} {half:?}: {} rooms, {:.0} m², {} items, {} triangles: implausible {:.2}%, \
                     seats {:.0}% of {}, beds {:.0}% of {}, floor {:.1}%, rooms {}/{}, region from \
                     the file {:.1} s",
                    apt.rooms.len(),
                    apt.home.size[0] * apt.home.size[1],
                    apt.home.furniture.len(),
                    triangles,
                    q.region_implausible_pct,
                    q.region_seat_coverage_pct,
                    q.seats,
                    q.region_bed_coverage_pct,
                    q.beds,
                    q.floor_coverage_pct,
                    reached.iter().filter(|r| **r).count(),
                    apt.rooms.len(),
                    file["total_ms"].as_f64().unwrap_or(0.0) / 1e3,
                ));
            }
            extra.push(serde_json::json!({
                "seed": seed,
                "rooms": apt.rooms.len(),
                "rooms_reached": reached.iter().filter(|r| **r).count(),
                "area_m2": apt.home.size[0] * apt.home.size[1],
                "items": apt.home.furniture.len(),
                "triangles": triangles,
                "samples": n,
                "from_file": file,
            }));
            bar.inc(1);
        }
        bar.finish_and_clear();
        let mut part = if args.timing {
            serde_json::json!({})
        } else {
            held_out.summary_json(args.first_seed)
        };
        let all_reached = extra
            .iter()
            .filter(|e| e["rooms_reached"] == e["rooms"])
            .count();
        let mut times: Vec<f64> = extra
            .iter()
            .map(|e| e["from_file"]["total_ms"].as_f64().unwrap_or(f64::NAN))
            .collect();
        times.sort_by(f64::total_cmp);
        part["apartments_with_every_room_reached"] = all_reached.into();
        part["region_from_file_median_ms"] = times.get(times.len() / 2).copied().into();
        part["region_from_file_worst_ms"] = times.last().copied().into();
        part["apartments"] = extra.into();
        line[format!("{half:?}").to_lowercase()] = part;
    }
    if !args.json {
        for half in ["evaluation", "training"] {
            let Some(p) = line.get(half) else { continue };
            if args.timing {
                eprintln!(
                    "{half}: region from the file: median {:.1} s, worst {:.1} s",
                    p["region_from_file_median_ms"].as_f64().unwrap_or(f64::NAN) / 1e3,
                    p["region_from_file_worst_ms"].as_f64().unwrap_or(f64::NAN) / 1e3,
                );
                continue;
            }
            eprintln!(
                "{half}: implausible {:.2}% (worst {:.2}%), seats {:.1}% (least {:.0}%), beds {:.1}%, \
                 floor {:.1}%, every room reached in {}/{}; controls: untrained implausible \
                 {:.2}%, uniform {:.2}%; region from the file: median {:.1} s, worst {:.1} s",
                p["region_implausible_pct"].as_f64().unwrap_or(f64::NAN),
                p["max_region_implausible_pct"].as_f64().unwrap_or(f64::NAN),
                p["region_seat_coverage_pct"].as_f64().unwrap_or(f64::NAN),
                p["min_region_seat_coverage_pct"].as_f64().unwrap_or(f64::NAN),
                p["region_bed_coverage_pct"].as_f64().unwrap_or(f64::NAN),
                p["floor_coverage_pct"].as_f64().unwrap_or(f64::NAN),
                p["apartments_with_every_room_reached"],
                args.count,
                p["untrained_vae"]["region_implausible_pct"].as_f64().unwrap_or(f64::NAN),
                p["uniform_box"]["region_implausible_pct"].as_f64().unwrap_or(f64::NAN),
                p["region_from_file_median_ms"].as_f64().unwrap_or(f64::NAN) / 1e3,
                p["region_from_file_worst_ms"].as_f64().unwrap_or(f64::NAN) / 1e3,
            );
        }
    }
    println!("{line}");
    Ok(())
}

fn one(args: &Args, vae: &Cvae, catalogue: &Catalogue, seed: u64) -> Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let models = catalogue.only(Half::Evaluation);
    let apt = apartment(&models, &ApartmentConfig::default(), seed)?;
    let scene_file = args.out.join(format!("apartment_{seed}.obj"));
    apt.home.scene.to_mesh().write(&scene_file)?;
    let drawn = draw(vae, &apt.home.scene, samples_for(&apt), seed, Gate::Trained)?;
    let region = AccessibleRegion::from_drawn(&apt.home.scene, &drawn, &RegionConfig::default())?;
    region.write_files(&args.out)?;
    room_view(&apt.home.scene, &[], &[])?.write_png(args.out.join("apartment.png"))?;
    // Where the region lies over furniture nobody sits or lies on: voxels by piece, and
    // their heights above the floor.
    let mut over = std::collections::BTreeMap::<String, Vec<f32>>::new();
    for c in region.voxel_centres() {
        if let Some(f) = apt
            .home
            .furniture
            .iter()
            .find(|f| !f.kind.is_seat() && f.covers(c[0], c[1]))
        {
            let name = apt.home.scene.objects()[f.object].name.clone();
            over.entry(name)
                .or_default()
                .push((c[2] * 100.0).round() / 100.0);
        }
    }
    // Each seat: where a body sits on it (the sit-down's last torso) and how far the nearest
    // accessible voxel's centre lies from there.
    let centres = region.voxel_centres();
    let mut seats = Vec::new();
    for f in apt.home.furniture.iter().filter(|f| f.kind.is_seat()) {
        let Some(seq) = envfield::affordance::sit_on(f)? else {
            continue;
        };
        let t = seq.frames.last().expect("frames").torso();
        let near = centres
            .iter()
            .map(|c| ((c[0] - t.x).powi(2) + (c[1] - t.y).powi(2) + (c[2] - t.z).powi(2)).sqrt())
            .fold(f32::INFINITY, f32::min);
        let name = apt.home.scene.objects()[f.object].name.clone();
        seats.push(
            serde_json::json!({"seat": name, "torso": [t.x, t.y, t.z], "nearest_voxel_m": near}),
        );
    }
    let reached = rooms_reached(&apt, &region);
    for (room, ok) in apt.rooms.iter().zip(&reached) {
        if !ok {
            eprintln!(
                "warning: the {:?} at {:?} is out of the region: no body passes its door",
                room.kind, room.bounds
            );
        }
    }
    let summary = serde_json::json!({
        "seed": seed,
        "seats": seats,
        "over_furniture": over,
        "scene": scene_file,
        "rooms": apt.rooms,
        "doors": apt.doors,
        "furniture": apt.items.iter().map(|&i| &models.items[i].name).collect::<Vec<_>>(),
        "region_voxels": region.grid.free_count(),
        "rooms_reached": reached,
        "region_ms": region.times,
    });
    envfield::grid::write_atomic(
        args.out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    println!("{summary}");
    Ok(())
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.count == 0 || args.count > 1000 {
        bail!("--count must be in 1..=1000 (got {})", args.count);
    }
    let dir = match &args.furniture {
        Some(d) => d.clone(),
        None => Catalogue::find_contrib().context(
            "no contributed furniture: run scripts/fetch_sweethome3d_contrib.sh (or pass --furniture)",
        )?,
    };
    let catalogue = Catalogue::read(&dir)
        .with_context(|| format!("reading the furniture at {}", dir.display()))?;
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/vae_gated.safetensors");
    let file = args.vae.clone().unwrap_or(shipped);
    let vae = Cvae::load(&file).with_context(|| format!("loading the VAE {}", file.display()))?;
    match args.one {
        Some(seed) => one(&args, &vae, &catalogue, seed),
        None => table(&args, &vae, &catalogue),
    }
}
