//! Human navigation in 3D rooms (paper section 4.2, Tables 3 and 4): the pose-dependent search
//! on the learned 3D field, with and without affordance, on the exact field, and RRT, RRT*,
//! PRM and the straight line on the same accessible region and collision test; every path is
//! fitted with the pose sequence and its poses checked.
//!
//! Ours (`ours`, `ours_exact`) is the search under the pose filter, then the region alone
//! where the poses allow no route within the budget (`--budget`, expansions per step of the
//! shortest walk; `FieldSearch3::search_relaxed`), then straight cuts the pose filter allows
//! (`FieldSearch3::shortcut`). `ours_raw` is the paper's search alone, and `ours_noaff` the
//! search and cuts under the region alone.
//!
//! ```text
//! cargo run --release --example room_nav                              # the shipped room, a few pairs
//! cargo run --release --example room_nav -- --rooms 5 --pairs 20 --json \
//!     --big-budget 20000 --fields out/fields                         # the tables
//! cargo run --release --example room_nav -- --scene room.obj          # a scene of your own
//! ```
//!
//! Walking pairs join two standing places of the accessible region at least a metre apart;
//! sit-down pairs start where the sit-down sequence starts in front of a seat and end seated.
//! Writes `scene.obj`, `region.ply`, `path_<planner>.obj`, `poses_<planner>.json` (the first
//! pair's aligned poses), `top.png` (every planner's first path over the floor) and `room.png`
//! (the room ray-cast from above one wall, the paths and five of ours' poses drawn) to `--out`.
//! The last line is one JSON object (`--json`).

use anyhow::{bail, Context, Result};
use clap::Parser;
use envfield::affordance::{walk, PoseSequence, Support, WalkConfig};
use envfield::grid::{Cell3, ContinuousField3, Point3m, SplitMix64};
use envfield::nets::FieldNet;
use envfield::plan::{
    prm, rrt, rrt_star, straight_line, FieldSearch3, Path3, SamplingConfig, StepFilter,
};
use envfield::scene::nalgebra::Point3;
use envfield::scene::{
    generate_room, sample_surface, write_polyline_obj, Room, RoomConfig, Scene, TriangleMesh,
};
use envfield::vae::{
    afford, point, sit_on, train_field3, AccessibleRegion, Cvae, ExactField3, Field3Config,
    LearnedField3, PoseFilter, RegionConfig,
};
use indicatif::{ProgressBar, ProgressStyle};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The room whose learned field ships in `models/`.
const SHIPPED_ROOM: u64 = 10_000;

#[derive(Parser)]
#[command(
    about = "Navigate people through 3D rooms: ours against RRT, RRT*, PRM and the straight line"
)]
struct Args {
    /// A scene to read instead of a generated room (OBJ or PLY, metres, z up).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Seed of the generated room (10000 and up were never seen by the VAE).
    #[arg(long, default_value_t = SHIPPED_ROOM)]
    seed: u64,
    /// Evaluate this many rooms (seeds from --seed on).
    #[arg(long, default_value_t = 1)]
    rooms: u64,
    /// Walking pairs per room (sit-down pairs: one per reachable seat).
    #[arg(long, default_value_t = 4)]
    pairs: usize,
    /// The VAE's weights.
    #[arg(long)]
    vae: Option<PathBuf>,
    /// The learned field's weights for the room (default: models/room_field_<seed>.safetensors
    /// when it is there; otherwise the field is trained).
    #[arg(long)]
    field: Option<PathBuf>,
    /// Training steps of a room's learned field.
    #[arg(long, default_value_t = 3000)]
    field_steps: u64,
    /// Save a trained field here (for a single room).
    #[arg(long)]
    save_field: Option<PathBuf>,
    /// Keep every trained room field in this folder
    /// (`room_field_<seed>_<region>_<steps>.safetensors`: the room, a fingerprint of its
    /// accessible region and the training steps) and load it from there on the next run, so a
    /// second run of the tables skips the training.
    #[arg(long)]
    fields: Option<PathBuf>,
    /// RRT* budget of the second row (raised until its path ratio matches ours).
    #[arg(long, default_value_t = 5000)]
    big_budget: usize,
    /// Ours' budget: expansions per step of the shortest walk (plus 200); past it, ours falls
    /// back to the region alone.
    #[arg(long, default_value_t = 5.0)]
    budget: f64,
    /// The same for sit-down pairs: the steps must match the sequence's frames to the seat,
    /// which takes more search than a walk.
    #[arg(long, default_value_t = 50.0)]
    sit_budget: f64,
    /// Torso samples drawn for the accessible region.
    #[arg(long, default_value_t = 6000)]
    samples: usize,
    /// Output folder.
    #[arg(long, default_value = "out/room_nav")]
    out: PathBuf,
    /// The summary as one JSON line only.
    #[arg(long)]
    json: bool,
}

const PLANNERS: [&str; 9] = [
    "ours",
    "ours_raw",
    "ours_noaff",
    "ours_exact",
    "rrt",
    "rrtstar",
    "rrtstar_big",
    "prm",
    "line",
];

/// One planner's result on one pair.
#[derive(Clone, Debug, Default)]
struct Outcome {
    reached: bool,
    /// The search opened every allowed point: no allowed route on its lattice (ours only).
    no_route: bool,
    /// The pose filter allowed no route in the budget; ours took the region's (ours only).
    relaxed: bool,
    dist_m: f64,
    seconds: f64,
    path_ratio: f64,
    support: f64,
    free: f64,
    valid: f64,
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A fingerprint of the region's voxels (FNV-1a over its shape and accessible voxels), so a
/// field kept by `--fields` is only loaded again for the very region it was trained on.
fn region_key(region: &AccessibleRegion) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let shape = region.frame.shape;
    for v in shape.iter().chain(region.free_indices()) {
        for b in (*v as u64).to_le_bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

/// The shipped learned field of the room, if any.
fn shipped_field(seed: u64) -> Option<PathBuf> {
    let p = root().join(format!("models/room_field_{seed}.safetensors"));
    p.is_file().then_some(p)
}

struct Pair {
    start: Point3m,
    goal: Point3m,
    sequence: PoseSequence,
    repeat: bool,
    kind: &'static str,
}

/// Walking pairs between standing places of the region (kept samples that afford standing)
/// at least a metre apart along the exact field, and sit-down pairs at every seat whose start
/// and seated torso both lie in the region.
fn pairs(
    room: Option<&Room>,
    scene: &Scene,
    region: &AccessibleRegion,
    count: usize,
    seed: u64,
) -> Result<Vec<Pair>> {
    let config = RegionConfig::default();
    let standing: Vec<Point3m> = region
        .samples
        .iter()
        .copied()
        .filter(|&s| region.contains(s))
        .filter(|&s| afford(scene, s, &config).is_ok_and(|a| a.valid == Some(Support::Standing)))
        .collect();
    if standing.len() < 2 {
        bail!("fewer than two standing places in the accessible region");
    }
    let gait = walk(&WalkConfig::default(), seed)?;
    let mut rng = SplitMix64::new(seed ^ 0x9A1B);
    let mut out = Vec::new();
    let mut tries = 0;
    while out.iter().filter(|p: &&Pair| p.kind == "walk").count() < count && tries < 100 * count {
        tries += 1;
        let (a, b) = (
            standing[rng.below(standing.len())],
            standing[rng.below(standing.len())],
        );
        let exact = ExactField3::new(region, b)?;
        let d = exact.value(a)?;
        if d.is_finite() && d >= 1.0 {
            out.push(Pair {
                start: a,
                goal: b,
                sequence: gait.clone(),
                repeat: true,
                kind: "walk",
            });
        }
    }
    if let Some(room) = room {
        for f in &room.furniture {
            if let Some(seq) = sit_on(f)? {
                let t0 = seq.frames[0].torso();
                let t1 = seq.frames.last().expect("frames").torso();
                let (s, g) = ([t0.x, t0.y, t0.z], [t1.x, t1.y, t1.z]);
                if region.contains(s) && region.contains(g) {
                    out.push(Pair {
                        start: s,
                        goal: g,
                        sequence: seq,
                        repeat: false,
                        kind: "sit",
                    });
                }
            }
        }
    }
    Ok(out)
}

/// The poses of the pair's sequence along `path` (resampled at the sequence's step unless it
/// is ours, whose points are the steps), placed as the search places them
/// (`PoseFilter::poses_along`): support, collision-free and valid shares, and the poses.
fn fit(
    filter: &PoseFilter,
    path: &[Point3m],
    resample: bool,
) -> Result<(f64, f64, f64, PoseSequence)> {
    let step = filter.sequence.step_length().max(1e-3);
    let traj: Vec<Point3m> = if resample && path.len() > 1 {
        let pts: Vec<Point3<f32>> = path.iter().map(|&p| point(p)).collect();
        envfield::affordance::resample_path(&pts, step)?
            .iter()
            .map(|p| [p.x, p.y, p.z])
            .collect()
    } else {
        path.to_vec()
    };
    let (poses, reports) = filter.poses_along(&traj)?;
    let n = reports.len().max(1) as f64;
    let share = |f: &dyn Fn(&envfield::affordance::AffordanceReport) -> bool| {
        100.0 * reports.iter().filter(|r| f(r)).count() as f64 / n
    };
    Ok((
        share(&|r| r.supported),
        share(&|r| r.collision_free),
        share(&|r| r.valid()),
        poses,
    ))
}

/// Runs every planner on one pair.
#[allow(clippy::type_complexity)]
fn run_pair(
    scene: &Scene,
    region: &AccessibleRegion,
    net: &FieldNet,
    pair: &Pair,
    big_budget: usize,
    budget: f64,
    seed: u64,
) -> Result<Vec<(&'static str, Outcome, Vec<Point3m>, PoseSequence)>> {
    let goal_cell = region.cell(pair.goal, "goal")?;
    region.cell(pair.start, "start")?;
    let exact = ExactField3::at_cell(region, goal_cell)?;
    let shortest = exact.value(pair.start)? as f64;
    let learned = LearnedField3::new(net, region, goal_cell)?;
    let step = pair.sequence.step_length();
    let search = FieldSearch3 {
        step,
        tolerance: 0.02,
        // A search that has not arrived by then is lost in a pocket the poses cannot leave,
        // and ours falls back to the region alone.
        max_steps: (budget * shortest.max(0.5) / step as f64) as usize + 200,
    };
    let poses = PoseFilter {
        scene,
        region,
        sequence: &pair.sequence,
        repeat: pair.repeat,
        // A walk faces where it goes; a sit-down keeps the heading made for its seat.
        face_the_move: pair.repeat,
        affordance: Default::default(),
    };
    let sampling = SamplingConfig {
        step: step.max(0.05),
        seed,
        ..SamplingConfig::default()
    };
    let mut out = Vec::new();
    for name in PLANNERS {
        let t = Instant::now();
        let path: Path3 = match name {
            // Ours: the search under the pose filter, the region alone where that finds no
            // route, then straight cuts; ours_raw is the paper's search alone.
            "ours" => search.search_relaxed(&learned, &poses, region, pair.start, pair.goal)?,
            "ours_raw" => search.search(&learned, &poses, pair.start, pair.goal)?,
            "ours_noaff" => {
                let f = region as &dyn StepFilter;
                let raw = search.search(&learned, f, pair.start, pair.goal)?;
                search.shortcut(f, &raw, pair.goal)?
            }
            "ours_exact" => search.search_relaxed(&exact, &poses, region, pair.start, pair.goal)?,
            "rrt" => rrt(region, pair.start, pair.goal, &sampling)?,
            "rrtstar" => rrt_star(region, pair.start, pair.goal, &sampling)?,
            "rrtstar_big" => rrt_star(
                region,
                pair.start,
                pair.goal,
                &SamplingConfig {
                    budget: big_budget,
                    ..sampling
                },
            )?,
            "prm" => prm(region, pair.start, pair.goal, &sampling)?,
            _ => Path3::ending(straight_line(pair.start, pair.goal, step)?, pair.goal, 0.02),
        };
        let seconds = t.elapsed().as_secs_f64();
        let ours = name.starts_with("ours");
        let (support, free, valid, aligned) = fit(&poses, &path.points, !ours)?;
        let o = Outcome {
            reached: path.reached,
            no_route: path.exhausted,
            relaxed: path.relaxed,
            dist_m: path.final_distance as f64,
            seconds,
            path_ratio: if path.reached && shortest > 0.0 {
                path.length() as f64 / shortest
            } else {
                f64::NAN
            },
            support,
            free,
            valid,
        };
        out.push((name, o, path.points, aligned));
    }
    Ok(out)
}

fn region_of(vae: &Cvae, scene: &Scene, samples: usize, seed: u64) -> Result<AccessibleRegion> {
    let cloud: Vec<[f32; 3]> = sample_surface(scene, vae.cloud_points(), seed)?
        .iter()
        .map(|p| [p.x, p.y, p.z])
        .collect();
    let drawn = vae.sample(&cloud, samples, seed)?;
    Ok(AccessibleRegion::from_drawn(
        scene,
        &drawn,
        &RegionConfig::default(),
    )?)
}

/// A top-down picture: accessible columns light, the rest dark, every planner's path in its
/// colour, start green and goal magenta.
fn top_png(region: &AccessibleRegion, paths: &[(&str, Vec<Point3m>)], path: &Path) -> Result<()> {
    let [nx, ny, nz] = region.frame.shape;
    let s = 6u32;
    let mut img =
        image::RgbImage::from_pixel(nx as u32 * s, ny as u32 * s, image::Rgb([40, 40, 48]));
    for x in 0..nx {
        for y in 0..ny {
            if (0..nz).any(|z| region.grid.is_free(Cell3::new(x, y, z))) {
                for px in 0..s {
                    for py in 0..s {
                        img.put_pixel(
                            x as u32 * s + px,
                            (ny - 1 - y) as u32 * s + py,
                            image::Rgb([225, 232, 220]),
                        );
                    }
                }
            }
        }
    }
    let to_px = |p: Point3m| {
        let x = (p[0] - region.frame.origin.x) / region.frame.voxel * s as f32;
        let y =
            (ny as f32 * s as f32) - (p[1] - region.frame.origin.y) / region.frame.voxel * s as f32;
        (x, y)
    };
    let dot = |img: &mut image::RgbImage, (x, y): (f32, f32), r: i32, c: [u8; 3]| {
        for dx in -r..=r {
            for dy in -r..=r {
                let (px, py) = (x as i32 + dx, y as i32 + dy);
                if px >= 0 && py >= 0 && (px as u32) < img.width() && (py as u32) < img.height() {
                    img.put_pixel(px as u32, py as u32, image::Rgb(c));
                }
            }
        }
    };
    for (name, pts) in paths {
        let c = planner_colour(name);
        for w in pts.windows(2) {
            let (a, b) = (to_px(w[0]), to_px(w[1]));
            let n = ((b.0 - a.0).hypot(b.1 - a.1)).ceil().max(1.0) as usize;
            for i in 0..=n {
                let t = i as f32 / n as f32;
                dot(
                    &mut img,
                    (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)),
                    1,
                    c,
                );
            }
        }
    }
    if let Some((_, pts)) = paths.first() {
        if let (Some(&a), Some(&b)) = (pts.first(), pts.last()) {
            dot(&mut img, to_px(a), 4, [30, 200, 30]);
            dot(&mut img, to_px(b), 4, [220, 30, 220]);
        }
    }
    write_png(img, path)
}

/// A picture of the room from above and behind one wall, looking down into it: each pixel one ray cast
/// with the scene's own ray queries, surfaces shaded by a light from above, coloured by what
/// they are; every planner's first path and a few of ours' poses drawn where they are not
/// hidden.
fn render_png(
    scene: &Scene,
    paths: &[(&str, Vec<Point3m>)],
    skeletons: &[envfield::affordance::Pose],
    path: &Path,
) -> Result<()> {
    use envfield::scene::nalgebra::Vector3;
    use rayon::prelude::*;
    let aabb = scene.aabb().context("the scene is empty")?;
    let (lo, hi) = (aabb.mins, aabb.maxs);
    let centre = Point3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0 + 0.3, 0.3);
    // Above and behind the near wall, high enough to see over it into the room.
    let eye = Point3::new(centre.x, lo.y - 0.8, hi.z + 3.5);
    let forward = (centre - eye).normalize();
    let right = forward.cross(&Vector3::z()).normalize();
    let up = right.cross(&forward);
    let (w, h) = (640usize, 440usize);
    let focal = 0.75 * w as f32;
    let ray = |px: f32, py: f32| {
        (forward + right * ((px - w as f32 / 2.0) / focal) - up * ((py - h as f32 / 2.0) / focal))
            .normalize()
    };
    let light = Vector3::new(0.3, -0.4, 1.0).normalize();
    let hits: Vec<(f32, [u8; 3])> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let d = ray((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            match scene.cast_ray(&eye, &d, 50.0).ok().flatten() {
                Some(hit) => {
                    let base: [f32; 3] = match scene.objects()[hit.object].kind {
                        envfield::scene::ObjectKind::Floor => [0.78, 0.74, 0.68],
                        envfield::scene::ObjectKind::Wall => [0.86, 0.86, 0.88],
                        envfield::scene::ObjectKind::Bed => [0.45, 0.55, 0.75],
                        envfield::scene::ObjectKind::Sofa => [0.65, 0.40, 0.35],
                        envfield::scene::ObjectKind::Chair => [0.55, 0.45, 0.30],
                        _ => [0.60, 0.52, 0.42],
                    };
                    let shade = 0.35 + 0.65 * hit.normal.dot(&light).abs();
                    (
                        hit.distance,
                        base.map(|c| (255.0 * c * shade).min(255.0) as u8),
                    )
                }
                None => (f32::INFINITY, [30, 30, 36]),
            }
        })
        .collect();
    let mut img = image::RgbImage::new(w as u32, h as u32);
    for (i, (_, c)) in hits.iter().enumerate() {
        img.put_pixel((i % w) as u32, (i / w) as u32, image::Rgb(*c));
    }
    // A point's pixel and depth along its ray, when in front of the camera.
    let project = |p: Point3<f32>| -> Option<(f32, f32, f32)> {
        let v = p - eye;
        let z = v.dot(&forward);
        (z > 0.05).then(|| {
            (
                w as f32 / 2.0 + focal * v.dot(&right) / z,
                h as f32 / 2.0 - focal * v.dot(&up) / z,
                v.norm(),
            )
        })
    };
    let segment = |img: &mut image::RgbImage, a: Point3<f32>, b: Point3<f32>, c: [u8; 3]| {
        let n = 40;
        for k in 0..=n {
            let p = a + (b - a) * (k as f32 / n as f32);
            if let Some((x, y, depth)) = project(p) {
                let (xi, yi) = (x as i64, y as i64);
                if xi < 0 || yi < 0 || xi >= w as i64 || yi >= h as i64 {
                    continue;
                }
                if depth <= hits[yi as usize * w + xi as usize].0 + 0.05 {
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let (px, py) = ((xi + dx).min(w as i64 - 1), (yi + dy).min(h as i64 - 1));
                        img.put_pixel(px as u32, py as u32, image::Rgb(c));
                    }
                }
            }
        }
    };
    for (name, pts) in paths {
        let c = planner_colour(name);
        for pair in pts.windows(2) {
            segment(&mut img, point(pair[0]), point(pair[1]), c);
        }
    }
    for pose in skeletons {
        for j in envfield::affordance::Joint::ALL {
            if let Some(parent) = j.parent() {
                segment(&mut img, pose.joint(j), pose.joint(parent), [20, 20, 20]);
            }
        }
    }
    write_png(img, path)
}

/// Encodes `img` as PNG and writes it atomically.
fn write_png(img: image::RgbImage, path: &Path) -> Result<()> {
    let mut bytes = Vec::new();
    image::DynamicImage::ImageRgb8(img).write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )?;
    envfield::grid::write_atomic(path, &bytes)?;
    Ok(())
}

/// Each planner's colour in the pictures.
fn planner_colour(name: &str) -> [u8; 3] {
    match name {
        "ours" => [220, 30, 30],
        "ours_raw" => [140, 20, 20],
        "ours_noaff" => [250, 150, 30],
        "ours_exact" => [30, 160, 60],
        "rrt" => [40, 90, 220],
        "rrtstar" => [130, 60, 200],
        "rrtstar_big" => [200, 80, 200],
        "prm" => [20, 170, 190],
        _ => [90, 90, 90],
    }
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.rooms == 0 || args.rooms > 1000 || args.pairs > 10_000 || args.samples == 0 {
        bail!("--rooms 1..=1000, --pairs up to 10000 and --samples >= 1");
    }
    for (flag, b) in [("--budget", args.budget), ("--sit-budget", args.sit_budget)] {
        if !(b.is_finite() && b > 0.0 && b <= 10_000.0) {
            bail!("{flag} must be in (0, 10000] (got {b})");
        }
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    envfield::grid::check_writable(args.out.join("top.png"))?;
    let vae_file = args
        .vae
        .clone()
        .unwrap_or_else(|| root().join("models/vae.safetensors"));
    let vae =
        Cvae::load(&vae_file).with_context(|| format!("loading the VAE {}", vae_file.display()))?;
    let mut all: BTreeMap<&str, Vec<(&'static str, Outcome)>> = BTreeMap::new();
    let mut field_s = Vec::new();
    let mut pair_count = 0usize;
    for k in 0..args.rooms {
        let seed = args.seed + k;
        let (scene, room) = match &args.scene {
            Some(f) => (Scene::from_mesh("scene", &TriangleMesh::read(f)?)?, None),
            None => {
                let r = generate_room(&RoomConfig::default(), seed)?;
                (r.scene.clone(), Some(r))
            }
        };
        let region = region_of(&vae, &scene, args.samples, seed)?;
        let cached = args
            .fields
            .as_ref()
            .filter(|_| args.scene.is_none())
            .map(|d| {
                d.join(format!(
                    "room_field_{seed}_{:016x}_{}.safetensors",
                    region_key(&region),
                    args.field_steps
                ))
            });
        let file = args
            .field
            .clone()
            .or_else(|| cached.clone().filter(|p| p.is_file()))
            .or_else(|| shipped_field(seed).filter(|_| args.scene.is_none()));
        let net = match file {
            Some(f) if k == 0 || args.field.is_none() => {
                if cached.as_ref() == Some(&f) {
                    eprintln!("room {seed}: field loaded from {}", f.display());
                }
                let net = FieldNet::load(&f)?;
                let shape = region.frame.shape.to_vec();
                match net.config() {
                    envfield::nets::ModelConfig::Goal(c) if c.extent == shape => net,
                    _ => bail!(
                        "{}: this field was trained on another region (the VAE or the room \
                         changed); train it again with --field-steps",
                        f.display()
                    ),
                }
            }
            _ => {
                let bar = ProgressBar::new(args.field_steps)
                    .with_message(format!("room {seed}: 3D field"));
                bar.set_style(ProgressStyle::with_template(
                    "{msg:>24} {bar:30} {pos}/{len} {elapsed_precise} (eta {eta})",
                )?);
                let cfg = Field3Config {
                    steps: args.field_steps,
                    seed,
                    ..Field3Config::default()
                };
                let (net, report) =
                    train_field3(&region, &cfg, None, |s, _, _| bar.set_position(s))?;
                bar.finish_and_clear();
                eprintln!(
                    "room {seed}: learned field, median error {:.3} m, p95 {:.3} m, {:.0} s",
                    report.median_err_m, report.p95_err_m, report.train_s
                );
                field_s.push(report.train_s);
                if let (Some(p), 1) = (&args.save_field, args.rooms) {
                    net.save(p)?;
                }
                if let Some(p) = &cached {
                    let dir = p.parent().expect("a folder");
                    std::fs::create_dir_all(dir)
                        .with_context(|| format!("--fields: creating {}", dir.display()))?;
                    net.save(p)?;
                    eprintln!("room {seed}: field kept in {}", p.display());
                }
                net
            }
        };
        let ps = pairs(room.as_ref(), &scene, &region, args.pairs, seed)?;
        for (i, pair) in ps.iter().enumerate() {
            let results = run_pair(
                &scene,
                &region,
                &net,
                pair,
                args.big_budget,
                if pair.repeat {
                    args.budget
                } else {
                    args.sit_budget
                },
                seed + i as u64,
            )?;
            if k == 0 && i == 0 {
                scene.to_mesh().write(args.out.join("scene.obj"))?;
                region.write_ply(args.out.join("region.ply"))?;
                let mut drawn = Vec::new();
                for (name, _, pts, aligned) in &results {
                    let line: Vec<Point3<f32>> = pts.iter().map(|&p| point(p)).collect();
                    if line.len() > 1 {
                        write_polyline_obj(&line, args.out.join(format!("path_{name}.obj")))?;
                    }
                    aligned.write(args.out.join(format!("poses_{name}.json")))?;
                    drawn.push((*name, pts.clone()));
                }
                top_png(&region, &drawn, &args.out.join("top.png"))?;
                // A few of ours' poses, evenly along its path.
                let ours = &results[0].3;
                let skeletons: Vec<_> = (0..5)
                    .map(|j| ours.frames[j * (ours.frames.len() - 1) / 4])
                    .collect();
                render_png(&scene, &drawn, &skeletons, &args.out.join("room.png"))?;
            }
            for (name, o, _, _) in results {
                all.entry(pair.kind).or_default().push((name, o));
            }
            pair_count += 1;
        }
    }
    // Summaries: per planner over all pairs (Table 3), and per kind (Table 4).
    let mut line = serde_json::json!({"rooms": args.rooms, "pairs": pair_count});
    let mean = |v: &[f64]| {
        let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        (!f.is_empty()).then(|| f.iter().sum::<f64>() / f.len() as f64)
    };
    if !args.json {
        println!("Table 3: {pair_count} pairs in {} room(s)", args.rooms);
        println!(
            "{:<12} {:>9} {:>10} {:>11} {:>11}",
            "planner", "reach %", "dist (m)", "s/path", "path ratio"
        );
    }
    for name in PLANNERS {
        let os: Vec<&Outcome> = all
            .values()
            .flatten()
            .filter(|(n, _)| *n == name)
            .map(|(_, o)| o)
            .collect();
        let n = os.len().max(1) as f64;
        let reach = 100.0 * os.iter().filter(|o| o.reached).count() as f64 / n;
        let dist = mean(&os.iter().map(|o| o.dist_m).collect::<Vec<_>>());
        let secs = mean(&os.iter().map(|o| o.seconds).collect::<Vec<_>>());
        let ratio = mean(&os.iter().map(|o| o.path_ratio).collect::<Vec<_>>());
        let sup = mean(&os.iter().map(|o| o.support).collect::<Vec<_>>());
        let free = mean(&os.iter().map(|o| o.free).collect::<Vec<_>>());
        let valid = mean(&os.iter().map(|o| o.valid).collect::<Vec<_>>());
        line[format!("{name}_reach_pct")] = reach.into();
        if name.starts_with("ours") {
            let none = 100.0 * os.iter().filter(|o| o.no_route).count() as f64 / n;
            line[format!("{name}_no_route_pct")] = none.into();
            let relaxed = 100.0 * os.iter().filter(|o| o.relaxed).count() as f64 / n;
            line[format!("{name}_relaxed_pct")] = relaxed.into();
        }
        line[format!("{name}_dist_m")] = dist.into();
        line[format!("{name}_s")] = secs.into();
        line[format!("{name}_path_ratio")] = ratio.into();
        line[format!("{name}_support_pct")] = sup.into();
        line[format!("{name}_free_pct")] = free.into();
        line[format!("{name}_valid_pct")] = valid.into();
        if !args.json {
            println!(
                "{name:<12} {reach:>9.1} {:>10.3} {:>11.5} {:>11}",
                dist.unwrap_or(f64::NAN),
                secs.unwrap_or(f64::NAN),
                ratio.map_or("-".into(), |r| format!("{r:.3}"))
            );
        }
    }
    if !args.json {
        println!("\nTable 4: aligned poses, percent supported / collision-free / valid");
    }
    for (kind, results) in &all {
        let mut per = serde_json::Map::new();
        for name in PLANNERS {
            let os: Vec<&Outcome> = results
                .iter()
                .filter(|(n, _)| *n == name)
                .map(|(_, o)| o)
                .collect();
            let m = |f: fn(&Outcome) -> f64| mean(&os.iter().map(|o| f(o)).collect::<Vec<_>>());
            let (s, f, v) = (m(|o| o.support), m(|o| o.free), m(|o| o.valid));
            let reach = m(|o| if o.reached { 100.0 } else { 0.0 });
            if !args.json {
                println!(
                    "{kind:<5} {name:<12} {:>6.1} {:>6.1} {:>6.1}  ({} pairs, {:.0}% reached)",
                    s.unwrap_or(f64::NAN),
                    f.unwrap_or(f64::NAN),
                    v.unwrap_or(f64::NAN),
                    os.len(),
                    reach.unwrap_or(f64::NAN)
                );
            }
            per.insert(name.into(), serde_json::json!({"support_pct": s, "free_pct": f, "valid_pct": v, "reach_pct": reach, "pairs": os.len()}));
        }
        line[format!("table4_{kind}")] = per.into();
    }
    line["field_train_s_per_room"] = mean(&field_s).into();
    println!("{line}");
    Ok(())
}
