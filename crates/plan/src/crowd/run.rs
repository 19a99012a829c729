//! [`CrowdRun`]: what a crowd loop did, and the collisions counted from its recorded motion.

use super::geometry::{closest_approach, segment_clear};
use envfield_grid::{Grid2, Point2};
use serde::{Deserialize, Serialize};

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
    /// Whether people stay on the map after reaching their goal (and may leave it again), as
    /// in [`pibt_crowd`](super::pibt_crowd), or leave it, as in Algorithm 1. With `true`,
    /// `arrived_at[i]` is the step person `i` last stepped onto their goal, if they stand
    /// there at the end.
    #[serde(default)]
    pub stay_on_map: bool,
    /// Why the loop stopped.
    #[serde(default)]
    pub ending: Ending,
}

/// Why a crowd loop stopped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ending {
    /// Everyone reached their goal.
    Arrived,
    /// The step budget ran out with someone short of their goal (`arrived_at` says who).
    #[default]
    StepBudget,
}

impl CrowdRun {
    /// A run that has only its first frame, everyone at `starts`.
    pub(crate) fn starting(starts: &[Point2]) -> Self {
        Self {
            frames: vec![starts.to_vec()],
            arrived_at: vec![None; starts.len()],
            waits: 0,
            yields: 0,
            stay_on_map: false,
            ending: Ending::StepBudget,
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
    pub(crate) fn walking(&self, i: usize, t: usize) -> bool {
        self.stay_on_map || self.arrived_at[i].is_none_or(|a| t < a)
    }

    /// Sets [`CrowdRun::ending`] from who has arrived: the loop has stopped.
    pub(crate) fn finish(&mut self) {
        self.ending = match self.all_arrived() {
            true => Ending::Arrived,
            false => Ending::StepBudget,
        };
    }

    /// Whether everyone stands on (or, in Algorithm 1, has reached) their goal.
    pub fn all_arrived(&self) -> bool {
        self.arrived_at.iter().all(Option::is_some)
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
