//! [`FieldNet`]: the four implicit field networks behind one type, built from a
//! [`ModelConfig`].

mod bound;
mod context;
mod hyper;
mod io;
mod path;

pub use bound::BoundField;
pub(crate) use io::read_config;

use crate::layers::{encode_coords, sample_features, ConvStack, IndexCache, Mlp};
use crate::params::ParamStore;
use crate::{Batch, ContextConfig, HyperConfig, ModelConfig, NetsError, Result, TargetEncoding};
use candle_core::{Device, Tensor, Var};
use context::Propagation;
use envfield_grid::{Cell2, Field2, FieldModel, Grid2, GridError, MoveRule};
use hyper::Hyper;
use path::{MinPlus, PathLayer, MOVES};
use rayon::prelude::*;

#[derive(Debug)]
enum Net {
    Plain(Mlp),
    Goal(Mlp),
    Context {
        encoder: ConvStack,
        propagation: Option<Propagation>,
        /// The paper's readout; `None` with a shortest-path readout.
        mlp: Option<Mlp>,
        path: Option<PathLayer>,
    },
    Hyper(Hyper),
}

/// The most cells [`FieldNet::field`] predicts at once (1024 x 1024, a few GB of features).
pub const MAX_FIELD_CELLS: usize = 1 << 20;

/// An implicit environment-field network (any of the four architectures), its parameters and
/// its device. Outputs are in the config's [`crate::TargetEncoding`] (the paper's `1 / (1 + d)`
/// or `1 - d / scale`, -1 blocked); [`FieldModel::predict`] decodes them into distances.
#[derive(Debug)]
pub struct FieldNet {
    config: ModelConfig,
    store: ParamStore,
    net: Net,
    cache: IndexCache,
    device: Device,
    /// The move rule of a shortest-path readout's recurrence.
    rule: MoveRule,
}

impl FieldNet {
    /// A freshly initialised network on the CPU; the same config and seed give the same weights.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] for a bad config.
    pub fn new(config: ModelConfig, seed: u64) -> Result<Self> {
        Self::new_on(config, seed, &Device::Cpu)
    }

    /// As [`FieldNet::new`] on `device` (a CUDA device with the `cuda` feature).
    ///
    /// # Errors
    /// As [`FieldNet::new`]; candle errors from the device.
    pub fn new_on(config: ModelConfig, seed: u64, device: &Device) -> Result<Self> {
        config.validate()?;
        let mut store = ParamStore::new(seed, device);
        let cin = |goal_channel: bool| 1 + goal_channel as usize;
        let net = match &config {
            ModelConfig::Plain(c) => {
                let input = c.mlp.encoded_width(c.extent.len());
                Net::Plain(Mlp::new(&mut store, "mlp", &c.mlp, input, 1)?)
            }
            ModelConfig::Goal(c) => {
                let input = 2 * c.mlp.encoded_width(c.extent.len());
                Net::Goal(Mlp::new(&mut store, "mlp", &c.mlp, input, 1)?)
            }
            ModelConfig::Context(c) => {
                let encoder = ConvStack::new(
                    &mut store,
                    "encoder",
                    cin(c.goal_channel),
                    &c.encoder,
                    c.residual,
                )?;
                let mut feat = c.encoder.last().map_or(0, |s| s.channels);
                let propagation = match c.propagation {
                    Some(p) => {
                        let layers = Propagation::new(&mut store, feat, p)?;
                        feat += p.q_channels + 1;
                        Some(layers)
                    }
                    None => None,
                };
                let (mlp, path) = match c.path {
                    Some(p) => (None, Some(PathLayer::new(&mut store, feat, p)?)),
                    None => {
                        let input = feat + 2 * c.mlp.encoded_width(2);
                        (Some(Mlp::new(&mut store, "mlp", &c.mlp, input, 1)?), None)
                    }
                };
                Net::Context {
                    encoder,
                    propagation,
                    mlp,
                    path,
                }
            }
            ModelConfig::Hyper(c) => Net::Hyper(Hyper::new(&mut store, c)?),
        };
        let rule = match &config {
            ModelConfig::Context(ContextConfig { path: Some(p), .. }) => p.rule,
            _ => MoveRule::Strict,
        };
        Ok(Self {
            config,
            store,
            net,
            cache: IndexCache::default(),
            device: device.clone(),
            rule,
        })
    }

    /// The move rule of a shortest-path readout ([`crate::PathConfig`]); the config's rule
    /// until [`FieldNet::set_rule`] changes it. Other networks ignore it.
    pub fn rule(&self) -> MoveRule {
        self.rule
    }

    /// Sets the move rule of a shortest-path readout's recurrence, so the field's moves are
    /// the ones the agent walks by (the learned costs do not depend on the rule). Other
    /// networks ignore it.
    pub fn set_rule(&mut self, rule: MoveRule) {
        self.rule = rule;
    }

    /// Whether the network has a shortest-path readout.
    pub fn has_path_readout(&self) -> bool {
        matches!(&self.net, Net::Context { path: Some(_), .. })
    }

    /// The min-plus problem of `batch`: its free cells, goals and this network's rule.
    fn min_plus(&self, batch: &Batch) -> MinPlus {
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
    fn path_readout(
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
        let encoded = match encoding {
            TargetEncoding::Reciprocal => (v + 1.0)?.recip()?,
            TargetEncoding::Linear { scale } => v.affine(-1.0 / scale as f64, 1.0)?.relu()?,
        };
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

    /// The move costs of `grids` (all of one size), `grids * cells * 8` values, through the
    /// inference path (no gradients) and one encoder pass: what [`FieldNet::move_costs`] and
    /// the whole-field predictions share.
    fn flat_costs(&self, grids: &[&Grid2]) -> Result<Vec<f32>> {
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
    fn path_fields(&self, problems: &[(&Grid2, Cell2)]) -> Result<Vec<Field2>> {
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

    /// The network's config.
    pub fn config(&self) -> &ModelConfig {
        &self.config
    }

    /// The device the network runs on.
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// Number of trainable scalars.
    pub fn parameter_count(&self) -> usize {
        self.store.count()
    }

    pub(crate) fn vars(&self) -> &[Var] {
        self.store.vars()
    }

    pub(crate) fn store(&self) -> &ParamStore {
        &self.store
    }

    pub(crate) fn param_names(&self) -> &[String] {
        self.store.names()
    }

    /// Normalised coordinates (N, d) from cell-unit coordinates.
    fn normalise(&self, x: &Tensor, extent: &[usize]) -> Result<Tensor> {
        let d = extent.len();
        let (centre, scale): (Vec<f32>, Vec<f32>) = match &self.config {
            ModelConfig::Plain(_) | ModelConfig::Goal(_) => extent
                .iter()
                .map(|&n| {
                    let half = (n as f32 - 1.0) / 2.0;
                    (half, 1.0 / half.max(1.0))
                })
                .unzip(),
            ModelConfig::Context(ContextConfig { coord_scale, .. })
            | ModelConfig::Hyper(HyperConfig { coord_scale, .. }) => extent
                .iter()
                .map(|&n| ((n as f32 - 1.0) / 2.0, 1.0 / coord_scale))
                .unzip(),
        };
        let centre = Tensor::from_vec(centre, (1, d), &self.device)?;
        let scale = Tensor::from_vec(scale, (1, d), &self.device)?;
        Ok(x.broadcast_sub(&centre)?.broadcast_mul(&scale)?)
    }

    /// The encoder input (B, H, W, 1 or 2): obstacles, and a one-hot goal map.
    fn grid_input(&self, batch: &Batch, goal_channel: bool) -> Result<Tensor> {
        let (h, w) = (batch.extent[0], batch.extent[1]);
        let c = 1 + goal_channel as usize;
        let mut data = vec![0f32; batch.items * h * w * c];
        for b in 0..batch.items {
            for i in 0..h * w {
                data[(b * h * w + i) * c] = batch.obstacles[b * h * w + i];
            }
            if goal_channel {
                let (gr, gc) = (
                    batch.goals[2 * b].round() as usize,
                    batch.goals[2 * b + 1].round() as usize,
                );
                data[(b * h * w + gr * w + gc) * c + 1] = 1.0;
            }
        }
        Ok(Tensor::from_vec(
            data,
            (batch.items, h, w, c),
            &self.device,
        )?)
    }

    /// The raw outputs (N,) for `batch`. `queries` must be the batch's query coordinates as
    /// an (N, d) tensor (a [`Var`] when input gradients are wanted). With `track` false, the
    /// parts that do not depend on the queries (the context encoder and value iteration) skip
    /// the autograd graph: right for inference and query gradients, not for training the
    /// weights.
    fn forward_with(&self, batch: &Batch, queries: &Tensor, track: bool) -> Result<Tensor> {
        let d = batch.extent.len();
        let n = batch.len();
        let goals_rep: Vec<f32> = (0..n)
            .flat_map(|i| {
                let b = i / batch.per_item;
                batch.goals[b * d..(b + 1) * d].to_vec()
            })
            .collect();
        let goals = Tensor::from_vec(goals_rep, (n, d), &self.device)?;
        let out = match (&self.net, &self.config) {
            (Net::Plain(mlp), ModelConfig::Plain(c)) => {
                let q = encode_coords(&self.normalise(queries, &batch.extent)?, c.mlp.fourier)?;
                mlp.forward(&q)?
            }
            (Net::Goal(mlp), ModelConfig::Goal(c)) => {
                let g = encode_coords(&self.normalise(&goals, &batch.extent)?, c.mlp.fourier)?;
                let q = encode_coords(&self.normalise(queries, &batch.extent)?, c.mlp.fourier)?;
                let raw = mlp.forward(&Tensor::cat(&[&g, &q], 1)?)?;
                if c.detour {
                    // The straight line, kept off 0 so its gradient stays finite at the goal.
                    let line = ((queries - &goals)?.sqr()?.sum_keepdim(1)? + 1e-6)?.sqrt()?;
                    encode_distance(&(line + raw)?, c.encoding)?
                } else {
                    raw
                }
            }
            (
                Net::Context {
                    encoder,
                    propagation,
                    mlp,
                    path,
                },
                ModelConfig::Context(c),
            ) => {
                let input = self.grid_input(batch, c.goal_channel)?;
                let mut features = if track {
                    encoder.forward(&input, &self.cache)?
                } else {
                    encoder.forward_inference(&input)?
                };
                if let Some(layer) = path {
                    let out =
                        self.path_readout(layer, &features, batch, queries, c.encoding, track)?;
                    return Ok(out.reshape(n)?);
                }
                let mlp = mlp.as_ref().expect("an MLP readout without a path readout");
                if let Some(p) = propagation {
                    // The propagated values do not depend on the queries: without training
                    // they need no gradient.
                    let values = if track {
                        p.forward(&features, &self.cache)?
                    } else {
                        p.forward_inference(&features.detach())?
                    };
                    features = Tensor::cat(&[&features, &values], 3)?;
                }
                let points: Vec<[f32; 2]> = batch
                    .queries
                    .chunks_exact(2)
                    .map(|p| [p[0], p[1]])
                    .collect();
                let rows = queries.narrow(1, 0, 1)?;
                let cols = queries.narrow(1, 1, 1)?;
                let f = sample_features(&features, &points, batch.per_item, &rows, &cols)?;
                let g = encode_coords(&self.normalise(&goals, &batch.extent)?, c.mlp.fourier)?;
                let q = encode_coords(&self.normalise(queries, &batch.extent)?, c.mlp.fourier)?;
                mlp.forward(&Tensor::cat(&[&f, &g, &q], 1)?)?
            }
            (Net::Hyper(hy), ModelConfig::Hyper(c)) => {
                self.hyper_forward(hy, c, batch, &goals, queries)?
            }
            _ => unreachable!("network and config built together"),
        };
        Ok(out.reshape(n)?)
    }

    /// The raw outputs (encoded targets) for `batch`, as a tensor that tracks gradients (the
    /// training path).
    ///
    /// # Errors
    /// [`NetsError::InvalidInput`] for a batch that does not fit the network.
    pub fn forward(&self, batch: &Batch) -> Result<Tensor> {
        self.forward_batch(batch, true)
    }

    /// Checks `batch` and runs the network on its queries; `track` as in
    /// [`FieldNet::forward_with`].
    fn forward_batch(&self, batch: &Batch, track: bool) -> Result<Tensor> {
        batch.check(&self.config)?;
        let d = batch.extent.len();
        let queries = Tensor::from_vec(batch.queries.clone(), (batch.len(), d), &self.device)?;
        self.forward_with(batch, &queries, track)
    }

    /// The raw outputs for `batch`, one per query.
    ///
    /// # Errors
    /// As [`FieldNet::forward`].
    pub fn predict_encoded(&self, batch: &Batch) -> Result<Vec<f32>> {
        Ok(self
            .forward_batch(batch, false)?
            .detach()
            .to_vec1::<f32>()?)
    }

    /// The raw outputs and their gradients with respect to the query coordinates (in cell
    /// units, `dims` values per query), by reverse-mode differentiation through the network
    /// (the bilinear feature sampling included).
    ///
    /// # Errors
    /// As [`FieldNet::forward`].
    pub fn predict_with_gradient(&self, batch: &Batch) -> Result<(Vec<f32>, Vec<f32>)> {
        batch.check(&self.config)?;
        let d = batch.extent.len();
        let queries = Var::from_vec(batch.queries.clone(), (batch.len(), d), &self.device)?;
        let out = self.forward_with(batch, queries.as_tensor(), false)?;
        let grads = out.sum_all()?.backward()?;
        let g = match grads.get(queries.as_tensor()) {
            Some(g) => g.flatten_all()?.to_vec1::<f32>()?,
            None => vec![0.0; batch.len() * d],
        };
        Ok((out.detach().to_vec1::<f32>()?, g))
    }

    fn check_scene(&self, grid: &Grid2, goal: Cell2) -> Result<()> {
        let extent = [grid.rows(), grid.cols()];
        match &self.config {
            ModelConfig::Plain(c) if c.extent != extent || c.goal != [goal.row, goal.col] => {
                Err(NetsError::InvalidInput(format!(
                    "this plain field was trained for a {:?} grid and goal {:?}, asked for {:?} and goal ({}, {})",
                    c.extent, c.goal, extent, goal.row, goal.col
                )))
            }
            ModelConfig::Goal(c) if c.extent != extent => Err(NetsError::InvalidInput(format!(
                "this goal-conditioned field was trained on a {:?} domain, asked for {:?}",
                c.extent, extent
            ))),
            _ if self.config.dims() != 2 => Err(NetsError::InvalidInput(format!(
                "a {}-axis network cannot predict a 2D grid",
                self.config.dims()
            ))),
            _ => Ok(()),
        }
    }

    /// The reaching-distance field of `grid` for `goal`: one batched forward pass (the encoder
    /// once, every free cell in one MLP batch), decoded with [`crate::TargetEncoding::decode`]; obstacles
    /// are infinite.
    ///
    /// # Errors
    /// A goal outside the grid or on an obstacle; a grid or goal the network does not accept;
    /// a grid of more than [`MAX_FIELD_CELLS`] cells.
    pub fn field(&self, grid: &Grid2, goal: Cell2) -> Result<Field2> {
        grid.check_free(goal, "goal")?;
        self.check_scene(grid, goal)?;
        if grid.len() > MAX_FIELD_CELLS {
            return Err(NetsError::InvalidInput(format!(
                "a {}x{} grid is too large for one field prediction: at most {MAX_FIELD_CELLS} \
                 cells (1024x1024), as the features of every cell are held at once (about 2.2 \
                 KB a cell for the default context network)",
                grid.rows(),
                grid.cols()
            )));
        }
        if self.has_path_readout() {
            let mut fields = self.path_fields(&[(grid, goal)])?;
            return Ok(fields.remove(0));
        }
        let raw = self.predict_encoded(&Batch::free_cells(grid, goal))?;
        let encoding = self.config.encoding();
        let mut free = raw.iter();
        let values = grid
            .obstacles()
            .iter()
            .map(|&o| match o {
                true => f32::INFINITY,
                false => free.next().map_or(f32::INFINITY, |&t| encoding.decode(t)),
            })
            .collect();
        Ok(Field2::new(grid.rows(), grid.cols(), values)?)
    }

    /// The fields of many `(grid, goal)` problems, in order. For a network with a
    /// shortest-path readout and grids of one size this is one encoder pass over all the
    /// grids and one Dijkstra pass per problem, in parallel; otherwise one
    /// [`FieldNet::field`] per problem.
    ///
    /// # Errors
    /// As [`FieldNet::field`], for the first bad problem.
    pub fn fields(&self, problems: &[(&Grid2, Cell2)]) -> Result<Vec<Field2>> {
        let Some(&(first, _)) = problems.first() else {
            return Ok(Vec::new());
        };
        let same_size = problems
            .iter()
            .all(|(g, _)| (g.rows(), g.cols()) == (first.rows(), first.cols()));
        if !(self.has_path_readout() && same_size) {
            return problems
                .iter()
                .map(|&(g, goal)| self.field(g, goal))
                .collect();
        }
        for &(grid, goal) in problems {
            grid.check_free(goal, "goal")?;
            self.check_scene(grid, goal)?;
        }
        // The encoder's features of every grid are held at once.
        if first.len().saturating_mul(problems.len()) > MAX_FIELD_CELLS {
            return problems
                .chunks((MAX_FIELD_CELLS / first.len().max(1)).max(1))
                .map(|chunk| match chunk.len() {
                    1 => self.field(chunk[0].0, chunk[0].1).map(|f| vec![f]),
                    _ => self.path_fields(chunk),
                })
                .collect::<Result<Vec<_>>>()
                .map(|v| v.into_iter().flatten().collect());
        }
        self.path_fields(problems)
    }

    /// A continuous view of the field of `grid` for `goal` (values and gradients at any point).
    ///
    /// # Errors
    /// As [`FieldNet::field`].
    pub fn bind<'a>(&'a self, grid: &'a Grid2, goal: Cell2) -> Result<BoundField<'a>> {
        grid.check_free(goal, "goal")?;
        self.check_scene(grid, goal)?;
        Ok(BoundField {
            net: self,
            grid,
            goal,
        })
    }
}

/// Distances (N, 1) in cells encoded as outputs: `1 - d / scale` (not clamped, so a blocked
/// target of -1 stays reachable) or `1 / (1 + max(d, 0))`.
fn encode_distance(d: &Tensor, encoding: TargetEncoding) -> Result<Tensor> {
    Ok(match encoding {
        TargetEncoding::Reciprocal => (d.relu()? + 1.0)?.recip()?,
        TargetEncoding::Linear { scale } => d.affine(-1.0 / scale as f64, 1.0)?,
    })
}

fn model_error(name: &str, e: NetsError) -> GridError {
    match e {
        NetsError::Grid(g) => g,
        other => GridError::Model {
            model: name.to_string(),
            source: Box::new(other),
        },
    }
}

impl FieldModel for FieldNet {
    fn name(&self) -> &str {
        self.config.arch()
    }

    fn predict(&self, grid: &Grid2, goal: Cell2) -> envfield_grid::Result<Field2> {
        self.field(grid, goal)
            .map_err(|e| model_error(self.name(), e))
    }

    fn predict_many(&self, problems: &[(&Grid2, Cell2)]) -> envfield_grid::Result<Vec<Field2>> {
        self.fields(problems)
            .map_err(|e| model_error(self.name(), e))
    }
}
