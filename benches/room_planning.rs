//! Time per trajectory in a 3D room, every planner of `room_nav`'s Table 3 in one run: ours
//! (the pose-dependent search with its fallback and straight cuts, as `room_nav` runs it) on
//! the shipped learned field and on the exact field, ours without affordance, PRM (its roadmap
//! built inside each call), RRT* at 500, 5000 and 20000 iterations and RRT, on the accessible
//! region the shipped VAE gives generated room 10000, for four walking pairs taken in turn.
//! Ours on the learned field makes its field of the goal inside each call, and on the exact
//! field its fast marching from the goal.
//!
//! `cargo bench --bench room_planning`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use envfield::affordance::{walk, WalkConfig};
use envfield::grid::ContinuousField3;
use envfield::nets::FieldNet;
use envfield::plan::space3::SamplingConfig;
use envfield::rooms::harness::{standing_places, Pair, PairKind, PairSetup, PlannerKind};
use envfield::rooms::{sample_region, ExactField3, LearnedField3};
use envfield::scene::{generate_room, RoomConfig};
use envfield::vae::Cvae;
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
    let region = sample_region(&vae, &room.scene, 6000, seed).expect("region");
    let standing = standing_places(&room.scene, &region);
    let gait = walk(&WalkConfig::default(), seed).expect("gait");
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
            let pair = Pair {
                start: a,
                goal: b,
                sequence: gait.clone(),
                repeat: true,
                kind: PairKind::Walk,
            };
            pairs.push((pair, region.cell(b, "goal").expect("goal"), d as f64));
        }
    }
    let sampling_seed = SamplingConfig::default().seed;
    let mut group = c.benchmark_group("room_planning");
    group.sample_size(10);
    let rows = [
        ("ours", PlannerKind::Ours, 0),
        ("ours_exact", PlannerKind::OursExact, 0),
        ("ours_noaff", PlannerKind::OursNoAff, 0),
        ("prm", PlannerKind::Prm, 0),
        ("rrtstar", PlannerKind::RrtStar, 0),
        ("rrtstar_5000", PlannerKind::RrtStarBig, 5000),
        ("rrtstar_20000", PlannerKind::RrtStarBig, 20_000),
        ("rrt", PlannerKind::Rrt, 0),
    ];
    for (name, planner, big_budget) in rows {
        group.bench_function(BenchmarkId::new(name, pairs.len()), |b| {
            let mut i = 0;
            b.iter(|| {
                let (pair, cell, shortest) = &pairs[i % pairs.len()];
                i += 1;
                // room_nav's budget: five times the steps of the shortest walk.
                let setup = PairSetup::new(
                    &room.scene,
                    &region,
                    pair,
                    *shortest,
                    5.0,
                    big_budget,
                    sampling_seed,
                );
                let path = match planner.field() {
                    Some(envfield::rooms::harness::FieldKind::Learned) => {
                        let learned = LearnedField3::new(&net, &region, *cell).expect("learned");
                        planner.plan(&setup, Some(&learned), pair.start, pair.goal)
                    }
                    Some(envfield::rooms::harness::FieldKind::Exact) => {
                        let exact = ExactField3::at_cell(&region, *cell).expect("exact");
                        planner.plan(&setup, Some(&exact), pair.start, pair.goal)
                    }
                    None => planner.plan(&setup, None, pair.start, pair.goal),
                };
                black_box(path.expect("plan"))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_rooms);
criterion_main!(benches);
