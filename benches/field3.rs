//! Query throughput of the 3D fields over an accessible region: the exact field (trilinear
//! over fast marching) and the learned goal-conditioned network (one pass per batch), for one
//! point, a search step's 27 candidates, and 4096 points. The learned network's cost does not
//! depend on its weights, so an untrained one of the shipped shape is timed.
//!
//! `cargo bench --bench field3`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use envfield::grid::{Cell3, ContinuousField3, Grid3, SplitMix64};
use envfield::nets::{FieldNet, GoalConfig, ModelConfig, TargetEncoding};
use envfield::rooms::{AccessibleRegion, ExactField3, Field3Config, LearnedField3};
use envfield::scene::nalgebra::Point3;
use envfield::scene::VoxelFrame;
use std::hint::black_box;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench_field3(c: &mut Criterion) {
    // A 6 x 5 x 2.5 m room at 0.1 m: the size of a generated room's lattice.
    let shape = [60, 50, 25];
    let frame = VoxelFrame {
        origin: Point3::new(0.0, 0.0, 0.0),
        voxel: 0.1,
        shape,
    };
    let grid = Grid3::new(shape[0], shape[1], shape[2]).expect("grid");
    let region = AccessibleRegion::new(frame, grid, vec![[0.05, 0.05, 0.05]], 1).expect("region");
    let goal = Cell3::new(10, 10, 9);
    let exact = ExactField3::at_cell(&region, goal).expect("field");
    let net = FieldNet::new(
        ModelConfig::Goal(GoalConfig {
            extent: shape.to_vec(),
            mlp: Field3Config::default().mlp,
            encoding: TargetEncoding::Linear { scale: 100.0 },
            detour: true,
        }),
        0,
    )
    .expect("net");
    let learned = LearnedField3::new(&net, &region, goal).expect("learned");
    let mut rng = SplitMix64::new(3);
    let points: Vec<[f32; 3]> = (0..4096)
        .map(|_| {
            [
                0.2 + 5.6 * rng.next_f32(),
                0.2 + 4.6 * rng.next_f32(),
                0.2 + 2.0 * rng.next_f32(),
            ]
        })
        .collect();
    let mut group = c.benchmark_group("field3_queries");
    for n in [1usize, 27, 4096] {
        group.throughput(Throughput::Elements(n as u64));
        let fields: [(&str, &dyn ContinuousField3); 2] = [("exact", &exact), ("learned", &learned)];
        for (name, field) in fields {
            group.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter(|| black_box(field.values(&points[..n]).expect("values")))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_field3);
criterion_main!(benches);
