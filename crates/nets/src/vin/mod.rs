//! The Value Iteration Network baseline (Tamar et al. 2016): the network, its files and its
//! policy (the network called at every step, as VIN plans). Training is in [`train`].

mod kernel;
mod train;

pub use train::{VinData, VinStep, VinTrainConfig, VinTrainer};

use crate::params::{
    weight_metadata, write_weights, Init, ParamStore, TensorFile, FORMAT, META_CONFIG, META_STEP,
};
use crate::{NetsError, Result};
use candle_core::{Device, Tensor};
use envfield_grid::{Cell2, Grid2, MoveRule, Policy};
use kernel::{MapInput, Weights, ACTIONS};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// VIN's settings (the published ones by default, with `iterations` per maze size).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct VinConfig {
    /// Channels of the first 3x3 convolution `h` (150).
    pub hidden: usize,
    /// Channels of the Q layer (10).
    pub q_channels: usize,
    /// Value-iteration steps K (10, 20, 36 for 8, 16, 28).
    pub iterations: usize,
    /// The move rule whose 8 actions the network chooses from.
    pub rule: MoveRule,
}

impl VinConfig {
    /// VIN's published setting for an `size x size` maze: K = 10, 20, 36 for 8, 16, 28
    /// (about 1.3 x size otherwise).
    pub fn for_size(size: usize) -> Self {
        let iterations = match size {
            8 => 10,
            16 => 20,
            28 => 36,
            n => (n * 13).div_ceil(10).max(4),
        };
        Self {
            hidden: 150,
            q_channels: 10,
            iterations,
            rule: MoveRule::Vin,
        }
    }

    fn validate(&self) -> Result<()> {
        let fields = [
            ("hidden", self.hidden),
            ("q_channels", self.q_channels),
            ("iterations", self.iterations),
        ];
        match fields.iter().find(|(_, v)| !(1..=4096).contains(v)) {
            Some((name, v)) => Err(NetsError::InvalidConfig(format!(
                "vin: {name} must be in 1..=4096 (got {v})"
            ))),
            None => Ok(()),
        }
    }
}

#[derive(Serialize, Deserialize)]
#[serde(tag = "arch", rename = "vin")]
struct VinFileConfig {
    #[serde(flatten)]
    config: VinConfig,
}

/// A Value Iteration Network: `h = conv3x3(obstacles, goal reward)`, `r = conv1x1(h)`,
/// `q = conv3x3([r, v])`, `v = max_channels(q)` repeated K times, then the Q values at the
/// agent's cell through a linear layer to 8 action logits (the order of
/// [`envfield_grid::DIRECTIONS_8`]).
///
/// Its passes are written by hand over plain buffers (`kernel`), several times faster than
/// candle's ops at VIN's sizes; the weights keep the file layout of envfield's other networks.
#[derive(Debug)]
pub struct Vin {
    config: VinConfig,
    /// Names, shapes and the seeded initialisation, in file order.
    store: ParamStore,
    weights: Weights,
}

impl Vin {
    /// A freshly initialised network (seeded).
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`].
    pub fn new(config: VinConfig, seed: u64) -> Result<Self> {
        config.validate()?;
        let device = Device::Cpu;
        let mut store = ParamStore::new(seed, &device);
        // VIN initialises every weight with standard deviation 0.01; larger Q weights make the
        // K max-iterations blow up.
        let small = Init::Normal(0.01);
        let (hidden, qc) = (config.hidden, config.q_channels);
        store.add("h.weight".into(), &[18, hidden], small)?;
        store.add("h.bias".into(), &[hidden], Init::Zeros)?;
        store.add("r.weight".into(), &[hidden, 1], small)?;
        store.add("r.bias".into(), &[1], Init::Zeros)?;
        store.add("q.weight".into(), &[18, qc], small)?;
        store.add("q.bias".into(), &[qc], Init::Zeros)?;
        store.add("policy.weight".into(), &[qc, ACTIONS], small)?;
        store.add("policy.bias".into(), &[ACTIONS], Init::Zeros)?;
        let weights = Self::read_store(&store)?;
        Ok(Self {
            config,
            store,
            weights,
        })
    }

    fn read_store(store: &ParamStore) -> Result<Weights> {
        let parts = store
            .vars()
            .iter()
            .map(|v| Ok(v.flatten_all()?.to_vec1::<f32>()?))
            .collect::<Result<Vec<_>>>()?;
        Ok(Weights::from_parts(parts))
    }

    /// The config.
    pub fn config(&self) -> &VinConfig {
        &self.config
    }

    /// The same network with `iterations` value-iteration steps: VIN's way to plan on larger
    /// maps than it was trained on (its paper raises K with the map's side; see
    /// [`VinConfig::for_size`]).
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] for iterations outside 1..=4096.
    pub fn with_iterations(mut self, iterations: usize) -> Result<Self> {
        let config = VinConfig {
            iterations,
            ..self.config
        };
        config.validate()?;
        self.config = config;
        Ok(self)
    }

    /// Number of trainable scalars.
    pub fn parameter_count(&self) -> usize {
        self.store.count()
    }

    pub(crate) fn weights(&self) -> &Weights {
        &self.weights
    }

    pub(crate) fn weights_mut(&mut self) -> &mut Weights {
        &mut self.weights
    }

    /// The 8 action logits at `state` of `grid` with `goal` (one full network pass).
    ///
    /// # Errors
    /// A state or goal outside the grid or on an obstacle.
    pub fn action_logits(&self, grid: &Grid2, goal: Cell2, state: Cell2) -> Result<[f32; 8]> {
        let goal = grid.check_free(goal, "goal")?;
        let state = grid.check_free(state, "state")?;
        let map = map_input(grid, goal);
        let fwd = kernel::forward(&self.weights, map, self.config.iterations, false);
        Ok(kernel::logits(&self.weights, &fwd.q, grid.len(), state))
    }

    /// Saves weights and config (atomically).
    ///
    /// # Errors
    /// I/O errors naming the file.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        self.write(path.as_ref(), None)
    }

    /// The weights as named tensors in file order (`prefix` before each name).
    fn named(&self, parts: &Weights, prefix: &str) -> Result<Vec<(String, Tensor)>> {
        let device = Device::Cpu;
        self.store
            .names()
            .iter()
            .zip(self.store.vars())
            .zip(parts.parts())
            .map(|((name, var), data)| {
                let t = Tensor::from_vec(data.clone(), var.dims(), &device)?;
                Ok((format!("{prefix}{name}"), t))
            })
            .collect()
    }

    /// Writes weights and config, and with `optimiser` RMSProp's mean squares and the step.
    pub(crate) fn write(&self, path: &Path, optimiser: Option<(&Weights, u64)>) -> Result<()> {
        let mut tensors = self.named(&self.weights, "")?;
        let file_config = VinFileConfig {
            config: self.config,
        };
        let mut meta = weight_metadata(FORMAT, &file_config)?;
        if let Some((squares, step)) = optimiser {
            tensors.extend(self.named(squares, SQUARES)?);
            meta.insert(META_STEP.into(), step.to_string());
        }
        write_weights(path, &tensors, meta)
    }

    /// Loads a network saved by [`Vin::save`] or a VIN training checkpoint.
    ///
    /// # Errors
    /// [`NetsError::Checkpoint`] for an unreadable or foreign file; missing, misshapen or
    /// unexpected tensors.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        Ok(Self::load_with_state(path.as_ref())?.0)
    }

    pub(crate) fn load_with_state(path: &Path) -> Result<(Self, Option<(Weights, u64)>)> {
        let mut file = TensorFile::read(path)?;
        let bad = |reason: String| NetsError::Checkpoint {
            path: path.to_path_buf(),
            reason,
        };
        let json = file
            .metadata
            .get(META_CONFIG)
            .ok_or_else(|| bad("no model config".into()))?;
        let cfg: VinFileConfig =
            serde_json::from_str(json).map_err(|e| bad(format!("not a VIN file: {e}")))?;
        let mut net = Self::new(cfg.config, 0)?;
        let device = Device::Cpu;
        let step = file.metadata.get(META_STEP).cloned();
        let mut take_all = |prefix: &str| -> Result<Weights> {
            let parts = net
                .store
                .names()
                .iter()
                .zip(net.store.vars())
                .map(|(name, var)| {
                    let t = file.take(path, &format!("{prefix}{name}"), var.dims(), &device)?;
                    Ok(t.flatten_all()?.to_vec1::<f32>()?)
                })
                .collect::<Result<Vec<_>>>()?;
            Ok(Weights::from_parts(parts))
        };
        net.weights = take_all("")?;
        let mut state = None;
        if let Some(step) = step {
            let step: u64 = step.parse().map_err(|e| bad(format!("bad step: {e}")))?;
            let squares = take_all(SQUARES).map_err(|e| match e {
                NetsError::MissingWeight { .. } => bad(
                    "a checkpoint without VIN's RMSProp state (written by an older trainer?)"
                        .into(),
                ),
                other => other,
            })?;
            state = Some((squares, step));
        }
        if let Some(name) = file.tensors.keys().min() {
            return Err(NetsError::UnexpectedWeight {
                path: path.to_path_buf(),
                name: name.clone(),
            });
        }
        Ok((net, state))
    }
}

/// The prefix of RMSProp's mean squares in a VIN checkpoint.
const SQUARES: &str = "optimiser.rmsprop.";

/// The kernel's view of a maze and its goal's flat index.
fn map_input(grid: &Grid2, goal: usize) -> MapInput<'_> {
    MapInput {
        obstacles: grid.obstacles(),
        rows: grid.rows(),
        cols: grid.cols(),
        goal,
    }
}

/// VIN's policy: the network runs on the maze for every move and scores the eight actions by
/// their logits, so `envfield_plan::PolicyWalk(vin)` plans as VIN does (the legal action with
/// the highest logit at every step).
impl Policy for Vin {
    fn name(&self) -> &str {
        "vin"
    }

    fn rule(&self) -> MoveRule {
        self.config.rule
    }

    fn action_scores(
        &self,
        grid: &Grid2,
        goal: Cell2,
        state: Cell2,
    ) -> envfield_grid::Result<[f32; 8]> {
        self.action_logits(grid, goal, state).map_err(|e| match e {
            NetsError::Grid(g) => g,
            other => envfield_grid::GridError::Model {
                model: "vin".into(),
                source: Box::new(other),
            },
        })
    }
}
