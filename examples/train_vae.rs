//! Trains the conditional VAE of torso locations on generated rooms, one VAE for all rooms
//! (paper section 4.2), checkpointing as it goes.
//!
//! ```text
//! cargo run --release --example train_vae -- --rooms 200 --steps 4000 --out models/vae.safetensors
//! cargo run --release --example train_vae -- --resume models/vae.safetensors.ckpt --steps 6000 --out models/vae.safetensors
//! ```
//!
//! Training rooms are the generated rooms of seeds `0..rooms`; `accessible` evaluates on seeds
//! from 10000 on, which training never sees.

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::rooms::torsos::{rooms_torsos, TorsoDataConfig};
use envfield::vae::{Cvae, TorsoSource, VaeConfig, VaeTrainConfig, VaeTrainer};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::time::Instant;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "Train the VAE of torso locations on generated rooms")]
struct Args {
    /// Training rooms (seeds 0..ROOMS).
    #[arg(long, default_value_t = 200)]
    rooms: u64,
    /// Total optimiser steps (a resumed run trains up to this many).
    #[arg(long, default_value_t = 4000)]
    steps: u64,
    /// Adam's learning rate (the paper: 5e-5).
    #[arg(long, default_value_t = 5e-5)]
    lr: f64,
    /// The KL weight at the top of each annealing cycle.
    #[arg(long, default_value_t = 1.0)]
    kl_max: f64,
    /// The reconstruction's standard deviation, metres.
    #[arg(long, default_value_t = 0.1)]
    recon_sigma: f32,
    /// Cycles of the KL annealing.
    #[arg(long, default_value_t = 4)]
    cycles: usize,
    /// Rooms per step.
    #[arg(long, default_value_t = 16)]
    scenes: usize,
    /// Torso locations per room per step.
    #[arg(long, default_value_t = 64)]
    torsos: usize,
    /// How often each kind of torso location is drawn, as WALK,SIT,LIE,STAND weights.
    #[arg(long, default_value = "1,1,1,1")]
    source_weights: String,
    /// Seed of the weights and batches.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Where the weights go (the checkpoint goes to OUT.ckpt).
    #[arg(long, default_value = "out/vae.safetensors")]
    out: PathBuf,
    /// Resume from this checkpoint (its configs win over the flags, except --steps).
    #[arg(long)]
    resume: Option<PathBuf>,
    /// Checkpoint every N steps.
    #[arg(long, default_value_t = 500)]
    every: u64,
    /// The local VAE (`VaeConfig::local`): conditioned on the surface points near an anchor
    /// instead of the whole room, and sampled at anchors all over the room.
    #[arg(long)]
    local: bool,
    /// The gated local VAE (`VaeConfig::local_gated`): anchors 0.05 m around their torso, an
    /// occupancy gate on the sampling anchors and pose kinds. Implies --local and
    /// --affordable-only.
    #[arg(long)]
    gated: bool,
    /// Spacing of the floor grid of standing poses in the training data, metres (the gated
    /// VAE's occupancy labels want it no coarser than twice the gate's radius).
    #[arg(long, default_value_t = 0.2)]
    floor_spacing: f32,
    /// Train only on the torso locations where the accessible region's filter finds a full
    /// pose (`TorsoDataConfig::affordable_only`): no frames from the middle of sitting down.
    #[arg(long)]
    affordable_only: bool,
    /// Add every place on a grid over the chairs, sofas and beds where the region's filter
    /// finds a sitting or lying pose (`TorsoDataConfig::seat_grid`).
    #[arg(long)]
    seat_grid: bool,
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.rooms == 0 || args.rooms > 100_000 {
        bail!("--rooms must be in 1..=100000 (got {})", args.rooms);
    }
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let ckpt = PathBuf::from(format!("{}.ckpt", args.out.display()));
    envfield::grid::check_writable(&args.out)?;
    envfield::grid::check_writable(&ckpt)?;
    // A run that would take no step writes no weights: a user's trained file stays as it is.
    if args.resume.is_none() && args.steps == 0 {
        bail!(
            "--steps 0 trains nothing: a fresh run takes at least one step ({} is left as it is)",
            args.out.display()
        );
    }
    let mut trainer = match &args.resume {
        Some(p) => {
            let mut t = VaeTrainer::resume(p)
                .with_context(|| format!("--resume {}: no checkpoint to resume", p.display()))?;
            eprintln!("resumed {} at step {}", p.display(), t.step());
            if args.steps <= t.step() {
                bail!(
                    "--steps {} trains nothing: {} is at step {} already ({} is left as it is)",
                    args.steps,
                    p.display(),
                    t.step(),
                    args.out.display()
                );
            }
            t.set_steps(args.steps);
            t
        }
        None => {
            let w: Vec<f32> = args
                .source_weights
                .split(',')
                .map(|x| x.trim().parse::<f32>())
                .collect::<std::result::Result<_, _>>()
                .with_context(|| format!("bad --source-weights `{}`", args.source_weights))?;
            let source_weights: [f32; 4] = w
                .try_into()
                .map_err(|_| anyhow::anyhow!("--source-weights takes four numbers"))?;
            let config = VaeTrainConfig {
                source_weights,
                kl_max: args.kl_max,
                recon_sigma: args.recon_sigma,
                lr: args.lr,
                steps: args.steps,
                scenes_per_step: args.scenes,
                torsos_per_scene: args.torsos,
                cycles: args.cycles,
                seed: args.seed,
                checkpoint_every: args.every,
            };
            let vae = match (args.gated, args.local) {
                (true, _) => VaeConfig::local_gated(),
                (false, true) => VaeConfig::local(),
                (false, false) => VaeConfig::default(),
            };
            VaeTrainer::new(Cvae::new(vae, args.seed)?, config)?
        }
    };
    let t = Instant::now();
    // A local VAE reads neighbourhoods, so its rooms' clouds are denser.
    let data_config = TorsoDataConfig {
        cloud_points: trainer
            .vae()
            .cloud_points()
            .max(TorsoDataConfig::default().cloud_points),
        floor_spacing: args.floor_spacing,
        affordable_only: args.affordable_only || trainer.vae().has_kinds(),
        seat_grid: args.seat_grid,
        ..TorsoDataConfig::default()
    };
    let rooms = rooms_torsos(0..args.rooms, &data_config)?;
    let data: Vec<_> = rooms.into_iter().map(|(_, d)| d).collect();
    let count = |s: TorsoSource| {
        data.iter()
            .flat_map(|d| &d.sources)
            .filter(|&&x| x == s)
            .count()
    };
    let data_s = t.elapsed().as_secs_f64();
    eprintln!(
        "{} rooms, {} torso locations (walk {}, sit {}, lie {}, stand {}) in {data_s:.1} s; {} parameters",
        data.len(),
        data.iter().map(|d| d.torsos.len()).sum::<usize>(),
        count(TorsoSource::Walk),
        count(TorsoSource::Sit),
        count(TorsoSource::Lie),
        count(TorsoSource::Stand),
        trainer.vae().parameter_count()
    );
    let bar = ProgressBar::new(trainer.config().steps);
    bar.set_style(ProgressStyle::with_template(
        "{bar:30} {pos}/{len} steps {elapsed_precise} (eta {eta}) {msg}",
    )?);
    bar.set_position(trainer.step());
    let last = trainer.run(&data, Some(&ckpt), |p| {
        bar.set_position(p.step);
        bar.set_message(format!(
            "recon {:.3} kl {:.3} (weight {:.2}) gate {:.3} kind {:.3}",
            p.recon, p.kl, p.kl_weight, p.gate, p.kind
        ));
        if bar.is_hidden() && (p.checkpointed || p.step % 100 == 0) {
            eprintln!(
                "step {}/{} loss {:.4} recon {:.4} kl {:.4} weight {:.2} gate {:.4} kind {:.4} {:.0} s",
                p.step, p.steps, p.loss, p.recon, p.kl, p.kl_weight, p.gate, p.kind, p.seconds
            );
        }
        true
    })?;
    bar.finish();
    trainer.vae().save(&args.out)?;
    eprintln!(
        "saved {} (checkpoint {})",
        args.out.display(),
        ckpt.display()
    );
    println!(
        "{}",
        serde_json::json!({
            "rooms": data.len(),
            "data_s": data_s,
            "step": trainer.step(),
            "last": last,
            "parameters": trainer.vae().parameter_count(),
        })
    );
    Ok(())
}
