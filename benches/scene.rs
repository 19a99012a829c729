//! Signed-distance throughput on a generated room of primitives (floor, walls, furniture) and
//! affordance checks per second.
//!
//! `cargo bench --bench scene` (set `RAYON_NUM_THREADS=1` for one core)

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use envfield::affordance::{
    align_to_trajectory, check_pose, check_sequence, standing_pose, walk, AffordanceConfig,
    Support, WalkConfig,
};
use envfield::grid::SplitMix64;
use envfield::scene::nalgebra::{Point3, Vector3};
use envfield::scene::{floor_map, generate_room, FloorMapConfig, RoomConfig};
use std::hint::black_box;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench_sdf(c: &mut Criterion) {
    let room = generate_room(&RoomConfig::default(), 0).expect("room");
    let aabb = *room.scene.aabb().expect("non-empty");
    let mut rng = SplitMix64::new(1);
    let points: Vec<Point3<f32>> = (0..100_000)
        .map(|_| {
            Point3::from(
                aabb.mins.coords
                    + (aabb.maxs - aabb.mins).component_mul(&Vector3::new(
                        rng.next_f32(),
                        rng.next_f32(),
                        rng.next_f32(),
                    )),
            )
        })
        .collect();
    let parts: usize = room.scene.objects().iter().map(|o| o.parts().len()).sum();
    eprintln!(
        "room: {} objects, {parts} parts, {:.1} x {:.1} m",
        room.scene.objects().len(),
        room.size[0],
        room.size[1]
    );
    let mut group = c.benchmark_group("scene_sdf");
    group.throughput(Throughput::Elements(points.len() as u64));
    group.bench_function(BenchmarkId::new("batched_parallel", points.len()), |b| {
        b.iter(|| {
            black_box(
                room.scene
                    .signed_distances(black_box(&points))
                    .expect("sdf"),
            )
        })
    });
    group.bench_function(BenchmarkId::new("one_by_one", points.len()), |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for p in &points {
                sum += room.scene.signed_distance(p).expect("sdf");
            }
            black_box(sum)
        })
    });
    group.finish();
}

fn bench_affordance(c: &mut Criterion) {
    let room = generate_room(&RoomConfig::default(), 0).expect("room");
    let map = floor_map(&room.scene, &FloorMapConfig::default()).expect("map");
    let cells: Vec<_> = map.grid.free_cells().step_by(97).take(1000).collect();
    let poses: Vec<_> = cells
        .iter()
        .map(|&cell| {
            let [x, y] = map.frame.center(cell);
            standing_pose().translated(&Vector3::new(x, y, 0.0))
        })
        .collect();
    let config = AffordanceConfig::default();
    let mut group = c.benchmark_group("affordance");
    group.throughput(Throughput::Elements(poses.len() as u64));
    group.bench_function(BenchmarkId::new("check_pose", poses.len()), |b| {
        b.iter(|| {
            poses
                .iter()
                .filter(|p| {
                    check_pose(&room.scene, p, Support::Standing, &config)
                        .expect("check")
                        .valid()
                })
                .count()
        })
    });
    let gait = walk(&WalkConfig::default(), 0).expect("walk");
    let path: Vec<_> = (0..1000)
        .map(|i| {
            let a = i as f32 * 0.01;
            Point3::new(
                room.size[0] / 2.0 + a.cos(),
                room.size[1] / 2.0 + a.sin(),
                0.0,
            )
        })
        .collect();
    let sequence = align_to_trajectory(&gait, &path, true).expect("align");
    group.bench_function(
        BenchmarkId::new("check_sequence_parallel", path.len()),
        |b| b.iter(|| black_box(check_sequence(&room.scene, &sequence, &config).expect("check"))),
    );
    group.finish();
}

criterion_group!(benches, bench_sdf, bench_affordance);
criterion_main!(benches);
