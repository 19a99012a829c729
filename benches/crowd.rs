//! Time per time step of several people walking at once on a 64x64 floor map (0.1 m cells),
//! for 2, 4 and 8 people: Algorithm 1 on the shipped bird's-eye field (one batched prediction
//! for everyone's changed map), the same loop on the exact solver (fast marching on each
//! changed map), and ORCA. Each loop is first walked three steps from the starts, so the step
//! timed is one with people under way; the timed step starts from a clone of that state.
//!
//! `crowd_step_16_32`: one time step of our step rule (PIBT over the fields' steps,
//! `PibtCrowd`) beside Algorithm 1's, for 16 people on a generated 4-6 m room and 32 on an
//! 8 x 7 m one, each on the shipped field and on the exact one.
//!
//! `cargo bench --bench crowd`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion};
use envfield::eikonal::FastMarching;
use envfield::nets::FieldNet;
use envfield::plan::crowd::{random_trips, Crowd, CrowdConfig, OrcaConfig, OrcaCrowd, PibtCrowd};
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

fn bench_many(c: &mut Criterion) {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    let net = FieldNet::load(models.join("birdseye.safetensors")).expect("the shipped field");
    let exact = FastMarching::default();
    let config = CrowdConfig::default();
    let large = RoomConfig {
        width: [8.0, 8.0],
        depth: [7.0, 7.0],
        ..RoomConfig::birdseye()
    };
    let mut group = c.benchmark_group("crowd_step_16_32");
    for (people, rooms, seed) in [
        (16usize, RoomConfig::birdseye(), 5_001u64),
        (32, large, 5_002),
    ] {
        let room = generate_room(&rooms, seed).expect("room");
        let map = floor_map(
            &room.scene,
            &FloorMapConfig {
                resolution: 0.1,
                ..FloorMapConfig::default()
            },
        )
        .expect("floor map");
        let fits = map.grid.rows() <= 64 && map.grid.cols() <= 64;
        let walkable = map
            .walkable(0.25, fits.then_some([64, 64]))
            .expect("walkable map");
        let trips = random_trips(&walkable, people, &config, 10.0, seed).expect("trips");
        let mut ours = PibtCrowd::new(&walkable, &trips, &net, &config).expect("crowd");
        let mut ours_exact = PibtCrowd::new(&walkable, &trips, &exact, &config).expect("crowd");
        let mut alg1 = Crowd::new(&walkable, &trips, &net, &config).expect("crowd");
        let mut alg1_exact = Crowd::new(&walkable, &trips, &exact, &config).expect("crowd");
        for _ in 0..3 {
            ours.step().expect("step");
            ours_exact.step().expect("step");
            alg1.step().expect("step");
            alg1_exact.step().expect("step");
        }
        group.bench_with_input(BenchmarkId::new("ours", people), &people, |b, _| {
            b.iter_batched(
                || ours.clone(),
                |mut crowd| crowd.step().expect("step"),
                BatchSize::SmallInput,
            )
        });
        group.bench_with_input(BenchmarkId::new("ours_exact", people), &people, |b, _| {
            b.iter_batched(
                || ours_exact.clone(),
                |mut crowd| crowd.step().expect("step"),
                BatchSize::SmallInput,
            )
        });
        group.bench_with_input(BenchmarkId::new("alg1", people), &people, |b, _| {
            b.iter_batched(
                || alg1.clone(),
                |mut crowd| crowd.step().expect("step"),
                BatchSize::SmallInput,
            )
        });
        group.bench_with_input(BenchmarkId::new("alg1_exact", people), &people, |b, _| {
            b.iter_batched(
                || alg1_exact.clone(),
                |mut crowd| crowd.step().expect("step"),
                BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, bench_crowd, bench_many);
criterion_main!(benches);
