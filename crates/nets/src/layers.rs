//! Building blocks: coordinate encodings, MLPs with ReLU or sine activations, convolutions
//! written as im2col + matrix multiply (channels-last), and bilinear feature sampling.

use crate::kernel::{conv3x3_relu, ConvShape};
use crate::params::{Init, ParamStore};
use crate::{NetsError, Result};
use candle_core::{Device, Tensor};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::sync::Mutex;

/// The activation of an MLP's hidden layers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Activation {
    /// ReLU with Kaiming-normal initialisation.
    Relu,
    /// SIREN (Sitzmann et al. 2020): `sin(omega0 * (W x + b))` with its initialisation
    /// (first layer uniform in `±1/in`, the others `±sqrt(6/in)/omega0`).
    Sine {
        /// The frequency of the first layer (30 in the SIREN paper).
        omega0: f32,
    },
}

/// A fully connected network: `layers` hidden layers of width `hidden`, then a linear output.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MlpConfig {
    /// Width of the hidden layers.
    pub hidden: usize,
    /// Number of hidden layers (each a linear map and an activation).
    pub layers: usize,
    /// The hidden activation.
    pub activation: Activation,
    /// Frequencies of the positional encoding of coordinates: each coordinate `x` also enters
    /// as `sin(2^k pi x), cos(2^k pi x)` for `k < fourier`; 0 feeds coordinates as they are.
    pub fourier: usize,
}

impl Default for MlpConfig {
    fn default() -> Self {
        Self {
            hidden: 128,
            layers: 4,
            activation: Activation::Relu,
            fourier: 0,
        }
    }
}

impl MlpConfig {
    pub(crate) fn validate(&self, what: &str) -> Result<()> {
        if !(1..=MAX_CHANNELS).contains(&self.hidden)
            || !(1..=MAX_CONVS).contains(&self.layers)
            || self.fourier > 16
        {
            return Err(NetsError::InvalidConfig(format!(
                "{what}: hidden in 1..=4096, layers in 1..=1024 and fourier <= 16 (got {}, {}, {})",
                self.hidden, self.layers, self.fourier
            )));
        }
        if let Activation::Sine { omega0 } = self.activation {
            if !(omega0.is_finite() && omega0 > 0.0) {
                return Err(NetsError::InvalidConfig(format!(
                    "{what}: omega0 must be positive and finite (got {omega0})"
                )));
            }
        }
        Ok(())
    }

    /// Width of `dims` coordinates after the positional encoding.
    pub(crate) fn encoded_width(&self, dims: usize) -> usize {
        dims * (1 + 2 * self.fourier)
    }
}

/// The positional encoding of coordinates `x` (N, d): `[x, sin(2^k pi x), cos(2^k pi x)]`.
pub(crate) fn encode_coords(x: &Tensor, fourier: usize) -> Result<Tensor> {
    if fourier == 0 {
        return Ok(x.clone());
    }
    let mut parts = vec![x.clone()];
    for k in 0..fourier {
        let scaled = (x * (std::f64::consts::PI * (1u64 << k) as f64))?;
        parts.push(scaled.sin()?);
        parts.push(scaled.cos()?);
    }
    Ok(Tensor::cat(&parts, 1)?)
}

/// A linear layer `x W + b` with `W` stored as (in, out).
#[derive(Clone, Debug)]
pub(crate) struct Linear {
    pub(crate) w: Tensor,
    pub(crate) b: Tensor,
}

impl Linear {
    pub(crate) fn new(
        store: &mut ParamStore,
        name: &str,
        fan_in: usize,
        fan_out: usize,
        init: Init,
    ) -> Result<Self> {
        Ok(Self {
            w: store.add(format!("{name}.weight"), &[fan_in, fan_out], init)?,
            b: store.add(format!("{name}.bias"), &[fan_out], Init::Zeros)?,
        })
    }

    pub(crate) fn forward(&self, x: &Tensor) -> Result<Tensor> {
        Ok(x.matmul(&self.w)?.broadcast_add(&self.b)?)
    }
}

/// An MLP from `input` features to `output` values.
#[derive(Clone, Debug)]
pub(crate) struct Mlp {
    layers: Vec<Linear>,
    activation: Activation,
}

impl Mlp {
    pub(crate) fn new(
        store: &mut ParamStore,
        name: &str,
        cfg: &MlpConfig,
        input: usize,
        output: usize,
    ) -> Result<Self> {
        let mut layers = Vec::with_capacity(cfg.layers + 1);
        let mut fan_in = input;
        for l in 0..=cfg.layers {
            let fan_out = if l == cfg.layers { output } else { cfg.hidden };
            let init = match cfg.activation {
                Activation::Relu if l == cfg.layers => Init::Normal((1.0 / fan_in as f32).sqrt()),
                Activation::Relu => Init::Normal((2.0 / fan_in as f32).sqrt()),
                Activation::Sine { .. } if l == 0 => Init::Uniform(1.0 / fan_in as f32),
                Activation::Sine { omega0 } => Init::Uniform((6.0 / fan_in as f32).sqrt() / omega0),
            };
            layers.push(Linear::new(
                store,
                &format!("{name}.{l}"),
                fan_in,
                fan_out,
                init,
            )?);
            fan_in = fan_out;
        }
        Ok(Self {
            layers,
            activation: cfg.activation,
        })
    }

    pub(crate) fn forward(&self, x: &Tensor) -> Result<Tensor> {
        let last = self.layers.len() - 1;
        let mut h = x.clone();
        for (l, layer) in self.layers.iter().enumerate() {
            h = layer.forward(&h)?;
            if l < last {
                h = activate(&h, self.activation)?;
            }
        }
        Ok(h)
    }
}

pub(crate) fn activate(x: &Tensor, activation: Activation) -> Result<Tensor> {
    Ok(match activation {
        Activation::Relu => x.relu()?,
        Activation::Sine { omega0 } => (x * omega0 as f64)?.sin()?,
    })
}

/// One 3x3 convolution of an encoder.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ConvSpec {
    /// Output channels.
    pub channels: usize,
    /// Dilation (the kernel's taps are `dilation` cells apart; padding keeps the size).
    pub dilation: usize,
    /// Stride (2 halves the feature map, rounding up).
    pub stride: usize,
}

impl ConvSpec {
    /// A stride-1 convolution.
    pub fn new(channels: usize, dilation: usize) -> Self {
        Self {
            channels,
            dilation,
            stride: 1,
        }
    }
}

/// im2col gather tables, one per (input size, dilation, stride), built on first use.
/// (input rows, input cols, dilation, stride).
type TableKey = (usize, usize, usize, usize);

/// A gather table and the output rows and cols.
type Table = (Tensor, usize, usize);

#[derive(Debug, Default)]
pub(crate) struct IndexCache {
    tables: Mutex<HashMap<TableKey, Table>>,
}

impl IndexCache {
    /// The table for a `h x w` input: for each output position and each of the 9 taps, the
    /// flat input position, or `h * w` (a zero row appended to the input) outside the input.
    fn table(
        &self,
        h: usize,
        w: usize,
        dilation: usize,
        stride: usize,
        device: &Device,
    ) -> Result<Table> {
        let key = (h, w, dilation, stride);
        let mut tables = self.tables.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(t) = tables.get(&key) {
            return Ok(t.clone());
        }
        let (ho, wo) = ((h - 1) / stride + 1, (w - 1) / stride + 1);
        let mut ids = Vec::with_capacity(ho * wo * 9);
        let d = dilation as isize;
        for oy in 0..ho {
            for ox in 0..wo {
                for ky in -1..=1isize {
                    for kx in -1..=1isize {
                        let iy = (oy * stride) as isize + ky * d;
                        let ix = (ox * stride) as isize + kx * d;
                        let inside = iy >= 0 && ix >= 0 && (iy as usize) < h && (ix as usize) < w;
                        ids.push(if inside {
                            (iy as usize * w + ix as usize) as u32
                        } else {
                            (h * w) as u32
                        });
                    }
                }
            }
        }
        let n = ids.len();
        let entry = (Tensor::from_vec(ids, n, device)?, ho, wo);
        tables.insert(key, entry.clone());
        Ok(entry)
    }
}

/// A 3x3 convolution on channels-last maps (B, H, W, C), as a gather (im2col) and one matrix
/// multiply; its backward is an index-add and a matrix multiply.
#[derive(Clone, Debug)]
pub(crate) struct Conv {
    pub(crate) linear: Linear,
    spec: ConvSpec,
}

impl Conv {
    pub(crate) fn with_init(
        store: &mut ParamStore,
        name: &str,
        cin: usize,
        spec: ConvSpec,
        init: Init,
    ) -> Result<Self> {
        let linear = Linear::new(store, name, 9 * cin, spec.channels, init)?;
        Ok(Self { linear, spec })
    }

    /// (B, H, W, C) -> (B, Ho, Wo, channels), without activation.
    pub(crate) fn forward(&self, x: &Tensor, cache: &IndexCache) -> Result<Tensor> {
        let (b, h, w, c) = x.dims4()?;
        let (ids, ho, wo) = cache.table(h, w, self.spec.dilation, self.spec.stride, x.device())?;
        let flat = x.reshape((b, h * w, c))?;
        let zero = Tensor::zeros((b, 1, c), x.dtype(), x.device())?;
        let padded = Tensor::cat(&[&flat, &zero], 1)?;
        let cols = padded
            .index_select(&ids, 1)?
            .reshape((b * ho * wo, 9 * c))?;
        let y = self.linear.forward(&cols)?;
        Ok(y.reshape((b, ho, wo, self.spec.channels))?)
    }
}

/// A stack of convolutions with ReLU between them (and after the last). In a residual stack,
/// each convolution that keeps the map's shape (stride 1, as many channels out as in) adds its
/// input before the ReLU: `relu(x + conv(x))`.
#[derive(Clone, Debug)]
pub(crate) struct ConvStack {
    /// Each convolution and whether it adds its input.
    convs: Vec<(Conv, bool)>,
}

impl ConvStack {
    pub(crate) fn new(
        store: &mut ParamStore,
        name: &str,
        cin: usize,
        specs: &[ConvSpec],
        residual: bool,
    ) -> Result<Self> {
        let mut convs = Vec::with_capacity(specs.len());
        let mut c = cin;
        for (i, s) in specs.iter().enumerate() {
            let skip = residual && s.stride == 1 && s.channels == c;
            let name = format!("{name}.{i}");
            // Kaiming-normal, halved on a residual branch so the sum starts near its input.
            let std = (2.0 / (9 * c) as f32).sqrt() * if skip { 0.5 } else { 1.0 };
            convs.push((
                Conv::with_init(store, &name, c, *s, Init::Normal(std))?,
                skip,
            ));
            c = s.channels;
        }
        Ok(Self { convs })
    }

    pub(crate) fn forward(&self, x: &Tensor, cache: &IndexCache) -> Result<Tensor> {
        let mut h = x.clone();
        for (conv, skip) in &self.convs {
            let y = conv.forward(&h, cache)?;
            h = if *skip { (y + &h)?.relu()? } else { y.relu()? };
        }
        Ok(h)
    }

    /// [`ConvStack::forward`] without autograd, for prediction: each layer is one direct
    /// convolution with bias and ReLU ([`crate::kernel::conv3x3_relu`]) over a plain buffer.
    /// Same result as `forward` up to the order of float additions.
    pub(crate) fn forward_inference(&self, x: &Tensor) -> Result<Tensor> {
        let (b, mut h, mut w, mut c) = x.dims4()?;
        let mut act: Vec<f32> = x.flatten_all()?.to_vec1()?;
        for (conv, skip) in &self.convs {
            let shape = ConvShape {
                h,
                w,
                c,
                co: conv.spec.channels,
                dilation: conv.spec.dilation,
                stride: conv.spec.stride,
            };
            let (ho, wo) = shape.out_hw();
            let weight: Vec<f32> = conv.linear.w.flatten_all()?.to_vec1()?;
            let bias: Vec<f32> = conv.linear.b.to_vec1()?;
            let mut y = vec![0.0f32; b * ho * wo * shape.co];
            // One image per task: a batch of maps (several people's, one time step) uses
            // every core.
            act.par_chunks_exact(h * w * c)
                .zip(y.par_chunks_exact_mut(ho * wo * shape.co))
                .for_each(|(image, out)| conv3x3_relu(shape, image, &weight, &bias, *skip, out));
            (act, h, w, c) = (y, ho, wo, shape.co);
        }
        Ok(Tensor::from_vec(act, (b, h, w, c), x.device())?)
    }
}

/// Bounds on an encoder: far beyond what trains on one machine, small enough that a typo is an
/// error and not an allocation that cannot succeed.
pub(crate) const MAX_CONVS: usize = 1024;
const MAX_CHANNELS: usize = 4096;
const MAX_DILATION: usize = 1 << 16;

pub(crate) fn validate_convs(specs: &[ConvSpec], what: &str) -> Result<()> {
    if specs.is_empty() {
        return Err(NetsError::InvalidConfig(format!("{what}: no convolution")));
    }
    if specs.len() > MAX_CONVS {
        return Err(NetsError::InvalidConfig(format!(
            "{what}: {} convolutions, at most {MAX_CONVS}",
            specs.len()
        )));
    }
    for (i, s) in specs.iter().enumerate() {
        if !(1..=MAX_CHANNELS).contains(&s.channels)
            || !(1..=MAX_DILATION).contains(&s.dilation)
            || !(1..=2).contains(&s.stride)
        {
            return Err(NetsError::InvalidConfig(format!(
                "{what}: convolution {i} needs channels in 1..={MAX_CHANNELS}, dilation in \
                 1..={MAX_DILATION}, stride 1 or 2 (got {s:?})"
            )));
        }
    }
    Ok(())
}

/// Bilinear samples of a channels-last feature map (B, H, W, C) at `points` (N = B * Q points,
/// `[row, col]` in cell units, the points of item `b` at `b*Q..(b+1)*Q`): returns (N, C).
/// `rows`/`cols` give the points as a tensor (N, 1) each, so gradients reach them; integral
/// points take one gather.
pub(crate) fn sample_features(
    features: &Tensor,
    points: &[[f32; 2]],
    per_item: usize,
    rows: &Tensor,
    cols: &Tensor,
) -> Result<Tensor> {
    let (b, h, w, c) = features.dims4()?;
    let flat = features.reshape((b * h * w, c))?;
    let device = features.device();
    let base = |i: usize| (i / per_item * h * w) as u32;
    let integral = points
        .iter()
        .all(|p| p[0].fract() == 0.0 && p[1].fract() == 0.0);
    if integral {
        let ids: Vec<u32> = points
            .iter()
            .enumerate()
            .map(|(i, p)| base(i) + p[0] as u32 * w as u32 + p[1] as u32)
            .collect();
        let n = ids.len();
        return Ok(flat.index_select(&Tensor::from_vec(ids, n, device)?, 0)?);
    }
    let corner =
        |x: f32, n: usize| -> u32 { (x.floor().max(0.0) as usize).min(n.saturating_sub(2)) as u32 };
    let n = points.len();
    let mut r0 = Vec::with_capacity(n);
    let mut c0 = Vec::with_capacity(n);
    let mut ids = [(); 4].map(|_| Vec::with_capacity(n));
    for (i, p) in points.iter().enumerate() {
        let (r, cc) = (corner(p[0], h), corner(p[1], w));
        r0.push(r as f32);
        c0.push(cc as f32);
        let r1 = (r + 1).min(h as u32 - 1);
        let c1 = (cc + 1).min(w as u32 - 1);
        let at = |rr: u32, ccc: u32| base(i) + rr * w as u32 + ccc;
        ids[0].push(at(r, cc));
        ids[1].push(at(r, c1));
        ids[2].push(at(r1, cc));
        ids[3].push(at(r1, c1));
    }
    let fr = rows.broadcast_sub(&Tensor::from_vec(r0, (n, 1), device)?)?;
    let fc = cols.broadcast_sub(&Tensor::from_vec(c0, (n, 1), device)?)?;
    let (gr, gc) = ((1.0 - &fr)?, (1.0 - &fc)?);
    let weights = [(&gr * &gc)?, (&gr * &fc)?, (&fr * &gc)?, (&fr * &fc)?];
    let mut out: Option<Tensor> = None;
    for (k, idk) in ids.into_iter().enumerate() {
        let g = flat.index_select(&Tensor::from_vec(idk, n, device)?, 0)?;
        let term = g.broadcast_mul(&weights[k])?;
        out = Some(match out {
            None => term,
            Some(o) => (o + term)?,
        });
    }
    Ok(out.expect("four corners"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inference path of a conv stack (plain loops around one matmul per layer) equals the
    /// tracked one, with dilations, a stride and a non-square map, biases non-zero.
    #[test]
    fn conv_stack_inference_matches_the_tracked_forward() -> Result<()> {
        let dev = Device::Cpu;
        let specs = [
            ConvSpec::new(5, 1),
            ConvSpec::new(6, 2),
            ConvSpec {
                channels: 4,
                dilation: 1,
                stride: 2,
            },
            ConvSpec::new(3, 3),
        ];
        for residual in [false, true] {
            let mut store = ParamStore::new(11, &dev);
            let mut specs = specs.to_vec();
            if residual {
                // Two layers that keep the shape, one at each resolution.
                specs.insert(2, ConvSpec::new(6, 1));
                specs.push(ConvSpec::new(3, 2));
            }
            let stack = ConvStack::new(&mut store, "enc", 3, &specs, residual)?;
            let skips = stack.convs.iter().filter(|(_, skip)| *skip).count();
            assert_eq!(skips, if residual { 2 } else { 0 });
            for (var, name) in store.vars().iter().zip(store.names()) {
                if name.ends_with("bias") {
                    var.set(&Tensor::randn(0f32, 0.3, var.dims(), &dev)?)?;
                }
            }
            let x = Tensor::randn(0f32, 1.0, (2, 9, 7, 3), &dev)?;
            let tracked = stack.forward(&x, &IndexCache::default())?;
            let fast = stack.forward_inference(&x)?;
            assert_eq!(tracked.dims(), fast.dims());
            assert_eq!(fast.dims(), &[2, 5, 4, 3]);
            let diff = (tracked - fast)?.abs()?.max_all()?.to_scalar::<f32>()?;
            assert!(diff < 1e-4, "residual {residual}: max difference {diff}");
        }
        Ok(())
    }

    /// The im2col convolution equals candle's direct conv2d (NCHW) for every dilation and
    /// stride the encoders use.
    #[test]
    fn im2col_matches_candle_conv2d() -> Result<()> {
        let dev = Device::Cpu;
        let (b, h, w, cin) = (2, 7, 6, 3);
        let cache = IndexCache::default();
        for (dilation, stride) in [(1, 1), (2, 1), (3, 1), (1, 2)] {
            let mut store = ParamStore::new(dilation as u64, &dev);
            let conv = Conv::with_init(
                &mut store,
                "c",
                cin,
                ConvSpec {
                    channels: 4,
                    dilation,
                    stride,
                },
                Init::Normal(0.3),
            )?;
            let bias = Tensor::new(&[0.1f32, -0.2, 0.3, 0.0], &dev)?;
            let x = Tensor::randn(0f32, 1.0, (b, h, w, cin), &dev)?;
            let conv = Conv {
                linear: Linear {
                    w: conv.linear.w.clone(),
                    b: bias.clone(),
                },
                spec: conv.spec,
            };
            let ours = conv.forward(&x, &cache)?.permute((0, 3, 1, 2))?;
            // (9*cin, cout) rows (ky*3+kx)*cin + c  ->  (cout, cin, 3, 3)
            let kernel = conv
                .linear
                .w
                .reshape((3, 3, cin, 4))?
                .permute((3, 2, 0, 1))?
                .contiguous()?;
            let theirs = x
                .permute((0, 3, 1, 2))?
                .contiguous()?
                .conv2d(&kernel, dilation, stride, dilation, 1)?
                .broadcast_add(&bias.reshape((1, 4, 1, 1))?)?;
            assert_eq!(
                ours.dims(),
                theirs.dims(),
                "dilation {dilation} stride {stride}"
            );
            let diff = (ours - theirs)?.abs()?.max_all()?.to_scalar::<f32>()?;
            assert!(
                diff < 1e-4,
                "dilation {dilation} stride {stride}: max diff {diff}"
            );
        }
        Ok(())
    }

    #[test]
    fn bilinear_sampling_interpolates_and_hits_cells() -> Result<()> {
        let dev = Device::Cpu;
        // One item, 2x3 map, 1 channel: value = 10 * row + col.
        let f = Tensor::new(&[0f32, 1., 2., 10., 11., 12.], &dev)?.reshape((1, 2, 3, 1))?;
        let pts = [[0.5f32, 1.25], [1.0, 2.0]];
        let rows = Tensor::new(&[[0.5f32], [1.0]], &dev)?;
        let cols = Tensor::new(&[[1.25f32], [2.0]], &dev)?;
        let s = sample_features(&f, &pts, 2, &rows, &cols)?
            .flatten_all()?
            .to_vec1::<f32>()?;
        assert!((s[0] - 6.25).abs() < 1e-5, "{s:?}");
        assert!((s[1] - 12.0).abs() < 1e-5, "{s:?}");
        Ok(())
    }
}
