//! The ORCA crowd loop (van den Berg et al. 2011, through `dodgy_2d`'s port of RVO2), set
//! beside Algorithm 1 on the same maps and trips.

use super::geometry::{candidates, point, segment_clear, value_at};
use super::{check_trips, CrowdConfig, CrowdRun, Trip};
use crate::Result;
use dodgy_2d::{Agent, AvoidanceOptions, Obstacle, Vec2};
use envfield_eikonal::{FastMarching, Order};
use envfield_grid::{Cell2, Field2, Grid2, Point2};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

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
    crowd.run.finish();
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
