//! Time per time step of several people walking at once on a 64x64 floor map (0.1 m cells),
//! for 2, 4 and 8 people: Algorithm 1 on the shipped bird's-eye field (one batched prediction
//! for everyone's changed map), the same loop on the exact solver (fast marching on each
//! changed map), and ORCA. Each loop is first walked three steps from the starts, so the step
//! timed is one with people under way; the timed step starts from a clone of that state.
//!
//! `cargo bench --bench crowd`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion};
use envfield::eikonal::FastMarching;
use envfield::nets::FieldNet;
use envfield::plan::crowd::{random_trips, Crowd, CrowdConfig, OrcaConfig, OrcaCrowd};
use envfield::scene::{floor_map, generate_room, FloorMapConfig, RoomConfig};
use std::path::Path;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench_crowd(c: &mut Criterion) {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    let net = FieldNet::load(models.join("birdseye.safetensors")).expect("the shipped field");
    let exact = FastMarching::default();
    let room = generate_room(&RoomConfig::birdseye(), 5_000).expect("room");
    let map = floor_map(
        &room.scene,
        &FloorMapConfig {
            resolution: 0.1,
            ..FloorMapConfig::default()
        },
    )
    .expect("floor map");
    let walkable = map.walkable(0.25, Some([64, 64])).expect("walkable map");
    let config = CrowdConfig::default();
    let mut group = c.benchmark_group("crowd_step_64x64");
    for people in [2usize, 4, 8] {
        let trips = random_trips(&walkable, people, &config, 10.0, 5_000).expect("trips");
        let mut learned = Crowd::new(&walkable, &trips, &net, &config).expect("crowd");
        let mut fmm = Crowd::new(&walkable, &trips, &exact, &config).expect("crowd");
        let mut orca =
            OrcaCrowd::new(&walkable, &trips, &config, &OrcaConfig::default()).expect("crowd");
        for _ in 0..3 {
            learned.step().expect("step");
            fmm.step().expect("step");
            orca.step();
        }
        group.bench_with_input(BenchmarkId::new("learned", people), &people, |b, _| {
            b.iter_batched(
                || learned.clone(),
                |mut crowd| crowd.step().expect("step"),
                BatchSize::SmallInput,
            )
        });
        group.bench_with_input(BenchmarkId::new("exact", people), &people, |b, _| {
            b.iter_batched(
                || fmm.clone(),
                |mut crowd| crowd.step().expect("step"),
                BatchSize::SmallInput,
            )
        });
        group.bench_with_input(BenchmarkId::new("orca", people), &people, |b, _| {
            b.iter_batched(
                || orca.clone(),
                |mut crowd| crowd.step(),
                BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, bench_crowd);
criterion_main!(benches);
