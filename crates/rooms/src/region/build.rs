//! How a region is built from kept torso samples, step by step: the lattice, the samples'
//! voxels, the gaps between them closed, the sit-downs laid in, the largest connected set
//! (parted where no chest passes).

use super::{
    AccessibleRegion, BuildTimes, LeftOut, LieDown, SitDown, LEFT_OUT_LEVEL_M, LEFT_OUT_NAMED_M2,
};
use crate::{Result, RoomsError};
use envfield_affordance::{Pose, PoseSequence};
use envfield_grid::Point3m;
use envfield_grid::{Cell3, Components, Grid3};
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::{Scene, VoxelFrame};
use std::time::Instant;

/// A person passes where their chest has this much room around it, metres: half a slim
/// adult's chest depth (0.2-0.3 m for adults). The region parts where its voxels have less,
/// when that leaves floors of 1 m2 or more apart; on its 0.1 m voxels a passage narrower than
/// 0.21 m always parts it and one of 0.31 m or more never does. Lattices coarser than 0.21 m
/// are not parted.
pub const PASSAGE_CLEARANCE: f32 = 0.105;

/// Where a torso voxel's room is measured: this far above its centre (metres), at a standing
/// body's chest; above a seated or lying torso it is open air.
const CHEST_ABOVE: f32 = 0.3;

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
    let (grid, components, left_out) = largest_set(&voxels, scene)?;
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

/// The largest 26-connected set of the voxels that are on, parted where a person does not
/// pass ([`part_at_passages`]), how many sets there were, and the sets left out, largest first.
fn largest_set(voxels: &Voxels<'_>, scene: &Scene) -> Result<(Grid3, usize, Vec<LeftOut>)> {
    let all = voxels.grid()?;
    let components = all.free_components();
    let largest = components.largest().unwrap_or(0);
    let mut labels = components.labels;
    let parts = if components.sizes.is_empty() {
        0
    } else {
        part_at_passages(voxels, &all, scene, &mut labels, largest)?
    };
    let obstacles = labels.iter().map(|&l| l != largest).collect();
    let grid = Grid3::from_obstacles(voxels.frame.shape, obstacles)?;
    if grid.free_count() == 0 {
        return Err(RoomsError::InvalidInput(
            "the kept samples all lie outside the scene's box".into(),
        ));
    }
    Ok((
        grid,
        components.sizes.len() + parts,
        left_out(voxels, &labels, largest),
    ))
}

/// Parts the set labelled `largest` where a person does not pass: where its voxels' chests
/// ([`CHEST_ABOVE`] over the torso) have less than [`PASSAGE_CLEARANCE`] of room, a body
/// turned sideways fits its joints through (a slot in a wall) but not its chest. The voxels
/// with room are grouped (26-connected); when two groups or more on the set's floor level
/// (its lowest voxel, within [`LEFT_OUT_LEVEL_M`]) each cover [`LEFT_OUT_NAMED_M2`] of floor,
/// every voxel of the set goes to the group nearest it (in voxel steps) and the set keeps the
/// group with the most; the others get new labels, after every label in use. Seats, beds and
/// corners with little room stay with the floor beside them: only floors apart count. On a
/// lattice coarser than twice the clearance (a level's 0.25 m voxels) nothing is parted.
/// Returns how many sets were parted off.
fn part_at_passages(
    voxels: &Voxels<'_>,
    all: &Grid3,
    scene: &Scene,
    labels: &mut [usize],
    largest: usize,
) -> Result<usize> {
    if voxels.frame.voxel > 2.0 * PASSAGE_CLEARANCE {
        // Too coarse to tell a slot from a doorway (a level's 0.25 m voxels).
        return Ok(0);
    }
    let members: Vec<usize> = (0..labels.len())
        .filter(|&i| labels[i] == largest)
        .collect();
    let frame = voxels.frame;
    let chests: Vec<Point3<f32>> = members
        .iter()
        .map(|&i| frame.center(voxels.cell(i)) + Vector3::new(0.0, 0.0, CHEST_ABOVE))
        .collect();
    let clear = scene.signed_distances(&chests)?;
    let mut roomy = vec![false; labels.len()];
    for (&i, &d) in members.iter().zip(&clear) {
        roomy[i] = d >= PASSAGE_CLEARANCE;
    }
    let groups = Components::label(&roomy, |i, visit| all.around(i, visit));
    // Each group's lowest voxel and its columns, to keep the floors of the set's level.
    let lowest = members.iter().map(|&i| voxels.cell(i).z).min().unwrap_or(0);
    let level = (LEFT_OUT_LEVEL_M / frame.voxel).round() as usize;
    let mut low = vec![usize::MAX; groups.count()];
    let mut columns = vec![std::collections::HashSet::new(); groups.count()];
    for &i in &members {
        let g = groups.labels[i];
        if g != usize::MAX {
            let c = voxels.cell(i);
            low[g] = low[g].min(c.z);
            columns[g].insert((c.x, c.y));
        }
    }
    let cell_m2 = frame.voxel * frame.voxel;
    let floors: Vec<usize> = (0..groups.count())
        .filter(|&g| {
            low[g] <= lowest + level && columns[g].len() as f32 * cell_m2 >= LEFT_OUT_NAMED_M2
        })
        .collect();
    if floors.len() < 2 {
        return Ok(0);
    }
    // Every voxel of the set to the floor nearest it, breadth first from all floors at once.
    let mut owner = vec![usize::MAX; labels.len()];
    let mut queue = std::collections::VecDeque::new();
    for (k, &g) in floors.iter().enumerate() {
        for &i in &members {
            if groups.labels[i] == g {
                owner[i] = k;
                queue.push_back(i);
            }
        }
    }
    while let Some(i) = queue.pop_front() {
        let k = owner[i];
        all.around(i, |j| {
            if labels[j] == largest && owner[j] == usize::MAX {
                owner[j] = k;
                queue.push_back(j);
            }
        });
    }
    let mut sizes = vec![0usize; floors.len()];
    for &i in &members {
        if owner[i] != usize::MAX {
            sizes[owner[i]] += 1;
        }
    }
    let kept = (0..floors.len()).max_by_key(|&k| sizes[k]).unwrap_or(0);
    let next = labels
        .iter()
        .filter(|&&l| l != usize::MAX)
        .max()
        .map_or(0, |&l| l + 1);
    for &i in &members {
        let k = owner[i];
        if k != usize::MAX && k != kept {
            labels[i] = next + if k < kept { k } else { k - 1 };
        }
    }
    Ok(floors.len() - 1)
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
