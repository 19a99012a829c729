use crate::descent::{descend, predict_checked};
use crate::planner::check_query;
use crate::{PlanOutcome, Planner, Result};
use envfield_grid::{Cell2, Field2, FieldModel, Grid2, MoveRule};
use std::collections::HashMap;

/// Field descent that, when the walk fails, plans through a relay cell so that no leg relies
/// on a field far from its goal.
///
/// A learned field ranks moves well near its goal and less well far from it (the decision
/// profile of a network trained on mazes shows the share of failing cells rising with the
/// distance). Both move rules are symmetric (a move is legal exactly when its reverse is), so
/// the field towards the *start* is also the distance *from* the start, and the two fields
/// together locate the middle of a shortest path: on one, `f_start + f_goal` is the path's
/// length, off it larger, so the cell minimising `max(f_start, f_goal)` is the middle of a
/// shortest path when the fields are exact. The walks are planned on the predicted fields
/// before the agent moves, so the planner knows whether one arrives (it ends on its goal, or
/// stops in a loop or a dead end). This planner:
///
/// 1. predicts the goal's field and walks down it from the start like
///    [`FieldDescent`](crate::FieldDescent); a walk that reaches the goal is the plan;
/// 2. otherwise predicts the start's field too and walks down it from the goal; if that walk
///    reaches the start, the plan is that walk backwards;
/// 3. otherwise ranks relay cells `r` by `max(f_start, f_goal)` ([`relay_cells`]) and takes
///    the first of the best [`candidates`](Self::candidates) from which both walks arrive:
///    down the start's field to the start (walked backwards) and down the goal's field to the
///    goal; these walks need no further prediction;
/// 4. when none arrives, plans the two legs of the best relay cell the same way, one level
///    deeper (a failing leg costs one more prediction), up to [`depth`](Self::depth) levels;
/// 5. cuts every loop out of the joined path (it stays a walk of legal moves).
///
/// When nothing arrives the plan is the first walk, which fails. Only failing walks get
/// further predictions, so the planner costs what descent does on the paths descent gets
/// right, and with exact fields it is plain descent. The two legs of a relay share the field
/// towards it, so a path costs at most `1 + 2^(depth - 1)` predictions (two at depth 1).
pub struct RelayDescent<M> {
    /// The field model.
    pub model: M,
    /// The move rule the agent walks under.
    pub rule: MoveRule,
    /// How many levels of splits a failing walk may get (0 is plain descent; each level at
    /// most doubles the legs).
    pub depth: usize,
    /// How many relay cells, best first, a failing walk tries with plain walks before the
    /// best one's legs are split again (walks cost no prediction). 1 by default; 0 leaves only
    /// the walk back from the goal. More candidates make the planner a search of its own: with
    /// every cell a candidate, even a field blind to the walls ([`Octile`](crate::Octile))
    /// solves nearly every gridworld maze, so the default keeps the planner's success down to
    /// its field.
    pub candidates: usize,
    name: String,
}

impl<M: FieldModel> RelayDescent<M> {
    /// Relay descent on `model` under `rule`, splitting failing walks up to `depth` levels
    /// deep, one relay candidate per split; the planner is named after the model with a
    /// `+relay` suffix.
    pub fn new(model: M, rule: MoveRule, depth: usize) -> Self {
        let name = format!("{}+relay", model.name());
        Self {
            model,
            rule,
            depth,
            candidates: 1,
            name,
        }
    }

    fn predict(&self, grid: &Grid2, goal: Cell2) -> Result<Field2> {
        predict_checked(&self.model, grid, goal)
    }

    /// Plans from `from` to `to` on `to_field` (the field towards `to`), splitting a failing
    /// walk at a relay cell while `depth` allows. `from_field` holds the field towards `from`
    /// once predicted: the two legs of a relay start from the same cell and share it.
    fn leg(
        &self,
        grid: &Grid2,
        from: Cell2,
        to: Cell2,
        to_field: &Field2,
        from_field: &mut Option<Field2>,
        Limits { depth, max_steps }: Limits,
    ) -> Result<PlanOutcome> {
        let walk = descend(grid, to_field, self.rule, from, to, max_steps);
        if walk.success || depth == 0 {
            return Ok(walk);
        }
        let from_field = match from_field {
            Some(field) => &*field,
            None => &*from_field.insert(self.predict(grid, from)?),
        };
        // The walk the other way, on the field towards `from`, turned round.
        let reverse = descend(grid, from_field, self.rule, to, from, max_steps);
        if reverse.success {
            let path = reverse.path.into_iter().rev().collect();
            return Ok(PlanOutcome {
                success: true,
                path,
            });
        }
        let candidates: Vec<Cell2> = relay_cells(grid, from_field, to_field, self.candidates)
            .into_iter()
            .filter(|&r| r != from && r != to)
            .collect();
        // Candidates whose two plain walks arrive cost no prediction: the best such one wins.
        for &relay in &candidates {
            let back = descend(grid, from_field, self.rule, relay, from, max_steps);
            let forth = descend(grid, to_field, self.rule, relay, to, max_steps);
            if let Some(path) = join(&back, &forth, to, max_steps) {
                return Ok(PlanOutcome {
                    success: true,
                    path,
                });
            }
        }
        // Otherwise split the legs of the best candidate again.
        let Some(&relay) = candidates.first() else {
            return Ok(walk);
        };
        let mut relay_field = None;
        let back = self.leg(
            grid,
            relay,
            from,
            from_field,
            &mut relay_field,
            Limits {
                depth: depth - 1,
                max_steps,
            },
        )?;
        let forth = self.leg(
            grid,
            relay,
            to,
            to_field,
            &mut relay_field,
            Limits {
                depth: depth - 1,
                max_steps,
            },
        )?;
        Ok(match join(&back, &forth, to, max_steps) {
            Some(path) => PlanOutcome {
                success: true,
                path,
            },
            None => walk,
        })
    }
}

/// The path `back` (from a relay to the start) walked backwards, then `forth` (from the relay
/// to `to`), with loops cut out; `None` unless both legs arrived and the joined path reaches
/// `to` within `max_steps` moves.
fn join(
    back: &PlanOutcome,
    forth: &PlanOutcome,
    to: Cell2,
    max_steps: usize,
) -> Option<Vec<Cell2>> {
    if !back.success || !forth.success {
        return None;
    }
    let joined: Vec<Cell2> = back
        .path
        .iter()
        .rev()
        .chain(forth.path.iter().skip(1))
        .copied()
        .collect();
    let path = remove_loops(&joined);
    (path.last() == Some(&to) && path.len() <= max_steps.saturating_add(1)).then_some(path)
}

/// Up to `k` relay cells, best first: the free cells where both fields are finite, by
/// `max(a, b)`, ties to the smaller `a + b` and then to row-major order. For exact fields of a
/// start and a goal the first is the middle of a shortest path between them.
pub fn relay_cells(grid: &Grid2, a: &Field2, b: &Field2, k: usize) -> Vec<Cell2> {
    let mut scored: Vec<(f32, f32, Cell2)> = Vec::new();
    for row in 0..grid.rows() {
        for col in 0..grid.cols() {
            let c = Cell2::new(row, col);
            if !grid.is_free(c) {
                continue;
            }
            let (Some(x), Some(y)) = (a.get(c), b.get(c)) else {
                continue;
            };
            if x.is_finite() && y.is_finite() {
                scored.push((x.max(y), x + y, c));
            }
        }
    }
    let order = |p: &(f32, f32, Cell2), q: &(f32, f32, Cell2)| {
        p.0.total_cmp(&q.0)
            .then(p.1.total_cmp(&q.1))
            .then(p.2.cmp(&q.2))
    };
    if k < scored.len() {
        if k > 0 {
            scored.select_nth_unstable_by(k - 1, order);
        }
        scored.truncate(k);
    }
    scored.sort_by(order);
    scored.into_iter().map(|(_, _, c)| c).collect()
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
        let limits = Limits {
            depth: self.depth,
            max_steps,
        };
        self.leg(grid, start, goal, &to_goal, &mut None, limits)
    }
}

/// How far a leg may still split (`depth` relays) and walk (`max_steps`).
#[derive(Clone, Copy)]
struct Limits {
    depth: usize,
    max_steps: usize,
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
    /// cells from its goal, with `depth` levels of relays and `candidates` relay cells.
    fn plan_myopic(horizon: f32, depth: usize, candidates: usize) -> PlanOutcome {
        let mazes = parse_mazes(SERPENT).unwrap();
        let rule = MoveRule::Vin;
        let myopic = Myopic {
            exact: GraphDistance::new(Neighbourhood2::Eight(rule)),
            horizon,
        };
        let mut relay = RelayDescent::new(myopic, rule, depth);
        relay.candidates = candidates;
        let out = relay.plan(&mazes[0].grid, c(1, 1), c(7, 9), 64).unwrap();
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
        // Depth 0 is plain descent, which the bumps far from the goal trap.
        assert!(!plan_myopic(16.0, 0, 1).success);
        // One split in the middle: each leg lies within 16 cells of its own goal.
        let one = plan_myopic(16.0, 1, 1);
        assert!(one.success, "{:?}", one.path);
        assert!((one.length() - shortest).abs() < 1e-4);
        // A field right only within 8 cells needs legs of a quarter of the path: with one
        // candidate, two levels.
        assert!(!plan_myopic(8.0, 1, 1).success);
        let two = plan_myopic(8.0, 2, 1);
        assert!(two.success, "{:?}", two.path);
        assert!((two.length() - shortest).abs() < 1e-4);
        // Bumps lie on every leg longer than 8 cells, so more candidates cannot replace the
        // second level, and the two compose.
        assert!(!plan_myopic(8.0, 1, usize::MAX).success);
        let all = plan_myopic(8.0, 2, usize::MAX);
        assert!(all.success, "{:?}", all.path);
        assert!((all.length() - shortest).abs() < 1e-4);
    }

    /// Counts the predictions of the model it wraps.
    struct Counted<M> {
        inner: M,
        calls: std::sync::atomic::AtomicUsize,
    }

    impl<M: FieldModel> FieldModel for Counted<M> {
        fn name(&self) -> &str {
            self.inner.name()
        }

        fn predict(&self, grid: &Grid2, goal: Cell2) -> envfield_grid::Result<Field2> {
            self.calls
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            self.inner.predict(grid, goal)
        }
    }

    #[test]
    fn the_legs_of_a_relay_share_its_field() {
        let mazes = parse_mazes(SERPENT).unwrap();
        let rule = MoveRule::Vin;
        let model = Counted {
            inner: Myopic {
                exact: GraphDistance::new(Neighbourhood2::Eight(rule)),
                horizon: 8.0,
            },
            calls: 0.into(),
        };
        let relay = RelayDescent::new(model, rule, 2);
        let out = relay.plan(&mazes[0].grid, c(1, 1), c(7, 9), 64).unwrap();
        assert!(out.success, "{:?}", out.path);
        // The goal's field, the start's, and one field towards the relay cell for both of
        // its failing legs: 1 + 2^(2 - 1).
        let calls = relay.model.calls.load(std::sync::atomic::Ordering::Relaxed);
        assert_eq!(calls, 3);
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

    /// A broken model: a 1x1 field for any grid.
    struct Tiny;

    impl FieldModel for Tiny {
        fn name(&self) -> &str {
            "tiny"
        }

        fn predict(&self, _: &Grid2, _: Cell2) -> envfield_grid::Result<Field2> {
            Field2::new(1, 1, vec![0.0])
        }
    }

    #[test]
    fn a_field_of_the_wrong_shape_is_an_error() {
        let mazes = parse_mazes(SERPENT).unwrap();
        let grid = &mazes[0].grid;
        let rule = MoveRule::Vin;
        let e = RelayDescent::new(Tiny, rule, 1)
            .plan(grid, c(1, 1), c(7, 9), 64)
            .unwrap_err();
        assert!(
            e.to_string()
                .contains("returned a 1x1 field for a 9x11 grid"),
            "{e}"
        );
        assert!(FieldDescent::new(Tiny, rule)
            .plan(grid, c(1, 1), c(7, 9), 64)
            .is_err());
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
