use super::*;

fn opts(order: Order) -> LevelSetOptions {
    LevelSetOptions {
        order,
        self_test: true,
        ..LevelSetOptions::default()
    }
}

fn close(got: &[f64], want: &[f64], tol: f64) {
    assert_eq!(got.len(), want.len());
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!((g - w).abs() <= tol, "cell {i}: {g} vs {w}\n{got:?}");
    }
}

const BLOCK: [f64; 16] = [
    -1., -1., 1., 1., -1., -1., 1., 1., 1., 1., 1., 1., 1., 1., 1., 1.,
];

#[test]
fn a_quarter_block_at_first_and_second_order() {
    // FiPy's values for this block (first order) and second order's, as scikit-fmm prints.
    let d = LevelSet::new(&[4, 4], &BLOCK)
        .distance(&opts(Order::First))
        .unwrap();
    #[rustfmt::skip]
    let first = [-1.20710678, -0.5, 0.5, 1.5, -0.5, -0.35355339, 0.5, 1.5,
        0.5, 0.5, 1.20710678, 2.04532893, 1.5, 1.5, 2.04532893, 2.75243571];
    close(&d.values, &first, 1e-7);
    let d = LevelSet::new(&[4, 4], &BLOCK)
        .distance(&opts(Order::Second))
        .unwrap();
    #[rustfmt::skip]
    let second = [-1.30473785, -0.5, 0.5, 1.49923009, -0.5, -0.35355339, 0.5, 1.45118446,
        0.5, 0.5, 0.97140452, 1.76215286, 1.49923009, 1.45118446, 1.76215286, 2.33721352];
    close(&d.values, &second, 1e-7);
    let speed = [1.0; 16];
    let t = LevelSet::new(&[4, 4], &BLOCK)
        .travel_time(&speed, &opts(Order::Second))
        .unwrap();
    close(&t.values, &second.map(f64::abs), 1e-7);
}

#[test]
fn ties_freeze_together_so_symmetric_cells_stay_equal() {
    #[rustfmt::skip]
    let phi = [-1., 1., 1., 1., 1., -1., -1., -1., -1., -1., -1., -1., -1., -1., -1., -1., -1., -1.];
    let o = opts(Order::Second);
    let d = LevelSet::new(&[3, 6], &phi).distance(&o).unwrap();
    assert_eq!(d.values[2 * 6 + 2], d.values[2 * 6 + 3]);
    let d = LevelSet::new(&[3, 6], &d.values).distance(&o).unwrap();
    assert_eq!(d.values[2 * 6 + 2], d.values[2 * 6 + 3]);
}

#[test]
fn one_dimension_spacing_and_exact_zeros() {
    let phi = [-1.0, 0.0, 1.0];
    let o = LevelSetOptions {
        dx: vec![2.0],
        ..opts(Order::Second)
    };
    assert_eq!(
        LevelSet::new(&[3], &phi).distance(&o).unwrap().values,
        [-2.0, 0.0, 2.0]
    );
    let t = LevelSet::new(&[3], &[1.0, 0.0, -1.0])
        .travel_time(&[2.0; 3], &opts(Order::Second))
        .unwrap();
    assert_eq!(t.values, [0.5, 0.0, 0.5]);
    // Opposite normals on both sides of one cell.
    let d = LevelSet::new(&[3], &[-1.0, 1.0, -1.0])
        .distance(&opts(Order::Second))
        .unwrap();
    assert_eq!(d.values, [-0.5, 0.5, -0.5]);
}

#[test]
fn a_mask_cuts_the_front_off() {
    let phi = [1.0, 1.0, 1.0, 0.0];
    let mask = [false, true, false, false];
    let d = LevelSet::new(&[4], &phi)
        .with_mask(&mask)
        .distance(&opts(Order::Second))
        .unwrap();
    assert_eq!(d.reached, [false, false, true, true]);
    assert_eq!(d.values[2..], [1.0, 0.0]);
}

#[test]
fn slow_cells_are_never_entered() {
    let t = LevelSet::new(&[5], &[-1.0, -1.0, 0.0, 1.0, 1.0])
        .travel_time(&[1.0, 1.0, 1.0, 1.0, 0.0], &opts(Order::Second))
        .unwrap();
    assert_eq!(t.reached, [true, true, true, true, false]);
    assert_eq!(t.values[..4], [2.0, 1.0, 0.0, 1.0]);
}

#[test]
fn the_narrow_band_stops_the_march() {
    let phi = [-1., -1., -1., 1., 1., 1.];
    let o = LevelSetOptions {
        narrow: 1.0,
        ..opts(Order::Second)
    };
    let d = LevelSet::new(&[6], &phi).distance(&o).unwrap();
    assert_eq!(d.reached, [false, false, true, true, false, false]);
    assert_eq!(d.values[2..4], [-0.5, 0.5]);
}

#[test]
fn periodic_axes_wrap() {
    let phi = [1.0, -1.0, 1.0, 1.0, 1.0, 1.0];
    let speed = [4.0, 1.0, 2.0, 2.0, 2.0, 2.0];
    let e = LevelSet::new(&[6], &phi)
        .extension_velocities(&speed, None, &opts(Order::Second))
        .unwrap();
    close(&e.velocity, &[2.5, 2.5, 1.5, 1.5, 1.5, 1.5], 1e-12);
    let o = LevelSetOptions {
        periodic: vec![true],
        ..opts(Order::Second)
    };
    let e = LevelSet::new(&[6], &phi)
        .extension_velocities(&speed, None, &o)
        .unwrap();
    close(&e.velocity, &[2.5, 2.5, 1.5, 1.5, 1.5, 2.5], 1e-12);
}

#[test]
fn extension_with_an_ext_mask() {
    let phi = [-1.0, 1.0, 1.0, 1.0];
    let speed = [-1.0, 0.5, 2.0, -1.0];
    let ext_mask = [true, false, false, false];
    let o = opts(Order::First);
    let e = LevelSet::new(&[2, 2], &phi)
        .extension_velocities(&speed, Some(&ext_mask), &o)
        .unwrap();
    let tmp = 1.0 / 2f64.sqrt();
    close(
        &e.distance.values,
        &[-tmp / 2.0, 0.5, 0.5, 0.5 + tmp],
        1e-12,
    );
    close(&e.velocity, &[1.25, 0.5, 2.0, 1.25], 1e-12);
}

#[test]
fn a_circle_is_within_a_cell_of_exact_in_three_dimensions_too() {
    let n = 15usize;
    let h = 2.0 / (n - 1) as f64;
    let mut phi = vec![1.0; n * n * n];
    phi[0] = -1.0;
    let o = LevelSetOptions {
        dx: vec![h; 3],
        ..opts(Order::Second)
    };
    let d = LevelSet::new(&[n, n, n], &phi).distance(&o).unwrap();
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let exact = ((i * i + j * j + k * k) as f64).sqrt() * h;
                let got = d.values[(i * n + j) * n + k];
                assert!((got - exact).abs() <= h, "({i},{j},{k}): {got} vs {exact}");
            }
        }
    }
}

#[test]
fn bad_input_is_refused_by_name() {
    let o = LevelSetOptions::default();
    let err = |r: Result<Marched>| r.unwrap_err().to_string();
    assert!(err(LevelSet::new(&[2], &[1.0, 1.0]).distance(&o)).contains("no zero contour"));
    assert!(err(LevelSet::new(&[3], &[1.0, f64::NAN, -1.0]).distance(&o)).contains("flat index 1"));
    assert!(err(LevelSet::new(&[2, 2], &[1.0, -1.0]).distance(&o)).contains("2 values"));
    let bad_dx = LevelSetOptions {
        dx: vec![0.0],
        ..LevelSetOptions::default()
    };
    assert!(err(LevelSet::new(&[2], &[1.0, -1.0]).distance(&bad_dx)).contains("spacing of axis 0"));
    let narrow = LevelSetOptions {
        narrow: -1.0,
        ..LevelSetOptions::default()
    };
    assert!(err(LevelSet::new(&[2], &[1.0, -1.0]).distance(&narrow)).contains("narrow"));
    assert!(err(LevelSet::new(&[1; 13], &[1.0]).distance(&o)).contains("13"));
}

#[test]
fn descend_reaches_the_contour_around_an_obstacle() {
    // A point source in a corner of a 40x40 grid, a wall across the middle with a gap.
    let n = 40;
    let mut phi = vec![1.0; n * n];
    phi[0] = -1.0;
    let mut mask = vec![false; n * n];
    for j in 0..30 {
        mask[20 * n + j] = true;
    }
    let t = LevelSet::new(&[n, n], &phi)
        .with_mask(&mask)
        .travel_time(&vec![1.0; n * n], &LevelSetOptions::default())
        .unwrap();
    let path = descend(&[n, n], &t.values, &t.reached, &[], &[39.0, 0.0]).unwrap();
    let end = path.last().unwrap();
    assert!(end[0] < 1.5 && end[1] < 1.5, "ends at {end:?}");
    // It goes round the wall's end, never through a masked cell.
    assert!(path.iter().any(|p| p[1] >= 29.5));
    for p in &path {
        let c = [p[0].round() as usize, p[1].round() as usize];
        assert!(!mask[c[0] * n + c[1]], "through the wall at {p:?}");
    }
    let err = descend(&[n, n], &t.values, &t.reached, &[], &[20.0, 3.0]).unwrap_err();
    assert!(err.to_string().contains("did not reach"));
}
