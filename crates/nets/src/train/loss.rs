//! The losses beyond L1: the neighbour-difference loss and the descent hinge, on queries laid
//! out in groups of an anchor and its neighbours.

use crate::{Batch, NetsError, Result};
use candle_core::{Device, Tensor};
use envfield_grid::{Cell2, Grid2, MoveRule, DIRECTIONS_8};

/// Queries per group of the descent loss: an anchor cell and its 8 neighbours.
pub(crate) const GROUP: usize = 9;

/// The groups of a batch sampled for the descent loss (anchor, then 8 neighbours), read back
/// from the queries and targets, each as (groups, 8) masks and values: which neighbours are
/// moves, how much each should rise above the anchor, which are the best moves, and by how much
/// each other move should score below them.
pub(crate) struct Groups {
    pub(crate) count: usize,
    /// 1 where neighbour `j` of group `g` (at `g * 8 + j`) is a reachable move.
    valid: Vec<f32>,
    /// True encoded output of the neighbour minus the anchor's.
    rise: Vec<f32>,
    /// 1 for the best moves (least true distance), in groups with a decision to make.
    winner: Vec<f32>,
    /// 1 for the other moves of those groups.
    other: Vec<f32>,
    /// The margin each other move should keep below the best: `margin.min(true gap)`.
    margin: Vec<f32>,
    /// Groups whose anchor is reachable, not the goal, and has a move.
    decisions: usize,
    /// Total weight of those groups (each group's weight scales its moves in `valid` and
    /// `other`).
    decision_weight: f32,
}

impl Groups {
    /// The groups of a batch sampled in groups of nine queries.
    pub(crate) fn new(batch: &Batch, targets: &[f32], margin: f32) -> Result<Self> {
        if batch.len() % GROUP != 0 || batch.per_item % GROUP != 0 {
            return Err(NetsError::InvalidInput(format!(
                "the descent loss needs queries in groups of {GROUP} per item (got {} per item)",
                batch.per_item
            )));
        }
        let count = batch.len() / GROUP;
        let mut moved = Vec::with_capacity(count * (GROUP - 1));
        let mut at_goal = Vec::with_capacity(count);
        for g in 0..count {
            let q = &batch.queries[2 * g * GROUP..][..2 * GROUP];
            let item = g * GROUP / batch.per_item;
            at_goal.push(q[..2] == batch.goals[2 * item..][..2]);
            moved.extend((1..GROUP).map(|j| q[2 * j..][..2] != q[..2]));
        }
        let weight = vec![1.0; count];
        Ok(Self::from_parts(targets, &moved, &at_goal, &weight, margin))
    }

    /// The groups of a dense batch (every cell of each item, row-major): one per reachable
    /// cell, with the indices into the batch's outputs that lay them out as groups of nine
    /// (a neighbour that is not a move under `rule` is the anchor again). Reachability comes
    /// from the targets (negative = blocked), which is all `rule` needs: a free cell next to a
    /// reachable one is reachable.
    ///
    /// With `detour_share` > 0, the groups of each item's detour cells (see
    /// [`crate::TrainConfig::detour_fraction`]; `distance` decodes a target into cells) carry that
    /// share of the item's weight, the rest the other cells.
    pub(crate) fn dense(
        batch: &Batch,
        targets: &[f32],
        rule: MoveRule,
        margin: f32,
        detour_share: f32,
        distance: impl Fn(f32) -> f32,
    ) -> Result<(Self, Vec<u32>)> {
        let (rows, cols) = match batch.extent[..] {
            [rows, cols] if rows * cols == batch.per_item => (rows, cols),
            _ => {
                return Err(NetsError::InvalidInput(format!(
                    "dense training needs every cell of a 2D grid per item ({:?} cells, {} \
                     queries per item)",
                    batch.extent, batch.per_item
                )))
            }
        };
        let cells = rows * cols;
        let mut index = Vec::new();
        let mut grouped = Vec::new();
        let mut moved = Vec::new();
        let mut at_goal = Vec::new();
        let mut weight = Vec::new();
        for (item, t) in targets.chunks_exact(cells).enumerate() {
            let blocked = t.iter().map(|&v| v < 0.0).collect();
            let grid = Grid2::from_obstacles(rows, cols, blocked)?;
            let goal = &batch.goals[2 * item..][..2];
            let base = item * cells;
            let detour: Vec<bool> = (0..cells)
                .map(|i| {
                    let cell = Cell2::new(i / cols, i % cols);
                    let goal = Cell2::new(goal[0] as usize, goal[1] as usize);
                    t[i] >= 0.0 && super::sampler::is_detour(distance(t[i]), cell, goal)
                })
                .collect();
            let detours = detour.iter().filter(|&&d| d).count();
            let plain = (0..cells).filter(|&i| t[i] >= 0.0).count() - detours;
            let (w_detour, w_plain) = if detour_share > 0.0 && detours > 0 && plain > 0 {
                let total = (detours + plain) as f32;
                (
                    detour_share * total / detours as f32,
                    (1.0 - detour_share) * total / plain as f32,
                )
            } else {
                (1.0, 1.0)
            };
            for i in (0..cells).filter(|&i| t[i] >= 0.0) {
                let from = Cell2::new(i / cols, i % cols);
                at_goal.push(goal == [from.row as f32, from.col as f32]);
                weight.push(if detour[i] { w_detour } else { w_plain });
                index.push((base + i) as u32);
                grouped.push(t[i]);
                for &(dr, dc) in &DIRECTIONS_8 {
                    let allowed = rule.allows(&grid, from, dr, dc);
                    let j = if allowed {
                        (i as isize + dr * cols as isize + dc) as usize
                    } else {
                        i
                    };
                    index.push((base + j) as u32);
                    grouped.push(t[j]);
                    moved.push(allowed);
                }
            }
        }
        let groups = Self::from_parts(&grouped, &moved, &at_goal, &weight, margin);
        Ok((groups, index))
    }

    /// Groups from their targets (nine per group: anchor first), whether each neighbour is a
    /// move (eight per group), whether each anchor is the goal, and each group's weight.
    fn from_parts(
        targets: &[f32],
        moved: &[bool],
        at_goal: &[bool],
        weight: &[f32],
        margin: f32,
    ) -> Self {
        let count = at_goal.len();
        let n = GROUP - 1;
        let zeros = || vec![0f32; count * n];
        let mut groups = Self {
            count,
            valid: zeros(),
            rise: zeros(),
            winner: zeros(),
            other: zeros(),
            margin: zeros(),
            decisions: 0,
            decision_weight: 0.0,
        };
        for g in 0..count {
            let t = &targets[g * GROUP..][..GROUP];
            let row = g * n..(g + 1) * n;
            let valid = &mut groups.valid[row.clone()];
            for j in 0..n {
                if t[0] >= 0.0 && t[j + 1] >= 0.0 && moved[g * n + j] {
                    valid[j] = weight[g];
                    groups.rise[g * n + j] = t[j + 1] - t[0];
                }
            }
            let best = (0..n)
                .filter(|&j| valid[j] > 0.0)
                .map(|j| t[j + 1])
                .fold(f32::NEG_INFINITY, f32::max);
            if best == f32::NEG_INFINITY || at_goal[g] {
                continue;
            }
            for j in (0..n).filter(|&j| valid[j] > 0.0) {
                // Ties within float noise of the encoding are all best moves.
                let gap = best - t[j + 1];
                if gap <= 1e-6 {
                    groups.winner[g * n + j] = 1.0;
                } else {
                    groups.other[g * n + j] = weight[g];
                    groups.margin[g * n + j] = gap.min(margin);
                }
            }
            groups.decisions += 1;
            groups.decision_weight += weight[g];
        }
        groups
    }

    /// (groups, 8) values as a tensor on `device`.
    fn tensor(&self, values: &[f32], device: &Device) -> Result<Tensor> {
        Ok(Tensor::from_vec(
            values.to_vec(),
            (self.count, GROUP - 1),
            device,
        )?)
    }

    /// The anchor's and the neighbours' outputs, (groups, 1) and (groups, 8), of the batch's
    /// outputs `pred` (one per query).
    fn split(&self, pred: &Tensor) -> Result<(Tensor, Tensor)> {
        let pred = pred.reshape((self.count, GROUP))?;
        Ok((pred.narrow(1, 0, 1)?, pred.narrow(1, 1, GROUP - 1)?))
    }

    /// Mean L1 error of each move's predicted rise above its anchor.
    pub(crate) fn slope_loss(&self, pred: &Tensor) -> Result<Tensor> {
        rise_loss(pred, GROUP, self.rise.clone(), self.valid.clone())
    }

    /// The descent hinge (see [`crate::TrainConfig::descent_weight`]) averaged over the groups with a
    /// decision; `None` when no group has one.
    pub(crate) fn descent_loss(&self, pred: &Tensor) -> Result<Option<Tensor>> {
        if self.decisions == 0 {
            return Ok(None);
        }
        let device = pred.device();
        let (_, neighbours) = self.split(pred)?;
        // The best output among the best moves (others pushed far below), then each other
        // move's shortfall from the margin.
        let shut = ((self.tensor(&self.winner, device)? - 1.0)? * 1e4)?;
        let best = (&neighbours + shut)?.max_keepdim(1)?;
        let gap = best.broadcast_sub(&neighbours)?;
        let hinge = (self.tensor(&self.margin, device)? - gap)?.relu()?;
        let others = self.tensor(&self.other, device)?;
        Ok(Some(
            ((hinge * others)?.sum_all()? / self.decision_weight as f64)?,
        ))
    }
}

/// The neighbour-difference loss on outputs `pred` laid out in groups of `size` (an anchor,
/// then `size - 1` others): the L1 error of each other output's rise above its anchor against
/// the true `rise`, averaged over the pairs with the weights in `valid` (0 leaves a pair out;
/// 1 for a plain mean). `rise` and `valid` hold
/// (groups, size - 1) values.
pub(crate) fn rise_loss(
    pred: &Tensor,
    size: usize,
    rise: Vec<f32>,
    valid: Vec<f32>,
) -> Result<Tensor> {
    let groups = pred.elem_count() / size;
    let pred = pred.reshape((groups, size))?;
    let (anchor, others) = (pred.narrow(1, 0, 1)?, pred.narrow(1, 1, size - 1)?);
    let pairs = valid.iter().sum::<f32>().max(1.0);
    let shape = (groups, size - 1);
    let truth = Tensor::from_vec(rise, shape, pred.device())?;
    let valid = Tensor::from_vec(valid, shape, pred.device())?;
    let err = (others.broadcast_sub(&anchor)? - truth)?.abs()?;
    Ok(((err * valid)?.sum_all()? / pairs as f64)?)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::TargetEncoding;
    use candle_core::Device;
    use envfield_grid::MoveRule;

    /// A 3x3 room, goal in the top-right corner, one group anchored at the centre under the
    /// linear encoding `1 - d/100`: slot 2 (left) is not a move (the anchor again), slot 4
    /// (top-left) is blocked, slot 5 (top-right) is the goal and the only best move.
    fn one_group(anchor_at_goal: bool) -> (Batch, Vec<f32>) {
        let t = |d: f32| 1.0 - d / 100.0;
        let s2 = std::f32::consts::SQRT_2;
        let mut queries = vec![1.0, 1.0, 0.0, 1.0, 2.0, 1.0, 1.0, 1.0, 1.0, 2.0];
        queries.extend([0.0, 0.0, 0.0, 2.0, 2.0, 0.0, 2.0, 2.0]);
        let targets = vec![
            t(s2),
            t(1.0),
            t(1.0 + s2),
            t(s2),
            t(1.0),
            -1.0,
            t(0.0),
            t(2.0 * s2),
            t(2.0),
        ];
        let goal = if anchor_at_goal {
            [1.0, 1.0]
        } else {
            [0.0, 2.0]
        };
        let batch = Batch {
            extent: vec![3, 3],
            items: 1,
            obstacles: vec![0.0; 9],
            goals: goal.to_vec(),
            per_item: GROUP,
            queries,
        };
        (batch, targets)
    }

    #[test]
    fn groups_read_back_moves_best_moves_and_margins() {
        let (batch, targets) = one_group(false);
        let g = Groups::new(&batch, &targets, 0.005).unwrap();
        assert_eq!(g.decisions, 1);
        assert_eq!(g.valid, [1.0, 1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0]);
        assert_eq!(g.winner, [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
        assert_eq!(g.other, [1.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0]);
        for (j, &m) in g.margin.iter().enumerate() {
            assert_eq!(m, if g.other[j] > 0.0 { 0.005 } else { 0.0 }, "slot {j}");
        }
        // Standing on the goal there is no decision.
        let (batch, targets) = one_group(true);
        assert_eq!(Groups::new(&batch, &targets, 0.005).unwrap().decisions, 0);
    }

    #[test]
    fn the_exact_field_scores_zero_and_a_wrong_ranking_pays_its_shortfall() {
        let (batch, targets) = one_group(false);
        let g = Groups::new(&batch, &targets, 0.005).unwrap();
        let loss = |pred: &[f32]| -> (f32, f32) {
            let pred = Tensor::from_vec(pred.to_vec(), pred.len(), &Device::Cpu).unwrap();
            let descent = g.descent_loss(&pred).unwrap().unwrap();
            let slope = g.slope_loss(&pred).unwrap();
            (
                descent.to_scalar::<f32>().unwrap(),
                slope.to_scalar::<f32>().unwrap(),
            )
        };
        assert_eq!(loss(&targets), (0.0, 0.0));
        // The top neighbour (slot 0) now scores 0.001 above the goal: a shortfall of 0.006.
        let mut wrong = targets.clone();
        wrong[1] = targets[6] + 0.001;
        let (descent, slope) = loss(&wrong);
        assert!((descent - 0.006).abs() < 1e-6, "{descent}");
        // Its rise above the anchor is off by the same change, over 6 moves.
        let change = wrong[1] - targets[1];
        assert!((slope - change / 6.0).abs() < 1e-6, "{slope}");
    }

    /// A dense 3x3 batch: walls at (0,1) and (1,1), goal (0,2), exact `vin`-rule distances
    /// under `1 - d/100`. Cells (0,0), (1,0) and (2,0) are detour cells.
    pub(crate) fn dense_room() -> (Batch, Vec<f32>) {
        let s2 = std::f32::consts::SQRT_2;
        let d = [
            2.0 + 2.0 * s2,
            f32::INFINITY,
            0.0,
            1.0 + 2.0 * s2,
            f32::INFINITY,
            1.0,
            2.0 + s2,
            1.0 + s2,
            2.0,
        ];
        let targets = d
            .iter()
            .map(|&d| TargetEncoding::Linear { scale: 100.0 }.encode(d));
        let queries = (0..9)
            .flat_map(|i| [(i / 3) as f32, (i % 3) as f32])
            .collect();
        let batch = Batch {
            extent: vec![3, 3],
            items: 1,
            obstacles: Vec::new(),
            goals: vec![0.0, 2.0],
            per_item: 9,
            queries,
        };
        (batch, targets.collect())
    }

    #[test]
    fn dense_groups_gather_every_reachable_cell_with_its_moves() {
        let (batch, targets) = dense_room();
        let decode = |t: f32| TargetEncoding::Linear { scale: 100.0 }.decode(t);
        let (g, index) =
            Groups::dense(&batch, &targets, MoveRule::Vin, 0.005, 0.0, decode).unwrap();
        // Seven reachable cells, six decisions (none on the goal).
        assert_eq!((g.count, g.decisions), (7, 6));
        // The group of (2,1), the sixth reachable cell: up and down-left/right are not moves
        // (the anchor again); up-left (1,0) and up-right (1,2) are, under the vin rule.
        assert_eq!(index[5 * GROUP..6 * GROUP], [7, 7, 7, 6, 8, 3, 5, 7, 7]);
        let (_, strict) =
            Groups::dense(&batch, &targets, MoveRule::Strict, 0.005, 0.0, decode).unwrap();
        assert_eq!(strict[5 * GROUP..6 * GROUP], [7, 7, 7, 6, 8, 7, 7, 7, 7]);
        // The exact field scores zero; gathered outputs are read through `index`.
        let pred = Tensor::from_vec(targets.clone(), 9, &Device::Cpu).unwrap();
        let idx = Tensor::from_vec(index, g.count * GROUP, &Device::Cpu).unwrap();
        let gathered = pred.index_select(&idx, 0).unwrap();
        let descent = g.descent_loss(&gathered).unwrap().unwrap();
        assert_eq!(descent.to_scalar::<f32>().unwrap(), 0.0);
        assert_eq!(
            g.slope_loss(&gathered).unwrap().to_scalar::<f32>().unwrap(),
            0.0
        );
        // Detour share 0.5: the three detour cells weigh 7/6 each, the four others 7/8.
        let (w, _) = Groups::dense(&batch, &targets, MoveRule::Vin, 0.005, 0.5, decode).unwrap();
        let expected = 3.0 * 7.0 / 6.0 + 3.0 * 7.0 / 8.0;
        assert!(
            (w.decision_weight - expected).abs() < 1e-5,
            "{}",
            w.decision_weight
        );
    }
}
