//! Several people walking through one floor map at once: our planner [`plan_crowd`] (priority
//! inheritance with backtracking over the fields' steps, [`pibt_crowd`], and the LaCAM search
//! [`lacam_crowd`] where that stalls; people stay on their goals and are pushed aside), the
//! paper's Algorithm 1 (section 4.1, [`walk_crowd`]), and to set beside them the ORCA crowd loop
//! (van den Berg et al. 2011, [`orca_crowd`]) and PIBT on a one-body-per-cell lattice
//! ([`grid_pibt`], as multi-agent path finding writes it).
//!
//! Everything is in cell units of the *walkable* map: the floor map with its obstacles grown by
//! the body radius, so a free cell is a place a person's centre may stand. People are discs of
//! [`CrowdConfig::body_radius`] around their centres.
//!
//! One time step of [`walk_crowd`] (Algorithm 1; [`PibtCrowd`] has ours):
//! 1. for every person still walking, the map with the others' discs (twice the body radius
//!    around their centres) marked as obstacles, and its field for that person's goal; all of
//!    them in one [`FieldModel::predict_many`](envfield_grid::FieldModel::predict_many) call (one batched forward pass for a network);
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

mod geometry;
mod grid_pibt;
mod lacam;
mod orca;
mod pibt;
mod push;
mod run;
mod step;
mod trips;

pub use geometry::{closest_approach, mark_discs};
pub use grid_pibt::grid_pibt;
pub use lacam::{lacam_crowd, plan_crowd, MAX_NODES, MAX_TRIES, STALL};
pub use orca::{orca_crowd, OrcaConfig, OrcaCrowd};
pub use pibt::{pibt_crowd, PibtCrowd};
pub use run::{CrowdRun, Ending};
pub use step::{walk_crowd, Crowd};
pub use trips::{check_trips, random_trips, shortest_lengths};

use crate::{PlanError, Result};
use envfield_grid::Cell2;
use serde::{Deserialize, Serialize};

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
    pub(crate) fn validate(&self) -> Result<()> {
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
