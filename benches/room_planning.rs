//! The room planners' costs in one criterion run, split as a navigation mesh splits them, on
//! generated room 10000 (never seen by the VAE) with the region the shipped gated VAE gives it
//! (as `room_nav` makes it):
//!
//! - per room: the scene's distance grid and surface columns that ours' pose checks read, and the navigation
//!   mesh's build (Recast's pipeline in Rust and Polyanya's import);
//! - per goal: the exact field's fast marching over the region's voxels (and, for the ratio,
//!   over its whole box; and as a walk marches it, to its start and 1 m past, over the ways at
//!   most 1 m longer than the shortest), and the learned field's one batched pass over the region (pinned to
//!   its goal, as `room_nav` makes it);
//! - per walking path, four pairs taken in turn: ours on the learned field's table, ours on
//!   the exact field with its fast marching (as `room_nav` marches it) inside each call
//!   (`ours_exact_with_goal`), the paper's search alone (a network pass per step), ours
//!   without affordance, the navigation mesh's query, PRM with its roadmap, RRT* at 500 / 5000 iterations and RRT;
//! - per sit-down path (every seat of the room its region reaches): ours on the exact field
//!   with its fast marching, ours on the learned field's table, PRM and RRT*;
//! - per walking path on real-furniture room 10000 (Sweet Home 3D's models, when
//!   `scripts/fetch_sweethome3d.sh` has fetched them; its field trained first, about 80 s):
//!   ours on the learned field's table, ours on the exact field with its fast marching, PRM.
//!
//! `cargo bench --bench room_planning`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use envfield::eikonal::{FastMarching, Order};
use envfield::grid::{Cell3, ContinuousField3};
use envfield::nets::FieldNet;
use envfield::rooms::harness::{
    learned_table, pairs, FloorPlanner, Pair, PairOptions, PairSetup, RoomContext, RoomPlanner,
    RunSettings, EXACT_BAND,
};
use envfield::rooms::nav::{BENEATH_CELL, DISTANCE_CELL};
use envfield::rooms::{
    sample_region, train_field3, AccessibleRegion, ExactField3, Field3Config, LearnedField3,
    SceneTables, VoxelField3,
};
use envfield::scene::{catalogue_room, generate_room, Catalogue, Room, RoomConfig};
use envfield::scene::{DistanceGrid, SurfaceColumns};
use envfield::vae::Cvae;
use envfield_examples::{Navmesh, NavmeshConfig};
use std::hint::black_box;
use std::path::Path;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// A pair with its goal voxel and shortest walk (metres).
struct Timed {
    pair: Pair,
    goal: Cell3,
    shortest: f64,
}

/// Four walking pairs at least 2 m apart along the exact field, drawn as `room_nav` draws
/// its pairs.
fn walking_pairs(room: &Room, region: &AccessibleRegion, seed: u64) -> Vec<Timed> {
    let options = PairOptions {
        walks: 4,
        min_distance: 2.0,
        sit_downs: false,
        seed,
        ..PairOptions::default()
    };
    timed(
        pairs(Some(room), &room.scene, region, &options).expect("pairs"),
        region,
    )
}

/// The sit-down pairs of the room's seats in `region`.
fn sitting_pairs(room: &Room, region: &AccessibleRegion, seed: u64) -> Vec<Timed> {
    let options = PairOptions {
        walks: 0,
        seed,
        ..PairOptions::default()
    };
    timed(
        pairs(Some(room), &room.scene, region, &options).expect("pairs"),
        region,
    )
}

/// Each pair with its goal's voxel and its shortest distance, where the exact field finds one.
fn timed(pairs: Vec<Pair>, region: &AccessibleRegion) -> Vec<Timed> {
    pairs
        .into_iter()
        .filter_map(|pair| {
            let goal = region.cell(pair.goal, "goal").ok()?;
            let d = ExactField3::at_cell(region, goal)
                .ok()?
                .value(pair.start)
                .ok()?;
            d.is_finite().then_some(Timed {
                pair,
                goal,
                shortest: d as f64,
            })
        })
        .collect()
}

/// Ours' learned table for each pair's goal, as `room_nav` makes it.
fn learned_tables(net: &FieldNet, region: &AccessibleRegion, pairs: &[Timed]) -> Vec<VoxelField3> {
    pairs
        .iter()
        .map(|t| {
            let learned = LearnedField3::new(net, region, t.goal).expect("learned");
            learned_table(&learned, region).expect("table")
        })
        .collect()
}

/// What every path of a room shares: the room, a region, the distance grid, the navigation
/// mesh.
struct Shared<'a> {
    room: &'a Room,
    region: &'a AccessibleRegion,
    tables: &'a SceneTables,
    navmesh: &'a dyn FloorPlanner,
}

impl Shared<'_> {
    /// One path of `planner` on pair `t` (its field made before, as in `room_nav`), `budget`
    /// expansions per step of the shortest walk.
    fn plan(
        &self,
        planner: RoomPlanner,
        t: &Timed,
        field: Option<&dyn ContinuousField3>,
        budget: f64,
    ) -> bool {
        let settings = RunSettings {
            budget,
            sit_budget: budget,
            ..RunSettings::default()
        };
        let mut setup = PairSetup::new(
            &self.room.scene,
            self.region,
            Some(self.tables),
            &t.pair,
            t.shortest,
            &settings,
        );
        setup.navmesh = Some(self.navmesh);
        let path = planner
            .plan(&setup, field, t.pair.start, t.pair.goal)
            .expect("plan");
        black_box(path).reached
    }
}

impl Shared<'_> {
    /// One path of `planner` on pair `t` at room_nav's budget (50 expansions per step): ours
    /// on the exact field marches it inside the call, ours on the learned field reads `table`.
    fn plan_marching(&self, planner: RoomPlanner, t: &Timed, table: Option<&VoxelField3>) -> bool {
        match planner {
            RoomPlanner::OursExact => {
                let field = ExactField3::toward(self.region, t.goal, t.pair.start, EXACT_BAND)
                    .expect("field");
                self.plan(planner, t, Some(&field), 50.0)
            }
            RoomPlanner::Ours => {
                let table = table.expect("ours needs its learned table");
                self.plan(planner, t, Some(table), 50.0)
            }
            _ => self.plan(planner, t, None, 50.0),
        }
    }
}

fn bench_rooms(c: &mut Criterion) {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    let vae = Cvae::load(models.join("vae_gated.safetensors")).expect("the shipped VAE");
    let net =
        FieldNet::load(models.join("room_field_10000.safetensors")).expect("the shipped field");
    let seed = 10_000;
    let room = generate_room(&RoomConfig::default(), seed).expect("room");
    // The region exactly as room_nav makes it.
    let region = sample_region(&vae, &room.scene, 6000, seed).expect("region");
    let walks = walking_pairs(&room, &region, seed);
    let (scene_tables, _) = RoomContext::tables(&room.scene).expect("tables");
    let config = NavmeshConfig::for_gait(&walks[0].pair.sequence);
    let navmesh = Navmesh::build(&room.scene, &config).expect("navmesh");
    eprintln!(
        "navigation mesh: {} polygons, {} vertices, {} bytes, built in {:.1} ms ({config:?})",
        navmesh.polygons,
        navmesh.vertices,
        navmesh.bytes(),
        1e3 * navmesh.build_s
    );

    let mut group = c.benchmark_group("room_planning");
    group.sample_size(10);
    group.bench_function("room/distance_grid", |b| {
        b.iter(|| black_box(DistanceGrid::around(&room.scene, 0.2, DISTANCE_CELL).expect("grid")))
    });
    group.bench_function("room/surface_columns", |b| {
        b.iter(|| {
            black_box(SurfaceColumns::around(&room.scene, 0.2, BENEATH_CELL).expect("columns"))
        })
    });
    group.bench_function("room/navmesh_build", |b| {
        b.iter(|| black_box(Navmesh::build(&room.scene, &config).expect("navmesh")))
    });
    group.bench_function("goal/exact_fast_marching", |b| {
        let mut i = 0;
        b.iter(|| {
            i += 1;
            black_box(ExactField3::at_cell(&region, walks[i % walks.len()].goal).expect("field"))
        })
    });
    // The march as a walk makes it: to the start and a metre past it, over the ways at most
    // a metre longer than the shortest.
    group.bench_function("goal/exact_fast_marching_toward_start", |b| {
        let mut i = 0;
        b.iter(|| {
            i += 1;
            let t = &walks[i % walks.len()];
            black_box(
                ExactField3::toward(&region, t.goal, t.pair.start, EXACT_BAND).expect("field"),
            )
        })
    });
    // The same march over the region's whole box (the dense solve), for the ratio.
    group.bench_function("goal/exact_fast_marching_dense", |b| {
        let fmm = FastMarching {
            order: Order::Second,
            spacing: region.frame.voxel,
            ..FastMarching::default()
        };
        let mut i = 0;
        b.iter(|| {
            i += 1;
            let goal = walks[i % walks.len()].goal;
            black_box(fmm.solve3(&region.grid, &[goal]).expect("field"))
        })
    });
    group.bench_function("goal/learned_table", |b| {
        let mut i = 0;
        b.iter(|| {
            i += 1;
            let learned = LearnedField3::new(&net, &region, walks[i % walks.len()].goal);
            black_box(
                learned
                    .and_then(|l| learned_table(&l, &region))
                    .expect("table"),
            )
        })
    });
    let exact: Vec<ExactField3> = walks
        .iter()
        .map(|t| ExactField3::at_cell(&region, t.goal).expect("field"))
        .collect();
    let tables = learned_tables(&net, &region, &walks);
    let n = walks.len();
    let walking = Shared {
        room: &room,
        region: &region,
        tables: &scene_tables,
        navmesh: &navmesh,
    };
    let rows = [
        ("ours", RoomPlanner::Ours),
        ("ours_exact", RoomPlanner::OursExact),
        ("ours_exact_with_goal", RoomPlanner::OursExact),
        ("ours_raw", RoomPlanner::OursRaw),
        ("ours_noaff", RoomPlanner::OursNoAff),
        ("navmesh", RoomPlanner::Navmesh),
        ("prm", RoomPlanner::Prm),
        ("rrtstar", RoomPlanner::RrtStar),
        ("rrtstar_5000", RoomPlanner::RrtStarBig),
        ("rrt", RoomPlanner::Rrt),
    ];
    for (name, planner) in rows {
        group.bench_function(BenchmarkId::new(format!("walk/{name}"), n), |b| {
            let mut i = 0;
            b.iter(|| {
                let k = i % n;
                i += 1;
                let t = &walks[k];
                // room_nav's budget: 50 expansions per step of the shortest walk.
                match name {
                    "ours_exact_with_goal" => walking.plan_marching(planner, t, None),
                    "ours_raw" => {
                        let field = LearnedField3::new(&net, &region, t.goal).expect("learned");
                        walking.plan(planner, t, Some(&field), 50.0)
                    }
                    _ => {
                        let field: Option<&dyn ContinuousField3> = match planner {
                            RoomPlanner::OursExact => Some(&exact[k]),
                            RoomPlanner::Ours | RoomPlanner::OursNoAff => Some(&tables[k]),
                            _ => None,
                        };
                        walking.plan(planner, t, field, 50.0)
                    }
                }
            })
        });
    }

    // Sit-down pairs: every seat of the room whose sit-down start and seated torso lie in
    // (or within SEAT_NEAR of) the region.
    let sits = sitting_pairs(&room, &region, seed);
    if sits.is_empty() {
        eprintln!("no sit-down pair in room {seed}: its region holds no seat");
    } else {
        let m = sits.len();
        eprintln!("sit-down pairs: {m} in room {seed}");
        for (name, planner) in [
            ("ours_exact_with_goal", RoomPlanner::OursExact),
            ("ours", RoomPlanner::Ours),
            ("prm", RoomPlanner::Prm),
            ("rrtstar", RoomPlanner::RrtStar),
        ] {
            let tables = if planner == RoomPlanner::Ours {
                learned_tables(&net, &region, &sits)
            } else {
                Vec::new()
            };
            group.bench_function(BenchmarkId::new(format!("sit/{name}"), m), |b| {
                let mut i = 0;
                b.iter(|| {
                    let k = i % m;
                    i += 1;
                    let t = &sits[k];
                    // room_nav's sit-down budget: 50 expansions per step.
                    walking.plan_marching(planner, t, tables.get(k))
                })
            });
        }
    }
    bench_real(&mut group, &vae, seed);
    group.finish();
}

/// The walking rows of ours and PRM on real-furniture room `seed` (Sweet Home 3D's models),
/// when the catalogue is fetched (`scripts/fetch_sweethome3d.sh`); its learned field is
/// trained here first, as `room_nav` trains it (the same weights).
fn bench_real(
    group: &mut criterion::BenchmarkGroup<criterion::measurement::WallTime>,
    vae: &Cvae,
    seed: u64,
) {
    let Some(dir) = Catalogue::find() else {
        eprintln!("no catalogue (scripts/fetch_sweethome3d.sh): no real-furniture rows");
        return;
    };
    let catalogue = Catalogue::read(dir).expect("the catalogue");
    let room = catalogue_room(&catalogue, &RoomConfig::catalogue(), seed).expect("room");
    let region = sample_region(vae, &room.scene, 6000, seed).expect("region");
    let config = Field3Config {
        seed,
        ..Field3Config::default()
    };
    eprintln!(
        "real-furniture room {seed}: training its field ({} steps)",
        config.steps
    );
    let (net, _) = train_field3(&region, &config, None, |_, _, _| {}).expect("field");
    let walks = walking_pairs(&room, &region, seed);
    let (scene_tables, _) = RoomContext::tables(&room.scene).expect("tables");
    let navmesh = Navmesh::build(
        &room.scene,
        &NavmeshConfig::for_gait(&walks[0].pair.sequence),
    )
    .expect("navmesh");
    let shared = Shared {
        room: &room,
        region: &region,
        tables: &scene_tables,
        navmesh: &navmesh,
    };
    let tables = learned_tables(&net, &region, &walks);
    let n = walks.len();
    for (name, planner) in [
        ("ours", RoomPlanner::Ours),
        ("ours_exact_with_goal", RoomPlanner::OursExact),
        ("prm", RoomPlanner::Prm),
    ] {
        group.bench_function(BenchmarkId::new(format!("real_walk/{name}"), n), |b| {
            let mut i = 0;
            b.iter(|| {
                let k = i % n;
                i += 1;
                let t = &walks[k];
                shared.plan_marching(planner, t, tables.get(k))
            })
        });
    }
}

criterion_group!(benches, bench_rooms);
criterion_main!(benches);
