//! The networks' configs: which architecture, with its settings.

use crate::layers::{validate_convs, ConvSpec, MlpConfig, MAX_CONVS};
use crate::{NetsError, Result, TargetEncoding};
use envfield_grid::MoveRule;
use serde::{Deserialize, Serialize};

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
    /// The MLP predicts the detour: the distance is the straight-line distance between goal
    /// and query (in cells) plus the MLP's output, then encoded. In open space the detour is
    /// 0, so the network learns only what the obstacles add. Off in the paper's network.
    #[serde(default)]
    pub detour: bool,
}

/// The context-aligned implicit function (paper Fig. 4c): a fully convolutional encoder of the
/// maze, its feature sampled bilinearly at the query, concatenated with goal and query
/// coordinates, and an MLP. Any maze size, any goal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContextConfig {
    /// The encoder's 3x3 convolutions (all stride 1: the feature map keeps the maze's size).
    /// Dilations let a few layers see the whole maze. The default, 11 convolutions (16, then
    /// 32 channels) with dilations cycling 1, 2, 4, 8 twice, passes information across a 28x28
    /// maze twice without the holes of a single 1-2-4-8-16 ramp.
    pub encoder: Vec<ConvSpec>,
    /// Residual encoder: each convolution that keeps its input's channel count adds its input
    /// before the ReLU, `relu(x + conv(x))`, the usual aid for training deep stacks. Off in the
    /// paper's encoder (and in models saved before it existed).
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
    /// The shortest-path readout (see [`PathConfig`]) in place of the MLP: `None` is the
    /// paper's readout.
    #[serde(default)]
    pub path: Option<PathConfig>,
}

/// The shortest-path readout of a context network: a 1x1 convolution turns the encoder's
/// features into eight move costs per cell, `min_cost + exp(s)`, and the field is the fixed
/// point of the min-plus Bellman recurrence over them, `v(x) = min_a c_a(x) + v(x + a)`,
/// `v(goal) = 0`, over the moves legal under the rule between free cells of the input map.
///
/// It is VIN's value iteration with `min` for `max`, the transition kernel fixed to the eight
/// moves, iterated until nothing changes; the fixed point is computed exactly by Dijkstra's
/// algorithm, so a path of any length is reached whatever the maze's size, and the gradient
/// reaches the costs along each cell's shortest-path branch. Descent on such a field never
/// meets a local minimum, whatever the costs: every reached cell has a move to a smaller
/// value. What is learned is the costs, and through them how long each path is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PathConfig {
    /// The least cost of a move (in cells): keeps every cost positive.
    pub min_cost: f32,
    /// The move rule of the recurrence's moves; [`crate::FieldNet::set_rule`] changes it for
    /// a loaded network (the costs do not depend on it).
    pub rule: MoveRule,
}

impl Default for PathConfig {
    fn default() -> Self {
        Self {
            min_cost: 0.05,
            rule: MoveRule::Strict,
        }
    }
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
            path: None,
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
                if let Some(p) = c.path {
                    if !(p.min_cost.is_finite() && p.min_cost > 0.0) {
                        return Err(NetsError::InvalidConfig(format!(
                            "context path: min_cost must be positive (got {})",
                            p.min_cost
                        )));
                    }
                    if c.propagation.is_some() {
                        return Err(NetsError::InvalidConfig(
                            "context: path and propagation are two readouts; give one".into(),
                        ));
                    }
                    if c.goal_channel {
                        return Err(NetsError::InvalidConfig(
                            "context path: the move costs are the maze's, the same for every \
                             goal: set goal_channel false"
                                .into(),
                        ));
                    }
                    return Ok(());
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

/// The four architectures, by name: `plain`, `goal`, `context` or `hyper`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Arch {
    /// [`PlainConfig`].
    Plain,
    /// [`GoalConfig`].
    Goal,
    /// [`ContextConfig`].
    Context,
    /// [`HyperConfig`].
    Hyper,
}

impl Arch {
    /// The architecture's name, as [`ModelConfig::arch`] gives it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Plain => "plain",
            Self::Goal => "goal",
            Self::Context => "context",
            Self::Hyper => "hyper",
        }
    }

    /// Whether the network learns one scene (plain: one goal too) rather than any maze.
    pub fn learns_one_scene(self) -> bool {
        matches!(self, Self::Plain | Self::Goal)
    }

    /// The preset network of this architecture for a `rows x cols` domain and a `goal` (the
    /// plain field's only goal), with `encoding`: the settings the examples and benchmarks
    /// train. Plain and goal-conditioned fields are 4 hidden layers of 128 with 4 Fourier
    /// frequencies; context and hyper are their configs' defaults.
    pub fn preset(
        self,
        rows: usize,
        cols: usize,
        goal: [usize; 2],
        encoding: TargetEncoding,
    ) -> ModelConfig {
        let mlp = MlpConfig {
            hidden: 128,
            layers: 4,
            fourier: 4,
            ..MlpConfig::default()
        };
        match self {
            Self::Plain => ModelConfig::Plain(PlainConfig {
                extent: vec![rows, cols],
                goal: goal.to_vec(),
                mlp,
                encoding,
            }),
            Self::Goal => ModelConfig::Goal(GoalConfig {
                extent: vec![rows, cols],
                mlp,
                encoding,
                detour: false,
            }),
            Self::Context => ModelConfig::Context(ContextConfig {
                encoding,
                ..ContextConfig::default()
            }),
            Self::Hyper => ModelConfig::Hyper(HyperConfig {
                encoding,
                ..HyperConfig::default()
            }),
        }
    }
}

impl std::fmt::Display for Arch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Arch {
    type Err = NetsError;

    fn from_str(s: &str) -> Result<Self> {
        [Self::Plain, Self::Goal, Self::Context, Self::Hyper]
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| {
                NetsError::InvalidConfig(format!(
                    "unknown architecture `{s}` (plain, goal, context or hyper)"
                ))
            })
    }
}

/// Convolutions from `CHANNELS:DILATION` items separated by commas (`:DILATION` may be left
/// out for 1), where `Nx[ITEMS]` repeats a group N times. The form the `train_maze` example's
/// `--encoder` takes.
///
/// ```
/// let convs = envfield_nets::parse_convs("16:1,8x[16:1,16:2,16:4,16:8],32")?;
/// assert_eq!(convs.len(), 34);
/// assert_eq!((convs[4].channels, convs[4].dilation), (16, 8));
/// # Ok::<(), envfield_nets::NetsError>(())
/// ```
///
/// # Errors
/// [`NetsError::InvalidConfig`] naming the item that is not a number, a `[` without `]`, a
/// group without its `Nx`, or more than 1024 convolutions.
pub fn parse_convs(spec: &str) -> Result<Vec<ConvSpec>> {
    let bad = |what: String| NetsError::InvalidConfig(format!("encoder `{spec}`: {what}"));
    let number = |s: &str, what: &str| -> Result<usize> {
        s.trim()
            .parse()
            .map_err(|_| bad(format!("{what} `{}` is not a whole number", s.trim())))
    };
    let mut out = Vec::new();
    let mut rest = spec.trim();
    while !rest.is_empty() {
        let item_end = match rest.find('[') {
            Some(open) if !rest[..open].contains(',') => {
                let close = rest
                    .find(']')
                    .ok_or_else(|| bad("`[` without `]`".into()))?;
                let times = rest[..open]
                    .trim()
                    .strip_suffix('x')
                    .ok_or_else(|| bad("a group is written Nx[...]".into()))?;
                let times = number(times, "repeat count")?;
                let group = parse_convs(&rest[open + 1..close])?;
                if times.saturating_mul(group.len()) > MAX_CONVS - out.len() {
                    return Err(bad(format!("more than {MAX_CONVS} convolutions")));
                }
                for _ in 0..times {
                    out.extend_from_slice(&group);
                }
                close + 1
            }
            _ => {
                let end = rest.find(',').unwrap_or(rest.len());
                let item = rest[..end].trim();
                let (channels, dilation) = item.split_once(':').unwrap_or((item, "1"));
                if out.len() == MAX_CONVS {
                    return Err(bad(format!("more than {MAX_CONVS} convolutions")));
                }
                out.push(ConvSpec::new(
                    number(channels, "channel count")?,
                    number(dilation, "dilation")?,
                ));
                end
            }
        };
        rest = rest[item_end..].trim_start();
        rest = rest.strip_prefix(',').unwrap_or(rest).trim_start();
    }
    Ok(out)
}
