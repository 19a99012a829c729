//! Evaluation pairs (`docs/evaluation.md`, step 1).

use crate::{MazeError, Result};
use envfield_eikonal::bfs2;
use envfield_grid::SplitMix64;
use envfield_grid::{Cell2, Maze, MoveRule, Neighbourhood2};
use serde::{Deserialize, Serialize};

/// One evaluation pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Pair {
    /// Index of the maze in its set.
    pub maze: usize,
    /// Start cell.
    pub start: Cell2,
    /// Goal cell.
    pub goal: Cell2,
}

/// The pairs to evaluate on `mazes`: a maze's own `S` and `G` when it has both; otherwise
/// `pairs_per_maze` random pairs of distinct free cells in one connected component under
/// `rule`, drawn with `seed` (maze `i` uses its own stream, so the pairs of a maze do not
/// depend on the others). A maze with a `G` but no `S` keeps its goal. Mazes with no two
/// connected free cells contribute no pair.
///
/// # Errors
/// [`MazeError::Grid`] when a marked start or goal is not a free cell.
pub fn evaluation_pairs(
    mazes: &[Maze],
    rule: MoveRule,
    pairs_per_maze: usize,
    seed: u64,
) -> Result<Vec<Pair>> {
    let nb = Neighbourhood2::Eight(rule);
    let mut out = Vec::new();
    for (i, m) in mazes.iter().enumerate() {
        if let (Some(s), Some(g)) = (m.start, m.goal) {
            m.grid.check_free(s, "start")?;
            m.grid.check_free(g, "goal")?;
            out.push(Pair {
                maze: i,
                start: s,
                goal: g,
            });
            continue;
        }
        if let Some(g) = m.goal {
            m.grid.check_free(g, "goal")?;
        }
        let free: Vec<Cell2> = m.grid.free_cells().collect();
        if free.len() < 2 {
            continue;
        }
        let mut rng = SplitMix64::new(seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let mut made = 0;
        let mut tries = 0;
        while made < pairs_per_maze && tries < 20 * pairs_per_maze.max(1) {
            tries += 1;
            let goal = m.goal.unwrap_or_else(|| free[rng.below(free.len())]);
            let reach = bfs2(&m.grid, &[goal], nb).map_err(MazeError::from)?;
            let candidates: Vec<Cell2> = free
                .iter()
                .copied()
                .filter(|&c| c != goal && reach.get(c).is_some_and(f32::is_finite))
                .collect();
            if candidates.is_empty() {
                continue;
            }
            let start = candidates[rng.below(candidates.len())];
            out.push(Pair {
                maze: i,
                start,
                goal,
            });
            made += 1;
        }
    }
    Ok(out)
}
