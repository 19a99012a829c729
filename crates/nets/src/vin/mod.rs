//! The Value Iteration Network baseline (Tamar et al. 2016): the network, its files and its
//! policy (the network called at every step, as VIN plans). Training is in [`train`].

mod train;

pub use train::{vin_examples, VinExample, VinTrainConfig, VinTrainer};

use crate::layers::{Conv, ConvSpec, IndexCache, Linear};
use crate::params::{
    weight_metadata, write_weights, AdamW, Init, ParamStore, TensorFile, FORMAT, META_CONFIG,
    META_STEP,
};
use crate::{NetsError, Result};
use candle_core::{Device, Tensor, D};
use envfield_grid::{Cell2, Grid2, MoveRule, Policy};
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
#[derive(Debug)]
pub struct Vin {
    config: VinConfig,
    store: ParamStore,
    h: Conv,
    r: Linear,
    q: Conv,
    policy: Linear,
    cache: IndexCache,
    device: Device,
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
        let h = Conv::with_init(&mut store, "h", 2, ConvSpec::new(config.hidden, 1), small)?;
        let r = Linear::new(&mut store, "r", config.hidden, 1, small)?;
        let q = Conv::with_init(
            &mut store,
            "q",
            2,
            ConvSpec::new(config.q_channels, 1),
            small,
        )?;
        let policy = Linear::new(&mut store, "policy", config.q_channels, 8, small)?;
        Ok(Self {
            config,
            store,
            h,
            r,
            q,
            policy,
            cache: IndexCache::default(),
            device,
        })
    }

    /// The config.
    pub fn config(&self) -> &VinConfig {
        &self.config
    }

    /// Number of trainable scalars.
    pub fn parameter_count(&self) -> usize {
        self.store.count()
    }

    /// The Q maps (B, H, W, q_channels) after K iterations, for mazes of one size.
    pub(crate) fn q_maps(&self, grids: &[&Grid2], goals: &[Cell2]) -> Result<Tensor> {
        let (h, w) = (grids[0].rows(), grids[0].cols());
        let b = grids.len();
        let mut input = vec![0f32; b * h * w * 2];
        for (k, (g, goal)) in grids.iter().zip(goals).enumerate() {
            if (g.rows(), g.cols()) != (h, w) {
                return Err(NetsError::InvalidInput("VIN batch mixes maze sizes".into()));
            }
            for (i, &o) in g.obstacles().iter().enumerate() {
                input[(k * h * w + i) * 2] = o as u8 as f32;
            }
            input[(k * h * w + goal.row * w + goal.col) * 2 + 1] = 10.0;
        }
        let x = Tensor::from_vec(input, (b, h, w, 2), &self.device)?;
        let hidden = self.h.forward(&x, &self.cache)?;
        let r = self
            .r
            .forward(&hidden.reshape((b * h * w, self.config.hidden))?)?
            .reshape((b, h, w, 1))?;
        let mut v = Tensor::zeros((b, h, w, 1), x.dtype(), &self.device)?;
        let mut q = self.q.forward(&Tensor::cat(&[&r, &v], 3)?, &self.cache)?;
        for _ in 0..self.config.iterations {
            v = q.max_keepdim(D::Minus1)?;
            q = self.q.forward(&Tensor::cat(&[&r, &v], 3)?, &self.cache)?;
        }
        Ok(q)
    }

    /// Action logits (N, 8) for `states[i]` of maze `items[i]`.
    pub(crate) fn logits(
        &self,
        q: &Tensor,
        w: usize,
        h: usize,
        states: &[(usize, Cell2)],
    ) -> Result<Tensor> {
        let ids: Vec<u32> = states
            .iter()
            .map(|&(b, c)| (b * h * w + c.row * w + c.col) as u32)
            .collect();
        let n = ids.len();
        let flat = q.reshape((
            q.elem_count() / self.config.q_channels,
            self.config.q_channels,
        ))?;
        let at = flat.index_select(&Tensor::from_vec(ids, n, &self.device)?, 0)?;
        self.policy.forward(&at)
    }

    /// The 8 action logits at `state` of `grid` with `goal` (one full network pass).
    ///
    /// # Errors
    /// A state or goal outside the grid or on an obstacle.
    pub fn action_logits(&self, grid: &Grid2, goal: Cell2, state: Cell2) -> Result<[f32; 8]> {
        grid.check_free(goal, "goal")?;
        grid.check_free(state, "state")?;
        let q = self.q_maps(&[grid], &[goal])?;
        let l = self.logits(&q, grid.cols(), grid.rows(), &[(0, state)])?;
        let v = l.flatten_all()?.to_vec1::<f32>()?;
        let mut out = [0f32; 8];
        out.copy_from_slice(&v);
        Ok(out)
    }

    /// Saves weights and config (atomically).
    ///
    /// # Errors
    /// I/O errors naming the file.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        self.write(path.as_ref(), None)
    }

    pub(crate) fn write(&self, path: &Path, optimiser: Option<&AdamW>) -> Result<()> {
        let mut tensors = self.store.named_tensors();
        let file_config = VinFileConfig {
            config: self.config,
        };
        let mut meta = weight_metadata(FORMAT, &file_config)?;
        if let Some(opt) = optimiser {
            tensors.extend(opt.state_tensors(self.store.names()));
            meta.insert(META_STEP.into(), opt.step.to_string());
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

    pub(crate) fn load_with_state(path: &Path) -> Result<(Self, Option<OptimiserState>)> {
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
        let net = Self::new(cfg.config, 0)?;
        let mut state = None;
        if let Some(step) = file.metadata.get(META_STEP).cloned() {
            let step: u64 = step.parse().map_err(|e| bad(format!("bad step: {e}")))?;
            let (m, v) = file.take_moments(path, &net.store, &net.device)?;
            state = Some((m, v, step));
        }
        let mut loaded = Vec::new();
        for (name, var) in net.store.names().iter().zip(net.store.vars()) {
            loaded.push(file.take(path, name, var.dims(), &net.device)?);
        }
        if let Some(name) = file.tensors.keys().min() {
            return Err(NetsError::UnexpectedWeight {
                path: path.to_path_buf(),
                name: name.clone(),
            });
        }
        for (var, t) in net.store.vars().iter().zip(loaded) {
            var.set(&t)?;
        }
        Ok((net, state))
    }
}

/// Adam's first and second moments and the step, as saved in a checkpoint.
pub(crate) type OptimiserState = (Vec<Tensor>, Vec<Tensor>, u64);

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
