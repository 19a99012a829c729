//! [`Cvae`]: the PointNet scene encoder and the conditional VAE of torso locations.

use crate::{LocalConfig, Result, VaeConfig, VaeError};
use candle_core::{Device, Tensor, Var};
use envfield_grid::SplitMix64;
use envfield_nets::params::{
    to_safetensors, Init, ParamStore, TensorFile, META_CONFIG, META_FORMAT,
};
use std::collections::HashMap;
use std::path::Path;

/// The format of envfield-vae's weight files and checkpoints.
pub(crate) const FORMAT: &str = "envfield-vae/1";

/// Named tensors and a file's metadata.
pub(crate) type Named = (Vec<(String, Tensor)>, HashMap<String, String>);

/// A dense layer `x W + b`.
#[derive(Debug)]
struct Dense {
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
    config: VaeConfig,
    store: ParamStore,
    pointnet: Vec<Dense>,
    encoder: Vec<Dense>,
    encoder_out: Dense,
    decoder: Vec<Dense>,
    decoder_out: Dense,
    /// The occupancy gate's hidden and output layers, for a gated local VAE.
    gate: Option<(Dense, Dense)>,
    /// The pose-kind head's hidden and output layers, for a VAE with pose kinds.
    kind: Option<(Dense, Dense)>,
    device: Device,
}

/// The loss of one batch and its parts (means over the batch's torso locations).
#[derive(Debug)]
pub(crate) struct Loss {
    pub(crate) total: Tensor,
    pub(crate) recon: f32,
    pub(crate) kl: f32,
    /// The gate's mean cross-entropy (0 without a gate batch).
    pub(crate) gate: f32,
    /// The pose-kind head's mean cross-entropy (0 without kinds).
    pub(crate) kind: f32,
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

    /// The scene feature of one cloud, (1, F).
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] for an empty cloud or a coordinate that is not finite.
    pub fn scene_feature(&self, points: &[[f32; 3]]) -> Result<Tensor> {
        self.global_only("scene_feature")?;
        let cloud = self.coords(points, "scene cloud")?.unsqueeze(0)?;
        Ok(self.features(&cloud)?.detach())
    }

    /// `feature` (B, F) repeated `k` times per row, (B * k, F).
    fn repeat(feature: &Tensor, k: usize) -> Result<Tensor> {
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
    fn encode_with(
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
    fn decode_with(&self, z: &Tensor, feature: &Tensor, kinds: Option<&Tensor>) -> Result<Tensor> {
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
    fn decode_local(&self, z: &Tensor, feature: &Tensor, rng: &mut SplitMix64) -> Result<Tensor> {
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
    fn kind_logits(&self, feature: &Tensor) -> Result<Option<Tensor>> {
        match &self.kind {
            None => Ok(None),
            Some((hidden, out)) => Ok(Some(out.forward(&hidden.forward(feature)?.relu()?)?)),
        }
    }

    /// Whether this VAE has pose kinds ([`GateConfig::kinds`](crate::GateConfig)).
    pub fn has_kinds(&self) -> bool {
        self.kind.is_some()
    }

    /// The encoder: for each of `torsos` in the scene of `points`, the mean and log variance
    /// of its latent Gaussian, each `(torsos.len(), latent)`.
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] for an empty cloud, no torsos or a coordinate that is not
    /// finite.
    pub fn encode(&self, points: &[[f32; 3]], torsos: &[[f32; 3]]) -> Result<(Tensor, Tensor)> {
        self.global_only("encode")?;
        let feature = self.scene_feature(points)?;
        let t = self.coords(torsos, "torso locations")?;
        let (mean, log_var) = self.encode_with(&Self::repeat(&feature, torsos.len())?, &t, None)?;
        Ok((mean.detach(), log_var.detach()))
    }

    /// The decoder: a torso location (metres) for each row of `z` (n, latent) in the scene of
    /// `points`.
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] for an empty cloud, a bad coordinate or a `z` that is not
    /// (n, latent).
    pub fn decode(&self, points: &[[f32; 3]], z: &Tensor) -> Result<Vec<[f32; 3]>> {
        self.global_only("decode")?;
        let feature = self.scene_feature(points)?;
        let (n, l) = z.dims2().map_err(|_| {
            VaeError::InvalidInput(format!(
                "z must be (n, {}), got {:?}",
                self.config.latent,
                z.dims()
            ))
        })?;
        if l != self.config.latent || n == 0 {
            return Err(VaeError::InvalidInput(format!(
                "z must be (n >= 1, {}), got {:?}",
                self.config.latent,
                z.dims()
            )));
        }
        let out = self.decode_with(z, &Self::repeat(&feature, n)?, None)?;
        self.to_metres(&out)
    }

    /// `n` torso locations drawn for the scene of `points`: codes from the standard normal
    /// (seeded), decoded. A local VAE ([`LocalConfig`]) draws one anchor per sample uniformly
    /// over the cloud's extent in x and y and decodes next to it.
    ///
    /// # Errors
    /// As [`Cvae::decode`]; `n` of 0 or above 10 million.
    pub fn sample(&self, points: &[[f32; 3]], n: usize, seed: u64) -> Result<Vec<[f32; 3]>> {
        self.sample_tempered(points, n, seed, 1.0)
    }

    /// [`Cvae::sample`] with the codes drawn from a normal of standard deviation
    /// `temperature` instead of 1: below 1 the samples keep nearer the decoder's most likely
    /// torsos (the usual trade of diversity for sharpness); 1 is [`Cvae::sample`].
    ///
    /// # Errors
    /// As [`Cvae::sample`]; a temperature that is not finite or not in (0, 10].
    pub fn sample_tempered(
        &self,
        points: &[[f32; 3]],
        n: usize,
        seed: u64,
        temperature: f32,
    ) -> Result<Vec<[f32; 3]>> {
        let gate = self.config.local.and_then(|l| l.gate).map(|g| g.threshold);
        self.sample_gated(points, n, seed, temperature, gate)
    }

    /// [`Cvae::sample_tempered`] with a gated local VAE's gate ([`GateConfig`]) at a
    /// threshold of one's own: `Some(t)` decodes the uniform anchors whose occupancy is at
    /// least `t`, `None` every one of them, as a local VAE without a gate does (the
    /// ablation). Other VAEs ignore `gate`.
    ///
    /// # Errors
    /// As [`Cvae::sample_tempered`]; [`VaeError::InvalidInput`] for a threshold outside
    /// [0, 1), and when the gate passes fewer than `n` of `50 max(n, 512)` anchors (a scene
    /// where nobody can be, such as one without a floor).
    ///
    /// [`GateConfig`]: crate::GateConfig
    pub fn sample_gated(
        &self,
        points: &[[f32; 3]],
        n: usize,
        seed: u64,
        temperature: f32,
        gate: Option<f32>,
    ) -> Result<Vec<[f32; 3]>> {
        if let Some(t) = gate.filter(|t| !(0.0..1.0).contains(t)) {
            return Err(VaeError::InvalidInput(format!(
                "gate threshold: in [0, 1) (got {t})"
            )));
        }
        if n == 0 || n > 10_000_000 {
            return Err(VaeError::InvalidInput(format!(
                "samples: 1 to 10,000,000 (got {n})"
            )));
        }
        let z = self.codes(n, seed, temperature)?;
        match self.config.local {
            Some(local) => self.sample_local(&local, points, &z, seed, gate),
            None => self.decode(points, &z),
        }
    }

    /// Whether this is a local VAE with an occupancy gate.
    pub fn gated(&self) -> bool {
        self.gate.is_some()
    }

    /// A gated local VAE's probability that someone can be at each of `anchors` (x-y,
    /// metres) in the scene of `points`, read from the anchor's neighbourhood.
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] on a VAE without a gate, for an empty or non-finite cloud,
    /// no anchors or one that is not finite.
    pub fn occupancy(&self, points: &[[f32; 3]], anchors: &[[f32; 2]]) -> Result<Vec<f32>> {
        let (Some(local), true) = (self.config.local, self.gate.is_some()) else {
            return Err(VaeError::InvalidInput(
                "occupancy: this VAE has no occupancy gate".into(),
            ));
        };
        check_anchors(anchors)?;
        let index = XyIndex::new(points, local.radius, "scene cloud")?;
        let mut rng = SplitMix64::new(0x0CC0_FA7E);
        let mut out = Vec::with_capacity(anchors.len());
        for chunk in anchors.chunks(CHUNK) {
            let feature = self.hood_features(&local, points, &index, chunk, &mut rng)?;
            out.extend(sigmoid(&self.gate_logits(&feature)?)?);
        }
        Ok(out)
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
    fn codes(&self, n: usize, seed: u64, temperature: f32) -> Result<Tensor> {
        if !(temperature.is_finite() && temperature > 0.0 && temperature <= 10.0) {
            return Err(VaeError::InvalidInput(format!(
                "sampling temperature: in (0, 10] (got {temperature})"
            )));
        }
        let z: Vec<f32> = normals(n * self.config.latent, seed)
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

    /// An error for the APIs that read one feature of the whole scene, on a local VAE.
    fn global_only(&self, what: &str) -> Result<()> {
        match self.config.local {
            Some(_) => Err(VaeError::InvalidInput(format!(
                "{what}: this VAE conditions on neighbourhoods, not on the whole scene; draw \
                 from it with sample()"
            ))),
            None => Ok(()),
        }
    }

    /// One torso drawn next to each of `anchors` (x-y, metres) by a local VAE
    /// ([`LocalConfig`]): each anchor's neighbourhood of `points` through the PointNet, a code
    /// of standard deviation `temperature` (seeded), the decoded relative torso moved to the
    /// anchor. [`Cvae::sample`] draws its anchors uniformly over the room; anchors placed
    /// where people are likely (another sampler's torsos, moved by
    /// [`LocalConfig::jitter`] as in training) keep the decoder on the anchors it learned.
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] on a VAE that is not local, for no anchors or more than 10
    /// million, an anchor that is not finite, or a temperature not in (0, 10]; as
    /// [`Cvae::decode`].
    pub fn sample_around(
        &self,
        points: &[[f32; 3]],
        anchors: &[[f32; 2]],
        seed: u64,
        temperature: f32,
    ) -> Result<Vec<[f32; 3]>> {
        let Some(local) = self.config.local else {
            return Err(VaeError::InvalidInput(
                "sample_around: this VAE reads the whole scene, not neighbourhoods; draw from \
                 it with sample()"
                    .into(),
            ));
        };
        check_anchors(anchors)?;
        let z = self.codes(anchors.len(), seed, temperature)?;
        let index = XyIndex::new(points, local.radius, "scene cloud")?;
        let mut rng = SplitMix64::new(seed ^ 0xA11C_4035);
        self.decode_around(&local, points, &index, anchors, &z, &mut rng)
    }

    /// The local sampler: anchors uniform over the cloud's x-y extent (seeded), each one's
    /// neighbourhood through the PointNet, the decoder's relative torso moved to the anchor.
    /// With a gate (and `gate` on), anchors are drawn in rounds and only those the gate
    /// passes are decoded, until `n` are.
    fn sample_local(
        &self,
        local: &LocalConfig,
        points: &[[f32; 3]],
        z: &Tensor,
        seed: u64,
        gate: Option<f32>,
    ) -> Result<Vec<[f32; 3]>> {
        let index = XyIndex::new(points, local.radius, "scene cloud")?;
        let n = z.dim(0)?;
        let mut rng = SplitMix64::new(seed ^ 0xA11C_4035);
        let [x0, y0, x1, y1] = index.extent;
        let uniform = |rng: &mut SplitMix64, m: usize| -> Vec<[f32; 2]> {
            (0..m)
                .map(|_| {
                    [
                        x0 + (x1 - x0) * rng.next_f32(),
                        y0 + (y1 - y0) * rng.next_f32(),
                    ]
                })
                .collect()
        };
        let threshold = match (gate, self.gate.is_some()) {
            (Some(t), true) => t,
            _ => {
                let anchors = uniform(&mut rng, n);
                return self.decode_around(local, points, &index, &anchors, z, &mut rng);
            }
        };
        let mut out = Vec::with_capacity(n);
        let mut tried = 0usize;
        while out.len() < n {
            if tried >= 50 * n.max(CHUNK) {
                return Err(VaeError::InvalidInput(format!(
                    "the occupancy gate passed {} of {tried} anchors, fewer than the {n} \
                     samples asked for: nobody can be anywhere in this scene (no floor?)",
                    out.len()
                )));
            }
            let anchors = uniform(&mut rng, CHUNK);
            tried += CHUNK;
            let feature = self.hood_features(local, points, &index, &anchors, &mut rng)?;
            let p = sigmoid(&self.gate_logits(&feature)?)?;
            let pass: Vec<u32> = (0..CHUNK as u32)
                .filter(|&i| p[i as usize] >= threshold)
                .take(n - out.len())
                .collect();
            if pass.is_empty() {
                continue;
            }
            let rows = Tensor::new(pass.as_slice(), &self.device)?;
            let zc = z.narrow(0, out.len(), pass.len())?;
            let passed = feature.index_select(&rows, 0)?;
            let rel = self.to_metres(&self.decode_local(&zc, &passed, &mut rng)?)?;
            out.extend(rel.iter().zip(&pass).map(|(t, &i)| {
                let a = anchors[i as usize];
                [t[0] + a[0], t[1] + a[1], t[2]]
            }));
        }
        Ok(out)
    }

    /// The PointNet features, (len, F), of the neighbourhoods of `anchors` in `points`.
    fn hood_features(
        &self,
        local: &LocalConfig,
        points: &[[f32; 3]],
        index: &XyIndex,
        anchors: &[[f32; 2]],
        rng: &mut SplitMix64,
    ) -> Result<Tensor> {
        let hood: Vec<[f32; 3]> = anchors
            .iter()
            .flat_map(|&a| index.neighbourhood(points, a, local, rng))
            .collect();
        let clouds =
            self.coords(&hood, "neighbourhoods")?
                .reshape((anchors.len(), local.points, 3))?;
        self.features(&clouds)
    }

    /// Codes `z` decoded next to `anchors`, in chunks so the per-point activations stay small.
    fn decode_around(
        &self,
        local: &LocalConfig,
        points: &[[f32; 3]],
        index: &XyIndex,
        anchors: &[[f32; 2]],
        z: &Tensor,
        rng: &mut SplitMix64,
    ) -> Result<Vec<[f32; 3]>> {
        let n = anchors.len();
        let mut out = Vec::with_capacity(n);
        for (c, chunk) in anchors.chunks(CHUNK).enumerate() {
            let feature = self.hood_features(local, points, index, chunk, rng)?;
            let zc = z.narrow(0, c * CHUNK, chunk.len())?;
            let rel = self.to_metres(&self.decode_local(&zc, &feature, rng)?)?;
            out.extend(
                rel.iter()
                    .zip(chunk)
                    .map(|(t, a)| [t[0] + a[0], t[1] + a[1], t[2]]),
            );
        }
        Ok(out)
    }

    /// (n, 3) normalised coordinates back to metres.
    fn to_metres(&self, t: &Tensor) -> Result<Vec<[f32; 3]>> {
        let (o, s) = (self.config.coord_offset, self.config.coord_scale);
        Ok(t.flatten_all()?
            .to_vec1::<f32>()?
            .chunks_exact(3)
            .map(|c| [c[0] * s + o[0], c[1] * s + o[1], c[2] * s + o[2]])
            .collect())
    }

    /// The training loss on a batch: `clouds` (B, N, 3) and `torsos` (B * k, 3), normalised,
    /// with standard-normal noise `eps` (B * k, latent). Reconstruction: squared error over
    /// `2 sigma^2` (sigma in normalised units), summed over xyz; KL to the standard normal,
    /// summed over the latent; both averaged over the torsos. `gate`, for a gated VAE: more
    /// neighbourhoods (M, N, 3) and their occupancy labels (M,) of 0 or 1, whose logistic
    /// cross-entropy, averaged, joins the total at the gate's weight. `kinds`, for a VAE with
    /// pose kinds: the torsos' (B * k, 3) one-hot kinds; the kind head's cross-entropy joins
    /// the total at the gate's weight.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn loss(
        &self,
        clouds: &Tensor,
        torsos: &Tensor,
        eps: &Tensor,
        kl_weight: f64,
        sigma: f32,
        gate: Option<(&Tensor, &Tensor)>,
        kinds: Option<&Tensor>,
    ) -> Result<Loss> {
        let b = clouds.dim(0)?;
        let k = torsos.dim(0)? / b;
        let feature = Self::repeat(&self.features(clouds)?, k)?;
        let kinds = match (self.has_kinds(), kinds) {
            (false, _) => None,
            (true, Some(k)) => Some(k),
            (true, None) => {
                return Err(VaeError::InvalidInput(
                    "a VAE with pose kinds needs each training torso's kind".into(),
                ))
            }
        };
        let (mean, log_var) = self.encode_with(&feature, torsos, kinds)?;
        let z = (&mean + ((&log_var * 0.5)?.exp()? * eps)?)?;
        let recon_xyz = self.decode_with(&z, &feature, kinds)?;
        let n = (b * k) as f64;
        let recon = ((recon_xyz - torsos)?.sqr()?.sum_all()? / (2.0 * (sigma * sigma) as f64 * n))?;
        let kl = (((mean.sqr()? + log_var.exp()?)? - &log_var)? - 1.0)?;
        let kl = (kl.sum_all()? * (0.5 / n))?;
        let mut total = (&recon + (&kl * kl_weight)?)?;
        let mut gate_loss = 0.0;
        if let (Some((hoods, labels)), Some(g)) = (gate, self.config.local.and_then(|l| l.gate)) {
            let x = self.gate_logits(&self.features(hoods)?)?;
            // Stable logistic cross-entropy: max(x, 0) - x y + ln(1 + exp(-|x|)).
            let bce = ((x.relu()? - (&x * labels)?)? + ((x.abs()?.neg()?.exp()? + 1.0)?.log()?))?
                .mean_all()?;
            gate_loss = bce.to_scalar::<f32>()?;
            total = (total + (bce * g.weight as f64)?)?;
        }
        let mut kind_loss = 0.0;
        if let (Some(onehot), Some(logits), Some(g)) = (
            kinds,
            self.kind_logits(&feature)?,
            self.config.local.and_then(|l| l.gate),
        ) {
            // Cross-entropy through a stable log-softmax.
            let top = logits.max_keepdim(1)?;
            let shifted = logits.broadcast_sub(&top)?;
            let lse = shifted.exp()?.sum_keepdim(1)?.log()?;
            let log_p = shifted.broadcast_sub(&lse)?;
            let ce = (log_p * onehot)?.sum(1)?.neg()?.mean_all()?;
            kind_loss = ce.to_scalar::<f32>()?;
            total = (total + (ce * g.weight as f64)?)?;
        }
        Ok(Loss {
            total,
            recon: recon.to_scalar::<f32>()?,
            kl: kl.to_scalar::<f32>()?,
            gate: gate_loss,
            kind: kind_loss,
        })
    }

    /// The weights as named tensors and the file's metadata (format and config).
    pub(crate) fn named(&self) -> Result<Named> {
        let tensors = self
            .store
            .names()
            .iter()
            .cloned()
            .zip(self.store.vars().iter().map(|v| v.as_tensor().clone()))
            .collect();
        let mut meta = HashMap::new();
        meta.insert(META_FORMAT.to_string(), FORMAT.to_string());
        meta.insert(
            META_CONFIG.to_string(),
            serde_json::to_string(&self.config)
                .map_err(|e| VaeError::InvalidInput(format!("cannot serialise the config: {e}")))?,
        );
        Ok((tensors, meta))
    }

    /// Saves the weights and config as safetensors, atomically (a temporary file, then a
    /// rename).
    ///
    /// # Errors
    /// I/O errors, naming the file.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let (tensors, meta) = self.named()?;
        let bytes = to_safetensors(&tensors, meta)?;
        envfield_grid::write_atomic(path.as_ref(), &bytes)?;
        Ok(())
    }

    /// Loads a VAE saved by [`Cvae::save`] (or a training checkpoint), rebuilding it from the
    /// config in the file and checking every tensor's name and shape.
    ///
    /// # Errors
    /// [`VaeError::Checkpoint`] for a file that is not an envfield-vae file (for example a
    /// field network's) or whose config is bad; a missing or misshapen tensor.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let mut file = TensorFile::read_format(path, FORMAT)?;
        Self::from_file(path, &mut file)
    }

    pub(crate) fn from_file(path: &Path, file: &mut TensorFile) -> Result<Self> {
        let bad = |reason: String| VaeError::Checkpoint {
            path: path.to_path_buf(),
            reason,
        };
        let config: VaeConfig = serde_json::from_str(
            file.metadata
                .get(META_CONFIG)
                .ok_or_else(|| bad("no config in the metadata".into()))?,
        )
        .map_err(|e| bad(format!("bad config: {e}")))?;
        config
            .validate()
            .map_err(|e| bad(format!("bad config: {e}")))?;
        let vae = Self::new(config, 0)?;
        for (name, var) in vae.store.names().iter().zip(vae.store.vars()) {
            let t = file.take(path, name, var.dims(), &vae.device)?;
            var.set(&t)?;
        }
        Ok(vae)
    }
}

/// Neighbourhoods through the PointNet at a time: the per-point activations stay small.
const CHUNK: usize = 512;

/// Pose kinds of a VAE with kinds: standing, sitting, lying, in this order.
pub(crate) const KINDS: usize = 3;

/// An error naming the first anchor that is not finite, or for none or too many.
fn check_anchors(anchors: &[[f32; 2]]) -> Result<()> {
    if anchors.is_empty() || anchors.len() > 10_000_000 {
        return Err(VaeError::InvalidInput(format!(
            "anchors: 1 to 10,000,000 (got {})",
            anchors.len()
        )));
    }
    match anchors
        .iter()
        .position(|a| !a.iter().all(|v| v.is_finite()))
    {
        Some(i) => Err(VaeError::InvalidInput(format!(
            "anchor {i} is not finite: {:?}",
            anchors[i]
        ))),
        None => Ok(()),
    }
}

/// The logistic function of a (n,) tensor, as a vector.
fn sigmoid(logits: &Tensor) -> Result<Vec<f32>> {
    Ok(logits
        .to_vec1::<f32>()?
        .into_iter()
        .map(|x| 1.0 / (1.0 + (-x).exp()))
        .collect())
}

/// A cloud's points binned in x-y squares of the neighbourhood radius, for neighbourhood
/// queries in 3x3 bins.
pub(crate) struct XyIndex {
    /// `[x0, y0, x1, y1]` of the cloud.
    pub(crate) extent: [f32; 4],
    cell: f32,
    cols: usize,
    rows: usize,
    bins: Vec<Vec<u32>>,
}

impl XyIndex {
    /// Bins `cloud` (checked non-empty and finite; `what` names it in errors).
    pub(crate) fn new(cloud: &[[f32; 3]], radius: f32, what: &str) -> Result<Self> {
        if cloud.is_empty() {
            return Err(VaeError::InvalidInput(format!("{what}: no points")));
        }
        if let Some(i) = cloud.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
            return Err(VaeError::InvalidInput(format!(
                "{what}: point {i} is not finite: {:?}",
                cloud[i]
            )));
        }
        let fold =
            |f: fn(f32, f32) -> f32, a: usize, init: f32| cloud.iter().map(|p| p[a]).fold(init, f);
        let extent = [
            fold(f32::min, 0, f32::INFINITY),
            fold(f32::min, 1, f32::INFINITY),
            fold(f32::max, 0, f32::NEG_INFINITY),
            fold(f32::max, 1, f32::NEG_INFINITY),
        ];
        // Bins no smaller than the radius, and at most 2^20 of them.
        let span = (extent[2] - extent[0]).max(extent[3] - extent[1]);
        let cell = radius.max(span / 1024.0).max(1e-3);
        let cols = ((extent[2] - extent[0]) / cell) as usize + 1;
        let rows = ((extent[3] - extent[1]) / cell) as usize + 1;
        let mut bins = vec![Vec::new(); rows * cols];
        for (i, p) in cloud.iter().enumerate() {
            let (c, r) = (
                ((p[0] - extent[0]) / cell) as usize,
                ((p[1] - extent[1]) / cell) as usize,
            );
            bins[r.min(rows - 1) * cols + c.min(cols - 1)].push(i as u32);
        }
        Ok(Self {
            extent,
            cell,
            cols,
            rows,
            bins,
        })
    }

    /// Whether some point of `cloud` (the points this index was made of) lies within
    /// `radius` (at most the index's radius) of `anchor` in x-y.
    pub(crate) fn any_within(&self, cloud: &[[f32; 3]], anchor: [f32; 2], radius: f32) -> bool {
        let (c, r) = (
            ((anchor[0] - self.extent[0]) / self.cell).floor() as isize,
            ((anchor[1] - self.extent[1]) / self.cell).floor() as isize,
        );
        let r2 = radius * radius;
        (-1..=1).any(|dr| {
            (-1..=1).any(|dc| {
                let (br, bc) = (r + dr, c + dc);
                br >= 0
                    && bc >= 0
                    && br < self.rows as isize
                    && bc < self.cols as isize
                    && self.bins[br as usize * self.cols + bc as usize]
                        .iter()
                        .any(|&i| {
                            let p = cloud[i as usize];
                            let (dx, dy) = (p[0] - anchor[0], p[1] - anchor[1]);
                            dx * dx + dy * dy <= r2
                        })
            })
        })
    }

    /// `local.points` points drawn with replacement from those of `cloud` within the radius
    /// of `anchor` in x-y, as `[dx, dy, z]` relative to it; `[0, 0, -0.5]` each when there is
    /// none (nothing here: below the floor).
    pub(crate) fn neighbourhood(
        &self,
        cloud: &[[f32; 3]],
        anchor: [f32; 2],
        local: &LocalConfig,
        rng: &mut SplitMix64,
    ) -> Vec<[f32; 3]> {
        let (c, r) = (
            ((anchor[0] - self.extent[0]) / self.cell).floor() as isize,
            ((anchor[1] - self.extent[1]) / self.cell).floor() as isize,
        );
        let r2 = local.radius * local.radius;
        let mut near = Vec::new();
        for dr in -1..=1 {
            for dc in -1..=1 {
                let (br, bc) = (r + dr, c + dc);
                if br < 0 || bc < 0 || br >= self.rows as isize || bc >= self.cols as isize {
                    continue;
                }
                for &i in &self.bins[br as usize * self.cols + bc as usize] {
                    let p = cloud[i as usize];
                    let (dx, dy) = (p[0] - anchor[0], p[1] - anchor[1]);
                    if dx * dx + dy * dy <= r2 {
                        near.push([dx, dy, p[2]]);
                    }
                }
            }
        }
        if near.is_empty() {
            return vec![[0.0, 0.0, -0.5]; local.points];
        }
        (0..local.points)
            .map(|_| near[rng.below(near.len())])
            .collect()
    }
}

/// `n` draws of the standard normal, seeded (Box-Muller over SplitMix64): the codes the VAE
/// samples with, and the training's anchor jitter.
pub fn normals(n: usize, seed: u64) -> Vec<f32> {
    let mut rng = SplitMix64::new(seed ^ 0x5EED_0F2A);
    let unit = |rng: &mut SplitMix64| ((rng.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    (0..n)
        .map(|_| {
            let (u1, u2) = (unit(&mut rng), unit(&mut rng));
            ((-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()) as f32
        })
        .collect()
}
