//! A region written out: its samples and voxels as PLY point clouds, its plan view as PNG.

use super::AccessibleRegion;
use crate::Result;
use envfield_grid::{height_colour, Cell3, Field2, HeatMapStyle};
use envfield_scene::nalgebra::Point3;
use std::path::Path;

impl AccessibleRegion {
    /// Writes the region's files into `dir`: `samples.ply` (the kept samples), `region.ply`
    /// (the accessible voxels coloured by height) and `region.png` (from above, 6 pixels a
    /// voxel), each atomically.
    ///
    /// # Errors
    /// I/O errors, naming the file.
    pub fn write_files(&self, dir: &Path) -> Result<()> {
        self.write_samples_ply(dir.join("samples.ply"))?;
        self.write_ply(dir.join("region.ply"))?;
        self.write_png(dir.join("region.png"), 6)
    }

    /// Writes the kept samples as a PLY point cloud, atomically.
    ///
    /// # Errors
    /// I/O errors, naming the file.
    pub fn write_samples_ply(&self, path: impl AsRef<Path>) -> Result<()> {
        let kept: Vec<Point3<f32>> = self.samples.iter().map(|s| Point3::from(*s)).collect();
        Ok(envfield_scene::write_point_cloud(&kept, None, path)?)
    }

    /// Writes the accessible voxels' centres as a PLY point cloud coloured by height
    /// ([`height_colour`]: dark blue low, yellow high), atomically.
    ///
    /// # Errors
    /// I/O errors, naming the file.
    pub fn write_ply(&self, path: impl AsRef<Path>) -> Result<()> {
        let points: Vec<Point3<f32>> = self.voxel_centres().into_iter().map(Point3::from).collect();
        let (lo, hi) = points
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), p| {
                (a.min(p.z), b.max(p.z))
            });
        let colours: Vec<[u8; 3]> = points
            .iter()
            .map(|p| height_colour(if hi > lo { (p.z - lo) / (hi - lo) } else { 0.0 }))
            .collect();
        Ok(envfield_scene::write_point_cloud(
            &points,
            Some(&colours),
            path,
        )?)
    }

    /// Writes a top-down PNG: each floor column coloured by the height of its highest
    /// accessible voxel (grey: none), north up, `scale` pixels per voxel.
    ///
    /// # Errors
    /// I/O errors, naming the file.
    pub fn write_png(&self, path: impl AsRef<Path>, scale: u32) -> Result<()> {
        let heights = self.plan_view(|c| Ok(self.frame.center(c).z))?;
        heights.write_png(
            path,
            &HeatMapStyle {
                scale: scale.max(1),
                ..HeatMapStyle::default()
            },
        )?;
        Ok(())
    }

    /// The region from above, north up: each floor column's `value` at its highest accessible
    /// voxel, infinite where the column has none (a heat map draws it grey).
    ///
    /// # Errors
    /// The first error of `value`.
    pub fn plan_view(&self, mut value: impl FnMut(Cell3) -> Result<f32>) -> Result<Field2> {
        let [nx, ny, nz] = self.frame.shape;
        let mut values = vec![f32::INFINITY; nx * ny];
        for x in 0..nx {
            for y in 0..ny {
                let top = (0..nz)
                    .rev()
                    .find(|&z| self.grid.is_free(Cell3::new(x, y, z)));
                if let Some(z) = top {
                    values[(ny - 1 - y) * nx + x] = value(Cell3::new(x, y, z))?;
                }
            }
        }
        Ok(Field2::new(ny, nx, values)?)
    }
}
