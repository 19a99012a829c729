//! Several people walking through a room at once, seen from above (paper section 4.1,
//! Algorithm 1): each person's field on the floor map the others change, predicted for all of
//! them in one batched pass per time step, against the same loop on the exact solver and
//! against ORCA.
//!
//! `cargo run --release --example birdseye_multi -- --people 4 --seed 3` writes
//! `out/birdseye/crowd.gif` (the floor map, each person's field contours, positions and
//! trails), `crowd.json` (paths in metres, arrival steps, pose checks) and each person's
//! aligned walking sequence `walk_N.json`, and prints a JSON summary.
//!
//! `--rooms 100 --people 4 --json` runs a batch on generated rooms and prints, as its last
//! line, one JSON object with the learned loop's figures and the same for the exact loop
//! (`exact_*`) and ORCA (`orca_*`).
//!
//! `--room FILE.obj|ply` reads a scene (metres, z up) instead of generating one.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::affordance::{
    align_in_scene, resample_path, walk, AffordanceReport, AlignConfig, PoseSequence, WalkConfig,
};
use envfield::eikonal::FastMarching;
use envfield::grid::{Cell2, Field2, FieldModel, Grid2, Point2};
use envfield::nets::FieldNet;
use envfield::plan::{
    mark_discs, orca_crowd, random_trips, shortest_lengths, walk_crowd, CrowdConfig, CrowdRun,
    OrcaConfig, Trip,
};
use envfield::scene::nalgebra::Point3;
use envfield::scene::{
    floor_map, generate_room, FloorMap, FloorMapConfig, RoomConfig, Scene, TriangleMesh,
};
use image::{Rgba, RgbaImage};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(about = "Several people walking through a room at once (Algorithm 1) against ORCA")]
struct Args {
    /// People walking at once.
    #[arg(long, default_value_t = 4)]
    people: usize,
    /// Seed of the room and of the start/goal pairs.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// A scene to read instead of a generated room: a triangle mesh as OBJ or PLY (metres,
    /// z up, the floor at its lowest point).
    #[arg(long)]
    room: Option<PathBuf>,
    /// Run a batch over this many generated rooms (seeds from --seed) and print the figures.
    #[arg(long)]
    rooms: Option<usize>,
    /// With --rooms: print the batch as one JSON object only.
    #[arg(long)]
    json: bool,
    /// The bird's-eye field.
    #[arg(long, default_value = "models/birdseye.safetensors")]
    model: PathBuf,
    /// Output folder.
    #[arg(long, default_value = "out/birdseye")]
    out: PathBuf,
    /// Write the frames as PNG files into this folder instead of an animated GIF.
    #[arg(long)]
    frames: Option<PathBuf>,
    /// Body radius, metres.
    #[arg(long, default_value_t = 0.25)]
    body_radius: f32,
    /// Step length, metres (one step per time step).
    #[arg(long, default_value_t = 0.5)]
    step_length: f32,
    /// Time steps a person held up by others waits for the way through them to clear.
    #[arg(long, default_value_t = 3)]
    patience: usize,
    /// Headings a step may take (8: the paper's).
    #[arg(long, default_value_t = 8)]
    directions: usize,
    /// Time steps before giving up.
    #[arg(long, default_value_t = 400)]
    max_steps: usize,
}

/// Floor-map cell side, metres.
const RESOLUTION: f32 = 0.1;
/// Generated rooms are padded to this many cells a side.
const SIDE: usize = 64;

/// A room's scene, floor map and walkable map (padded to 64x64 when it fits).
struct Floor {
    scene: Scene,
    map: FloorMap,
    walkable: Grid2,
}

fn floor(scene: Scene, body_radius: f32) -> Result<Floor> {
    let map = floor_map(
        &scene,
        &FloorMapConfig {
            resolution: RESOLUTION,
            ..FloorMapConfig::default()
        },
    )?;
    let fits = map.grid.rows() <= SIDE && map.grid.cols() <= SIDE;
    let walkable = map.walkable(body_radius, fits.then_some([SIDE, SIDE]))?;
    Ok(Floor {
        scene,
        map,
        walkable,
    })
}

/// One loop's figures on one room.
#[derive(Default)]
struct Tally {
    people: usize,
    reached: usize,
    person_collisions: usize,
    furniture_collisions: usize,
    ratios: Vec<f32>,
    steps: usize,
    seconds: f64,
    waits: usize,
    pose_frames: usize,
    pose_valid: usize,
}

impl Tally {
    fn add(
        &mut self,
        run: &CrowdRun,
        shortest: &[f32],
        floor: &Floor,
        radius: f32,
        s: f64,
        gait: &PoseSequence,
    ) -> Result<()> {
        let walkable = &floor.walkable;
        for i in 0..run.people() {
            let (_, reports) = aligned_walk(floor, run, i, gait)?;
            self.pose_frames += reports.len();
            self.pose_valid += reports.iter().filter(|r| r.valid()).count();
        }
        self.people += run.people();
        self.reached += run.arrived_at.iter().flatten().count();
        self.person_collisions += run.person_collisions(radius);
        self.furniture_collisions += run.obstacle_collisions(walkable);
        for (i, arrived) in run.arrived_at.iter().enumerate() {
            if arrived.is_some() && shortest[i] > 0.0 {
                self.ratios.push(run.path_length(i) / shortest[i]);
            }
        }
        self.steps += run.steps();
        self.seconds += s;
        self.waits += run.waits;
        Ok(())
    }

    fn json(&self, prefix: &str, out: &mut serde_json::Map<String, serde_json::Value>) {
        let mean = self.ratios.iter().sum::<f32>() / self.ratios.len().max(1) as f32;
        let mut put = |k: &str, v: serde_json::Value| {
            out.insert(format!("{prefix}{k}"), v);
        };
        put(
            "reach_pct",
            (100.0 * self.reached as f64 / self.people.max(1) as f64).into(),
        );
        put("person_collisions", self.person_collisions.into());
        put("furniture_collisions", self.furniture_collisions.into());
        put("path_ratio", mean.into());
        put(
            "ms_per_step",
            (1e3 * self.seconds / self.steps.max(1) as f64).into(),
        );
        put(
            "pose_valid_pct",
            (100.0 * self.pose_valid as f64 / self.pose_frames.max(1) as f64).into(),
        );
        put("steps", self.steps.into());
        put("waits", self.waits.into());
    }
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.people == 0 || args.rooms == Some(0) {
        bail!("--people and --rooms must be at least 1");
    }
    if !(args.body_radius.is_finite() && args.body_radius > 0.0) {
        bail!(
            "--body-radius must be a positive number of metres, got {}",
            args.body_radius
        );
    }
    if !(args.step_length.is_finite() && args.step_length >= RESOLUTION) {
        bail!(
            "--step-length must be at least the map's {RESOLUTION} m cell, got {}",
            args.step_length
        );
    }
    let model = FieldNet::load(&args.model)
        .with_context(|| format!("loading the bird's-eye field {}", args.model.display()))?;
    let cells = |m: f32| m / RESOLUTION;
    let config = CrowdConfig {
        body_radius: cells(args.body_radius),
        step_length: cells(args.step_length),
        max_steps: args.max_steps,
        patience: args.patience,
        directions: args.directions,
    };
    match args.rooms {
        Some(rooms) => batch(&args, rooms, &model, &config),
        None => one_room(&args, &model, &config),
    }
}

fn batch(args: &Args, rooms: usize, model: &FieldNet, config: &CrowdConfig) -> Result<()> {
    let exact = FastMarching::default();
    let (mut learned, mut fmm, mut orca) = (Tally::default(), Tally::default(), Tally::default());
    let gait = walk(&WalkConfig::default(), args.seed)?;
    for room in args.seed..args.seed + rooms as u64 {
        let scene = generate_room(&RoomConfig::birdseye(), room)?.scene;
        let floor = floor(scene, args.body_radius)?;
        let trips = random_trips(&floor.walkable, args.people, config, 1.0 / RESOLUTION, room)?;
        let shortest = shortest_lengths(&floor.walkable, &trips)?;
        let (w, r) = (&floor.walkable, config.body_radius);
        let t = Instant::now();
        let run = walk_crowd(w, &trips, model, config)?;
        let s = t.elapsed().as_secs_f64();
        learned.add(&run, &shortest, &floor, r, s, &gait)?;
        let t = Instant::now();
        let run = walk_crowd(w, &trips, &exact, config)?;
        let s = t.elapsed().as_secs_f64();
        fmm.add(&run, &shortest, &floor, r, s, &gait)?;
        let t = Instant::now();
        let run = orca_crowd(w, &trips, config, &OrcaConfig::default())?;
        let s = t.elapsed().as_secs_f64();
        orca.add(&run, &shortest, &floor, r, s, &gait)?;
        if !args.json {
            eprintln!(
                "room {room}: learned {}/{} exact {}/{} orca {}/{} reached",
                learned.reached, learned.people, fmm.reached, fmm.people, orca.reached, orca.people
            );
        }
    }
    let mut out = serde_json::Map::new();
    out.insert("rooms".into(), rooms.into());
    out.insert("people".into(), args.people.into());
    out.insert("body_radius_m".into(), args.body_radius.into());
    out.insert("step_length_m".into(), args.step_length.into());
    learned.json("", &mut out);
    fmm.json("exact_", &mut out);
    orca.json("orca_", &mut out);
    println!("{}", serde_json::Value::Object(out));
    Ok(())
}

fn one_room(args: &Args, model: &FieldNet, config: &CrowdConfig) -> Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    envfield::grid::check_writable(args.out.join("crowd.json"))?;
    let scene = match &args.room {
        Some(file) => Scene::from_mesh("scene", &TriangleMesh::read(file)?)?,
        None => generate_room(&RoomConfig::birdseye(), args.seed)?.scene,
    };
    let floor = floor(scene, args.body_radius)?;
    let trips = random_trips(
        &floor.walkable,
        args.people,
        config,
        1.0 / RESOLUTION,
        args.seed,
    )?;
    let shortest = shortest_lengths(&floor.walkable, &trips)?;
    let t = Instant::now();
    let run = walk_crowd(&floor.walkable, &trips, model, config)?;
    let ms_per_step = 1e3 * t.elapsed().as_secs_f64() / run.steps().max(1) as f64;
    let exact = walk_crowd(&floor.walkable, &trips, &FastMarching::default(), config)?;
    let orca = orca_crowd(&floor.walkable, &trips, config, &OrcaConfig::default())?;

    // Each person's walk, aligned to their path and checked in the scene.
    let gait = walk(&WalkConfig::default(), args.seed)?;
    let mut people = Vec::new();
    for (i, trip) in trips.iter().enumerate() {
        let (aligned, reports) = aligned_walk(&floor, &run, i, &gait)?;
        aligned.write(args.out.join(format!("walk_{i}.json")))?;
        let valid = reports.iter().filter(|r| r.valid()).count();
        people.push(serde_json::json!({
            "start_m": world(&floor.map, point(trip.start)).coords.as_slice()[..2],
            "goal_m": world(&floor.map, point(trip.goal)).coords.as_slice()[..2],
            "arrived_at_step": run.arrived_at[i],
            "path_m": run.path(i).iter().map(|&p| {
                let w = world(&floor.map, p);
                [w.x, w.y]
            }).collect::<Vec<_>>(),
            "path_ratio": run.path_length(i) / shortest[i],
            "pose_frames": reports.len(),
            "pose_valid_pct": 100.0 * valid as f64 / reports.len().max(1) as f64,
        }));
    }
    let summary = serde_json::json!({
        "seed": args.seed,
        "floor_map": [floor.walkable.rows(), floor.walkable.cols()],
        "people": people,
        "steps": run.steps(),
        "ms_per_step": ms_per_step,
        "person_collisions": run.person_collisions(config.body_radius),
        "furniture_collisions": run.obstacle_collisions(&floor.walkable),
        "exact_arrived": exact.arrived_at.iter().flatten().count(),
        "orca_arrived": orca.arrived_at.iter().flatten().count(),
        "orca_person_collisions": orca.person_collisions(config.body_radius),
    });
    envfield::grid::write_atomic(
        args.out.join("crowd.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    let frames = render(&floor.walkable, &trips, &run, model, config)?;
    match &args.frames {
        Some(dir) => {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            for (t, frame) in frames.iter().enumerate() {
                write_png(frame, &dir.join(format!("frame_{t:04}.png")))?;
            }
        }
        None => write_gif(&frames, &args.out.join("crowd.gif"))?,
    }
    let mut summary = summary;
    summary.as_object_mut().map(|o| o.remove("people"));
    summary["out"] = serde_json::json!(args.out);
    println!("{summary}");
    Ok(())
}

/// Person `i`'s walking sequence aligned to their path in `floor`'s scene, and each frame's
/// support and collision check.
fn aligned_walk(
    floor: &Floor,
    run: &CrowdRun,
    i: usize,
    gait: &PoseSequence,
) -> Result<(PoseSequence, Vec<AffordanceReport>)> {
    let path: Vec<Point3<f32>> = run.path(i).iter().map(|&p| world(&floor.map, p)).collect();
    let trajectory = resample_path(&path, gait.step_length())?;
    let align = AlignConfig {
        keep_height: true,
        ..AlignConfig::default()
    };
    Ok(align_in_scene(&floor.scene, gait, &trajectory, &align)?)
}

/// World `(x, y, 0)` of a map point (cell centres at integer coordinates).
fn world(map: &FloorMap, p: Point2) -> Point3<f32> {
    let f = &map.frame;
    Point3::new(
        f.origin[0] + (p.col + 0.5) * f.resolution,
        f.origin[1] + (p.row + 0.5) * f.resolution,
        map.floor_height,
    )
}

fn point(c: Cell2) -> Point2 {
    Point2::new(c.row as f32, c.col as f32)
}

const COLOURS: [[u8; 3]; 8] = [
    [230, 25, 75],
    [60, 180, 75],
    [0, 130, 200],
    [245, 130, 48],
    [145, 30, 180],
    [70, 200, 200],
    [240, 50, 230],
    [150, 120, 30],
];

/// One picture per time step: the walkable map, each walking person's field contours (every
/// half metre of reaching distance, on the map as they see it), trails, bodies and goals.
fn render(
    walkable: &Grid2,
    trips: &[Trip],
    run: &CrowdRun,
    model: &FieldNet,
    config: &CrowdConfig,
) -> Result<Vec<RgbaImage>> {
    const SCALE: u32 = 8;
    let (rows, cols) = (walkable.rows(), walkable.cols());
    let mut frames = Vec::new();
    for t in 0..run.frames.len() {
        let positions = &run.frames[t];
        let walking: Vec<usize> = (0..trips.len())
            .filter(|&i| run.arrived_at[i].is_none_or(|a| t < a))
            .collect();
        let maps: Vec<Grid2> = walking
            .iter()
            .map(|&i| {
                let others = walking.iter().filter(|&&j| j != i).map(|&j| positions[j]);
                mark_discs(walkable, others, 2.0 * config.body_radius)
            })
            .collect::<envfield::plan::Result<_>>()?;
        let asked: Vec<(&Grid2, Cell2)> = walking
            .iter()
            .zip(&maps)
            .filter(|(&i, m)| m.is_free(trips[i].goal))
            .map(|(&i, m)| (m, trips[i].goal))
            .collect();
        let fields: Vec<Field2> = model.predict_many(&asked)?;
        let mut img = RgbaImage::from_pixel(
            cols as u32 * SCALE,
            rows as u32 * SCALE,
            Rgba([250, 250, 250, 255]),
        );
        for r in 0..rows {
            for c in 0..cols {
                if walkable.is_obstacle(Cell2::new(r, c)) {
                    fill(
                        &mut img,
                        c as u32 * SCALE,
                        r as u32 * SCALE,
                        SCALE,
                        [70, 70, 80],
                    );
                }
            }
        }
        // Contours of each person's field within 2 m of them (every 0.5 m): how it bends
        // round the others. A cell is on one where the field crosses a level against a
        // neighbour.
        let mut k = 0;
        for (&i, m) in walking.iter().zip(&maps) {
            if !m.is_free(trips[i].goal) {
                continue;
            }
            let f = &fields[k];
            k += 1;
            let band = |cell: Cell2| {
                f.get(cell)
                    .filter(|v| v.is_finite())
                    .map(|v| (v / 5.0) as i32)
            };
            let colour = tint(COLOURS[i % 8], 0.7);
            for r in 0..rows {
                for c in 0..cols.saturating_sub(1) {
                    if Point2::new(r as f32, c as f32).distance(positions[i]) > 20.0 {
                        continue;
                    }
                    let (a, b) = (band(Cell2::new(r, c)), band(Cell2::new(r, c + 1)));
                    let down = (r + 1 < rows).then(|| band(Cell2::new(r + 1, c))).flatten();
                    // One side of each crossing: the cell on the lower level.
                    if a.is_some() && ((b.is_some() && a < b) || (down.is_some() && a < down)) {
                        fill(
                            &mut img,
                            c as u32 * SCALE + SCALE / 2 - 1,
                            r as u32 * SCALE + SCALE / 2 - 1,
                            3,
                            colour,
                        );
                    }
                }
            }
        }
        for i in 0..trips.len() {
            let colour = COLOURS[i % 8];
            let g = trips[i].goal;
            cross(&mut img, g.col as f32, g.row as f32, SCALE, colour);
            for s in 1..=t {
                let (a, b) = (run.frames[s - 1][i], run.frames[s][i]);
                line(&mut img, a, b, SCALE, tint(colour, 0.35));
            }
            let p = positions[i];
            let here = run.arrived_at[i].is_none_or(|a| t <= a);
            if here {
                disc(&mut img, p, config.body_radius, SCALE, colour);
            }
        }
        // Only the room: the free cells' bounding box and a cell around it.
        let (r0, r1, c0, c1) = walkable
            .free_cells()
            .fold((rows, 0, cols, 0), |(r0, r1, c0, c1), c| {
                (r0.min(c.row), r1.max(c.row), c0.min(c.col), c1.max(c.col))
            });
        let (r0, c0) = (r0.saturating_sub(1) as u32, c0.saturating_sub(1) as u32);
        let (r1, c1) = ((r1 + 2).min(rows) as u32, (c1 + 2).min(cols) as u32);
        let crop = image::imageops::crop_imm(
            &img,
            c0 * SCALE,
            r0 * SCALE,
            (c1.saturating_sub(c0)) * SCALE,
            (r1.saturating_sub(r0)) * SCALE,
        );
        frames.push(crop.to_image());
    }
    Ok(frames)
}

fn tint(c: [u8; 3], keep: f32) -> [u8; 3] {
    c.map(|v| (v as f32 * keep + 255.0 * (1.0 - keep)) as u8)
}

fn put(img: &mut RgbaImage, x: i64, y: i64, c: [u8; 3]) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, Rgba([c[0], c[1], c[2], 255]));
    }
}

fn fill(img: &mut RgbaImage, x: u32, y: u32, side: u32, c: [u8; 3]) {
    for dy in 0..side {
        for dx in 0..side {
            put(img, (x + dx) as i64, (y + dy) as i64, c);
        }
    }
}

/// Pixel centre of map point `p`.
fn pixel(p: Point2, scale: u32) -> (f32, f32) {
    ((p.col + 0.5) * scale as f32, (p.row + 0.5) * scale as f32)
}

fn disc(img: &mut RgbaImage, p: Point2, radius: f32, scale: u32, c: [u8; 3]) {
    let (x, y) = pixel(p, scale);
    let r = radius * scale as f32;
    for dy in -(r as i64)..=(r as i64) {
        for dx in -(r as i64)..=(r as i64) {
            let d = ((dx * dx + dy * dy) as f32).sqrt();
            if d <= r {
                let edge = d > r - 1.5;
                put(
                    img,
                    x as i64 + dx,
                    y as i64 + dy,
                    if edge { [20, 20, 20] } else { c },
                );
            }
        }
    }
}

fn line(img: &mut RgbaImage, a: Point2, b: Point2, scale: u32, c: [u8; 3]) {
    let (ax, ay) = pixel(a, scale);
    let (bx, by) = pixel(b, scale);
    let n = ((bx - ax).abs().max((by - ay).abs()).ceil() as usize).max(1);
    for k in 0..=n {
        let s = k as f32 / n as f32;
        let (x, y) = (ax + s * (bx - ax), ay + s * (by - ay));
        for (dx, dy) in [(0, 0), (1, 0), (0, 1)] {
            put(img, x as i64 + dx, y as i64 + dy, c);
        }
    }
}

fn cross(img: &mut RgbaImage, col: f32, row: f32, scale: u32, c: [u8; 3]) {
    let (x, y) = pixel(Point2::new(row, col), scale);
    for d in -5i64..=5 {
        for w in 0..2 {
            put(img, x as i64 + d, y as i64 + d + w, c);
            put(img, x as i64 + d, y as i64 - d + w, c);
        }
    }
}

fn write_png(img: &RgbaImage, path: &Path) -> Result<()> {
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )?;
    envfield::grid::write_atomic(path, &bytes)?;
    Ok(())
}

/// An animated GIF, ten frames a second, looping; written atomically.
fn write_gif(frames: &[RgbaImage], path: &Path) -> Result<()> {
    use image::codecs::gif::{GifEncoder, Repeat};
    let mut bytes = Vec::new();
    {
        let mut encoder = GifEncoder::new_with_speed(&mut bytes, 20);
        encoder.set_repeat(Repeat::Infinite)?;
        let delay = image::Delay::from_numer_denom_ms(100, 1);
        encoder.encode_frames(
            frames
                .iter()
                .map(|f| image::Frame::from_parts(f.clone(), 0, 0, delay)),
        )?;
    }
    envfield::grid::write_atomic(path, &bytes)?;
    Ok(())
}
