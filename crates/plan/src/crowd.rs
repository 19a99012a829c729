//! Several people walking through one floor map at once (paper section 4.1 and its Algorithm
//! 1), and the ORCA crowd loop (van den Berg et al. 2011) to set beside it.
//!
//! Everything is in cell units of the *walkable* map: the floor map with its obstacles grown by
//! the body radius, so a free cell is a place a person's centre may stand. People are discs of
//! [`CrowdConfig::body_radius`] around their centres.
//!
//! One time step of [`walk_crowd`] (Algorithm 1):
//! 1. for every person still walking, the map with the others' discs (twice the body radius
//!    around their centres) marked as obstacles, and its field for that person's goal; all of
//!    them in one [`FieldModel::predict_many`] call (one batched forward pass for a network);
//! 2. people whose goal the others cut off are *blocked*. Priority goes to the smaller
//!    remaining distance (the model's own field value; ties to the lower index). A blocked
//!    person plans again on the map with only the discs of people ahead of them in priority
//!    (a second batched call): the highest-priority person always has a way, and the others
//!    step out of it;
//! 3. in priority order, each person takes the step among 8 directions (step length, half of
//!    it, one cell) that lowers their field most, with the swept step clear of the map and,
//!    in continuous time, of every other person's motion this step. A person with no way
//!    yields: the step that most increases their distance from the nearest person ahead of
//!    them in priority. A person with no safe step waits.
//!
//! People who reach their goal leave the map (they are no longer anyone's obstacle), in both
//! loops alike.

use std::borrow::Cow;

use dodgy_2d::{Agent, AvoidanceOptions, Obstacle, Vec2};
use envfield_eikonal::{FastMarching, Order};
use envfield_grid::{Cell2, Field2, FieldModel, Grid2, Point2, SplitMix64};
use serde::{Deserialize, Serialize};

use crate::{PlanError, Result};

/// How people walk, in cells of the walkable map.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CrowdConfig {
    /// Radius of a person's disc.
    pub body_radius: f32,
    /// Length of one step (one time step).
    pub step_length: f32,
    /// Time steps before the loop gives up on the people still walking.
    pub max_steps: usize,
    /// Time steps a person held up by others (their way around them more than a step longer
    /// than the way through) waits for the way through to clear before going round.
    pub patience: usize,
    /// Headings a step may take, evenly spaced (8 in the paper: the grid's moves).
    pub directions: usize,
}

impl Default for CrowdConfig {
    /// A 0.25 m body and a 0.5 m step on a 0.1 m map, 400 steps (200 s at a step a half
    /// second).
    fn default() -> Self {
        Self {
            body_radius: 2.5,
            step_length: 5.0,
            max_steps: 400,
            patience: 3,
            directions: 8,
        }
    }
}

impl CrowdConfig {
    fn validate(&self) -> Result<()> {
        let positive = |v: f32| v.is_finite() && v > 0.0;
        if !(positive(self.body_radius) && self.step_length.is_finite() && self.step_length >= 1.0)
            || self.max_steps == 0
            || self.directions < 4
        {
            return Err(PlanError::Invalid(format!(
                "crowd config: body radius > 0, step length >= 1 cell, max_steps >= 1 and \
                 at least 4 directions (got {}, {}, {}, {})",
                self.body_radius, self.step_length, self.max_steps, self.directions
            )));
        }
        Ok(())
    }
}

/// One person's start and goal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Trip {
    /// Where the person stands at time 0.
    pub start: Cell2,
    /// Where they walk to.
    pub goal: Cell2,
}

/// What a crowd loop did: everyone's position at every time step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CrowdRun {
    /// `frames[t][i]`: person `i` at time step `t` (frame 0 holds the starts). After their
    /// arrival a person stays at their goal in the frames but is no longer on the map.
    pub frames: Vec<Vec<Point2>>,
    /// The time step each person reached their goal at, `None` for those who did not.
    pub arrived_at: Vec<Option<usize>>,
    /// Person-steps spent waiting (no safe step).
    pub waits: usize,
    /// Person-steps spent yielding (stepping out of a higher-priority person's way).
    pub yields: usize,
}

impl CrowdRun {
    /// A run that has only its first frame, everyone at `starts`.
    fn starting(starts: &[Point2]) -> Self {
        Self {
            frames: vec![starts.to_vec()],
            arrived_at: vec![None; starts.len()],
            waits: 0,
            yields: 0,
        }
    }

    /// Number of people.
    pub fn people(&self) -> usize {
        self.arrived_at.len()
    }

    /// Time steps taken.
    pub fn steps(&self) -> usize {
        self.frames.len().saturating_sub(1)
    }

    /// Whether person `i` is on the map during the step from frame `t` to `t + 1`.
    fn walking(&self, i: usize, t: usize) -> bool {
        self.arrived_at[i].is_none_or(|a| t < a)
    }

    /// Person `i`'s positions up to their arrival (or the last frame), waits included.
    pub fn path(&self, i: usize) -> Vec<Point2> {
        let end = self.arrived_at[i].unwrap_or(self.steps());
        self.frames[..=end].iter().map(|f| f[i]).collect()
    }

    /// Length of person `i`'s path in cells.
    pub fn path_length(&self, i: usize) -> f32 {
        self.path(i).windows(2).map(|w| w[0].distance(w[1])).sum()
    }

    /// Pairs of people closer than twice `body_radius` at some moment, counted once per pair
    /// and time step, with both moving in straight lines between frames.
    pub fn person_collisions(&self, body_radius: f32) -> usize {
        let n = self.people();
        let mut count = 0;
        for t in 0..self.steps() {
            let (now, next) = (&self.frames[t], &self.frames[t + 1]);
            for i in 0..n {
                for j in i + 1..n {
                    if self.walking(i, t)
                        && self.walking(j, t)
                        && closest_approach(now[i], next[i], now[j], next[j])
                            < 2.0 * body_radius - 1e-3
                    {
                        count += 1;
                    }
                }
            }
        }
        count
    }

    /// Person-steps whose swept step (sampled every quarter cell) enters a cell that
    /// `walkable` blocks, that is where the body would overlap the floor map's obstacles.
    pub fn obstacle_collisions(&self, walkable: &Grid2) -> usize {
        (0..self.steps())
            .map(|t| {
                (0..self.people())
                    .filter(|&i| {
                        self.walking(i, t)
                            && !segment_clear(walkable, self.frames[t][i], self.frames[t + 1][i])
                    })
                    .count()
            })
            .sum()
    }
}

/// Checks a crowd problem: every start and goal on a free cell of `walkable`, starts at least
/// twice the body radius apart, no more people than fit on the free floor, and every goal
/// reachable from its start on the empty map.
///
/// # Errors
/// [`PlanError::Invalid`] naming the person and what is wrong.
pub fn check_trips(walkable: &Grid2, trips: &[Trip], config: &CrowdConfig) -> Result<()> {
    config.validate()?;
    if trips.is_empty() {
        return Err(PlanError::Invalid(
            "a crowd needs at least one person".into(),
        ));
    }
    let capacity = capacity(walkable, config);
    if trips.len() > capacity {
        return Err(PlanError::Invalid(format!(
            "{} people do not fit on {} free cells (at most {capacity} bodies of radius {} cells)",
            trips.len(),
            walkable.free_count(),
            config.body_radius
        )));
    }
    for (i, trip) in trips.iter().enumerate() {
        for (what, cell) in [("start", trip.start), ("goal", trip.goal)] {
            if !walkable.contains(cell) {
                return Err(PlanError::Invalid(format!(
                    "person {i}'s {what} {cell:?} is outside the {}x{} floor map",
                    walkable.rows(),
                    walkable.cols()
                )));
            }
            if walkable.is_obstacle(cell) {
                return Err(PlanError::Invalid(format!(
                    "person {i}'s {what} {cell:?} is on furniture, a wall or too close to one \
                     for a body of radius {} cells",
                    config.body_radius
                )));
            }
        }
        for (j, other) in trips.iter().enumerate().take(i) {
            let d = point(other.start).distance(point(trip.start));
            if d < 2.0 * config.body_radius {
                return Err(PlanError::Invalid(format!(
                    "persons {j} and {i} start {d:.2} cells apart, closer than two body radii \
                     ({:.2}): their bodies overlap",
                    2.0 * config.body_radius
                )));
            }
        }
    }
    let fields = FastMarching::default()
        .solve2_batch(&trips.iter().map(|t| (walkable, t.goal)).collect::<Vec<_>>())?;
    for (i, (trip, field)) in trips.iter().zip(&fields).enumerate() {
        if !value(field, trip.start).is_finite() {
            return Err(PlanError::Invalid(format!(
                "person {i}'s goal {:?} cannot be reached from their start {:?} on the floor map",
                trip.goal, trip.start
            )));
        }
    }
    Ok(())
}

/// `people` random trips on `walkable`, seeded: starts and goals on the largest 4-connected
/// free region, starts (and goals) at least two body radii and a cell apart, each goal at
/// least `min_length` cells in a straight line from its start.
///
/// # Errors
/// [`PlanError::Invalid`] when the map has no free cell or that many people cannot be placed
/// (after `2000 x people` draws).
pub fn random_trips(
    walkable: &Grid2,
    people: usize,
    config: &CrowdConfig,
    min_length: f32,
    seed: u64,
) -> Result<Vec<Trip>> {
    config.validate()?;
    let cells = largest_region(walkable);
    if cells.is_empty() {
        return Err(PlanError::Invalid(
            "the walkable map has no free cell".into(),
        ));
    }
    if people > capacity(walkable, config) {
        return Err(PlanError::Invalid(format!(
            "{people} people do not fit on {} free cells (at most {} bodies of radius {} cells)",
            walkable.free_count(),
            capacity(walkable, config),
            config.body_radius
        )));
    }
    let apart = 2.0 * config.body_radius + 1.0;
    let far = |a: Cell2, b: Cell2, d: f32| point(a).distance(point(b)) >= d;
    let mut rng = SplitMix64::new(seed ^ 0xC0_FFEE);
    let mut trips: Vec<Trip> = Vec::new();
    for _ in 0..people.saturating_mul(2000) {
        if trips.len() == people {
            break;
        }
        let (start, goal) = (cells[rng.below(cells.len())], cells[rng.below(cells.len())]);
        let separate = trips
            .iter()
            .all(|t| far(t.start, start, apart) && far(t.goal, goal, apart));
        if separate && far(start, goal, min_length) {
            trips.push(Trip { start, goal });
        }
    }
    if trips.len() < people {
        return Err(PlanError::Invalid(format!(
            "could not place {people} people with separate starts and goals on {} free cells \
             (placed {})",
            cells.len(),
            trips.len()
        )));
    }
    Ok(trips)
}

/// The cells of the largest 4-connected free region of `grid`.
fn largest_region(grid: &Grid2) -> Vec<Cell2> {
    let (rows, cols) = (grid.rows(), grid.cols());
    let mut seen = vec![false; grid.len()];
    let mut best: Vec<Cell2> = Vec::new();
    for first in 0..grid.len() {
        if seen[first] || grid.obstacles()[first] {
            continue;
        }
        seen[first] = true;
        let mut region = vec![grid.cell(first)];
        let mut k = 0;
        while k < region.len() {
            let c = region[k];
            k += 1;
            let next = [
                (c.row > 0).then(|| Cell2::new(c.row.wrapping_sub(1), c.col)),
                (c.row + 1 < rows).then(|| Cell2::new(c.row + 1, c.col)),
                (c.col > 0).then(|| Cell2::new(c.row, c.col.wrapping_sub(1))),
                (c.col + 1 < cols).then(|| Cell2::new(c.row, c.col + 1)),
            ];
            for n in next.into_iter().flatten() {
                let i = n.row * cols + n.col;
                if !seen[i] && !grid.obstacles()[i] {
                    seen[i] = true;
                    region.push(n);
                }
            }
        }
        if region.len() > best.len() {
            best = region;
        }
    }
    best
}

/// How many bodies fit on the free floor at most: discs of diameter two body radii packed in
/// squares (a generous bound; at least 1).
fn capacity(walkable: &Grid2, config: &CrowdConfig) -> usize {
    let side = 2.0 * config.body_radius;
    ((walkable.free_count() as f32 / (side * side)).floor() as usize).max(1)
}

/// Each person's shortest path length on the empty `walkable` map, in cells (second-order fast
/// marching): what path ratios divide by.
///
/// # Errors
/// As [`FastMarching::solve2`].
pub fn shortest_lengths(walkable: &Grid2, trips: &[Trip]) -> Result<Vec<f32>> {
    let fields = FastMarching::with_order(Order::Second)
        .solve2_batch(&trips.iter().map(|t| (walkable, t.goal)).collect::<Vec<_>>())?;
    Ok(trips
        .iter()
        .zip(&fields)
        .map(|(t, f)| value(f, t.start))
        .collect())
}

/// Algorithm 1 with `model`'s fields (module docs): every person's field on the map the
/// others change, one batched prediction per time step, until everyone has arrived or
/// `config.max_steps` steps. [`Crowd`] takes the same loop a step at a time.
///
/// ```
/// use envfield_eikonal::FastMarching;
/// use envfield_grid::{Cell2, Grid2};
/// use envfield_plan::{walk_crowd, CrowdConfig, Trip};
///
/// // An empty 30x30 floor (centre space, 0.1 m cells): two people swap corners.
/// let floor = Grid2::new(30, 30)?;
/// let trips = [
///     Trip { start: Cell2::new(3, 3), goal: Cell2::new(26, 26) },
///     Trip { start: Cell2::new(26, 26), goal: Cell2::new(3, 3) },
/// ];
/// let config = CrowdConfig::default();
/// let run = walk_crowd(&floor, &trips, &FastMarching::default(), &config)?;
/// assert!(run.arrived_at.iter().all(Option::is_some));
/// assert_eq!(run.person_collisions(config.body_radius), 0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// A bad problem ([`check_trips`]); the model's errors.
pub fn walk_crowd(
    walkable: &Grid2,
    trips: &[Trip],
    model: &impl FieldModel,
    config: &CrowdConfig,
) -> Result<CrowdRun> {
    let mut crowd = Crowd::new(walkable, trips, model, config)?;
    while crowd.run.steps() < config.max_steps && crowd.step()? {}
    Ok(crowd.run)
}

/// Several people on one walkable map, stepped one time step at a time by Algorithm 1
/// (module docs): for simulations that interleave other work, and for timing one step.
#[derive(Debug)]
pub struct Crowd<'a, M> {
    walkable: &'a Grid2,
    trips: Vec<Trip>,
    model: &'a M,
    config: CrowdConfig,
    goals: Vec<Point2>,
    pos: Vec<Point2>,
    /// The model's last finite remaining distance per person (priority); the straight line
    /// until there is one.
    remaining: Vec<f32>,
    /// Each person's field on the map without people.
    statics: Vec<Field2>,
    /// Steps each person has waited held up.
    held: Vec<usize>,
    run: CrowdRun,
}

// By hand: a derive would ask `M: Clone`, and only the reference is cloned.
impl<M> Clone for Crowd<'_, M> {
    fn clone(&self) -> Self {
        Self {
            walkable: self.walkable,
            trips: self.trips.clone(),
            model: self.model,
            config: self.config,
            goals: self.goals.clone(),
            pos: self.pos.clone(),
            remaining: self.remaining.clone(),
            statics: self.statics.clone(),
            held: self.held.clone(),
            run: self.run.clone(),
        }
    }
}

impl<'a, M: FieldModel> Crowd<'a, M> {
    /// Everyone at their start, with each person's field on the empty map (one batched
    /// prediction).
    ///
    /// # Errors
    /// A bad problem ([`check_trips`]); the model's errors.
    pub fn new(
        walkable: &'a Grid2,
        trips: &[Trip],
        model: &'a M,
        config: &CrowdConfig,
    ) -> Result<Self> {
        check_trips(walkable, trips, config)?;
        let n = trips.len();
        let goals: Vec<Point2> = trips.iter().map(|t| point(t.goal)).collect();
        let pos: Vec<Point2> = trips.iter().map(|t| point(t.start)).collect();
        let statics =
            model.predict_many(&trips.iter().map(|t| (walkable, t.goal)).collect::<Vec<_>>())?;
        Ok(Self {
            walkable,
            trips: trips.to_vec(),
            model,
            config: *config,
            remaining: (0..n).map(|i| pos[i].distance(goals[i])).collect(),
            goals,
            run: CrowdRun::starting(&pos),
            pos,
            statics,
            held: vec![0; n],
        })
    }

    /// Everyone's current position.
    pub fn positions(&self) -> &[Point2] {
        &self.pos
    }

    /// What has happened so far.
    pub fn run(&self) -> &CrowdRun {
        &self.run
    }

    /// The record of every step taken.
    pub fn into_run(self) -> CrowdRun {
        self.run
    }

    /// One time step for everyone still walking. Returns whether anyone still walks
    /// afterwards (`false` once all have arrived, and then the step does nothing).
    ///
    /// # Errors
    /// The model's errors.
    pub fn step(&mut self) -> Result<bool> {
        let n = self.trips.len();
        let walking: Vec<usize> = (0..n)
            .filter(|&i| self.run.arrived_at[i].is_none())
            .collect();
        if walking.is_empty() {
            return Ok(false);
        }
        let t = self.run.steps() + 1;
        let Self {
            walkable,
            trips,
            model,
            config,
            goals,
            pos,
            remaining,
            statics,
            held,
            run,
        } = self;
        let (walkable, model) = (*walkable, *model);
        let disc = 2.0 * config.body_radius;
        let maps: Vec<Grid2> = walking
            .iter()
            .map(|&i| {
                let others = walking.iter().filter(|&&j| j != i);
                mark_discs(walkable, others.map(|&j| pos[j]), disc)
            })
            .collect::<Result<_>>()?;
        let fields = predict_where_free(model, &maps, walking.iter().map(|&i| trips[i].goal))?;
        let mut field_of: Vec<Option<Field2>> = vec![None; n];
        let mut blocked = Vec::new();
        for (k, (&i, field)) in walking.iter().zip(fields).enumerate() {
            let v = field
                .as_ref()
                .map_or(f32::INFINITY, |f| value_at(f, pos[i]));
            if v.is_finite() {
                remaining[i] = v;
                field_of[i] = field;
            } else {
                blocked.push(k);
            }
        }
        let mut order = walking.clone();
        order.sort_by(|&a, &b| remaining[a].total_cmp(&remaining[b]).then(a.cmp(&b)));
        let rank = |i: usize| order.iter().position(|&j| j == i).unwrap_or(usize::MAX);
        // The blocked plan again past everyone behind them in priority.
        if !blocked.is_empty() {
            let relaxed: Vec<Grid2> = blocked
                .iter()
                .map(|&k| {
                    let i = walking[k];
                    let ahead = walking.iter().filter(|&&j| j != i && rank(j) < rank(i));
                    mark_discs(walkable, ahead.map(|&j| pos[j]), disc)
                })
                .collect::<Result<_>>()?;
            let goals_blocked = blocked.iter().map(|&k| trips[walking[k]].goal);
            for (&k, field) in
                blocked
                    .iter()
                    .zip(predict_where_free(model, &relaxed, goals_blocked)?)
            {
                let i = walking[k];
                if field
                    .as_ref()
                    .is_some_and(|f| value_at(f, pos[i]).is_finite())
                {
                    field_of[i] = field;
                }
            }
        }
        // Steps in priority order; `next` holds this step's end for those who have moved.
        let mut next: Vec<Option<Point2>> = vec![None; n];
        for &i in &order {
            let others = |p0: Point2, p1: Point2| {
                walking.iter().all(|&j| {
                    j == i || {
                        let (q0, q1) = (pos[j], next[j].unwrap_or(pos[j]));
                        closest_approach(p0, p1, q0, q1) >= disc
                    }
                })
            };
            let candidates = candidates(pos[i], goals[i], config.step_length, config.directions);
            // The best step down `field`, pairwise safe; the goal itself beats every other
            // end (a step may end on the goal's cell short of its centre, where the field is
            // 0 too).
            let descend = |field: &Field2| {
                let here = value_at(field, pos[i]);
                candidates
                    .iter()
                    .filter(|&&p| segment_clear(walkable, pos[i], p) && others(pos[i], p))
                    .map(|&p| {
                        (
                            p,
                            if p == goals[i] {
                                -1.0
                            } else {
                                value_at(field, p)
                            },
                        )
                    })
                    .filter(|&(_, v)| v < here - 1e-3)
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|(p, _)| p)
            };
            // Held up: the way around the others is more than a step longer than the way
            // through them. Someone near moves on soon, so keep to the way through them (the
            // pairwise check keeps the distance) for `patience` steps before going round.
            let held_up = field_of[i].as_ref().is_some_and(|f| {
                value_at(f, pos[i]) > value_at(&statics[i], pos[i]) + config.step_length
            });
            if !held_up {
                held[i] = 0;
            }
            let chosen = match &field_of[i] {
                Some(_) if held_up && held[i] < config.patience => {
                    let step = descend(&statics[i]);
                    if step.is_none() {
                        held[i] += 1;
                    }
                    step
                }
                Some(field) => descend(field),
                None => {
                    // Out of the way of the people ahead in priority who could not move
                    // this step and are close enough to be held up by this one (within two
                    // steps of touching); with none, wait.
                    let close = disc + 2.0 * config.step_length;
                    let ahead: Vec<Point2> = walking
                        .iter()
                        .filter(|&&j| {
                            rank(j) < rank(i)
                                && next[j] == Some(pos[j])
                                && pos[j].distance(pos[i]) <= close
                        })
                        .map(|&j| pos[j])
                        .collect();
                    let clearance = |p: Point2| {
                        ahead
                            .iter()
                            .map(|&q| q.distance(p))
                            .fold(f32::INFINITY, f32::min)
                    };
                    let here = clearance(pos[i]);
                    let step = candidates
                        .iter()
                        .filter(|&&p| segment_clear(walkable, pos[i], p) && others(pos[i], p))
                        .map(|&p| (p, clearance(p)))
                        .filter(|&(_, c)| c > here + 1e-3)
                        .max_by(|a, b| a.1.total_cmp(&b.1))
                        .map(|(p, _)| p);
                    run.yields += step.is_some() as usize;
                    step
                }
            };
            if chosen.is_none() {
                run.waits += 1;
            }
            next[i] = Some(chosen.unwrap_or(pos[i]));
        }
        for &i in &walking {
            pos[i] = next[i].unwrap_or(pos[i]);
            if pos[i] == goals[i] {
                run.arrived_at[i] = Some(t);
            }
        }
        run.frames.push(pos.clone());
        Ok(run.arrived_at.iter().any(Option::is_none))
    }
}

/// How the ORCA loop of [`orca_crowd`] looks ahead, in time steps.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrcaConfig {
    /// How far ahead collisions between people are avoided.
    pub time_horizon: f32,
    /// How far ahead collisions with the map are avoided.
    pub obstacle_time_horizon: f32,
    /// ORCA updates per time step (a simulation's small time step: a step of 0.5 m is two
    /// body radii, too far to move blind).
    pub substeps: usize,
}

impl Default for OrcaConfig {
    fn default() -> Self {
        Self {
            time_horizon: 3.0,
            obstacle_time_horizon: 1.0,
            substeps: 4,
        }
    }
}

/// ORCA (optimal reciprocal collision avoidance, `dodgy_2d`'s port of RVO2) on the same
/// problem: every person's preferred velocity heads for the best point one step away on the
/// exact field of the empty map (the waypoint a crowd simulation would be given), and ORCA
/// turns it into a velocity that avoids the others and the map's blocked cells near them (as
/// closed square obstacles). All people move at once, at most a step per time step; a person
/// within half a cell of their goal has arrived.
///
/// # Errors
/// A bad problem ([`check_trips`]); solver errors.
pub fn orca_crowd(
    walkable: &Grid2,
    trips: &[Trip],
    config: &CrowdConfig,
    orca: &OrcaConfig,
) -> Result<CrowdRun> {
    let mut crowd = OrcaCrowd::new(walkable, trips, config, orca)?;
    while crowd.run.steps() < config.max_steps && crowd.step() {}
    Ok(crowd.run)
}

/// The ORCA loop of [`orca_crowd`], a time step at a time.
#[derive(Clone, Debug)]
pub struct OrcaCrowd<'a> {
    walkable: &'a Grid2,
    config: CrowdConfig,
    orca: OrcaConfig,
    /// Each person's exact field on the empty map (the waypoints' source).
    statics: Vec<Field2>,
    goals: Vec<Point2>,
    pos: Vec<Point2>,
    vel: Vec<Vec2>,
    run: CrowdRun,
}

impl<'a> OrcaCrowd<'a> {
    /// Everyone at their start, at rest, with their exact fields on the empty map.
    ///
    /// # Errors
    /// A bad problem ([`check_trips`]); solver errors.
    pub fn new(
        walkable: &'a Grid2,
        trips: &[Trip],
        config: &CrowdConfig,
        orca: &OrcaConfig,
    ) -> Result<Self> {
        check_trips(walkable, trips, config)?;
        let n = trips.len();
        let statics = FastMarching::with_order(Order::Second)
            .solve2_batch(&trips.iter().map(|t| (walkable, t.goal)).collect::<Vec<_>>())?;
        let pos: Vec<Point2> = trips.iter().map(|t| point(t.start)).collect();
        Ok(Self {
            walkable,
            config: *config,
            orca: *orca,
            statics,
            goals: trips.iter().map(|t| point(t.goal)).collect(),
            run: CrowdRun::starting(&pos),
            pos,
            vel: vec![Vec2::ZERO; n],
        })
    }

    /// What has happened so far.
    pub fn run(&self) -> &CrowdRun {
        &self.run
    }

    /// The record of every step taken.
    pub fn into_run(self) -> CrowdRun {
        self.run
    }

    /// One time step: every walking person's ORCA velocity from the same state, then all
    /// move. Returns whether anyone still walks afterwards.
    pub fn step(&mut self) -> bool {
        let n = self.goals.len();
        let walking: Vec<usize> = (0..n)
            .filter(|&i| self.run.arrived_at[i].is_none())
            .collect();
        if walking.is_empty() {
            return false;
        }
        let t = self.run.steps() + 1;
        let Self {
            walkable,
            config,
            orca,
            statics,
            goals,
            pos,
            vel,
            run,
        } = self;
        let walkable = *walkable;
        let options = AvoidanceOptions {
            obstacle_margin: 0.1,
            time_horizon: orca.time_horizon,
            obstacle_time_horizon: orca.obstacle_time_horizon,
        };
        let step = config.step_length;
        let reach = step * (orca.time_horizon + 1.0) + 2.0 * config.body_radius;
        // Velocities are in cells per time step; ORCA moves in `substeps` smaller steps.
        let dt = 1.0 / orca.substeps.max(1) as f32;
        let before = pos.clone();
        for _ in 0..orca.substeps.max(1) {
            let walking: Vec<usize> = (0..n).filter(|&i| run.arrived_at[i].is_none()).collect();
            let agent = |i: usize| Agent {
                position: Vec2::new(pos[i].col, pos[i].row),
                velocity: vel[i],
                radius: config.body_radius,
                avoidance_responsibility: 1.0,
            };
            let velocities: Vec<Vec2> = walking
                .iter()
                .map(|&i| {
                    let waypoint = candidates(pos[i], goals[i], step, config.directions)
                        .into_iter()
                        .filter(|&p| segment_clear(walkable, pos[i], p))
                        .min_by(|&a, &b| {
                            value_at(&statics[i], a).total_cmp(&value_at(&statics[i], b))
                        })
                        .unwrap_or(pos[i]);
                    let preferred = Vec2::new(waypoint.col - pos[i].col, waypoint.row - pos[i].row);
                    let neighbours: Vec<Cow<Agent>> = walking
                        .iter()
                        .filter(|&&j| j != i && pos[j].distance(pos[i]) < reach)
                        .map(|&j| Cow::Owned(agent(j)))
                        .collect();
                    let obstacles =
                        square_obstacles(walkable, pos[i], step * orca.obstacle_time_horizon + 2.0);
                    let obstacles: Vec<Cow<Obstacle>> =
                        obstacles.into_iter().map(Cow::Owned).collect();
                    agent(i).compute_avoiding_velocity(
                        &neighbours,
                        &obstacles,
                        preferred,
                        step,
                        dt,
                        &options,
                    )
                })
                .collect();
            for (&i, v) in walking.iter().zip(velocities) {
                vel[i] = v;
                pos[i] = Point2::new(pos[i].row + dt * v.y, pos[i].col + dt * v.x);
                if pos[i].distance(goals[i]) < 0.5 {
                    pos[i] = goals[i];
                    run.arrived_at[i] = Some(t);
                }
            }
        }
        run.waits += walking
            .iter()
            .filter(|&&i| before[i].distance(pos[i]) < 0.05)
            .count();
        run.frames.push(pos.clone());
        run.arrived_at.iter().any(Option::is_none)
    }
}

/// The blocked cells of `grid` with a free 8-neighbour within `range` cells of `at`, as
/// counter-clockwise unit squares in ORCA's `(x, y) = (col, row)` frame.
fn square_obstacles(grid: &Grid2, at: Point2, range: f32) -> Vec<Obstacle> {
    let (rows, cols) = (grid.rows() as isize, grid.cols() as isize);
    let lo = |v: f32| (v - range).floor().max(0.0) as isize;
    let hi = |v: f32, n: isize| ((v + range).ceil() as isize).min(n - 1);
    let mut out = Vec::new();
    for r in lo(at.row)..=hi(at.row, rows) {
        for c in lo(at.col)..=hi(at.col, cols) {
            let cell = Cell2::new(r as usize, c as usize);
            let border = grid.is_obstacle(cell)
                && (-1..=1).any(|dr| {
                    (-1..=1).any(|dc| {
                        let (nr, nc) = (r + dr, c + dc);
                        nr >= 0
                            && nc >= 0
                            && nr < rows
                            && nc < cols
                            && grid.is_free(Cell2::new(nr as usize, nc as usize))
                    })
                });
            if border {
                let (x, y) = (c as f32, r as f32);
                out.push(Obstacle::Closed {
                    vertices: vec![
                        Vec2::new(x - 0.5, y - 0.5),
                        Vec2::new(x + 0.5, y - 0.5),
                        Vec2::new(x + 0.5, y + 0.5),
                        Vec2::new(x - 0.5, y + 0.5),
                    ],
                });
            }
        }
    }
    out
}

/// The fields of `goals` on `maps`, `None` where the goal is covered on its map (someone
/// stands on it): one [`FieldModel::predict_many`] call for the rest.
fn predict_where_free(
    model: &impl FieldModel,
    maps: &[Grid2],
    goals: impl Iterator<Item = Cell2>,
) -> Result<Vec<Option<Field2>>> {
    let goals: Vec<Cell2> = goals.collect();
    let asked: Vec<(&Grid2, Cell2)> = maps
        .iter()
        .zip(&goals)
        .filter(|(m, &g)| m.is_free(g))
        .map(|(m, &g)| (m, g))
        .collect();
    let mut fields = model.predict_many(&asked)?.into_iter();
    Ok(maps
        .iter()
        .zip(&goals)
        .map(|(m, &g)| m.is_free(g).then(|| fields.next()).flatten())
        .collect())
}

/// `grid` with every cell whose centre is closer than `radius` cells to one of `centres`
/// blocked: other people on a person's map (at twice the body radius, in centre space).
///
/// # Errors
/// None in practice (the grid keeps its valid shape).
pub fn mark_discs(
    grid: &Grid2,
    centres: impl Iterator<Item = Point2>,
    radius: f32,
) -> Result<Grid2> {
    let (rows, cols) = (grid.rows(), grid.cols());
    let mut obstacles = grid.obstacles().to_vec();
    for p in centres {
        let r0 = (p.row - radius).floor().max(0.0) as usize;
        let c0 = (p.col - radius).floor().max(0.0) as usize;
        let r1 = ((p.row + radius).ceil().max(0.0) as usize).min(rows.saturating_sub(1));
        let c1 = ((p.col + radius).ceil().max(0.0) as usize).min(cols.saturating_sub(1));
        for r in r0..=r1 {
            for c in c0..=c1 {
                if Point2::new(r as f32, c as f32).distance(p) < radius {
                    obstacles[r * cols + c] = true;
                }
            }
        }
    }
    Ok(Grid2::from_obstacles(rows, cols, obstacles)?)
}

/// The points a step from `at` may end at: `directions` evenly spaced headings (the first
/// along -row) at the step length, half of it and one cell, and the goal itself when it is
/// within a step.
fn candidates(at: Point2, goal: Point2, step: f32, directions: usize) -> Vec<Point2> {
    let mut out: Vec<Point2> = [step, 0.5 * step, 1.0]
        .iter()
        .flat_map(|&len| {
            (0..directions).map(move |k| {
                let a = std::f32::consts::TAU * k as f32 / directions as f32;
                Point2::new(at.row - len * a.cos(), at.col + len * a.sin())
            })
        })
        .collect();
    if at.distance(goal) <= step {
        out.push(goal);
    }
    out
}

/// Whether the straight step from `a` to `b`, sampled every quarter cell, stays on free cells.
fn segment_clear(grid: &Grid2, a: Point2, b: Point2) -> bool {
    let n = (a.distance(b) / 0.25).ceil().max(1.0) as usize;
    (0..=n).all(|k| {
        let s = k as f32 / n as f32;
        Point2::new(a.row + s * (b.row - a.row), a.col + s * (b.col - a.col))
            .round()
            .is_some_and(|c| grid.contains(c) && grid.is_free(c))
    })
}

/// The smallest distance between two points moving in straight lines at constant speed over
/// the same time step, `a0 -> a1` and `b0 -> b1`.
pub fn closest_approach(a0: Point2, a1: Point2, b0: Point2, b1: Point2) -> f32 {
    let (dr, dc) = (a0.row - b0.row, a0.col - b0.col);
    let (vr, vc) = (
        (a1.row - a0.row) - (b1.row - b0.row),
        (a1.col - a0.col) - (b1.col - b0.col),
    );
    let vv = vr * vr + vc * vc;
    let s = match vv > 0.0 {
        true => (-(dr * vr + dc * vc) / vv).clamp(0.0, 1.0),
        false => 0.0,
    };
    (dr + s * vr).hypot(dc + s * vc)
}

/// The field's value at the cell under `p`, infinite off the grid.
fn value_at(field: &Field2, p: Point2) -> f32 {
    p.round().map_or(f32::INFINITY, |c| value(field, c))
}

fn value(field: &Field2, c: Cell2) -> f32 {
    field.get(c).unwrap_or(f32::INFINITY)
}

fn point(c: Cell2) -> Point2 {
    Point2::new(c.row as f32, c.col as f32)
}
