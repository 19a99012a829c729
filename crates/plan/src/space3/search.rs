//! [`FieldSearch3`]: the pose-dependent search on a continuous 3D field (paper section 4.2,
//! "Pose-dependent trajectory"): from the start, step `s` towards each of the 26 directions of
//! `{-1, 0, 1}^3 \ {0}`, normalised so every candidate lies exactly `s` away; ask the field at
//! all candidates in one batch, keep the ones a [`StepFilter`] allows (the pose of this step
//! supported and collision-free, or simply inside the accessible region), and move to the
//! smallest value; where the filter leaves no way down, go on from the best point left
//! (greedy best-first, [`FieldSearch3::search`]). [`FieldSearch3::shortcut`] then straightens
//! the path where the filter allows a straight cut.

use super::{directions26, distance, Path3, StepFilter};
use crate::{PlanError, Result};
use envfield_grid::{ContinuousField3, Point3m};
use serde::{Deserialize, Serialize};
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// FxHash's multiply-rotate over the opened set's keys (packed lattice cells, hashed once per
/// candidate): std's SipHash guards against chosen keys, which a search never meets, at
/// several times the cost.
#[derive(Default)]
struct LatticeHasher(u64);

impl LatticeHasher {
    fn add(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
}

impl Hasher for LatticeHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        bytes.iter().for_each(|&b| self.add(u64::from(b)));
    }
    fn write_u64(&mut self, i: u64) {
        self.add(i);
    }
    fn write_usize(&mut self, i: usize) {
        self.add(i as u64);
    }
}

/// The pose-dependent search's settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FieldSearch3 {
    /// Step length `s`, metres (the pose sequence's `step_length`).
    pub step: f32,
    /// The search stops when the torso is this close to the goal, metres.
    pub tolerance: f32,
    /// Expansions at most (each one batched field query).
    pub max_steps: usize,
    /// Filter calls at most (a pose check each, refused or not), 0 for no limit. Where the
    /// filter refuses nearly everything (a pocket the poses cannot leave) a search spends its
    /// expansions slowly and its checks fast; this stops it there.
    #[serde(default)]
    pub max_checks: usize,
    /// Filter calls at most without coming nearer the goal, once the search has opened a
    /// point within two steps of it; 0 for no limit. A goal that a body fits only at a few
    /// frames of its gait and headings is come close to early and never landed on; past
    /// this many refusals in a row near it, the search ends there rather than spend its
    /// budget on the rest of the room.
    #[serde(default)]
    pub near_stall: usize,
}

impl FieldSearch3 {
    /// Searches from `start` to `goal` on `field`, each step's candidates filtered by
    /// `filter`: greedy best-first on the field's values. Each expansion asks the field at
    /// the 26 candidates of the point it expands in one batch and puts them on the open list;
    /// the point of least value comes off the list next, and the filter is asked about it
    /// then (lazily: a clear descent checks one pose per step, not 26). A point within `s / 2`
    /// of one already opened is not opened again. Where the field has no local minimum under
    /// the filter this is exactly the paper's descent, moving to the smallest allowed
    /// candidate at every step; where the filter blocks that descent (the pose of the best
    /// step would collide), the search goes on from the best point left instead of stopping.
    /// When the goal lies within `s` and the filter allows it, the path lands on it. The path
    /// is the chain of steps from the start to the point it ends on: the goal, or after
    /// `max_steps` expansions (or `max_checks` filter calls, or `near_stall` of them near the
    /// goal without coming nearer) the opened point nearest the goal (then `reached` is
    /// false). A step's filter call gets the step's index along that chain.
    ///
    /// # Errors
    /// [`PlanError::Invalid`] for a step, tolerance or point that is not positive / finite;
    /// errors of the filter.
    pub fn search<F, S>(
        &self,
        field: &F,
        filter: &S,
        start: Point3m,
        goal: Point3m,
    ) -> Result<Path3>
    where
        F: ContinuousField3 + ?Sized,
        S: StepFilter + ?Sized,
    {
        let ok = self.step.is_finite()
            && self.step > 0.0
            && self.tolerance.is_finite()
            && self.tolerance >= 0.0;
        if !ok {
            return Err(PlanError::Invalid(format!(
                "3D search: a positive step and a tolerance >= 0 (got {} and {}); a pose \
                 sequence with no motion has step length 0",
                self.step, self.tolerance
            )));
        }
        for (what, p) in [("start", start), ("goal", goal)] {
            if !p.iter().all(|v| v.is_finite()) {
                return Err(PlanError::Invalid(format!(
                    "3D search: {what} {p:?} is not finite"
                )));
            }
        }
        let dirs = directions26();
        let s = self.step;
        let key = |p: Point3m| lattice_key(p, 0.5 * s);
        // The opened points: position, parent and depth (the index along its chain).
        let mut nodes: Vec<Node> = Vec::new();
        // Each expansion's candidates with finite values, in increasing value (ties in the
        // directions' order; the best first, the rest sorted when the second is asked for),
        // in `pending[first..first + len]`; the open list holds each
        // expansion's best candidate not yet taken, and taking one puts its next on the list.
        // This is the order in which a list of every candidate would give them up, at a
        // fraction of the list's work: a clear descent takes one candidate per expansion.
        let mut expansions: Vec<Expansion> = Vec::new();
        let mut pending: Vec<(f32, Point3m)> = Vec::new();
        let mut opened: HashSet<u64, BuildHasherDefault<LatticeHasher>> = HashSet::default();
        // Each entry (value, expansion, candidate) packed into one ordered word: the heap's
        // compares are then one integer compare, in the tuple's order.
        let mut open: BinaryHeap<Reverse<u128>> = BinaryHeap::new();
        let mut nearest = (f32::INFINITY, 0usize);
        // The filter calls made when the search last came nearer the goal.
        let mut nearer_at = 0;
        let mut end = None;
        let mut exhausted = false;
        let (mut expanded, mut checks) = (0, 0);
        let mut candidates = [[0.0f32; 3]; 26];
        let mut started = false;
        loop {
            // The next point: the start first, then the best candidate on the list.
            let (here, parent, depth) = if started {
                let Some(Reverse(entry)) = open.pop() else {
                    exhausted = true;
                    break;
                };
                let (e, k) = unpack_open(entry);
                let x = &mut expansions[e];
                if k + 1 < x.len {
                    if !x.sorted {
                        // Its second candidate is asked for: the rest is sorted now (most
                        // expansions of a clear descent give up their best alone).
                        pending[x.first + 1..x.first + x.len].sort_by(|a, b| a.0.total_cmp(&b.0));
                        x.sorted = true;
                    }
                    let (v, _) = pending[x.first + k + 1];
                    open.push(Reverse(pack_open(v, e, k + 1)));
                }
                (pending[x.first + k].1, x.parent, nodes[x.parent].depth + 1)
            } else {
                (start, usize::MAX, 0)
            };
            started = true;
            if opened.contains(&key(here)) {
                continue;
            }
            // Lazy: a candidate's pose is checked when it comes off the list, so a clear
            // descent checks one pose per step rather than all 26. The start needs no check.
            if parent != usize::MAX {
                if self.max_checks > 0 && checks == self.max_checks {
                    break;
                }
                let stalled = self.near_stall > 0
                    && nearest.0 <= 2.0 * s
                    && checks - nearer_at >= self.near_stall;
                if stalled {
                    break;
                }
                checks += 1;
                if !filter.keep_one(depth - 1, nodes[parent].at, here)? {
                    continue;
                }
            }
            opened.insert(key(here));
            nodes.push(Node {
                at: here,
                parent,
                depth,
            });
            let n = nodes.len() - 1;
            let d = distance(here, goal);
            if d < nearest.0 {
                nearest = (d, n);
                nearer_at = checks;
            }
            if d <= self.tolerance {
                end = Some(n);
                break;
            }
            if d <= s && filter.keep_one(depth, here, goal)? {
                nodes.push(Node {
                    at: goal,
                    parent: n,
                    depth: depth + 1,
                });
                end = Some(nodes.len() - 1);
                break;
            }
            if expanded == self.max_steps {
                break;
            }
            expanded += 1;
            for (c, v) in candidates.iter_mut().zip(&dirs) {
                *c = [here[0] + s * v[0], here[1] + s * v[1], here[2] + s * v[2]];
            }
            let values = values_or_infinity(field, &candidates);
            let first = pending.len();
            // Whether a candidate was opened already is asked when it comes off the list: most
            // never do.
            pending.extend(
                candidates
                    .iter()
                    .zip(values)
                    .filter(|&(_, v)| v.is_finite())
                    .map(|(&c, v)| (v, c)),
            );
            let len = pending.len() - first;
            if len > 0 {
                // The best candidate first (the first of the least values, where a stable sort
                // puts it), the rest in the directions' order until one of them is asked for,
                // then sorted stably: the order a stable sort of them all gives.
                let best = (first..pending.len())
                    .min_by(|&a, &b| pending[a].0.total_cmp(&pending[b].0))
                    .expect("a candidate");
                pending[first..=best].rotate_right(1);
                open.push(Reverse(pack_open(pending[first].0, expansions.len(), 0)));
                expansions.push(Expansion {
                    parent: n,
                    first,
                    len,
                    sorted: len <= 2,
                });
            }
        }
        let mut chain = Vec::new();
        let mut at = end.unwrap_or(nearest.1);
        while at != usize::MAX {
            chain.push(nodes[at].at);
            at = nodes[at].parent;
        }
        chain.reverse();
        Ok(Path3 {
            exhausted,
            ..Path3::ending(chain, goal, self.tolerance)
        })
    }

    /// [`FieldSearch3::search`] under `filter`; where that does not reach the goal, again
    /// under `fallback` (a looser filter, such as the accessible region alone), so a route is
    /// found wherever the looser filter has one. Either path is then straightened by
    /// [`FieldSearch3::shortcut`] under `filter`. `relaxed` says whether the fallback was
    /// taken, `exhausted` whether the strict search opened every point it allows.
    ///
    /// # Errors
    /// As [`FieldSearch3::search`].
    pub fn search_relaxed<F, S, L>(
        &self,
        field: &F,
        filter: &S,
        fallback: &L,
        start: Point3m,
        goal: Point3m,
    ) -> Result<Path3>
    where
        F: ContinuousField3 + ?Sized,
        S: StepFilter + ?Sized,
        L: StepFilter + ?Sized,
    {
        let strict = self.search(field, filter, start, goal)?;
        if strict.reached {
            return self.shortcut(filter, &strict, goal);
        }
        let loose = self.search(field, fallback, start, goal)?;
        let path = Path3 {
            relaxed: true,
            exhausted: strict.exhausted,
            ..loose
        };
        self.shortcut(filter, &path, goal)
    }

    /// Shortens `path` by straight cuts the filter allows (path optimisation after the
    /// search): from each kept point, the farthest later point of `path` (of 16 tried, evenly
    /// spaced) whose straight segment, walked in equal steps no longer than [`FieldSearch3::step`], passes `filter`
    /// at every step (with the steps' indices along the new path, so a gait keeps its
    /// rhythm), is joined to it. Where no cut from a point passes, the path's next point is
    /// kept as it is. The ends stay. A path that is not `relaxed` (every step passed the
    /// filter) comes back unchanged if a kept step fails under its new index, so the cut
    /// never makes its poses worse.
    ///
    /// # Errors
    /// [`PlanError::Invalid`] for a step that is not positive; errors of the filter.
    pub fn shortcut<S>(&self, filter: &S, path: &Path3, goal: Point3m) -> Result<Path3>
    where
        S: StepFilter + ?Sized,
    {
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err(PlanError::Invalid(format!(
                "shortcut: a positive step (got {})",
                self.step
            )));
        }
        let pts = &path.points;
        if pts.len() < 3 {
            return Ok(path.clone());
        }
        let mut out = vec![pts[0]];
        let mut i = 0;
        while i + 1 < pts.len() {
            let mut joined = false;
            // At most 16 cuts tried from each point (every stride-th later point, the
            // farthest first), so a long path costs O(length) checks per kept point.
            let stride = (pts.len() - 1 - i).div_ceil(16);
            let tries = (i + 1..pts.len())
                .rev()
                .step_by(stride)
                .chain(((pts.len() - 2 - i) % stride != 0).then_some(i + 1));
            for j in tries {
                if let Some(steps) = self.straight_steps(filter, &out, pts[j])? {
                    out.extend(steps);
                    i = j;
                    joined = true;
                    break;
                }
            }
            if !joined {
                if !path.relaxed {
                    return Ok(path.clone());
                }
                out.push(pts[i + 1]);
                i += 1;
            }
        }
        Ok(Path3 {
            exhausted: path.exhausted,
            relaxed: path.relaxed,
            ..Path3::ending(out, goal, self.tolerance)
        })
    }

    /// The steps from the last point of `so_far` to `to` along the straight line, or `None`
    /// when one fails `filter`.
    fn straight_steps<S>(
        &self,
        filter: &S,
        so_far: &[Point3m],
        to: Point3m,
    ) -> Result<Option<Vec<Point3m>>>
    where
        S: StepFilter + ?Sized,
    {
        let from = *so_far.last().expect("a start");
        let n = (distance(from, to) / self.step).ceil().max(1.0) as usize;
        let steps: Vec<Point3m> = (1..=n)
            .map(|k| {
                let t = k as f32 / n as f32;
                std::array::from_fn(|a| from[a] + t * (to[a] - from[a]))
            })
            .collect();
        // The cheap test of every step first: a cut that leaves the free space far along
        // costs no pose before it.
        if !steps.iter().all(|&p| filter.may_keep(p)) {
            return Ok(None);
        }
        let mut prev = from;
        for (k, &p) in steps.iter().enumerate() {
            if !filter.keep_one(so_far.len() - 1 + k, prev, p)? {
                return Ok(None);
            }
            prev = p;
        }
        Ok(Some(steps))
    }
}

/// The lattice cell of `p` at spacing `cell` (rounded to the nearest), its three indices
/// packed in 21 bits each: cells 2^21 apart on an axis (kilometres at any step a body takes)
/// would share a key.
fn lattice_key(p: Point3m, cell: f32) -> u64 {
    // Half away from zero, as f32::round, without a call into libm.
    let index = |v: f32| {
        let x = v / cell;
        (x + 0.5f32.copysign(x)) as i64 as u64 & 0x1F_FFFF
    };
    (index(p[0]) << 42) | (index(p[1]) << 21) | index(p[2])
}

/// A point the search opened.
#[derive(Clone, Copy, Debug)]
struct Node {
    at: Point3m,
    parent: usize,
    depth: usize,
}

/// One expansion's candidates: `pending[first..first + len]`, from the opened point `parent`.
#[derive(Clone, Copy, Debug)]
struct Expansion {
    parent: usize,
    first: usize,
    len: usize,
    /// Whether `pending[first + 1..first + len]` is sorted yet (the best is first always).
    sorted: bool,
}

/// An open-list entry: `value` in `f32::total_cmp`'s order (its bits, the sign bit flipped
/// for positives and every bit for negatives), then the expansion `e` and its candidate `k`,
/// in one word ordered as the triple.
fn pack_open(value: f32, e: usize, k: usize) -> u128 {
    let bits = value.to_bits();
    let ordered = if bits >> 31 == 1 {
        !bits
    } else {
        bits | 0x8000_0000
    };
    (u128::from(ordered) << 96) | ((e as u128) << 32) | k as u128
}

/// The expansion and candidate of an open-list entry ([`pack_open`]).
fn unpack_open(entry: u128) -> (usize, usize) {
    (
        (entry >> 32) as u64 as usize,
        (entry & 0xFFFF_FFFF) as usize,
    )
}

/// The field at every candidate in one call; a batch that fails (a point outside the field's
/// box) is asked point by point, and the failing points are infinite.
fn values_or_infinity<F: ContinuousField3 + ?Sized>(field: &F, points: &[Point3m]) -> Vec<f32> {
    match field.values(points) {
        Ok(v) => v,
        Err(_) => points
            .iter()
            .map(|&p| field.value(p).unwrap_or(f32::INFINITY))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::super::{straight_line, AnyStep};
    use super::*;

    /// A search of step `step` and `max_steps` expansions, 2 cm from its goal, no other limit.
    fn settings(step: f32, max_steps: usize) -> FieldSearch3 {
        FieldSearch3 {
            step,
            tolerance: 0.02,
            max_steps,
            max_checks: 0,
            near_stall: 0,
        }
    }

    /// The distance to a goal point in open space.
    struct Cone(Point3m);

    impl ContinuousField3 for Cone {
        fn value(&self, p: Point3m) -> envfield_grid::Result<f32> {
            Ok(distance(p, self.0))
        }
        fn gradient(&self, _: Point3m) -> envfield_grid::Result<Option<Point3m>> {
            Ok(None)
        }
    }

    /// No candidate with z below 0.5 (a floor the torso must stay above).
    struct Above(f32);

    impl StepFilter for Above {
        fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
            Ok(c.iter().map(|p| p[2] >= self.0).collect())
        }
    }

    /// A walled-in start: the search opens every point of the box and says so.
    #[test]
    fn a_start_walled_in_by_the_filter_exhausts_the_search() {
        struct Cube;
        impl StepFilter for Cube {
            fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
                Ok(c.iter().map(|p| p.iter().all(|v| v.abs() <= 0.3)).collect())
            }
        }
        let goal = [1.0, 0.0, 0.0];
        let search = settings(0.1, 100_000);
        let path = search.search(&Cone(goal), &Cube, [0.0; 3], goal).unwrap();
        assert!(!path.reached && path.exhausted, "{path:?}");
        assert!((path.final_distance - 0.7).abs() < 0.05, "{path:?}");
        let open = search
            .search(&Cone(goal), &AnyStep, [0.0; 3], goal)
            .unwrap();
        assert!(open.reached && !open.exhausted);
    }

    #[test]
    fn the_search_walks_a_cone_to_its_goal_near_the_straight_line() {
        let goal = [2.0, 1.0, 1.0];
        let search = settings(0.1, 200);
        let path = search
            .search(&Cone(goal), &AnyStep, [0.0, 0.0, 1.0], goal)
            .unwrap();
        assert!(path.reached, "{path:?}");
        assert!(distance(*path.points.last().unwrap(), goal) <= 0.02);
        let straight = distance([0.0, 0.0, 1.0], goal);
        assert!(
            path.length() < 1.1 * straight,
            "{} against {straight}",
            path.length()
        );
        // Every step is s long but the last.
        for w in path.points[..path.points.len() - 1].windows(2) {
            assert!((distance(w[0], w[1]) - 0.1).abs() < 1e-5);
        }
    }

    #[test]
    fn the_filter_is_obeyed_and_a_dead_end_stops_the_walk() {
        let goal = [1.0, 0.0, 0.0];
        let search = settings(0.1, 100);
        let path = search
            .search(&Cone(goal), &Above(0.5), [0.0, 0.0, 1.0], goal)
            .unwrap();
        assert!(!path.reached);
        assert!(
            !path.exhausted,
            "the half-space above z = 0.5 has points left to open"
        );
        assert!(path.points.iter().all(|p| p[2] >= 0.5 - 1e-6));
        assert!(path.final_distance > 0.4);
        let bad = FieldSearch3 {
            step: 0.0,
            ..search
        };
        let e = bad
            .search(&Cone(goal), &AnyStep, [0.0; 3], goal)
            .unwrap_err()
            .to_string();
        assert!(e.contains("step length 0"), "{e}");
        assert!(search
            .search(&Cone(goal), &AnyStep, [f32::NAN, 0.0, 0.0], goal)
            .is_err());
    }

    /// A box across the straight line: the search walks round it; the shortcut keeps every
    /// step allowed, keeps the ends and comes close to the shortest way round (1.2 m).
    #[test]
    fn the_shortcut_straightens_a_detour_and_keeps_every_step_allowed() {
        struct Outside;
        impl StepFilter for Outside {
            fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
                Ok(c.iter()
                    .map(|p| !((p[0] - 0.5).abs() < 0.1 && p[1].abs() < 0.3))
                    .collect())
            }
        }
        let (start, goal) = ([0.0, 0.0, 1.0], [1.0, 0.0, 1.0]);
        let search = settings(0.05, 10_000);
        let raw = search.search(&Cone(goal), &Outside, start, goal).unwrap();
        assert!(raw.reached, "{raw:?}");
        let cut = search.shortcut(&Outside, &raw, goal).unwrap();
        assert!(cut.reached);
        assert_eq!(cut.points[0], start);
        assert_eq!(*cut.points.last().unwrap(), *raw.points.last().unwrap());
        for (k, w) in cut.points.windows(2).enumerate() {
            assert!(
                Outside.keep(k, w[0], &[w[1]]).unwrap()[0],
                "step {k}: {w:?}"
            );
            assert!(distance(w[0], w[1]) <= 0.05 + 1e-5);
        }
        assert!(
            cut.length() < raw.length() && cut.length() < 1.25,
            "raw {} cut {}",
            raw.length(),
            cut.length()
        );
        // Nothing to cut on a straight walk.
        let open = search.search(&Cone(goal), &AnyStep, start, goal).unwrap();
        let same = search.shortcut(&AnyStep, &open, goal).unwrap();
        assert!((same.length() - open.length()).abs() < 1e-4);
    }

    /// A start walled in by the strict filter: the relaxed search takes the looser one and
    /// says so; where the strict filter has a route, it is the strict path, cut straight.
    #[test]
    fn the_relaxed_search_leaves_a_pocket_the_strict_filter_cannot() {
        struct Pocket;
        impl StepFilter for Pocket {
            fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
                // A shell at 0.3 m round the origin that the strict filter never allows.
                Ok(c.iter()
                    .map(|&p| (distance(p, [0.0; 3]) - 0.3).abs() > 0.1)
                    .collect())
            }
        }
        let goal = [1.0, 0.0, 0.0];
        let search = settings(0.1, 5_000);
        let strict = search.search(&Cone(goal), &Pocket, [0.0; 3], goal).unwrap();
        assert!(!strict.reached);
        let path = search
            .search_relaxed(&Cone(goal), &Pocket, &AnyStep, [0.0; 3], goal)
            .unwrap();
        assert!(path.reached && path.relaxed && path.exhausted, "{path:?}");
        assert!(path.length() < 1.1, "{}", path.length());
        // Outside the shell the strict filter has its way.
        let start = [0.0, 0.8, 0.0];
        let free = search
            .search_relaxed(&Cone(goal), &Pocket, &AnyStep, start, goal)
            .unwrap();
        assert!(free.reached && !free.relaxed);
        for (k, w) in free.points.windows(2).enumerate() {
            assert!(Pocket.keep(k, w[0], &[w[1]]).unwrap()[0]);
        }
    }

    /// A goal the filter never lets a step land on, in open space: without a limit the search
    /// spends its whole budget of checks on the space round it; with `near_stall` it ends
    /// that many checks after it last came nearer, close to the goal.
    #[test]
    fn a_goal_no_step_lands_on_ends_the_search_near_it() {
        struct Barred(std::cell::Cell<usize>);
        impl StepFilter for Barred {
            fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
                self.0.set(self.0.get() + c.len());
                // Nothing within 3 cm of the goal.
                Ok(c.iter()
                    .map(|&p| distance(p, [1.0, 0.0, 0.0]) > 0.03)
                    .collect())
            }
        }
        let goal = [1.0, 0.0, 0.0];
        let search = FieldSearch3 {
            max_checks: 5_000,
            ..settings(0.05, 100_000)
        };
        let calls = |near_stall: usize| {
            let filter = Barred(Default::default());
            let s = FieldSearch3 {
                near_stall,
                ..search
            };
            let path = s.search(&Cone(goal), &filter, [0.0; 3], goal).unwrap();
            assert!(!path.reached && !path.exhausted, "{path:?}");
            assert!(path.final_distance < 0.1, "{path:?}");
            filter.0.get()
        };
        // The landing tries count too: a few more calls than the budget's checks.
        let (all, limited) = (calls(0), calls(100));
        assert!(all >= 5_000, "{all}");
        assert!(limited < 1_000, "{limited}");
        // Where the goal is reached, the limit changes nothing.
        let open = FieldSearch3 {
            near_stall: 100,
            ..search
        };
        let path = open.search(&Cone(goal), &AnyStep, [0.0; 3], goal).unwrap();
        assert!(path.reached);
    }

    /// Where every candidate ties (a flat field), the search takes them in the directions'
    /// order, the oldest expansion's first: the start's 26 candidates are checked before any
    /// of its children's.
    #[test]
    fn tied_candidates_come_off_in_the_directions_order() {
        struct Flat;
        impl ContinuousField3 for Flat {
            fn value(&self, _: Point3m) -> envfield_grid::Result<f32> {
                Ok(1.0)
            }
            fn gradient(&self, _: Point3m) -> envfield_grid::Result<Option<Point3m>> {
                Ok(None)
            }
        }
        struct Record(std::cell::RefCell<Vec<Point3m>>);
        impl StepFilter for Record {
            fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
                self.0.borrow_mut().extend_from_slice(c);
                Ok(vec![true; c.len()])
            }
        }
        let search = settings(0.1, 40);
        let record = Record(Default::default());
        search
            .search(&Flat, &record, [0.0; 3], [5.0, 0.0, 0.0])
            .unwrap();
        let checked = record.0.into_inner();
        assert!(checked.len() > 26);
        for (k, d) in directions26().iter().enumerate() {
            let want = d.map(|v| 0.1 * v);
            assert!(distance(checked[k], want) < 1e-6, "{k}: {:?}", checked[k]);
        }
    }

    /// The open list's packed entries order as the (value by `total_cmp`, expansion,
    /// candidate) triples they pack, negative values, zeros and infinities included.
    #[test]
    fn open_entries_order_as_their_triples() {
        let values = [
            f32::NEG_INFINITY,
            -3.5,
            -1e-30,
            -0.0,
            0.0,
            1e-30,
            0.25,
            0.2500001,
            7.0,
            f32::INFINITY,
        ];
        let mut triples = Vec::new();
        for &v in &values {
            for e in [0usize, 1, 70_000, 1 << 40] {
                for k in [0usize, 1, 25] {
                    triples.push((v, e, k));
                }
            }
        }
        for &a in &triples {
            for &b in &triples {
                let want = a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2));
                let (pa, pb) = (pack_open(a.0, a.1, a.2), pack_open(b.0, b.1, b.2));
                assert_eq!(pa.cmp(&pb), want, "{a:?} {b:?}");
            }
            assert_eq!(unpack_open(pack_open(a.0, a.1, a.2)), (a.1, a.2));
        }
    }

    /// The packed key is the rounded lattice cell: equal within a cell, apart across cells,
    /// on both sides of zero.
    #[test]
    fn lattice_keys_round_to_the_nearest_cell() {
        let k = |x: f32, y: f32, z: f32| lattice_key([x, y, z], 0.02);
        assert_eq!(k(0.0, 0.0, 0.0), k(0.009, -0.009, 0.0));
        assert_ne!(k(0.0, 0.0, 0.0), k(0.011, 0.0, 0.0));
        assert_ne!(k(-0.011, 0.0, 0.0), k(0.011, 0.0, 0.0));
        assert_eq!(k(-1.0, 2.0, -3.0), k(-1.005, 2.005, -2.995));
        let mut keys: Vec<u64> = (-30..30)
            .flat_map(|i| (-3..3).map(move |j| k(0.02 * i as f32, 0.02 * j as f32, 1.0)))
            .collect();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), 60 * 6);
    }

    #[test]
    fn the_straight_line_ends_on_the_goal() {
        let line = straight_line([0.0; 3], [1.0, 0.0, 0.0], 0.3).unwrap();
        assert_eq!(line.len(), 5);
        assert_eq!(*line.last().unwrap(), [1.0, 0.0, 0.0]);
        assert!(straight_line([0.0; 3], [1.0; 3], 0.0).is_err());
    }
}
