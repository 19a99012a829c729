use crate::{Cell2, Cell3, GridError, Result};
use serde::{Deserialize, Serialize};

pub(crate) fn checked_len(shape: &[usize]) -> Result<usize> {
    if shape.contains(&0) {
        return Err(GridError::InvalidShape {
            shape: shape.to_vec(),
            reason: "every dimension must be at least 1".into(),
        });
    }
    shape
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .filter(|&n| n <= u32::MAX as usize / 2)
        .ok_or_else(|| GridError::InvalidShape {
            shape: shape.to_vec(),
            reason: "too many cells (at most 2^31)".into(),
        })
}

fn check_len(len: usize, shape: &[usize]) -> Result<()> {
    let expected = checked_len(shape)?;
    if len != expected {
        return Err(GridError::LengthMismatch {
            len,
            shape: shape.to_vec(),
            expected,
        });
    }
    Ok(())
}

/// A 2D occupancy grid: each cell is free or an obstacle. Row-major storage.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Grid2 {
    rows: usize,
    cols: usize,
    obstacles: Vec<bool>,
}

impl Grid2 {
    /// An obstacle-free grid of `rows x cols` cells.
    ///
    /// # Errors
    /// [`GridError::InvalidShape`] when a dimension is 0 or the grid has more than 2^31 cells.
    pub fn new(rows: usize, cols: usize) -> Result<Self> {
        let n = checked_len(&[rows, cols])?;
        Ok(Self {
            rows,
            cols,
            obstacles: vec![false; n],
        })
    }

    /// A grid from a row-major obstacle mask (`true` = obstacle).
    ///
    /// # Errors
    /// [`GridError::LengthMismatch`] when `obstacles.len() != rows * cols`.
    pub fn from_obstacles(rows: usize, cols: usize, obstacles: Vec<bool>) -> Result<Self> {
        check_len(obstacles.len(), &[rows, cols])?;
        Ok(Self {
            rows,
            cols,
            obstacles,
        })
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.obstacles.len()
    }

    /// Always `false`: a grid has at least one cell.
    pub fn is_empty(&self) -> bool {
        self.obstacles.is_empty()
    }

    /// The row-major obstacle mask (`true` = obstacle).
    pub fn obstacles(&self) -> &[bool] {
        &self.obstacles
    }

    /// Whether `cell` lies inside the grid.
    pub fn contains(&self, cell: Cell2) -> bool {
        cell.row < self.rows && cell.col < self.cols
    }

    /// The row-major index of `cell`, or `None` when it lies outside.
    pub fn index(&self, cell: Cell2) -> Option<usize> {
        self.contains(cell).then(|| cell.row * self.cols + cell.col)
    }

    /// The cell at row-major index `i` (which must be `< len()`).
    pub fn cell(&self, i: usize) -> Cell2 {
        Cell2::new(i / self.cols, i % self.cols)
    }

    /// Whether `cell` is inside the grid and free.
    pub fn is_free(&self, cell: Cell2) -> bool {
        self.index(cell).is_some_and(|i| !self.obstacles[i])
    }

    /// Whether `cell` is an obstacle; cells outside the grid count as obstacles.
    pub fn is_obstacle(&self, cell: Cell2) -> bool {
        !self.is_free(cell)
    }

    /// Marks `cell` as an obstacle (`true`) or free (`false`).
    ///
    /// # Errors
    /// [`GridError::OutOfBounds`] when the cell lies outside the grid.
    pub fn set_obstacle(&mut self, cell: Cell2, obstacle: bool) -> Result<()> {
        let i = self.check(cell)?;
        self.obstacles[i] = obstacle;
        Ok(())
    }

    /// The index of `cell`, or an error naming the cell when it lies outside.
    ///
    /// # Errors
    /// [`GridError::OutOfBounds`].
    pub fn check(&self, cell: Cell2) -> Result<usize> {
        self.index(cell).ok_or_else(|| GridError::OutOfBounds {
            cell: cell.to_string(),
            shape: format!("{}x{}", self.rows, self.cols),
        })
    }

    /// The index of `cell` when it is inside and free; otherwise an error that says which.
    ///
    /// # Errors
    /// [`GridError::OutOfBounds`] or [`GridError::Invalid`] (the cell is an obstacle); `what`
    /// names the cell's role in the message ("goal", "start", ...).
    pub fn check_free(&self, cell: Cell2, what: &str) -> Result<usize> {
        let i = self.check(cell)?;
        if self.obstacles[i] {
            return Err(GridError::Invalid(format!(
                "{what} {cell} is on an obstacle"
            )));
        }
        Ok(i)
    }

    /// Number of free cells.
    pub fn free_count(&self) -> usize {
        self.obstacles.iter().filter(|&&o| !o).count()
    }

    /// Iterator over the free cells in row-major order.
    pub fn free_cells(&self) -> impl Iterator<Item = Cell2> + '_ {
        self.obstacles
            .iter()
            .enumerate()
            .filter(|(_, &o)| !o)
            .map(|(i, _)| self.cell(i))
    }

    /// This grid in the top-left corner of a `rows x cols` grid whose other cells are
    /// obstacles: maps of different sizes brought to one size for a batch, cells keeping
    /// their coordinates.
    ///
    /// # Errors
    /// [`GridError::InvalidShape`] when `rows x cols` is smaller than this grid along either axis.
    pub fn padded(&self, rows: usize, cols: usize) -> Result<Self> {
        if rows < self.rows || cols < self.cols {
            return Err(GridError::InvalidShape {
                shape: vec![rows, cols],
                reason: format!(
                    "cannot pad a {}x{} grid to a smaller {rows}x{cols}",
                    self.rows, self.cols
                ),
            });
        }
        let mut obstacles = vec![true; rows * cols];
        for r in 0..self.rows {
            obstacles[r * cols..r * cols + self.cols]
                .copy_from_slice(&self.obstacles[r * self.cols..(r + 1) * self.cols]);
        }
        Self::from_obstacles(rows, cols, obstacles)
    }
}

/// A 3D occupancy grid indexed `(x, y, z)`, stored in C order (z fastest), as `numpy` stores
/// an array of shape `(nx, ny, nz)`.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Grid3 {
    shape: [usize; 3],
    obstacles: Vec<bool>,
}

impl Grid3 {
    /// An obstacle-free grid of `nx x ny x nz` cells.
    ///
    /// # Errors
    /// [`GridError::InvalidShape`] when a dimension is 0 or the grid has more than 2^31 cells.
    pub fn new(nx: usize, ny: usize, nz: usize) -> Result<Self> {
        let n = checked_len(&[nx, ny, nz])?;
        Ok(Self {
            shape: [nx, ny, nz],
            obstacles: vec![false; n],
        })
    }

    /// A grid from a C-order obstacle mask (`true` = obstacle).
    ///
    /// # Errors
    /// [`GridError::LengthMismatch`] when the mask length is not `nx * ny * nz`.
    pub fn from_obstacles(shape: [usize; 3], obstacles: Vec<bool>) -> Result<Self> {
        check_len(obstacles.len(), &shape)?;
        Ok(Self { shape, obstacles })
    }

    /// `[nx, ny, nz]`.
    pub fn shape(&self) -> [usize; 3] {
        self.shape
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.obstacles.len()
    }

    /// Always `false`: a grid has at least one cell.
    pub fn is_empty(&self) -> bool {
        self.obstacles.is_empty()
    }

    /// The C-order obstacle mask.
    pub fn obstacles(&self) -> &[bool] {
        &self.obstacles
    }

    /// Whether `cell` lies inside the grid.
    pub fn contains(&self, c: Cell3) -> bool {
        c.x < self.shape[0] && c.y < self.shape[1] && c.z < self.shape[2]
    }

    /// The C-order index of `cell`, or `None` when it lies outside.
    pub fn index(&self, c: Cell3) -> Option<usize> {
        self.contains(c)
            .then(|| (c.x * self.shape[1] + c.y) * self.shape[2] + c.z)
    }

    /// The cell at C-order index `i` (which must be `< len()`).
    pub fn cell(&self, i: usize) -> Cell3 {
        let z = i % self.shape[2];
        let y = (i / self.shape[2]) % self.shape[1];
        Cell3::new(i / (self.shape[1] * self.shape[2]), y, z)
    }

    /// Whether `cell` is inside and free.
    pub fn is_free(&self, c: Cell3) -> bool {
        self.index(c).is_some_and(|i| !self.obstacles[i])
    }

    /// Marks `cell` as an obstacle or free.
    ///
    /// # Errors
    /// [`GridError::OutOfBounds`] when the cell lies outside the grid.
    pub fn set_obstacle(&mut self, c: Cell3, obstacle: bool) -> Result<()> {
        let i = self.check(c)?;
        self.obstacles[i] = obstacle;
        Ok(())
    }

    /// The index of `cell`, or an error naming it when it lies outside.
    ///
    /// # Errors
    /// [`GridError::OutOfBounds`].
    pub fn check(&self, c: Cell3) -> Result<usize> {
        self.index(c).ok_or_else(|| GridError::OutOfBounds {
            cell: c.to_string(),
            shape: format!("{}x{}x{}", self.shape[0], self.shape[1], self.shape[2]),
        })
    }

    /// The index of `cell` when it is inside and free; otherwise an error naming it as `what`.
    ///
    /// # Errors
    /// [`GridError::OutOfBounds`] or [`GridError::Invalid`].
    pub fn check_free(&self, c: Cell3, what: &str) -> Result<usize> {
        let i = self.check(c)?;
        if self.obstacles[i] {
            return Err(GridError::Invalid(format!("{what} {c} is on an obstacle")));
        }
        Ok(i)
    }

    /// Number of free cells.
    pub fn free_count(&self) -> usize {
        self.obstacles.iter().filter(|&&o| !o).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn padding_keeps_the_cells_and_blocks_the_rest() {
        let mut g = Grid2::new(2, 3).unwrap();
        g.set_obstacle(Cell2::new(1, 2), true).unwrap();
        let p = g.padded(4, 5).unwrap();
        for r in 0..4 {
            for c in 0..5 {
                let cell = Cell2::new(r, c);
                // Outside the original 2x3 every cell is padding.
                let expected = !(r < 2 && c < 3) || g.is_obstacle(cell);
                assert_eq!(p.is_obstacle(cell), expected, "{cell:?}");
            }
        }
        assert_eq!(g.padded(2, 3).unwrap(), g);
        assert!(g.padded(1, 5).unwrap_err().to_string().contains("smaller"));
    }

    #[test]
    fn zero_sized_grids_are_rejected() {
        assert!(matches!(
            Grid2::new(0, 3),
            Err(GridError::InvalidShape { .. })
        ));
        assert!(Grid3::new(2, 0, 2).is_err());
        assert!(matches!(
            Grid2::from_obstacles(2, 2, vec![false; 3]),
            Err(GridError::LengthMismatch { expected: 4, .. })
        ));
    }

    #[test]
    fn indices_round_trip() {
        let g = Grid3::new(3, 4, 5).unwrap();
        for i in 0..g.len() {
            assert_eq!(g.index(g.cell(i)), Some(i));
        }
        let g = Grid2::new(3, 7).unwrap();
        for i in 0..g.len() {
            assert_eq!(g.index(g.cell(i)), Some(i));
        }
        assert!(g.is_obstacle(Cell2::new(3, 0)));
    }
}
