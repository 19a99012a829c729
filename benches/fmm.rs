//! Fast marching speed on the grids of the scikit-fmm comparison (`benches/fmm_vs_skfmm.py`):
//! 28^2, 256^2, 1024^2 with 20% random square obstacles, 64^3 and 128^3 with 20% random cubes,
//! the source at the centre. The exact graph distance (Dijkstra, 8-connected) runs in the same
//! groups as a baseline.
//!
//! The level-set marcher (scikit-fmm's problem, `envfield.fmm` from Python) runs on the same
//! grids in `level_set_2d`/`level_set_3d`, the obstacles as its mask and the front starting
//! around the centre cell, beside the point-source marcher.
//!
//! `cargo bench --bench fmm`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use envfield::eikonal::level_set::{LevelSet, LevelSetOptions};
use envfield::eikonal::{dijkstra2, FastMarching, Order};
use envfield::grid::synth::{scatter_cubes3, scatter_squares2};
use envfield::grid::{Cell2, Cell3, MoveRule, Neighbourhood2};
use std::hint::black_box;
use std::time::Duration;

// As the examples and the Python module: freed pages are kept for the next solve.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench_2d(c: &mut Criterion) {
    let mut group = c.benchmark_group("fmm_2d");
    for n in [28usize, 256, 1024] {
        let src = Cell2::new(n / 2, n / 2);
        let grid = scatter_squares2(n, n, 0.2, (n / 128).max(1), 0, &[src]).expect("grid");
        if n >= 1024 {
            group
                .sample_size(10)
                .measurement_time(Duration::from_secs(8));
        }
        for order in [Order::First, Order::Second] {
            let fmm = FastMarching::with_order(order);
            let id = BenchmarkId::new(format!("order{}", order.as_number()), n);
            group.bench_with_input(id, &grid, |b, g| {
                b.iter(|| fmm.solve2(black_box(g), &[src]).expect("solve"))
            });
        }
        let nb = Neighbourhood2::Eight(MoveRule::Strict);
        group.bench_with_input(BenchmarkId::new("dijkstra8", n), &grid, |b, g| {
            b.iter(|| dijkstra2(black_box(g), &[src], nb, std::f32::consts::SQRT_2).expect("solve"))
        });
    }
    group.finish();
}

fn bench_3d(c: &mut Criterion) {
    let mut group = c.benchmark_group("fmm_3d");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    for n in [64usize, 128] {
        let src = Cell3::new(n / 2, n / 2, n / 2);
        let grid = scatter_cubes3([n, n, n], 0.2, (n / 128).max(1), 0, &[src]).expect("grid");
        for order in [Order::First, Order::Second] {
            let fmm = FastMarching::with_order(order);
            let id = BenchmarkId::new(format!("order{}", order.as_number()), n);
            group.bench_with_input(id, &grid, |b, g| {
                b.iter(|| fmm.solve3(black_box(g), &[src]).expect("solve"))
            });
        }
    }
    group.finish();
}

/// The level set of a point source at `centre` (-1 there, 1 elsewhere) on `shape`.
fn point_level_set(shape: &[usize], centre: usize) -> Vec<f64> {
    let mut phi = vec![1.0; shape.iter().product()];
    phi[centre] = -1.0;
    phi
}

fn bench_level_set(c: &mut Criterion) {
    let mut group = c.benchmark_group("level_set");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(8));
    let n = 1024;
    let src = Cell2::new(n / 2, n / 2);
    let grid = scatter_squares2(n, n, 0.2, n / 128, 0, &[src]).expect("grid");
    let phi2 = point_level_set(&[n, n], grid.index(src).expect("inside"));
    let m = 128;
    let src3 = Cell3::new(m / 2, m / 2, m / 2);
    let grid3 = scatter_cubes3([m, m, m], 0.2, 1, 0, &[src3]).expect("grid");
    let phi3 = point_level_set(&[m, m, m], grid3.index(src3).expect("inside"));
    let (shape2, shape3) = ([n, n], [m, m, m]);
    for order in [Order::First, Order::Second] {
        let options = LevelSetOptions {
            order,
            ..LevelSetOptions::default()
        };
        let set = LevelSet::new(&shape2, &phi2).with_mask(grid.obstacles());
        let id = BenchmarkId::new(format!("distance_order{}", order.as_number()), n);
        group.bench_function(id, |b| {
            b.iter(|| black_box(set).distance(&options).expect("march"))
        });
        let set = LevelSet::new(&shape3, &phi3).with_mask(grid3.obstacles());
        let id = BenchmarkId::new(
            format!("distance_order{}", order.as_number()),
            format!("{m}^3"),
        );
        group.bench_function(id, |b| {
            b.iter(|| black_box(set).distance(&options).expect("march"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_2d, bench_3d, bench_level_set);
criterion_main!(benches);
