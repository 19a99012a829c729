//! Fast marching on a grid from a file: prints the median solve time as one JSON line.
//!
//! ```text
//! cargo run --release --example fmm -- maze.txt                 # goal = the maze's G
//! cargo run --release --example fmm -- grid.npy --goal 512,512 --order 2 --repeat 20
//! cargo run --release --example fmm -- room.npy --goal 64,64,64 --out field.npy
//! cargo run --release --example fmm -- maze.png --goal 3,4 --out field.png
//! ```

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::eikonal::{FastMarching, Order};
use envfield::grid::{Cell2, Cell3, Grid2, Grid3, HeatMapStyle, NpyArray};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Parser)]
#[command(
    about = "Fast marching on a grid (.txt maze, .png or .npy); prints the median solve time as JSON"
)]
struct Args {
    /// The grid: a maze text file, a PNG (dark = obstacle) or a 2D/3D bool/uint8 .npy array.
    grid: PathBuf,
    /// Source cell: R,C in 2D or X,Y,Z in 3D. Default: the maze's G, else the centre.
    #[arg(long)]
    goal: Option<String>,
    /// Stencil order, 1 or 2.
    #[arg(long, default_value_t = 1)]
    order: u8,
    /// Grid spacing.
    #[arg(long, default_value_t = 1.0)]
    spacing: f32,
    /// Exact initialisation radius around the source (cells).
    #[arg(long, default_value_t = 2)]
    source_radius: usize,
    /// Write the field to this file (.npy, or .png for a 2D heat map).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Solve this many times and report the median.
    #[arg(long, default_value_t = 1)]
    repeat: usize,
}

enum Input {
    Two(Grid2, Option<Cell2>),
    Three(Grid3),
}

fn load(path: &Path) -> Result<Input> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    Ok(match ext {
        "txt" => {
            let mut mazes = envfield::grid::read_mazes(path)?;
            if mazes.len() != 1 {
                bail!(
                    "{}: holds {} mazes; fmm solves one grid (split the file, or use maze_nav \
                     for many)",
                    path.display(),
                    mazes.len()
                );
            }
            let m = mazes.remove(0);
            Input::Two(m.grid, m.goal)
        }
        "png" => Input::Two(Grid2::read_png(path)?, None),
        "npy" => match NpyArray::read(path)?.shape.len() {
            2 => Input::Two(Grid2::read_npy(path)?, None),
            3 => Input::Three(Grid3::read_npy(path)?),
            n => bail!("{}: expected a 2D or 3D array, found {n}D", path.display()),
        },
        _ => bail!(
            "{}: unknown grid format (expected .txt, .png or .npy)",
            path.display()
        ),
    })
}

fn parse_cell(s: &str) -> Result<Vec<usize>> {
    s.split(',')
        .map(|p| {
            p.trim()
                .parse::<usize>()
                .with_context(|| format!("bad coordinate {p:?} in --goal {s:?}"))
        })
        .collect()
}

fn median_ms(mut times: Vec<f64>) -> f64 {
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// Solves a timing run repeats at most: more is a typo, not a measurement.
const MAX_REPEAT: usize = 1_000_000;

fn main() -> Result<()> {
    let args = Args::parse();
    if !(1..=MAX_REPEAT).contains(&args.repeat) {
        bail!("--repeat must be in 1..={MAX_REPEAT} (got {})", args.repeat);
    }
    let fmm = FastMarching {
        order: Order::from_number(args.order)?,
        spacing: args.spacing,
        source_radius: args.source_radius,
    };
    let goal = args.goal.as_deref().map(parse_cell).transpose()?;
    let mut times = Vec::new();
    match load(&args.grid)? {
        Input::Two(grid, maze_goal) => {
            let goal = match goal.as_deref() {
                Some([r, c]) => Cell2::new(*r, *c),
                Some(other) => bail!(
                    "--goal needs R,C for a 2D grid, got {} numbers",
                    other.len()
                ),
                None => maze_goal.unwrap_or(Cell2::new(grid.rows() / 2, grid.cols() / 2)),
            };
            let mut field = None;
            for _ in 0..args.repeat {
                let t = Instant::now();
                let f = fmm.solve2(&grid, &[goal])?;
                times.push(t.elapsed().as_secs_f64() * 1e3);
                field = Some(f);
            }
            let field = field.expect("repeat >= 1");
            match &args.out {
                Some(p) if p.extension().is_some_and(|e| e == "png") => {
                    let scale = (512 / grid.rows().max(grid.cols())).clamp(1, 16) as u32;
                    let style = HeatMapStyle {
                        scale,
                        grid: Some(&grid),
                        goal: Some(goal),
                        ..Default::default()
                    };
                    field.write_png(p, &style)?;
                }
                Some(p) => field.write_npy(p)?,
                None => {}
            }
            println!(
                "{{\"cells\":{},\"order\":{},\"median_ms\":{:.4}}}",
                grid.len(),
                args.order,
                median_ms(times)
            );
        }
        Input::Three(grid) => {
            let [nx, ny, nz] = grid.shape();
            let goal = match goal.as_deref() {
                Some([x, y, z]) => Cell3::new(*x, *y, *z),
                Some(other) => bail!(
                    "--goal needs X,Y,Z for a 3D grid, got {} numbers",
                    other.len()
                ),
                None => Cell3::new(nx / 2, ny / 2, nz / 2),
            };
            let mut field = None;
            for _ in 0..args.repeat {
                let t = Instant::now();
                let f = fmm.solve3(&grid, &[goal])?;
                times.push(t.elapsed().as_secs_f64() * 1e3);
                field = Some(f);
            }
            if let Some(p) = &args.out {
                if p.extension().is_some_and(|e| e == "png") {
                    bail!("PNG output is 2D only; use .npy for a 3D field");
                }
                field.expect("repeat >= 1").write_npy(p)?;
            }
            println!(
                "{{\"cells\":{},\"order\":{},\"median_ms\":{:.4}}}",
                grid.len(),
                args.order,
                median_ms(times)
            );
        }
    }
    Ok(())
}
