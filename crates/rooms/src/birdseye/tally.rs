//! [`CrowdTally`]: one crowd loop's figures over rooms, as the crowd table reports them.

use super::Floor;
use crate::Result;
use envfield_affordance::PoseSequence;
use envfield_plan::crowd::{CrowdConfig, CrowdRun};
use serde_json::{Map, Value};

/// One loop's figures summed over rooms: reach, collisions counted from the recorded motion,
/// path ratios over each person's own shortest path, sum of costs and makespan over their
/// lower bounds, time per step, and the share of aligned walking poses that are supported and
/// collision-free.
#[derive(Clone, Debug, Default)]
pub struct CrowdTally {
    /// People who set out.
    pub people: usize,
    /// People who arrived.
    pub reached: usize,
    /// Pairs of people whose bodies overlapped at some moment.
    pub person_collisions: usize,
    /// People whose body entered furniture at some moment.
    pub furniture_collisions: usize,
    /// Path length over the shortest, per person who arrived.
    pub ratios: Vec<f32>,
    /// Time steps run.
    pub steps: usize,
    /// Seconds the loops took.
    pub seconds: f64,
    /// Times someone waited for the way to clear.
    pub waits: usize,
    /// Runs added.
    pub runs: usize,
    /// Runs in which everyone arrived.
    pub solved: usize,
    /// Over solved runs: the time steps at which each person arrived, summed (the sum of
    /// costs).
    pub cost: usize,
    /// Over solved runs: each person's lower bound, their own shortest path in whole steps,
    /// summed.
    pub cost_bound: usize,
    /// Over solved runs: the last arrival over the longest lower bound, per run.
    pub makespan_ratios: Vec<f32>,
    /// Aligned walking poses checked.
    pub pose_frames: usize,
    /// Of those, supported and collision-free.
    pub pose_valid: usize,
}

impl CrowdTally {
    /// Adds one run on `floor` under `config` (cells): `shortest` is each person's shortest
    /// path (cells), `seconds` the run's time; each person's `gait` is aligned to their path
    /// and checked. A person's lower bound is their shortest path in steps of
    /// `config.step_length`, rounded up.
    ///
    /// # Errors
    /// Errors of the alignment and the checks.
    pub fn add(
        &mut self,
        run: &CrowdRun,
        shortest: &[f32],
        floor: &Floor,
        config: &CrowdConfig,
        seconds: f64,
        gait: &PoseSequence,
    ) -> Result<()> {
        for i in 0..run.people() {
            let (_, reports) = floor.aligned_walk(run, i, gait)?;
            self.pose_frames += reports.len();
            self.pose_valid += reports.iter().filter(|r| r.valid()).count();
        }
        self.people += run.people();
        self.reached += run.arrived_at.iter().flatten().count();
        self.person_collisions += run.person_collisions(config.body_radius);
        self.furniture_collisions += run.obstacle_collisions(&floor.walkable);
        for (i, arrived) in run.arrived_at.iter().enumerate() {
            if arrived.is_some() && shortest[i] > 0.0 {
                self.ratios.push(run.path_length(i) / shortest[i]);
            }
        }
        self.runs += 1;
        if run.all_arrived() {
            let bounds: Vec<usize> = shortest
                .iter()
                .map(|&s| ((s / config.step_length).ceil() as usize).max(1))
                .collect();
            let arrivals: Vec<usize> = run.arrived_at.iter().flatten().copied().collect();
            self.solved += 1;
            self.cost += arrivals.iter().sum::<usize>();
            self.cost_bound += bounds.iter().sum::<usize>();
            let (last, bound) = (arrivals.iter().max(), bounds.iter().max());
            if let (Some(&last), Some(&bound)) = (last, bound) {
                self.makespan_ratios.push(last as f32 / bound as f32);
            }
        }
        self.steps += run.steps();
        self.seconds += seconds;
        self.waits += run.waits;
        Ok(())
    }

    /// The figures as JSON keys into `out`, each name after `prefix`: `reach_pct`,
    /// `person_collisions`, `furniture_collisions`, `path_ratio` (null for no arrival),
    /// `ms_per_step` (null for no step), `pose_valid_pct` (null for no pose), `steps`,
    /// `waits`, `solved_pct` (runs in which everyone arrived), `sum_of_costs_ratio` and
    /// `makespan_ratio` (over solved runs; null for none).
    pub fn json(&self, prefix: &str, out: &mut Map<String, Value>) {
        let ratio = (!self.ratios.is_empty())
            .then(|| self.ratios.iter().sum::<f32>() / self.ratios.len() as f32);
        let mut put = |k: &str, v: Value| {
            out.insert(format!("{prefix}{k}"), v);
        };
        put(
            "reach_pct",
            (100.0 * self.reached as f64 / self.people.max(1) as f64).into(),
        );
        put("person_collisions", self.person_collisions.into());
        put("furniture_collisions", self.furniture_collisions.into());
        put("path_ratio", ratio.into());
        put(
            "ms_per_step",
            (self.steps > 0)
                .then(|| 1e3 * self.seconds / self.steps as f64)
                .into(),
        );
        put(
            "pose_valid_pct",
            (self.pose_frames > 0)
                .then(|| 100.0 * self.pose_valid as f64 / self.pose_frames as f64)
                .into(),
        );
        put("steps", self.steps.into());
        put("waits", self.waits.into());
        put(
            "solved_pct",
            (100.0 * self.solved as f64 / self.runs.max(1) as f64).into(),
        );
        put(
            "sum_of_costs_ratio",
            (self.cost_bound > 0)
                .then(|| self.cost as f64 / self.cost_bound as f64)
                .into(),
        );
        let makespan = (!self.makespan_ratios.is_empty())
            .then(|| self.makespan_ratios.iter().sum::<f32>() / self.makespan_ratios.len() as f32);
        put("makespan_ratio", makespan.into());
    }
}
