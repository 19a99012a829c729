//! 3D environment fields over an accessible region: the exact one (fast marching over the
//! accessible voxels, in metres) and the learned one (the goal-conditioned network, trained
//! per scene as in the paper), both behind [`ContinuousField3`]. Either can be a
//! [`VoxelField3`]: one goal's values at the region's voxel centres, made once per goal (the
//! fast marching, or one batched network pass), then read by interpolation at every step.

use crate::{AccessibleRegion, Result, RoomsError};
use envfield_eikonal::{FastMarching, FreeCells3, Order, SolveOptions3};
use envfield_grid::{sample_finite_within, Cell3, ContinuousField3, Field3, Point3, Point3m};
use envfield_nets::{Batch, FieldNet, ModelConfig};
use envfield_scene::VoxelFrame;
use std::sync::Arc;

/// A point in metres as continuous voxel coordinates (voxel centres at integers), checked to
/// lie within the lattice's box.
fn to_voxel(frame: &VoxelFrame, p: Point3m) -> envfield_grid::Result<Point3> {
    if !p.iter().all(|v| v.is_finite()) {
        return Err(envfield_grid::GridError::Invalid(format!(
            "point {p:?} is not finite"
        )));
    }
    let q: [f32; 3] = std::array::from_fn(|a| (p[a] - frame.origin[a]) / frame.voxel - 0.5);
    for a in 0..3 {
        let n = frame.shape[a] as f32;
        if q[a] < -0.5 || q[a] > n - 0.5 {
            return Err(envfield_grid::GridError::Invalid(format!(
                "point {p:?} is outside the field's box"
            )));
        }
    }
    let clamp = |v: f32, a: usize| v.clamp(0.0, (frame.shape[a] - 1) as f32);
    Ok(Point3::new(clamp(q[0], 0), clamp(q[1], 1), clamp(q[2], 2)))
}

/// A 3D field of one goal tabulated at an accessible region's voxel centres, in metres: the
/// exact field ([`VoxelField3::new`], fast marching over the accessible voxels, second order,
/// 6 neighbours) or a learned one ([`LearnedField3::tabulate`]). Between voxel centres it is
/// trilinear over the accessible corners (their weights renormalised), so it is finite
/// everywhere in an accessible voxel, right up to the region's faces, and infinite in an
/// inaccessible one.
#[derive(Clone, Debug)]
pub struct VoxelField3 {
    /// Metres at each accessible voxel, in `cells`' numbering.
    metres: Vec<f32>,
    /// The region's accessible voxels.
    cells: Arc<FreeCells3>,
    frame: VoxelFrame,
    goal: Cell3,
}

/// The exact field: a [`VoxelField3`] made by fast marching.
pub type ExactField3 = VoxelField3;

impl VoxelField3 {
    /// The field of `region` for the goal at `goal` (metres): fast marching over the region's
    /// accessible voxels, O(n log n) in their number.
    ///
    /// ```
    /// use envfield_grid::{ContinuousField3, Grid3};
    /// use envfield_rooms::{AccessibleRegion, ExactField3};
    /// use envfield_scene::parry3d::bounding_volume::Aabb;
    /// use envfield_scene::nalgebra::Point3;
    /// use envfield_scene::VoxelFrame;
    ///
    /// // A corridor 4 m long, one 10 cm voxel wide and high: every voxel accessible.
    /// let frame = VoxelFrame::covering(
    ///     &Aabb::new(Point3::new(0.0, 0.0, 0.9), Point3::new(4.0, 0.1, 1.0)),
    ///     0.1,
    /// )?;
    /// let grid = Grid3::new(frame.shape[0], frame.shape[1], frame.shape[2])?;
    /// let region = AccessibleRegion::new(frame, grid, Vec::new(), 1)?;
    /// let field = ExactField3::new(&region, [0.05, 0.05, 0.95])?;
    /// let d = field.value([3.05, 0.05, 0.95])?;
    /// assert!((d - 3.0).abs() < 0.05, "{d}");
    /// # Ok::<(), envfield_rooms::RoomsError>(())
    /// ```
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] for a goal outside the accessible region.
    pub fn new(region: &AccessibleRegion, goal: Point3m) -> Result<Self> {
        let cell = region.cell(goal, "goal")?;
        Self::at_cell(region, cell)
    }

    /// The field for the goal voxel `goal`.
    ///
    /// # Errors
    /// As [`ExactField3::new`].
    pub fn at_cell(region: &AccessibleRegion, goal: Cell3) -> Result<Self> {
        Self::march(region, goal, SolveOptions3::default())
    }

    /// The field for the goal voxel `goal` marched only where one path from `start` may go:
    /// over the voxels on ways from the start to the goal at most `band` metres longer than
    /// the shortest, and no more than `band` above the start's value
    /// ([`SolveOptions3::detour`], [`SolveOptions3::past_stop`]), infinite elsewhere. A
    /// descent from the start never climbs above its own value; the band leaves room for a
    /// search to go round what the poses refuse.
    ///
    /// # Errors
    /// As [`ExactField3::new`]; [`RoomsError::InvalidInput`] for a start outside the region
    /// or a band that is negative or NaN.
    pub fn toward(
        region: &AccessibleRegion,
        goal: Cell3,
        start: Point3m,
        band: f32,
    ) -> Result<Self> {
        let stop = region.cell(start, "start")?;
        if band.is_nan() || band < 0.0 {
            return Err(RoomsError::InvalidInput(format!(
                "the band past the start must be >= 0 metres, got {band}"
            )));
        }
        let options = SolveOptions3 {
            stop_at: Some(stop),
            past_stop: band,
            detour: Some(band),
            ..Default::default()
        };
        Self::march(region, goal, options)
    }

    fn march(region: &AccessibleRegion, goal: Cell3, options: SolveOptions3) -> Result<Self> {
        if !region.grid.is_free(goal) {
            return Err(RoomsError::InvalidInput(format!(
                "goal voxel {goal:?} is outside the accessible region"
            )));
        }
        // Marched in metres (no second pass to scale it), over the accessible voxels alone:
        // a room's region fills a few percent of its box.
        let fmm = FastMarching {
            order: Order::Second,
            spacing: region.frame.voxel,
            ..FastMarching::default()
        };
        let cells = region.free_cells()?;
        let metres = fmm.solve3_free(&cells, &[goal], options)?;
        Ok(Self {
            metres,
            cells,
            frame: region.frame,
            goal,
        })
    }

    /// The value at voxel `cell`'s centre, metres: infinite outside the region (or, for a
    /// field marched [`VoxelField3::toward`] a start, off the ways it keeps to).
    pub fn at(&self, cell: Cell3) -> f32 {
        self.cells
            .number(cell)
            .map_or(f32::INFINITY, |k| self.metres[k])
    }

    /// The values at every voxel centre of the lattice (infinite outside the region), metres.
    ///
    /// # Errors
    /// [`RoomsError::Grid`] for a lattice too large to hold in one array.
    pub fn voxels(&self) -> Result<Field3> {
        let mut all = vec![f32::INFINITY; self.frame.shape.iter().product()];
        for (&i, &v) in self.cells.indices().iter().zip(&self.metres) {
            all[i as usize] = v;
        }
        Ok(Field3::new(self.frame.shape, all)?)
    }

    /// The goal voxel.
    pub fn goal(&self) -> Cell3 {
        self.goal
    }

    /// The field pinned to its goal: within `radius` metres of the goal voxel's centre each
    /// value `v` at distance `r` becomes `w v + (1 - w) r`, `w` rising smoothly from 0 at the
    /// goal to 1 at `radius` (`3t^2 - 2t^3`, `t = r / radius`), so the field is 0 at its goal
    /// and falls towards it from every side nearby. A learned field is least right at its own
    /// goal (a network reads a few centimetres to a metre there, where the exact field reads
    /// 0), and a search stops in the hollow that leaves; the straight line is the reaching
    /// distance wherever the way to the goal is clear, as it is within a sit-down's reach.
    /// Farther out the field is unchanged.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] for a radius that is negative or not finite.
    pub fn pinned(mut self, radius: f32) -> Result<Self> {
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(RoomsError::InvalidInput(format!(
                "a field's pinning radius must be finite and >= 0 metres, got {radius}"
            )));
        }
        if radius == 0.0 {
            return Ok(self);
        }
        let goal = self.frame.center(self.goal);
        for k in 0..self.cells.len() {
            let r = (self.frame.center(self.cells.cell(k)) - goal).norm();
            if r < radius {
                let t = r / radius;
                let w = t * t * (3.0 - 2.0 * t);
                self.metres[k] = w * self.metres[k] + (1.0 - w) * r;
            }
        }
        Ok(self)
    }

    /// Bytes of the table (a value per accessible voxel; the numbering of the voxels is the
    /// region's, [`FreeCells3::bytes`]).
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(&self.metres[..])
    }
}

impl ContinuousField3 for VoxelField3 {
    fn value(&self, p: Point3m) -> envfield_grid::Result<f32> {
        // Over the accessible corners: plain trilinear weighting would make every point within
        // half a voxel of the region's faces infinite, and a torso standing in an accessible
        // voxel near a wall could neither be reached nor left.
        // `to_voxel` checked it: finite, inside the lattice.
        let q = to_voxel(&self.frame, p)?;
        Ok(sample_finite_within(self.frame.shape, q, |i| {
            self.cells
                .number_at(i)
                .map_or(f32::INFINITY, |k| self.metres[k])
        }))
    }

    /// Central differences of the trilinear interpolant over half a voxel.
    fn gradient(&self, p: Point3m) -> envfield_grid::Result<Option<Point3m>> {
        self.value(p)?;
        let h = 0.5 * self.frame.voxel;
        let mut g = [0.0; 3];
        for a in 0..3 {
            let (mut lo, mut hi) = (p, p);
            lo[a] -= h;
            hi[a] += h;
            let (Ok(vl), Ok(vh)) = (self.value(lo), self.value(hi)) else {
                return Ok(None);
            };
            if !(vl.is_finite() && vh.is_finite()) {
                return Ok(None);
            }
            g[a] = (vh - vl) / (2.0 * h);
        }
        Ok(Some(g))
    }
}

/// A learned 3D field bound to one region's lattice and goal, in metres.
#[derive(Debug)]
pub struct LearnedField3<'a> {
    net: &'a FieldNet,
    frame: VoxelFrame,
    goal: Cell3,
}

impl<'a> LearnedField3<'a> {
    /// `net` (a goal-conditioned network over `region`'s lattice) for the goal voxel `goal`.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] for a network of another lattice or a goal outside the
    /// region.
    pub fn new(net: &'a FieldNet, region: &AccessibleRegion, goal: Cell3) -> Result<Self> {
        match net.config() {
            ModelConfig::Goal(c) if c.extent == region.frame.shape.to_vec() => {}
            other => {
                return Err(RoomsError::InvalidInput(format!(
                    "a 3D field needs a goal-conditioned network over the region's {:?} voxels, \
                     not a {} network{}",
                    region.frame.shape,
                    other.arch(),
                    match other {
                        ModelConfig::Goal(c) => format!(" over {:?}", c.extent),
                        _ => String::new(),
                    }
                )))
            }
        }
        if !region.grid.is_free(goal) {
            return Err(RoomsError::InvalidInput(format!(
                "goal voxel {goal:?} is outside the accessible region"
            )));
        }
        Ok(Self {
            net,
            frame: region.frame,
            goal,
        })
    }

    /// The field at every accessible voxel centre of `region` in one batched network pass
    /// (infinite elsewhere), as a [`VoxelField3`] read by interpolation: the per-goal pass
    /// that makes every later step a lookup.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] for a region of another lattice; errors of the network.
    pub fn tabulate(&self, region: &AccessibleRegion) -> Result<VoxelField3> {
        if region.frame.shape != self.frame.shape {
            return Err(RoomsError::InvalidInput(format!(
                "tabulating a field of {:?} voxels over a region of {:?}",
                self.frame.shape, region.frame.shape
            )));
        }
        let cells = region.free_cells()?;
        let mut queries = Vec::with_capacity(3 * cells.len());
        for k in 0..cells.len() {
            let c = cells.cell(k);
            queries.extend([c.x as f32, c.y as f32, c.z as f32]);
        }
        let raw = self.net.predict_encoded(&self.batch_of(queries))?;
        let encoding = self.net.config().encoding();
        let metres = raw
            .iter()
            .map(|&t| encoding.decode(t) * self.frame.voxel)
            .collect();
        Ok(VoxelField3 {
            metres,
            cells,
            frame: self.frame,
            goal: self.goal,
        })
    }

    fn batch(&self, points: &[Point3m]) -> envfield_grid::Result<Batch> {
        let mut queries = Vec::with_capacity(3 * points.len());
        for &p in points {
            let q = to_voxel(&self.frame, p)?;
            queries.extend([q.x, q.y, q.z]);
        }
        Ok(self.batch_of(queries))
    }

    /// One network batch of the goal and `queries` (continuous voxel coordinates, x y z).
    fn batch_of(&self, queries: Vec<f32>) -> Batch {
        Batch {
            extent: self.frame.shape.to_vec(),
            items: 1,
            obstacles: Vec::new(),
            goals: vec![self.goal.x as f32, self.goal.y as f32, self.goal.z as f32],
            per_item: queries.len() / 3,
            queries,
        }
    }
}

fn model_error(e: envfield_nets::NetsError) -> envfield_grid::GridError {
    envfield_grid::GridError::Model {
        model: "field3".into(),
        source: Box::new(e),
    }
}

impl ContinuousField3 for LearnedField3<'_> {
    fn value(&self, p: Point3m) -> envfield_grid::Result<f32> {
        Ok(self.values(&[p])?[0])
    }

    /// One network pass for all the points.
    fn values(&self, points: &[Point3m]) -> envfield_grid::Result<Vec<f32>> {
        if points.is_empty() {
            return Ok(Vec::new());
        }
        let raw = self
            .net
            .predict_encoded(&self.batch(points)?)
            .map_err(model_error)?;
        let encoding = self.net.config().encoding();
        let v = self.frame.voxel;
        Ok(raw.iter().map(|&t| encoding.decode(t) * v).collect())
    }

    fn gradient(&self, p: Point3m) -> envfield_grid::Result<Option<Point3m>> {
        let (raw, grad) = self
            .net
            .predict_with_gradient(&self.batch(&[p])?)
            .map_err(model_error)?;
        let encoding = self.net.config().encoding();
        if !encoding.decode(raw[0]).is_finite() {
            return Ok(None);
        }
        // d metres / d metres: the output's slope per voxel unit, in metres per voxel, over
        // metres per voxel.
        let slope = encoding.slope(raw[0]);
        Ok(Some([slope * grad[0], slope * grad[1], slope * grad[2]]))
    }
}
