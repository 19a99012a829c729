//! Value iteration inside the context encoder ([`crate::PropagationConfig`]).

use crate::layers::{Conv, ConvSpec, IndexCache, Linear};
use crate::params::{Init, ParamStore};
use crate::{PropagationConfig, Result};
use candle_core::Tensor;

/// Value-iteration layers of a context encoder.
#[derive(Debug)]
pub(super) struct Propagation {
    pub(super) reward: Linear,
    pub(super) q: Conv,
    pub(super) config: PropagationConfig,
}

impl Propagation {
    /// The reward map and the Q convolution on top of `features` encoder channels, both
    /// initialised small as VIN does.
    pub(super) fn new(
        store: &mut ParamStore,
        features: usize,
        config: PropagationConfig,
    ) -> Result<Self> {
        let small = Init::Normal(0.01);
        let reward = Linear::new(store, "vi.reward", features, 1, small)?;
        let q = Conv::with_init(store, "vi.q", 2, ConvSpec::new(config.q_channels, 1), small)?;
        Ok(Self { reward, q, config })
    }

    /// (B, H, W, C) features -> (B, H, W, Q + 1): the last Q map and its channel maximum.
    pub(super) fn forward(&self, features: &Tensor, cache: &IndexCache) -> Result<Tensor> {
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
    pub(super) fn forward_inference(&self, features: &Tensor) -> Result<Tensor> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::Device;

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
