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
