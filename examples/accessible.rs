//! Where people can be in a room: VAE samples of torso locations, the filter, the voxels of the
//! accessible region, the exact 3D field over it and the learned one, to files a person opens.
//!
//! ```text
//! cargo run --release --example accessible                         # one held-out room, out/accessible
//! cargo run --release --example accessible -- --scene room.obj     # a scene of your own
//! cargo run --release --example accessible -- --rooms 20 --json    # the figures on 20 held-out rooms
//! ```
//!
//! Writes `scene.obj`, `samples.ply` (kept samples), `region.ply` (accessible voxels coloured
//! by height), `region.png` (top-down, coloured by the highest accessible height),
//! `field_exact.png` and `field_learned.png` (top-down, the field at each column's highest
//! accessible voxel, for one goal) and `summary.json`. `--rooms N` evaluates N generated
//! rooms of seeds 10000.. (training used 0..200) against two controls, an untrained VAE and
//! uniform samples in the room's box; its last line is one JSON object. The default VAE is the
//! gated one (`models/vae_gated.safetensors`); `--vae models/vae.safetensors` is the paper's.

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::affordance::afford_all;
use envfield::rooms::pictures::write_field_view;
use envfield::rooms::quality::{judge_region, summarise_drawn, uniform_in_room, HeldOut};
use envfield::rooms::sampling::middle_goal;
use envfield::rooms::{
    draw_torsos, train_field3, AccessibleRegion, ExactField3, Field3Config, LearnedField3,
    RegionConfig,
};
use envfield::scene::{RoomConfig, Scene};
use envfield::vae::{Cvae, Gate, SampleOptions};
use envfield_examples::{MotionArgs, SceneArgs};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "The accessible region of a room and the 3D fields over it")]
struct Args {
    #[command(flatten)]
    scene: SceneArgs,
    /// Seed of the generated room (10000 and up were never trained on).
    #[arg(long, default_value_t = 10_000)]
    seed: u64,
    /// The VAE's weights (default: the shipped gated VAE, `models/vae_gated.safetensors`).
    #[arg(long)]
    vae: Option<PathBuf>,
    /// Torso samples drawn per room.
    #[arg(long, default_value_t = 6000)]
    samples: usize,
    /// Output folder.
    #[arg(long, default_value = "out/accessible")]
    out: PathBuf,
    /// Evaluate this many held-out generated rooms instead of drawing one.
    #[arg(long)]
    rooms: Option<u64>,
    /// Train and measure the learned field on the first this many rooms of --rooms.
    #[arg(long, default_value_t = 5)]
    field_rooms: u64,
    /// Training steps of each learned field.
    #[arg(long, default_value_t = 3000)]
    field_steps: u64,
    /// Fourier frequencies of the learned field's input encoding (default: `Field3Config`'s).
    #[arg(long)]
    field_fourier: Option<usize>,
    /// Hidden width of the learned field's network (default: `Field3Config`'s).
    #[arg(long)]
    field_hidden: Option<usize>,
    /// Radius of the torso sphere the filter keeps clear of geometry, metres.
    #[arg(long)]
    torso_radius: Option<f32>,
    /// Turn the filter's plausibility rule off (bones through tables, legs hanging off
    /// table tops pass; no settling): the ablation.
    #[arg(long)]
    no_plausible: bool,
    /// How far a sample may settle to sit, metres (default: `RegionConfig`'s 0.2).
    #[arg(long)]
    settle: Option<f32>,
    /// Skip the learned field.
    #[arg(long)]
    no_field: bool,
    /// The VAE's sampling temperature (the codes' standard deviation; 1 is the prior).
    #[arg(long, default_value_t = 1.0)]
    temperature: f32,
    /// Draw a local VAE's anchors from this (whole-scene) VAE's samples, each moved by the
    /// local VAE's training jitter, instead of uniformly over the room.
    #[arg(long)]
    anchors_from: Option<PathBuf>,
    /// Sample a gated VAE's anchors uniformly, without its occupancy gate (the ablation).
    #[arg(long)]
    no_gate: bool,
    /// A gated VAE's occupancy threshold (default: the one it was trained with).
    #[arg(long)]
    gate_threshold: Option<f32>,
    /// Print the summary as one JSON line (always the last line with --rooms).
    #[arg(long)]
    json: bool,
    /// The scene (and, on the page, its region) out for a viewer: `--gltf` writes the scene
    /// alone, y up, a glTF file any tool reads back as the same scene.
    #[command(flatten)]
    motion: MotionArgs,
}

/// What the rooms are, for the summary.
fn furniture(args: &Args) -> &'static str {
    if args.scene.catalogue {
        "real-furniture room"
    } else {
        "generated room"
    }
}

fn region_config(args: &Args) -> RegionConfig {
    let mut config = RegionConfig::default();
    config.filter.torso_radius = args.torso_radius.unwrap_or(config.filter.torso_radius);
    config.filter.settle = args.settle.unwrap_or(config.filter.settle);
    if args.no_plausible {
        (config.filter.plausible, config.filter.settle) = (false, 0.0);
    }
    config
}

/// The learned field's training config: `Field3Config`'s defaults under the `--field-*` flags.
fn field_config(args: &Args, seed: u64) -> Field3Config {
    let mut c = Field3Config::default();
    (c.steps, c.seed) = (args.field_steps, seed);
    c.mlp.fourier = args.field_fourier.unwrap_or(c.mlp.fourier);
    c.mlp.hidden = args.field_hidden.unwrap_or(c.mlp.hidden);
    c
}

/// `args.samples` torsos of `vae` (next to `anchors`' samples with `--anchors-from`).
fn draw(
    args: &Args,
    vae: &Cvae,
    anchors: Option<&Cvae>,
    scene: &Scene,
    seed: u64,
    gate_off: bool,
) -> Result<Vec<[f32; 3]>> {
    let gate = match args.gate_threshold {
        _ if args.no_gate || gate_off => Gate::Off,
        Some(t) => Gate::Threshold(t),
        None => Gate::Trained,
    };
    let options = SampleOptions::new(args.samples, seed)
        .with_temperature(args.temperature)
        .with_gate(gate);
    Ok(draw_torsos(vae, scene, &options, anchors)?)
}

fn progress(len: u64, what: &str) -> Result<ProgressBar> {
    let style = "{msg:>24} {bar:30} {pos}/{len} {elapsed_precise} (eta {eta})";
    let bar = ProgressBar::new(len).with_message(what.to_string());
    Ok(bar.with_style(ProgressStyle::with_template(style)?))
}

fn one(args: &Args, vae: &Cvae) -> Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    args.scene.protect();
    envfield::grid::check_writable(args.out.join("summary.json"))?;
    envfield::grid::check_writable(args.out.join("scene.obj")).with_context(|| {
        format!(
            "--out {}: the scene is written there as scene.obj",
            args.out.display()
        )
    })?;
    let inputs: Vec<&std::path::Path> = args.scene.scene.iter().map(PathBuf::as_path).collect();
    args.motion.check(&inputs)?;
    let rooms = args.scene.rooms(RoomConfig::default())?;
    let (scene, room) = args.scene.scene(&rooms, args.seed, Some(args.samples))?;
    scene.to_mesh().write(args.out.join("scene.obj"))?;
    let t = Instant::now();
    let anchors = anchor_vae(args)?;
    let samples = draw(args, vae, anchors.as_ref(), &scene, args.seed, false)?;
    let sample_ms = t.elapsed().as_secs_f64() * 1e3;
    let config = region_config(args);
    let t = Instant::now();
    // The filter once: the region, its quality and the summary all read its answers.
    let affords = afford_all(&scene, &samples, &config.filter)?;
    let filter_ms = t.elapsed().as_secs_f64() * 1e3;
    let kept = affords.iter().filter(|a| a.kept()).map(|a| a.at).collect();
    let mut region = AccessibleRegion::from_kept(&scene, kept, &config)?;
    region.times.filter_ms = filter_ms;
    let region_ms = t.elapsed().as_secs_f64() * 1e3;
    let left_out = region.left_out_warning();
    if let Some(w) = &left_out {
        eprintln!("warning: {w}");
    }
    region.write_files(&args.out)?;
    if args.motion.any() {
        let points: Vec<_> = region.voxel_centres().iter().map(|&p| p.into()).collect();
        let title = format!("{} {}", furniture(args), args.seed);
        for f in args
            .motion
            .write(&scene.to_mesh(), &points, &[], &title, true)?
        {
            eprintln!("wrote {}", f.display());
        }
    }
    let goal = middle_goal(&region);
    let exact = ExactField3::new(&region, goal)?;
    write_field_view(&region, &exact, args.out.join("field_exact.png"))?;
    let quality = room
        .as_ref()
        .map(|r| judge_region(r, &affords, Some(&region)));
    let quality = quality.transpose()?;
    let learned = if args.no_field {
        None
    } else {
        let bar = progress(args.field_steps, "learned 3D field")?;
        let cfg = field_config(args, 0);
        let (net, report) = train_field3(&region, &cfg, None, |s, _, _| bar.set_position(s))?;
        bar.finish_and_clear();
        let field = LearnedField3::new(&net, &region, exact.goal())?;
        write_field_view(&region, &field, args.out.join("field_learned.png"))?;
        Some(report)
    };
    let drawn = summarise_drawn(&samples, &affords);
    let summary = serde_json::json!({
        "affords_clear_supported_valid": drawn["affords_clear_supported_valid"],
        "drawn_by_height_m": drawn["drawn_by_height_m"],
        "scene": args.scene.scene.as_ref().map(|p| p.display().to_string()).unwrap_or(format!("{} {}", furniture(args), args.seed)),
        "samples": samples.len(),
        "kept": region.samples.len(),
        "accessible_voxels": region.grid.free_count(),
        "components_before_largest": region.components,
        "left_out": left_out,
        "voxel_m": region.frame.voxel,
        "goal": goal,
        "quality": quality,
        "learned_field": learned,
        "sample_ms": sample_ms,
        "filter_and_voxels_ms": region_ms,
        "region_split_ms": region.times,
        "out": args.out,
    });
    envfield::grid::write_atomic(
        args.out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    let text = serde_json::to_string_pretty(&summary)?;
    println!("{}", if args.json { summary.to_string() } else { text });
    Ok(())
}

fn many(args: &Args, vae: &Cvae, rooms: u64) -> Result<()> {
    let config = region_config(args);
    let untrained = Cvae::new(vae.config().clone(), 1)?;
    let anchors = anchor_vae(args)?;
    let mut held_out = HeldOut::default();
    let bar = progress(rooms, "held-out rooms")?;
    let makes = args.scene.rooms(RoomConfig::default())?;
    for k in 0..rooms {
        let seed = 10_000 + k;
        let room = makes.room(seed)?;
        let drawn = draw(args, vae, anchors.as_ref(), &room.scene, seed, false)?;
        // An untrained gate may pass no anchor at all: the twin decodes every one.
        let twin = draw(args, &untrained, anchors.as_ref(), &room.scene, seed, true)?;
        let uniform = uniform_in_room(&room, 2.5, args.samples, seed);
        let region = held_out.add(&room, &drawn, &twin, &uniform, &config)?;
        if !args.no_field && k < args.field_rooms {
            let region = region.with_context(|| format!("room {seed}: no sample kept"))?;
            let cfg = field_config(args, seed);
            let (_, report) = train_field3(&region, &cfg, None, |_, _, _| {})?;
            eprintln!("room {seed}: learned field {report:?}");
            held_out.add_field(report);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let mut line = held_out.summary_json(10_000);
    line["rooms"] = rooms.into();
    line["furniture"] = furniture(args).into();
    line["samples_per_room"] = args.samples.into();
    if !args.json {
        eprintln!("{}", serde_json::to_string_pretty(&line)?);
    }
    println!("{line}");
    Ok(())
}

/// The VAE of `--anchors-from`, if any.
fn anchor_vae(args: &Args) -> Result<Option<Cvae>> {
    let load = |f: &PathBuf| Cvae::load(f).with_context(|| format!("loading {}", f.display()));
    args.anchors_from.as_ref().map(load).transpose()
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.samples == 0 || args.samples > 1_000_000 {
        bail!("--samples must be in 1..=1000000 (got {})", args.samples);
    }
    // Flags that would be ignored are refused, not dropped in silence.
    if args.rooms.is_some() && args.scene.scene.is_some() {
        bail!("--rooms evaluates generated rooms and would never read --scene: give one of them");
    }
    if args.rooms.is_some() && args.motion.any() {
        bail!("--gltf, --bvh and --html write one scene: not with --rooms");
    }
    if !args.no_field && !(1..=10_000_000).contains(&args.field_steps) {
        bail!(
            "--field-steps must be in 1..=10000000 (got {}): an untrained field is no field \
             (--no-field leaves it out)",
            args.field_steps
        );
    }
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/vae_gated.safetensors");
    let file = args.vae.clone().unwrap_or(shipped);
    let vae = Cvae::load(&file).with_context(|| {
        format!(
            "loading the VAE {} (train one with the command in models/README.md)",
            file.display()
        )
    })?;
    match args.rooms {
        Some(0) => bail!("--rooms 0 evaluates nothing"),
        Some(n) if n > 10_000 => bail!("--rooms {n}: at most 10000"),
        Some(n) => many(&args, &vae, n),
        None => one(&args, &vae),
    }
}
