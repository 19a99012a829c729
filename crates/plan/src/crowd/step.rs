//! Algorithm 1: [`walk_crowd`] and [`Crowd`], one time step at a time.

use super::geometry::{candidates, closest_approach, mark_discs, point, predict_where_free};
use super::geometry::{segment_clear, value_at};
use super::{check_trips, CrowdConfig, CrowdRun, Trip};
use crate::Result;
use envfield_grid::{Field2, FieldModel, Grid2, Point2};

/// Algorithm 1 with `model`'s fields (module docs): every person's field on the map the
/// others change, one batched prediction per time step, until everyone has arrived or
/// `config.max_steps` steps. [`Crowd`] takes the same loop a step at a time.
///
/// ```
/// use envfield_eikonal::FastMarching;
/// use envfield_grid::{Cell2, Grid2};
/// use envfield_plan::crowd::{walk_crowd, CrowdConfig, Trip};
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
    crowd.run.finish();
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

    /// One time step for everyone still walking (Algorithm 1, module docs): each walker's
    /// field with the others marked, the priority order, a second look for those whose goal
    /// the others cut off, then everyone's step in priority order. Returns whether anyone
    /// still walks afterwards (`false` once all have arrived, and then the step does nothing).
    ///
    /// # Errors
    /// The model's errors.
    pub fn step(&mut self) -> Result<bool> {
        let walking: Vec<usize> = (0..self.trips.len())
            .filter(|&i| self.run.arrived_at[i].is_none())
            .collect();
        if walking.is_empty() {
            return Ok(false);
        }
        let (mut field_of, blocked) = self.fields_with_others(&walking)?;
        let order = self.priority_order(&walking);
        self.replan_blocked(&walking, &blocked, &order, &mut field_of)?;
        // Steps in priority order; `next` holds this step's end for those who have moved.
        let mut next: Vec<Option<Point2>> = vec![None; self.trips.len()];
        for &i in &order {
            let chosen = self.choose_step(i, &walking, &order, &next, field_of[i].as_ref());
            if chosen.is_none() {
                self.run.waits += 1;
            }
            next[i] = Some(chosen.unwrap_or(self.pos[i]));
        }
        let t = self.run.steps() + 1;
        for &i in &walking {
            self.pos[i] = next[i].unwrap_or(self.pos[i]);
            if self.pos[i] == self.goals[i] {
                self.run.arrived_at[i] = Some(t);
            }
        }
        self.run.frames.push(self.pos.clone());
        Ok(self.run.arrived_at.iter().any(Option::is_none))
    }

    /// Step 1: each walker's field on the map with the others' discs marked, in one batch.
    /// Where the walker's field is finite it becomes their remaining distance; the others
    /// (their goal cut off) come back as `blocked`, by their index in `walking`.
    fn fields_with_others(
        &mut self,
        walking: &[usize],
    ) -> Result<(Vec<Option<Field2>>, Vec<usize>)> {
        let disc = 2.0 * self.config.body_radius;
        let pos = &self.pos;
        let maps: Vec<Grid2> = walking
            .iter()
            .map(|&i| {
                let others = walking.iter().filter(|&&j| j != i);
                mark_discs(self.walkable, others.map(|&j| pos[j]), disc)
            })
            .collect::<Result<_>>()?;
        let goals = walking.iter().map(|&i| self.trips[i].goal);
        let fields = predict_where_free(self.model, &maps, goals)?;
        let mut field_of: Vec<Option<Field2>> = vec![None; self.trips.len()];
        let mut blocked = Vec::new();
        for (k, (&i, field)) in walking.iter().zip(fields).enumerate() {
            let v = field
                .as_ref()
                .map_or(f32::INFINITY, |f| value_at(f, self.pos[i]));
            if v.is_finite() {
                self.remaining[i] = v;
                field_of[i] = field;
            } else {
                blocked.push(k);
            }
        }
        Ok((field_of, blocked))
    }

    /// Step 2: the walkers by priority, the smaller remaining distance first (ties to the
    /// lower index).
    fn priority_order(&self, walking: &[usize]) -> Vec<usize> {
        let mut order = walking.to_vec();
        let remaining = &self.remaining;
        order.sort_by(|&a, &b| remaining[a].total_cmp(&remaining[b]).then(a.cmp(&b)));
        order
    }

    /// Step 2 for the blocked: each plans again on the map with only the discs of the people
    /// ahead of them in priority (one more batch); a field that reaches them replaces none.
    fn replan_blocked(
        &self,
        walking: &[usize],
        blocked: &[usize],
        order: &[usize],
        field_of: &mut [Option<Field2>],
    ) -> Result<()> {
        if blocked.is_empty() {
            return Ok(());
        }
        let rank = |i: usize| order.iter().position(|&j| j == i).unwrap_or(usize::MAX);
        let disc = 2.0 * self.config.body_radius;
        let relaxed: Vec<Grid2> = blocked
            .iter()
            .map(|&k| {
                let i = walking[k];
                let ahead = walking.iter().filter(|&&j| j != i && rank(j) < rank(i));
                mark_discs(self.walkable, ahead.map(|&j| self.pos[j]), disc)
            })
            .collect::<Result<_>>()?;
        let goals = blocked.iter().map(|&k| self.trips[walking[k]].goal);
        for (&k, field) in blocked
            .iter()
            .zip(predict_where_free(self.model, &relaxed, goals)?)
        {
            let i = walking[k];
            if field
                .as_ref()
                .is_some_and(|f| value_at(f, self.pos[i]).is_finite())
            {
                field_of[i] = field;
            }
        }
        Ok(())
    }

    /// Step 3 for person `i`: the best safe step down their field (or, held up, down their
    /// field of the empty map for `patience` steps), or with no field a step out of the way of
    /// the people ahead; `None` to wait. `next` holds the ends of the steps already chosen.
    fn choose_step(
        &mut self,
        i: usize,
        walking: &[usize],
        order: &[usize],
        next: &[Option<Point2>],
        field: Option<&Field2>,
    ) -> Option<Point2> {
        let (pos, config) = (&self.pos, &self.config);
        let disc = 2.0 * config.body_radius;
        let others = |p0: Point2, p1: Point2| {
            walking.iter().all(|&j| {
                j == i || {
                    let (q0, q1) = (pos[j], next[j].unwrap_or(pos[j]));
                    closest_approach(p0, p1, q0, q1) >= disc
                }
            })
        };
        let safe = |p: Point2| segment_clear(self.walkable, pos[i], p) && others(pos[i], p);
        let candidates = candidates(pos[i], self.goals[i], config.step_length, config.directions);
        // The best step down `field`, pairwise safe; the goal itself beats every other end (a
        // step may end on the goal's cell short of its centre, where the field is 0 too).
        let descend = |field: &Field2| {
            let here = value_at(field, pos[i]);
            candidates
                .iter()
                .filter(|&&p| safe(p))
                .map(|&p| {
                    (
                        p,
                        if p == self.goals[i] {
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
        // Held up: the way around the others is more than a step longer than the way through
        // them. Someone near moves on soon, so keep to the way through them (the pairwise check
        // keeps the distance) for `patience` steps before going round.
        let statics = &self.statics[i];
        let held_up = field
            .is_some_and(|f| value_at(f, pos[i]) > value_at(statics, pos[i]) + config.step_length);
        match field {
            Some(_) if held_up && self.held[i] < config.patience => {
                let step = descend(statics);
                if step.is_none() {
                    self.held[i] += 1;
                }
                step
            }
            Some(field) => {
                if !held_up {
                    self.held[i] = 0;
                }
                descend(field)
            }
            None => {
                // Out of the way of the people ahead in priority who could not move this step
                // and are close enough to be held up by this one (within two steps of
                // touching); with none, wait.
                let rank = |i: usize| order.iter().position(|&j| j == i).unwrap_or(usize::MAX);
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
                    .filter(|&&p| safe(p))
                    .map(|&p| (p, clearance(p)))
                    .filter(|&(_, c)| c > here + 1e-3)
                    .max_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|(p, _)| p);
                self.held[i] = 0;
                self.run.yields += step.is_some() as usize;
                step
            }
        }
    }
}
