//! Priority inheritance with backtracking over the fields' steps: [`pibt_crowd`] and
//! [`PibtCrowd`], a step rule that does not gridlock where Algorithm 1 does.

use super::geometry::{candidates, closest_approach, mark_discs, point, predict_where_free};
use super::geometry::{segment_clear, value_at};
use super::push::Pushes;
use super::{check_trips, CrowdConfig, CrowdRun, Trip};
use crate::Result;
use envfield_grid::{Cell2, Field2, FieldModel, Grid2, Point2, SplitMix64};

/// Calls of the recursive choice per person and time step after which nobody else is asked
/// to move in that step (plain PIBT asks each person once).
const TRIES_PER_PERSON: usize = 64;

/// Several people by priority inheritance with backtracking (PIBT, Okumura et al. 2019/2022)
/// over continuous steps, guided by `model`'s fields, until everyone stands on their goal at
/// once or `config.max_steps` steps. [`PibtCrowd`] takes the same loop a step at a time; its
/// docs have the rule.
///
/// ```
/// use envfield_eikonal::FastMarching;
/// use envfield_grid::{Cell2, Grid2};
/// use envfield_plan::crowd::{pibt_crowd, CrowdConfig, Ending, Trip};
///
/// // An empty 30x30 floor (centre space, 0.1 m cells): four people cross to the far corners.
/// let floor = Grid2::new(30, 30)?;
/// let corners = [Cell2::new(3, 3), Cell2::new(3, 26), Cell2::new(26, 26), Cell2::new(26, 3)];
/// let trips: Vec<Trip> =
///     (0..4).map(|k| Trip { start: corners[k], goal: corners[(k + 2) % 4] }).collect();
/// let config = CrowdConfig::default();
/// let run = pibt_crowd(&floor, &trips, &FastMarching::default(), &config)?;
/// assert_eq!(run.ending, Ending::Arrived);
/// assert_eq!(run.person_collisions(config.body_radius), 0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// A bad problem ([`check_trips`]); the model's errors.
pub fn pibt_crowd(
    walkable: &Grid2,
    trips: &[Trip],
    model: &impl FieldModel,
    config: &CrowdConfig,
) -> Result<CrowdRun> {
    let mut crowd = PibtCrowd::new(walkable, trips, model, config)?;
    while crowd.run.steps() < config.max_steps && crowd.step()? {}
    crowd.run.finish();
    Ok(crowd.run)
}

/// Several people on one walkable map, stepped by priority inheritance with backtracking.
///
/// One time step:
/// 1. **Fields.** For every person off their goal, the map with everyone else's disc marked
///    and its field for that person's goal, all in one
///    [`FieldModel::predict_many`](envfield_grid::FieldModel::predict_many) call: Algorithm 1's
///    batched pass.
/// 2. **Priority.** Each person's priority is the number of time steps since they last stood
///    on their goal, plus a fixed fraction of their own to break ties. People on their goal
///    have the lowest; whoever has waited longest goes first, so everyone comes first in time.
/// 3. **Steps, in priority order, with inheritance.** A person's candidate ends are the
///    headings at the step length, half of it and one cell, the goal when within a step, and
///    standing still. Each is ranked by the smaller of its value on the changed map (the way
///    round the others) and its value on the empty map plus one step (the way through someone,
///    who must step aside); a person who stood still last step has their ranks shaken by up to
///    a step, since the same choices would repeat. A candidate is taken if its swept step is clear of the map and, in continuous time, of
///    every step already chosen. If it would touch exactly one person who has not chosen yet,
///    that person inherits the priority and must choose a step out of the way first (with the
///    same rule, recursively); if they cannot, the next candidate is tried (backtracking).
///    A person who can take no candidate stands, and reports failure to whoever pushed them;
///    everything chosen under a failed try is undone.
/// 4. **The cornered go first.** When the first in priority cannot move, the person standing in
///    their best step's way takes the first priority until they reach their goal.
///
/// People who reach their goal stay on the map. They are pushed aside like anyone else when
/// someone needs to pass, and walk back.
#[derive(Debug)]
pub struct PibtCrowd<'a, M> {
    walkable: &'a Grid2,
    model: &'a M,
    config: CrowdConfig,
    goal_cells: Vec<Cell2>,
    goals: Vec<Point2>,
    pos: Vec<Point2>,
    /// Each person's field on the map without people.
    statics: Vec<Field2>,
    /// Time steps since each person last stood on their goal, plus a tie-breaking fraction.
    priority: Vec<f32>,
    /// Time steps each person off their goal has stood still.
    still: Vec<usize>,
    run: CrowdRun,
}

// By hand: a derive would ask `M: Clone`, and only the reference is cloned.
impl<M> Clone for PibtCrowd<'_, M> {
    fn clone(&self) -> Self {
        Self {
            walkable: self.walkable,
            model: self.model,
            config: self.config,
            goal_cells: self.goal_cells.clone(),
            goals: self.goals.clone(),
            pos: self.pos.clone(),
            statics: self.statics.clone(),
            priority: self.priority.clone(),
            still: self.still.clone(),
            run: self.run.clone(),
        }
    }
}

impl<'a, M: FieldModel> PibtCrowd<'a, M> {
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
        let mut run = CrowdRun::starting(&pos);
        run.stay_on_map = true;
        Ok(Self {
            walkable,
            model,
            config: *config,
            goal_cells: trips.iter().map(|t| t.goal).collect(),
            still: vec![0; n],
            priority: (0..n).map(|i| (i as f32 + 0.5) / n as f32).collect(),
            goals,
            pos,
            statics,
            run,
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

    /// One time step for everyone (the type's docs). Returns whether anyone is still off
    /// their goal afterwards (`false` once all stand on them, and then the step does nothing).
    ///
    /// # Errors
    /// The model's errors.
    pub fn step(&mut self) -> Result<bool> {
        let n = self.goals.len();
        let off: Vec<usize> = (0..n).filter(|&i| self.pos[i] != self.goals[i]).collect();
        if off.is_empty() {
            return Ok(false);
        }
        let changed = self.fields_with_others(&off)?;
        let mut fields: Vec<Option<&Field2>> = vec![None; n];
        for (&i, field) in off.iter().zip(&changed) {
            fields[i] = field
                .as_ref()
                .filter(|f| value_at(f, self.pos[i]).is_finite());
        }
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| self.priority[b].total_cmp(&self.priority[a]));
        let disc = 2.0 * self.config.body_radius;
        let mut pushes = Pushes::new(&self.pos, vec![None; n], disc, TRIES_PER_PERSON * n);
        let mut ends = |i: usize| self.ordered_candidates(i, fields[i]);
        let mut waits = 0;
        for &i in &order {
            if pushes.next[i].is_none() && !pushes.choose(i, &mut ends) {
                pushes.next[i] = Some(self.pos[i]);
                waits += 1;
            }
        }
        let next = pushes.next;
        self.run.waits += waits;
        // The first in priority could not move: whoever stands in their best step's way and
        // could not make way (cornered) goes first from now on, until they reach their goal.
        let top = order[0];
        if self.pos[top] != self.goals[top] && next[top] == Some(self.pos[top]) {
            if let Some(k) = self.in_the_way(top, fields[top]) {
                self.priority[k] = self.priority[top].floor() + 1.0 + self.priority[k].fract();
            }
        }
        let t = self.run.steps() + 1;
        for i in 0..n {
            let end = next[i].unwrap_or(self.pos[i]);
            let was_home = self.pos[i] == self.goals[i];
            self.still[i] = match end == self.pos[i] && !was_home {
                true => self.still[i] + 1,
                false => 0,
            };
            self.pos[i] = end;
            let home = end == self.goals[i];
            if home {
                self.priority[i] = self.priority[i].fract();
                if !was_home {
                    self.run.arrived_at[i] = Some(t);
                }
            } else {
                self.priority[i] += 1.0;
                self.run.arrived_at[i] = None;
            }
        }
        self.run.frames.push(self.pos.clone());
        Ok(!self.run.all_arrived())
    }

    /// Step 1: the field of each person in `off` on the map with everyone else's disc marked,
    /// in one batch.
    fn fields_with_others(&self, off: &[usize]) -> Result<Vec<Option<Field2>>> {
        let disc = 2.0 * self.config.body_radius;
        let maps: Vec<Grid2> = off
            .iter()
            .map(|&i| {
                let others = (0..self.pos.len()).filter(|&j| j != i);
                mark_discs(self.walkable, others.map(|j| self.pos[j]), disc)
            })
            .collect::<Result<_>>()?;
        let goals = off.iter().map(|&i| self.goal_cells[i]);
        predict_where_free(self.model, &maps, goals)
    }

    /// The person nearest to `i` among those standing in the way of `i`'s best step clear of
    /// the map.
    fn in_the_way(&self, i: usize, changed: Option<&Field2>) -> Option<usize> {
        let disc = 2.0 * self.config.body_radius;
        let from = self.pos[i];
        let to = self
            .ordered_candidates(i, changed)
            .into_iter()
            .find(|&to| to != from)?;
        (0..self.pos.len())
            .filter(|&k| k != i)
            .map(|k| (k, closest_approach(from, to, self.pos[k], self.pos[k])))
            .filter(|&(_, d)| d < disc)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(k, _)| k)
    }

    /// `i`'s candidate ends whose swept step is clear of the map, best first: by the changed
    /// map's field where it is finite there, then by the empty map's field; standing still
    /// among them.
    fn ordered_candidates(&self, i: usize, changed: Option<&Field2>) -> Vec<Point2> {
        let (from, goal) = (self.pos[i], self.goals[i]);
        let mut ends = candidates(from, goal, self.config.step_length, self.config.directions);
        ends.push(from);
        let statics = &self.statics[i];
        let at = |field: &Field2, p: Point2| match p == goal {
            true => -1.0,
            false => value_at(field, p),
        };
        // The way through someone costs them a step out of the way: a candidate's rank is the
        // smaller of its value round the others and its value through them plus a step.
        let push = self.config.step_length;
        let rank = |p: Point2| -> f32 {
            let through = at(statics, p) + push;
            changed.map_or(through, |f| at(f, p).min(through))
        };
        // Someone who has stood still for two steps or more tries their candidates in a
        // shuffled order within a step's worth of rank: the same choices would repeat.
        let mut rng = SplitMix64::new(((self.run.steps() as u64) << 20) ^ i as u64 ^ 0x5EED);
        let shake = match self.still[i] >= 1 {
            true => self.config.step_length,
            false => 0.0,
        };
        let mut keyed: Vec<(Point2, f32, f32)> = ends
            .into_iter()
            .map(|p| (p, rank(p) + shake * rng.next_f32(), at(statics, p)))
            .filter(|&(p, _, empty)| empty.is_finite() && segment_clear(self.walkable, from, p))
            .collect();
        keyed.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.2.total_cmp(&b.2)));
        keyed.into_iter().map(|(p, _, _)| p).collect()
    }
}
