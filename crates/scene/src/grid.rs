//! A scene's signed distance sampled once on a lattice and read back by trilinear
//! interpolation: a per-room table that turns the many signed-distance queries of pose checks
//! (22 per pose, each a pass over the scene's parts) into eight lookups each.

use crate::error::{check_point, Result, SceneError};
use crate::Scene;
use nalgebra::Point3;

/// Anything that answers signed-distance queries in metres (negative inside): a [`Scene`]
/// exactly, a [`DistanceGrid`] from its samples.
pub trait SignedDistance {
    /// The signed distance at `p`.
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for a non-finite point.
    fn distance_at(&self, p: &Point3<f32>) -> Result<f32>;
}

impl SignedDistance for Scene {
    fn distance_at(&self, p: &Point3<f32>) -> Result<f32> {
        self.signed_distance(p)
    }
}

/// The most samples a [`DistanceGrid`] may hold (256 MB of f32).
pub const MAX_DISTANCE_SAMPLES: usize = 1 << 26;

/// A scene's signed distance at the corners of a regular lattice over a box, trilinear in
/// between. Where the scene's surface is a plane across a cell the interpolation is exact; near
/// edges and corners it errs by at most about half a cell, towards larger values on the convex
/// side. Outside the box the value is the nearest corner's plus the distance to the box (the
/// signed distance grows at most that fast).
#[derive(Clone, Debug, PartialEq)]
pub struct DistanceGrid {
    origin: [f32; 3],
    cell: f32,
    shape: [usize; 3],
    values: Vec<f32>,
}

impl DistanceGrid {
    /// Samples `scene` (in parallel) over the box from `min` to `max` at `cell` metres.
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for a non-finite or empty box, a cell that is not positive,
    /// or more than 2^26 samples.
    pub fn new(scene: &Scene, min: Point3<f32>, max: Point3<f32>, cell: f32) -> Result<Self> {
        check_point(&min, "grid corner")?;
        check_point(&max, "grid corner")?;
        if !(cell.is_finite() && cell > 0.0) || (0..3).any(|a| max[a] <= min[a]) {
            return Err(SceneError::InvalidInput(format!(
                "distance grid: a positive cell (got {cell}) over a box with max > min (got \
                 {min:?} to {max:?})"
            )));
        }
        let shape: [usize; 3] =
            std::array::from_fn(|a| ((max[a] - min[a]) / cell).ceil() as usize + 1);
        let n = shape
            .iter()
            .try_fold(1usize, |n, &s| n.checked_mul(s))
            .filter(|&n| n <= MAX_DISTANCE_SAMPLES)
            .ok_or_else(|| {
                SceneError::InvalidInput(format!(
                    "distance grid of {shape:?} samples at {cell} m is larger than {MAX_DISTANCE_SAMPLES}: \
                     use a larger cell"
                ))
            })?;
        let points: Vec<Point3<f32>> = (0..n)
            .map(|i| {
                let (x, y, z) = (
                    i / (shape[1] * shape[2]),
                    (i / shape[2]) % shape[1],
                    i % shape[2],
                );
                Point3::new(
                    min.x + x as f32 * cell,
                    min.y + y as f32 * cell,
                    min.z + z as f32 * cell,
                )
            })
            .collect();
        let values = scene.signed_distances(&points)?;
        Ok(Self {
            origin: [min.x, min.y, min.z],
            cell,
            shape,
            values,
        })
    }

    /// Samples the scene over its bounding box grown by `margin` on every side.
    ///
    /// # Errors
    /// As [`DistanceGrid::new`]; an empty scene.
    pub fn around(scene: &Scene, margin: f32, cell: f32) -> Result<Self> {
        let aabb = scene
            .aabb()
            .ok_or_else(|| SceneError::InvalidInput("distance grid of an empty scene".into()))?;
        let m = nalgebra::Vector3::repeat(margin.max(0.0));
        Self::new(scene, aabb.mins - m, aabb.maxs + m, cell)
    }

    /// Samples per axis.
    pub fn shape(&self) -> [usize; 3] {
        self.shape
    }

    /// The lattice's spacing, metres.
    pub fn cell(&self) -> f32 {
        self.cell
    }

    /// Bytes of the samples.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(&self.values[..])
    }
}

impl SignedDistance for DistanceGrid {
    fn distance_at(&self, p: &Point3<f32>) -> Result<f32> {
        check_point(p, "query point")?;
        let mut base = [0usize; 3];
        let mut frac = [0f32; 3];
        let mut outside = 0f32;
        for a in 0..3 {
            let top = (self.shape[a] - 1) as f32;
            let q = (p[a] - self.origin[a]) / self.cell;
            let c = q.clamp(0.0, top);
            outside += ((q - c) * self.cell).powi(2);
            // c >= 0, so the cast is the floor (and needs no call into libm).
            let b = (c as usize).min(self.shape[a].saturating_sub(2));
            base[a] = b;
            frac[a] = if self.shape[a] > 1 { c - b as f32 } else { 0.0 };
        }
        // Every axis has at least two samples (`new`), so `base + 1` lies inside the grid.
        let [_, sy, sz] = self.shape;
        let (dx, dy) = (sy * sz, sz);
        let i = (base[0] * sy + base[1]) * sz + base[2];
        let at = |x: usize, y: usize, z: usize| self.values[i + x * dx + y * dy + z];
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let mut v = [0f32; 4];
        for (k, v) in v.iter_mut().enumerate() {
            let (x, y) = (k / 2, k % 2);
            *v = lerp(at(x, y, 0), at(x, y, 1), frac[2]);
        }
        let v0 = lerp(v[0], v[1], frac[1]);
        let v1 = lerp(v[2], v[3], frac[1]);
        // Inside the box (nearly every query) there is no distance to it to add.
        if outside == 0.0 {
            return Ok(lerp(v0, v1, frac[0]));
        }
        Ok(lerp(v0, v1, frac[0]) + outside.sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{generate_room, RoomConfig};

    /// On a furnished room the grid at 4 cm reads within 2 cm of the exact distance near
    /// surfaces, agrees on the side (in or out) wherever the surface is more than 2 cm away,
    /// and answers beyond its box.
    #[test]
    fn the_grid_reads_close_to_the_scene() {
        let room = generate_room(&RoomConfig::default(), 3).unwrap();
        let grid = DistanceGrid::around(&room.scene, 0.1, 0.04).unwrap();
        let mut rng = envfield_grid::SplitMix64::new(5);
        let (mut worst, mut near) = (0f32, 0);
        for _ in 0..20_000 {
            let p = Point3::new(
                rng.next_f32() * room.size[0],
                rng.next_f32() * room.size[1],
                rng.next_f32() * 2.0,
            );
            let exact = room.scene.signed_distance(&p).unwrap();
            let read = grid.distance_at(&p).unwrap();
            if exact.abs() < 0.3 {
                near += 1;
                worst = worst.max((read - exact).abs());
            }
            if exact.abs() > 0.02 {
                assert_eq!(read > 0.0, exact > 0.0, "at {p:?}: {read} vs {exact}");
            }
        }
        assert!(
            near > 1000 && worst < 0.02,
            "{near} near points, worst error {worst}"
        );
        let far = Point3::new(-50.0, 0.0, 1.0);
        assert!(grid.distance_at(&far).unwrap() > 40.0);
        assert!(grid.distance_at(&Point3::new(f32::NAN, 0.0, 0.0)).is_err());
        assert!(DistanceGrid::around(&room.scene, 0.1, 0.0).is_err());
        assert!(DistanceGrid::around(&room.scene, 0.1, 1e-4).is_err());
    }
}
