//! What lies straight beneath a point: the heights of every surface along vertical lines,
//! exactly from a [`Scene`] (one ray) or from [`SurfaceColumns`], a raster of those lines cast
//! once per room and read back by lookups.
//!
//! A [`crate::DistanceGrid`] cannot answer this near a thin part: its samples on either side of
//! a 4 cm table top both read 2 cm, and so does every point interpolated between them, so a
//! march down by its distances walks through the top.

use crate::error::{check_point, Result, SceneError};
use crate::Scene;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Anything that says whether a surface crosses a vertical segment.
pub trait SurfacesBeneath {
    /// Whether some surface crosses the vertical segment at `(x, y)` strictly between heights
    /// `low` and `high`.
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for a non-finite coordinate.
    fn any_between(&self, x: f32, y: f32, low: f32, high: f32) -> Result<bool>;
}

/// Exact: one ray down from `high`, meeting surfaces from either side (a segment wholly
/// inside a solid crosses none).
impl SurfacesBeneath for Scene {
    fn any_between(&self, x: f32, y: f32, low: f32, high: f32) -> Result<bool> {
        check_point(&Point3::new(x, y, low), "segment")?;
        check_point(&Point3::new(x, y, high), "segment")?;
        if high <= low {
            return Ok(false);
        }
        let hits = self.surfaces_along(&Point3::new(x, y, high), &-Vector3::z(), high - low, 1)?;
        Ok(hits
            .first()
            .is_some_and(|h| h.distance > 0.0 && h.distance < high - low))
    }
}

/// The most columns a raster may hold.
const MAX_COLUMNS: usize = 1 << 24;

/// The most surfaces kept per column (a stack of floors, furniture and their undersides).
const MAX_PER_COLUMN: usize = 64;

/// The heights of every surface along vertical lines on a square raster over a scene's
/// footprint, cast once (in parallel). A query reads the four columns around its point, so a
/// surface within one raster cell (horizontally) of the point counts as beneath it: the
/// answer errs towards "something is there" by up to `cell * sqrt(2)`, never the other way
/// except for a part thinner than a cell that falls between four columns.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceColumns {
    origin: [f32; 2],
    cell: f32,
    shape: [usize; 2],
    /// Where each column's heights start in `heights` (one more entry than columns).
    starts: Vec<u32>,
    /// Every column's surface heights, from the top down.
    heights: Vec<f32>,
}

impl SurfaceColumns {
    /// Casts a column every `cell` metres over `scene`'s footprint grown by `margin`, from
    /// above its top to below its bottom.
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for an empty scene, a cell or margin that is not positive
    /// and finite, or more than 2^24 columns (a level too large for the cell: use a larger
    /// one, or the scene's exact answer).
    pub fn around(scene: &Scene, margin: f32, cell: f32) -> Result<Self> {
        let aabb = scene
            .aabb()
            .ok_or_else(|| SceneError::InvalidInput("surface columns of an empty scene".into()))?;
        if !(cell.is_finite() && cell > 0.0 && margin.is_finite() && margin >= 0.0) {
            return Err(SceneError::InvalidInput(format!(
                "surface columns: a positive cell and a margin >= 0 (got {cell} and {margin})"
            )));
        }
        let origin = [aabb.mins.x - margin, aabb.mins.y - margin];
        let shape: [usize; 2] = std::array::from_fn(|a| {
            ((aabb.maxs[a] - aabb.mins[a] + 2.0 * margin) / cell).ceil() as usize + 1
        });
        let n = shape[0]
            .checked_mul(shape[1])
            .filter(|&n| n <= MAX_COLUMNS)
            .ok_or_else(|| {
                SceneError::InvalidInput(format!(
                    "surface columns: {shape:?} columns at {cell} m is more than {MAX_COLUMNS}: \
                     use a larger cell"
                ))
            })?;
        let top = aabb.maxs.z + 0.01;
        let depth = top - aabb.mins.z + 0.01;
        let columns: Vec<Vec<f32>> = (0..n)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i / shape[1], i % shape[1]);
                let from = Point3::new(
                    origin[0] + x as f32 * cell,
                    origin[1] + y as f32 * cell,
                    top,
                );
                scene
                    .surfaces_along(&from, &-Vector3::z(), depth, MAX_PER_COLUMN)
                    .map(|hits| hits.iter().map(|h| h.point.z).collect())
            })
            .collect::<Result<_>>()?;
        let mut starts = Vec::with_capacity(n + 1);
        let mut heights = Vec::new();
        for c in columns {
            starts.push(heights.len() as u32);
            heights.extend(c);
        }
        starts.push(heights.len() as u32);
        Ok(Self {
            origin,
            cell,
            shape,
            starts,
            heights,
        })
    }

    /// The raster's spacing, metres.
    pub fn cell(&self) -> f32 {
        self.cell
    }

    /// Columns per axis (x, y).
    pub fn shape(&self) -> [usize; 2] {
        self.shape
    }

    /// Bytes of the columns' offsets and heights.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(&self.starts[..]) + std::mem::size_of_val(&self.heights[..])
    }

    /// The surface heights of column `(x, y)`, from the top down.
    fn column(&self, x: usize, y: usize) -> &[f32] {
        let i = x * self.shape[1] + y;
        &self.heights[self.starts[i] as usize..self.starts[i + 1] as usize]
    }
}

impl SurfacesBeneath for SurfaceColumns {
    fn any_between(&self, x: f32, y: f32, low: f32, high: f32) -> Result<bool> {
        check_point(&Point3::new(x, y, low), "segment")?;
        check_point(&Point3::new(x, y, high), "segment")?;
        let q = [
            (x - self.origin[0]) / self.cell,
            (y - self.origin[1]) / self.cell,
        ];
        // Beyond the raster there is no part of the scene.
        let inside = (0..2).all(|a| q[a] >= 0.0 && q[a] <= (self.shape[a] - 1) as f32);
        if !inside {
            return Ok(false);
        }
        // q >= 0, so the casts are floors.
        let lo = [q[0] as usize, q[1] as usize];
        let hi = [
            (lo[0] + 1).min(self.shape[0] - 1),
            (lo[1] + 1).min(self.shape[1] - 1),
        ];
        Ok([
            (lo[0], lo[1]),
            (lo[0], hi[1]),
            (hi[0], lo[1]),
            (hi[0], hi[1]),
        ]
        .iter()
        .any(|&(cx, cy)| self.column(cx, cy).iter().any(|&h| h > low && h < high)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{generate_room, RoomConfig};

    /// On a furnished room the columns agree with the scene's own ray wherever no surface
    /// edge lies within a cell, and where they disagree it is the columns that see a surface.
    #[test]
    fn the_columns_agree_with_the_scenes_rays_or_err_towards_a_surface() {
        let room = generate_room(&RoomConfig::default(), 3).unwrap();
        let columns = SurfaceColumns::around(&room.scene, 0.1, 0.02).unwrap();
        let mut rng = envfield_grid::SplitMix64::new(9);
        let (mut agree, mut towards) = (0, 0);
        for _ in 0..5_000 {
            let (x, y) = (rng.next_f32() * room.size[0], rng.next_f32() * room.size[1]);
            let high = 0.3 + rng.next_f32() * 1.2;
            let low = 0.05;
            let exact = room.scene.any_between(x, y, low, high).unwrap();
            let read = columns.any_between(x, y, low, high).unwrap();
            if exact == read {
                agree += 1;
            } else {
                assert!(
                    read,
                    "the columns missed a surface at ({x}, {y}) in {low}..{high}"
                );
                towards += 1;
            }
        }
        assert!(
            agree > 4_800,
            "{agree} agree, {towards} err towards a surface"
        );
        assert!(columns.bytes() > 0);
        assert!(!columns.any_between(-50.0, 0.0, 0.0, 1.0).unwrap());
        assert!(columns.any_between(f32::NAN, 0.0, 0.0, 1.0).is_err());
        assert!(SurfaceColumns::around(&room.scene, 0.1, 0.0).is_err());
        assert!(SurfaceColumns::around(&Scene::new(), 0.1, 0.02).is_err());
    }
}
