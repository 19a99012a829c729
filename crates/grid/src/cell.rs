use serde::{Deserialize, Serialize};
use std::fmt;

/// A cell of a 2D grid: `row` down, `col` across.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Cell2 {
    /// Row index (0 at the top).
    pub row: usize,
    /// Column index (0 at the left).
    pub col: usize,
}

impl Cell2 {
    /// The cell at `(row, col)`.
    pub const fn new(row: usize, col: usize) -> Self {
        Self { row, col }
    }

    /// The cell's centre as a continuous point.
    pub fn center(self) -> Point2 {
        Point2::new(self.row as f32, self.col as f32)
    }

    /// The cell displaced by `(dr, dc)`, or `None` when that leaves the non-negative quadrant.
    pub fn offset(self, dr: isize, dc: isize) -> Option<Cell2> {
        Some(Cell2::new(
            self.row.checked_add_signed(dr)?,
            self.col.checked_add_signed(dc)?,
        ))
    }
}

impl fmt::Display for Cell2 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {})", self.row, self.col)
    }
}

/// A cell of a 3D grid, indexed `(x, y, z)`; z is up.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Cell3 {
    /// First index.
    pub x: usize,
    /// Second index.
    pub y: usize,
    /// Third index (up).
    pub z: usize,
}

impl Cell3 {
    /// The cell at `(x, y, z)`.
    pub const fn new(x: usize, y: usize, z: usize) -> Self {
        Self { x, y, z }
    }

    /// The cell's centre as a continuous point.
    pub fn center(self) -> Point3 {
        Point3::new(self.x as f32, self.y as f32, self.z as f32)
    }
}

impl fmt::Display for Cell3 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {}, {})", self.x, self.y, self.z)
    }
}

/// A continuous position on a 2D grid, in cell units: cell `(r, c)` has its centre at
/// `Point2 { row: r, col: c }`.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct Point2 {
    /// Row coordinate.
    pub row: f32,
    /// Column coordinate.
    pub col: f32,
}

impl Point2 {
    /// The point at `(row, col)`.
    pub const fn new(row: f32, col: f32) -> Self {
        Self { row, col }
    }

    /// Euclidean distance to `other`, in cells.
    pub fn distance(self, other: Point2) -> f32 {
        (self.row - other.row).hypot(self.col - other.col)
    }

    /// The nearest cell, or `None` when the point is not finite or lies before row/column 0.
    pub fn round(self) -> Option<Cell2> {
        let (r, c) = (self.row.round(), self.col.round());
        (r.is_finite() && c.is_finite() && r >= 0.0 && c >= 0.0)
            .then(|| Cell2::new(r as usize, c as usize))
    }
}

/// A continuous position on a 3D grid, in cell units (cell centres at integer coordinates).
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct Point3 {
    /// x coordinate.
    pub x: f32,
    /// y coordinate.
    pub y: f32,
    /// z coordinate (up).
    pub z: f32,
}

impl Point3 {
    /// The point at `(x, y, z)`.
    pub const fn new(x: f32, y: f32, z: f32) -> Self {
        Self { x, y, z }
    }

    /// Euclidean distance to `other`, in cells.
    pub fn distance(self, other: Point3) -> f32 {
        let (dx, dy, dz) = (self.x - other.x, self.y - other.y, self.z - other.z);
        (dx * dx + dy * dy + dz * dz).sqrt()
    }
}
