use crate::planner::check_query;
use crate::{PlanOutcome, Planner, Result};
use envfield_grid::{Cell2, Grid2, Policy, DIRECTIONS_8};
use std::collections::HashSet;

/// A planner that asks a [`Policy`] for every move: at each step the agent takes the legal
/// move (under the policy's rule) of highest score, as VIN does. It stops on the goal, after
/// `max_steps` moves, when no move is legal, or on revisiting a cell. One policy call per
/// step.
#[derive(Clone, Debug)]
pub struct PolicyWalk<P>(pub P);

impl<P: Policy> Planner for PolicyWalk<P> {
    fn name(&self) -> &str {
        self.0.name()
    }

    fn plan(
        &self,
        grid: &Grid2,
        start: Cell2,
        goal: Cell2,
        max_steps: usize,
    ) -> Result<PlanOutcome> {
        check_query(grid, start, goal)?;
        let rule = self.0.rule();
        let mut path = vec![start];
        let mut seen = HashSet::from([start]);
        let mut here = start;
        while here != goal && path.len() <= max_steps {
            let scores = self.0.action_scores(grid, goal, here)?;
            let best = (0..8)
                .filter(|&k| {
                    let (dr, dc) = DIRECTIONS_8[k];
                    rule.allows(grid, here, dr, dc)
                })
                .max_by(|&a, &b| scores[a].total_cmp(&scores[b]));
            let Some(k) = best else { break };
            let (dr, dc) = DIRECTIONS_8[k];
            let Some(next) = here.offset(dr, dc) else {
                break;
            };
            if !seen.insert(next) {
                break;
            }
            path.push(next);
            here = next;
        }
        Ok(PlanOutcome {
            success: here == goal,
            path,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use envfield_grid::{parse_mazes, MoveRule};

    /// Scores every move by how much closer it brings the agent to the goal, the octile way.
    struct Greedy;

    impl Policy for Greedy {
        fn name(&self) -> &str {
            "greedy"
        }
        fn rule(&self) -> MoveRule {
            MoveRule::Strict
        }
        fn action_scores(
            &self,
            _grid: &Grid2,
            goal: Cell2,
            state: Cell2,
        ) -> envfield_grid::Result<[f32; 8]> {
            Ok(DIRECTIONS_8.map(|(dr, dc)| match state.offset(dr, dc) {
                Some(c) => -envfield_grid::octile_distance(c, goal),
                None => f32::NEG_INFINITY,
            }))
        }
    }

    #[test]
    fn walks_a_policy_to_the_goal_and_stops_on_a_loop() {
        let open = &parse_mazes("S....\n.....\n....G\n").unwrap()[0];
        let (s, g) = (open.start.unwrap(), open.goal.unwrap());
        let out = PolicyWalk(Greedy).plan(&open.grid, s, g, 100).unwrap();
        assert!(out.success);
        assert_eq!(out.steps(), 4);
        // A wall the greedy policy walks into: it oscillates, and the walk stops on the loop.
        let walled = &parse_mazes("S.#..\n..#.G\n..#..\n").unwrap()[0];
        let (s, g) = (walled.start.unwrap(), walled.goal.unwrap());
        let out = PolicyWalk(Greedy).plan(&walled.grid, s, g, 100).unwrap();
        assert!(!out.success);
        assert!(out.steps() < 10);
        assert!(PolicyWalk(Greedy)
            .plan(&walled.grid, s, Cell2::new(0, 2), 9)
            .is_err());
    }
}
