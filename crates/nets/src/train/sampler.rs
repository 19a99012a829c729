//! The batch sampler: which mazes and cells each step trains on, seeded by the step.

use super::loss::GROUP;
use super::Trainer;
use crate::{Batch, NetsError, Result};
use envfield_grid::{is_wrong_move, octile_distance, Cell2, SplitMix64, DIRECTIONS_8};
use envfield_mazes::{Dataset, Sample};

impl Trainer {
    /// The training batch of step `step` from `data` and its targets (in the network's
    /// encoding): `batch_items` random samples, `queries_per_item` random cells each, seeded by
    /// the config's seed and the step, so a resumed run draws the same batches as an
    /// uninterrupted one.
    ///
    /// # Errors
    /// [`NetsError::InvalidInput`] for an empty dataset.
    pub fn sample_batch(&self, data: &Dataset, step: u64) -> Result<(Batch, Vec<f32>)> {
        if data.samples.is_empty() {
            return Err(NetsError::InvalidInput("empty dataset".into()));
        }
        let mut rng = SplitMix64::new(
            self.config
                .seed
                .wrapping_mul(0x9E37_79B9)
                .wrapping_add(step),
        );
        let first = &data.samples[0];
        let (rows, cols) = (first.grid.rows(), first.grid.cols());
        let b = self.config.batch_items;
        let q = if self.config.dense {
            rows * cols
        } else {
            self.config.queries_per_item
        };
        let reads_grid = self.net.config().reads_grid();
        let encoding = self.net.config().encoding();
        let mut batch = Batch {
            extent: vec![rows, cols],
            items: b,
            obstacles: Vec::with_capacity(if reads_grid { b * rows * cols } else { 0 }),
            goals: Vec::with_capacity(2 * b),
            per_item: q,
            queries: Vec::with_capacity(2 * b * q),
        };
        let mut targets = Vec::with_capacity(b * q);
        for _ in 0..b {
            let s = &data.samples[rng.below(data.samples.len())];
            if reads_grid {
                batch
                    .obstacles
                    .extend(s.grid.obstacles().iter().map(|&o| o as u8 as f32));
            }
            batch.goals.extend([s.goal.row as f32, s.goal.col as f32]);
            let pairs = self.config.neighbour_weight > 0.0;
            let detours = if self.config.detour_fraction > 0.0 && !self.config.dense {
                detour_cells(s)
            } else {
                Vec::new()
            };
            let far = if self.config.far_fraction > 0.0 && !self.config.dense {
                far_cells(s)
            } else {
                Vec::new()
            };
            let hard = if self.config.hard_fraction > 0.0 && !self.config.dense {
                self.hard_cells(s)?
            } else {
                Vec::new()
            };
            let anchor = |rng: &mut SplitMix64| {
                if !hard.is_empty() && rng.next_f64() < self.config.hard_fraction {
                    hard[rng.below(hard.len())]
                } else if !far.is_empty() && rng.next_f64() < self.config.far_fraction {
                    far[rng.below(far.len())]
                } else if !detours.is_empty() && rng.next_f64() < self.config.detour_fraction {
                    detours[rng.below(detours.len())]
                } else {
                    rng.below(rows * cols)
                }
            };
            let mut cells = Vec::with_capacity(q);
            if self.config.dense {
                cells.extend(0..q);
            } else if self.config.grouped() {
                // An anchor, then its 8 neighbours in `DIRECTIONS_8` order; the anchor again
                // where a neighbour is not a move.
                let rule = self.config.descent_rule;
                for _ in 0..q / GROUP {
                    let i = anchor(&mut rng);
                    let from = Cell2::new(i / cols, i % cols);
                    cells.push(i);
                    cells.extend(DIRECTIONS_8.iter().map(|&(dr, dc)| {
                        if rule.allows(&s.grid, from, dr, dc) {
                            (i as isize + dr * cols as isize + dc) as usize
                        } else {
                            i
                        }
                    }));
                }
            } else {
                for k in 0..q {
                    cells.push(if pairs && k % 2 == 1 {
                        // A random in-bounds neighbour of the previous query.
                        let (r, c) = (cells[k - 1] / cols, cells[k - 1] % cols);
                        loop {
                            let (dr, dc) = DIRECTIONS_8[rng.below(8)];
                            let (nr, nc) = (r as isize + dr, c as isize + dc);
                            if nr >= 0 && nc >= 0 && (nr as usize) < rows && (nc as usize) < cols {
                                break nr as usize * cols + nc as usize;
                            }
                        }
                    } else {
                        anchor(&mut rng)
                    });
                }
            }
            for i in cells {
                batch.queries.extend([(i / cols) as f32, (i % cols) as f32]);
                targets.push(encoding.encode(s.distance[i]));
            }
        }
        Ok((batch, targets))
    }

    /// The reachable cells of `s` (the goal excluded) where descent on the network's current
    /// field takes a move whose true distance exceeds the best move's.
    fn hard_cells(&self, s: &Sample) -> Result<Vec<usize>> {
        let field = self.net.field(&s.grid, s.goal)?;
        let rule = self.config.descent_rule;
        let cols = s.grid.cols();
        let distance = |c: Cell2| s.distance[c.row * cols + c.col];
        Ok(s.grid
            .free_cells()
            .filter(|&c| c != s.goal && distance(c).is_finite())
            .filter(|&c| is_wrong_move(&s.grid, &field, rule, c, distance))
            .map(|c| c.row * cols + c.col)
            .collect())
    }
}

/// The reachable cells of `s` whose distance exceeds the octile distance to the goal by more
/// than half a cell.
fn detour_cells(s: &Sample) -> Vec<usize> {
    let cols = s.grid.cols();
    s.distance
        .iter()
        .enumerate()
        .filter_map(|(i, &d)| is_detour(d, Cell2::new(i / cols, i % cols), s.goal).then_some(i))
        .collect()
}

/// The reachable cells of `s` at least half its largest reachable distance from the goal
/// (none when the goal reaches nothing).
fn far_cells(s: &Sample) -> Vec<usize> {
    let distance = &s.distance;
    let max = distance
        .iter()
        .filter(|d| d.is_finite())
        .fold(0.0f32, |m, &d| m.max(d));
    if max <= 0.0 {
        return Vec::new();
    }
    (0..distance.len())
        .filter(|&i| distance[i].is_finite() && distance[i] >= 0.5 * max)
        .collect()
}

/// Whether `cell`, at true distance `distance` (infinite: unreachable) from `goal`, is a
/// detour cell: its distance exceeds the octile distance by more than half a cell.
pub(crate) fn is_detour(distance: f32, cell: Cell2, goal: Cell2) -> bool {
    distance.is_finite() && distance > octile_distance(cell, goal) + 0.5
}
