//! A furnished room end to end: generate it, export it, map its floor from above, plan a walk
//! across it on the floor map (fast marching + descent), play a procedural gait along the path
//! and check every frame for support and collisions.
//!
//! `cargo run --release --example room -- --seed 3 --out out/room`
//!
//! `--scene FILE.obj|ply` reads a scene instead of generating one.
//!
//! Writes `scene.obj`, `scene.ply`, `points.ply` (surface samples), `floor.png` (the reaching
//! distance on the floor map with the path), `path.obj` and `walk.json` (the aligned gait) to
//! `--out`, and prints a JSON summary.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Parser;
use envfield::affordance::{align_in_scene, resample_path, walk, AlignConfig, Joint, WalkConfig};
use envfield::eikonal::FastMarching;
use envfield::grid::{Cell2, HeatMapStyle, MoveRule};
use envfield::plan::descend;
use envfield::scene::nalgebra::{distance, Point3};
use envfield::scene::{
    floor_map, sample_surface, write_point_cloud, write_polyline_obj, FloorMapConfig, RoomConfig,
    Scene,
};
use envfield_examples::SceneArgs;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "Generate a room, map its floor, walk across it and check the poses")]
struct Args {
    /// Room seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output folder.
    #[arg(long, default_value = "out/room")]
    out: PathBuf,
    /// Floor-map resolution in metres.
    #[arg(long, default_value_t = 0.05)]
    resolution: f32,
    /// Body radius kept from obstacles when planning, metres.
    #[arg(long, default_value_t = 0.25)]
    body_radius: f32,
    /// Surface points to sample.
    #[arg(long, default_value_t = 20_000)]
    points: usize,
    #[command(flatten)]
    scene: SceneArgs,
}

fn main() -> Result<()> {
    let args = Args::parse();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    args.scene.protect();
    envfield::grid::check_writable(args.out.join("scene.obj")).with_context(|| {
        format!(
            "--out {}: the scene is written there as scene.obj",
            args.out.display()
        )
    })?;
    let t = Instant::now();
    // The scene, its size in metres and the kinds of its furniture (none known for a file).
    let rooms = args.scene.rooms(RoomConfig::default())?;
    let (scene, size, kinds): (Scene, [f32; 2], Vec<String>) =
        match args.scene.scene(&rooms, args.seed, None)? {
            (scene, None) => {
                let aabb = scene.aabb().context("the scene is empty")?;
                let extent = aabb.maxs - aabb.mins;
                (scene, [extent.x, extent.y], Vec::new())
            }
            (scene, Some(room)) => {
                let kinds = room
                    .furniture
                    .iter()
                    .map(|f| format!("{:?}", f.kind).to_lowercase())
                    .collect();
                (scene, room.size, kinds)
            }
        };
    let generate_ms = t.elapsed().as_secs_f64() * 1e3;
    let mesh = scene.to_mesh();
    mesh.write(args.out.join("scene.obj"))?;
    mesh.write(args.out.join("scene.ply"))?;
    let points = sample_surface(&scene, args.points, args.seed)?;
    write_point_cloud(&points, None, args.out.join("points.ply"))?;

    let t = Instant::now();
    let map = floor_map(
        &scene,
        &FloorMapConfig {
            resolution: args.resolution,
            ..FloorMapConfig::default()
        },
    )?;
    let map_ms = t.elapsed().as_secs_f64() * 1e3;
    let walkable = map.inflated(args.body_radius)?;

    // Start and goal: the two ends of the longest shortest path in the largest free region.
    let envfield::grid::Components { labels, sizes } = walkable.free_components();
    let largest = (0..sizes.len())
        .max_by_key(|&k| sizes[k])
        .with_context(|| {
            format!(
                "no floor is wide enough for the body radius ({} m, --body-radius): the floor \
                 map has no free cell the body fits on. A floor off level or a ramp, a scene \
                 read with the wrong up axis (--up) or in other units (--units) leaves none: the \
                 import's warnings say which",
                args.body_radius
            )
        })?;
    let any = walkable.cell(
        labels
            .iter()
            .position(|&l| l == largest)
            .context("empty region")?,
    );
    let fmm = FastMarching::default();
    let farthest = |field: &envfield::grid::Field2| -> Cell2 {
        walkable
            .free_cells()
            .filter(|&c| field.get(c).is_some_and(f32::is_finite))
            .max_by(|&a, &b| {
                field
                    .get(a)
                    .unwrap_or(0.0)
                    .total_cmp(&field.get(b).unwrap_or(0.0))
            })
            .unwrap_or(any)
    };
    let start = farthest(&fmm.solve2(&walkable, &[any])?);
    let field_from_start = fmm.solve2(&walkable, &[start])?;
    let goal = farthest(&field_from_start);
    let t = Instant::now();
    let field = fmm.solve2(&walkable, &[goal])?;
    let plan = descend(
        &walkable,
        &field,
        MoveRule::Strict,
        start,
        goal,
        walkable.len(),
    );
    let plan_ms = t.elapsed().as_secs_f64() * 1e3;
    anyhow::ensure!(plan.success, "descent did not reach the goal");
    field.write_png(
        args.out.join("floor.png"),
        &HeatMapStyle {
            scale: 4,
            grid: Some(&walkable),
            path: &plan.path,
            start: Some(start),
            goal: Some(goal),
            ..HeatMapStyle::default()
        },
    )?;

    // The path in metres, resampled at the gait's own step per frame.
    let gait = walk(&WalkConfig::default(), args.seed)?;
    let step = gait.step_length();
    let cells: Vec<Point3<f32>> = plan
        .path
        .iter()
        .map(|&c| {
            let [x, y] = map.frame.center(c);
            Point3::new(x, y, 0.0)
        })
        .collect();
    let trajectory = resample_path(&cells, step)?;
    let length: f32 = cells.windows(2).map(|w| distance(&w[0], &w[1])).sum();
    let t = Instant::now();
    let (aligned, reports) = align_in_scene(
        &scene,
        &gait,
        &trajectory,
        &AlignConfig {
            keep_height: true,
            ..AlignConfig::default()
        },
    )?;
    let check_ms = t.elapsed().as_secs_f64() * 1e3;
    let valid = reports.iter().filter(|r| r.valid()).count();
    // Which joints broke the invalid frames.
    let mut culprits = std::collections::BTreeMap::<&str, usize>::new();
    for r in reports.iter().filter(|r| !r.valid()) {
        if !r.supported {
            *culprits.entry("unsupported").or_default() += 1;
        }
        for joint in Joint::ALL {
            if !r.support.joints().contains(&joint) && r.distances[joint.index()] < 0.0 {
                *culprits.entry(joint.name()).or_default() += 1;
            }
        }
    }
    let lifted: Vec<Point3<f32>> = trajectory
        .iter()
        .map(|p| p + envfield::scene::nalgebra::Vector3::new(0.0, 0.0, 0.05))
        .collect();
    write_polyline_obj(&lifted, args.out.join("path.obj"))?;
    aligned.write(args.out.join("walk.json"))?;

    println!(
        "{}",
        serde_json::json!({
            "seed": args.seed,
            "room_m": size,
            "furniture": kinds,
            "parts": scene.objects().iter().map(|o| o.parts().len()).sum::<usize>(),
            "triangles": mesh.triangles.len(),
            "floor_map": [map.grid.rows(), map.grid.cols()],
            "free_floor_fraction": map.grid.free_count() as f32 / map.grid.len() as f32,
            "path_m": length,
            "frames": aligned.frames.len(),
            "valid_frames": valid,
            "valid_percent": 100.0 * valid as f32 / reports.len().max(1) as f32,
            "invalid_because": culprits,
            "generate_ms": generate_ms,
            "floor_map_ms": map_ms,
            "plan_ms": plan_ms,
            "align_and_check_ms": check_ms,
            "out": args.out,
        })
    );
    Ok(())
}
