//! The shortest-path readout driven from the network: the min-plus problem of a batch, the
//! readout's forward pass, the learned move costs (one encoder pass for many grids, or the
//! union of near-identical grids and a window per grid), and whole fields by Dijkstra.

use super::path::{MinPlus, PathLayer, MOVES};
use super::{FieldNet, Net, MAX_FIELD_CELLS};
use crate::layers::sample_features;
use crate::{Batch, ModelConfig, NetsError, Result, TargetEncoding};
use candle_core::Tensor;
use envfield_grid::{Cell2, Field2, Grid2, MoveRule, Neighbourhood2, DIRECTIONS_8};
use rayon::prelude::*;

impl FieldNet {
    /// The min-plus problem of `batch`: its free cells, goals and this network's rule.
    pub(super) fn min_plus(&self, batch: &Batch) -> MinPlus {
        let (rows, cols) = (batch.extent[0], batch.extent[1]);
        MinPlus {
            rows,
            cols,
            free: batch.obstacles.iter().map(|&o| o < 0.5).collect(),
            goals: (0..batch.items)
                .map(|b| {
                    let (r, c) = (batch.goals[2 * b].round(), batch.goals[2 * b + 1].round());
                    r as usize * cols + c as usize
                })
                .collect(),
            rule: self.rule,
        }
    }

    /// The shortest-path readout: move costs from `features`, the fixed point over them, its
    /// bilinear sample at the queries, encoded, and [`crate::BLOCKED`] where the query's
    /// cell is not reached from the goal.
    pub(super) fn path_readout(
        &self,
        layer: &PathLayer,
        features: &Tensor,
        batch: &Batch,
        queries: &Tensor,
        encoding: TargetEncoding,
        track: bool,
    ) -> Result<Tensor> {
        let costs = layer.costs(features)?;
        let costs = if track { costs } else { costs.detach() };
        let problem = self.min_plus(batch);
        let (rows, cols) = (problem.rows, problem.cols);
        let reached: Vec<Vec<bool>> = (0..batch.items).map(|b| problem.reached(b)).collect();
        let values = costs.contiguous()?.apply_op1(problem)?;
        let points: Vec<[f32; 2]> = batch
            .queries
            .chunks_exact(2)
            .map(|p| [p[0], p[1]])
            .collect();
        let rows_t = queries.narrow(1, 0, 1)?;
        let cols_t = queries.narrow(1, 1, 1)?;
        let v = sample_features(&values, &points, batch.per_item, &rows_t, &cols_t)?;
        let mask: Vec<f32> = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let (r, c) = (p[0].round() as usize, p[1].round() as usize);
                let inside = r < rows && c < cols;
                (inside && reached[i / batch.per_item][r * cols + c]) as u8 as f32
            })
            .collect();
        let n = mask.len();
        let mask = Tensor::from_vec(mask, (n, 1), &self.device)?;
        // Path values are never negative; the linear encoding stops at 0 past its scale.
        let encoded = encoding.encode_tensor(&v)?.relu()?;
        Ok(((encoded * &mask)? + (mask - 1.0)?)?)
    }

    /// The learned move costs of a shortest-path readout on `grid` (in cells), eight per cell
    /// in [`envfield_grid::DIRECTIONS_8`] order, cells row-major; every move is costed,
    /// legal or not (the recurrence takes only the legal ones). What the network learned, to
    /// set beside the exact 1 and sqrt 2.
    ///
    /// # Errors
    /// [`NetsError::InvalidInput`] for a network without a shortest-path readout or a grid
    /// of more than [`MAX_FIELD_CELLS`] cells.
    pub fn move_costs(&self, grid: &Grid2) -> Result<Vec<[f32; 8]>> {
        if grid.len() > MAX_FIELD_CELLS {
            return Err(NetsError::InvalidInput(format!(
                "a {}x{} grid is more than {MAX_FIELD_CELLS} cells",
                grid.rows(),
                grid.cols()
            )));
        }
        let costs = self.flat_costs(&[grid])?;
        Ok(costs
            .chunks_exact(MOVES)
            .map(|m| std::array::from_fn(|k| m[k]))
            .collect())
    }

    /// The learned costs of the legal moves of `grid` under `rule` (each free cell's moves
    /// that the rule allows), split into orthogonal and diagonal ones: what the network
    /// learned of a move's length, to set beside the exact 1 and sqrt 2.
    ///
    /// # Errors
    /// As [`FieldNet::move_costs`].
    pub fn legal_move_costs(&self, grid: &Grid2, rule: MoveRule) -> Result<(Vec<f32>, Vec<f32>)> {
        let costs = self.move_costs(grid)?;
        let (mut orthogonal, mut diagonal) = (Vec::new(), Vec::new());
        for cell in grid.free_cells() {
            let i = cell.row * grid.cols() + cell.col;
            for (next, _) in grid.neighbours(cell, Neighbourhood2::Eight(rule)) {
                let d = (
                    next.row as isize - cell.row as isize,
                    next.col as isize - cell.col as isize,
                );
                let Some(k) = DIRECTIONS_8.iter().position(|&m| m == d) else {
                    continue;
                };
                match d.0 == 0 || d.1 == 0 {
                    true => orthogonal.push(costs[i][k]),
                    false => diagonal.push(costs[i][k]),
                }
            }
        }
        Ok((orthogonal, diagonal))
    }

    /// The move costs of `grids` (all of one size), `grids * cells * 8` values, through the
    /// inference path (no gradients) and one encoder pass: what [`FieldNet::move_costs`] and
    /// the whole-field predictions share.
    pub(super) fn flat_costs(&self, grids: &[&Grid2]) -> Result<Vec<f32>> {
        let (
            Net::Context {
                encoder,
                path: Some(layer),
                ..
            },
            ModelConfig::Context(c),
        ) = (&self.net, &self.config)
        else {
            return Err(NetsError::InvalidInput(format!(
                "a {} network without a shortest-path readout has no move costs",
                self.config.arch()
            )));
        };
        let Some(first) = grids.first() else {
            return Ok(Vec::new());
        };
        // The costs do not depend on the goal (no goal channel), so any cell serves.
        let batch = Batch {
            extent: vec![first.rows(), first.cols()],
            items: grids.len(),
            obstacles: grids
                .iter()
                .flat_map(|g| g.obstacles().iter().map(|&o| o as u8 as f32))
                .collect(),
            goals: vec![0.0; 2 * grids.len()],
            per_item: 0,
            queries: Vec::new(),
        };
        let input = self.grid_input(&batch, c.goal_channel)?;
        let features = encoder.forward_inference(&input)?;
        Ok(layer.costs(&features)?.flatten_all()?.to_vec1::<f32>()?)
    }

    /// How far a cell's move costs see: the sum of the encoder's dilations (3x3 kernels), or
    /// `None` when a stride or value-iteration layers make costs depend on more than a window.
    fn receptive_radius(&self) -> Option<usize> {
        let ModelConfig::Context(c) = &self.config else {
            return None;
        };
        let plain = c.propagation.is_none() && c.encoder.iter().all(|s| s.stride == 1);
        plain.then(|| c.encoder.iter().map(|s| s.dilation).sum())
    }

    /// [`FieldNet::flat_costs`] of same-sized `grids` that are one map changed in a few small
    /// places (several people's maps of one time step: the floor and everyone else's disc).
    /// The encoder runs once on their union (every cell blocked in any of them) and, for each
    /// grid, on a window around where it differs from the union; costs farther than the
    /// receptive radius from a difference are the union's. Grids that differ widely take the
    /// plain batched pass. Either way the costs are the plain pass's.
    fn batch_costs(&self, grids: &[&Grid2]) -> Result<Vec<f32>> {
        let (Some(radius), Some(first), true) =
            (self.receptive_radius(), grids.first(), grids.len() > 1)
        else {
            return self.flat_costs(grids);
        };
        let (rows, cols) = (first.rows(), first.cols());
        let n = rows * cols;
        let union: Vec<bool> = (0..n)
            .map(|k| grids.iter().any(|g| g.obstacles()[k]))
            .collect();
        // Per grid, the cells whose costs may differ from the union's: the bounding box of
        // its differences grown by the radius, as inclusive (r0, r1, c0, c1).
        let windows: Vec<Option<[usize; 4]>> = grids
            .iter()
            .map(|g| {
                let diff = (0..n).filter(|&k| union[k] && !g.obstacles()[k]);
                diff.fold(None, |b: Option<[usize; 4]>, k| {
                    let (r, c) = (k / cols, k % cols);
                    Some(b.map_or([r, r, c, c], |[r0, r1, c0, c1]| {
                        [r0.min(r), r1.max(r), c0.min(c), c1.max(c)]
                    }))
                })
                .map(|[r0, r1, c0, c1]| {
                    [
                        r0.saturating_sub(radius),
                        (r1 + radius).min(rows - 1),
                        c0.saturating_sub(radius),
                        (c1 + radius).min(cols - 1),
                    ]
                })
            })
            .collect();
        // One crop size for all, so the crops go through the encoder as one batch: each
        // window and the radius around it (clamped to the map, whose edge pads alike).
        let (ch, cw) = windows
            .iter()
            .flatten()
            .fold((0, 0), |(h, w), &[r0, r1, c0, c1]| {
                (
                    h.max((r1 - r0 + 1 + 2 * radius).min(rows)),
                    w.max((c1 - c0 + 1 + 2 * radius).min(cols)),
                )
            });
        let crops_cells = ch * cw * windows.iter().flatten().count();
        if 2 * (n + crops_cells) > n * grids.len() {
            return self.flat_costs(grids);
        }
        let union_grid = Grid2::from_obstacles(rows, cols, union)?;
        let base = self.flat_costs(&[&union_grid])?;
        let mut origins = Vec::new();
        let mut crops = Vec::new();
        for (g, w) in grids.iter().zip(&windows) {
            let Some([r0, _, c0, _]) = *w else { continue };
            let (cr, cc) = (
                r0.saturating_sub(radius).min(rows - ch),
                c0.saturating_sub(radius).min(cols - cw),
            );
            let cells = (0..ch * cw)
                .map(|k| g.obstacles()[(cr + k / cw) * cols + cc + k % cw])
                .collect();
            crops.push(Grid2::from_obstacles(ch, cw, cells)?);
            origins.push((cr, cc));
        }
        let crop_costs = self.flat_costs(&crops.iter().collect::<Vec<_>>())?;
        let mut out = Vec::with_capacity(grids.len() * n * MOVES);
        let mut k = 0;
        for w in &windows {
            let start = out.len();
            out.extend_from_slice(&base);
            let Some([r0, r1, c0, c1]) = *w else { continue };
            let (cr, cc) = origins[k];
            let crop = &crop_costs[k * ch * cw * MOVES..(k + 1) * ch * cw * MOVES];
            k += 1;
            for r in r0..=r1 {
                for c in c0..=c1 {
                    let to = start + (r * cols + c) * MOVES;
                    let from = ((r - cr) * cw + (c - cc)) * MOVES;
                    out[to..to + MOVES].copy_from_slice(&crop[from..from + MOVES]);
                }
            }
        }
        Ok(out)
    }

    /// The fields of a network with a shortest-path readout for same-sized `problems`: the
    /// encoder and the costs without gradients in one pass, then one Dijkstra pass per
    /// problem (in parallel); cells the goal does not reach are infinite.
    pub(super) fn path_fields(&self, problems: &[(&Grid2, Cell2)]) -> Result<Vec<Field2>> {
        let grids: Vec<&Grid2> = problems.iter().map(|&(g, _)| g).collect();
        let costs = self.batch_costs(&grids)?;
        let Some(&(first, _)) = problems.first() else {
            return Ok(Vec::new());
        };
        let (rows, cols) = (first.rows(), first.cols());
        let n = rows * cols;
        debug_assert_eq!(costs.len(), problems.len() * n * MOVES);
        let problem = MinPlus {
            rows,
            cols,
            free: grids
                .iter()
                .flat_map(|g| g.obstacles().iter().map(|&o| !o))
                .collect(),
            goals: problems
                .iter()
                .map(|&(_, goal)| goal.row * cols + goal.col)
                .collect(),
            rule: self.rule,
        };
        (0..problems.len())
            .into_par_iter()
            .map(|b| {
                let solved = problem.solve(b, &costs[b * n * MOVES..(b + 1) * n * MOVES]);
                let goal_index = problem.goals[b];
                let values = solved
                    .values
                    .iter()
                    .zip(&solved.first_move)
                    .enumerate()
                    .map(|(i, (&v, &m))| match m != u8::MAX || i == goal_index {
                        true => v,
                        false => f32::INFINITY,
                    })
                    .collect();
                Ok(Field2::new(rows, cols, values)?)
            })
            .collect()
    }
}
