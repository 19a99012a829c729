//! Averaging the fields of several models of the same maze.

use crate::{Cell2, Field2, FieldModel, Grid2, Result};

/// A [`FieldModel`] whose field is the cell-by-cell mean of several models' fields (an
/// ensemble: networks trained from different seeds or recipes make partly independent
/// mistakes, which the mean dilutes). Cells that any model calls unreachable stay infinite.
/// It costs one prediction per model.
pub struct Ensemble<M> {
    models: Vec<M>,
    name: String,
}

impl<M: FieldModel> Ensemble<M> {
    /// The mean of `models`, named after the first one with the count (`context+2`).
    ///
    /// # Errors
    /// When `models` is empty.
    pub fn new(models: Vec<M>) -> Result<Self> {
        let first = models.first().ok_or_else(|| {
            crate::GridError::Invalid("an ensemble needs at least one model".into())
        })?;
        let name = format!("{}+{}", first.name(), models.len());
        Ok(Self { models, name })
    }

    /// The models averaged.
    pub fn models(&self) -> &[M] {
        &self.models
    }
}

impl<M: FieldModel> FieldModel for Ensemble<M> {
    fn name(&self) -> &str {
        &self.name
    }

    fn predict(&self, grid: &Grid2, goal: Cell2) -> Result<Field2> {
        let mut sum = vec![0.0f32; grid.len()];
        for model in &self.models {
            let field = model.predict(grid, goal)?;
            sum.iter_mut()
                .zip(field.values())
                .for_each(|(s, v)| *s += v);
        }
        let n = self.models.len() as f32;
        sum.iter_mut().for_each(|v| *v /= n);
        Field2::new(grid.rows(), grid.cols(), sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model whose field is `value` everywhere but one unreachable cell.
    struct Flat {
        value: f32,
        unreachable: usize,
    }

    impl FieldModel for Flat {
        fn name(&self) -> &str {
            "flat"
        }

        fn predict(&self, grid: &Grid2, _goal: Cell2) -> Result<Field2> {
            let mut values = vec![self.value; grid.len()];
            values[self.unreachable] = f32::INFINITY;
            Field2::new(grid.rows(), grid.cols(), values)
        }
    }

    #[test]
    fn averages_cell_by_cell_and_keeps_unreachable_cells() {
        let grid = Grid2::new(2, 3).unwrap();
        let models = vec![
            Flat {
                value: 1.0,
                unreachable: 0,
            },
            Flat {
                value: 4.0,
                unreachable: 5,
            },
        ];
        let ensemble = Ensemble::new(models).unwrap();
        assert_eq!(ensemble.name(), "flat+2");
        let field = ensemble.predict(&grid, Cell2::new(0, 1)).unwrap();
        let v = field.values();
        assert!(v[0].is_infinite() && v[5].is_infinite());
        assert!(v[1..5].iter().all(|&x| x == 2.5), "{v:?}");
        assert!(Ensemble::<Flat>::new(Vec::new()).is_err());
    }
}
