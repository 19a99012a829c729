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
//! - `vin`: the VIN baseline where a model for the maze's side exists (8, 16, 28).
//!
//! Generated families are walked under the `strict` rule, except VIN-style gridworlds and
//! VIN's test sets (the `vin` rule, VIN's benchmark). Minigrid layouts come from
//! `data/minigrid/` (`scripts/export_minigrid.py`), VIN's sets from `../shared/data/vin/`
//! when it is there.

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::grid::{write_atomic, Grid2, Maze, MoveRule, Neighbourhood2};
use envfield::mazes::{GeneratorKind, MazeGenerator};
use envfield::models::ModelSource;
use envfield::nets::{FieldNet, NetsError};
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

/// One row of the table: a set of mazes and the rule they are walked by.
struct Set {
    label: String,
    rule: MoveRule,
    mazes: Vec<Maze>,
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The `rows x cols` window of `maze` at the top-left corner (start and goal dropped).
fn crop(maze: &Maze, rows: usize, cols: usize) -> Result<Maze> {
    let g = &maze.grid;
    let obstacles = (0..rows)
        .flat_map(|r| (0..cols).map(move |c| (r, c)))
        .map(|(r, c)| g.obstacles()[r * g.cols() + c])
        .collect();
    Ok(Maze {
        grid: Grid2::from_obstacles(rows, cols, obstacles)?,
        start: None,
        goal: None,
    })
}

/// `maze` without its outermost rows and columns (start and goal kept when inside).
fn strip_border(maze: &Maze) -> Result<Maze> {
    let g = &maze.grid;
    let (rows, cols) = (g.rows() - 2, g.cols() - 2);
    let obstacles = (0..rows)
        .flat_map(|r| (0..cols).map(move |c| (r, c)))
        .map(|(r, c)| g.obstacles()[(r + 1) * g.cols() + c + 1])
        .collect();
    let inside = |p: Option<envfield::grid::Cell2>| {
        p.filter(|p| (1..=rows).contains(&p.row) && (1..=cols).contains(&p.col))
            .map(|p| envfield::grid::Cell2::new(p.row - 1, p.col - 1))
    };
    let (start, goal) = (inside(maze.start), inside(maze.goal));
    let both = start.is_some() && goal.is_some();
    Ok(Maze {
        grid: Grid2::from_obstacles(rows, cols, obstacles)?,
        start: start.filter(|_| both),
        goal: goal.filter(|_| both),
    })
}

fn sets(args: &Args) -> Result<Vec<Set>> {
    let generated = |kind: GeneratorKind, size: usize| -> Result<Vec<Maze>> {
        Ok(MazeGenerator::new(kind, size)?.generate_many(args.count, args.seed)?)
    };
    let mut out = Vec::new();
    for (kind, rule, sizes) in [
        (
            GeneratorKind::Gridworld,
            MoveRule::Vin,
            &[8, 16, 28, 48, 64][..],
        ),
        (
            GeneratorKind::Crossings,
            MoveRule::Strict,
            &[8, 16, 28, 48, 64],
        ),
        (GeneratorKind::Rooms, MoveRule::Strict, &[8, 16, 28, 48, 64]),
        (GeneratorKind::Perfect, MoveRule::Strict, &[21, 41, 63]),
    ] {
        for &size in sizes {
            out.push(Set {
                label: format!("{kind} {size}x{size}"),
                rule,
                mazes: generated(kind, size)?,
            });
        }
    }
    // Any frame: open edges and non-square mazes.
    let no_border = |kind, size| -> Result<Vec<Maze>> {
        generated(kind, size)?.iter().map(strip_border).collect()
    };
    let window = |kind, size, rows, cols| -> Result<Vec<Maze>> {
        generated(kind, size)?
            .iter()
            .map(|m| crop(m, rows, cols))
            .collect()
    };
    out.push(Set {
        label: "perfect 41x41, border removed (39x39)".into(),
        rule: MoveRule::Strict,
        mazes: no_border(GeneratorKind::Perfect, 41)?,
    });
    out.push(Set {
        label: "rooms 16x40 (window of 40x40)".into(),
        rule: MoveRule::Strict,
        mazes: window(GeneratorKind::Rooms, 40, 16, 40)?,
    });
    out.push(Set {
        label: "gridworld 16x40 (window of 40x40)".into(),
        rule: MoveRule::Vin,
        mazes: window(GeneratorKind::Gridworld, 40, 16, 40)?,
    });
    let vin_dir = root().join("../shared/data/vin");
    for size in [8, 16, 28] {
        let file = vin_dir.join(format!("vin_test_{size}.txt"));
        if file.is_file() {
            let mazes = envfield::grid::read_mazes(&file)?;
            if size == 16 {
                out.push(Set {
                    label: "VIN test 16, border removed (14x14)".into(),
                    rule: MoveRule::Vin,
                    mazes: mazes.iter().map(strip_border).collect::<Result<_>>()?,
                });
            }
            out.push(Set {
                label: format!("VIN test {size}x{size}"),
                rule: MoveRule::Vin,
                mazes,
            });
        }
    }
    let mut minigrid: Vec<PathBuf> = std::fs::read_dir(root().join("data/minigrid"))
        .context("reading data/minigrid (scripts/export_minigrid.py writes it)")?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "txt"))
        .collect();
    minigrid.sort();
    for file in minigrid {
        let name = file.file_stem().unwrap_or_default().to_string_lossy();
        let mazes = envfield::grid::read_mazes(&file)?;
        let (r, c) = (mazes[0].grid.rows(), mazes[0].grid.cols());
        out.push(Set {
            label: format!("Minigrid {name} {r}x{c}"),
            rule: MoveRule::Strict,
            mazes,
        });
    }
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
fn cost_summary(net: &FieldNet, sets: &[Set]) -> Result<serde_json::Value> {
    let (mut orth, mut diag) = (Vec::new(), Vec::new());
    for set in sets {
        let grid = &set.mazes[0].grid;
        let costs = net.move_costs(grid)?;
        for cell in grid.free_cells() {
            let i = cell.row * grid.cols() + cell.col;
            for (next, _) in grid.neighbours(cell, Neighbourhood2::Eight(set.rule)) {
                let (dr, dc) = (
                    next.row as isize - cell.row as isize,
                    next.col as isize - cell.col as isize,
                );
                let k = envfield::grid::DIRECTIONS_8
                    .iter()
                    .position(|&d| d == (dr, dc))
                    .expect("a neighbour is one of the 8 moves");
                match dr == 0 || dc == 0 {
                    true => orth.push(costs[i][k]),
                    false => diag.push(costs[i][k]),
                }
            }
        }
    }
    let stats = |v: &[f32]| {
        let mean = v.iter().map(|&x| x as f64).sum::<f64>() / v.len().max(1) as f64;
        let min = v.iter().copied().fold(f32::INFINITY, f32::min);
        let max = v.iter().copied().fold(f32::NEG_INFINITY, f32::max);
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
                "vin" if !args.no_vin => Some(PlannerKind::Vin),
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
