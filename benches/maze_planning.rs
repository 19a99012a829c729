//! Planning time per path on generated gridworld mazes, one group per size (8, 16, 28, 64).
//! Each group holds the exact oracles (fast-marching and graph-distance field descent: the
//! whole field computed, then the walk) and A*; the learned planners and VIN join the same
//! groups in later issues.
//!
//! `cargo bench --bench maze_planning`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use envfield::eikonal::{FastMarching, GraphDistance};
use envfield::grid::{MoveRule, Neighbourhood2};
use envfield::mazes::{evaluation_pairs, GeneratorKind, MazeGenerator};
use envfield::plan::{AStar, FieldDescent, Planner};
use std::hint::black_box;

fn bench_planners(c: &mut Criterion) {
    let rule = MoveRule::Strict;
    let fmm = FieldDescent::new(FastMarching::default(), rule);
    let graph = FieldDescent::new(GraphDistance::new(Neighbourhood2::Eight(rule)), rule);
    let astar = AStar { rule };
    let planners: [&dyn Planner; 3] = [&fmm, &graph, &astar];
    for size in [8usize, 16, 28, 64] {
        let mazes = MazeGenerator::new(GeneratorKind::Gridworld, size)
            .expect("size")
            .generate_many(50, 1)
            .expect("mazes");
        let pairs = evaluation_pairs(&mazes, rule, 2, 1).expect("pairs");
        let mut group = c.benchmark_group(format!("maze_planning_{size}"));
        for p in planners {
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
