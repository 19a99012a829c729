//! A search over the whole crowd's configurations whose successors PIBT generates (LaCAM,
//! Okumura 2023): [`lacam_crowd`], for the problems PIBT alone leaves short.

use super::geometry::{candidates, closest_approach, point, segment_clear, value_at};
use super::push::Pushes;
use super::{check_trips, CrowdConfig, CrowdRun, Ending, PibtCrowd, Trip};
use crate::Result;
use envfield_grid::{Field2, FieldModel, Grid2, Point2, SplitMix64};
use std::cell::RefCell;
use std::collections::{HashMap, VecDeque};
use std::rc::Rc;

/// Time steps without one more person on their goal after which [`plan_crowd`] stops
/// walking PIBT and searches.
pub const STALL: usize = 40;

/// Configurations [`lacam_crowd`] may open before it gives up.
pub const MAX_NODES: usize = 100_000;

/// Successors [`lacam_crowd`] may try (one PIBT step each, new configurations or not) before
/// it gives up: the bound on its time and memory when it keeps coming back to known ones.
pub const MAX_TRIES: usize = 1_000_000;

/// Several people planned together: a depth-first search over configurations (everyone's
/// position) in the manner of LaCAM (Okumura, "LaCAM: Search-Based Algorithm for Quick
/// Multi-Agent Pathfinding", AAAI 2023), each successor one time step of priority inheritance
/// with backtracking under the constraints the search has laid (some people's ends fixed).
/// The first successor of a configuration is PIBT's own step; when the search comes back to a
/// configuration it has seen (people walking in circles, two waiting for each other in a
/// corridor), it tries the next constraint there instead, so alternatives PIBT never takes are
/// tried in turn.
///
/// Steps are those of [`PibtCrowd`](super::PibtCrowd) (headings at the step length, half of
/// it and one cell, the goal within a step, standing still; swept steps clear of the map and,
/// in continuous time, of each other), ordered by each person's field on the empty map from
/// `model` (one batched prediction). The search ends at the first configuration with everyone
/// on their goal, or after [`MAX_NODES`] configurations or [`MAX_TRIES`] successors; then the run is the path to the
/// configuration seen with the most people on their goals (`Ending::StepBudget`). A plan
/// longer than `config.max_steps` is cut there.
///
/// ```
/// use envfield_eikonal::FastMarching;
/// use envfield_grid::{Cell2, Grid2};
/// use envfield_plan::crowd::{lacam_crowd, CrowdConfig, Ending, Trip};
///
/// // A dead-end corridor one body wide off a room: two people in it must swap ends.
/// let mut obstacles = vec![true; 20 * 40];
/// for row in 2..18 {
///     for col in 2..15 {
///         obstacles[row * 40 + col] = false; // the room
///     }
/// }
/// for col in 15..38 {
///     obstacles[10 * 40 + col] = false; // the corridor
/// }
/// let floor = Grid2::from_obstacles(20, 40, obstacles)?;
/// let trips = [
///     Trip { start: Cell2::new(10, 30), goal: Cell2::new(10, 36) },
///     Trip { start: Cell2::new(10, 36), goal: Cell2::new(10, 30) },
/// ];
/// let run = lacam_crowd(&floor, &trips, &FastMarching::default(), &CrowdConfig::default())?;
/// assert_eq!(run.ending, Ending::Arrived);
/// assert_eq!(run.person_collisions(2.5), 0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// A bad problem ([`check_trips`]); the model's errors.
pub fn lacam_crowd(
    walkable: &Grid2,
    trips: &[Trip],
    model: &impl FieldModel,
    config: &CrowdConfig,
) -> Result<CrowdRun> {
    check_trips(walkable, trips, config)?;
    let statics =
        model.predict_many(&trips.iter().map(|t| (walkable, t.goal)).collect::<Vec<_>>())?;
    let space = Space {
        walkable,
        config,
        goals: trips.iter().map(|t| point(t.goal)).collect(),
        statics: &statics,
        ends: RefCell::default(),
    };
    let n = trips.len();
    let starts: Vec<Point2> = trips.iter().map(|t| point(t.start)).collect();
    let mut links = Links::default();
    let mut nodes = vec![Node::new(starts, None, &space, None)];
    let mut seen: HashMap<Vec<u32>, usize> = HashMap::from([(key(&nodes[0].config), 0)]);
    let mut open = vec![0usize];
    let mut rng = SplitMix64::new(0x1A_CA3);
    let (mut found, mut tries) = (None, 0);
    while let Some(&top) = open.last() {
        if nodes[top].home == n {
            found = Some(top);
            break;
        }
        if nodes.len() >= MAX_NODES || tries >= MAX_TRIES {
            break;
        }
        tries += 1;
        let Some(link) = nodes[top].tree.pop_front() else {
            open.pop();
            continue;
        };
        let constraint = links.constraint(link);
        // The next people's fixed ends, to be tried later from this configuration.
        if constraint.len() < n {
            let i = nodes[top].order[constraint.len()];
            let mut ends = space.ends(i, nodes[top].config[i]).to_vec();
            for k in (1..ends.len()).rev() {
                ends.swap(k, rng.below(k + 1));
            }
            for end in ends {
                let child = links.push(link, i, end);
                nodes[top].tree.push_back(child);
            }
        }
        let Some(next) = space.step(&nodes[top].config, &nodes[top].order, &constraint) else {
            continue;
        };
        match seen.get(&key(&next)) {
            Some(&known) => open.push(known),
            None => {
                let id = nodes.len();
                seen.insert(key(&next), id);
                let node = Node::new(next, Some(top), &space, Some(&nodes[top]));
                nodes.push(node);
                open.push(id);
            }
        }
    }
    let end = found.unwrap_or_else(|| {
        (0..nodes.len())
            .max_by_key(|&k| (nodes[k].home, std::cmp::Reverse(nodes[k].depth)))
            .unwrap_or(0)
    });
    let mut chain = vec![end];
    while let Some(parent) = nodes[chain[chain.len() - 1]].parent {
        chain.push(parent);
    }
    chain.reverse();
    chain.truncate(config.max_steps + 1);
    let mut run = CrowdRun::starting(&nodes[0].config);
    run.stay_on_map = true;
    for &k in &chain[1..] {
        run.frames.push(nodes[k].config.clone());
    }
    // Each person's arrival: the first frame from which they stay on their goal.
    for i in 0..n {
        let frames = &run.frames;
        let last_off = (0..frames.len())
            .rev()
            .find(|&t| frames[t][i] != space.goals[i]);
        run.arrived_at[i] = match last_off {
            None => Some(0),
            Some(t) if t + 1 < frames.len() => Some(t + 1),
            Some(_) => None,
        };
    }
    run.finish();
    Ok(run)
}

/// Our crowd planner: PIBT over the fields' steps as people walk ([`pibt_crowd`](super::pibt_crowd)), and
/// where that stalls (no more people on their goals for [`STALL`] steps) or runs out of
/// steps, the LaCAM search ([`lacam_crowd`]) from the starts; whichever brings more people
/// home (PIBT on a tie).
///
/// ```
/// use envfield_eikonal::FastMarching;
/// use envfield_grid::{Cell2, Grid2};
/// use envfield_plan::crowd::{plan_crowd, CrowdConfig, Ending, Trip};
///
/// // Two rooms joined by a corridor one body wide: two people swap rooms through it.
/// let mut obstacles = vec![false; 30 * 41];
/// for row in 0..30 {
///     for col in 18..23 {
///         obstacles[row * 41 + col] = row != 15;
///     }
/// }
/// let floor = Grid2::from_obstacles(30, 41, obstacles)?;
/// let trips = [
///     Trip { start: Cell2::new(15, 5), goal: Cell2::new(15, 35) },
///     Trip { start: Cell2::new(15, 35), goal: Cell2::new(15, 5) },
/// ];
/// let config = CrowdConfig::default();
/// let run = plan_crowd(&floor, &trips, &FastMarching::default(), &config)?;
/// assert_eq!(run.ending, Ending::Arrived);
/// assert_eq!(run.person_collisions(config.body_radius), 0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// A bad problem ([`check_trips`]); the model's errors.
pub fn plan_crowd(
    walkable: &Grid2,
    trips: &[Trip],
    model: &impl FieldModel,
    config: &CrowdConfig,
) -> Result<CrowdRun> {
    let mut crowd = PibtCrowd::new(walkable, trips, model, config)?;
    let (mut best, mut since) = (0, 0);
    while crowd.run().steps() < config.max_steps && crowd.step()? {
        let home = crowd.run().arrived_at.iter().flatten().count();
        if home > best {
            (best, since) = (home, crowd.run().steps());
        } else if crowd.run().steps() - since >= STALL {
            break;
        }
    }
    let mut walked = crowd.into_run();
    walked.finish();
    if walked.ending == Ending::Arrived {
        return Ok(walked);
    }
    let searched = lacam_crowd(walkable, trips, model, config)?;
    let home = |run: &CrowdRun| run.arrived_at.iter().flatten().count();
    Ok(match home(&searched) > home(&walked) {
        true => searched,
        false => walked,
    })
}

/// A configuration's hash key: everyone's coordinates' bits.
fn key(config: &[Point2]) -> Vec<u32> {
    config
        .iter()
        .flat_map(|p| [p.row.to_bits(), p.col.to_bits()])
        .collect()
}

/// Some people's ends fixed, in the node's priority order.
type Constraint = Vec<(usize, Point2)>;

/// Every constraint the search has made, each one end more than its parent's (index 0: the
/// empty constraint): a node's queue holds indices, not lists.
struct Links {
    /// Parent link, person, end.
    links: Vec<(u32, u32, Point2)>,
}

impl Default for Links {
    fn default() -> Self {
        Self {
            links: vec![(0, u32::MAX, Point2::new(0.0, 0.0))],
        }
    }
}

impl Links {
    fn push(&mut self, parent: u32, person: usize, end: Point2) -> u32 {
        self.links.push((parent, person as u32, end));
        (self.links.len() - 1) as u32
    }

    /// The constraint `link` stands for, first person first.
    fn constraint(&self, mut link: u32) -> Constraint {
        let mut out = Vec::new();
        while link != 0 {
            let (parent, person, end) = self.links[link as usize];
            out.push((person as usize, end));
            link = parent;
        }
        out.reverse();
        out
    }
}

/// A configuration the search reached.
struct Node {
    config: Vec<Point2>,
    parent: Option<usize>,
    depth: usize,
    /// People on their goal.
    home: usize,
    /// Priorities: time steps off the goal (PIBT's), carried from the parent.
    priority: Vec<f32>,
    /// The people by priority, first first.
    order: Vec<usize>,
    /// Constraints still to try from here, breadth first (indices into [`Links`]).
    tree: VecDeque<u32>,
}

impl Node {
    fn new(config: Vec<Point2>, parent: Option<usize>, space: &Space, from: Option<&Node>) -> Self {
        let n = config.len();
        let priority: Vec<f32> = (0..n)
            .map(|i| {
                let base = from.map_or((i as f32 + 0.5) / n as f32, |p| p.priority[i]);
                match config[i] == space.goals[i] {
                    true => base.fract(),
                    false => base + 1.0,
                }
            })
            .collect();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| priority[b].total_cmp(&priority[a]));
        Self {
            home: (0..n).filter(|&i| config[i] == space.goals[i]).count(),
            depth: from.map_or(0, |p| p.depth + 1),
            config,
            parent,
            priority,
            order,
            tree: VecDeque::from([0]),
        }
    }
}

/// A person and the cell they stand on (its coordinates' bits).
type EndsKey = (usize, u32, u32);

/// The map, the people's goals and fields: what a step needs.
struct Space<'a> {
    walkable: &'a Grid2,
    config: &'a CrowdConfig,
    goals: Vec<Point2>,
    statics: &'a [Field2],
    /// Each person's ordered ends from each cell they have stood on.
    ends: RefCell<HashMap<EndsKey, Rc<[Point2]>>>,
}

impl Space<'_> {
    /// Person `i`'s candidate ends from `at`, best first by their field on the empty map
    /// (standing still among them); ends off the field or through furniture dropped. Worked
    /// out once per person and cell.
    fn ends(&self, i: usize, at: Point2) -> Rc<[Point2]> {
        let key = (i, at.row.to_bits(), at.col.to_bits());
        if let Some(ends) = self.ends.borrow().get(&key) {
            return ends.clone();
        }
        let ends: Rc<[Point2]> = self.work_out_ends(i, at).into();
        self.ends.borrow_mut().insert(key, ends.clone());
        ends
    }

    fn work_out_ends(&self, i: usize, at: Point2) -> Vec<Point2> {
        let goal = self.goals[i];
        // Ends on cell centres, so that configurations recur and the search sees them again.
        let step = self.config.step_length;
        let mut ends: Vec<Point2> = candidates(at, goal, step, self.config.directions)
            .into_iter()
            .map(|p| {
                let (dr, dc) = (p.row - at.row, p.col - at.col);
                let (r, c) = match dr.round().hypot(dc.round()) <= step {
                    true => (dr.round(), dc.round()),
                    false => (dr.trunc(), dc.trunc()),
                };
                Point2::new(at.row + r, at.col + c)
            })
            .collect();
        ends.push(at);
        ends.sort_by(|a, b| a.row.total_cmp(&b.row).then(a.col.total_cmp(&b.col)));
        ends.dedup();
        let value = |p: Point2| match p == goal {
            true => -1.0,
            false => value_at(&self.statics[i], p),
        };
        let mut keyed: Vec<(Point2, f32)> = ends
            .into_iter()
            .map(|p| (p, value(p)))
            .filter(|&(p, v)| v.is_finite() && segment_clear(self.walkable, at, p))
            .collect();
        keyed.sort_by(|a, b| a.1.total_cmp(&b.1));
        keyed.into_iter().map(|(p, _)| p).collect()
    }

    /// One time step from `config` under `constraint`: the constrained people's ends, then
    /// PIBT in `order` for the rest. `None` when the constrained ends clash or someone cannot
    /// stand clear of them.
    fn step(
        &self,
        config: &[Point2],
        order: &[usize],
        constraint: &Constraint,
    ) -> Option<Vec<Point2>> {
        let n = config.len();
        let disc = 2.0 * self.config.body_radius;
        let mut next: Vec<Option<Point2>> = vec![None; n];
        for &(i, end) in constraint {
            let clashes = constraint
                .iter()
                .any(|&(k, e)| k != i && closest_approach(config[i], end, config[k], e) < disc);
            if clashes {
                return None;
            }
            next[i] = Some(end);
        }
        let mut pushes = Pushes::new(config, next, disc, 64 * n);
        let mut ends = |i: usize| self.ends(i, config[i]);
        for &i in order {
            if pushes.next[i].is_none() && !pushes.choose(i, &mut ends) {
                pushes.next[i] = Some(config[i]);
            }
        }
        let next: Vec<Point2> = (0..n)
            .map(|i| pushes.next[i].unwrap_or(config[i]))
            .collect();
        // Someone who could not move may stand in a constrained step's way.
        for i in 0..n {
            for k in i + 1..n {
                if closest_approach(config[i], next[i], config[k], next[k]) < disc {
                    return None;
                }
            }
        }
        Some(next)
    }
}
