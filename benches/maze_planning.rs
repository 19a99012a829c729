//! Planning time per path on generated gridworld mazes, one group per size (8, 16, 28, 64).
//! Each group holds the exact oracles (fast-marching and graph-distance field descent: the
//! whole field computed, then the walk), A*, and, when the shipped models are in `models/`,
//! the learned field (the whole field predicted once, then descent; all inference included),
//! the same field with relays (`RelayDescent`: a failing walk is planned again through a relay
//! cell, one more prediction per split), the hypernetwork (up to 28x28), and VIN (one network
//! pass per step, VIN's own protocol). VIN has no model for 64x64: there an untrained VIN with
//! VIN's K for the size (84) is timed, named `vin-untrained-k84`, since its cost does not
//! depend on its weights. Pairs and rule are `vin` here, as in the maze benchmark.
//!
//! `cargo bench --bench maze_planning`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use envfield::grid::MoveRule;
use envfield::grid::{Cell2, Grid2, Policy};
use envfield::mazes::{evaluation_pairs, GeneratorKind, MazeGenerator};
use envfield::models::ModelSource;
use envfield::nets::{Vin, VinConfig};
use envfield::plan::{NamedPlanner, PlannerKind, PlannerOptions, PolicyWalk};
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
            .filter(|k| size <= 28 || k.model_family() != Some("hyper"))
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
        let mut planners = planners;
        if size > 28 {
            let vin = Vin::new(VinConfig::for_size(size), 0).expect("VIN");
            planners.push(NamedPlanner::Policy(PolicyWalk(Box::new(Untrained(vin)))));
        }
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

/// A VIN with random weights, renamed so no table mistakes it for the trained baseline.
struct Untrained(Vin);

impl Policy for Untrained {
    fn name(&self) -> &str {
        "vin-untrained-k84"
    }

    fn rule(&self) -> MoveRule {
        Policy::rule(&self.0)
    }

    fn action_scores(
        &self,
        grid: &Grid2,
        goal: Cell2,
        state: Cell2,
    ) -> envfield::grid::Result<[f32; 8]> {
        self.0.action_scores(grid, goal, state)
    }
}

criterion_group!(benches, bench_planners);
criterion_main!(benches);
