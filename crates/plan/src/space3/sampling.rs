//! The sampling-based baselines of the 3D tables (paper Table 3, appendix "Path planning by RRT
//! and PRM"): RRT (LaValle 1998), RRT* (Karaman and Frazzoli 2011) and PRM (Kavraki et al.
//! 1996), on any [`Space3`] (the accessible region and its collision test). Nearest
//! neighbours come from a k-d tree (`kiddo`), PRM's shortest path from `pathfinding`'s
//! Dijkstra.

use super::{distance, Path3};
use crate::{PlanError, Result};
use envfield_grid::{Point3m, SplitMix64};
use kiddo::{KdTree, SquaredEuclidean};
use serde::{Deserialize, Serialize};

/// Where a torso may be, and how to draw a random such place.
pub trait Space3 {
    /// Whether a torso at `p` is allowed.
    fn is_free(&self, p: Point3m) -> bool;

    /// A random allowed point.
    fn sample(&self, rng: &mut SplitMix64) -> Point3m;
}

/// Whether the segment `a`-`b` is free, checked at points at most `resolution` apart (both
/// ends included).
pub fn edge_free<S: Space3 + ?Sized>(space: &S, a: Point3m, b: Point3m, resolution: f32) -> bool {
    let n = (distance(a, b) / resolution).ceil().max(1.0) as usize;
    (0..=n).all(|i| {
        let t = i as f32 / n as f32;
        space.is_free(std::array::from_fn(|k| a[k] + t * (b[k] - a[k])))
    })
}

/// The baselines' settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SamplingConfig {
    /// RRT and RRT*: iterations; PRM: roadmap samples (the paper: 500 for both).
    pub budget: usize,
    /// RRT and RRT*: the extension step, metres (the pose sequence's step length).
    pub step: f32,
    /// RRT and RRT*: the chance of sampling the goal itself.
    pub goal_bias: f32,
    /// PRM: nearest neighbours each node tries to connect to (the paper: 5). RRT*: the
    /// rewiring neighbourhood is `neighbours` times the step (at least 2).
    pub neighbours: usize,
    /// Edges are checked at points this far apart, metres.
    pub edge_resolution: f32,
    /// The goal counts as reached within this distance, metres.
    pub tolerance: f32,
    /// Seed of the samples.
    pub seed: u64,
}

impl Default for SamplingConfig {
    fn default() -> Self {
        Self {
            budget: 500,
            step: 0.1,
            goal_bias: 0.1,
            neighbours: 5,
            edge_resolution: 0.05,
            tolerance: 0.02,
            seed: 0,
        }
    }
}

impl SamplingConfig {
    fn validate(&self, start: Point3m, goal: Point3m) -> Result<()> {
        let positive = |v: f32| v.is_finite() && v > 0.0;
        let ok = self.budget > 0
            && positive(self.step)
            && positive(self.edge_resolution)
            && (0.0..=1.0).contains(&self.goal_bias)
            && self.neighbours > 0
            && self.tolerance.is_finite()
            && self.tolerance >= 0.0;
        if !ok {
            return Err(PlanError::Invalid(format!(
                "sampling planner: budget >= 1, positive step and edge resolution, goal bias in \
                 [0, 1], neighbours >= 1 (got {self:?})"
            )));
        }
        if !start.iter().chain(&goal).all(|v| v.is_finite()) {
            return Err(PlanError::Invalid(format!(
                "sampling planner: start {start:?} and goal {goal:?} must be finite"
            )));
        }
        Ok(())
    }
}

fn check_ends<S: Space3 + ?Sized>(space: &S, start: Point3m, goal: Point3m) -> Result<()> {
    for (what, p) in [("start", start), ("goal", goal)] {
        if !space.is_free(p) {
            return Err(PlanError::Invalid(format!(
                "the {what} {p:?} is outside the free space"
            )));
        }
    }
    Ok(())
}

/// A tree of points with parents and path costs, and a k-d tree over them.
struct Tree {
    points: Vec<Point3m>,
    parent: Vec<usize>,
    cost: Vec<f32>,
    index: KdTree<f32, 3>,
}

impl Tree {
    fn new(root: Point3m) -> Self {
        let mut index = KdTree::new();
        index.add(&root, 0);
        Self {
            points: vec![root],
            parent: vec![usize::MAX],
            cost: vec![0.0],
            index,
        }
    }

    fn add(&mut self, p: Point3m, parent: usize) -> usize {
        let id = self.points.len();
        self.points.push(p);
        self.parent.push(parent);
        self.cost
            .push(self.cost[parent] + distance(self.points[parent], p));
        self.index.add(&p, id as u64);
        id
    }

    fn nearest(&self, p: Point3m) -> usize {
        self.index.nearest_one::<SquaredEuclidean>(&p).item as usize
    }

    fn path_to(&self, mut node: usize) -> Vec<Point3m> {
        let mut out = Vec::new();
        while node != usize::MAX {
            out.push(self.points[node]);
            node = self.parent[node];
        }
        out.reverse();
        out
    }

    /// Whether `ancestor` lies on the path from `node` to the root.
    fn descends_from(&self, mut node: usize, ancestor: usize) -> bool {
        while node != usize::MAX {
            if node == ancestor {
                return true;
            }
            node = self.parent[node];
        }
        false
    }

    /// The node closest to `goal`: where a failed search ends.
    fn closest_to(&self, goal: Point3m) -> usize {
        self.nearest(goal)
    }
}

/// One RRT extension: from the tree node nearest `target`, a step of at most `step` towards
/// it. `None` when the new point or its edge is not free.
fn steer<S: Space3 + ?Sized>(
    space: &S,
    tree: &Tree,
    target: Point3m,
    cfg: &SamplingConfig,
) -> Option<(usize, Point3m)> {
    let near = tree.nearest(target);
    let from = tree.points[near];
    let d = distance(from, target);
    if d < 1e-6 {
        return None;
    }
    let t = (cfg.step / d).min(1.0);
    let new: Point3m = std::array::from_fn(|k| from[k] + t * (target[k] - from[k]));
    (space.is_free(new) && edge_free(space, from, new, cfg.edge_resolution)).then_some((near, new))
}

fn draw<S: Space3 + ?Sized>(
    space: &S,
    goal: Point3m,
    cfg: &SamplingConfig,
    rng: &mut SplitMix64,
) -> Point3m {
    if rng.next_f32() < cfg.goal_bias {
        goal
    } else {
        space.sample(rng)
    }
}

/// RRT: grow a tree from the start by steps of `step` towards random free points (the goal
/// itself with `goal_bias`) for at most `budget` iterations, and stop when a node within a
/// step of the goal connects to it by a free edge. A search that runs out ends at the node
/// nearest the goal (`reached` false).
///
/// # Errors
/// [`PlanError::Invalid`] for bad settings or a start or goal outside the free space.
pub fn rrt<S: Space3 + ?Sized>(
    space: &S,
    start: Point3m,
    goal: Point3m,
    cfg: &SamplingConfig,
) -> Result<Path3> {
    cfg.validate(start, goal)?;
    check_ends(space, start, goal)?;
    let mut rng = SplitMix64::new(cfg.seed ^ 0x05EE_DA11);
    let mut tree = Tree::new(start);
    if distance(start, goal) <= cfg.step && edge_free(space, start, goal, cfg.edge_resolution) {
        return Ok(Path3::ending(vec![start, goal], goal, cfg.tolerance));
    }
    for _ in 0..cfg.budget {
        let target = draw(space, goal, cfg, &mut rng);
        let Some((near, new)) = steer(space, &tree, target, cfg) else {
            continue;
        };
        let id = tree.add(new, near);
        if distance(new, goal) <= cfg.step && edge_free(space, new, goal, cfg.edge_resolution) {
            let g = tree.add(goal, id);
            return Ok(Path3::ending(tree.path_to(g), goal, cfg.tolerance));
        }
    }
    let last = tree.closest_to(goal);
    Ok(Path3::ending(tree.path_to(last), goal, cfg.tolerance))
}

/// RRT*: RRT whose new nodes take the cheapest parent among the tree's nodes within
/// `neighbours x step` (at least two steps) and rewire those neighbours through themselves
/// when that is shorter; it runs all `budget` iterations and returns the cheapest connection
/// to the goal found (or, failing one, the node nearest the goal).
///
/// # Errors
/// As [`rrt`].
pub fn rrt_star<S: Space3 + ?Sized>(
    space: &S,
    start: Point3m,
    goal: Point3m,
    cfg: &SamplingConfig,
) -> Result<Path3> {
    cfg.validate(start, goal)?;
    check_ends(space, start, goal)?;
    let mut rng = SplitMix64::new(cfg.seed ^ 0x05EE_DA12);
    let mut tree = Tree::new(start);
    let radius = cfg.step * (cfg.neighbours.max(2) as f32);
    let mut best_goal: Option<(f32, usize)> = None;
    let connect = |tree: &Tree, id: usize, best: &mut Option<(f32, usize)>| {
        let p = tree.points[id];
        if distance(p, goal) <= cfg.step && edge_free(space, p, goal, cfg.edge_resolution) {
            let c = tree.cost[id] + distance(p, goal);
            if best.is_none_or(|(b, _)| c < b) {
                *best = Some((c, id));
            }
        }
    };
    connect(&tree, 0, &mut best_goal);
    for _ in 0..cfg.budget {
        let target = draw(space, goal, cfg, &mut rng);
        let Some((near, new)) = steer(space, &tree, target, cfg) else {
            continue;
        };
        let around: Vec<usize> = tree
            .index
            .within::<SquaredEuclidean>(&new, radius * radius)
            .iter()
            .map(|n| n.item as usize)
            .collect();
        // The cheapest parent in reach.
        let mut parent = near;
        let mut cost = tree.cost[near] + distance(tree.points[near], new);
        for &j in &around {
            let c = tree.cost[j] + distance(tree.points[j], new);
            if c < cost && edge_free(space, tree.points[j], new, cfg.edge_resolution) {
                (parent, cost) = (j, c);
            }
        }
        let id = tree.add(new, parent);
        // Rewire: neighbours reached more cheaply through the new node. The descendants of a
        // rewired node keep their older, higher costs until they are rewired themselves (a
        // common simplification: it costs some optimality, never validity), so a node is
        // never made the child of its own descendant.
        for &j in &around {
            let c = cost + distance(new, tree.points[j]);
            if j != parent
                && c < tree.cost[j]
                && !tree.descends_from(id, j)
                && edge_free(space, new, tree.points[j], cfg.edge_resolution)
            {
                tree.parent[j] = id;
                tree.cost[j] = c;
            }
        }
        connect(&tree, id, &mut best_goal);
    }
    // The path's length is measured afresh from its points (costs below rewired nodes are
    // stale).
    let end = match best_goal {
        Some((_, id)) => {
            let mut path = tree.path_to(id);
            path.push(goal);
            path
        }
        None => tree.path_to(tree.closest_to(goal)),
    };
    Ok(Path3::ending(end, goal, cfg.tolerance))
}

/// PRM: `budget` random free points plus the start and the goal; each connects to its
/// `neighbours` nearest by free edges; Dijkstra from the start to the goal on that roadmap
/// (the roadmap's construction is part of the call, as in the paper's timing). No path: the
/// start alone (`reached` false).
///
/// # Errors
/// As [`rrt`].
pub fn prm<S: Space3 + ?Sized>(
    space: &S,
    start: Point3m,
    goal: Point3m,
    cfg: &SamplingConfig,
) -> Result<Path3> {
    cfg.validate(start, goal)?;
    check_ends(space, start, goal)?;
    let mut rng = SplitMix64::new(cfg.seed ^ 0x05EE_DA13);
    let mut nodes = vec![start, goal];
    nodes.extend((0..cfg.budget).map(|_| space.sample(&mut rng)));
    let mut index: KdTree<f32, 3> = KdTree::new();
    for (i, p) in nodes.iter().enumerate() {
        index.add(p, i as u64);
    }
    // Undirected edges, weights in micrometres (Dijkstra needs an ordered cost).
    let mut adjacent: Vec<Vec<(usize, u64)>> = vec![Vec::new(); nodes.len()];
    for (i, p) in nodes.iter().enumerate() {
        for n in index.nearest_n::<SquaredEuclidean>(p, cfg.neighbours + 1) {
            let j = n.item as usize;
            if j == i || adjacent[i].iter().any(|&(k, _)| k == j) {
                continue;
            }
            if edge_free(space, *p, nodes[j], cfg.edge_resolution) {
                let w = (distance(*p, nodes[j]) * 1e6) as u64;
                adjacent[i].push((j, w));
                adjacent[j].push((i, w));
            }
        }
    }
    let found = pathfinding::prelude::dijkstra(&0usize, |&i| adjacent[i].clone(), |&i| i == 1);
    let points = match found {
        Some((ids, _)) => ids.into_iter().map(|i| nodes[i]).collect(),
        None => vec![start],
    };
    Ok(Path3::ending(points, goal, cfg.tolerance))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 x 2 x 1 box with a wall at x in [1.9, 2.1] open only for y > 1.5.
    struct Walled;

    impl Space3 for Walled {
        fn is_free(&self, p: Point3m) -> bool {
            let inside = (0.0..=4.0).contains(&p[0])
                && (0.0..=2.0).contains(&p[1])
                && (0.0..=1.0).contains(&p[2]);
            let wall = (1.9..=2.1).contains(&p[0]) && p[1] < 1.5;
            inside && !wall
        }
        fn sample(&self, rng: &mut SplitMix64) -> Point3m {
            loop {
                let p = [4.0 * rng.next_f32(), 2.0 * rng.next_f32(), rng.next_f32()];
                if self.is_free(p) {
                    return p;
                }
            }
        }
    }

    fn every_edge_free(path: &Path3) -> bool {
        path.points
            .windows(2)
            .all(|w| edge_free(&Walled, w[0], w[1], 0.01))
    }

    #[test]
    fn all_three_go_around_the_wall() {
        let (start, goal) = ([0.5, 0.5, 0.5], [3.5, 0.5, 0.5]);
        let cfg = SamplingConfig {
            budget: 3000,
            step: 0.2,
            ..SamplingConfig::default()
        };
        for (name, path) in [
            ("rrt", rrt(&Walled, start, goal, &cfg).unwrap()),
            ("rrt*", rrt_star(&Walled, start, goal, &cfg).unwrap()),
            (
                "prm",
                prm(&Walled, start, goal, &SamplingConfig { budget: 500, ..cfg }).unwrap(),
            ),
        ] {
            assert!(path.reached, "{name}: {path:?}");
            assert!(every_edge_free(&path), "{name} crosses the wall");
            // Around the wall's end at y = 1.5: at least 2 x 1.72 + 0.2 = 3.64.
            assert!(path.length() > 3.6, "{name}: {}", path.length());
        }
        // RRT* is no longer than RRT on the same seed and budget.
        let a = rrt(&Walled, start, goal, &cfg).unwrap().length();
        let b = rrt_star(&Walled, start, goal, &cfg).unwrap().length();
        assert!(b <= a, "rrt* {b} against rrt {a}");
    }

    #[test]
    fn ends_outside_the_space_and_bad_settings_are_refused() {
        let cfg = SamplingConfig::default();
        let e = rrt(&Walled, [2.0, 0.5, 0.5], [3.5, 0.5, 0.5], &cfg)
            .unwrap_err()
            .to_string();
        assert!(e.contains("start"), "{e}");
        assert!(prm(&Walled, [0.5, 0.5, 0.5], [9.0, 0.5, 0.5], &cfg).is_err());
        let bad = SamplingConfig { budget: 0, ..cfg };
        assert!(rrt_star(&Walled, [0.5; 3], [3.5, 0.5, 0.5], &bad).is_err());
    }
}
