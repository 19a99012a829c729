//! Time per trajectory in a 3D room, every planner of `room_nav`'s Table 3 in one run: ours
//! (the pose-dependent search with its fallback and straight cuts, as `room_nav` runs it) on
//! the shipped learned field and on the exact field, ours without affordance, PRM (its roadmap
//! built inside each call), RRT* at 500, 5000 and 20000 iterations and RRT, on the accessible
//! region the shipped VAE gives generated room 10000, for four walking pairs taken in turn.
//!
//! `cargo bench --bench room_planning`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use envfield::affordance::{walk, Support, WalkConfig};
use envfield::grid::{ContinuousField3, Point3m};
use envfield::nets::FieldNet;
use envfield::plan::{prm, rrt, rrt_star, FieldSearch3, SamplingConfig, StepFilter};
use envfield::scene::{generate_room, sample_surface, RoomConfig};
use envfield::vae::{
    afford, AccessibleRegion, Cvae, ExactField3, LearnedField3, PoseFilter, RegionConfig,
};
use std::hint::black_box;
use std::path::Path;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench_rooms(c: &mut Criterion) {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    let vae = Cvae::load(models.join("vae.safetensors")).expect("the shipped VAE");
    let net =
        FieldNet::load(models.join("room_field_10000.safetensors")).expect("the shipped field");
    let seed = 10_000;
    let room = generate_room(&RoomConfig::default(), seed).expect("room");
    // The region exactly as room_nav makes it.
    let cloud: Vec<[f32; 3]> = sample_surface(&room.scene, vae.cloud_points(), seed)
        .expect("cloud")
        .iter()
        .map(|p| [p.x, p.y, p.z])
        .collect();
    let drawn = vae.sample(&cloud, 6000, seed).expect("samples");
    let config = RegionConfig::default();
    let region = AccessibleRegion::from_drawn(&room.scene, &drawn, &config).expect("region");
    let standing: Vec<Point3m> = region
        .samples
        .iter()
        .copied()
        .filter(|&s| region.contains(s))
        .filter(|&s| {
            afford(&room.scene, s, &config).is_ok_and(|a| a.valid == Some(Support::Standing))
        })
        .collect();
    let gait = walk(&WalkConfig::default(), seed).expect("gait");
    let step = gait.step_length();
    // Four pairs at least 2 m apart that every planner reaches.
    let mut pairs = Vec::new();
    let mut k = 0;
    while pairs.len() < 4 && k < standing.len() * standing.len() {
        let (a, b) = (
            standing[k % standing.len()],
            standing[(k * 7919 + 13) % standing.len()],
        );
        k += 1;
        let exact = ExactField3::new(&region, b).expect("field");
        let d = exact.value(a).expect("value");
        if d.is_finite() && d > 2.0 {
            pairs.push((a, b, region.cell(b, "goal").expect("goal"), d));
        }
    }
    // room_nav's budget: five times the steps of the shortest walk.
    let search = |shortest: f32| FieldSearch3 {
        step,
        tolerance: 0.02,
        max_steps: (5.0 * shortest / step) as usize + 200,
    };
    let poses = PoseFilter {
        scene: &room.scene,
        region: &region,
        sequence: &gait,
        repeat: true,
        face_the_move: true,
        affordance: Default::default(),
    };
    let sampling = SamplingConfig {
        step: step.max(0.05),
        ..SamplingConfig::default()
    };
    let mut group = c.benchmark_group("room_planning");
    group.sample_size(10);
    let names = [
        "ours",
        "ours_exact",
        "ours_noaff",
        "prm",
        "rrtstar",
        "rrtstar_5000",
        "rrtstar_20000",
        "rrt",
    ];
    for name in names {
        group.bench_function(BenchmarkId::new(name, pairs.len()), |b| {
            let mut i = 0;
            b.iter(|| {
                let (start, goal, cell, shortest) = pairs[i % pairs.len()];
                i += 1;
                let search = search(shortest);
                let path = match name {
                    "ours" => {
                        let learned = LearnedField3::new(&net, &region, cell).expect("learned");
                        search.search_relaxed(&learned, &poses, &region, start, goal)
                    }
                    "ours_exact" => {
                        let exact = ExactField3::at_cell(&region, cell).expect("exact");
                        search.search_relaxed(&exact, &poses, &region, start, goal)
                    }
                    "ours_noaff" => {
                        let learned = LearnedField3::new(&net, &region, cell).expect("learned");
                        let f = &region as &dyn StepFilter;
                        search
                            .search(&learned, f, start, goal)
                            .and_then(|raw| search.shortcut(f, &raw, goal))
                    }
                    "prm" => prm(&region, start, goal, &sampling),
                    "rrtstar" => rrt_star(&region, start, goal, &sampling),
                    "rrtstar_5000" | "rrtstar_20000" => rrt_star(
                        &region,
                        start,
                        goal,
                        &SamplingConfig {
                            budget: if name == "rrtstar_5000" { 5000 } else { 20_000 },
                            ..sampling
                        },
                    ),
                    _ => rrt(&region, start, goal, &sampling),
                };
                black_box(path.expect("plan"))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_rooms);
criterion_main!(benches);
