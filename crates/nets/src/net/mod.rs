//! [`FieldNet`]: the four implicit field networks behind one type, built from a
//! [`ModelConfig`].

mod bound;
mod context;
mod hyper;
mod io;
mod path;
mod readout;

pub use bound::BoundField;
pub(crate) use io::read_config;

use crate::layers::{encode_coords, sample_features, ConvStack, IndexCache, Mlp};
use crate::params::ParamStore;
use crate::{Batch, ContextConfig, HyperConfig, ModelConfig, NetsError, Result};
use candle_core::{Device, Tensor, Var};
use context::Propagation;
use envfield_grid::{Cell2, Field2, FieldModel, Grid2, GridError, MoveRule};
use hyper::Hyper;
use path::PathLayer;

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

    /// Cell-unit coordinates (N, d) normalised and Fourier-encoded with `fourier`
    /// frequencies: what every network's MLP reads.
    fn encoded_coords(&self, x: &Tensor, extent: &[usize], fourier: usize) -> Result<Tensor> {
        encode_coords(&self.normalise(x, extent)?, fourier)
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
                let q = self.encoded_coords(queries, &batch.extent, c.mlp.fourier)?;
                mlp.forward(&q)?
            }
            (Net::Goal(mlp), ModelConfig::Goal(c)) => {
                let g = self.encoded_coords(&goals, &batch.extent, c.mlp.fourier)?;
                let q = self.encoded_coords(queries, &batch.extent, c.mlp.fourier)?;
                let raw = mlp.forward(&Tensor::cat(&[&g, &q], 1)?)?;
                if c.detour {
                    // The straight line, kept off 0 so its gradient stays finite at the goal.
                    let line = ((queries - &goals)?.sqr()?.sum_keepdim(1)? + 1e-6)?.sqrt()?;
                    c.encoding.encode_tensor(&(line + raw)?)?
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
                let g = self.encoded_coords(&goals, &batch.extent, c.mlp.fourier)?;
                let q = self.encoded_coords(queries, &batch.extent, c.mlp.fourier)?;
                mlp.forward(&Tensor::cat(&[&f, &g, &q], 1)?)?
            }
            (Net::Hyper(hy), ModelConfig::Hyper(c)) => {
                self.hyper_forward(hy, c, batch, &goals, queries)?
            }
            _ => {
                return Err(NetsError::InvalidConfig(format!(
                    "a {} network built for another config",
                    self.config.arch()
                )))
            }
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
