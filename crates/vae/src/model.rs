//! [`Cvae`]: the PointNet scene encoder and the conditional VAE of torso locations: its layers,
//! construction and the encoder and decoder passes every variant shares.

use crate::{Result, VaeConfig, VaeError};
use candle_core::{Device, Tensor, Var};
use envfield_grid::SplitMix64;
use envfield_nets::params::{Init, ParamStore};

/// A dense layer `x W + b`.
#[derive(Debug)]
pub(crate) struct Dense {
    w: Tensor,
    b: Tensor,
}

impl Dense {
    /// He-initialised weights for a ReLU layer, or small ones for an output layer.
    fn new(
        store: &mut ParamStore,
        name: &str,
        fan_in: usize,
        fan_out: usize,
        out: bool,
    ) -> Result<Self> {
        let std = if out {
            0.01
        } else {
            (2.0 / fan_in as f32).sqrt()
        };
        Ok(Self {
            w: store.add(
                format!("{name}.weight"),
                &[fan_in, fan_out],
                Init::Normal(std),
            )?,
            b: store.add(format!("{name}.bias"), &[fan_out], Init::Zeros)?,
        })
    }

    fn forward(&self, x: &Tensor) -> Result<Tensor> {
        Ok(x.matmul(&self.w)?.broadcast_add(&self.b)?)
    }
}

/// ReLU layers then a linear output layer.
fn mlp(layers: &[Dense], out: &Dense, x: &Tensor) -> Result<Tensor> {
    let mut h = x.clone();
    for l in layers {
        h = l.forward(&h)?.relu()?;
    }
    out.forward(&h)
}

/// The conditional VAE of torso locations ([`VaeConfig`]), its parameters and its device.
///
/// Points and torso locations are `[x, y, z]` in metres, z up, in the scene's frame.
#[derive(Debug)]
pub struct Cvae {
    pub(crate) config: VaeConfig,
    pub(crate) store: ParamStore,
    pub(crate) pointnet: Vec<Dense>,
    pub(crate) encoder: Vec<Dense>,
    pub(crate) encoder_out: Dense,
    pub(crate) decoder: Vec<Dense>,
    pub(crate) decoder_out: Dense,
    /// The occupancy gate's hidden and output layers, for a gated local VAE.
    pub(crate) gate: Option<(Dense, Dense)>,
    /// The pose-kind head's hidden and output layers, for a VAE with pose kinds.
    pub(crate) kind: Option<(Dense, Dense)>,
    pub(crate) device: Device,
}

/// The three variants of [`Cvae`], fixed by its config: which views
/// ([`Cvae::as_whole`], [`Cvae::as_local`], [`Cvae::as_gated`]) it offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VaeKind {
    /// The paper's VAE: one PointNet feature of the whole scene ([`VaeConfig::default`]).
    Whole,
    /// The local VAE: the surface points around an anchor ([`VaeConfig::local`]).
    Local,
    /// The local VAE with an occupancy gate, and with pose kinds when `kinds`
    /// ([`VaeConfig::local_gated`]).
    Gated {
        /// Whether it has the pose-kind head.
        kinds: bool,
    },
}

impl Cvae {
    /// A freshly initialised VAE on the CPU; the same config and seed give the same weights.
    ///
    /// # Errors
    /// [`VaeError::InvalidConfig`] for a bad config.
    pub fn new(config: VaeConfig, seed: u64) -> Result<Self> {
        Self::new_on(config, seed, &Device::Cpu)
    }

    /// As [`Cvae::new`] on `device`.
    ///
    /// # Errors
    /// As [`Cvae::new`].
    pub fn new_on(config: VaeConfig, seed: u64, device: &Device) -> Result<Self> {
        config.validate()?;
        let mut store = ParamStore::new(seed, device);
        let mut pointnet = Vec::new();
        let mut width = 3;
        for (i, &w) in config.pointnet.iter().enumerate() {
            pointnet.push(Dense::new(
                &mut store,
                &format!("pointnet.{i}"),
                width,
                w,
                false,
            )?);
            width = w;
        }
        let feature = width;
        let stack = |store: &mut ParamStore, name: &str, input: usize| -> Result<Vec<Dense>> {
            let mut out = Vec::new();
            let mut w = input;
            for i in 0..config.layers {
                out.push(Dense::new(
                    store,
                    &format!("{name}.{i}"),
                    w,
                    config.hidden,
                    false,
                )?);
                w = config.hidden;
            }
            Ok(out)
        };
        let kinds = config.local.and_then(|l| l.gate).is_some_and(|g| g.kinds);
        // With pose kinds the encoder also reads the torso's kind (one-hot) and the decoder
        // gives one torso per kind.
        let (kind_in, outs) = if kinds { (KINDS, KINDS) } else { (0, 1) };
        let encoder = stack(&mut store, "encoder", feature + 3 + kind_in)?;
        let encoder_out = Dense::new(
            &mut store,
            "encoder.out",
            config.hidden,
            2 * config.latent,
            true,
        )?;
        let decoder = stack(&mut store, "decoder", feature + config.latent)?;
        let decoder_out = Dense::new(&mut store, "decoder.out", config.hidden, 3 * outs, true)?;
        let gate = match config.local.and_then(|l| l.gate) {
            Some(_) => Some((
                Dense::new(&mut store, "gate.0", feature, config.hidden, false)?,
                Dense::new(&mut store, "gate.out", config.hidden, 1, true)?,
            )),
            None => None,
        };
        let kind = match kinds {
            true => Some((
                Dense::new(&mut store, "kind.0", feature, config.hidden, false)?,
                Dense::new(&mut store, "kind.out", config.hidden, KINDS, true)?,
            )),
            false => None,
        };
        Ok(Self {
            config,
            store,
            pointnet,
            encoder,
            encoder_out,
            decoder,
            decoder_out,
            gate,
            kind,
            device: device.clone(),
        })
    }

    /// The VAE's config.
    pub fn config(&self) -> &VaeConfig {
        &self.config
    }

    /// Number of trainable scalars.
    pub fn parameter_count(&self) -> usize {
        self.store.count()
    }

    pub(crate) fn store(&self) -> &ParamStore {
        &self.store
    }

    pub(crate) fn vars(&self) -> &[Var] {
        self.store.vars()
    }

    pub(crate) fn device(&self) -> &Device {
        &self.device
    }

    /// `points` normalised as a (len, 3) tensor, each checked finite; `what` names them in
    /// errors.
    pub(crate) fn coords(&self, points: &[[f32; 3]], what: &str) -> Result<Tensor> {
        if points.is_empty() {
            return Err(VaeError::InvalidInput(format!("{what}: no points")));
        }
        let (o, s) = (self.config.coord_offset, self.config.coord_scale);
        let mut data = Vec::with_capacity(points.len() * 3);
        for (i, p) in points.iter().enumerate() {
            if !p.iter().all(|v| v.is_finite()) {
                return Err(VaeError::InvalidInput(format!(
                    "{what}: point {i} is not finite: {p:?}"
                )));
            }
            data.extend((0..3).map(|a| (p[a] - o[a]) / s));
        }
        Ok(Tensor::from_vec(data, (points.len(), 3), &self.device)?)
    }

    /// (B, N, 3) normalised clouds -> (B, F) global features: the shared per-point MLP, then a
    /// maximum over the points, so the feature does not depend on their order.
    pub(crate) fn features(&self, clouds: &Tensor) -> Result<Tensor> {
        let (b, n, _) = clouds.dims3()?;
        let mut h = clouds.reshape((b * n, 3))?;
        for l in &self.pointnet {
            h = l.forward(&h)?.relu()?;
        }
        let f = h.dim(1)?;
        Ok(h.reshape((b, n, f))?.max(1)?)
    }

    /// `feature` (B, F) repeated `k` times per row, (B * k, F).
    pub(crate) fn repeat(feature: &Tensor, k: usize) -> Result<Tensor> {
        let (b, f) = feature.dims2()?;
        Ok(feature
            .unsqueeze(1)?
            .broadcast_as((b, k, f))?
            .contiguous()?
            .reshape((b * k, f))?)
    }

    /// The encoder on (B * k, F) repeated features and (B * k, 3) normalised torsos (and,
    /// with pose kinds, their (B * k, 3) one-hot kinds): mean and log variance, each
    /// (B * k, latent); the log variance is clamped to [-12, 8].
    pub(crate) fn encode_with(
        &self,
        feature: &Tensor,
        torsos: &Tensor,
        kinds: Option<&Tensor>,
    ) -> Result<(Tensor, Tensor)> {
        let input = match kinds {
            Some(k) => Tensor::cat(&[feature, torsos, k], 1)?,
            None => Tensor::cat(&[feature, torsos], 1)?,
        };
        let out = mlp(&self.encoder, &self.encoder_out, &input)?;
        let l = self.config.latent;
        let mean = out.narrow(1, 0, l)?;
        let log_var = out.narrow(1, l, l)?.clamp(-12f32, 8f32)?;
        Ok((mean, log_var))
    }

    /// The decoder on (n, latent) codes and (n, F) features: (n, 3) normalised torsos, or
    /// with pose kinds the torso of each row's kind in the (n, 3) one-hot `kinds`.
    pub(crate) fn decode_with(
        &self,
        z: &Tensor,
        feature: &Tensor,
        kinds: Option<&Tensor>,
    ) -> Result<Tensor> {
        let out = mlp(
            &self.decoder,
            &self.decoder_out,
            &Tensor::cat(&[z, feature], 1)?,
        )?;
        match kinds {
            None => Ok(out),
            Some(k) => {
                let n = out.dim(0)?;
                Ok(out
                    .reshape((n, KINDS, 3))?
                    .broadcast_mul(&k.unsqueeze(2)?)?
                    .sum(1)?)
            }
        }
    }

    /// The decoder next to neighbourhoods of (n, F) features: with pose kinds, each row's kind
    /// drawn (seeded by `rng`) from the kind head's probabilities.
    pub(crate) fn decode_local(
        &self,
        z: &Tensor,
        feature: &Tensor,
        rng: &mut SplitMix64,
    ) -> Result<Tensor> {
        let Some(logits) = self.kind_logits(feature)? else {
            return self.decode_with(z, feature, None);
        };
        let n = logits.dim(0)?;
        let mut onehot = vec![0f32; n * KINDS];
        for (i, row) in logits.to_vec2::<f32>()?.iter().enumerate() {
            let top = row.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            let w: Vec<f32> = row.iter().map(|x| (x - top).exp()).collect();
            let mut u = rng.next_f32() * w.iter().sum::<f32>();
            let k = (0..KINDS)
                .find(|&k| {
                    u -= w[k];
                    u < 0.0
                })
                .unwrap_or(KINDS - 1);
            onehot[i * KINDS + k] = 1.0;
        }
        let kinds = Tensor::from_vec(onehot, (n, KINDS), &self.device)?;
        self.decode_with(z, feature, Some(&kinds))
    }

    /// The pose-kind head's logits on (n, F) features, (n, 3), for a VAE with pose kinds.
    pub(crate) fn kind_logits(&self, feature: &Tensor) -> Result<Option<Tensor>> {
        match &self.kind {
            None => Ok(None),
            Some((hidden, out)) => Ok(Some(out.forward(&hidden.forward(feature)?.relu()?)?)),
        }
    }

    /// Whether this VAE has pose kinds ([`GateConfig::kinds`](crate::GateConfig)).
    pub fn has_kinds(&self) -> bool {
        self.kind.is_some()
    }

    /// Which variant this VAE is.
    pub fn kind(&self) -> VaeKind {
        match (self.config.local, self.gate.is_some()) {
            (None, _) => VaeKind::Whole,
            (Some(_), false) => VaeKind::Local,
            (Some(_), true) => VaeKind::Gated {
                kinds: self.has_kinds(),
            },
        }
    }

    /// Whether this is a local VAE with an occupancy gate.
    pub fn gated(&self) -> bool {
        self.gate.is_some()
    }

    /// The gate's logits on (n, F) features, (n,).
    pub(crate) fn gate_logits(&self, feature: &Tensor) -> Result<Tensor> {
        let (hidden, out) = self
            .gate
            .as_ref()
            .ok_or_else(|| VaeError::InvalidInput("this VAE has no occupancy gate".into()))?;
        Ok(out.forward(&hidden.forward(feature)?.relu()?)?.squeeze(1)?)
    }

    /// `n` codes of standard deviation `temperature` (seeded), as an (n, latent) tensor.
    pub(crate) fn codes(&self, n: usize, seed: u64, temperature: f32) -> Result<Tensor> {
        if !(temperature.is_finite() && temperature > 0.0 && temperature <= 10.0) {
            return Err(VaeError::InvalidInput(format!(
                "sampling temperature: in (0, 10] (got {temperature})"
            )));
        }
        let z: Vec<f32> = envfield_grid::normals(n * self.config.latent, seed ^ NORMAL_SALT)
            .into_iter()
            .map(|v| v * temperature)
            .collect();
        Ok(Tensor::from_vec(z, (n, self.config.latent), &self.device)?)
    }

    /// How many surface points a scene's cloud should hold for this VAE: the config's
    /// `points` for the paper's VAE, the local config's `cloud` for a local one.
    pub fn cloud_points(&self) -> usize {
        self.config.local.map_or(self.config.points, |l| l.cloud)
    }

    /// (n, 3) normalised coordinates back to metres.
    pub(crate) fn to_metres(&self, t: &Tensor) -> Result<Vec<[f32; 3]>> {
        let (o, s) = (self.config.coord_offset, self.config.coord_scale);
        Ok(t.flatten_all()?
            .to_vec1::<f32>()?
            .chunks_exact(3)
            .map(|c| [c[0] * s + o[0], c[1] * s + o[1], c[2] * s + o[2]])
            .collect())
    }
}

/// Mixed into a seed for the VAE's standard-normal draws (its codes, and the anchors' jitter in
/// training and in `envfield_rooms::draw_torsos`), so they do not repeat the generator's other
/// draws from the same seed.
pub const NORMAL_SALT: u64 = 0x5EED_0F2A;

/// Pose kinds of a VAE with kinds: standing, sitting, lying, in this order.
pub(crate) const KINDS: usize = 3;
