use crate::planner::check_query;
use crate::{PlanOutcome, Planner, Result};
use envfield_grid::{octile_distance, Cell2, Field2, FieldModel, Grid2, MoveRule, Neighbourhood2};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// A* with the octile heuristic (admissible and consistent for steps of 1 and sqrt 2) under a
/// move rule. Finds a shortest path; O(n log n) in the cells it expands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AStar {
    /// The move rule.
    pub rule: MoveRule,
}

#[derive(PartialEq)]
struct Node(f32, f32, usize);
impl Eq for Node {}
impl PartialOrd for Node {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Node {
    fn cmp(&self, o: &Self) -> Ordering {
        // Min-heap on f, ties to the larger g (deeper nodes first).
        o.0.total_cmp(&self.0).then(self.1.total_cmp(&o.1))
    }
}

/// The octile distance to the goal on every free cell (obstacles infinite), blind to the walls
/// in between: what a field knows with no knowledge of the maze's layout. The control for
/// learned fields and for planners built on them (how much of a planner's success does not
/// come from its field).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Octile;

impl FieldModel for Octile {
    fn name(&self) -> &str {
        "octile"
    }

    fn predict(&self, grid: &Grid2, goal: Cell2) -> envfield_grid::Result<Field2> {
        let mut values = Vec::with_capacity(grid.len());
        for row in 0..grid.rows() {
            for col in 0..grid.cols() {
                let c = Cell2::new(row, col);
                values.push(if grid.is_free(c) {
                    octile_distance(c, goal)
                } else {
                    f32::INFINITY
                });
            }
        }
        Field2::new(grid.rows(), grid.cols(), values)
    }
}

impl Planner for AStar {
    fn name(&self) -> &str {
        "astar"
    }

    fn plan(
        &self,
        grid: &Grid2,
        start: Cell2,
        goal: Cell2,
        max_steps: usize,
    ) -> Result<PlanOutcome> {
        check_query(grid, start, goal)?;
        let n = grid.len();
        let mut g = vec![f32::INFINITY; n];
        let mut parent = vec![usize::MAX; n];
        let mut closed = vec![false; n];
        let (s, t) = (grid.check(start)?, grid.check(goal)?);
        g[s] = 0.0;
        let mut open = BinaryHeap::new();
        open.push(Node(octile_distance(start, goal), 0.0, s));
        while let Some(Node(_, gi, i)) = open.pop() {
            if closed[i] {
                continue;
            }
            closed[i] = true;
            if i == t {
                break;
            }
            for (c, len) in grid.neighbours(grid.cell(i), Neighbourhood2::Eight(self.rule)) {
                let j = c.row * grid.cols() + c.col;
                let ng = gi + len;
                if ng < g[j] {
                    g[j] = ng;
                    parent[j] = i;
                    open.push(Node(ng + octile_distance(c, goal), ng, j));
                }
            }
        }
        if !closed[t] {
            return Ok(PlanOutcome {
                path: Vec::new(),
                success: false,
            });
        }
        let mut path = vec![goal];
        let mut i = t;
        while i != s {
            i = parent[i];
            path.push(grid.cell(i));
        }
        path.reverse();
        let success = path.len() <= max_steps + 1;
        if !success {
            path.truncate(max_steps + 1);
        }
        Ok(PlanOutcome { path, success })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use envfield_eikonal::GraphDistance;
    use envfield_grid::parse_mazes;

    #[test]
    fn octile_is_the_exact_field_without_walls_and_blind_with_them() {
        let open = &parse_mazes(".....\n.....\n..G..\n.....\n")
            .unwrap()
            .remove(0)
            .grid;
        let goal = Cell2::new(2, 2);
        let exact = GraphDistance::new(Neighbourhood2::Eight(MoveRule::Vin))
            .predict(open, goal)
            .unwrap();
        let blind = Octile.predict(open, goal).unwrap();
        for (a, b) in exact.values().iter().zip(blind.values()) {
            assert!((a - b).abs() < 1e-5, "{a} {b}");
        }
        // A wall between: the exact field goes round it, octile does not see it.
        let walled = &parse_mazes("G.#..\n..#..\n..#..\n.....\n")
            .unwrap()
            .remove(0)
            .grid;
        let blind = Octile.predict(walled, Cell2::new(0, 0)).unwrap();
        assert_eq!(blind.get(Cell2::new(0, 2)), Some(f32::INFINITY));
        assert_eq!(blind.get(Cell2::new(0, 3)), Some(3.0));
        let exact = GraphDistance::new(Neighbourhood2::Eight(MoveRule::Vin))
            .predict(walled, Cell2::new(0, 0))
            .unwrap();
        assert!(exact.get(Cell2::new(0, 3)).unwrap() > 5.0);
    }
}
