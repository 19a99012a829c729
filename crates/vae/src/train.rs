//! [`VaeTrainer`]: Adam on reconstruction plus cyclically annealed KL, seeded batches from
//! [`RoomTorsos`], atomic checkpoints that resume exactly.

use crate::file::FORMAT;
use crate::index::XyIndex;
use crate::model::{KINDS, NORMAL_SALT};
use crate::{Cvae, Result, RoomTorsos, TorsoSource, VaeError, VaeTrainConfig};
use candle_core::Tensor;
use envfield_grid::normals;
use envfield_grid::SplitMix64;
use envfield_nets::params::{write_weights, AdamW, TensorFile, META_STEP};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// One step's batch: clouds, torsos, noise, a gated VAE's neighbourhoods with their
/// occupancy labels, and the torsos' one-hot pose kinds for a VAE with kinds.
type Batch = (
    Tensor,
    Tensor,
    Tensor,
    Option<(Tensor, Tensor)>,
    Option<Tensor>,
);

/// The metadata key of a checkpoint's training config.
const META_TRAIN: &str = "envfield.vae_train";

/// After each step: where training stands.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VaeProgress {
    /// Steps done.
    pub step: u64,
    /// Steps in the run.
    pub steps: u64,
    /// This step's loss (reconstruction + weighted KL).
    pub loss: f32,
    /// Its reconstruction part.
    pub recon: f32,
    /// Its KL part (unweighted).
    pub kl: f32,
    /// The occupancy gate's cross-entropy (unweighted; 0 without a gate).
    #[serde(default)]
    pub gate: f32,
    /// The pose-kind head's cross-entropy (unweighted; 0 without kinds).
    #[serde(default)]
    pub kind: f32,
    /// The KL weight of this step.
    pub kl_weight: f64,
    /// Whether a checkpoint was written after it.
    pub checkpointed: bool,
    /// Seconds since the run started.
    pub seconds: f64,
}

/// Trains a [`Cvae`].
#[derive(Debug)]
pub struct VaeTrainer {
    vae: Cvae,
    optimiser: AdamW,
    config: VaeTrainConfig,
}

impl VaeTrainer {
    /// A trainer for `vae` at step 0 (Adam: betas 0.9 and 0.999, no weight decay).
    ///
    /// # Errors
    /// [`VaeError::InvalidConfig`] for a bad config.
    pub fn new(vae: Cvae, config: VaeTrainConfig) -> Result<Self> {
        config.validate()?;
        let optimiser = AdamW::new(vae.vars(), config.lr, (0.9, 0.999), 1e-8, 0.0)?;
        Ok(Self {
            vae,
            optimiser,
            config,
        })
    }

    /// Steps done so far.
    pub fn step(&self) -> u64 {
        self.optimiser.step
    }

    /// The VAE.
    pub fn vae(&self) -> &Cvae {
        &self.vae
    }

    /// The training config.
    pub fn config(&self) -> &VaeTrainConfig {
        &self.config
    }

    /// Lengthens (or shortens) the run: the KL schedule's cycles stretch with it.
    pub fn set_steps(&mut self, steps: u64) {
        self.config.steps = steps;
    }

    /// A draw of one of `room`'s torso indices: a kind by `source_weights` among the kinds
    /// the room has, then a torso of that kind (any torso when no kind has weight).
    fn kind_picker<'r>(&self, room: &'r RoomTorsos) -> impl Fn(&mut SplitMix64) -> usize + 'r {
        const KINDS: [TorsoSource; 4] = [
            TorsoSource::Walk,
            TorsoSource::Sit,
            TorsoSource::Lie,
            TorsoSource::Stand,
        ];
        let by_kind: Vec<Vec<usize>> = KINDS
            .iter()
            .map(|&s| {
                (0..room.torsos.len())
                    .filter(|&i| room.sources[i] == s)
                    .collect()
            })
            .collect();
        let weights: Vec<f32> = (0..4)
            .map(|j| match by_kind[j].is_empty() {
                true => 0.0,
                false => self.config.source_weights[j],
            })
            .collect();
        let total: f32 = weights.iter().sum();
        let all = room.torsos.len();
        move |rng: &mut SplitMix64| {
            if total <= 0.0 {
                return rng.below(all);
            }
            let mut u = rng.next_f32() * total;
            let j = (0..4)
                .find(|&j| {
                    u -= weights[j];
                    u < 0.0 && weights[j] > 0.0
                })
                .unwrap_or_else(|| (0..4).rfind(|&j| weights[j] > 0.0).unwrap_or(0));
            by_kind[j][rng.below(by_kind[j].len())]
        }
    }

    /// One step's batch: `(clouds, torsos, eps, gate, kinds)`, normalised. For the paper's VAE,
    /// `scenes_per_step` rooms' clouds of `points` points and `torsos_per_scene` torso
    /// locations each. For a local VAE, `scenes_per_step x torsos_per_scene` torso locations,
    /// each with its own neighbourhood around an anchor `jitter` away, the torso relative to
    /// it (`index` holds each room's binned cloud). Torsos are drawn by kind with
    /// `source_weights` among the kinds a room has. For a gated VAE, `gate` holds as many
    /// neighbourhoods again around anchors uniform over the same rooms, each labelled 1 when
    /// one of the room's torsos lies within the gate's radius (`torso_index` holds each
    /// room's binned torsos). With pose kinds, `kinds` holds each torso's one-hot kind.
    fn batch(
        &self,
        data: &[RoomTorsos],
        index: &[XyIndex],
        torso_index: &[XyIndex],
        step: u64,
    ) -> Result<Batch> {
        let mut rng = SplitMix64::new(self.config.seed ^ step.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let (b, k, n) = (
            self.config.scenes_per_step,
            self.config.torsos_per_scene,
            self.vae.config().points,
        );
        let (mut cloud, mut torsos) = (Vec::with_capacity(b * n), Vec::with_capacity(b * k));
        let local = self.vae.config().local;
        let gate = local.and_then(|l| l.gate.map(|g| (l, g)));
        let (mut gate_cloud, mut labels) = (Vec::new(), Vec::new());
        let with_kinds = self.vae.has_kinds();
        let mut kinds = Vec::new();
        for _ in 0..b {
            let r = rng.below(data.len());
            let room = &data[r];
            if let Some((l, g)) = gate {
                let [x0, y0, x1, y1] = index[r].extent;
                for _ in 0..k {
                    let a = [
                        x0 + (x1 - x0) * rng.next_f32(),
                        y0 + (y1 - y0) * rng.next_f32(),
                    ];
                    gate_cloud.extend(index[r].neighbourhood(&room.cloud, a, &l, &mut rng));
                    let occupied = torso_index[r].any_within(&room.torsos, a, g.radius);
                    labels.push(if occupied { 1f32 } else { 0.0 });
                }
            }
            if local.is_none() {
                for _ in 0..n {
                    cloud.push(room.cloud[rng.below(room.cloud.len())]);
                }
            }
            let pick = self.kind_picker(room);
            for _ in 0..k {
                let i = pick(&mut rng);
                let t = room.torsos[i];
                if with_kinds {
                    let mut onehot = [0f32; KINDS];
                    onehot[kind_index(room.kinds[i])?] = 1.0;
                    kinds.extend(onehot);
                }
                match &local {
                    None => torsos.push(t),
                    Some(l) => {
                        let g = normals(2, rng.next_u64() ^ NORMAL_SALT);
                        let anchor = [t[0] + l.jitter * g[0], t[1] + l.jitter * g[1]];
                        cloud.extend(index[r].neighbourhood(&room.cloud, anchor, l, &mut rng));
                        torsos.push([t[0] - anchor[0], t[1] - anchor[1], t[2]]);
                    }
                }
            }
        }
        // A local batch is b * k neighbourhoods with one torso each.
        let (b, k) = match local {
            Some(_) => (b * k, 1),
            None => (b, k),
        };
        let cloud = self
            .vae
            .coords(&cloud, "training clouds")?
            .reshape((b, n, 3))?;
        let torsos = self.vae.coords(&torsos, "training torsos")?;
        let latent = self.vae.config().latent;
        let eps = Tensor::from_vec(
            normals(b * k * latent, rng.next_u64() ^ NORMAL_SALT),
            (b * k, latent),
            self.vae.device(),
        )?;
        let gate = match labels.is_empty() {
            true => None,
            false => Some((
                self.vae
                    .coords(&gate_cloud, "training neighbourhoods")?
                    .reshape((labels.len(), n, 3))?,
                Tensor::from_vec(labels, gate_cloud.len() / n, self.vae.device())?,
            )),
        };
        let kinds = match with_kinds {
            true => Some(Tensor::from_vec(kinds, (b * k, KINDS), self.vae.device())?),
            false => None,
        };
        Ok((cloud, torsos, eps, gate, kinds))
    }

    /// Trains until the config's `steps` (from the current step) on `data`, checkpointing to
    /// `checkpoint`, calling `on_progress` after every step (returning `false` stops, with a
    /// checkpoint). Returns the last step's progress.
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] for no rooms, or a room without cloud or torsos;
    /// [`VaeError::Diverged`]; I/O errors of the checkpoint.
    pub fn run(
        &mut self,
        data: &[RoomTorsos],
        checkpoint: Option<&Path>,
        mut on_progress: impl FnMut(&VaeProgress) -> bool,
    ) -> Result<Option<VaeProgress>> {
        if data.is_empty() {
            return Err(VaeError::InvalidInput("no training rooms".into()));
        }
        if let Some(i) = data.iter().position(|r| {
            r.cloud.is_empty()
                || r.torsos.is_empty()
                || r.sources.len() != r.torsos.len()
                || r.kinds.len() != r.torsos.len()
        }) {
            return Err(VaeError::InvalidInput(format!(
                "training room {i} has no surface points, no torso locations, or not one \
                 source and one kind per torso location"
            )));
        }
        if self.vae.has_kinds() {
            if let Some(i) = data
                .iter()
                .position(|r| r.kinds.iter().any(Option::is_none))
            {
                return Err(VaeError::InvalidInput(format!(
                    "training room {i} has torso locations that afford no pose: a VAE with pose \
                     kinds trains on affordable ones only (TorsoDataConfig::affordable_only)"
                )));
            }
        }
        // Each room's binned cloud, for a local VAE's neighbourhoods.
        let index: Vec<XyIndex> = match self.vae.config().local {
            Some(l) => data
                .iter()
                .enumerate()
                .map(|(i, r)| XyIndex::new(&r.cloud, l.radius, &format!("training room {i}")))
                .collect::<Result<_>>()?,
            None => Vec::new(),
        };
        // Each room's binned torsos, for a gated VAE's occupancy labels.
        let torso_index: Vec<XyIndex> = match self.vae.config().local.and_then(|l| l.gate) {
            Some(g) => data
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    XyIndex::new(&r.torsos, g.radius, &format!("training room {i}'s torsos"))
                })
                .collect::<Result<_>>()?,
            None => Vec::new(),
        };
        let start = Instant::now();
        let mut last = None;
        while self.step() < self.config.steps {
            let step = self.step();
            let (cloud, torsos, eps, gate, kinds) = self.batch(data, &index, &torso_index, step)?;
            let kl_weight = self.config.kl_weight(step);
            let sigma = self.config.recon_sigma / self.vae.config().coord_scale;
            let gate = gate.as_ref().map(|(h, l)| (h, l));
            let loss = self.vae.loss(
                &cloud,
                &torsos,
                &eps,
                (kl_weight, sigma),
                gate,
                kinds.as_ref(),
            )?;
            let value = loss.total.to_scalar::<f32>()?;
            if !value.is_finite() {
                return Err(VaeError::Diverged { step, loss: value });
            }
            self.optimiser.backward_step(self.vae.vars(), &loss.total)?;
            let done = self.step();
            let every = self.config.checkpoint_every;
            let due = done >= self.config.steps || (every > 0 && done % every == 0);
            let checkpointed = match checkpoint {
                Some(p) if due => {
                    self.save_checkpoint(p)?;
                    true
                }
                _ => false,
            };
            let progress = VaeProgress {
                step: done,
                steps: self.config.steps,
                loss: value,
                recon: loss.recon,
                kl: loss.kl,
                gate: loss.gate,
                kind: loss.kind,
                kl_weight,
                checkpointed,
                seconds: start.elapsed().as_secs_f64(),
            };
            let go_on = on_progress(&progress);
            last = Some(progress);
            if !go_on {
                if let (Some(p), false) = (checkpoint, checkpointed) {
                    self.save_checkpoint(p)?;
                }
                break;
            }
        }
        Ok(last)
    }

    /// Writes the weights, Adam's moments, the step and the training config, atomically. A
    /// checkpoint loads as a VAE too ([`Cvae::load`]).
    ///
    /// # Errors
    /// I/O errors, naming the file.
    pub fn save_checkpoint(&self, path: impl AsRef<Path>) -> Result<()> {
        let (mut tensors, mut meta) = self.vae.named()?;
        tensors.extend(self.optimiser.state_tensors(self.vae.store().names()));
        meta.insert(META_STEP.to_string(), self.step().to_string());
        meta.insert(
            META_TRAIN.to_string(),
            serde_json::to_string(&self.config)
                .map_err(|e| VaeError::InvalidInput(format!("cannot serialise the config: {e}")))?,
        );
        write_weights(path.as_ref(), &tensors, meta)?;
        Ok(())
    }

    /// Resumes from a checkpoint written by [`VaeTrainer::save_checkpoint`]: the same weights,
    /// moments, step and config, so the run goes on exactly as if it had not stopped.
    ///
    /// # Errors
    /// [`VaeError::Checkpoint`] for a weight file without training state, or a file that does
    /// not fit.
    pub fn resume(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let mut file = TensorFile::read_format(path, FORMAT)?;
        let bad = |reason: String| VaeError::Checkpoint {
            path: path.to_path_buf(),
            reason,
        };
        let step: u64 = file
            .metadata
            .get(META_STEP)
            .ok_or_else(|| bad("no step: a weight file, not a training checkpoint".into()))?
            .parse()
            .map_err(|e| bad(format!("bad step: {e}")))?;
        let config: VaeTrainConfig = serde_json::from_str(
            file.metadata
                .get(META_TRAIN)
                .ok_or_else(|| bad("no training config".into()))?,
        )
        .map_err(|e| bad(format!("bad training config: {e}")))?;
        let vae = Cvae::from_file(path, &mut file)?;
        let (m, v) = file.take_moments(path, vae.store(), vae.device())?;
        let mut trainer = Self::new(vae, config)?;
        trainer.optimiser.set_moments(m, v, step);
        Ok(trainer)
    }
}

/// A pose kind's index among the [`KINDS`] outputs: standing, sitting, lying.
fn kind_index(kind: Option<crate::PoseKind>) -> Result<usize> {
    kind.map(crate::PoseKind::index).ok_or_else(|| {
        VaeError::InvalidInput("a torso location that affords no pose has no kind".into())
    })
}
