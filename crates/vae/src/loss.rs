//! The VAE's training loss: reconstruction, KL, and the gate's and pose-kind head's
//! cross-entropies.

use crate::{Cvae, Result, VaeError};
use candle_core::Tensor;

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
    /// The training loss on a batch: `clouds` (B, N, 3) and `torsos` (B * k, 3), normalised,
    /// with standard-normal noise `eps` (B * k, latent), weighted by `(kl_weight, sigma)`.
    /// Reconstruction: squared error over `2 sigma^2` (sigma in normalised units), summed
    /// over xyz; KL to the standard normal,
    /// summed over the latent; both averaged over the torsos. `gate`, for a gated VAE: more
    /// neighbourhoods (M, N, 3) and their occupancy labels (M,) of 0 or 1, whose logistic
    /// cross-entropy, averaged, joins the total at the gate's weight. `kinds`, for a VAE with
    /// pose kinds: the torsos' (B * k, 3) one-hot kinds; the kind head's cross-entropy joins
    /// the total at the gate's weight.
    pub(crate) fn loss(
        &self,
        clouds: &Tensor,
        torsos: &Tensor,
        eps: &Tensor,
        (kl_weight, sigma): (f64, f32),
        gate: Option<(&Tensor, &Tensor)>,
        kinds: Option<&Tensor>,
    ) -> Result<Loss> {
        let b = clouds.dim(0)?;
        let k = torsos.dim(0)? / b;
        let feature = Cvae::repeat(&self.features(clouds)?, k)?;
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
}
