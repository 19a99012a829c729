//! The doorway scene the crowd tests share (this crate's and the facade's, which includes
//! this file by path): its parent brings `Cell2`, `Grid2` and `Trip` into scope.

use super::{Cell2, Grid2, Trip};

/// Two 17x17 rooms side by side (in centre space: where a body's centre may stand), joined
/// by a doorway three cells wide and five long: one person at a time fits through it.
pub fn two_rooms() -> Grid2 {
    let (rows, cols) = (21, 41);
    let obstacles = (0..rows * cols)
        .map(|i| {
            let (r, c) = (i / cols, i % cols);
            let border = r < 2 || r >= rows - 2 || c < 2 || c >= cols - 2;
            border || ((18..=22).contains(&c) && !(9..=11).contains(&r))
        })
        .collect();
    Grid2::from_obstacles(rows, cols, obstacles).unwrap()
}

/// Two people crossing the doorway in opposite directions.
pub fn opposite_trips() -> Vec<Trip> {
    vec![
        Trip {
            start: Cell2::new(10, 5),
            goal: Cell2::new(12, 36),
        },
        Trip {
            start: Cell2::new(8, 35),
            goal: Cell2::new(10, 4),
        },
    ]
}
