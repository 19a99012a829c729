use crate::{Cell2, Field2, Grid2, Point2, Result};

/// A point in a 3D field's own frame, as `[x, y, z]` (metres for the fields of 3D scenes).
pub type Point3m = [f32; 3];

/// The seam between learning and planning: anything that can answer "the reaching-distance
/// field of this grid for this goal".
///
/// Values are in distance units (cells): the goal is 0, smaller is closer, obstacles and
/// unreachable cells are `f32::INFINITY`. The exact solvers of `envfield-eikonal` (the oracle)
/// and every trained network implement it, so planners, metrics and benchmarks treat them alike.
pub trait FieldModel {
    /// A short name for tables and logs ("fmm", "context", ...).
    fn name(&self) -> &str;

    /// The reaching-distance field of `grid` for `goal`, one value per cell.
    ///
    /// # Errors
    /// When the goal is outside the grid or on an obstacle, when the grid is a size the model
    /// does not accept, or when the model itself fails ([`crate::GridError::Model`]).
    fn predict(&self, grid: &Grid2, goal: Cell2) -> Result<Field2>;

    /// The fields of many `(grid, goal)` problems, in order. The default answers them one by
    /// one; a network answers same-sized grids in one batched pass and the exact solvers in
    /// parallel, which is what a step of several people on their own changed maps needs.
    ///
    /// # Errors
    /// The first error of any problem, as [`FieldModel::predict`].
    fn predict_many(&self, problems: &[(&Grid2, Cell2)]) -> Result<Vec<Field2>> {
        problems
            .iter()
            .map(|&(grid, goal)| self.predict(grid, goal))
            .collect()
    }
}

/// A continuous reaching-distance field on one grid with one goal, for queries at arbitrary
/// points (gradient descent, 3D search). Points are in cell units as in [`Point2`].
pub trait ContinuousField2 {
    /// The reaching distance at `p`.
    ///
    /// # Errors
    /// When `p` is not finite or lies outside the domain.
    fn value(&self, p: Point2) -> Result<f32>;

    /// The gradient `(d/d row, d/d col)` at `p`, or `Ok(None)` when the model has none there
    /// (for example next to an obstacle of a sampled field).
    ///
    /// # Errors
    /// As [`ContinuousField2::value`].
    fn gradient(&self, p: Point2) -> Result<Option<(f32, f32)>>;
}

/// A continuous reaching-distance field in 3D, for queries at arbitrary points in the field's
/// own frame (metres, z up, for the fields of 3D scenes): the exact field of an accessible
/// region (trilinear) and a learned one answer alike, so 3D planners need no candle.
///
/// Values are distances to the field's goal; points outside the accessible region are
/// `f32::INFINITY`.
pub trait ContinuousField3 {
    /// The reaching distance at `p`.
    ///
    /// # Errors
    /// When `p` is not finite or lies outside the field's domain, or the model fails.
    fn value(&self, p: Point3m) -> Result<f32>;

    /// The reaching distances at many points; a learned field answers them in one network
    /// pass.
    ///
    /// # Errors
    /// As [`ContinuousField3::value`], for the first bad point.
    fn values(&self, points: &[Point3m]) -> Result<Vec<f32>> {
        points.iter().map(|&p| self.value(p)).collect()
    }

    /// The gradient at `p`, or `Ok(None)` where the field has none (outside the accessible
    /// region, or beside its edge for a sampled field).
    ///
    /// # Errors
    /// As [`ContinuousField3::value`].
    fn gradient(&self, p: Point3m) -> Result<Option<Point3m>>;
}

impl<F: ContinuousField3 + ?Sized> ContinuousField3 for &F {
    fn value(&self, p: Point3m) -> Result<f32> {
        (**self).value(p)
    }

    fn values(&self, points: &[Point3m]) -> Result<Vec<f32>> {
        (**self).values(points)
    }

    fn gradient(&self, p: Point3m) -> Result<Option<Point3m>> {
        (**self).gradient(p)
    }
}

impl ContinuousField2 for Field2 {
    fn value(&self, p: Point2) -> Result<f32> {
        self.sample(p)
    }

    /// Central differences of the bilinear interpolant over half a cell, clamped to the field.
    fn gradient(&self, p: Point2) -> Result<Option<(f32, f32)>> {
        self.sample(p)?;
        let h = 0.5f32;
        let (rmax, cmax) = ((self.rows() - 1) as f32, (self.cols() - 1) as f32);
        let diff = |a: Point2, b: Point2, len: f32| -> Result<Option<f32>> {
            let (va, vb) = (self.sample(a)?, self.sample(b)?);
            Ok((va.is_finite() && vb.is_finite() && len > 0.0).then(|| (vb - va) / len))
        };
        let (r0, r1) = ((p.row - h).max(0.0), (p.row + h).min(rmax));
        let (c0, c1) = ((p.col - h).max(0.0), (p.col + h).min(cmax));
        let dr = diff(Point2::new(r0, p.col), Point2::new(r1, p.col), r1 - r0)?;
        let dc = diff(Point2::new(p.row, c0), Point2::new(p.row, c1), c1 - c0)?;
        Ok(dr.zip(dc))
    }
}

impl<M: FieldModel + ?Sized> FieldModel for Box<M> {
    fn name(&self) -> &str {
        (**self).name()
    }

    fn predict(&self, grid: &Grid2, goal: Cell2) -> Result<Field2> {
        (**self).predict(grid, goal)
    }

    fn predict_many(&self, problems: &[(&Grid2, Cell2)]) -> Result<Vec<Field2>> {
        (**self).predict_many(problems)
    }
}

impl<M: FieldModel + ?Sized> FieldModel for &M {
    fn name(&self) -> &str {
        (**self).name()
    }

    fn predict(&self, grid: &Grid2, goal: Cell2) -> Result<Field2> {
        (**self).predict(grid, goal)
    }

    fn predict_many(&self, problems: &[(&Grid2, Cell2)]) -> Result<Vec<Field2>> {
        (**self).predict_many(problems)
    }
}
