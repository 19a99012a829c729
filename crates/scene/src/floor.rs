//! The bird's-eye floor map of paper section 4.1: a top-down depth image whose deepest pixels
//! (the floor) are free and the rest obstacles.

use envfield_grid::{Cell2, Grid2};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Result, SceneError};
use crate::scene::Scene;

/// How [`floor_map`] renders the scene.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FloorMapConfig {
    /// Side of a pixel in metres.
    pub resolution: f32,
    /// Pixels whose depth is within this of the deepest pixel count as floor (metres).
    pub floor_tolerance: f32,
    /// The camera height: rays start here, below a scanned ceiling. `None`: just above the
    /// scene's top.
    pub camera_height: Option<f32>,
}

impl Default for FloorMapConfig {
    fn default() -> Self {
        Self {
            resolution: 0.05,
            floor_tolerance: 0.02,
            camera_height: None,
        }
    }
}

/// How map cells relate to the world: cell `(row, col)` covers
/// `x in origin[0] + [col, col+1) * resolution`, `y in origin[1] + [row, row+1) * resolution`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapFrame {
    /// World `(x, y)` of the map's minimum corner.
    pub origin: [f32; 2],
    /// Side of a cell in metres.
    pub resolution: f32,
}

impl MapFrame {
    /// World `(x, y)` of a cell's centre.
    pub fn center(&self, cell: Cell2) -> [f32; 2] {
        [
            self.origin[0] + (cell.col as f32 + 0.5) * self.resolution,
            self.origin[1] + (cell.row as f32 + 0.5) * self.resolution,
        ]
    }

    /// The cell under world `(x, y)`, or `None` outside `rows x cols`.
    pub fn cell_of(&self, x: f32, y: f32, rows: usize, cols: usize) -> Option<Cell2> {
        let c = (x - self.origin[0]) / self.resolution;
        let r = (y - self.origin[1]) / self.resolution;
        (c >= 0.0 && r >= 0.0 && (c as usize) < cols && (r as usize) < rows)
            .then(|| Cell2::new(r as usize, c as usize))
    }
}

/// A top-down floor map: free cells are floor seen from above.
#[derive(Clone, Debug, PartialEq)]
pub struct FloorMap {
    /// Obstacles: pixels where something stands above the floor, or where no floor is seen.
    pub grid: Grid2,
    /// Cells to metres.
    pub frame: MapFrame,
    /// The height of the first surface seen from above per cell (row-major), `-inf` where the
    /// ray met nothing.
    pub heights: Vec<f32>,
    /// The floor height found (the lowest surface seen).
    pub floor_height: f32,
}

impl FloorMap {
    /// The map with obstacles grown by a disc of `radius` metres: the cells where the centre
    /// of a body of that radius can stand, that is the cells farther than `radius` (rounded to
    /// whole cells) from every obstacle cell. O(cells) for any radius, by an exact Euclidean
    /// distance transform (Felzenszwalb and Huttenlocher 2012); a radius wider than the map
    /// blocks every cell of a map with an obstacle.
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for a negative or non-finite radius.
    pub fn inflated(&self, radius: f32) -> Result<Grid2> {
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(SceneError::InvalidInput(format!(
                "inflation radius must be >= 0, got {radius}"
            )));
        }
        let (rows, cols) = (self.grid.rows(), self.grid.cols());
        // Past the map's extent every radius blocks the same cells.
        let r = ((radius / self.frame.resolution).round() as f64).min((rows + cols) as f64);
        let d2 = squared_distance_to_obstacles(self.grid.obstacles(), rows, cols);
        let out = d2.iter().map(|&d| d <= r * r).collect();
        Ok(Grid2::from_obstacles(rows, cols, out)?)
    }
}

impl FloorMap {
    /// Where a body of `radius` metres may stand ([`FloorMap::inflated`]), padded with
    /// obstacles at the far rows and columns to `extent` cells when one is given: the
    /// walkable map people navigate, at one size for every room of a batch.
    ///
    /// # Errors
    /// As [`FloorMap::inflated`]; [`SceneError::InvalidInput`] when the map is larger than
    /// `extent`.
    pub fn walkable(&self, radius: f32, extent: Option<[usize; 2]>) -> Result<Grid2> {
        let grid = self.inflated(radius)?;
        match extent {
            None => Ok(grid),
            Some([rows, cols]) if rows >= grid.rows() && cols >= grid.cols() => {
                Ok(grid.padded(rows, cols)?)
            }
            Some([rows, cols]) => Err(SceneError::InvalidInput(format!(
                "a {}x{} floor map does not fit in {rows}x{cols} cells; use a coarser resolution \
                 or a larger extent",
                grid.rows(),
                grid.cols()
            ))),
        }
    }
}

/// The squared Euclidean distance, in cells, from every cell of a `rows x cols` map to the
/// nearest obstacle cell (0 on obstacles, infinite without any): a column pass, then the lower
/// envelope of parabolas along each row. Every value is an exact integer.
fn squared_distance_to_obstacles(obstacles: &[bool], rows: usize, cols: usize) -> Vec<f64> {
    // Rows to the nearest obstacle in the same column.
    let mut vertical = vec![f64::INFINITY; rows * cols];
    for c in 0..cols {
        let mut last = None;
        for r in 0..rows {
            if obstacles[r * cols + c] {
                last = Some(r);
            }
            if let Some(l) = last {
                vertical[r * cols + c] = (r - l) as f64;
            }
        }
        last = None;
        for r in (0..rows).rev() {
            if obstacles[r * cols + c] {
                last = Some(r);
            }
            if let Some(l) = last {
                let v = &mut vertical[r * cols + c];
                *v = v.min((l - r) as f64);
            }
        }
    }
    let mut out = vec![f64::INFINITY; rows * cols];
    // The parabolas of the envelope (their columns) and where each takes over.
    let mut apex = vec![0usize; cols];
    let mut from = vec![0f64; cols + 1];
    for r in 0..rows {
        let f = |q: usize| vertical[r * cols + q].powi(2);
        let meet = |p: usize, q: usize| {
            ((f(q) + (q * q) as f64) - (f(p) + (p * p) as f64)) / (2.0 * (q as f64 - p as f64))
        };
        let mut k = 0usize;
        for q in (0..cols).filter(|&q| f(q).is_finite()) {
            // Drop the parabolas that q's hides, then add q's.
            loop {
                if k == 0 {
                    (apex[0], from[0], from[1], k) = (q, f64::NEG_INFINITY, f64::INFINITY, 1);
                    break;
                }
                let s = meet(apex[k - 1], q);
                if s <= from[k - 1] {
                    k -= 1;
                    continue;
                }
                (apex[k], from[k], from[k + 1]) = (q, s, f64::INFINITY);
                k += 1;
                break;
            }
        }
        if k == 0 {
            continue;
        }
        let mut j = 0;
        for c in 0..cols {
            while from[j + 1] < c as f64 {
                j += 1;
            }
            let p = apex[j];
            out[r * cols + c] = (c as f64 - p as f64).powi(2) + f(p);
        }
    }
    out
}

/// Renders the top-down depth image of `scene` over its bounding box and marks the deepest
/// pixels free. Cost: one ray cast per pixel, in parallel.
///
/// # Errors
/// [`SceneError::InvalidInput`] for an empty scene, a non-positive resolution or tolerance, a
/// map of more than 2^28 pixels, or a scene where no ray meets anything.
pub fn floor_map(scene: &Scene, config: &FloorMapConfig) -> Result<FloorMap> {
    let aabb = scene
        .aabb()
        .ok_or_else(|| SceneError::InvalidInput("the scene is empty".into()))?;
    let res = config.resolution;
    let tolerance_ok = config.floor_tolerance.is_finite() && config.floor_tolerance >= 0.0;
    if !(res.is_finite() && res > 0.0 && tolerance_ok) {
        return Err(SceneError::InvalidInput(format!(
            "floor map resolution must be > 0 and tolerance >= 0, got {} and {}",
            res, config.floor_tolerance
        )));
    }
    let cols = ((aabb.maxs.x - aabb.mins.x) / res).ceil().max(1.0) as usize;
    let rows = ((aabb.maxs.y - aabb.mins.y) / res).ceil().max(1.0) as usize;
    if rows.saturating_mul(cols) > 1 << 28 {
        return Err(SceneError::InvalidInput(format!(
            "a {rows} x {cols} floor map is too large; use a coarser resolution"
        )));
    }
    let frame = MapFrame {
        origin: [aabb.mins.x, aabb.mins.y],
        resolution: res,
    };
    let top = config.camera_height.unwrap_or(aabb.maxs.z + 0.1);
    let range = top - aabb.mins.z + 0.1;
    let down = -Vector3::z();
    let heights: Vec<f32> = (0..rows * cols)
        .into_par_iter()
        .with_min_len(256)
        .map(|i| {
            let [x, y] = frame.center(Cell2::new(i / cols, i % cols));
            match scene.cast_ray(&Point3::new(x, y, top), &down, range) {
                Ok(Some(hit)) => top - hit.distance,
                _ => f32::NEG_INFINITY,
            }
        })
        .collect();
    let floor_height = heights
        .iter()
        .copied()
        .filter(|h| h.is_finite())
        .fold(f32::INFINITY, f32::min);
    if !floor_height.is_finite() {
        let size = aabb.maxs - aabb.mins;
        return Err(SceneError::InvalidInput(format!(
            "no ray from above met the scene: it is {:.2e} x {:.2e} m and the map's cells are \
             {res} m apart{}",
            size.x,
            size.y,
            if size.x.max(size.y) < res {
                ": far smaller than a room (is it in other units than read? --units)"
            } else {
                ""
            }
        )));
    }
    let obstacles = heights
        .iter()
        .map(|&h| !(h.is_finite() && h <= floor_height + config.floor_tolerance))
        .collect();
    Ok(FloorMap {
        grid: Grid2::from_obstacles(rows, cols, obstacles)?,
        frame,
        heights,
        floor_height,
    })
}

#[cfg(test)]
mod distance_tests {
    use super::*;
    use envfield_grid::SplitMix64;

    /// The old way: stamp a disc around every obstacle cell.
    fn stamped(obstacles: &[bool], rows: usize, cols: usize, r: i64) -> Vec<bool> {
        let mut out = obstacles.to_vec();
        for (i, _) in obstacles.iter().enumerate().filter(|(_, &o)| o) {
            let (row, col) = ((i / cols) as i64, (i % cols) as i64);
            for dr in -r..=r {
                for dc in -r..=r {
                    let (y, x) = (row + dr, col + dc);
                    let inside = y >= 0 && x >= 0 && (y as usize) < rows && (x as usize) < cols;
                    if dr * dr + dc * dc <= r * r && inside {
                        out[y as usize * cols + x as usize] = true;
                    }
                }
            }
        }
        out
    }

    #[test]
    fn the_transform_blocks_exactly_the_cells_a_stamped_disc_does() {
        let mut rng = SplitMix64::new(5);
        for case in 0..60 {
            let (rows, cols) = (1 + rng.below(23), 1 + rng.below(23));
            let density = [0.0, 0.01, 0.05, 0.3, 1.0][case % 5];
            let obstacles: Vec<bool> = (0..rows * cols).map(|_| rng.next_f64() < density).collect();
            let d2 = squared_distance_to_obstacles(&obstacles, rows, cols);
            for r in [0i64, 1, 2, 3, 5, 8, 40] {
                let by_transform: Vec<bool> = d2.iter().map(|&d| d <= (r * r) as f64).collect();
                assert_eq!(
                    by_transform,
                    stamped(&obstacles, rows, cols, r),
                    "case {case}, {rows}x{cols}, radius {r}"
                );
            }
        }
    }
}
