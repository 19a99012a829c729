//! The eight symmetries of a grid (the dihedral group of the square): transposes and flips.
//!
//! Both move rules look the same in every one of them, so the distance field of a transformed
//! grid is the transformed field. [`Symmetric`] uses that to average a model's predictions over
//! several views of one maze (test-time augmentation).

use crate::{Cell2, Field2, FieldModel, Grid2, Result};

/// One of the eight symmetries of a grid: an optional transpose, then optional flips of the
/// rows (top to bottom) and of the columns (left to right).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Symmetry {
    /// Swap rows and columns first.
    pub transpose: bool,
    /// Then reverse the row order.
    pub flip_rows: bool,
    /// Then reverse the column order.
    pub flip_cols: bool,
}

impl Symmetry {
    /// The identity.
    pub const IDENTITY: Symmetry = Symmetry {
        transpose: false,
        flip_rows: false,
        flip_cols: false,
    };

    /// All eight, the identity first.
    pub fn all() -> [Symmetry; 8] {
        std::array::from_fn(|k| Symmetry {
            transpose: k & 4 != 0,
            flip_rows: k & 1 != 0,
            flip_cols: k & 2 != 0,
        })
    }

    /// The shape `(rows, cols)` of a `rows x cols` grid after the transform.
    pub fn shape(self, rows: usize, cols: usize) -> (usize, usize) {
        if self.transpose {
            (cols, rows)
        } else {
            (rows, cols)
        }
    }

    /// Where `cell` of a `rows x cols` grid lands. The cell must lie in the grid.
    pub fn cell(self, cell: Cell2, rows: usize, cols: usize) -> Cell2 {
        let (r, c) = if self.transpose {
            (cell.col, cell.row)
        } else {
            (cell.row, cell.col)
        };
        let (rows, cols) = self.shape(rows, cols);
        Cell2::new(
            if self.flip_rows { rows - 1 - r } else { r },
            if self.flip_cols { cols - 1 - c } else { c },
        )
    }

    /// The transformed grid.
    pub fn grid(self, grid: &Grid2) -> Grid2 {
        let (rows, cols) = self.shape(grid.rows(), grid.cols());
        let mut obstacles = vec![false; grid.len()];
        for (i, &blocked) in grid.obstacles().iter().enumerate() {
            let to = self.cell(grid.cell(i), grid.rows(), grid.cols());
            obstacles[to.row * cols + to.col] = blocked;
        }
        Grid2::from_obstacles(rows, cols, obstacles).expect("same number of cells")
    }

    /// Adds the values of `field`, a field on the *transformed* `rows x cols` grid, back onto
    /// the cells of the original grid: `sum[i] += field[self.cell(i)]`.
    fn add_back(self, field: &Field2, rows: usize, cols: usize, sum: &mut [f32]) {
        let (_, tcols) = self.shape(rows, cols);
        let values = field.values();
        for (i, s) in sum.iter_mut().enumerate() {
            let to = self.cell(Cell2::new(i / cols, i % cols), rows, cols);
            *s += values[to.row * tcols + to.col];
        }
    }
}

/// A [`FieldModel`] that averages another model's fields over several [`Symmetry`] views of
/// the maze: each view's field is mapped back and the mean taken cell by cell. Cells that any
/// view calls unreachable stay infinite. It costs one prediction per view.
pub struct Symmetric<M> {
    /// The model asked for every view.
    pub model: M,
    symmetries: Vec<Symmetry>,
    name: String,
}

impl<M: FieldModel> Symmetric<M> {
    /// Averages `model` over the first `views` of [`Symmetry::all`] (1 to 8; 1 is the model
    /// alone, 2 adds the transpose-free row flip, 4 all flips, 8 all symmetries).
    ///
    /// # Errors
    /// When `views` is not in `1..=8`.
    pub fn new(model: M, views: usize) -> Result<Self> {
        if !(1..=8).contains(&views) {
            return Err(crate::GridError::Invalid(format!(
                "symmetric views must be 1 to 8, got {views}"
            )));
        }
        let name = format!("{}x{views}", model.name());
        Ok(Self {
            model,
            symmetries: Symmetry::all()[..views].to_vec(),
            name,
        })
    }
}

impl<M: FieldModel> FieldModel for Symmetric<M> {
    fn name(&self) -> &str {
        &self.name
    }

    fn predict(&self, grid: &Grid2, goal: Cell2) -> Result<Field2> {
        grid.check_free(goal, "goal")?;
        let (rows, cols) = (grid.rows(), grid.cols());
        let mut sum = vec![0.0f32; grid.len()];
        for &s in &self.symmetries {
            let field = self
                .model
                .predict(&s.grid(grid), s.cell(goal, rows, cols))?;
            s.add_back(&field, rows, cols, &mut sum);
        }
        let n = self.symmetries.len() as f32;
        sum.iter_mut().for_each(|v| *v /= n);
        Field2::new(rows, cols, sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_symmetry_is_a_bijection_and_maps_grids_consistently() {
        let mut grid = Grid2::new(3, 5).unwrap();
        grid.set_obstacle(Cell2::new(0, 1), true).unwrap();
        grid.set_obstacle(Cell2::new(2, 4), true).unwrap();
        for s in Symmetry::all() {
            let t = s.grid(&grid);
            assert_eq!((t.rows(), t.cols()), s.shape(3, 5));
            let mut seen = std::collections::HashSet::new();
            for i in 0..grid.len() {
                let c = grid.cell(i);
                let to = s.cell(c, 3, 5);
                assert!(t.contains(to));
                assert!(seen.insert(to), "{s:?} maps two cells onto {to:?}");
                assert_eq!(grid.is_obstacle(c), t.is_obstacle(to));
            }
        }
    }
}
