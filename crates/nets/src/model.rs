//! The four implicit field networks behind one type, [`FieldNet`].

use crate::layers::{
    encode_coords, sample_features, validate_convs, Conv, ConvSpec, ConvStack, IndexCache, Linear,
    Mlp, MlpConfig,
};
use crate::params::{
    to_safetensors, Init, ParamStore, TensorFile, FORMAT, META_CONFIG, META_FORMAT,
    OPTIMISER_PREFIX,
};
use crate::{NetsError, Result};
use candle_core::{Device, Tensor, Var};
use envfield_grid::{Cell2, ContinuousField2, Field2, FieldModel, Grid2, GridError, Point2};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::Path;

/// How reaching distances are encoded as network outputs. Obstacles and unreachable cells
/// are -1 in both.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TargetEncoding {
    /// The paper's `1 / (1 + d)` (appendix A.4; [`envfield_mazes::encode_target`]): precise
    /// near the goal, but neighbouring cells 40 steps away differ by only 6e-4.
    #[default]
    Reciprocal,
    /// `1 - d / scale`, clamped at 0: every step changes the output by `1 / scale`, so
    /// descent far from the goal needs no more precision than near it.
    Linear {
        /// The distance (in cells) mapped to 0; pick it above the longest path.
        scale: f32,
    },
}

impl TargetEncoding {
    /// Encodes a distance in cells (infinite = blocked).
    pub fn encode(self, distance: f32) -> f32 {
        match self {
            Self::Reciprocal => envfield_mazes::encode_target(distance),
            Self::Linear { scale } if distance.is_finite() && distance >= 0.0 => {
                (1.0 - distance / scale).max(0.0)
            }
            Self::Linear { .. } => envfield_mazes::BLOCKED_TARGET,
        }
    }

    /// Decodes a raw network output into a distance in cells, monotone (a larger output is
    /// never farther) above -0.5, halfway to the blocked value -1; below it, infinite.
    /// The reciprocal encoding continues steeply linearly below a small floor (see
    /// [`prediction_to_distance`]); the linear one continues its line below 0.
    pub fn decode(self, t: f32) -> f32 {
        match self {
            Self::Reciprocal => prediction_to_distance(t),
            Self::Linear { scale } if t > -0.5 => ((1.0 - t) * scale).max(0.0),
            Self::Linear { .. } => f32::INFINITY,
        }
    }

    /// `d distance / d output` at output `t` (for gradients in distance units).
    pub fn slope(self, t: f32) -> f32 {
        match self {
            Self::Reciprocal if t >= FLOOR => -1.0 / (t * t),
            Self::Reciprocal => -1e4,
            Self::Linear { scale } => -scale,
        }
    }

    fn validate(self) -> Result<()> {
        match self {
            Self::Linear { scale } if !(scale.is_finite() && scale > 0.0) => {
                Err(NetsError::InvalidConfig(format!(
                    "linear encoding: scale must be positive (got {scale})"
                )))
            }
            _ => Ok(()),
        }
    }
}

/// A plain field (paper Fig. 4a): query coordinates -> reaching distance, for one scene and goal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlainConfig {
    /// The domain in cells per axis (`[rows, cols]` in 2D, `[nx, ny, nz]` in 3D).
    pub extent: Vec<usize>,
    /// The goal cell the field was trained for.
    pub goal: Vec<usize>,
    /// The MLP.
    pub mlp: MlpConfig,
    /// How distances are encoded as outputs.
    #[serde(default)]
    pub encoding: TargetEncoding,
}

/// A goal-conditioned field (paper Fig. 4b): (goal, query) -> reaching distance, one scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GoalConfig {
    /// The domain in cells per axis (2 or 3 axes).
    pub extent: Vec<usize>,
    /// The MLP.
    pub mlp: MlpConfig,
    /// How distances are encoded as outputs.
    #[serde(default)]
    pub encoding: TargetEncoding,
}

/// The context-aligned implicit function (paper Fig. 4c): a fully convolutional encoder of the
/// maze, its feature sampled bilinearly at the query, concatenated with goal and query
/// coordinates, and an MLP. Any maze size, any goal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContextConfig {
    /// The encoder's 3x3 convolutions (all stride 1: the feature map keeps the maze's size).
    /// Dilations let a few layers see the whole maze. The default, 11 convolutions (16, then
    /// 32 channels) with dilations cycling 1, 2, 4, 8 twice, passes information across a 28x28
    /// maze twice without the holes of a single 1-2-4-8-16 ramp; it took VIN's test sets from
    /// 95.0 / 92.5% (16x16 / 28x28, 7 convolutions, one ramp) to the figures in the README.
    pub encoder: Vec<ConvSpec>,
    /// Residual encoder: each convolution that keeps its input's channel count adds its input
    /// before the ReLU, `relu(x + conv(x))`, the usual aid for training deep stacks. Off in the
    /// paper's encoder (and in models saved before it existed). On gridworld mazes a residual
    /// 20-layer encoder scored what the default 11 layers do (`models/README.md`).
    #[serde(default)]
    pub residual: bool,
    /// Feed a one-hot goal map to the encoder beside the obstacle map.
    pub goal_channel: bool,
    /// Coordinates enter as `(cell - (n - 1) / 2) / coord_scale`, the same for every maze size.
    pub coord_scale: f32,
    /// The MLP.
    pub mlp: MlpConfig,
    /// How distances are encoded as outputs.
    #[serde(default)]
    pub encoding: TargetEncoding,
    /// Value-iteration layers on top of the encoder (see [`PropagationConfig`]); `None` is the
    /// paper's plain encoder.
    #[serde(default)]
    pub propagation: Option<PropagationConfig>,
}

/// Value iteration inside the context encoder, VIN's recurrence (Tamar et al. 2016) as a
/// feature extractor: a reward map `r = conv1x1(features)`, then `q = conv3x3([r, v])`,
/// `v = max_channels(q)` repeated `K = ceil(iterations_per_cell * max(rows, cols))` times with
/// shared weights, so information travels one cell per iteration across a maze of any size.
/// The encoder's features, `q` and `v` are what the query samples.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PropagationConfig {
    /// Channels of the Q layer (VIN: 10).
    pub q_channels: usize,
    /// Iterations per cell of the maze's longer side (VIN used 1.25-1.3).
    pub iterations_per_cell: f32,
}

impl Default for PropagationConfig {
    fn default() -> Self {
        Self {
            q_channels: 10,
            iterations_per_cell: 1.3,
        }
    }
}

impl PropagationConfig {
    /// The number of iterations for a `rows x cols` maze.
    pub fn iterations(&self, rows: usize, cols: usize) -> usize {
        ((self.iterations_per_cell * rows.max(cols) as f32).ceil() as usize).max(1)
    }
}

impl Default for ContextConfig {
    fn default() -> Self {
        Self {
            encoder: [
                (16, 1),
                (32, 1),
                (32, 2),
                (32, 4),
                (32, 8),
                (32, 1),
                (32, 2),
                (32, 4),
                (32, 8),
                (32, 16),
                (32, 1),
            ]
            .map(|(c, d)| ConvSpec::new(c, d))
            .to_vec(),
            residual: false,
            goal_channel: true,
            coord_scale: 16.0,
            mlp: MlpConfig {
                hidden: 64,
                layers: 3,
                ..MlpConfig::default()
            },
            encoding: TargetEncoding::Reciprocal,
            propagation: None,
        }
    }
}

/// The hypernetwork (paper appendix A.1): a convolutional network reads the maze and predicts
/// the weights of a SIREN hyponetwork that maps (goal, query) to the reaching distance. The
/// predicted weights are offsets to learned base weights.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HyperConfig {
    /// The convolutions (stride 2 shrinks the map); their output is averaged over the map.
    pub encoder: Vec<ConvSpec>,
    /// Feed a one-hot goal map to the encoder beside the obstacle map.
    pub goal_channel: bool,
    /// Widths of the fully connected layers after pooling (the last linear layer, to the
    /// hyponetwork's weights, comes on top).
    pub fc: Vec<usize>,
    /// Width of the hyponetwork's hidden layers.
    pub hypo_hidden: usize,
    /// Number of hidden layers of the hyponetwork.
    pub hypo_layers: usize,
    /// SIREN frequency of the hyponetwork.
    pub omega0: f32,
    /// As [`ContextConfig::coord_scale`].
    pub coord_scale: f32,
    /// How distances are encoded as outputs.
    #[serde(default)]
    pub encoding: TargetEncoding,
}

impl Default for HyperConfig {
    fn default() -> Self {
        Self {
            encoder: [(16, 1), (32, 2), (32, 1), (64, 2), (64, 1), (64, 2)]
                .map(|(c, s)| ConvSpec {
                    channels: c,
                    dilation: 1,
                    stride: s,
                })
                .to_vec(),
            goal_channel: true,
            fc: vec![256, 256],
            hypo_hidden: 32,
            hypo_layers: 4,
            omega0: 30.0,
            coord_scale: 16.0,
            encoding: TargetEncoding::Reciprocal,
        }
    }
}

/// Which network, with its settings. Serialised (JSON, tagged by `arch`) into every weight
/// file, so a file is enough to rebuild its network.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "arch", rename_all = "snake_case")]
pub enum ModelConfig {
    /// [`PlainConfig`].
    Plain(PlainConfig),
    /// [`GoalConfig`].
    Goal(GoalConfig),
    /// [`ContextConfig`].
    Context(ContextConfig),
    /// [`HyperConfig`].
    Hyper(HyperConfig),
}

impl ModelConfig {
    /// The architecture's short name: `plain`, `goal`, `context` or `hyper`.
    pub fn arch(&self) -> &'static str {
        match self {
            Self::Plain(_) => "plain",
            Self::Goal(_) => "goal",
            Self::Context(_) => "context",
            Self::Hyper(_) => "hyper",
        }
    }

    /// Number of coordinate axes (2 or 3).
    pub fn dims(&self) -> usize {
        match self {
            Self::Plain(c) => c.extent.len(),
            Self::Goal(c) => c.extent.len(),
            Self::Context(_) | Self::Hyper(_) => 2,
        }
    }

    /// How the network's outputs encode distances.
    pub fn encoding(&self) -> TargetEncoding {
        match self {
            Self::Plain(c) => c.encoding,
            Self::Goal(c) => c.encoding,
            Self::Context(c) => c.encoding,
            Self::Hyper(c) => c.encoding,
        }
    }

    /// Whether the network reads the obstacle map (context and hyper do).
    pub fn reads_grid(&self) -> bool {
        matches!(self, Self::Context(_) | Self::Hyper(_))
    }

    /// Checks every setting.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] naming the setting.
    pub fn validate(&self) -> Result<()> {
        self.encoding().validate()?;
        let extent = |e: &[usize]| {
            if !(2..=3).contains(&e.len()) || e.contains(&0) {
                Err(NetsError::InvalidConfig(format!(
                    "extent must have 2 or 3 nonzero axes (got {e:?})"
                )))
            } else {
                Ok(())
            }
        };
        let scale = |s: f32| {
            if s.is_finite() && s > 0.0 {
                Ok(())
            } else {
                Err(NetsError::InvalidConfig(format!(
                    "coord_scale must be positive (got {s})"
                )))
            }
        };
        match self {
            Self::Plain(c) => {
                extent(&c.extent)?;
                if c.goal.len() != c.extent.len()
                    || c.goal.iter().zip(&c.extent).any(|(g, n)| g >= n)
                {
                    return Err(NetsError::InvalidConfig(format!(
                        "plain: goal {:?} is not a cell of extent {:?}",
                        c.goal, c.extent
                    )));
                }
                c.mlp.validate("plain mlp")
            }
            Self::Goal(c) => {
                extent(&c.extent)?;
                c.mlp.validate("goal mlp")
            }
            Self::Context(c) => {
                validate_convs(&c.encoder, "context encoder")?;
                if c.encoder.iter().any(|s| s.stride != 1) {
                    return Err(NetsError::InvalidConfig(
                        "context encoder: every convolution must have stride 1 (features align with cells)".into(),
                    ));
                }
                scale(c.coord_scale)?;
                if let Some(p) = c.propagation {
                    if p.q_channels == 0
                        || !(p.iterations_per_cell.is_finite() && p.iterations_per_cell > 0.0)
                    {
                        return Err(NetsError::InvalidConfig(format!(
                            "context propagation: q_channels >= 1 and iterations_per_cell > 0 (got {p:?})"
                        )));
                    }
                }
                c.mlp.validate("context mlp")
            }
            Self::Hyper(c) => {
                validate_convs(&c.encoder, "hyper encoder")?;
                scale(c.coord_scale)?;
                if c.hypo_hidden == 0 || c.hypo_layers == 0 || c.fc.contains(&0) {
                    return Err(NetsError::InvalidConfig(
                        "hyper: hypo_hidden, hypo_layers and fc widths must be >= 1".into(),
                    ));
                }
                if !(c.omega0.is_finite() && c.omega0 > 0.0) {
                    return Err(NetsError::InvalidConfig(format!(
                        "hyper: omega0 must be positive (got {})",
                        c.omega0
                    )));
                }
                Ok(())
            }
        }
    }
}

/// Queries for a network: `items` (scene, goal) pairs, each with `per_item` query points.
/// Coordinates are in cell units (`[row, col]` in 2D, `[x, y, z]` in 3D), continuous.
#[derive(Clone, Debug, PartialEq)]
pub struct Batch {
    /// Cells per axis of every item's domain.
    pub extent: Vec<usize>,
    /// Number of (scene, goal) items.
    pub items: usize,
    /// Obstacle maps, `items * rows * cols` values (1 = obstacle, 0 = free), row-major; empty
    /// for networks that do not read the grid.
    pub obstacles: Vec<f32>,
    /// Goals, `items * dims` coordinates.
    pub goals: Vec<f32>,
    /// Query points per item.
    pub per_item: usize,
    /// Queries, `items * per_item * dims` coordinates.
    pub queries: Vec<f32>,
}

impl Batch {
    /// Every cell of `grid` as a query for `goal` (row-major order).
    pub fn whole_grid(grid: &Grid2, goal: Cell2) -> Self {
        let queries = (0..grid.len()).map(|i| grid.cell(i));
        Self::on_grid(
            grid,
            goal,
            queries.flat_map(|c| [c.row as f32, c.col as f32]),
        )
    }

    /// Every free cell of `grid` as a query for `goal` (row-major order): what a field needs,
    /// since obstacles are infinite whatever the network says.
    pub fn free_cells(grid: &Grid2, goal: Cell2) -> Self {
        let queries = grid.free_cells();
        Self::on_grid(
            grid,
            goal,
            queries.flat_map(|c| [c.row as f32, c.col as f32]),
        )
    }

    /// Continuous points of one 2D grid and goal.
    pub fn points(grid: &Grid2, goal: Cell2, points: &[Point2]) -> Self {
        Self::on_grid(grid, goal, points.iter().flat_map(|p| [p.row, p.col]))
    }

    /// One item: `grid` and `goal` with the `(row, col)` query coordinates `queries`.
    fn on_grid(grid: &Grid2, goal: Cell2, queries: impl Iterator<Item = f32>) -> Self {
        let queries: Vec<f32> = queries.collect();
        Self {
            extent: vec![grid.rows(), grid.cols()],
            items: 1,
            obstacles: obstacle_map(grid),
            goals: vec![goal.row as f32, goal.col as f32],
            per_item: queries.len() / 2,
            queries,
        }
    }

    /// Number of query points.
    pub fn len(&self) -> usize {
        self.items * self.per_item
    }

    /// Whether there is no query.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn check(&self, cfg: &ModelConfig) -> Result<()> {
        let d = self.extent.len();
        let bad = |m: String| Err(NetsError::InvalidInput(m));
        if d != cfg.dims() {
            return bad(format!(
                "{}-axis queries for a {}-axis {} network",
                d,
                cfg.dims(),
                cfg.arch()
            ));
        }
        let cells: usize = self.extent.iter().product();
        if self.items == 0 || self.per_item == 0 {
            return bad("an empty batch".into());
        }
        if self.goals.len() != self.items * d || self.queries.len() != self.len() * d {
            return bad(format!(
                "batch of {} items x {} queries needs {} goal and {} query coordinates (got {}, {})",
                self.items,
                self.per_item,
                self.items * d,
                self.len() * d,
                self.goals.len(),
                self.queries.len()
            ));
        }
        if cfg.reads_grid() && self.obstacles.len() != self.items * cells {
            return bad(format!(
                "the {} network reads the grid: need {} obstacle values, got {}",
                cfg.arch(),
                self.items * cells,
                self.obstacles.len()
            ));
        }
        for (what, xs) in [("goal", &self.goals), ("query", &self.queries)] {
            if let Some(i) = xs.iter().position(|x| !x.is_finite()) {
                return bad(format!("{what} coordinate {i} is not finite ({})", xs[i]));
            }
            for (i, x) in xs.iter().enumerate() {
                let n = self.extent[i % d] as f32;
                if *x < 0.0 || *x > n - 1.0 {
                    return bad(format!(
                        "{what} {} lies outside the domain {:?} (axis {} value {x})",
                        i / d,
                        self.extent,
                        i % d
                    ));
                }
            }
        }
        Ok(())
    }
}

fn obstacle_map(grid: &Grid2) -> Vec<f32> {
    grid.obstacles().iter().map(|&o| o as u8 as f32).collect()
}

/// The hyponetwork's layer shapes: (fan_in, fan_out) per layer.
fn hypo_shapes(c: &HyperConfig) -> Vec<(usize, usize)> {
    let mut shapes = vec![(4, c.hypo_hidden)];
    for _ in 1..c.hypo_layers {
        shapes.push((c.hypo_hidden, c.hypo_hidden));
    }
    shapes.push((c.hypo_hidden, 1));
    shapes
}

#[derive(Debug)]
struct Hyper {
    encoder: ConvStack,
    fc: Vec<Linear>,
    head: Linear,
    base: Vec<Linear>,
}

/// Value-iteration layers of a context encoder.
#[derive(Debug)]
struct Propagation {
    reward: Linear,
    q: Conv,
    config: PropagationConfig,
}

impl Propagation {
    /// (B, H, W, C) features -> (B, H, W, Q + 1): the last Q map and its channel maximum.
    fn forward(&self, features: &Tensor, cache: &IndexCache) -> Result<Tensor> {
        let (b, h, w, c) = features.dims4()?;
        let r = self
            .reward
            .forward(&features.reshape((b * h * w, c))?)?
            .reshape((b, h, w, 1))?;
        let mut v = r.zeros_like()?;
        let mut q = self.q.forward(&Tensor::cat(&[&r, &v], 3)?, cache)?;
        for _ in 0..self.config.iterations(h, w) {
            v = q.max_keepdim(3)?;
            q = self.q.forward(&Tensor::cat(&[&r, &v], 3)?, cache)?;
        }
        v = q.max_keepdim(3)?;
        Ok(Tensor::cat(&[&q, &v], 3)?)
    }

    /// The same values as [`Propagation::forward`] without gradients, in plain loops: one
    /// iteration is a 3x3 convolution of a single map into Q channels (about 7k multiply-adds
    /// for 28x28 and Q = 10), far below the cost of candle's per-op dispatch, which
    /// `forward` pays five times per iteration. The reward's share of each Q map is the
    /// same in every iteration and is computed once.
    fn forward_inference(&self, features: &Tensor) -> Result<Tensor> {
        let (b, h, w, c) = features.dims4()?;
        let r = self
            .reward
            .forward(&features.reshape((b * h * w, c))?)?
            .flatten_all()?
            .to_vec1::<f32>()?;
        let nq = self.config.q_channels;
        // Rows of the (18, Q) weight: tap-major, channel 0 = reward, channel 1 = value.
        let weight = self.q.linear.w.flatten_all()?.to_vec1::<f32>()?;
        let bias = self.q.linear.b.to_vec1::<f32>()?;
        let iterations = self.config.iterations(h, w);
        let hw = h * w;
        let mut out = vec![0f32; b * hw * (nq + 1)];
        // Channel-major Q maps so the inner loop runs along a row.
        let mut base = vec![0f32; nq * hw];
        let mut q = vec![0f32; nq * hw];
        let mut v = vec![0f32; hw];
        let taps: Vec<(usize, isize, isize)> = (0..9)
            .map(|t| (t, t as isize / 3 - 1, t as isize % 3 - 1))
            .collect();
        // q[o][y][x] += m[y+dy][x+dx] * weight[tap][channel][o] over the in-bounds range.
        let accumulate = |dst: &mut [f32], src: &[f32], channel: usize| {
            for &(t, dy, dx) in &taps {
                let x0 = (-dx).max(0) as usize;
                let x1 = (w as isize - dx.max(0)) as usize;
                for o in 0..nq {
                    let k = weight[(2 * t + channel) * nq + o];
                    if k == 0.0 {
                        continue;
                    }
                    for y in 0..h {
                        let sy = y as isize + dy;
                        if sy < 0 || sy >= h as isize {
                            continue;
                        }
                        let row = &mut dst[o * hw + y * w + x0..o * hw + y * w + x1];
                        let from = (sy * w as isize + x0 as isize + dx) as usize;
                        let srow = &src[from..from + (x1 - x0)];
                        // Slices of equal length: the compiler vectorises this.
                        for (a, b) in row.iter_mut().zip(srow) {
                            *a += k * b;
                        }
                    }
                }
            }
        };
        for item in 0..b {
            let r = &r[item * hw..(item + 1) * hw];
            for o in 0..nq {
                base[o * hw..(o + 1) * hw].fill(bias[o]);
            }
            accumulate(&mut base, r, 0);
            // v starts at 0, so the first Q maps are the reward's share alone.
            q.copy_from_slice(&base);
            for _ in 0..iterations {
                v.copy_from_slice(&q[..hw]);
                for o in 1..nq {
                    for (vi, qi) in v.iter_mut().zip(&q[o * hw..(o + 1) * hw]) {
                        *vi = vi.max(*qi);
                    }
                }
                q.copy_from_slice(&base);
                accumulate(&mut q, &v, 1);
            }
            let dst = &mut out[item * hw * (nq + 1)..(item + 1) * hw * (nq + 1)];
            for i in 0..hw {
                let mut m = f32::NEG_INFINITY;
                for o in 0..nq {
                    let x = q[o * hw + i];
                    dst[i * (nq + 1) + o] = x;
                    m = m.max(x);
                }
                dst[i * (nq + 1) + nq] = m;
            }
        }
        Ok(Tensor::from_vec(out, (b, h, w, nq + 1), features.device())?)
    }
}

#[derive(Debug)]
enum Net {
    Plain(Mlp),
    Goal(Mlp),
    Context {
        encoder: ConvStack,
        propagation: Option<Propagation>,
        mlp: Mlp,
    },
    Hyper(Hyper),
}

/// An implicit environment-field network (any of the four architectures), its parameters and
/// its device. Outputs are in the paper's target encoding (`1 / (1 + d)`, -1 blocked; see
/// [`envfield_mazes::encode_target`]); [`FieldModel::predict`] decodes them into distances.
#[derive(Debug)]
pub struct FieldNet {
    config: ModelConfig,
    store: ParamStore,
    net: Net,
    cache: IndexCache,
    device: Device,
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
                        let small = Init::Normal(0.01);
                        let reward = Linear::new(&mut store, "vi.reward", feat, 1, small)?;
                        let spec = ConvSpec::new(p.q_channels, 1);
                        let q = Conv::with_init(&mut store, "vi.q", 2, spec, small)?;
                        feat += p.q_channels + 1;
                        Some(Propagation {
                            reward,
                            q,
                            config: p,
                        })
                    }
                    None => None,
                };
                let input = feat + 2 * c.mlp.encoded_width(2);
                let mlp = Mlp::new(&mut store, "mlp", &c.mlp, input, 1)?;
                Net::Context {
                    encoder,
                    propagation,
                    mlp,
                }
            }
            ModelConfig::Hyper(c) => {
                let encoder = ConvStack::new(
                    &mut store,
                    "encoder",
                    cin(c.goal_channel),
                    &c.encoder,
                    false,
                )?;
                let mut width = c.encoder.last().map_or(0, |s| s.channels);
                let mut fc = Vec::new();
                for (i, &w) in c.fc.iter().enumerate() {
                    let init = Init::Normal((2.0 / width as f32).sqrt());
                    fc.push(Linear::new(&mut store, &format!("fc.{i}"), width, w, init)?);
                    width = w;
                }
                let shapes = hypo_shapes(c);
                let total: usize = shapes.iter().map(|(i, o)| i * o + o).sum();
                let head = Linear::new(
                    &mut store,
                    "head",
                    width,
                    total,
                    Init::Normal(1e-3 / (width as f32).sqrt()),
                )?;
                let mut base = Vec::new();
                for (l, &(i, o)) in shapes.iter().enumerate() {
                    let bound = if l == 0 {
                        1.0 / i as f32
                    } else {
                        (6.0 / i as f32).sqrt() / c.omega0
                    };
                    base.push(Linear::new(
                        &mut store,
                        &format!("hypo.{l}"),
                        i,
                        o,
                        Init::Uniform(bound),
                    )?);
                }
                Net::Hyper(Hyper {
                    encoder,
                    fc,
                    head,
                    base,
                })
            }
        };
        Ok(Self {
            config,
            store,
            net,
            cache: IndexCache::default(),
            device: device.clone(),
        })
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
                mlp.forward(&Tensor::cat(&[&g, &q], 1)?)?
            }
            (
                Net::Context {
                    encoder,
                    propagation,
                    mlp,
                },
                ModelConfig::Context(c),
            ) => {
                let input = self.grid_input(batch, c.goal_channel)?;
                let mut features = if track {
                    encoder.forward(&input, &self.cache)?
                } else {
                    encoder.forward_inference(&input)?
                };
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

    fn hyper_forward(
        &self,
        hy: &Hyper,
        c: &HyperConfig,
        batch: &Batch,
        goals: &Tensor,
        queries: &Tensor,
    ) -> Result<Tensor> {
        let features = hy
            .encoder
            .forward(&self.grid_input(batch, c.goal_channel)?, &self.cache)?;
        let mut h = features.mean(2)?.mean(1)?; // (B, C)
        for layer in &hy.fc {
            h = layer.forward(&h)?.relu()?;
        }
        let delta = hy.head.forward(&h)?; // (B, P)
        let (b, q) = (batch.items, batch.per_item);
        let g = self.normalise(goals, &batch.extent)?;
        let x = self.normalise(queries, &batch.extent)?;
        let mut act = Tensor::cat(&[&g, &x], 1)?.reshape((b, q, 4))?;
        let last = hy.base.len() - 1;
        let mut offset = 0;
        for (l, base) in hy.base.iter().enumerate() {
            let (fi, fo) = base.w.dims2()?;
            let dw = delta.narrow(1, offset, fi * fo)?.reshape((b, fi, fo))?;
            offset += fi * fo;
            let db = delta.narrow(1, offset, fo)?.reshape((b, 1, fo))?;
            offset += fo;
            let w = dw.broadcast_add(&base.w)?;
            let bias = db.broadcast_add(&base.b)?;
            act = act.matmul(&w)?.broadcast_add(&bias)?;
            if l < last {
                act = (act * c.omega0 as f64)?.sin()?;
            }
        }
        Ok(act.reshape((b * q, 1))?)
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
    /// once, every free cell in one MLP batch), decoded with [`TargetEncoding::decode`]; obstacles
    /// are infinite.
    ///
    /// # Errors
    /// A goal outside the grid or on an obstacle; a grid or goal the network does not accept.
    pub fn field(&self, grid: &Grid2, goal: Cell2) -> Result<Field2> {
        grid.check_free(goal, "goal")?;
        self.check_scene(grid, goal)?;
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

    fn tensors(&self) -> Vec<(String, Tensor)> {
        self.store
            .names()
            .iter()
            .cloned()
            .zip(self.store.vars().iter().map(|v| v.as_tensor().clone()))
            .collect()
    }

    pub(crate) fn write_file(
        &self,
        path: &Path,
        extra: Vec<(String, Tensor)>,
        mut metadata: HashMap<String, String>,
    ) -> Result<()> {
        metadata.insert(META_FORMAT.into(), FORMAT.into());
        let config = serde_json::to_string(&self.config)
            .map_err(|e| NetsError::InvalidConfig(format!("cannot serialise the config: {e}")))?;
        metadata.insert(META_CONFIG.into(), config);
        let mut tensors = self.tensors();
        tensors.extend(extra);
        let bytes = to_safetensors(&tensors, metadata)?;
        envfield_grid::write_atomic(path, &bytes)?;
        Ok(())
    }

    /// Saves the weights and the config as one safetensors file (written atomically).
    ///
    /// # Errors
    /// I/O errors naming the file.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        self.write_file(path.as_ref(), Vec::new(), HashMap::new())
    }

    /// Loads a network saved by [`FieldNet::save`] (or a training checkpoint), rebuilding it
    /// from the config in the file. A checkpoint that keeps a moving average of the weights
    /// ([`crate::TrainConfig::ema_decay`]) loads the average: the network that training
    /// would export at that step.
    ///
    /// # Errors
    /// [`NetsError::Checkpoint`] for an unreadable, truncated or foreign file; the errors of
    /// [`FieldNet::load_weights`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        Self::load_on(path, &Device::Cpu)
    }

    /// As [`FieldNet::load`] on `device`.
    ///
    /// # Errors
    /// As [`FieldNet::load`].
    pub fn load_on(path: impl AsRef<Path>, device: &Device) -> Result<Self> {
        let path = path.as_ref();
        let mut file = TensorFile::read(path)?;
        let config = read_config(path, &file)?;
        let mut net = Self::new_on(config, 0, device)?;
        let average = file.take_average(path, &net.store, device, false)?;
        net.take_weights(path, &mut file)?;
        for (var, t) in net.store.vars().iter().zip(average.into_iter().flatten()) {
            var.set(&t)?;
        }
        Ok(net)
    }

    /// Overwrites this network's weights with those in `path`, checking that every parameter
    /// is there with the same shape and that the file holds nothing else (optimiser state of a
    /// training checkpoint aside).
    ///
    /// # Errors
    /// [`NetsError::Checkpoint`], [`NetsError::MissingWeight`], [`NetsError::ShapeMismatch`],
    /// [`NetsError::UnexpectedWeight`].
    pub fn load_weights(&mut self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let mut file = TensorFile::read(path)?;
        self.take_weights(path, &mut file)
    }

    pub(crate) fn take_weights(&mut self, path: &Path, file: &mut TensorFile) -> Result<()> {
        let mut loaded = Vec::with_capacity(self.store.vars().len());
        for (name, var) in self.store.names().iter().zip(self.store.vars()) {
            loaded.push(file.take(path, name, var.dims(), &self.device)?);
        }
        if let Some(name) = file
            .tensors
            .keys()
            .filter(|k| !k.starts_with(OPTIMISER_PREFIX))
            .min()
        {
            return Err(NetsError::UnexpectedWeight {
                path: path.to_path_buf(),
                name: name.clone(),
            });
        }
        for (var, t) in self.store.vars().iter().zip(loaded) {
            var.set(&t)?;
        }
        Ok(())
    }
}

pub(crate) fn read_config(path: &Path, file: &TensorFile) -> Result<ModelConfig> {
    let json = file
        .metadata
        .get(META_CONFIG)
        .ok_or_else(|| NetsError::Checkpoint {
            path: path.to_path_buf(),
            reason: format!("no `{META_CONFIG}` metadata"),
        })?;
    serde_json::from_str(json).map_err(|e| NetsError::Checkpoint {
        path: path.to_path_buf(),
        reason: format!("bad model config: {e}"),
    })
}

/// Below this raw output a free cell is decoded linearly (see [`prediction_to_distance`]).
const FLOOR: f32 = 1e-3;

/// Decodes a raw network output into a reaching distance in cells: the inverse of the
/// paper's encoding (`1/t - 1`) above a small floor; below it, down to -0.5 (halfway to the
/// blocked value -1), a steep linear continuation, so the decoded field still decreases
/// wherever the raw output increases and descent on it follows the network; below -0.5 the
/// network says "blocked" and the distance is infinite.
pub fn prediction_to_distance(t: f32) -> f32 {
    if t >= FLOOR {
        (1.0 / t - 1.0).max(0.0)
    } else if t > -0.5 {
        (1.0 / FLOOR - 1.0) + (FLOOR - t) * 1e4
    } else {
        f32::INFINITY
    }
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
}

/// A network bound to one grid and goal: values and analytic gradients at continuous points
/// ([`ContinuousField2`]), in distance units (decoded as [`TargetEncoding::decode`]).
#[derive(Debug)]
pub struct BoundField<'a> {
    net: &'a FieldNet,
    grid: &'a Grid2,
    goal: Cell2,
}

impl BoundField<'_> {
    /// Distances and gradients `(d/d row, d/d col)` at many points in one pass.
    ///
    /// # Errors
    /// A point outside the grid or not finite.
    pub fn values_and_gradients(&self, points: &[Point2]) -> Result<Vec<(f32, [f32; 2])>> {
        let (raw, grad) = self
            .net
            .predict_with_gradient(&Batch::points(self.grid, self.goal, points))?;
        let encoding = self.net.config.encoding();
        Ok(raw
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                let d = encoding.decode(t);
                let slope = encoding.slope(t);
                (d, [slope * grad[2 * i], slope * grad[2 * i + 1]])
            })
            .collect())
    }
}

impl ContinuousField2 for BoundField<'_> {
    fn value(&self, p: Point2) -> envfield_grid::Result<f32> {
        let v = self
            .values_and_gradients(&[p])
            .map_err(|e| model_error(self.net.name(), e))?;
        Ok(v[0].0)
    }

    fn gradient(&self, p: Point2) -> envfield_grid::Result<Option<(f32, f32)>> {
        let v = self
            .values_and_gradients(&[p])
            .map_err(|e| model_error(self.net.name(), e))?;
        let (d, g) = v[0];
        Ok(d.is_finite().then_some((g[0], g[1])))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inference_value_iteration_matches_the_tracked_one() {
        let device = Device::Cpu;
        let mut store = ParamStore::new(3, &device);
        let init = Init::Normal(0.4);
        let config = PropagationConfig {
            q_channels: 5,
            iterations_per_cell: 0.7,
        };
        let p = Propagation {
            reward: Linear::new(&mut store, "r", 4, 1, init).unwrap(),
            q: Conv::with_init(&mut store, "q", 2, ConvSpec::new(5, 1), init).unwrap(),
            config,
        };
        let cache = IndexCache::default();
        // Two items of a 7 x 9 map (not square: rows and columns must not be swapped).
        let features = Tensor::randn(0f32, 1.0, (2, 7, 9, 4), &device).unwrap();
        let tracked = p.forward(&features, &cache).unwrap();
        let fast = p.forward_inference(&features).unwrap();
        assert_eq!(tracked.dims(), fast.dims());
        let diff = (tracked - fast)
            .unwrap()
            .abs()
            .unwrap()
            .max_all()
            .unwrap()
            .to_scalar::<f32>()
            .unwrap();
        assert!(diff < 1e-4, "max difference {diff}");
    }
}
