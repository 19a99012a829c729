//! The accessible region of a scene: torso samples kept by the torso filter
//! ([`envfield_affordance::afford`]: a clear torso sphere, some supported and plausible pose,
//! settling onto a seat), voxelised into one connected set.
//!
//! The build, step by step (`build`): a lattice over the scene and the samples; each kept
//! sample's voxel; the gaps between them closed through face neighbours whose centres pass
//! the filter too, so the region does not spill over a table's edge; the sit-downs that join
//! a seat's voxels to the floor's ([`SitDown`], every pose valid and plausible); the
//! lie-downs from those sit-downs onto the length of a bed or sofa ([`LieDown`], the same);
//! the largest 26-connected set, parted where no chest passes ([`PASSAGE_CLEARANCE`]).
//! [`crate::quality`] judges the result.

mod bridges;
mod build;
mod config;
mod lie;
mod write;

pub(crate) use bridges::sit_down_to;
pub use bridges::SitDown;
pub use build::PASSAGE_CLEARANCE;
pub use config::RegionConfig;
pub use lie::{LieDown, LIE_LIFT, LIE_ROOM, LIE_SLIDES, LIE_TURNS};

use crate::{Result, RoomsError};
use envfield_affordance::{afford_all, Afford};
use envfield_eikonal::FreeCells3;
use envfield_grid::Point3m;
use envfield_grid::{Cell3, Grid3};
use envfield_scene::nalgebra::Point3;
use envfield_scene::{Scene, VoxelFrame};

/// How long each step of a region's build took, milliseconds of wall time (0 for a step not
/// run): the torso filter of the drawn samples, closing the gaps (the filter again, at the
/// neighbouring voxels' centres), the sit-down bridges, and the voxels (lattice, sets).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BuildTimes {
    /// The filter of the drawn samples.
    pub filter_ms: f64,
    /// The gaps between samples closed.
    pub gaps_ms: f64,
    /// The sit-downs that join seats to the floor.
    pub sit_downs_ms: f64,
    /// The lie-downs from the sit-downs onto beds and sofas.
    #[serde(default)]
    pub lie_downs_ms: f64,
    /// The lattice, the samples' voxels and the largest set.
    pub voxels_ms: f64,
}

/// A connected set of accessible voxels that the region left out, for it keeps only the
/// largest: a room joined to the rest by no way the body fits through, a seat no sit-down
/// reaches, a table top.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LeftOut {
    /// Its voxels.
    pub voxels: usize,
    /// The floor it covers seen from above (its voxel columns), square metres.
    pub area_m2: f32,
    /// Its box's minimum corner, metres.
    pub min: [f32; 3],
    /// Its box's maximum corner, metres.
    pub max: [f32; 3],
}

/// A part left out of the region at the kept part's floor level (within
/// [`LEFT_OUT_LEVEL_M`]) is named in [`AccessibleRegion::left_out_warning`] when it covers
/// this much floor (square metres) or more: a room on the same floor, not a corner.
pub const LEFT_OUT_NAMED_M2: f32 = 1.0;

/// A part left out at another height is named when it covers this much (square metres) or
/// more: a storey or a gallery, larger than any bed, table top or seat.
pub const LEFT_OUT_STOREY_M2: f32 = 6.0;

/// How far (metres) a part's lowest voxel may lie from the kept part's for the two to be on
/// one floor.
pub const LEFT_OUT_LEVEL_M: f32 = 0.15;

/// The accessible region of a scene: the voxels holding kept torso samples (and their six
/// neighbours, closing the gaps between samples), reduced to its largest 26-connected set
/// (parted first where a chest has less than [`PASSAGE_CLEARANCE`] of room).
#[derive(Clone, Debug)]
pub struct AccessibleRegion {
    /// The voxel lattice, metres.
    pub frame: VoxelFrame,
    /// Free voxels are accessible.
    pub grid: Grid3,
    /// The kept samples, metres.
    pub samples: Vec<Point3m>,
    /// Connected sets before the largest was kept (those parted at a passage included).
    pub components: usize,
    /// The sets apart from the largest, left out of the region, largest first (empty for a
    /// region made from its parts).
    pub left_out: Vec<LeftOut>,
    /// The sit-downs that joined seats to the floor's set ([`AccessibleRegion::from_kept`]),
    /// each ending seated in the region.
    pub sit_downs: Vec<SitDown>,
    /// The lie-downs from its sit-downs onto the length of a bed or sofa
    /// ([`AccessibleRegion::from_kept`]), each starting and ending in the region.
    pub lie_downs: Vec<LieDown>,
    /// How long each step of its build took.
    pub times: BuildTimes,
    /// The accessible voxels' indices, made on first use.
    free: std::sync::OnceLock<Vec<usize>>,
    /// The accessible voxels numbered and linked for fast marching, made on first use.
    cells: std::sync::OnceLock<std::sync::Arc<FreeCells3>>,
}

impl AccessibleRegion {
    /// A region from its parts: `grid`'s free voxels on `frame` are accessible.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] when the grid's shape is not the frame's or no voxel is
    /// free.
    pub fn new(
        frame: VoxelFrame,
        grid: Grid3,
        samples: Vec<Point3m>,
        components: usize,
    ) -> Result<Self> {
        if grid.shape() != frame.shape {
            return Err(RoomsError::InvalidInput(format!(
                "a region's grid {:?} must have its frame's shape {:?}",
                grid.shape(),
                frame.shape
            )));
        }
        if grid.free_count() == 0 {
            return Err(RoomsError::InvalidInput(
                "a region needs an accessible voxel".into(),
            ));
        }
        Ok(Self {
            frame,
            grid,
            samples,
            components,
            left_out: Vec::new(),
            sit_downs: Vec::new(),
            lie_downs: Vec::new(),
            times: BuildTimes::default(),
            free: std::sync::OnceLock::new(),
            cells: std::sync::OnceLock::new(),
        })
    }

    /// The accessible voxels numbered in C order and linked to their neighbours, made once
    /// (on first use) and shared by every field of the region: fast marching over them
    /// ([`FastMarching::solve3_free`](envfield_eikonal::FastMarching::solve3_free)) costs
    /// the voxels it reaches, not the region's box, and a [`crate::VoxelField3`] keeps a
    /// value per accessible voxel alone.
    ///
    /// # Errors
    /// [`RoomsError::Eikonal`] for a lattice too large to march.
    pub fn free_cells(&self) -> Result<std::sync::Arc<FreeCells3>> {
        if let Some(cells) = self.cells.get() {
            return Ok(cells.clone());
        }
        let cells = std::sync::Arc::new(FreeCells3::new(&self.grid)?);
        Ok(self.cells.get_or_init(|| cells).clone())
    }

    /// The accessible voxels' indices (C order).
    pub fn free_indices(&self) -> &[usize] {
        self.free.get_or_init(|| {
            (0..self.grid.len())
                .filter(|&i| !self.grid.obstacles()[i])
                .collect()
        })
    }

    /// The region of drawn torso `samples` in `scene`: the torso filter ([`afford_all`], keeping
    /// what [`Afford::kept`] keeps), then [`AccessibleRegion::from_samples`] at the config's
    /// voxel.
    ///
    /// # Errors
    /// As [`afford_all`] and [`AccessibleRegion::from_samples`].
    pub fn from_drawn(scene: &Scene, samples: &[Point3m], config: &RegionConfig) -> Result<Self> {
        config.validate()?;
        let start = std::time::Instant::now();
        let kept = afford_all(scene, samples, &config.filter)?
            .iter()
            .filter(|a| a.kept())
            .map(|a| a.at)
            .collect();
        let filter_ms = start.elapsed().as_secs_f64() * 1e3;
        let mut region = Self::from_kept(scene, kept, config)?;
        region.times.filter_ms = filter_ms;
        Ok(region)
    }

    /// The region of `kept` samples (already filtered by `config`'s filter): as
    /// [`AccessibleRegion::from_samples`], except that with [`FilterConfig::plausible`](envfield_affordance::FilterConfig::plausible) a
    /// neighbouring voxel joins only if a torso at its centre passes the filter too, so the
    /// gaps between samples close without the region spilling over a table's edge, and a set
    /// of voxels apart from the largest joins it through a sit-down that ends in it (every
    /// pose of it valid and plausible): a seat's voxels lie half a metre below the floor's.
    ///
    /// # Errors
    /// As [`afford_all`] and [`AccessibleRegion::from_samples`].
    pub fn from_kept(scene: &Scene, kept: Vec<Point3m>, config: &RegionConfig) -> Result<Self> {
        config.validate()?;
        if !config.filter.plausible {
            return Self::from_samples(scene, kept, config.voxel);
        }
        let in_place = config.in_place();
        build::build(
            scene,
            kept,
            config.voxel,
            |centres| {
                Ok(afford_all(scene, centres, &in_place.filter)?
                    .iter()
                    .map(Afford::kept)
                    .collect())
            },
            |frame, all, kept| bridges::links(scene, frame, all, kept, config),
        )
    }

    /// The region of `kept` samples (already filtered) on a lattice covering `scene`.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] for no samples (a scene with no floor keeps none) or an
    /// empty scene.
    pub fn from_samples(scene: &Scene, kept: Vec<Point3m>, voxel: f32) -> Result<Self> {
        build::build(
            scene,
            kept,
            voxel,
            |centres| Ok(vec![true; centres.len()]),
            |_, _, _| {
                Ok(build::Links {
                    sit_downs: Vec::new(),
                    lie_downs: Vec::new(),
                    lie_downs_ms: 0.0,
                })
            },
        )
    }

    /// What the region left out that a user would miss: the parts apart from the largest on
    /// its floor covering [`LEFT_OUT_NAMED_M2`] or more, or at other heights
    /// [`LEFT_OUT_STOREY_M2`] or more (a bed or a table top left out is no news), named by
    /// where they lie, with the floor the region kept; `None` when there are none. Paths are planned within the part
    /// kept only, so a scene of two rooms joined by a slot narrower than the body reaches
    /// one of them: this says so.
    pub fn left_out_warning(&self) -> Option<String> {
        // The kept part's floor: the lowest of its voxels.
        let floor = self
            .free_indices()
            .iter()
            .map(|&i| self.frame.center(self.grid.cell(i)).z)
            .fold(f32::INFINITY, f32::min)
            - 0.5 * self.frame.voxel;
        let named: Vec<&LeftOut> = self
            .left_out
            .iter()
            .filter(|p| {
                let level = (p.min[2] - floor).abs() <= LEFT_OUT_LEVEL_M;
                p.area_m2
                    >= if level {
                        LEFT_OUT_NAMED_M2
                    } else {
                        LEFT_OUT_STOREY_M2
                    }
            })
            .collect();
        let first = named.first()?;
        let kept = {
            let columns: std::collections::HashSet<(usize, usize)> = self
                .free_indices()
                .iter()
                .map(|&i| {
                    let c = self.grid.cell(i);
                    (c.x, c.y)
                })
                .collect();
            columns.len() as f32 * self.frame.voxel * self.frame.voxel
        };
        let total: f32 = named.iter().map(|p| p.area_m2).sum();
        Some(format!(
            "the region keeps one connected part ({kept:.1} m2 of floor); {} part(s) apart from \
             it are left out ({total:.1} m2), the largest {:.1} m2 at x {:.2}..{:.2}, y \
             {:.2}..{:.2}, z {:.2}..{:.2} m: no way the body fits joins them to it (a doorway \
             or gap narrower than the body, a step too high, a floor without stairs?), and \
             nothing is planned there",
            named.len(),
            first.area_m2,
            first.min[0],
            first.max[0],
            first.min[1],
            first.max[1],
            first.min[2],
            first.max[2],
        ))
    }

    /// Whether `p` (metres) lies in an accessible voxel.
    pub fn contains(&self, p: Point3m) -> bool {
        self.frame
            .cell_of(&Point3::from(p))
            .is_some_and(|c| self.grid.is_free(c))
    }

    /// The accessible voxels' centres, metres.
    pub fn voxel_centres(&self) -> Vec<Point3m> {
        self.free_indices()
            .iter()
            .map(|&i| self.frame.center(self.grid.cell(i)).into())
            .collect()
    }

    /// The voxel of `p` when it is accessible.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] naming `what` for a point outside the region.
    pub fn cell(&self, p: Point3m, what: &str) -> Result<Cell3> {
        match self.frame.cell_of(&Point3::from(p)) {
            Some(c) if self.grid.is_free(c) => Ok(c),
            _ => Err(RoomsError::InvalidInput(format!(
                "{what} {p:?} is outside the accessible region"
            ))),
        }
    }
}
