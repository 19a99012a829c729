//! The shortest-path readout of a context network ([`crate::PathConfig`]): learned move costs
//! and the exact fixed point of the min-plus Bellman recurrence over them.
//!
//! The recurrence `v(x) = min over moves a of (c_a(x) + v(x + a))`, `v(goal) = 0`, is VIN's
//! value iteration with `min` for `max` and the transition kernel fixed to the eight moves
//! (Tamar et al. 2016), or the shortest-path layer of Neural A* (Yonetani et al. 2021) and of
//! black-box solver differentiation (Vlastelica et al. 2020). Iterated until nothing changes,
//! its fixed point is the shortest-path distance over the costs, which Dijkstra's algorithm
//! reaches in one pass over the cells instead of one iteration per cell of path length: a
//! perfect 64x64 maze has paths of about 2000 cells.
//!
//! The gradient of the fixed point with respect to the costs is exact almost everywhere:
//! `v(x)` is the sum of the costs along its shortest-path tree branch, so `dL/dc_a(x)` is the
//! sum of `dL/dv` over `x` and every cell whose branch passes through `x`, for the move `a`
//! that branch takes from `x`, and zero for other moves.

use crate::layers::Linear;
use crate::params::{Init, ParamStore};
use crate::{PathConfig, Result};
use candle_core::{CpuStorage, CustomOp1, Layout, Shape, Tensor};
use envfield_grid::{MoveRule, DIRECTIONS_8};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The value of cells the goal does not reach and that touch no reached cell. Finite, so that
/// a zero bilinear weight times it stays zero; far above any path (`MAX_FIELD_CELLS` cells of
/// sqrt 2 at most).
pub(super) const UNREACHED: f32 = 1e7;

/// Moves per cell, in [`DIRECTIONS_8`] order.
pub(super) const MOVES: usize = 8;

/// The cost layer: one 1x1 convolution from the encoder's features to eight move costs,
/// `min_cost + exp(s)`.
#[derive(Debug)]
pub(super) struct PathLayer {
    pub(super) cost: Linear,
    pub(super) config: PathConfig,
}

impl PathLayer {
    /// Small weights and zero biases: every move starts at `min_cost + 1` whatever the maze.
    pub(super) fn new(store: &mut ParamStore, features: usize, config: PathConfig) -> Result<Self> {
        let cost = Linear::new(store, "path.cost", features, MOVES, Init::Normal(0.01))?;
        Ok(Self { cost, config })
    }

    /// (B, H, W, C) features -> (B, H, W, 8) move costs, at least `min_cost`. The exponent
    /// is clamped so that no cost overflows.
    pub(super) fn costs(&self, features: &Tensor) -> Result<Tensor> {
        let (b, h, w, c) = features.dims4()?;
        let s = self.cost.forward(&features.reshape((b * h * w, c))?)?;
        let costs = (s.clamp(-30f32, 30f32)?.exp()? + self.config.min_cost as f64)?;
        Ok(costs.reshape((b, h, w, MOVES))?)
    }
}

/// The cells, goals and rule one batch's min-plus fixed point runs on.
#[derive(Clone, Debug)]
pub(super) struct MinPlus {
    pub(super) rows: usize,
    pub(super) cols: usize,
    /// `items * rows * cols`, true where a cell is free.
    pub(super) free: Vec<bool>,
    /// One goal cell index per item (row-major within the item).
    pub(super) goals: Vec<usize>,
    pub(super) rule: MoveRule,
}

/// One item's fixed point: the values (with [`fill_unreached`] applied) and, per cell, the
/// move its shortest path takes first (`u8::MAX` for the goal and unreached cells), with the
/// cells in the order Dijkstra settled them and, for unreached cells, the reached neighbour
/// their value comes from (`u32::MAX` for none).
pub(super) struct Solved {
    pub(super) values: Vec<f32>,
    pub(super) first_move: Vec<u8>,
    pub(super) order: Vec<u32>,
    pub(super) fill_source: Vec<u32>,
}

impl MinPlus {
    fn cells(&self) -> usize {
        self.rows * self.cols
    }

    /// Whether the move `k` from the free cell `(r, c)` is legal under the rule, and where
    /// it lands.
    #[inline]
    fn step(&self, free: &[bool], r: usize, c: usize, k: usize) -> Option<usize> {
        let (dr, dc) = DIRECTIONS_8[k];
        let (nr, nc) = (r as isize + dr, c as isize + dc);
        if nr < 0 || nc < 0 || nr >= self.rows as isize || nc >= self.cols as isize {
            return None;
        }
        let (nr, nc) = (nr as usize, nc as usize);
        let to = nr * self.cols + nc;
        if !free[to] {
            return None;
        }
        if dr != 0 && dc != 0 && self.rule == MoveRule::Strict {
            // No corner cutting: both orthogonal cells the diagonal passes must be free.
            if !free[nr * self.cols + c] || !free[r * self.cols + nc] {
                return None;
            }
        }
        Some(to)
    }

    /// The cells of `item` the goal reaches by legal moves (the rules' moves are symmetric,
    /// so a search from the goal finds them).
    pub(super) fn reached(&self, item: usize) -> Vec<bool> {
        let n = self.cells();
        let free = &self.free[item * n..(item + 1) * n];
        let mut seen = vec![false; n];
        let goal = self.goals[item];
        if goal >= n || !free[goal] {
            return seen;
        }
        seen[goal] = true;
        let mut stack = vec![goal];
        while let Some(x) = stack.pop() {
            for k in 0..MOVES {
                if let Some(y) = self.step(free, x / self.cols, x % self.cols, k) {
                    if !seen[y] {
                        seen[y] = true;
                        stack.push(y);
                    }
                }
            }
        }
        seen
    }

    /// Dijkstra from the goal of `item` backwards over the moves: `v(x) = c_a(x) + v(x + a)`
    /// for the best legal move `a`. `costs` holds this item's `cells * 8` move costs.
    pub(super) fn solve(&self, item: usize, costs: &[f32]) -> Solved {
        let n = self.cells();
        let free = &self.free[item * n..(item + 1) * n];
        let goal = self.goals[item];
        let mut values = vec![f32::INFINITY; n];
        let mut first_move = vec![u8::MAX; n];
        let mut done = vec![false; n];
        let mut order = Vec::with_capacity(n);
        let mut heap = BinaryHeap::new();
        if goal < n && free[goal] {
            values[goal] = 0.0;
            heap.push(Reverse((0u32, goal as u32)));
        }
        while let Some(Reverse((bits, y))) = heap.pop() {
            let y = y as usize;
            if done[y] || f32::from_bits(bits) > values[y] {
                continue;
            }
            done[y] = true;
            order.push(y as u32);
            let (yr, yc) = (y / self.cols, y % self.cols);
            // Predecessors: cells x with a legal move k from x to y, i.e. x = y - d_k.
            for (k, &(dr, dc)) in DIRECTIONS_8.iter().enumerate() {
                let (xr, xc) = (yr as isize - dr, yc as isize - dc);
                if xr < 0 || xc < 0 || xr >= self.rows as isize || xc >= self.cols as isize {
                    continue;
                }
                let x = xr as usize * self.cols + xc as usize;
                if done[x] || !free[x] || self.step(free, xr as usize, xc as usize, k) != Some(y) {
                    continue;
                }
                let v = values[y] + costs[x * MOVES + k];
                if v < values[x] {
                    values[x] = v;
                    first_move[x] = k as u8;
                    // Non-negative floats order as their bits.
                    heap.push(Reverse((v.to_bits(), x as u32)));
                }
            }
        }
        let fill_source = fill_unreached(&mut values, self.rows, self.cols);
        Solved {
            values,
            first_move,
            order,
            fill_source,
        }
    }
}

/// Gives every unreached cell a finite value: one more than its least reached 8-neighbour
/// (so a bilinear sample beside a wall rises towards it), else [`UNREACHED`]. Returns, per
/// cell, the neighbour its value was taken from (`u32::MAX` for none).
fn fill_unreached(values: &mut [f32], rows: usize, cols: usize) -> Vec<u32> {
    let reached: Vec<bool> = values.iter().map(|v| v.is_finite()).collect();
    let mut source = vec![u32::MAX; values.len()];
    for i in 0..values.len() {
        if reached[i] {
            continue;
        }
        let (r, c) = (i / cols, i % cols);
        let mut best = f32::INFINITY;
        for &(dr, dc) in &DIRECTIONS_8 {
            let (nr, nc) = (r as isize + dr, c as isize + dc);
            if nr >= 0 && nc >= 0 && (nr as usize) < rows && (nc as usize) < cols {
                let j = nr as usize * cols + nc as usize;
                if reached[j] && values[j] < best {
                    best = values[j];
                    source[i] = j as u32;
                }
            }
        }
        values[i] = if best.is_finite() {
            best + 1.0
        } else {
            UNREACHED
        };
    }
    source
}

impl MinPlus {
    /// The costs as a contiguous f32 slice of `items * cells * 8`.
    fn check<'a>(&self, data: &'a [f32], what: &str) -> candle_core::Result<&'a [f32]> {
        let want = self.goals.len() * self.cells() * MOVES;
        if data.len() != want {
            candle_core::bail!(
                "min-plus {what}: {} costs for {} items of {}x{} cells and 8 moves",
                data.len(),
                self.goals.len(),
                self.rows,
                self.cols
            );
        }
        Ok(data)
    }
}

impl CustomOp1 for MinPlus {
    fn name(&self) -> &'static str {
        "min-plus-fixed-point"
    }

    fn cpu_fwd(
        &self,
        storage: &CpuStorage,
        layout: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let CpuStorage::F32(data) = storage else {
            candle_core::bail!("min-plus: costs must be f32");
        };
        let Some((start, end)) = layout.contiguous_offsets() else {
            candle_core::bail!("min-plus: costs must be contiguous");
        };
        let costs = self.check(&data[start..end], "forward")?;
        let n = self.cells();
        let mut out = Vec::with_capacity(self.goals.len() * n);
        for item in 0..self.goals.len() {
            out.extend(
                self.solve(item, &costs[item * n * MOVES..(item + 1) * n * MOVES])
                    .values,
            );
        }
        let shape = Shape::from((self.goals.len(), self.rows, self.cols, 1));
        Ok((CpuStorage::F32(out), shape))
    }

    fn bwd(
        &self,
        arg: &Tensor,
        _res: &Tensor,
        grad_res: &Tensor,
    ) -> candle_core::Result<Option<Tensor>> {
        let costs = arg.flatten_all()?.to_vec1::<f32>()?;
        let costs = self.check(&costs, "backward")?;
        let grad = grad_res.flatten_all()?.to_vec1::<f32>()?;
        let n = self.cells();
        let mut out = vec![0f32; costs.len()];
        for item in 0..self.goals.len() {
            let solved = self.solve(item, &costs[item * n * MOVES..(item + 1) * n * MOVES]);
            // Each cell's gradient, then its branch's, flows to the cell its first move
            // reaches: settled later means farther down the tree, so reverse order visits
            // every cell after all the cells whose paths pass through it.
            let mut acc = grad[item * n..(item + 1) * n].to_vec();
            // An unreached cell's value is its source's plus one.
            for (i, &j) in solved.fill_source.iter().enumerate() {
                if j != u32::MAX {
                    acc[j as usize] += acc[i];
                }
            }
            let g = &mut out[item * n * MOVES..(item + 1) * n * MOVES];
            for &x in solved.order.iter().rev() {
                let x = x as usize;
                let k = solved.first_move[x];
                if k == u8::MAX {
                    continue;
                }
                let k = k as usize;
                g[x * MOVES + k] += acc[x];
                let (dr, dc) = DIRECTIONS_8[k];
                let y = ((x / self.cols) as isize + dr) as usize * self.cols
                    + ((x % self.cols) as isize + dc) as usize;
                acc[y] += acc[x];
            }
        }
        Ok(Some(Tensor::from_vec(out, arg.shape(), arg.device())?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{Device, Var};

    fn op(rows: usize, cols: usize, walls: &[usize], goal: usize, rule: MoveRule) -> MinPlus {
        let mut free = vec![true; rows * cols];
        for &w in walls {
            free[w] = false;
        }
        MinPlus {
            rows,
            cols,
            free,
            goals: vec![goal],
            rule,
        }
    }

    /// With unit orthogonal and sqrt 2 diagonal costs the fixed point is the graph distance
    /// under the rule, computed here by hand on a 3x3 grid with a wall in the middle.
    #[test]
    fn exact_costs_give_the_graph_distance() {
        let costs: Vec<f32> = (0..9)
            .flat_map(|_| {
                [
                    1.0,
                    1.0,
                    1.0,
                    1.0,
                    2f32.sqrt(),
                    2f32.sqrt(),
                    2f32.sqrt(),
                    2f32.sqrt(),
                ]
            })
            .collect();
        let strict = op(3, 3, &[4], 0, MoveRule::Strict).solve(0, &costs);
        // Around the wall: (0,2) is 2 away, (2,2) 4 (no diagonal past the wall's corners).
        assert_eq!(strict.values[2], 2.0);
        assert_eq!(strict.values[8], 4.0);
        // The wall is unreached: one more than its least reached neighbour, the goal.
        assert_eq!(strict.values[4], 1.0);
        assert_eq!(strict.first_move[4], u8::MAX);
        let vin = op(3, 3, &[4], 0, MoveRule::Vin).solve(0, &costs);
        assert!((vin.values[8] - (2.0 + 2f32.sqrt())).abs() < 1e-6);
    }

    /// Whatever the (positive) costs, every reached cell but the goal has a legal move to a
    /// strictly smaller value, under both rules: descent on the fixed point cannot stall.
    #[test]
    fn random_costs_leave_no_local_minimum() {
        let mut rng = envfield_grid::SplitMix64::new(17);
        for trial in 0..40 {
            let (rows, cols) = (3 + rng.below(9), 3 + rng.below(9));
            let n = rows * cols;
            let walls: Vec<usize> = (0..n).filter(|_| rng.below(3) == 0).collect();
            let goal = (0..n).find(|i| !walls.contains(i)).unwrap_or(0);
            if walls.contains(&goal) {
                continue;
            }
            let costs: Vec<f32> = (0..n * MOVES)
                .map(|_| 0.05 + 10.0 * rng.below(1000) as f32 / 1000.0)
                .collect();
            for rule in [MoveRule::Strict, MoveRule::Vin] {
                let mp = op(rows, cols, &walls, goal, rule);
                let solved = mp.solve(0, &costs);
                let reached = mp.reached(0);
                for x in (0..n).filter(|&x| reached[x] && x != goal) {
                    let k = solved.first_move[x] as usize;
                    let y = mp
                        .step(&mp.free, x / cols, x % cols, k)
                        .expect("a legal move");
                    assert!(
                        solved.values[y] < solved.values[x],
                        "trial {trial} {rule}: cell {x}"
                    );
                }
                // Exactly the reached cells have a first move (or are the goal).
                for x in 0..n {
                    assert_eq!(reached[x], x == goal || solved.first_move[x] != u8::MAX);
                }
            }
        }
    }

    /// The op's gradient matches central finite differences of a weighted sum of the values,
    /// wherever the sum is differentiable: a cost whose nudge switches a shortest path (the two
    /// one-sided differences disagree) has no derivative to match, and is left out.
    #[test]
    fn gradient_matches_finite_differences() -> Result<()> {
        let device = Device::Cpu;
        let (rows, cols) = (4, 5);
        let mp = op(rows, cols, &[6, 7, 13], 0, MoveRule::Strict);
        // Seeded: candle's `rand` is not, and a draw with two paths tied within the step made
        // this test fail now and then.
        let mut rng = envfield_grid::SplitMix64::new(7);
        let mut draw = |n: usize, lo: f32, hi: f32| -> Vec<f32> {
            (0..n).map(|_| lo + (hi - lo) * rng.next_f32()).collect()
        };
        let base = Tensor::from_vec(
            draw(rows * cols * MOVES, 0.5, 2.0),
            (1, rows, cols, MOVES),
            &device,
        )?;
        let weights = Tensor::from_vec(draw(rows * cols, 0.0, 1.0), (1, rows, cols, 1), &device)?;
        let var = Var::from_tensor(&base)?;
        let loss = |t: &Tensor| -> Result<Tensor> {
            Ok((t.apply_op1(mp.clone())? * &weights)?.sum_all()?)
        };
        let grads = loss(var.as_tensor())?.backward()?;
        let g = grads
            .get(var.as_tensor())
            .expect("gradient")
            .flatten_all()?;
        let g = g.to_vec1::<f32>()?;
        let x = base.flatten_all()?.to_vec1::<f32>()?;
        let eps = 1e-3f32;
        let mut checked = 0;
        for i in 0..x.len() {
            let at = |d: f32| -> Result<f32> {
                let mut y = x.clone();
                y[i] += d;
                let t = Tensor::from_vec(y, (1, rows, cols, MOVES), &device)?;
                Ok(loss(&t)?.to_scalar::<f32>()?)
            };
            let (up, mid, down) = (at(eps)?, at(0.0)?, at(-eps)?);
            if ((up - mid) - (mid - down)).abs() / eps > 1e-2 {
                continue; // a kink: the nudge switches a shortest path
            }
            let fd = (up - down) / (2.0 * eps);
            assert!(
                (fd - g[i]).abs() < 2e-2,
                "cost {i}: analytic {} numeric {fd}",
                g[i]
            );
            checked += (g[i] != 0.0) as usize;
        }
        assert!(checked > 5, "only {checked} costs carry a gradient");
        Ok(())
    }
}
