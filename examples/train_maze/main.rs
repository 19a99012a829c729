//! Trains an environment-field network on generated mazes, checkpointing as it goes, and
//! reports the validation loss and the navigation success on held-out generated mazes.
//!
//! ```text
//! cargo run --release --example train_maze -- --arch context --size 28 --steps 20000 --out models/context_28.safetensors
//! cargo run --release --example train_maze -- --resume models/context_28.safetensors.ckpt --steps 30000 --out models/context_28.safetensors
//! cargo run --release --example train_maze -- --arch plain --size 8 --steps 2000 --lr 1e-3
//! ```
//!
//! `--size 8,16,28` trains one model on all three sizes (one dataset per size, taken in turn).

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::nets::{
    resume_on, Arch, ContextOptions, FieldNet, LossShaping, MazeRecipe, PathConfig,
    PropagationConfig, TrainConfig, Trainer,
};
use envfield::plan::{evaluate, EvalConfig, FieldDescent};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

mod args;
use args::Args;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> Result<()> {
    let args = Args::parse();
    let (kind, target, encoding) = (args.generator, args.target, args.encoding);
    let sizes = MazeRecipe::parse_sizes(&args.size).context("--size")?;
    let rule = target.rule();
    let single = args.arch.learns_one_scene();
    // The data flags, recorded in every checkpoint: a resumed run must be given the same ones,
    // checked before the datasets are generated.
    let recipe = MazeRecipe {
        arch: args.arch,
        generator: kind,
        sizes: sizes.clone(),
        mazes: args.mazes,
        goals_per_maze: args.goals_per_maze,
        target,
        seed: args.seed,
    };
    recipe
        .validate()
        .context("--arch, --size, --mazes or --goals-per-maze")?;
    if args.resume.is_none() && (args.steps == 0 || args.stop_at == Some(0)) {
        bail!(
            "--steps 0 or --stop-at 0 trains nothing: a fresh run takes at least one step \
             ({} is left as it is)",
            args.out.display()
        );
    }
    // The outputs are checked before the data is made and the network trained.
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let ckpt = PathBuf::from(format!("{}.ckpt", args.out.display()));
    envfield::grid::check_writable(&args.out)?;
    envfield::grid::check_writable(&ckpt)?;
    let data = recipe.describe();
    if args.new_data && args.resume.is_none() {
        bail!("--new-data changes the data of a resumed run: give --resume too");
    }
    let resumed = match &args.resume {
        Some(path) => {
            let (t, note) = resume_on(path, &data, args.new_data).with_context(|| {
                format!(
                    "{}: pass the data flags of the run it continues, or --new-data to change \
                     them on purpose",
                    path.display()
                )
            })?;
            if let Some(note) = note {
                eprintln!("{note}");
            }
            // The data differ by architecture (one maze for plain and goal fields), so a
            // checkpoint of another one than --arch would be trained on the wrong data.
            let theirs = t.net().config().arch();
            if theirs != args.arch.name() {
                bail!(
                    "{} is a {theirs} network, but --arch is {}: pass --arch {theirs} to continue \
                     it ({} is left as it is)",
                    path.display(),
                    args.arch,
                    args.out.display()
                );
            }
            eprintln!("resumed {} at step {}", path.display(), t.step());
            let stop = args.stop_at.map_or(args.steps, |s| s.min(args.steps));
            if stop <= t.step() {
                bail!(
                    "--steps {} trains nothing: {} is at step {} already ({} is left as it is)",
                    stop,
                    path.display(),
                    t.step(),
                    args.out.display()
                );
            }
            Some(t)
        }
        None => None,
    };
    // Training data: mazes 0..mazes of the seed; the held-out mazes use another seed.
    let (datasets, validation) = recipe.datasets()?;
    let first = datasets
        .first()
        .and_then(|d| d.samples.first())
        .context("the training data came out empty")?;
    let shaping = LossShaping {
        neighbour_weight: args.neighbour_weight,
        detour_fraction: args.detour_fraction,
        far_fraction: args.far_fraction,
        hard_fraction: args.hard_fraction,
        descent: args.descent_weight.map(|w| (w, args.descent_margin, rule)),
        dense: args.dense,
        ema_decay: args.ema,
    };
    let mut trainer = match resumed {
        // The checkpoint's config, with the flags that apply to a resumed run.
        Some(mut t) => {
            let c = shaping.apply(TrainConfig {
                steps: args.steps,
                ..t.config().clone()
            });
            t.set_config(c)?;
            t
        }
        None => {
            let (w, l) = args.mlp.split_once(':').context("--mlp WIDTH:LAYERS")?;
            let context = ContextOptions {
                residual: args.residual,
                encoder: args.encoder.clone(),
                path: args.path.then_some(PathConfig {
                    min_cost: args.min_cost,
                    rule,
                }),
                propagation: (args.propagation > 0).then_some(PropagationConfig {
                    q_channels: args.propagation,
                    iterations_per_cell: args.propagation_iterations,
                }),
                mlp: Some((
                    w.parse()
                        .with_context(|| format!("bad --mlp width `{w}`"))?,
                    l.parse()
                        .with_context(|| format!("bad --mlp layers `{l}`"))?,
                )),
            };
            let (rows, cols) = (first.grid.rows(), first.grid.cols());
            let goal = [first.goal.row, first.goal.col];
            let model = context.apply(args.arch.preset(rows, cols, goal, encoding))?;
            let train = shaping.apply(TrainConfig {
                lr: args.lr,
                final_lr_fraction: args.final_lr,
                batch_items: if single { 1 } else { args.batch },
                queries_per_item: match args.arch {
                    Arch::Plain => first.grid.len(),
                    _ => args.queries,
                },
                steps: args.steps,
                seed: args.seed,
                checkpoint_every: args.every,
                validate_every: args.every,
                validation_samples: 64,
                neighbour_weight: 0.0,
                detour_fraction: 0.0,
                far_fraction: 0.0,
                hard_fraction: 0.0,
                descent_weight: 0.0,
                descent_margin: args.descent_margin,
                descent_rule: rule,
                dense: false,
                ema_decay: 0.0,
                ..TrainConfig::default()
            });
            let mut t = Trainer::new(FieldNet::new(model, args.seed)?, train)?;
            t.continue_with_data(data, false)?;
            t
        }
    };
    let (net, samples) = (trainer.net(), datasets[0].samples.len());
    let (arch, params) = (net.config().arch(), net.parameter_count());
    eprintln!("{arch} network, {params} parameters, sizes {sizes:?}, {samples} samples per size");
    let bar = ProgressBar::new(trainer.config().steps);
    bar.set_style(ProgressStyle::with_template(
        "{bar:30} {pos}/{len} steps {elapsed_precise} (eta {eta}) {msg}",
    )?);
    bar.set_position(trainer.step());
    let val_for_training = (sizes.len() == 1).then(|| &validation[0]);
    let mut last_val = None;
    // A run resumed at or past --stop-at only writes the weights out (no extra step).
    let stopped = args.stop_at.is_some_and(|stop| trainer.step() >= stop);
    let summary = (!stopped)
        .then(|| {
            trainer.run(&datasets, val_for_training, Some(&ckpt), |p| {
                bar.set_position(p.step);
                last_val = p.validation.or(last_val);
                let val = last_val.map_or("-".into(), |v| format!("{v:.4}"));
                let status = format!(
                    "loss {:.4} val {val} {:.2} steps/s",
                    p.loss, p.steps_per_second
                );
                if bar.is_hidden() && (p.validation.is_some() || p.checkpointed) {
                    let at = format!("step {}/{}", p.step, p.steps);
                    eprintln!("{at} {status} {:.0} s", p.elapsed.as_secs_f64());
                }
                bar.set_message(status);
                args.stop_at.is_none_or(|stop| p.step < stop)
            })
        })
        .transpose()?;
    bar.finish();
    // The moving average of the weights when one is kept.
    let net = trainer.averaged_net()?;
    net.save(&args.out)?;
    match summary.is_some() {
        true => eprintln!(
            "saved {} (checkpoint {})",
            args.out.display(),
            ckpt.display()
        ),
        false => eprintln!(
            "saved {} (no step taken, no checkpoint written)",
            args.out.display()
        ),
    }
    if let Some(summary) = summary {
        println!("{}", serde_json::to_string(&summary)?);
    }
    // Navigation on held-out mazes (for plain/goal, the training maze itself).
    for (k, &size) in sizes.iter().enumerate() {
        let val_loss = envfield::nets::validation_loss(&net, &validation[k], 256)?;
        let mazes = recipe.check_mazes(size, args.eval_mazes, first)?;
        let planner = FieldDescent::new(&net, rule);
        let eval = EvalConfig {
            rule,
            pairs_per_maze: if single { 64 } else { 1 },
            seed: 7,
        };
        let report = evaluate(&planner, &mazes, &eval, &mut |_, _| {})?;
        // No pair (--eval-mazes 0) has no success rate; a ratio without a success is null.
        let (s, any) = (&report.summary, report.summary.pairs > 0);
        let ratio = s.path_ratio.is_finite().then_some(s.path_ratio);
        println!(
            "{}",
            serde_json::json!({"size": size, "validation_l1": val_loss,
                "success_rate": any.then_some(s.success_rate), "path_ratio": ratio,
                "pairs": s.pairs, "ms_per_path": any.then_some(s.ms_per_path)})
        );
    }
    Ok(())
}
