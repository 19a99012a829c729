//! Bad input gives a clear error, never a panic.

use envfield_eikonal::{bfs2, dijkstra2, EikonalError, FastMarching, SolveOptions2, SolveOptions3};
use envfield_grid::{Cell2, Cell3, Field2, Field3, Grid2, Grid3, Neighbourhood2};

#[test]
fn bad_sources_are_named() {
    let mut g = Grid2::new(4, 5).unwrap();
    g.set_obstacle(Cell2::new(1, 1), true).unwrap();
    let fmm = FastMarching::default();
    let e = fmm.solve2(&g, &[Cell2::new(1, 1)]).unwrap_err();
    assert!(matches!(e, EikonalError::SourceOnObstacle { .. }));
    assert!(e.to_string().contains("(1, 1)"), "{e}");
    let e = fmm.solve2(&g, &[Cell2::new(4, 0)]).unwrap_err();
    assert!(matches!(e, EikonalError::SourceOutside { .. }));
    assert!(
        e.to_string().contains("(4, 0)") && e.to_string().contains("4x5"),
        "{e}"
    );
    assert!(matches!(fmm.solve2(&g, &[]), Err(EikonalError::NoSources)));
    assert!(matches!(
        dijkstra2(&g, &[Cell2::new(1, 1)], Neighbourhood2::Four, 1.0),
        Err(EikonalError::SourceOnObstacle { .. })
    ));
    assert!(bfs2(&g, &[Cell2::new(9, 9)], Neighbourhood2::Four).is_err());
    assert!(dijkstra2(&g, &[Cell2::new(0, 0)], Neighbourhood2::Four, f32::NAN).is_err());
    let e = FastMarching::default().solve3(&Grid3::new(2, 2, 2).unwrap(), &[Cell3::new(0, 2, 0)]);
    assert!(matches!(e, Err(EikonalError::SourceOutside { .. })));
}

#[test]
fn a_grid_without_free_cells_is_an_error() {
    let g = Grid2::from_obstacles(2, 2, vec![true; 4]).unwrap();
    assert!(matches!(
        FastMarching::default().solve2(&g, &[Cell2::new(0, 0)]),
        Err(EikonalError::NoFreeCell)
    ));
    assert!(matches!(
        bfs2(&g, &[Cell2::new(0, 0)], Neighbourhood2::Four),
        Err(EikonalError::NoFreeCell)
    ));
}

#[test]
fn bad_speed_maps_are_named() {
    let g = Grid2::new(3, 3).unwrap();
    let src = [Cell2::new(0, 0)];
    let fmm = FastMarching::default();
    for bad in [f32::NAN, -1.0, f32::INFINITY] {
        let mut s = Field2::filled(3, 3, 1.0).unwrap();
        s.set(Cell2::new(2, 1), bad).unwrap();
        let e = fmm
            .solve2_with(
                &g,
                &src,
                SolveOptions2 {
                    speed: Some(&s),
                    stop_at: None,
                    ..Default::default()
                },
            )
            .unwrap_err();
        assert!(matches!(e, EikonalError::InvalidSpeed { .. }), "{e}");
        assert!(e.to_string().contains("(2, 1)"), "{e}");
    }
    let s = Field2::filled(3, 4, 1.0).unwrap();
    let e = fmm
        .solve2_with(
            &g,
            &src,
            SolveOptions2 {
                speed: Some(&s),
                stop_at: None,
                ..Default::default()
            },
        )
        .unwrap_err();
    assert!(matches!(e, EikonalError::SpeedShape { .. }));
    assert!(
        e.to_string().contains("3x4") && e.to_string().contains("3x3"),
        "{e}"
    );
    // A zero speed is allowed (never entered) but not under a source.
    let mut s = Field2::filled(3, 3, 1.0).unwrap();
    s.set(Cell2::new(0, 0), 0.0).unwrap();
    let e = fmm.solve2_with(
        &g,
        &src,
        SolveOptions2 {
            speed: Some(&s),
            stop_at: None,
            ..Default::default()
        },
    );
    assert!(matches!(e, Err(EikonalError::SourceOnObstacle { .. })));
    let s3 = Field3::new([2, 2, 3], vec![1.0; 12]).unwrap();
    let g3 = Grid3::new(2, 2, 2).unwrap();
    let e = fmm.solve3_with(
        &g3,
        &[Cell3::new(0, 0, 0)],
        SolveOptions3 {
            speed: Some(&s3),
            stop_at: None,
            ..Default::default()
        },
    );
    assert!(matches!(e, Err(EikonalError::SpeedShape { .. })));
}

#[test]
fn bad_settings_are_rejected() {
    let g = Grid2::new(3, 3).unwrap();
    for spacing in [0.0, -1.0, f32::NAN] {
        let fmm = FastMarching {
            spacing,
            ..FastMarching::default()
        };
        assert!(matches!(
            fmm.solve2(&g, &[Cell2::new(0, 0)]),
            Err(EikonalError::InvalidConfig(_))
        ));
    }
    assert!(envfield_eikonal::Order::from_number(3).is_err());
}

#[test]
fn a_stop_cell_outside_the_grid_is_an_error() {
    let g = Grid2::new(3, 3).unwrap();
    let e = FastMarching::default().solve2_with(
        &g,
        &[Cell2::new(0, 0)],
        SolveOptions2 {
            speed: None,
            stop_at: Some(Cell2::new(7, 7)),
            ..Default::default()
        },
    );
    assert!(e.is_err());
}

/// A spacing whose distances leave f32's range is refused, never returned as NaN or as
/// "unreachable"; with a speed map the overflow is caught on the result.
#[test]
fn distances_that_overflow_f32_are_errors() {
    let grid = Grid2::new(40, 40).unwrap();
    let huge = FastMarching {
        spacing: 1e38,
        ..FastMarching::default()
    };
    let err = huge
        .solve2(&grid, &[Cell2::new(20, 20)])
        .unwrap_err()
        .to_string();
    assert!(err.contains("overflow"), "{err}");
    let fine = FastMarching {
        spacing: 1e30,
        ..FastMarching::default()
    };
    let field = fine.solve2(&grid, &[Cell2::new(20, 20)]).unwrap();
    assert!(field.values().iter().all(|v| v.is_finite()));
    let slow = Field2::new(40, 40, vec![1e-37; 1600]).unwrap();
    let options = SolveOptions2 {
        speed: Some(&slow),
        ..SolveOptions2::default()
    };
    let out = FastMarching::default().solve2_with(&grid, &[Cell2::new(20, 20)], options);
    match out {
        Err(e) => assert!(e.to_string().contains("overflow"), "{e}"),
        Ok(f) => assert!(f.values().iter().all(|v| !v.is_nan())),
    }
}
