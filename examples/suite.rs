//! The whole maze table in one command: every layout family at every size, mazes without a
//! border and non-square ones, real Minigrid layouts and VIN's test sets, each with the
//! shipped field beside its controls.
//!
//! ```text
//! cargo run --release --example suite                        # the table (markdown), a few minutes
//! cargo run --release --example suite -- --json suite.json   # and every figure as JSON
//! cargo run --release --example suite -- --only perfect,minigrid --no-vin
//! ```
//!
//! Columns, each `success % / path ratio / ms per path` (`docs/evaluation.md`):
//! - `field`: the shipped field (`models/context.safetensors`), plain descent;
//! - `relay`: the same field, a failing descent planned again through a relay cell;
//! - `untrained`: the same network with fresh random weights: what the structure gives
//!   without learning;
//! - `octile`: the straight-line distance, blind to walls;
//! - `exact`: descent on the exact graph distance (the oracle);
//! - `vin`: the VIN baseline where a VIN of the maze's side was trained (8, 16, 28), and on
//!   every side of VIN's own benchmark (the `vin`-rule sets) with the nearest trained side's
//!   network and K set for the maze's side.
//!
//! Generated families are walked under the `strict` rule, except VIN-style gridworlds and
//! VIN's test sets (the `vin` rule, VIN's benchmark). Minigrid layouts come from
//! `data/minigrid/` (`scripts/export_minigrid.py`), VIN's sets from `../shared/data/vin/`
//! when it is there.

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::grid::{write_atomic, MoveRule};
use envfield::mazes::{suite_sets, MazeSet};
use envfield::models::ModelSource;
use envfield::nets::{model_file, FieldNet, NetsError};
use envfield::plan::{evaluate, EvalConfig, FieldDescent, PlannerKind, PlannerOptions, Summary};
use std::path::{Path, PathBuf};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "The maze suite: every family and size, the shipped field beside its controls")]
struct Args {
    /// Mazes per generated set (one random pair each).
    #[arg(long, default_value_t = 200)]
    count: usize,
    /// Seed of generated mazes and pairs.
    #[arg(long, default_value_t = 4242)]
    seed: u64,
    /// Field weights (default: models/context.safetensors).
    #[arg(long)]
    model: Option<PathBuf>,
    /// Write every figure to this JSON file.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Leave VIN out (the slowest column).
    #[arg(long)]
    no_vin: bool,
    /// Only the sets whose label contains one of these words (comma-separated).
    #[arg(long, value_delimiter = ',')]
    only: Option<Vec<String>>,
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The suite's sets, VIN's when `../shared/data/vin/` is there, those `--only` names.
fn sets(args: &Args) -> Result<Vec<MazeSet>> {
    let vin = root().join("../shared/data/vin");
    let minigrid = root().join("data/minigrid");
    let mut out = suite_sets(
        args.count,
        args.seed,
        Some(vin.as_path()).filter(|d| d.is_dir()),
        Some(minigrid.as_path()),
    )
    .context("the suite's sets (data/minigrid comes from scripts/export_minigrid.py)")?;
    if let Some(words) = &args.only {
        out.retain(|s| {
            words
                .iter()
                .any(|w| s.label.to_lowercase().contains(&w.to_lowercase()))
        });
    }
    Ok(out)
}

/// The mean, least and greatest learned cost of the legal orthogonal and diagonal moves of
/// every set's first maze.
fn cost_summary(net: &FieldNet, sets: &[MazeSet]) -> Result<serde_json::Value> {
    let (mut orth, mut diag) = (Vec::new(), Vec::new());
    for set in sets {
        let (o, d) = net.legal_move_costs(&set.mazes[0].grid, set.rule)?;
        orth.extend(o);
        diag.extend(d);
    }
    let stats = |v: &[f32]| {
        // No move has no mean, least or greatest cost: null, not 0 or infinity.
        let any = !v.is_empty();
        let mean = any.then(|| v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64);
        let min = v.iter().copied().reduce(f32::min);
        let max = v.iter().copied().reduce(f32::max);
        serde_json::json!({"moves": v.len(), "mean": mean, "min": min, "max": max})
    };
    Ok(serde_json::json!({"orthogonal": stats(&orth), "diagonal": stats(&diag)}))
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.count == 0 || args.count > 100_000 {
        bail!("--count must be in 1..=100000 (got {})", args.count);
    }
    if let Some(p) = &args.json {
        envfield::grid::check_writable(p)?;
    }
    let sets = sets(&args)?;
    if sets.is_empty() {
        bail!("--only matches no set");
    }
    let columns = ["field", "relay", "untrained", "octile", "exact", "vin"];
    let mut rows: Vec<(String, MoveRule, Vec<Option<Summary>>)> = Vec::new();
    let mut records = Vec::new();
    let mut shipped: Option<FieldNet> = None;
    for set in &sets {
        let size = set.mazes[0].grid.rows().max(set.mazes[0].grid.cols());
        let source = ModelSource {
            explicit: args.model.clone(),
            rule: set.rule,
            ..ModelSource::new(root().join("models"))
        };
        let options = PlannerOptions {
            rule: set.rule,
            ..PlannerOptions::default()
        };
        let file = source.file("context", size)?;
        let own_vin = model_file(&source.dir, "vin", size).is_ok();
        let mut untrained = FieldNet::new(FieldNet::load(&file)?.config().clone(), 1)?;
        untrained.set_rule(set.rule);
        if shipped.is_none() {
            shipped = Some(FieldNet::load(&file)?);
        }
        let cfg = EvalConfig {
            rule: set.rule,
            pairs_per_maze: 1,
            seed: args.seed,
        };
        let mut cells = Vec::new();
        for column in columns {
            let kind = match column {
                "field" => Some(PlannerKind::Field),
                "relay" => Some(PlannerKind::Relay),
                "octile" => Some(PlannerKind::Octile),
                "exact" => Some(PlannerKind::Graph),
                // VIN on every side of its own benchmark (the `vin`-rule sets), elsewhere
                // where a VIN of the side was trained.
                "vin" if !args.no_vin && (set.rule == MoveRule::Vin || own_vin) => {
                    Some(PlannerKind::Vin)
                }
                _ => None,
            };
            let report = match (column, kind) {
                ("untrained", _) => {
                    let p = FieldDescent::new(&untrained, set.rule);
                    Some(evaluate(&p, &set.mazes, &cfg, &mut |_, _| {})?)
                }
                (_, Some(kind)) => {
                    let built = kind.build(&options, |family| {
                        source
                            .load(family, size)
                            .map(|(_, m)| m)
                            .map_err(anyhow::Error::from)
                    });
                    match built {
                        Ok(p) => Some(evaluate(p.planner(), &set.mazes, &cfg, &mut |_, _| {})?),
                        // VIN has models for 8, 16 and 28 only.
                        Err(e)
                            if column == "vin"
                                && matches!(
                                    e.downcast_ref::<NetsError>(),
                                    Some(NetsError::ModelNotFound { .. })
                                ) =>
                        {
                            None
                        }
                        Err(e) => return Err(e),
                    }
                }
                _ => None,
            };
            let summary = report.map(|r| r.summary);
            if let Some(s) = &summary {
                eprintln!(
                    "{:<40} {:<10} {:>6.1}% {:.4} {:.3} ms",
                    set.label, column, s.success_rate, s.path_ratio, s.ms_per_path
                );
                records.push(serde_json::json!({
                    "set": set.label, "rule": set.rule.to_string(), "column": column,
                    "planner": s.planner, "mazes": s.mazes, "pairs": s.pairs,
                    "success_rate": s.success_rate,
                    "path_ratio": s.path_ratio.is_finite().then_some(s.path_ratio),
                    "ms_per_path": s.ms_per_path,
                }));
            }
            cells.push(summary);
        }
        rows.push((set.label.clone(), set.rule, cells));
    }
    let costs = cost_summary(shipped.as_ref().context("no set was run")?, &sets)?;
    println!(
        "{} mazes per generated set, one pair each, seed {}; each cell: success % / path ratio / ms per path",
        args.count, args.seed
    );
    println!();
    println!("| mazes | rule | {} |", columns.join(" | "));
    println!("|---|---|{}", "---|".repeat(columns.len()));
    for (label, rule, cells) in &rows {
        let cells: Vec<String> = cells
            .iter()
            .map(|c| match c {
                Some(s) if s.path_ratio.is_finite() => format!(
                    "{:.1} / {:.3} / {:.2}",
                    s.success_rate, s.path_ratio, s.ms_per_path
                ),
                Some(s) => format!("{:.1} / - / {:.2}", s.success_rate, s.ms_per_path),
                None => "-".into(),
            })
            .collect();
        println!("| {label} | {rule} | {} |", cells.join(" | "));
    }
    println!();
    println!("learned move costs (exact: 1 and 1.414): {costs}");
    if let Some(p) = &args.json {
        let all = serde_json::json!({"count": args.count, "seed": args.seed,
            "rows": records, "move_costs": costs});
        write_atomic(p, serde_json::to_string_pretty(&all)?.as_bytes())?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}
