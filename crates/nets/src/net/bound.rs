//! A network bound to one grid and goal, as a continuous field.

use super::{model_error, FieldNet};
use crate::{Batch, Result};
use envfield_grid::{Cell2, ContinuousField2, FieldModel, Grid2, Point2};

/// A network bound to one grid and goal: values and analytic gradients at continuous points
/// ([`ContinuousField2`]), in distance units (decoded as [`crate::TargetEncoding::decode`]).
#[derive(Debug)]
pub struct BoundField<'a> {
    pub(super) net: &'a FieldNet,
    pub(super) grid: &'a Grid2,
    pub(super) goal: Cell2,
}

impl BoundField<'_> {
    /// Distances and gradients `(d/d row, d/d col)` at many points in one pass.
    ///
    /// # Errors
    /// A point outside the grid or not finite.
    pub fn values_and_gradients(&self, points: &[Point2]) -> Result<Vec<(f32, [f32; 2])>> {
        let (raw, grad) = self
            .net
            .predict_with_gradient(&Batch::points(self.grid, self.goal, points))?;
        let encoding = self.net.config.encoding();
        Ok(raw
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                let d = encoding.decode(t);
                let slope = encoding.slope(t);
                (d, [slope * grad[2 * i], slope * grad[2 * i + 1]])
            })
            .collect())
    }
}

impl ContinuousField2 for BoundField<'_> {
    fn value(&self, p: Point2) -> envfield_grid::Result<f32> {
        let v = self
            .values_and_gradients(&[p])
            .map_err(|e| model_error(self.net.name(), e))?;
        Ok(v[0].0)
    }

    fn gradient(&self, p: Point2) -> envfield_grid::Result<Option<(f32, f32)>> {
        let v = self
            .values_and_gradients(&[p])
            .map_err(|e| model_error(self.net.name(), e))?;
        let (d, g) = v[0];
        Ok(d.is_finite().then_some((g[0], g[1])))
    }
}
