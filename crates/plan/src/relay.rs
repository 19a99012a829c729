use crate::descent::descend;
use crate::planner::check_query;
use crate::{PlanError, PlanOutcome, Planner, Result};
use envfield_grid::{Cell2, Field2, FieldModel, Grid2, MoveRule};
use std::collections::HashMap;

/// Field descent that, when the walk fails, splits the path at a relay cell so that no leg
/// relies on a field far from its goal.
///
/// A learned field ranks moves well near its goal and less well far from it (the decision
/// profile of a network trained on mazes shows the share of failing cells rising with the
/// distance). Both move rules are symmetric (a move is legal exactly when its reverse is), so
/// the field towards the *start* is also the distance *from* the start, and the two fields
/// together locate the middle of a shortest path: on one, `f_start + f_goal` is the path's
/// length, off it larger, so the cell minimising `max(f_start, f_goal)` is the middle of a
/// shortest path when the fields are exact. This planner:
///
/// 1. predicts the goal's field and walks down it from the start like
///    [`FieldDescent`](crate::FieldDescent); when the walk reaches the goal, that is the plan
///    (the walk is planned on the predicted field before the agent moves, so the planner
///    knows whether it arrives: it ends on the goal or stops in a loop or a dead end);
/// 2. otherwise it predicts the start's field too and picks the relay cell `r` minimising
///    `max(f_start, f_goal)` over the cells where both are finite (ties to the smaller sum,
///    then the first cell in row-major order);
/// 3. plans from `r` to the start on the start's field and walks that path backwards, then
///    from `r` to the goal on the goal's field, each leg about half the path and planned the
///    same way (a failing leg is split again, up to [`depth`](Self::depth) levels);
/// 4. cuts every loop out of the joined path (it stays a walk of legal moves).
///
/// When a leg cannot be planned, the plan is the first descent (which fails). Each split
/// costs one field prediction, and only failing walks are split, so the planner costs what
/// descent does on the paths descent gets right. With exact fields it is plain descent.
pub struct RelayDescent<M> {
    /// The field model.
    pub model: M,
    /// The move rule the agent walks under.
    pub rule: MoveRule,
    /// How many levels of splits a failing walk may get (0 is plain descent; each level at
    /// most doubles the legs).
    pub depth: usize,
    name: String,
}

impl<M: FieldModel> RelayDescent<M> {
    /// Relay descent on `model` under `rule`, splitting failing walks up to `depth` levels
    /// deep; the planner is named after the model with a `+relay` suffix.
    pub fn new(model: M, rule: MoveRule, depth: usize) -> Self {
        let name = format!("{}+relay", model.name());
        Self {
            model,
            rule,
            depth,
            name,
        }
    }

    fn predict(&self, grid: &Grid2, goal: Cell2) -> Result<Field2> {
        let field = self.model.predict(grid, goal)?;
        if (field.rows(), field.cols()) != (grid.rows(), grid.cols()) {
            return Err(PlanError::Invalid(format!(
                "model {} returned a {}x{} field for a {}x{} grid",
                self.model.name(),
                field.rows(),
                field.cols(),
                grid.rows(),
                grid.cols()
            )));
        }
        Ok(field)
    }

    /// Plans from `from` to `to` on `to_field` (the field towards `to`), splitting a failing
    /// walk at a relay cell while `depth` allows.
    fn leg(
        &self,
        grid: &Grid2,
        from: Cell2,
        to: Cell2,
        to_field: &Field2,
        depth: usize,
        max_steps: usize,
    ) -> Result<PlanOutcome> {
        let walk = descend(grid, to_field, self.rule, from, to, max_steps);
        if walk.success || depth == 0 {
            return Ok(walk);
        }
        let from_field = self.predict(grid, from)?;
        let relay = match relay_cell(grid, &from_field, to_field) {
            Some(r) if r != from && r != to => r,
            _ => return Ok(walk),
        };
        let back = self.leg(grid, relay, from, &from_field, depth - 1, max_steps)?;
        if !back.success {
            return Ok(walk);
        }
        let forth = self.leg(grid, relay, to, to_field, depth - 1, max_steps)?;
        if !forth.success {
            return Ok(walk);
        }
        let joined: Vec<Cell2> = back
            .path
            .iter()
            .rev()
            .chain(forth.path.iter().skip(1))
            .copied()
            .collect();
        let mut path = remove_loops(&joined);
        path.truncate(max_steps.saturating_add(1));
        if path.last() != Some(&to) {
            return Ok(walk);
        }
        Ok(PlanOutcome {
            success: true,
            path,
        })
    }
}

/// The cell minimising `max(a, b)` among the free cells where both fields are finite, ties to
/// the smaller `a + b` and then to row-major order; `None` when there is no such cell.
pub fn relay_cell(grid: &Grid2, a: &Field2, b: &Field2) -> Option<Cell2> {
    let mut best: Option<(Cell2, f32, f32)> = None;
    for row in 0..grid.rows() {
        for col in 0..grid.cols() {
            let c = Cell2::new(row, col);
            if !grid.is_free(c) {
                continue;
            }
            let (Some(x), Some(y)) = (a.get(c), b.get(c)) else {
                continue;
            };
            if !x.is_finite() || !y.is_finite() {
                continue;
            }
            let (m, s) = (x.max(y), x + y);
            if best.is_none_or(|(_, bm, bs)| m < bm || (m == bm && s < bs)) {
                best = Some((c, m, s));
            }
        }
    }
    best.map(|(c, _, _)| c)
}

/// `path` with every loop cut out: when a cell comes back, the walk since its first visit is
/// dropped. Consecutive cells of the result were consecutive in `path`, so a walk of legal
/// moves stays one.
pub fn remove_loops(path: &[Cell2]) -> Vec<Cell2> {
    let mut out: Vec<Cell2> = Vec::with_capacity(path.len());
    let mut at: HashMap<Cell2, usize> = HashMap::with_capacity(path.len());
    for &c in path {
        if let Some(&k) = at.get(&c) {
            for dropped in out.drain(k + 1..) {
                at.remove(&dropped);
            }
        } else {
            at.insert(c, out.len());
            out.push(c);
        }
    }
    out
}

impl<M: FieldModel> Planner for RelayDescent<M> {
    fn name(&self) -> &str {
        &self.name
    }

    fn plan(
        &self,
        grid: &Grid2,
        start: Cell2,
        goal: Cell2,
        max_steps: usize,
    ) -> Result<PlanOutcome> {
        check_query(grid, start, goal)?;
        let to_goal = self.predict(grid, goal)?;
        self.leg(grid, start, goal, &to_goal, self.depth, max_steps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{evaluate, is_legal_walk, EvalConfig, FieldDescent};
    use envfield_eikonal::GraphDistance;
    use envfield_grid::{parse_mazes, Neighbourhood2};

    fn c(row: usize, col: usize) -> Cell2 {
        Cell2::new(row, col)
    }

    /// A long winding maze: a serpentine corridor.
    const SERPENT: &str = "\
###########
#S........#
#########.#
#.........#
#.#########
#.........#
#########.#
#........G#
###########
";

    /// The exact graph field with a bump of three cells on every third column more than
    /// `horizon` cells from the goal: descent walks into the bump, turns back and stops in a
    /// loop. A model that is right near its goal and unreliable far from it, the failure a
    /// learned field shows.
    struct Myopic {
        exact: GraphDistance,
        horizon: f32,
    }

    impl FieldModel for Myopic {
        fn name(&self) -> &str {
            "myopic"
        }

        fn predict(&self, grid: &Grid2, goal: Cell2) -> envfield_grid::Result<Field2> {
            let mut field = self.exact.predict(grid, goal)?;
            for row in 0..grid.rows() {
                for col in 0..grid.cols() {
                    let v = field.get(c(row, col)).unwrap_or(f32::INFINITY);
                    if v.is_finite() && v > self.horizon {
                        let noise = if col % 3 == 0 { 3.0 } else { 0.0 };
                        field.set(c(row, col), v + noise)?;
                    }
                }
            }
            Ok(field)
        }
    }

    #[test]
    fn exact_fields_give_shortest_paths() {
        let mazes = parse_mazes(SERPENT).unwrap();
        let rule = MoveRule::Vin;
        let cfg = EvalConfig {
            rule,
            pairs_per_maze: 20,
            seed: 3,
        };
        let exact = GraphDistance::new(Neighbourhood2::Eight(rule));
        let relay = RelayDescent::new(exact, rule, 2);
        let report = evaluate(&relay, &mazes, &cfg, &mut |_, _| {}).unwrap();
        assert_eq!(report.summary.success_rate, 100.0);
        assert!((report.summary.path_ratio - 1.0).abs() < 1e-5);
    }

    /// Plans from the serpent's start to its goal on a field that is exact up to `horizon`
    /// cells from its goal, with `depth` levels of relays.
    fn plan_myopic(horizon: f32, depth: usize) -> PlanOutcome {
        let mazes = parse_mazes(SERPENT).unwrap();
        let rule = MoveRule::Vin;
        let myopic = Myopic {
            exact: GraphDistance::new(Neighbourhood2::Eight(rule)),
            horizon,
        };
        let out = RelayDescent::new(myopic, rule, depth)
            .plan(&mazes[0].grid, c(1, 1), c(7, 9), 64)
            .unwrap();
        assert!(is_legal_walk(&mazes[0].grid, rule, &out.path));
        assert_eq!(out.path.first(), Some(&c(1, 1)));
        out
    }

    #[test]
    fn relays_fix_a_field_that_is_wrong_far_from_its_goal() {
        let mazes = parse_mazes(SERPENT).unwrap();
        let rule = MoveRule::Vin;
        let exact = GraphDistance::new(Neighbourhood2::Eight(rule))
            .predict(&mazes[0].grid, c(7, 9))
            .unwrap();
        let shortest = exact.get(c(1, 1)).unwrap();
        assert!(shortest > 24.0, "{shortest}");
        // Depth 0 is plain descent, which the noise far from the goal traps.
        assert!(!plan_myopic(16.0, 0).success);
        // One split in the middle: each leg lies within 16 cells of its own goal.
        let one = plan_myopic(16.0, 1);
        assert!(one.success, "{:?}", one.path);
        assert!((one.length() - shortest).abs() < 1e-4);
        // A field right only within 8 cells needs legs of a quarter of the path: two levels.
        assert!(!plan_myopic(8.0, 1).success);
        let two = plan_myopic(8.0, 2);
        assert!(two.success, "{:?}", two.path);
        assert!((two.length() - shortest).abs() < 1e-4);
    }

    #[test]
    fn successful_walks_are_plain_descent() {
        let mazes = parse_mazes(SERPENT).unwrap();
        let grid = &mazes[0].grid;
        let rule = MoveRule::Vin;
        let myopic = || Myopic {
            exact: GraphDistance::new(Neighbourhood2::Eight(rule)),
            horizon: 16.0,
        };
        let relay = RelayDescent::new(myopic(), rule, 2);
        let plain = FieldDescent::new(myopic(), rule);
        for start in [c(3, 4), c(5, 1), c(5, 8), c(7, 2)] {
            let a = relay.plan(grid, start, c(7, 9), 64).unwrap();
            let b = plain.plan(grid, start, c(7, 9), 64).unwrap();
            assert!(b.success);
            assert_eq!(a, b);
        }
    }

    #[test]
    fn loops_are_cut_out() {
        let p = [c(0, 0), c(0, 1), c(1, 1), c(1, 0), c(0, 1), c(0, 2)];
        assert_eq!(remove_loops(&p), vec![c(0, 0), c(0, 1), c(0, 2)]);
        let q = [c(0, 0), c(0, 1), c(0, 0), c(1, 0)];
        assert_eq!(remove_loops(&q), vec![c(0, 0), c(1, 0)]);
        assert_eq!(remove_loops(&[]), Vec::<Cell2>::new());
    }
}
