//! PIBT as multi-agent path finding writes it (Okumura et al. 2019/2022): the baseline
//! [`grid_pibt`] on an occupancy grid whose cell holds one body.

use super::geometry::{point, segment_clear};
use super::{check_trips, CrowdConfig, CrowdRun, Trip};
use crate::Result;
use envfield_grid::{Cell2, Grid2, Point2, SplitMix64};
use std::collections::VecDeque;

/// Priority inheritance with backtracking (Okumura, Machida, Défago and Tamura, "Priority
/// Inheritance with Backtracking for Iterative Multi-agent Path Finding", IJCAI 2019 / AIJ
/// 2022) on an occupancy grid of one body per cell: the baseline multi-agent path finding
/// would bring, written here from the paper.
///
/// The grid: a lattice of `walkable`'s points every body diameter (twice
/// [`CrowdConfig::body_radius`], rounded to whole cells), a vertex where the walkable map is
/// free, 4-connected where the straight step between two vertices is clear; of the lattice's
/// offsets, the one whose largest connected set is largest. Each person starts by moving to the
/// vertex nearest their start within a straight step (any nearest one if none is; in frame 1;
/// no two share one) and has arrived when they stand on the vertex chosen so for their goal.
/// Every time step each person moves to a neighbouring vertex or stays (one step is one body
/// diameter, whatever `config.step_length`). PIBT's rules: priorities grow by one each step
/// off the goal and drop to a fixed fraction on it; in priority order, each person takes the
/// nearest vertex (breadth-first distance to the goal; ties in a seeded random order) not
/// taken this step; a person standing on it is pushed (inherits the priority) and must move
/// first, anywhere but the pusher's vertex; if they cannot, the next vertex is tried.
///
/// The motion is recorded like the other loops', so the collisions counted from it are those
/// of bodies moving in straight lines between frames: a vertex conflict cannot happen, but two
/// people turning a corner one behind the other come closer than a diameter midway.
///
/// # Errors
/// A bad problem ([`check_trips`]); more people than the lattice has vertices
/// ([`crate::PlanError::Invalid`]). A person whose goal vertex the lattice does not join to
/// their start vertex (a door narrower than its spacing) is no error: they cannot arrive.
///
/// ```
/// use envfield_grid::{Cell2, Grid2};
/// use envfield_plan::crowd::{grid_pibt, CrowdConfig, Ending, Trip};
///
/// let floor = Grid2::new(30, 30)?;
/// let trips = [
///     Trip { start: Cell2::new(3, 3), goal: Cell2::new(26, 26) },
///     Trip { start: Cell2::new(26, 26), goal: Cell2::new(3, 3) },
/// ];
/// let run = grid_pibt(&floor, &trips, &CrowdConfig::default(), 0)?;
/// assert_eq!(run.ending, Ending::Arrived);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn grid_pibt(
    walkable: &Grid2,
    trips: &[Trip],
    config: &CrowdConfig,
    seed: u64,
) -> Result<CrowdRun> {
    check_trips(walkable, trips, config)?;
    let spacing = (2.0 * config.body_radius).round().max(1.0) as usize;
    let lattice = (0..spacing * spacing)
        .map(|k| Lattice::new(walkable, spacing, [k / spacing, k % spacing]))
        .max_by_key(Lattice::connected)
        .expect("at least one offset");
    let starts = lattice.snap(trips.iter().map(|t| t.start), "start")?;
    let goals = lattice.snap(trips.iter().map(|t| t.goal), "goal")?;
    let dist: Vec<Vec<u32>> = goals.iter().map(|&g| lattice.distances(g)).collect();
    let n = trips.len();
    let mut run = CrowdRun::starting(&trips.iter().map(|t| point(t.start)).collect::<Vec<_>>());
    run.stay_on_map = true;
    let mut at: Vec<usize> = starts;
    run.frames
        .push(at.iter().map(|&v| lattice.point(v)).collect());
    let mut priority: Vec<f32> = (0..n).map(|i| (i as f32 + 0.5) / n as f32).collect();
    let mut rng = SplitMix64::new(seed ^ 0x9_1B7);
    let mut arrived_since: Vec<Option<usize>> = vec![None; n];
    let mut occupant = vec![usize::MAX; lattice.len()];
    for (i, &v) in at.iter().enumerate() {
        occupant[v] = i;
    }
    while run.steps() < config.max_steps && (0..n).any(|i| at[i] != goals[i]) {
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| priority[b].total_cmp(&priority[a]));
        let mut step = Step {
            lattice: &lattice,
            dist: &dist,
            from: &at,
            occupant: &occupant,
            next: vec![usize::MAX; n],
            taken: vec![usize::MAX; lattice.len()],
            rng: &mut rng,
        };
        for &i in &order {
            if step.next[i] == usize::MAX && !step.choose(i, None) {
                run.waits += 1;
            }
        }
        let next = step.next;
        for &v in &at {
            occupant[v] = usize::MAX;
        }
        let t = run.steps() + 1;
        for i in 0..n {
            at[i] = next[i];
            occupant[at[i]] = i;
            if at[i] == goals[i] {
                priority[i] = priority[i].fract();
                arrived_since[i] = arrived_since[i].or(Some(t));
            } else {
                priority[i] += 1.0;
                arrived_since[i] = None;
            }
        }
        run.frames
            .push(at.iter().map(|&v| lattice.point(v)).collect());
    }
    run.arrived_at = arrived_since;
    run.finish();
    Ok(run)
}

/// The lattice of one body per cell over a walkable map.
struct Lattice<'a> {
    walkable: &'a Grid2,
    spacing: usize,
    /// The first vertex's cell.
    offset: [usize; 2],
    rows: usize,
    cols: usize,
    /// Each vertex's neighbours (free, step clear).
    neighbours: Vec<Vec<usize>>,
}

impl<'a> Lattice<'a> {
    fn new(walkable: &'a Grid2, spacing: usize, offset: [usize; 2]) -> Self {
        let rows = walkable.rows().saturating_sub(offset[0]).div_ceil(spacing);
        let cols = walkable.cols().saturating_sub(offset[1]).div_ceil(spacing);
        let cell = |v: usize| {
            Cell2::new(
                offset[0] + v / cols * spacing,
                offset[1] + v % cols * spacing,
            )
        };
        let free: Vec<bool> = (0..rows * cols)
            .map(|v| walkable.is_free(cell(v)))
            .collect();
        let neighbours = (0..rows * cols)
            .map(|v| {
                if !free[v] {
                    return Vec::new();
                }
                let (r, c) = (v / cols, v % cols);
                [
                    (r > 0).then(|| v - cols),
                    (r + 1 < rows).then(|| v + cols),
                    (c > 0).then(|| v - 1),
                    (c + 1 < cols).then(|| v + 1),
                ]
                .into_iter()
                .flatten()
                .filter(|&u| free[u] && segment_clear(walkable, point(cell(v)), point(cell(u))))
                .collect()
            })
            .collect();
        Self {
            walkable,
            spacing,
            offset,
            rows,
            cols,
            neighbours,
        }
    }

    /// Vertices in the largest connected set.
    fn connected(&self) -> usize {
        let mut seen = vec![false; self.len()];
        let mut best = 0;
        for first in 0..self.len() {
            if seen[first] || self.neighbours[first].is_empty() {
                continue;
            }
            seen[first] = true;
            let (mut stack, mut size) = (vec![first], 0);
            while let Some(v) = stack.pop() {
                size += 1;
                for &u in &self.neighbours[v] {
                    if !seen[u] {
                        seen[u] = true;
                        stack.push(u);
                    }
                }
            }
            best = best.max(size);
        }
        best
    }

    fn len(&self) -> usize {
        self.rows * self.cols
    }

    fn point(&self, v: usize) -> Point2 {
        Point2::new(
            (self.offset[0] + v / self.cols * self.spacing) as f32,
            (self.offset[1] + v % self.cols * self.spacing) as f32,
        )
    }

    /// Each cell's nearest free vertex within a straight step (or nearest at all), none
    /// shared, in the order given.
    fn snap(&self, cells: impl Iterator<Item = Cell2>, what: &str) -> Result<Vec<usize>> {
        let mut used = vec![false; self.len()];
        let mut out = Vec::new();
        for (i, c) in cells.enumerate() {
            let p = point(c);
            let open: Vec<usize> = (0..self.len())
                .filter(|&v| !used[v] && !self.neighbours[v].is_empty())
                .collect();
            let nearest = |vs: &mut dyn Iterator<Item = usize>| {
                vs.min_by(|&a, &b| {
                    p.distance(self.point(a))
                        .total_cmp(&p.distance(self.point(b)))
                })
            };
            let straight = nearest(
                &mut open
                    .iter()
                    .copied()
                    .filter(|&v| segment_clear(self.walkable, p, self.point(v))),
            );
            let best = straight
                .or_else(|| nearest(&mut open.iter().copied()))
                .ok_or_else(|| {
                    crate::PlanError::Invalid(format!(
                        "person {i}'s {what}: no free vertex left on the lattice of one body \
                         per cell"
                    ))
                })?;
            used[best] = true;
            out.push(best);
        }
        Ok(out)
    }

    /// Breadth-first distance of every vertex to `goal` (`u32::MAX`: unreachable).
    fn distances(&self, goal: usize) -> Vec<u32> {
        let mut dist = vec![u32::MAX; self.len()];
        dist[goal] = 0;
        let mut queue = VecDeque::from([goal]);
        while let Some(v) = queue.pop_front() {
            for &u in &self.neighbours[v] {
                if dist[u] == u32::MAX {
                    dist[u] = dist[v] + 1;
                    queue.push_back(u);
                }
            }
        }
        dist
    }
}

/// One time step of PIBT.
struct Step<'s> {
    lattice: &'s Lattice<'s>,
    dist: &'s [Vec<u32>],
    /// Each person's vertex now.
    from: &'s [usize],
    /// Who stands on each vertex now.
    occupant: &'s [usize],
    /// Each person's vertex next (`usize::MAX`: not chosen yet).
    next: Vec<usize>,
    /// Who takes each vertex next.
    taken: Vec<usize>,
    rng: &'s mut SplitMix64,
}

impl Step<'_> {
    /// PIBT(i, pusher): the paper's recursive call.
    fn choose(&mut self, i: usize, pusher: Option<usize>) -> bool {
        let here = self.from[i];
        let mut options: Vec<usize> = self.lattice.neighbours[here].clone();
        options.push(here);
        // Ties in a random order, then nearest first.
        for k in (1..options.len()).rev() {
            options.swap(k, self.rng.below(k + 1));
        }
        options.sort_by_key(|&v| self.dist[i][v]);
        for v in options {
            if self.taken[v] != usize::MAX {
                continue;
            }
            if pusher.is_some_and(|j| self.from[j] == v) {
                continue;
            }
            self.next[i] = v;
            self.taken[v] = i;
            let k = self.occupant[v];
            if k != usize::MAX && k != i && self.next[k] == usize::MAX && !self.choose(k, Some(i)) {
                // k stays on v (its failed call took it).
                continue;
            }
            return true;
        }
        self.next[i] = here;
        self.taken[here] = i;
        false
    }
}
