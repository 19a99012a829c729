//! Surface point sampling (the point cloud a scene encoder reads) and voxelisation.

use envfield_grid::SplitMix64;
use envfield_grid::{Cell3, Grid3};
use nalgebra::{Point3, Vector3};
use parry3d::bounding_volume::Aabb;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Result, SceneError};
use crate::scene::Scene;

/// The most points [`sample_surface`] draws in one call (about 800 MB of points).
pub const MAX_SURFACE_POINTS: usize = 1 << 26;

/// `count` points spread uniformly (by area) over the scene's visible surfaces, seeded.
///
/// Points of a part's surface that lie inside another part (a table leg's end in the floor)
/// are discarded and redrawn, so the cloud samples the boundary of the union, as a scan would.
/// Cost: O(count) signed-distance queries, in parallel.
///
/// # Errors
/// [`SceneError::InvalidInput`] for an empty scene, a `count` of 0 or above
/// [`MAX_SURFACE_POINTS`], or when the surfaces are almost entirely hidden inside each other.
pub fn sample_surface(scene: &Scene, count: usize, seed: u64) -> Result<Vec<Point3<f32>>> {
    if !(1..=MAX_SURFACE_POINTS).contains(&count) {
        return Err(SceneError::InvalidInput(format!(
            "sample between 1 and {MAX_SURFACE_POINTS} surface points (got {count})"
        )));
    }
    let mesh = scene.to_mesh();
    let mut cumulative = Vec::with_capacity(mesh.triangles.len());
    let mut total = 0.0f64;
    for t in &mesh.triangles {
        total += mesh.triangle_area(t) as f64;
        cumulative.push(total);
    }
    if total <= 0.0 {
        return Err(SceneError::InvalidInput(
            "the scene has no surface to sample".into(),
        ));
    }
    let mut rng = SplitMix64::new(seed);
    let mut points = Vec::with_capacity(count);
    for _round in 0..32 {
        let candidates: Vec<Point3<f32>> = (0..count)
            .map(|_| {
                let r = rng.next_f32() as f64 * total;
                let i = cumulative
                    .partition_point(|&c| c <= r)
                    .min(cumulative.len() - 1);
                let [a, b, c] = mesh.triangles[i].map(|v| mesh.vertices[v as usize]);
                let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                a + (b - a) * u + (c - a) * v
            })
            .collect();
        let distances = scene.signed_distances(&candidates)?;
        points.extend(
            candidates
                .into_iter()
                .zip(distances)
                .filter(|(_, d)| *d > -1e-3)
                .map(|(p, _)| p),
        );
        if points.len() >= count {
            points.truncate(count);
            return Ok(points);
        }
    }
    Err(SceneError::InvalidInput(format!(
        "only {} of {count} surface samples lie on the scene's outer surface",
        points.len()
    )))
}

/// A regular voxel lattice in the world: `shape` voxels of side `voxel` from `origin` (the
/// minimum corner). Voxel `(x, y, z)` covers `origin + [x, x+1) * voxel` on each axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct VoxelFrame {
    /// The minimum corner in metres.
    pub origin: Point3<f32>,
    /// The side of a voxel in metres.
    pub voxel: f32,
    /// Voxels along x, y, z.
    pub shape: [usize; 3],
}

impl VoxelFrame {
    /// The smallest lattice of `voxel`-sized cells from `aabb`'s minimum corner that covers it.
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for a non-positive voxel, a non-finite box, or more than
    /// 2^31 voxels.
    pub fn covering(aabb: &Aabb, voxel: f32) -> Result<Self> {
        if !(voxel.is_finite() && voxel > 0.0) {
            return Err(SceneError::InvalidInput(format!(
                "voxel size must be positive, got {voxel}"
            )));
        }
        let extent = aabb.maxs - aabb.mins;
        if !extent.iter().all(|v| v.is_finite() && *v >= 0.0) {
            return Err(SceneError::InvalidInput(format!(
                "bad bounding box {aabb:?}"
            )));
        }
        let shape = [0, 1, 2].map(|a| ((extent[a] / voxel).ceil() as usize).max(1));
        if shape.iter().map(|&n| n as u128).product::<u128>() > 1 << 31 {
            return Err(SceneError::InvalidInput(format!(
                "{shape:?} voxels of {voxel} m are too many"
            )));
        }
        Ok(Self {
            origin: aabb.mins,
            voxel,
            shape,
        })
    }

    /// The centre of a voxel.
    pub fn center(&self, c: Cell3) -> Point3<f32> {
        self.origin
            + Vector3::new(c.x as f32 + 0.5, c.y as f32 + 0.5, c.z as f32 + 0.5) * self.voxel
    }

    /// The voxel holding `p`, or `None` outside the lattice.
    pub fn cell_of(&self, p: &Point3<f32>) -> Option<Cell3> {
        let q = (p - self.origin) / self.voxel;
        let mut idx = [0usize; 3];
        for a in 0..3 {
            if q[a].is_nan() || q[a] < 0.0 || q[a] >= self.shape[a] as f32 {
                return None;
            }
            idx[a] = q[a] as usize;
        }
        Some(Cell3::new(idx[0], idx[1], idx[2]))
    }
}

/// Voxelises the scene on `frame`: a voxel is an obstacle when its centre is inside solid
/// geometry or within half a voxel of a surface (signed distance <= voxel / 2), so thin
/// furniture never vanishes between voxel centres. Cost: one signed-distance query per voxel,
/// in parallel.
///
/// # Errors
/// As [`Grid3::new`] for a degenerate frame.
pub fn voxelize(scene: &Scene, frame: &VoxelFrame) -> Result<Grid3> {
    let [nx, ny, nz] = frame.shape;
    let mut grid = Grid3::new(nx, ny, nz)?;
    let half = frame.voxel / 2.0;
    let occupied: Vec<bool> = (0..grid.len())
        .into_par_iter()
        .with_min_len(1024)
        .map(|i| {
            let p = frame.center(grid.cell(i));
            scene.signed_distance(&p).map(|d| d <= half).unwrap_or(true)
        })
        .collect();
    grid = Grid3::from_obstacles(frame.shape, occupied)?;
    Ok(grid)
}
