//! Drawing torso locations: [`Cvae::sample`] with its [`SampleOptions`] for every variant, and
//! the calls only one variant answers, on views that exist only for it: [`WholeScene`]
//! (encode, decode), [`Neighbourhoods`] (draws next to given anchors) and [`Gated`] (the
//! occupancy gate's probabilities).

use crate::index::XyIndex;
use crate::{Cvae, LocalConfig, Result, VaeError};
use candle_core::Tensor;
use envfield_grid::SplitMix64;

/// Which anchors a gated VAE decodes ([`SampleOptions::gate`]). Other VAEs decode every
/// anchor (or, for the paper's VAE, the whole scene) whatever this says.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Gate {
    /// The anchors whose occupancy reaches the threshold the VAE was saved with
    /// ([`GateConfig::threshold`](crate::GateConfig)).
    #[default]
    Trained,
    /// The anchors whose occupancy reaches this threshold, in [0, 1).
    Threshold(f32),
    /// Every anchor, as a local VAE without a gate does (the ablation).
    Off,
}

/// How [`Cvae::sample`] draws: how many torso locations, the seed, the codes' spread and a
/// gated VAE's gate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleOptions {
    /// Torso locations to draw, 1 to 10 million.
    pub n: usize,
    /// The seed of the codes and anchors; the same seed gives the same draws.
    pub seed: u64,
    /// Standard deviation of the codes, in (0, 10]: 1 draws from the prior; below 1 the
    /// samples keep nearer the decoder's most likely torsos (the usual trade of diversity
    /// for sharpness).
    pub temperature: f32,
    /// A gated VAE's gate.
    pub gate: Gate,
}

impl Default for SampleOptions {
    fn default() -> Self {
        Self::new(6000, 0)
    }
}

impl SampleOptions {
    /// `n` draws from `seed` at temperature 1 through the trained gate.
    pub fn new(n: usize, seed: u64) -> Self {
        Self {
            n,
            seed,
            temperature: 1.0,
            gate: Gate::Trained,
        }
    }

    /// The same options at another temperature.
    pub fn with_temperature(self, temperature: f32) -> Self {
        Self {
            temperature,
            ..self
        }
    }

    /// The same options with another gate.
    pub fn with_gate(self, gate: Gate) -> Self {
        Self { gate, ..self }
    }
}

/// The paper's VAE ([`VaeKind::Whole`](crate::VaeKind)), seen as what only it does: one
/// feature of the whole scene, encoded and decoded ([`Cvae::as_whole`]).
#[derive(Clone, Copy, Debug)]
pub struct WholeScene<'a>(&'a Cvae);

/// A local VAE (gated or not), seen as what only it does: torsos drawn next to anchors the
/// caller gives ([`Cvae::as_local`]).
#[derive(Clone, Copy, Debug)]
pub struct Neighbourhoods<'a> {
    vae: &'a Cvae,
    local: LocalConfig,
}

/// A gated local VAE, seen as what only it does: the occupancy gate's probabilities
/// ([`Cvae::as_gated`]).
#[derive(Clone, Copy, Debug)]
pub struct Gated<'a>(Neighbourhoods<'a>);

impl Cvae {
    /// `options.n` torso locations drawn for the scene of `points`: codes from a normal of
    /// standard deviation `options.temperature` (seeded), decoded. The paper's VAE decodes
    /// them with the whole scene's feature. A local VAE draws one anchor per sample uniformly
    /// over the cloud's extent in x and y and decodes next to it; a gated one draws anchors in
    /// rounds and decodes those its gate passes ([`Gate`]).
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] for an empty cloud or a coordinate that is not finite, `n`
    /// of 0 or above 10 million, a temperature not in (0, 10], a gate threshold outside
    /// [0, 1), and when the gate passes fewer than `n` of `50 max(n, 512)` anchors (a scene
    /// where nobody can be, such as one without a floor).
    pub fn sample(&self, points: &[[f32; 3]], options: &SampleOptions) -> Result<Vec<[f32; 3]>> {
        let SampleOptions {
            n,
            seed,
            temperature,
            gate,
        } = *options;
        let gate = match gate {
            Gate::Trained => self.config.local.and_then(|l| l.gate).map(|g| g.threshold),
            Gate::Threshold(t) => Some(t),
            Gate::Off => None,
        };
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
            None => WholeScene(self).decode(points, &z),
        }
    }

    /// The whole-scene calls, on the paper's VAE; `None` on a local one.
    pub fn as_whole(&self) -> Option<WholeScene<'_>> {
        self.config.local.is_none().then_some(WholeScene(self))
    }

    /// Draws next to given anchors, on a local VAE (gated or not); `None` on the paper's.
    pub fn as_local(&self) -> Option<Neighbourhoods<'_>> {
        self.config
            .local
            .map(|local| Neighbourhoods { vae: self, local })
    }

    /// The occupancy gate, on a gated local VAE; `None` on the others.
    pub fn as_gated(&self) -> Option<Gated<'_>> {
        self.as_local().filter(|_| self.gate.is_some()).map(Gated)
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
                     samples asked for: nobody can be anywhere in this scene (no floor? A scene \
                     read with the wrong up axis (--up), in other units (--units) or off level \
                     has none: the import's warnings say which)",
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
}

impl WholeScene<'_> {
    /// The scene feature of one cloud, (1, F).
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] for an empty cloud or a coordinate that is not finite.
    pub fn scene_feature(&self, points: &[[f32; 3]]) -> Result<Tensor> {
        let cloud = self.0.coords(points, "scene cloud")?.unsqueeze(0)?;
        Ok(self.0.features(&cloud)?.detach())
    }

    /// The encoder: for each of `torsos` in the scene of `points`, the mean and log variance
    /// of its latent Gaussian, each `(torsos.len(), latent)`.
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] for an empty cloud, no torsos or a coordinate that is not
    /// finite.
    pub fn encode(&self, points: &[[f32; 3]], torsos: &[[f32; 3]]) -> Result<(Tensor, Tensor)> {
        let feature = self.scene_feature(points)?;
        let t = self.0.coords(torsos, "torso locations")?;
        let (mean, log_var) =
            self.0
                .encode_with(&Cvae::repeat(&feature, torsos.len())?, &t, None)?;
        Ok((mean.detach(), log_var.detach()))
    }

    /// The decoder: a torso location (metres) for each row of `z` (n, latent) in the scene of
    /// `points`.
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] for an empty cloud, a bad coordinate or a `z` that is not
    /// (n, latent).
    pub fn decode(&self, points: &[[f32; 3]], z: &Tensor) -> Result<Vec<[f32; 3]>> {
        let feature = self.scene_feature(points)?;
        let (n, l) = z.dims2().map_err(|_| {
            VaeError::InvalidInput(format!(
                "z must be (n, {}), got {:?}",
                self.0.config.latent,
                z.dims()
            ))
        })?;
        if l != self.0.config.latent || n == 0 {
            return Err(VaeError::InvalidInput(format!(
                "z must be (n >= 1, {}), got {:?}",
                self.0.config.latent,
                z.dims()
            )));
        }
        let out = self.0.decode_with(z, &Cvae::repeat(&feature, n)?, None)?;
        self.0.to_metres(&out)
    }
}

impl Neighbourhoods<'_> {
    /// One torso drawn next to each of `anchors` (x-y, metres) by a local VAE
    /// ([`LocalConfig`]): each anchor's neighbourhood of `points` through the PointNet, a code
    /// of standard deviation `temperature` (seeded), the decoded relative torso moved to the
    /// anchor. [`Cvae::sample`] draws its anchors uniformly over the room; anchors placed
    /// where people are likely (another sampler's torsos, moved by
    /// [`LocalConfig::jitter`] as in training) keep the decoder on the anchors it learned.
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] for no anchors or more than 10 million, an anchor that is
    /// not finite, or a temperature not in (0, 10]; for an empty or non-finite cloud.
    pub fn sample_around(
        &self,
        points: &[[f32; 3]],
        anchors: &[[f32; 2]],
        seed: u64,
        temperature: f32,
    ) -> Result<Vec<[f32; 3]>> {
        check_anchors(anchors)?;
        let z = self.vae.codes(anchors.len(), seed, temperature)?;
        let index = XyIndex::new(points, self.local.radius, "scene cloud")?;
        let mut rng = SplitMix64::new(seed ^ 0xA11C_4035);
        self.vae
            .decode_around(&self.local, points, &index, anchors, &z, &mut rng)
    }
}

impl Gated<'_> {
    /// A gated local VAE's probability that someone can be at each of `anchors` (x-y,
    /// metres) in the scene of `points`, read from the anchor's neighbourhood.
    ///
    /// # Errors
    /// [`VaeError::InvalidInput`] for an empty or non-finite cloud, no anchors or one that
    /// is not finite.
    pub fn occupancy(&self, points: &[[f32; 3]], anchors: &[[f32; 2]]) -> Result<Vec<f32>> {
        check_anchors(anchors)?;
        let index = XyIndex::new(points, self.0.local.radius, "scene cloud")?;
        let mut rng = SplitMix64::new(0x0CC0_FA7E);
        let mut out = Vec::with_capacity(anchors.len());
        for chunk in anchors.chunks(CHUNK) {
            let feature =
                self.0
                    .vae
                    .hood_features(&self.0.local, points, &index, chunk, &mut rng)?;
            out.extend(sigmoid(&self.0.vae.gate_logits(&feature)?)?);
        }
        Ok(out)
    }
}

/// Neighbourhoods through the PointNet at a time: the per-point activations stay small.
const CHUNK: usize = 512;

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
