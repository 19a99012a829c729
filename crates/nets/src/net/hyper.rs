//! The hypernetwork (paper appendix A.1): a convolutional network predicts the weights of a
//! SIREN that maps (goal, query) to the distance.

use super::FieldNet;
use crate::layers::{ConvStack, Linear};
use crate::params::{Init, ParamStore};
use crate::{Batch, HyperConfig, Result};
use candle_core::Tensor;

/// The hyponetwork's layer shapes: (fan_in, fan_out) per layer.
fn hypo_shapes(c: &HyperConfig) -> Vec<(usize, usize)> {
    let mut shapes = vec![(4, c.hypo_hidden)];
    for _ in 1..c.hypo_layers {
        shapes.push((c.hypo_hidden, c.hypo_hidden));
    }
    shapes.push((c.hypo_hidden, 1));
    shapes
}

#[derive(Debug)]
pub(super) struct Hyper {
    encoder: ConvStack,
    fc: Vec<Linear>,
    head: Linear,
    base: Vec<Linear>,
}

impl Hyper {
    /// The encoder, the fully connected layers, the head and the base weights, created in
    /// that order (the order fixes which random numbers each parameter draws).
    pub(super) fn new(store: &mut ParamStore, c: &HyperConfig) -> Result<Self> {
        let encoder = ConvStack::new(
            store,
            "encoder",
            1 + c.goal_channel as usize,
            &c.encoder,
            false,
        )?;
        let mut width = c.encoder.last().map_or(0, |s| s.channels);
        let mut fc = Vec::new();
        for (i, &w) in c.fc.iter().enumerate() {
            let init = Init::Normal((2.0 / width as f32).sqrt());
            fc.push(Linear::new(store, &format!("fc.{i}"), width, w, init)?);
            width = w;
        }
        let shapes = hypo_shapes(c);
        let total: usize = shapes.iter().map(|(i, o)| i * o + o).sum();
        let head = Linear::new(
            store,
            "head",
            width,
            total,
            Init::Normal(1e-3 / (width as f32).sqrt()),
        )?;
        let mut base = Vec::new();
        for (l, &(i, o)) in shapes.iter().enumerate() {
            let bound = if l == 0 {
                1.0 / i as f32
            } else {
                (6.0 / i as f32).sqrt() / c.omega0
            };
            base.push(Linear::new(
                store,
                &format!("hypo.{l}"),
                i,
                o,
                Init::Uniform(bound),
            )?);
        }
        Ok(Hyper {
            encoder,
            fc,
            head,
            base,
        })
    }
}

impl FieldNet {
    pub(super) fn hyper_forward(
        &self,
        hy: &Hyper,
        c: &HyperConfig,
        batch: &Batch,
        goals: &Tensor,
        queries: &Tensor,
    ) -> Result<Tensor> {
        let features = hy
            .encoder
            .forward(&self.grid_input(batch, c.goal_channel)?, &self.cache)?;
        let mut h = features.mean(2)?.mean(1)?; // (B, C)
        for layer in &hy.fc {
            h = layer.forward(&h)?.relu()?;
        }
        let delta = hy.head.forward(&h)?; // (B, P)
        let (b, q) = (batch.items, batch.per_item);
        let g = self.normalise(goals, &batch.extent)?;
        let x = self.normalise(queries, &batch.extent)?;
        let mut act = Tensor::cat(&[&g, &x], 1)?.reshape((b, q, 4))?;
        let last = hy.base.len() - 1;
        let mut offset = 0;
        for (l, base) in hy.base.iter().enumerate() {
            let (fi, fo) = base.w.dims2()?;
            let dw = delta.narrow(1, offset, fi * fo)?.reshape((b, fi, fo))?;
            offset += fi * fo;
            let db = delta.narrow(1, offset, fo)?.reshape((b, 1, fo))?;
            offset += fo;
            let w = dw.broadcast_add(&base.w)?;
            let bias = db.broadcast_add(&base.b)?;
            act = act.matmul(&w)?.broadcast_add(&bias)?;
            if l < last {
                act = (act * c.omega0 as f64)?.sin()?;
            }
        }
        Ok(act.reshape((b * q, 1))?)
    }
}
