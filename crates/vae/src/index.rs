//! [`XyIndex`]: a cloud's points binned in x-y, for a local VAE's neighbourhoods.

use crate::{LocalConfig, Result, VaeError};
use envfield_grid::SplitMix64;

/// A cloud's points binned in x-y squares of the neighbourhood radius, for neighbourhood
/// queries in 3x3 bins.
pub(crate) struct XyIndex {
    /// `[x0, y0, x1, y1]` of the cloud.
    pub(crate) extent: [f32; 4],
    cell: f32,
    cols: usize,
    rows: usize,
    bins: Vec<Vec<u32>>,
}

impl XyIndex {
    /// Bins `cloud` (checked non-empty and finite; `what` names it in errors).
    pub(crate) fn new(cloud: &[[f32; 3]], radius: f32, what: &str) -> Result<Self> {
        if cloud.is_empty() {
            return Err(VaeError::InvalidInput(format!("{what}: no points")));
        }
        if let Some(i) = cloud.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
            return Err(VaeError::InvalidInput(format!(
                "{what}: point {i} is not finite: {:?}",
                cloud[i]
            )));
        }
        let fold =
            |f: fn(f32, f32) -> f32, a: usize, init: f32| cloud.iter().map(|p| p[a]).fold(init, f);
        let extent = [
            fold(f32::min, 0, f32::INFINITY),
            fold(f32::min, 1, f32::INFINITY),
            fold(f32::max, 0, f32::NEG_INFINITY),
            fold(f32::max, 1, f32::NEG_INFINITY),
        ];
        // Bins no smaller than the radius, and at most 2^20 of them.
        let span = (extent[2] - extent[0]).max(extent[3] - extent[1]);
        let cell = radius.max(span / 1024.0).max(1e-3);
        let cols = ((extent[2] - extent[0]) / cell) as usize + 1;
        let rows = ((extent[3] - extent[1]) / cell) as usize + 1;
        let mut bins = vec![Vec::new(); rows * cols];
        for (i, p) in cloud.iter().enumerate() {
            let (c, r) = (
                ((p[0] - extent[0]) / cell) as usize,
                ((p[1] - extent[1]) / cell) as usize,
            );
            bins[r.min(rows - 1) * cols + c.min(cols - 1)].push(i as u32);
        }
        Ok(Self {
            extent,
            cell,
            cols,
            rows,
            bins,
        })
    }

    /// Whether some point of `cloud` (the points this index was made of) lies within
    /// `radius` (at most the index's radius) of `anchor` in x-y.
    pub(crate) fn any_within(&self, cloud: &[[f32; 3]], anchor: [f32; 2], radius: f32) -> bool {
        let (c, r) = (
            ((anchor[0] - self.extent[0]) / self.cell).floor() as isize,
            ((anchor[1] - self.extent[1]) / self.cell).floor() as isize,
        );
        let r2 = radius * radius;
        (-1..=1).any(|dr| {
            (-1..=1).any(|dc| {
                let (br, bc) = (r + dr, c + dc);
                br >= 0
                    && bc >= 0
                    && br < self.rows as isize
                    && bc < self.cols as isize
                    && self.bins[br as usize * self.cols + bc as usize]
                        .iter()
                        .any(|&i| {
                            let p = cloud[i as usize];
                            let (dx, dy) = (p[0] - anchor[0], p[1] - anchor[1]);
                            dx * dx + dy * dy <= r2
                        })
            })
        })
    }

    /// `local.points` points drawn with replacement from those of `cloud` within the radius
    /// of `anchor` in x-y, as `[dx, dy, z]` relative to it; `[0, 0, -0.5]` each when there is
    /// none (nothing here: below the floor).
    pub(crate) fn neighbourhood(
        &self,
        cloud: &[[f32; 3]],
        anchor: [f32; 2],
        local: &LocalConfig,
        rng: &mut SplitMix64,
    ) -> Vec<[f32; 3]> {
        let (c, r) = (
            ((anchor[0] - self.extent[0]) / self.cell).floor() as isize,
            ((anchor[1] - self.extent[1]) / self.cell).floor() as isize,
        );
        let r2 = local.radius * local.radius;
        let mut near = Vec::new();
        for dr in -1..=1 {
            for dc in -1..=1 {
                let (br, bc) = (r + dr, c + dc);
                if br < 0 || bc < 0 || br >= self.rows as isize || bc >= self.cols as isize {
                    continue;
                }
                for &i in &self.bins[br as usize * self.cols + bc as usize] {
                    let p = cloud[i as usize];
                    let (dx, dy) = (p[0] - anchor[0], p[1] - anchor[1]);
                    if dx * dx + dy * dy <= r2 {
                        near.push([dx, dy, p[2]]);
                    }
                }
            }
        }
        if near.is_empty() {
            return vec![[0.0, 0.0, -0.5]; local.points];
        }
        (0..local.points)
            .map(|_| near[rng.below(near.len())])
            .collect()
    }
}
