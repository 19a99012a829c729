//! The VAE's config and its training config.

use crate::{Result, VaeError};
use serde::{Deserialize, Serialize};

/// The conditional VAE of torso locations (paper section 4.2, Fig. 6): a PointNet reads the
/// scene's surface points into one global feature; the encoder maps (feature, torso xyz) to a
/// diagonal Gaussian over `latent` dimensions; the decoder maps (z, feature) back to a torso
/// xyz. Serialised into every weight file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VaeConfig {
    /// Widths of the PointNet's shared per-point layers (ReLU); the last is the feature size.
    pub pointnet: Vec<usize>,
    /// Surface points per scene cloud.
    pub points: usize,
    /// Latent dimensions.
    pub latent: usize,
    /// Width of the encoder's and decoder's hidden layers.
    pub hidden: usize,
    /// Hidden layers of the encoder and of the decoder.
    pub layers: usize,
    /// Coordinates enter as `(p - coord_offset) / coord_scale` (metres), the same for the cloud
    /// and the torsos.
    pub coord_offset: [f32; 3],
    /// See [`VaeConfig::coord_offset`].
    pub coord_scale: f32,
    /// Local conditioning in place of the whole room's feature: `None` is the paper's cVAE.
    #[serde(default)]
    pub local: Option<LocalConfig>,
}

/// Conditioning on the scene near a place instead of the whole scene. The PointNet reads the
/// surface points within `radius` (in x and y) of an *anchor*, relative to it; the decoder
/// gives a torso location relative to the anchor. Sampling draws anchors uniformly over the
/// cloud's extent in x and y, one torso each, so every part of the room is asked what a
/// person could do there: a global feature must encode where the seats are, a local one only
/// what is near. Training anchors are torso locations moved by `jitter`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LocalConfig {
    /// Neighbourhood radius in x and y, metres.
    pub radius: f32,
    /// Points per neighbourhood (drawn with replacement from those within the radius).
    pub points: usize,
    /// Standard deviation of the training anchors around their torso, metres.
    pub jitter: f32,
    /// Surface points a room's cloud should hold (dense enough that a neighbourhood sees a
    /// seat).
    pub cloud: usize,
    /// The occupancy gate on sampling anchors (`None`: every anchor is decoded).
    #[serde(default)]
    pub gate: Option<GateConfig>,
}

/// The occupancy gate of a local VAE: a second head on the neighbourhood's feature gives the
/// probability that someone can be at the anchor, and sampling decodes only the anchors it
/// passes. Anchors drawn uniformly over a room fall on tables, wardrobes and walls as often as
/// on floor; a decoder trained only next to real torsos has nothing sensible to say there, so
/// the gate says "nobody" instead. With the gate the VAE is a hurdle model: nobody with
/// probability `1 - gate`, else a torso from the conditional VAE.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GateConfig {
    /// In training, an anchor is occupied when a training torso lies within this distance of
    /// it in x and y, metres (about the floor grid's half diagonal, so the occupied set has
    /// no holes).
    pub radius: f32,
    /// Sampling keeps the anchors whose occupancy probability is at least this.
    pub threshold: f32,
    /// Weight of the gate's cross-entropy in the training loss (and of the pose-kind head's,
    /// with `kinds`).
    pub weight: f32,
    /// Pose kinds: the decoder gives one torso per kind of pose (standing, sitting, lying),
    /// the encoder reads the torso's kind, and a third head, on the same neighbourhood
    /// feature, picks the kind a sample takes. A single Gaussian decoder over a standing
    /// height of 0.93 m and a sitting one of 0.53 m fills the gap between them with torsos
    /// that afford neither; with kinds the latent code only has to carry what varies within
    /// a kind. Trains on torsos labelled by the pose they afford
    /// (`envfield_rooms::TorsoDataConfig::affordable_only`).
    #[serde(default)]
    pub kinds: bool,
}

impl VaeConfig {
    /// The local variant ([`LocalConfig`]): neighbourhoods of 0.6 m, 64 points, anchors
    /// 0.25 m around their torso; relative coordinates enter over 0.6 m, heights about 0.8 m.
    pub fn local() -> Self {
        Self {
            points: 64,
            coord_offset: [0.0, 0.0, 0.8],
            coord_scale: 0.6,
            local: Some(LocalConfig {
                radius: 0.6,
                points: 64,
                jitter: 0.25,
                cloud: 8192,
                gate: None,
            }),
            ..Self::default()
        }
    }

    /// The gated local variant: [`VaeConfig::local`] with anchors 0.05 m around their torso,
    /// so the decoder gives a torso's height where it is asked rather than guessing where
    /// near the anchor it might be, an occupancy [`GateConfig`] (radius 0.08 m, threshold
    /// 0.5, weight 1) that keeps anchors where nobody can be from being decoded, and pose
    /// kinds ([`GateConfig::kinds`]).
    pub fn local_gated() -> Self {
        let mut c = Self::local();
        if let Some(l) = c.local.as_mut() {
            l.jitter = 0.05;
            l.gate = Some(GateConfig {
                radius: 0.08,
                threshold: 0.5,
                weight: 1.0,
                kinds: true,
            });
        }
        c
    }
}

impl Default for VaeConfig {
    fn default() -> Self {
        Self {
            pointnet: vec![64, 128, 128],
            points: 512,
            latent: 8,
            hidden: 256,
            layers: 2,
            coord_offset: [3.5, 3.0, 1.0],
            coord_scale: 3.0,
            local: None,
        }
    }
}

/// The most scalars a VAE may have: a config past it is a typo.
const MAX_WIDTH: usize = 1 << 14;

impl VaeConfig {
    /// Checks every setting.
    ///
    /// # Errors
    /// [`VaeError::InvalidConfig`] naming the setting.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(VaeError::InvalidConfig(m));
        if self.pointnet.is_empty() || self.pointnet.iter().any(|&w| w == 0 || w > MAX_WIDTH) {
            return bad(format!(
                "pointnet: one or more widths in 1..={MAX_WIDTH} (got {:?})",
                self.pointnet
            ));
        }
        if !(1..=1 << 16).contains(&self.points) {
            return bad(format!("points: 1 to 65536 (got {})", self.points));
        }
        if !(1..=256).contains(&self.latent) {
            return bad(format!("latent: 1 to 256 (got {})", self.latent));
        }
        if !(1..=MAX_WIDTH).contains(&self.hidden) || !(1..=16).contains(&self.layers) {
            return bad(format!(
                "hidden 1..={MAX_WIDTH} and layers 1..=16 (got {} and {})",
                self.hidden, self.layers
            ));
        }
        if let Some(l) = self.local {
            if !(l.radius.is_finite() && l.radius > 0.0 && l.jitter.is_finite() && l.jitter >= 0.0)
                || l.points != self.points
                || !(1..=1 << 22).contains(&l.cloud)
            {
                return bad(format!(
                    "local: a positive radius, a jitter >= 0, points equal to `points` and a \
                     cloud of 1 to 2^22 points (got {l:?}, points {})",
                    self.points
                ));
            }
            if let Some(g) = l.gate {
                if !(g.radius.is_finite()
                    && g.radius > 0.0
                    && (0.0..1.0).contains(&g.threshold)
                    && g.weight.is_finite()
                    && g.weight >= 0.0)
                {
                    return bad(format!(
                        "gate: a positive radius, a threshold in [0, 1) and a weight >= 0 \
                         (got {g:?})"
                    ));
                }
            }
        }
        if !(self.coord_offset.iter().all(|v| v.is_finite())
            && self.coord_scale.is_finite()
            && self.coord_scale > 0.0)
        {
            return bad(format!(
                "coord_offset finite and coord_scale positive (got {:?} and {})",
                self.coord_offset, self.coord_scale
            ));
        }
        Ok(())
    }
}

/// How the VAE trains.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VaeTrainConfig {
    /// Adam's learning rate (the paper's 5e-5).
    pub lr: f64,
    /// Optimiser steps.
    pub steps: u64,
    /// Scenes per step.
    pub scenes_per_step: usize,
    /// Torso locations per scene per step.
    pub torsos_per_scene: usize,
    /// Cycles of the KL weight's annealing (Fu et al. 2019): in each cycle it ramps from 0 to
    /// `kl_max` over the first half and stays there for the second.
    pub cycles: usize,
    /// The KL weight at the top of each cycle.
    pub kl_max: f64,
    /// The reconstruction's standard deviation in metres: the reconstruction loss is the
    /// squared error over `2 sigma^2`, a Gaussian likelihood.
    pub recon_sigma: f32,
    /// How often each kind of torso location is drawn into a batch, in [`TorsoSource`](crate::TorsoSource) order
    /// (walk, sit, lie, stand), among the kinds a room has. Standing poses on the floor grid
    /// outnumber seated ones about five to one; drawn in proportion, the VAE averages the
    /// rarer poses away.
    pub source_weights: [f32; 4],
    /// Seed of batches, noise and the cloud subsets.
    pub seed: u64,
    /// Checkpoint every this many steps (0: only at the end).
    pub checkpoint_every: u64,
}

impl Default for VaeTrainConfig {
    fn default() -> Self {
        Self {
            lr: 5e-5,
            steps: 4000,
            scenes_per_step: 16,
            torsos_per_scene: 64,
            cycles: 4,
            kl_max: 1.0,
            recon_sigma: 0.1,
            source_weights: [1.0; 4],
            seed: 0,
            checkpoint_every: 500,
        }
    }
}

impl VaeTrainConfig {
    /// Checks every setting.
    ///
    /// # Errors
    /// [`VaeError::InvalidConfig`] naming the setting.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(VaeError::InvalidConfig(m));
        if !(self.lr.is_finite() && self.lr > 0.0) {
            return bad(format!("lr must be positive (got {})", self.lr));
        }
        if self.scenes_per_step == 0 || self.torsos_per_scene == 0 {
            return bad("scenes_per_step and torsos_per_scene must be at least 1".into());
        }
        // A step's batch holds every scene's cloud and torsos: past a million torsos a step
        // no machine this runs on has the memory, and the allocation would abort.
        if self.scenes_per_step > 4096
            || self.scenes_per_step.saturating_mul(self.torsos_per_scene) > 1_000_000
        {
            return bad(format!(
                "scenes_per_step x torsos_per_scene: at most 4096 scenes and 1,000,000 torsos \
                 a step (got {} x {})",
                self.scenes_per_step, self.torsos_per_scene
            ));
        }
        if self.cycles == 0 {
            return bad("cycles must be at least 1".into());
        }
        if !(self.kl_max.is_finite() && self.kl_max >= 0.0) {
            return bad(format!(
                "kl_max must be finite and >= 0 (got {})",
                self.kl_max
            ));
        }
        if !self
            .source_weights
            .iter()
            .all(|w| w.is_finite() && *w >= 0.0)
            || self.source_weights.iter().sum::<f32>() <= 0.0
        {
            return bad(format!(
                "source_weights must be >= 0 with a positive sum (got {:?})",
                self.source_weights
            ));
        }
        if !(self.recon_sigma.is_finite() && self.recon_sigma > 0.0) {
            return bad(format!(
                "recon_sigma must be positive (got {})",
                self.recon_sigma
            ));
        }
        Ok(())
    }

    /// The KL weight at `step`: the cyclical annealing schedule of Fu et al. (NAACL 2019).
    /// The run's steps are split into `cycles` equal cycles; within each, the weight rises
    /// linearly from 0 to `kl_max` over the first half and holds for the second.
    ///
    /// ```
    /// let c = envfield_vae::VaeTrainConfig { steps: 400, cycles: 4, ..Default::default() };
    /// assert_eq!(c.kl_weight(0), 0.0);
    /// assert_eq!(c.kl_weight(25), 0.5);
    /// assert_eq!(c.kl_weight(75), 1.0);
    /// assert_eq!(c.kl_weight(100), 0.0); // the second cycle starts again
    /// ```
    pub fn kl_weight(&self, step: u64) -> f64 {
        let period = (self.steps as f64 / self.cycles as f64).max(1.0);
        let phase = (step as f64 % period) / period;
        self.kl_max * (2.0 * phase).min(1.0)
    }
}
