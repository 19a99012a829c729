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
use envfield::eikonal::{FastMarching, GraphDistance};
use envfield::grid::{MoveRule, Neighbourhood2};
use envfield::mazes::{evaluation_pairs, GeneratorKind, MazeGenerator};
use envfield::nets::{FieldNet, Vin};
use envfield::plan::{AStar, FieldDescent, Planner, RelayDescent};
use std::hint::black_box;
use std::path::Path;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench_planners(c: &mut Criterion) {
    let rule = MoveRule::Vin;
    let fmm = FieldDescent::new(FastMarching::default(), rule);
    let graph = FieldDescent::new(GraphDistance::new(Neighbourhood2::Eight(rule)), rule);
    let astar = AStar { rule };
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    // The model maze_nav picks for the size; a size without one is left out.
    let file = |arch: &str, size: usize| envfield::nets::model_file(&models, arch, size).ok();
    let net = |p: std::path::PathBuf| FieldNet::load(p).expect("shipped model loads");
    let load = |arch: &str, size: usize| file(arch, size).map(|p| FieldDescent::new(net(p), rule));
    let relay = |size: usize| file("context", size).map(|p| RelayDescent::new(net(p), rule, 1));
    for size in [8usize, 16, 28, 64] {
        let field = load("context", size);
        let relayed = relay(size);
        let hyper = load("hyper", size);
        let vin = file("vin", size).map(|p| Vin::load(p).expect("vin loads"));
        let mut planners: Vec<&dyn Planner> = vec![&fmm, &graph, &astar];
        if size <= 28 {
            planners.extend(field.as_ref().map(|p| p as &dyn Planner));
            planners.extend(relayed.as_ref().map(|p| p as &dyn Planner));
            planners.extend(hyper.as_ref().map(|p| p as &dyn Planner));
        }
        planners.extend(vin.as_ref().map(|p| p as &dyn Planner));
        let mazes = MazeGenerator::new(GeneratorKind::Gridworld, size)
            .expect("size")
            .generate_many(50, 1)
            .expect("mazes");
        let pairs = evaluation_pairs(&mazes, rule, 2, 1).expect("pairs");
        let mut group = c.benchmark_group(format!("maze_planning_{size}"));
        for &p in &planners {
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
