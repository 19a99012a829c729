//! Planning time per path on generated gridworld mazes, one group per size (8, 16, 28, 64).
//! Each group holds the exact oracles (fast-marching and graph-distance field descent: the
//! whole field computed, then the walk), A*, and, when the shipped models are in `models/`,
//! the learned field (the whole field predicted once, then descent; all inference included),
//! the same field with relays (`RelayDescent`: a failing walk is planned again through a relay
//! cell, one more prediction per split), the hypernetwork, and VIN (one network pass per step,
//! VIN's own protocol). Pairs and rule are `vin` here, as in the maze benchmark.
//!
//! `cargo bench --bench maze_planning`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use envfield::grid::MoveRule;
use envfield::mazes::{evaluation_pairs, GeneratorKind, MazeGenerator};
use envfield::models::ModelSource;
use envfield::plan::{NamedPlanner, PlannerKind, PlannerOptions};
use std::hint::black_box;
use std::path::Path;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench_planners(c: &mut Criterion) {
    let options = PlannerOptions {
        rule: MoveRule::Vin,
        ..PlannerOptions::default()
    };
    let source = ModelSource::new(Path::new(env!("CARGO_MANIFEST_DIR")).join("models"));
    // The planners maze_nav builds by these names, with the models it picks for the size; a
    // learned planner without a model for the size is left out, and the learned fields are
    // timed up to 28x28 (VIN at every size).
    let kinds = [
        PlannerKind::Fmm,
        PlannerKind::Graph,
        PlannerKind::AStar,
        PlannerKind::Field,
        PlannerKind::Relay,
        PlannerKind::Hyper,
        PlannerKind::Vin,
    ];
    for size in [8usize, 16, 28, 64] {
        let planners: Vec<NamedPlanner> = kinds
            .iter()
            .filter(|k| size <= 28 || !matches!(k.model_family(), Some("context" | "hyper")))
            .filter_map(|k| {
                k.build(&options, |family| {
                    source
                        .load(family, size)
                        .map(|(_, model)| model)
                        .map_err(anyhow::Error::from)
                })
                .ok()
            })
            .collect();
        let mazes = MazeGenerator::new(GeneratorKind::Gridworld, size)
            .expect("size")
            .generate_many(50, 1)
            .expect("mazes");
        let pairs = evaluation_pairs(&mazes, options.rule, 2, 1).expect("pairs");
        let mut group = c.benchmark_group(format!("maze_planning_{size}"));
        for p in planners.iter().map(NamedPlanner::planner) {
            group.bench_function(BenchmarkId::new(p.name(), size), |b| {
                let mut k = 0;
                b.iter(|| {
                    let pair = &pairs[k % pairs.len()];
                    k += 1;
                    let grid = &mazes[pair.maze].grid;
                    black_box(
                        p.plan(grid, pair.start, pair.goal, 4 * size * size)
                            .expect("plan"),
                    )
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, bench_planners);
criterion_main!(benches);
