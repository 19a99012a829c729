//! How a region is built from kept torso samples, step by step: the lattice, the samples'
//! voxels, the gaps between them closed, the sit-downs laid in, the largest connected set.

use super::{AccessibleRegion, BuildTimes, LeftOut, LieDown, SitDown};
use crate::{Result, RoomsError};
use envfield_affordance::{Pose, PoseSequence};
use envfield_grid::Point3m;
use envfield_grid::{Cell3, Grid3};
use envfield_scene::nalgebra::Point3;
use envfield_scene::{Scene, VoxelFrame};
use std::time::Instant;

/// The six face neighbours of a voxel.
const FACES: [(isize, isize, isize); 6] = [
    (1, 0, 0),
    (-1, 0, 0),
    (0, 1, 0),
    (0, -1, 0),
    (0, 0, 1),
    (0, 0, -1),
];

/// Voxels on a lattice, on or off, in C order.
struct Voxels<'a> {
    frame: &'a VoxelFrame,
    on: Vec<bool>,
}

impl<'a> Voxels<'a> {
    fn new(frame: &'a VoxelFrame) -> Self {
        let [nx, ny, nz] = frame.shape;
        Self {
            frame,
            on: vec![false; nx * ny * nz],
        }
    }

    fn index(&self, c: Cell3) -> usize {
        let [_, ny, nz] = self.frame.shape;
        (c.x * ny + c.y) * nz + c.z
    }

    fn cell(&self, i: usize) -> Cell3 {
        let [_, ny, nz] = self.frame.shape;
        Cell3::new(i / (ny * nz), (i / nz) % ny, i % nz)
    }

    /// Turns on the voxel of `p`, if it lies on the lattice.
    fn set(&mut self, p: &Point3<f32>) {
        if let Some(c) = self.frame.cell_of(p) {
            let i = self.index(c);
            self.on[i] = true;
        }
    }

    /// The voxels that are on as a grid's free cells.
    fn grid(&self) -> Result<Grid3> {
        Ok(Grid3::from_obstacles(
            self.frame.shape,
            self.on.iter().map(|&o| !o).collect(),
        )?)
    }
}

/// The sit-downs and lie-downs whose torsos join voxels a region's samples left apart.
pub(super) struct Links {
    /// Sit-downs from the floor onto seats.
    pub sit_downs: Vec<SitDown>,
    /// Lie-downs from the edge of a bed or sofa onto its length.
    pub lie_downs: Vec<LieDown>,
    /// Milliseconds the lie-downs took (apart from the sit-downs').
    pub lie_downs_ms: f64,
}

/// Builds the region of `kept` (see [`AccessibleRegion::from_kept`]): each face neighbour of a
/// sample's voxel joins when `joins` says so of its centre (asked once, for all of them), and
/// the voxels along the torsos of each sit-down and lie-down `links` gives (for the lattice,
/// the voxels so far and the samples) join too, before the largest connected set is kept; the
/// sit-downs that end in it and the lie-downs that start and end in it are the region's.
pub(super) fn build(
    scene: &Scene,
    kept: Vec<Point3m>,
    voxel: f32,
    joins: impl FnOnce(&[Point3m]) -> Result<Vec<bool>>,
    links: impl FnOnce(&VoxelFrame, &Grid3, &[Point3m]) -> Result<Links>,
) -> Result<AccessibleRegion> {
    if kept.is_empty() {
        return Err(RoomsError::InvalidInput(
            "no torso sample affords a pose here: the scene has no floor or seat the samples \
             reach (a scene read with the wrong up axis (--up), in other units (--units) or off \
             level has none: the import's warnings say which)"
                .into(),
        ));
    }
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let mut times = BuildTimes::default();
    let start = Instant::now();
    let frame = lattice(scene, &kept, voxel)?;
    let mut voxels = Voxels::new(&frame);
    for p in &kept {
        voxels.set(&Point3::from(*p));
    }
    times.voxels_ms += ms(start);
    let start = Instant::now();
    close_gaps(&mut voxels, &kept, joins)?;
    times.gaps_ms = ms(start);
    let start = Instant::now();
    let Links {
        sit_downs,
        lie_downs,
        lie_downs_ms,
    } = links(&frame, &voxels.grid()?, &kept)?;
    for sit in &sit_downs {
        lay_torsos(&mut voxels, &sit.sequence()?, voxel);
    }
    for lie in &lie_downs {
        lay_torsos(&mut voxels, &lie.sequence()?, voxel);
    }
    times.sit_downs_ms = ms(start) - lie_downs_ms;
    times.lie_downs_ms = lie_downs_ms;
    let start = Instant::now();
    let (grid, components, left_out) = largest_set(&voxels)?;
    let mut region = AccessibleRegion::new(frame, grid, kept, components)?;
    region.left_out = left_out;
    region.sit_downs = sit_downs
        .into_iter()
        .filter(|s| region.contains(s.seated))
        .collect();
    region.lie_downs = lie_downs
        .into_iter()
        .filter(|l| region.contains(l.sit.seated) && region.contains(l.lying))
        .collect();
    times.voxels_ms += ms(start);
    region.times = times;
    Ok(region)
}

/// A lattice of `voxel` covering the scene and every kept sample, with a voxel to spare.
fn lattice(scene: &Scene, kept: &[Point3m], voxel: f32) -> Result<VoxelFrame> {
    let scene_box = scene
        .aabb()
        .ok_or_else(|| RoomsError::InvalidInput("the scene is empty".into()))?;
    let (mut lo, mut hi) = (scene_box.mins, scene_box.maxs);
    for p in kept {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a] - voxel);
            hi[a] = hi[a].max(p[a] + voxel);
        }
    }
    let aabb = envfield_scene::parry3d::bounding_volume::Aabb::new(lo, hi);
    Ok(VoxelFrame::covering(&aabb, voxel)?)
}

/// Closes the gaps between samples: every face neighbour of a sample's voxel that holds no
/// sample joins when `joins` says so of its centre.
fn close_gaps(
    voxels: &mut Voxels<'_>,
    kept: &[Point3m],
    joins: impl FnOnce(&[Point3m]) -> Result<Vec<bool>>,
) -> Result<()> {
    let [nx, ny, nz] = voxels.frame.shape;
    let mut near = vec![false; voxels.on.len()];
    for p in kept {
        let Some(c) = voxels.frame.cell_of(&Point3::from(*p)) else {
            continue;
        };
        for (dx, dy, dz) in FACES {
            let (x, y, z) = (c.x as isize + dx, c.y as isize + dy, c.z as isize + dz);
            let inside = x >= 0
                && y >= 0
                && z >= 0
                && (x as usize) < nx
                && (y as usize) < ny
                && (z as usize) < nz;
            if inside {
                let i = voxels.index(Cell3::new(x as usize, y as usize, z as usize));
                near[i] = !voxels.on[i];
            }
        }
    }
    let candidates: Vec<usize> = (0..near.len()).filter(|&i| near[i]).collect();
    let centres: Vec<Point3m> = candidates
        .iter()
        .map(|&i| voxels.frame.center(voxels.cell(i)).into())
        .collect();
    for (i, join) in candidates.into_iter().zip(joins(&centres)?) {
        voxels.on[i] = join;
    }
    Ok(())
}

/// Turns on the voxels along a sequence's torsos (a sit-down's, a lie-down's), in steps of at
/// most half a voxel so that the chain's voxels touch.
fn lay_torsos(voxels: &mut Voxels<'_>, seq: &PoseSequence, voxel: f32) {
    let chain: Vec<Point3<f32>> = seq.frames.iter().map(Pose::torso).collect();
    for pair in chain.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let steps = ((b - a).norm() / (0.5 * voxel)).ceil().max(1.0) as usize;
        for k in 0..=steps {
            voxels.set(&(a + (b - a) * (k as f32 / steps as f32)));
        }
    }
}

/// The largest 26-connected set of the voxels that are on, how many sets there were, and the
/// sets left out, largest first.
fn largest_set(voxels: &Voxels<'_>) -> Result<(Grid3, usize, Vec<LeftOut>)> {
    let all = voxels.grid()?;
    let components = all.free_components();
    let largest = components.largest().unwrap_or(0);
    let obstacles = components.labels.iter().map(|&l| l != largest).collect();
    let grid = Grid3::from_obstacles(voxels.frame.shape, obstacles)?;
    if grid.free_count() == 0 {
        return Err(RoomsError::InvalidInput(
            "the kept samples all lie outside the scene's box".into(),
        ));
    }
    Ok((
        grid,
        components.count(),
        left_out(voxels, &components.labels, largest),
    ))
}

/// What each set of voxels but the `largest` covers: its voxels, its columns and its box.
fn left_out(voxels: &Voxels<'_>, labels: &[usize], largest: usize) -> Vec<LeftOut> {
    use std::collections::{HashMap, HashSet};
    /// A set's voxels, its columns seen from above and its box, in cells.
    struct Set {
        voxels: usize,
        columns: HashSet<(usize, usize)>,
        lo: [usize; 3],
        hi: [usize; 3],
    }
    let mut sets: HashMap<usize, Set> = HashMap::new();
    for (i, &l) in labels.iter().enumerate() {
        if l == usize::MAX || l == largest {
            continue;
        }
        let c = voxels.cell(i);
        let set = sets.entry(l).or_insert_with(|| Set {
            voxels: 0,
            columns: HashSet::new(),
            lo: [usize::MAX; 3],
            hi: [0; 3],
        });
        set.voxels += 1;
        set.columns.insert((c.x, c.y));
        for (k, v) in [c.x, c.y, c.z].into_iter().enumerate() {
            set.lo[k] = set.lo[k].min(v);
            set.hi[k] = set.hi[k].max(v);
        }
    }
    let frame = &voxels.frame;
    let corner = |c: [usize; 3], far: f32| -> [f32; 3] {
        std::array::from_fn(|k| frame.origin[k] + (c[k] as f32 + far) * frame.voxel)
    };
    let mut out: Vec<LeftOut> = sets
        .into_values()
        .map(|set| LeftOut {
            voxels: set.voxels,
            area_m2: set.columns.len() as f32 * frame.voxel * frame.voxel,
            min: corner(set.lo, 0.0),
            max: corner(set.hi, 1.0),
        })
        .collect();
    out.sort_by_key(|set| std::cmp::Reverse(set.voxels));
    out
}
