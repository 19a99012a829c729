use crate::{Cell2, Cell3, GridError, Point2, Point3, Result};
use serde::{Deserialize, Serialize};

fn check_point(what: &'static str, v: f32, extent: usize) -> Result<()> {
    if !v.is_finite() {
        return Err(GridError::NotFinite { what, value: v });
    }
    if v < 0.0 || v > (extent - 1) as f32 {
        return Err(GridError::Invalid(format!(
            "coordinate {what} = {v} is outside [0, {}]",
            extent - 1
        )));
    }
    Ok(())
}

/// Splits a coordinate in `[0, n-1]` into a lower cell index and a weight for the upper one.
fn split(v: f32, n: usize) -> (usize, usize, f32) {
    // v >= 0 (checked by every caller), so the cast is the floor, without a call into libm.
    let i0 = (v as usize).min(n - 1);
    let i1 = (i0 + 1).min(n - 1);
    (i0, i1, v - i0 as f32)
}

/// Interpolates between corner values; a corner that carries weight and is infinite makes the
/// result infinite (an obstacle or unreachable cell is never averaged into a finite value).
fn lerp_inf(values: &[(f32, f32)]) -> f32 {
    let mut acc = 0.0f32;
    for &(v, w) in values {
        if w > 0.0 {
            if !v.is_finite() {
                return f32::INFINITY;
            }
            acc += v * w;
        }
    }
    acc
}

/// A scalar field on a 2D grid (row-major, f32). In reaching-distance fields the value is the
/// distance to the goal and `f32::INFINITY` marks obstacles and unreachable cells.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Field2 {
    rows: usize,
    cols: usize,
    values: Vec<f32>,
}

impl Field2 {
    /// A field from row-major values.
    ///
    /// # Errors
    /// [`GridError::LengthMismatch`] or [`GridError::InvalidShape`].
    pub fn new(rows: usize, cols: usize, values: Vec<f32>) -> Result<Self> {
        crate::grid::checked_len(&[rows, cols])?;
        if values.len() != rows * cols {
            return Err(GridError::LengthMismatch {
                len: values.len(),
                shape: vec![rows, cols],
                expected: rows * cols,
            });
        }
        Ok(Self { rows, cols, values })
    }

    /// A field with every cell set to `value`.
    ///
    /// # Errors
    /// [`GridError::InvalidShape`].
    pub fn filled(rows: usize, cols: usize, value: f32) -> Result<Self> {
        crate::grid::checked_len(&[rows, cols])?;
        Ok(Self {
            rows,
            cols,
            values: vec![value; rows * cols],
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

    /// The row-major values.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The row-major values, mutable.
    pub fn values_mut(&mut self) -> &mut [f32] {
        &mut self.values
    }

    /// Consumes the field and returns its values.
    pub fn into_values(self) -> Vec<f32> {
        self.values
    }

    /// The value at `cell`, or `None` outside the field.
    pub fn get(&self, cell: Cell2) -> Option<f32> {
        (cell.row < self.rows && cell.col < self.cols)
            .then(|| self.values[cell.row * self.cols + cell.col])
    }

    /// Sets the value at `cell`.
    ///
    /// # Errors
    /// [`GridError::OutOfBounds`].
    pub fn set(&mut self, cell: Cell2, value: f32) -> Result<()> {
        if cell.row >= self.rows || cell.col >= self.cols {
            return Err(GridError::OutOfBounds {
                cell: cell.to_string(),
                shape: format!("{}x{}", self.rows, self.cols),
            });
        }
        self.values[cell.row * self.cols + cell.col] = value;
        Ok(())
    }

    /// Bilinear interpolation at a continuous point (cell centres at integer coordinates).
    /// Infinite when a corner with non-zero weight is infinite.
    ///
    /// # Errors
    /// [`GridError::NotFinite`] for a NaN or infinite coordinate, [`GridError::Invalid`] for a
    /// point outside `[0, rows-1] x [0, cols-1]`.
    pub fn sample(&self, p: Point2) -> Result<f32> {
        check_point("row", p.row, self.rows)?;
        check_point("col", p.col, self.cols)?;
        let (r0, r1, fr) = split(p.row, self.rows);
        let (c0, c1, fc) = split(p.col, self.cols);
        let at = |r: usize, c: usize| self.values[r * self.cols + c];
        Ok(lerp_inf(&[
            (at(r0, c0), (1.0 - fr) * (1.0 - fc)),
            (at(r0, c1), (1.0 - fr) * fc),
            (at(r1, c0), fr * (1.0 - fc)),
            (at(r1, c1), fr * fc),
        ]))
    }

    /// The smallest and largest finite values, or `None` when no value is finite.
    pub fn finite_range(&self) -> Option<(f32, f32)> {
        self.values
            .iter()
            .filter(|v| v.is_finite())
            .fold(None, |acc, &v| match acc {
                None => Some((v, v)),
                Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
            })
    }
}

/// A scalar field on a 3D grid (C order, z fastest, f32); `f32::INFINITY` marks obstacles and
/// unreachable cells in reaching-distance fields.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Field3 {
    shape: [usize; 3],
    values: Vec<f32>,
}

impl Field3 {
    /// A field from C-order values.
    ///
    /// # Errors
    /// [`GridError::LengthMismatch`] or [`GridError::InvalidShape`].
    pub fn new(shape: [usize; 3], values: Vec<f32>) -> Result<Self> {
        crate::grid::checked_len(&shape)?;
        let n = shape.iter().product();
        if values.len() != n {
            return Err(GridError::LengthMismatch {
                len: values.len(),
                shape: shape.to_vec(),
                expected: n,
            });
        }
        Ok(Self { shape, values })
    }

    /// `[nx, ny, nz]`.
    pub fn shape(&self) -> [usize; 3] {
        self.shape
    }

    /// The C-order values.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// Consumes the field and returns its values.
    pub fn into_values(self) -> Vec<f32> {
        self.values
    }

    /// The value at `cell`, or `None` outside the field.
    pub fn get(&self, c: Cell3) -> Option<f32> {
        let [nx, ny, nz] = self.shape;
        (c.x < nx && c.y < ny && c.z < nz).then(|| self.values[(c.x * ny + c.y) * nz + c.z])
    }

    /// Trilinear interpolation at a continuous point; infinite when a weighted corner is.
    ///
    /// # Errors
    /// [`GridError::NotFinite`] or [`GridError::Invalid`] (outside the field).
    pub fn sample(&self, p: Point3) -> Result<f32> {
        Ok(lerp_inf(&self.corners(p)?))
    }

    /// Trilinear interpolation over the finite corners only, their weights renormalised;
    /// infinite when the cell holding `p` (the nearest cell centre) is. Where infinity marks
    /// obstacles, this is finite everywhere in a free cell, right up to its faces, which
    /// [`Field3::sample`] is not within half a cell of an obstacle.
    ///
    /// # Errors
    /// As [`Field3::sample`].
    pub fn sample_finite(&self, p: Point3) -> Result<f32> {
        check_inside(self.shape, p)?;
        Ok(sample_finite_within(self.shape, p, |i| self.values[i]))
    }

    /// The eight (value, trilinear weight) corners around `p`.
    fn corners(&self, p: Point3) -> Result<[(f32, f32); 8]> {
        check_inside(self.shape, p)?;
        Ok(corner_weights(self.shape, p).map(|(i, w)| (self.values[i], w)))
    }
}

/// Checks that `p` is finite and within a field of `shape` on every axis.
fn check_inside(shape: [usize; 3], p: Point3) -> Result<()> {
    let [nx, ny, nz] = shape;
    check_point("x", p.x, nx)?;
    check_point("y", p.y, ny)?;
    check_point("z", p.z, nz)
}

/// [`Field3::sample_finite`]'s arithmetic over a field of `shape` whose value at C-order index
/// `i` is `at(i)` (a field stored otherwise than as a dense array: the values of a region's
/// accessible voxels alone), at a point the caller has checked: finite, every coordinate
/// within `[0, n - 1]` of its axis (a point outside reads the nearest cells inside, never out
/// of bounds). Only corners that weigh are read. A search asks this of thousands of points a
/// path, each checked once already.
#[inline]
pub fn sample_finite_within(shape: [usize; 3], p: Point3, at: impl Fn(usize) -> f32) -> f32 {
    let [nx, ny, nz] = shape;
    // Half up is f32::round here for coordinates >= 0, without libm.
    let round = |v: f32, n: usize| ((v + 0.5) as usize).min(n - 1);
    if !at((round(p.x, nx) * ny + round(p.y, ny)) * nz + round(p.z, nz)).is_finite() {
        return f32::INFINITY;
    }
    let (mut acc, mut weight) = (0.0f32, 0.0f32);
    for (i, w) in corner_weights(shape, p) {
        if w > 0.0 {
            let v = at(i);
            if v.is_finite() {
                acc += v * w;
                weight += w;
            }
        }
    }
    // The holding cell is finite and weighs at least 1/8.
    acc / weight
}

/// The C-order index and trilinear weight of each of the eight corners around `p` in a field
/// of `shape` (every coordinate of `p` checked to lie within its axis).
#[inline]
fn corner_weights(shape: [usize; 3], p: Point3) -> [(usize, f32); 8] {
    let [nx, ny, nz] = shape;
    let (x0, x1, fx) = split(p.x, nx);
    let (y0, y1, fy) = split(p.y, ny);
    let (z0, z1, fz) = split(p.z, nz);
    std::array::from_fn(|k| {
        let (bx, by, bz) = (k & 4 != 0, k & 2 != 0, k & 1 != 0);
        let w = (if bx { fx } else { 1.0 - fx })
            * (if by { fy } else { 1.0 - fy })
            * (if bz { fz } else { 1.0 - fz });
        let (x, y, z) = (
            if bx { x1 } else { x0 },
            if by { y1 } else { y0 },
            if bz { z1 } else { z0 },
        );
        ((x * ny + y) * nz + z, w)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn finite_corner_sampling_stays_finite_in_free_cells() {
        let f = Field3::new([3, 1, 1], vec![1.0, 2.0, f32::INFINITY]).unwrap();
        assert!(f.sample(Point3::new(1.3, 0.0, 0.0)).unwrap().is_infinite());
        assert_relative_eq!(f.sample_finite(Point3::new(1.3, 0.0, 0.0)).unwrap(), 2.0);
        assert_relative_eq!(f.sample_finite(Point3::new(0.5, 0.0, 0.0)).unwrap(), 1.5);
        assert!(f
            .sample_finite(Point3::new(1.6, 0.0, 0.0))
            .unwrap()
            .is_infinite());
        let f = Field3::new([3, 1, 1], vec![f32::INFINITY, 2.0, 3.0]).unwrap();
        assert_relative_eq!(f.sample_finite(Point3::new(0.8, 0.0, 0.0)).unwrap(), 2.0);
        assert!(f.sample_finite(Point3::new(f32::NAN, 0.0, 0.0)).is_err());
    }

    #[test]
    fn bilinear_is_exact_on_planes_and_respects_infinity() {
        let f = Field2::new(2, 3, vec![0.0, 1.0, 2.0, 10.0, 11.0, 12.0]).unwrap();
        assert_relative_eq!(f.sample(Point2::new(0.5, 1.5)).unwrap(), 6.5);
        assert_relative_eq!(f.sample(Point2::new(1.0, 2.0)).unwrap(), 12.0);
        assert!(f.sample(Point2::new(f32::NAN, 0.0)).is_err());
        assert!(f.sample(Point2::new(0.0, 2.5)).is_err());
        let mut g = f.clone();
        g.set(Cell2::new(0, 0), f32::INFINITY).unwrap();
        assert!(g.sample(Point2::new(0.5, 0.5)).unwrap().is_infinite());
        // A point exactly on a finite cell does not see its infinite neighbour.
        assert_relative_eq!(g.sample(Point2::new(0.0, 1.0)).unwrap(), 1.0);
    }

    #[test]
    fn trilinear_is_exact_on_linear_functions() {
        let shape = [3, 4, 5];
        let vals: Vec<f32> = (0..60)
            .map(|i| {
                let (x, y, z) = (i / 20, (i / 5) % 4, i % 5);
                x as f32 + 2.0 * y as f32 - 0.5 * z as f32
            })
            .collect();
        let f = Field3::new(shape, vals).unwrap();
        let p = Point3::new(1.25, 2.5, 3.75);
        assert_relative_eq!(f.sample(p).unwrap(), 1.25 + 5.0 - 1.875, epsilon = 1e-5);
    }
}
