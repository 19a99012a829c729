//! The maze evaluation harness: the protocol of `docs/evaluation.md`, exactly.

use crate::{path_length, Planner, Result};
use envfield_eikonal::{bfs2, dijkstra2};
use envfield_grid::{Cell2, Grid2, Maze, MoveRule, Neighbourhood2};
use envfield_mazes::{evaluation_pairs, Pair};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// How to evaluate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalConfig {
    /// The move rule of the agent and of the optimal references.
    pub rule: MoveRule,
    /// Random pairs per maze for mazes without both `S` and `G`.
    pub pairs_per_maze: usize,
    /// Seed of the random pairs.
    pub seed: u64,
}

/// The result of one pair.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairResult {
    /// Index of the maze.
    pub maze: usize,
    /// Start cell.
    pub start: Cell2,
    /// Goal cell.
    pub goal: Cell2,
    /// The cells the agent visited, in order.
    pub path: Vec<Cell2>,
    /// Whether the agent stood on the goal within the budget, by legal moves.
    pub success: bool,
    /// The fewest cells on any path from start to goal under the rule (both included).
    pub optimal_cells: usize,
    /// The shortest path length under the rule (orthogonal 1, diagonal sqrt 2).
    pub optimal_length: f32,
    /// The path's length.
    pub length: f32,
    /// Milliseconds the planner took (all inference included).
    pub ms: f64,
}

/// The summary line of an evaluation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Planner name.
    pub planner: String,
    /// Move rule.
    pub rule: MoveRule,
    /// Mazes evaluated.
    pub mazes: usize,
    /// Pairs evaluated.
    pub pairs: usize,
    /// Successful pairs, in percent.
    pub success_rate: f64,
    /// Mean of path length / optimal length over successful pairs (1 = optimal); NaN when none
    /// succeeded, written as `null` in JSON (which has no NaN).
    #[serde(with = "nan_as_null")]
    pub path_ratio: f64,
    /// Mean milliseconds per path, all inference included.
    pub ms_per_path: f64,
}

/// Per-pair results and their summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// The summary.
    pub summary: Summary,
    /// One entry per pair.
    pub results: Vec<PairResult>,
}

/// Summaries as a text table, one row per `(label, summary)`: mazes, planner, mazes, pairs,
/// success %, path ratio, ms per path.
pub fn summary_table(rows: &[(String, Summary)]) -> String {
    use std::fmt::Write;
    let mut out = format!(
        "{:<22} {:<14} {:>6} {:>7} {:>10} {:>11} {:>11}\n",
        "mazes", "planner", "mazes", "pairs", "success %", "path ratio", "ms/path"
    );
    for (label, s) in rows {
        let _ = writeln!(
            out,
            "{:<22} {:<14} {:>6} {:>7} {:>10.2} {:>11.4} {:>11.4}",
            label, s.planner, s.mazes, s.pairs, s.success_rate, s.path_ratio, s.ms_per_path
        );
    }
    out
}

impl Report {
    /// A picture of the first pair of the report (on `mazes`, the mazes it was made on): the
    /// field of `field` (the exact graph distance under `rule` when `None`), the obstacles,
    /// the planner's path in red and a shortest path (A*) in white, as a PNG at `path`.
    ///
    /// # Errors
    /// [`PlanError::Invalid`](crate::PlanError) for a report without a pair; errors of the
    /// field, the search and the file.
    pub fn write_first_png(
        &self,
        path: &std::path::Path,
        mazes: &[Maze],
        field: Option<&dyn envfield_grid::FieldModel>,
        rule: MoveRule,
    ) -> Result<()> {
        use envfield_grid::{FieldModel, HeatMapStyle};
        let first = self
            .results
            .first()
            .ok_or_else(|| crate::PlanError::Invalid("no pair to draw".into()))?;
        let grid = &mazes
            .get(first.maze)
            .ok_or_else(|| crate::PlanError::Invalid("the pair's maze is not there".into()))?
            .grid;
        let values = match field {
            Some(m) => m.predict(grid, first.goal)?,
            None => envfield_eikonal::GraphDistance::new(Neighbourhood2::Eight(rule))
                .predict(grid, first.goal)?,
        };
        let optimal = crate::AStar { rule }
            .plan(grid, first.start, first.goal, usize::MAX / 4)?
            .path;
        let scale = (640 / grid.rows().max(grid.cols())).clamp(2, 32) as u32;
        let style = HeatMapStyle {
            scale,
            grid: Some(grid),
            path: &first.path,
            reference_path: &optimal,
            start: Some(first.start),
            goal: Some(first.goal),
        };
        values.write_png(path, &style)?;
        Ok(())
    }
}

/// Whether `path` is a walk of legal moves under `rule` from `start`.
pub fn is_legal_walk(grid: &Grid2, rule: MoveRule, path: &[Cell2]) -> bool {
    path.first().is_some_and(|&c| grid.is_free(c))
        && path.windows(2).all(|w| {
            let dr = w[1].row as isize - w[0].row as isize;
            let dc = w[1].col as isize - w[0].col as isize;
            dr.abs() <= 1 && dc.abs() <= 1 && (dr, dc) != (0, 0) && rule.allows(grid, w[0], dr, dc)
        })
}

/// Runs `planner` on every evaluation pair of `mazes` ([`evaluation_pairs`]) by the evaluation
/// protocol: the agent succeeds when its path is a legal walk from the start that ends on the
/// goal within `2 x optimal_cells` moves; the path ratio averages length / shortest length over
/// successes; time covers the planner's whole call. The harness rechecks every path itself
/// rather than trusting the planner's claim. `progress(done, total)` is called after each pair.
///
/// # Errors
/// A marked start or goal on an obstacle; a planner error.
pub fn evaluate(
    planner: &dyn Planner,
    mazes: &[Maze],
    cfg: &EvalConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Report> {
    let pairs = evaluation_pairs(mazes, cfg.rule, cfg.pairs_per_maze, cfg.seed)?;
    evaluate_pairs(planner, mazes, &pairs, cfg.rule, progress)
}

/// [`evaluate`] on given pairs.
///
/// # Errors
/// As [`evaluate`].
pub fn evaluate_pairs(
    planner: &dyn Planner,
    mazes: &[Maze],
    pairs: &[Pair],
    rule: MoveRule,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Report> {
    let nb = Neighbourhood2::Eight(rule);
    let mut results = Vec::with_capacity(pairs.len());
    for (k, p) in pairs.iter().enumerate() {
        let grid = &mazes
            .get(p.maze)
            .ok_or_else(|| {
                crate::PlanError::Invalid(format!(
                    "pair {k} names maze {} of {}",
                    p.maze,
                    mazes.len()
                ))
            })?
            .grid;
        grid.check_free(p.start, "start")?;
        grid.check_free(p.goal, "goal")?;
        let steps = bfs2(grid, &[p.goal], nb)?
            .get(p.start)
            .unwrap_or(f32::INFINITY);
        let optimal_length = dijkstra2(grid, &[p.goal], nb, std::f32::consts::SQRT_2)?
            .get(p.start)
            .unwrap_or(f32::INFINITY);
        if !steps.is_finite() {
            return Err(crate::PlanError::Invalid(format!(
                "maze {}: goal {} cannot be reached from start {} under the {rule} rule",
                p.maze, p.goal, p.start
            )));
        }
        let optimal_cells = steps as usize + 1;
        let budget = 2 * optimal_cells;
        let t = Instant::now();
        let outcome = planner.plan(grid, p.start, p.goal, budget)?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let path = outcome.path;
        let success = path.first() == Some(&p.start)
            && path.last() == Some(&p.goal)
            && path.len() - 1 <= budget
            && is_legal_walk(grid, rule, &path);
        results.push(PairResult {
            maze: p.maze,
            start: p.start,
            goal: p.goal,
            length: path_length(&path),
            path,
            success,
            optimal_cells,
            optimal_length,
            ms,
        });
        progress(k + 1, pairs.len());
    }
    let n = results.len();
    let wins: Vec<&PairResult> = results.iter().filter(|r| r.success).collect();
    let summary = Summary {
        planner: planner.name().to_string(),
        rule,
        mazes: mazes.len(),
        pairs: n,
        success_rate: if n == 0 {
            0.0
        } else {
            100.0 * wins.len() as f64 / n as f64
        },
        path_ratio: if wins.is_empty() {
            f64::NAN
        } else {
            // A legal walk is never shorter than the shortest one, so a ratio below 1 is the
            // f32 rounding of the optimal length (Dijkstra adds up to millions of steps in
            // f32): it counts as 1. The walk's own length is exact, in f64.
            wins.iter()
                .map(|r| {
                    let optimal = (r.optimal_length as f64).max(f64::MIN_POSITIVE);
                    (exact_length(&r.path) / optimal).max(1.0)
                })
                .sum::<f64>()
                / wins.len() as f64
        },
        ms_per_path: if n == 0 {
            0.0
        } else {
            results.iter().map(|r| r.ms).sum::<f64>() / n as f64
        },
    };
    Ok(Report { summary, results })
}

/// The length of a path of neighbouring cells in f64: straight moves 1, diagonal sqrt 2.
fn exact_length(path: &[Cell2]) -> f64 {
    let diagonal = path
        .windows(2)
        .filter(|w| w[0].row != w[1].row && w[0].col != w[1].col)
        .count();
    let straight = path.len().saturating_sub(1) - diagonal;
    straight as f64 + diagonal as f64 * std::f64::consts::SQRT_2
}

/// JSON has no NaN: a figure that is not a number is written as `null` and read back as NaN.
mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serializer};

    pub(super) fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        match x.is_finite() {
            true => s.serialize_f64(*x),
            false => s.serialize_none(),
        }
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ratio_of_no_success_is_null_in_json_and_nan_again_when_read() {
        let summary = Summary {
            planner: "x".into(),
            rule: MoveRule::Strict,
            mazes: 1,
            pairs: 1,
            success_rate: 0.0,
            path_ratio: f64::NAN,
            ms_per_path: 0.5,
        };
        let json = serde_json::to_string(&summary).unwrap();
        assert!(json.contains("\"path_ratio\":null"), "{json}");
        let back: Summary = serde_json::from_str(&json).unwrap();
        assert!(back.path_ratio.is_nan());
        let ok = Summary {
            path_ratio: 1.25,
            ..summary
        };
        let back: Summary = serde_json::from_str(&serde_json::to_string(&ok).unwrap()).unwrap();
        assert_eq!(back.path_ratio, 1.25);
    }
}
