//! Fast marching against known answers: the straight-line distance on obstacle-free grids.
//!
//! The bounds (scikit-fmm 2025.6.23, measured in cells) are for 1024^2 and 128^3;
//! first- and second-order errors from a point source grow with the distance to it, so they
//! hold a fortiori on the smaller grids used here to keep the suite fast. `fmm` (the example)
//! measures the full-size grids; see the README.

use envfield_eikonal::{FastMarching, Order};
use envfield_grid::{Cell2, Cell3, Grid2, Grid3};

fn errors2(n: usize, order: Order) -> (f32, f32) {
    let grid = Grid2::new(n, n).unwrap();
    let c = n / 2;
    let field = FastMarching::with_order(order)
        .solve2(&grid, &[Cell2::new(c, c)])
        .unwrap();
    let (mut max, mut sum) = (0.0f32, 0.0f64);
    for cell in grid.free_cells() {
        let exact =
            ((cell.row as f32 - c as f32).powi(2) + (cell.col as f32 - c as f32).powi(2)).sqrt();
        let e = (field.get(cell).unwrap() - exact).abs();
        max = max.max(e);
        sum += e as f64;
    }
    (max, (sum / grid.len() as f64) as f32)
}

#[test]
fn first_order_2d_is_no_worse_than_scikit_fmm() {
    let (max, mean) = errors2(384, Order::First);
    assert!(max <= 2.11 && mean <= 1.24, "max {max} mean {mean}");
    // And it is a first-order method: the error is at least visible at this size.
    assert!(max > 0.5, "suspiciously exact: {max}");
}

#[test]
fn second_order_2d_is_no_worse_than_scikit_fmm() {
    let (max, mean) = errors2(384, Order::Second);
    assert!(max <= 0.33 && mean <= 0.19, "max {max} mean {mean}");
}

#[test]
fn second_order_3d_is_no_worse_than_scikit_fmm() {
    let n = 48;
    let grid = Grid3::new(n, n, n).unwrap();
    let c = n / 2;
    let field = FastMarching::with_order(Order::Second)
        .solve3(&grid, &[Cell3::new(c, c, c)])
        .unwrap();
    let (mut max, mut sum) = (0.0f32, 0.0f64);
    for i in 0..grid.len() {
        let cell = grid.cell(i);
        let d = |a: usize| a as f32 - c as f32;
        let exact = (d(cell.x).powi(2) + d(cell.y).powi(2) + d(cell.z).powi(2)).sqrt();
        let e = (field.get(cell).unwrap() - exact).abs();
        max = max.max(e);
        sum += e as f64;
    }
    let mean = (sum / grid.len() as f64) as f32;
    assert!(max <= 0.62 && mean <= 0.41, "max {max} mean {mean}");
}

#[test]
fn point_source_neighbours_are_exact() {
    // scikit-fmm's issue #47: its diagonal neighbour of a point source is 1.707, not sqrt 2.
    let grid = Grid2::new(5, 5).unwrap();
    for order in [Order::First, Order::Second] {
        let f = FastMarching::with_order(order)
            .solve2(&grid, &[Cell2::new(2, 2)])
            .unwrap();
        assert_eq!(f.get(Cell2::new(2, 2)), Some(0.0));
        assert_eq!(f.get(Cell2::new(2, 3)), Some(1.0));
        assert!((f.get(Cell2::new(3, 3)).unwrap() - 2f32.sqrt()).abs() < 1e-6);
        assert!((f.get(Cell2::new(4, 3)).unwrap() - 5f32.sqrt()).abs() < 1e-6);
    }
    // Without line of sight (a wall between), the exact initialisation does not apply.
    let mut walled = Grid2::new(5, 5).unwrap();
    walled.set_obstacle(Cell2::new(2, 3), true).unwrap();
    walled.set_obstacle(Cell2::new(3, 2), true).unwrap();
    let f = FastMarching::default()
        .solve2(&walled, &[Cell2::new(2, 2)])
        .unwrap();
    assert!(f.get(Cell2::new(3, 3)).unwrap() > 2.0);
}

#[test]
fn travel_time_scales_with_speed_and_spacing() {
    use envfield_eikonal::SolveOptions2;
    use envfield_grid::Field2;
    let grid = Grid2::new(40, 40).unwrap();
    let src = [Cell2::new(5, 7)];
    let base = FastMarching::default().solve2(&grid, &src).unwrap();
    let fast = Field2::filled(40, 40, 4.0).unwrap();
    let timed = FastMarching::default()
        .solve2_with(
            &grid,
            &src,
            SolveOptions2 {
                speed: Some(&fast),
                stop_at: None,
                ..Default::default()
            },
        )
        .unwrap();
    let halved = FastMarching {
        spacing: 0.5,
        ..FastMarching::default()
    }
    .solve2(&grid, &src)
    .unwrap();
    for i in 0..grid.len() {
        let b = base.values()[i];
        assert!((timed.values()[i] - b / 4.0).abs() < 1e-4 * b.max(1.0));
        assert!((halved.values()[i] - b / 2.0).abs() < 1e-4 * b.max(1.0));
    }
    // A slow band doubles the time to cross it.
    let mut speed = Field2::filled(1, 30, 1.0).unwrap();
    for c in 10..20 {
        speed.set(Cell2::new(0, c), 0.5).unwrap();
    }
    let line = Grid2::new(1, 30).unwrap();
    let f = FastMarching::default()
        .solve2_with(
            &line,
            &[Cell2::new(0, 0)],
            SolveOptions2 {
                speed: Some(&speed),
                stop_at: None,
                ..Default::default()
            },
        )
        .unwrap();
    let end = f.get(Cell2::new(0, 29)).unwrap();
    assert!((end - 39.0).abs() < 0.6, "{end}");
}

#[test]
fn early_stop_keeps_the_target_value() {
    use envfield_eikonal::SolveOptions2;
    let grid = envfield_grid::synth::scatter_squares2(
        64,
        64,
        0.2,
        3,
        11,
        &[Cell2::new(5, 5), Cell2::new(30, 30)],
    )
    .unwrap();
    let full = FastMarching::default()
        .solve2(&grid, &[Cell2::new(5, 5)])
        .unwrap();
    let target = Cell2::new(30, 30);
    let part = FastMarching::default()
        .solve2_with(
            &grid,
            &[Cell2::new(5, 5)],
            SolveOptions2 {
                speed: None,
                stop_at: Some(target),
                ..Default::default()
            },
        )
        .unwrap();
    assert_eq!(part.get(target), full.get(target));
    let missing = part.values().iter().filter(|v| v.is_infinite()).count();
    let missing_full = full.values().iter().filter(|v| v.is_infinite()).count();
    assert!(missing > missing_full, "the early stop skipped nothing");
}

/// Past the stop cell the march goes on through a band: every cell up to that much above
/// the stop's value has the full march's value exactly, and no cell beyond it is reached.
#[test]
fn the_band_past_the_stop_cell_is_the_full_fields() {
    let grid = Grid3::from_obstacles([24, 20, 6], vec![false; 24 * 20 * 6]).unwrap();
    let source = Cell3::new(2, 2, 1);
    let stop = Cell3::new(12, 10, 3);
    let full = FastMarching::default().solve3(&grid, &[source]).unwrap();
    let band = 4.0;
    let part = FastMarching::default()
        .solve3_with(
            &grid,
            &[source],
            envfield_eikonal::SolveOptions3 {
                stop_at: Some(stop),
                past_stop: band,
                ..Default::default()
            },
        )
        .unwrap();
    let limit = full.get(stop).unwrap() + band;
    let (mut kept, mut left) = (0, 0);
    for (f, p) in full.values().iter().zip(part.values()) {
        if *f <= limit - 1e-3 {
            assert_eq!(f.to_bits(), p.to_bits(), "{f} against {p} within the band");
            kept += 1;
        } else if *f > limit + 1e-3 {
            assert!(p.is_infinite(), "{p} reached beyond the band (full {f})");
            left += 1;
        }
    }
    assert!(kept > 0 && left > 0, "{kept} kept, {left} left");
    for bad in [f32::NAN, -1.0] {
        let e = FastMarching::default().solve3_with(
            &grid,
            &[source],
            envfield_eikonal::SolveOptions3 {
                stop_at: Some(stop),
                past_stop: bad,
                ..Default::default()
            },
        );
        assert!(e.unwrap_err().to_string().contains("past_stop"));
    }
}
