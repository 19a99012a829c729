//! Several people sitting down together in 3D: in each apartment (2-4 rooms furnished with
//! the evaluation half of the contributed models, never trained or tuned on), N people walk in
//! from different rooms and each sits on a different chair of the dining table
//! ([`plan_party`]: ours on the exact field to the region's sit-down of each chair, then the
//! sit-down; guests placed one after another, each waiting at its start until its motion meets
//! no body already placed). Every pose is checked against the scene (supported and
//! collision-free) and every pair of people at every frame (bones as capsules).
//!
//! The table is laid first: its chairs, tucked under it, pulled out ([`lay_table`]; `--as-found`
//! leaves them).
//!
//! `cargo run --release --example party -- --apartments 20 --seed 31000 --json` prints one
//! JSON line per apartment and a summary: guests seated, body overlaps, valid poses, the
//! seconds per party (and per region). `--gltf party.glb` / `--html party.html` write the
//! first apartment's party for a viewer.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::affordance::Actor;
use envfield::rooms::party::{dining_chairs, lay_table, plan_party, PartyConfig};
use envfield::rooms::sample_region;
use envfield::scene::RoomConfig;
use envfield::vae::Cvae;
use envfield_examples::{MotionArgs, SceneArgs};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "People walking in from different rooms to sit at one dining table")]
struct Args {
    /// Parties to run: apartments from --seed on whose dining table has a chair for every
    /// person (the others, without a kitchen table or with fewer chairs, are counted apart).
    #[arg(long, default_value_t = 1)]
    apartments: u64,
    /// Seed of the first apartment.
    #[arg(long, default_value_t = 31000)]
    seed: u64,
    /// People at the table, each on a different chair.
    #[arg(long, default_value_t = 4)]
    people: usize,
    /// People walking through meanwhile (half from the party's room to another, half between
    /// other rooms); the guests wait for them too.
    #[arg(long, default_value_t = 0)]
    passers: usize,
    /// Torso samples drawn for each apartment's accessible region.
    #[arg(long, default_value_t = 15000)]
    samples: usize,
    /// The VAE's weights (default: the shipped gated VAE).
    #[arg(long)]
    vae: Option<PathBuf>,
    /// Leave the table's chairs where the apartment has them (tucked 5-15 cm under it), rather
    /// than pulling them out before the party ([`lay_table`]).
    #[arg(long)]
    as_found: bool,
    /// Print JSON lines only.
    #[arg(long)]
    json: bool,
    /// The first apartment's party out for a viewer.
    #[command(flatten)]
    motion: MotionArgs,
}

fn main() -> Result<()> {
    let args = Args::parse();
    if !(1..=1000).contains(&args.apartments)
        || !(1..=8).contains(&args.people)
        || args.passers > 8
        || !(1..=1_000_000).contains(&args.samples)
        || args.seed.checked_add(args.apartments).is_none()
    {
        bail!(
            "--apartments must be in 1..=1000, --people in 1..=8, --passers in 0..=8, \
             --samples in 1..=1000000 and --seed + --apartments fit in 64 bits"
        );
    }
    args.motion.check(&[])?;
    let vae_file = args.vae.clone().unwrap_or_else(|| {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("models/vae_gated.safetensors")
    });
    let vae =
        Cvae::load(&vae_file).with_context(|| format!("loading the VAE {}", vae_file.display()))?;
    let scene_args = SceneArgs {
        scene: None,
        up: None,
        units: None,
        catalogue: false,
        apartment: true,
    };
    let maker = scene_args.rooms(RoomConfig::default())?;
    let (mut asked, mut seated, mut overlaps, mut valid, mut frames) = (0, 0, 0, 0.0, 0usize);
    let mut through = 0;
    let (mut party_s, mut region_s, mut failed) = (Vec::new(), Vec::new(), Vec::new());
    let (mut run, mut skipped, mut seed) = (0u64, Vec::new(), args.seed);
    while run < args.apartments {
        if seed - args.seed >= 20 * args.apartments {
            bail!(
                "{} apartments from seed {} have no dining table with {} chairs",
                skipped.len(),
                args.seed,
                args.people
            );
        }
        let (found, rooms) = maker.room_and_rooms(seed)?;
        seed += 1;
        let chairs = dining_chairs(&found);
        if chairs.len() < args.people {
            skipped.push(seed - 1);
            continue;
        }
        let (home, pulled) = if args.as_found {
            (found, vec![0.0; chairs.len()])
        } else {
            lay_table(&found, &chairs)?
        };
        let (k, seed) = (run, seed - 1);
        run += 1;
        let t = Instant::now();
        let region = sample_region(&vae, &home.scene, args.samples, seed)?;
        region_s.push(t.elapsed().as_secs_f64());
        let config = PartyConfig {
            people: args.people,
            passers: args.passers,
            seed,
            ..PartyConfig::default()
        };
        let party = match plan_party(&home.scene, &region, &home, &rooms, &config) {
            Ok(p) => p,
            Err(e) => {
                // No party here: all its guests count as not seated.
                asked += args.people;
                failed.push(seed);
                let line = serde_json::json!({"apartment": seed, "error": e.to_string()});
                println!("{line}");
                continue;
            }
        };
        asked += args.people;
        let sat = party.guests.iter().filter(|g| g.seated).count();
        seated += sat;
        overlaps += party.overlaps;
        through += party.passers.len();
        for g in &party.guests {
            valid += g.valid_pct * g.motion.frames.len() as f64 / 100.0;
            frames += g.motion.frames.len();
        }
        party_s.push(party.seconds);
        let line = serde_json::json!({
            "apartment": seed,
            "rooms": rooms.len(),
            "chairs_pulled_m": pulled,
            "seats_reached": party.chairs,
            "at": party.at,
            "seated": sat,
            "people": args.people,
            "body_overlaps": party.overlaps,
            "passers": args.passers,
            "passers_through": party.passers.len(),
            "valid_pct": party.guests.iter().map(|g| g.valid_pct).collect::<Vec<_>>(),
            "waits_frames": party.guests.iter().map(|g| g.wait).collect::<Vec<_>>(),
            "frames": party.frames,
            "party_s": party.seconds,
            "region_s": region_s.last(),
        });
        println!("{line}");
        if k == 0 && args.motion.any() {
            let timelines = party.timelines()?;
            let guests = party.guests.len();
            let names: Vec<String> = (0..timelines.len())
                .map(|i| match i < guests {
                    true => format!("guest_{i}"),
                    false => format!("passer_{}", i - guests),
                })
                .collect();
            let actors: Vec<Actor> = names
                .iter()
                .zip(&timelines)
                .map(|(name, poses)| Actor { name, poses })
                .collect();
            let points: Vec<_> = region.voxel_centres().iter().map(|&p| p.into()).collect();
            let title = format!("a party of {} in apartment {seed}", timelines.len());
            for f in args
                .motion
                .write(&home.scene.to_mesh(), &points, &actors, &title, true)?
            {
                eprintln!("wrote {}", f.display());
            }
        }
    }
    let mean = |v: &[f64]| {
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let summary = serde_json::json!({
        "apartments": args.apartments,
        "people": args.people,
        "seated_pct": 100.0 * seated as f64 / asked.max(1) as f64,
        "body_overlaps": overlaps,
        "passers_through": through,
        "valid_pct": 100.0 * valid / frames.max(1) as f64,
        "party_s_mean": mean(&party_s),
        "region_s_mean": mean(&region_s),
        "no_party": failed,
        "no_table": skipped,
    });
    if !args.json {
        eprintln!(
            "{seated} of {asked} seated, {overlaps} body overlaps, {:.1}% valid poses, {:.1} s \
             per party (+ {:.0} s per region)",
            100.0 * valid / frames.max(1) as f64,
            mean(&party_s),
            mean(&region_s)
        );
    }
    println!("{summary}");
    Ok(())
}
