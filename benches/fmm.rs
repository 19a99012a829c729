//! Fast marching speed on the grids of the scikit-fmm comparison (`benches/fmm_vs_skfmm.py`):
//! 28^2, 256^2, 1024^2 with 20% random square obstacles, 64^3 and 128^3 with 20% random cubes,
//! the source at the centre. The exact graph distance (Dijkstra, 8-connected) runs in the same
//! groups as a baseline.
//!
//! `cargo bench --bench fmm`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use envfield::eikonal::{dijkstra2, FastMarching, Order};
use envfield::grid::synth::{scatter_cubes3, scatter_squares2};
use envfield::grid::{Cell2, Cell3, MoveRule, Neighbourhood2};
use std::hint::black_box;
use std::time::Duration;

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

criterion_group!(benches, bench_2d, bench_3d);
criterion_main!(benches);
