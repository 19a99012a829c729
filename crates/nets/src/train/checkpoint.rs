//! Training checkpoints: the network, the optimiser's moments, the step, the training config
//! and a description of the data, in one safetensors file that resumes exactly.

use super::Trainer;
use crate::net::read_config;
use crate::params::{ema_name, TensorFile, META_STEP};
use crate::{FieldNet, NetsError, Result, TrainConfig};
use candle_core::Device;
use std::collections::HashMap;
use std::path::Path;

const META_TRAIN: &str = "envfield.train";
const META_DATA: &str = "envfield.data";

/// How the data a resumed run is given compares with what its checkpoint recorded (see
/// [`Trainer::continue_with_data`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DataCheck {
    /// The same data, or a fresh trainer.
    Same,
    /// Other data, accepted on purpose; `recorded` is what the checkpoint was trained on.
    Changed {
        /// The checkpoint's description.
        recorded: String,
    },
    /// The checkpoint records no data (an older file).
    Unrecorded,
}

impl Trainer {
    /// Resumes from a checkpoint written by [`Trainer::save_checkpoint`]: the network, the
    /// optimiser's moments, the step and the training config.
    ///
    /// # Errors
    /// [`NetsError::Checkpoint`] and the weight errors of [`FieldNet::load_weights`].
    pub fn resume(path: impl AsRef<Path>) -> Result<Self> {
        Self::resume_on(path, &Device::Cpu)
    }

    /// As [`Trainer::resume`] on `device`.
    ///
    /// # Errors
    /// As [`Trainer::resume`].
    pub fn resume_on(path: impl AsRef<Path>, device: &Device) -> Result<Self> {
        let path = path.as_ref();
        let mut file = TensorFile::read(path)?;
        let bad = |reason: String| NetsError::Checkpoint {
            path: path.to_path_buf(),
            reason,
        };
        let step: u64 = file
            .metadata
            .get(META_STEP)
            .ok_or_else(|| {
                bad(format!(
                    "no `{META_STEP}`: a weight file, not a training checkpoint"
                ))
            })?
            .parse()
            .map_err(|e| bad(format!("bad step: {e}")))?;
        let config: TrainConfig = serde_json::from_str(
            file.metadata
                .get(META_TRAIN)
                .ok_or_else(|| bad(format!("no `{META_TRAIN}` metadata")))?,
        )
        .map_err(|e| bad(format!("bad training config: {e}")))?;
        let model = read_config(path, &file)?;
        let mut net = FieldNet::new_on(model, 0, device)?;
        let (m, v) = file.take_moments(path, net.store(), device)?;
        let ema = file.take_average(path, net.store(), device, config.ema_decay > 0.0)?;
        net.take_weights(path, &mut file)?;
        let mut trainer = Self::new(net, config)?;
        trainer.optimiser.set_moments(m, v, step);
        trainer.ema = ema;
        trainer.data = file.metadata.get(META_DATA).cloned();
        Ok(trainer)
    }

    /// What this trainer's data is, as [`Trainer::continue_with_data`] recorded it or its
    /// checkpoint carried it. The datasets are the caller's, so a checkpoint cannot hold them;
    /// it holds this text instead.
    pub fn data_description(&self) -> Option<&str> {
        self.data.as_deref()
    }

    /// Checks the data a run goes on with against the description its checkpoint recorded,
    /// then records `data` as this run's: a resumed run must train on the data it began with,
    /// unless `allow_change` (fine-tuning, a curriculum). A fresh trainer takes any data.
    ///
    /// # Errors
    /// [`NetsError::DataMismatch`] for other data without `allow_change`.
    pub fn continue_with_data(
        &mut self,
        data: impl Into<String>,
        allow_change: bool,
    ) -> Result<DataCheck> {
        let data = data.into();
        let check = match self.data.take() {
            None if self.step() > 0 => DataCheck::Unrecorded,
            None => DataCheck::Same,
            Some(recorded) if recorded == data => DataCheck::Same,
            Some(recorded) if allow_change => DataCheck::Changed { recorded },
            Some(recorded) => {
                let err = NetsError::DataMismatch {
                    recorded: recorded.clone(),
                    given: data,
                };
                self.data = Some(recorded);
                return Err(err);
            }
        };
        self.data = Some(data);
        Ok(check)
    }

    /// Writes a checkpoint (weights, config, optimiser moments, step, training config) to
    /// `path` atomically: a reader sees the old file or the new one, never a partial one.
    ///
    /// # Errors
    /// I/O errors naming the file.
    pub fn save_checkpoint(&self, path: impl AsRef<Path>) -> Result<()> {
        let mut extra = self.optimiser.state_tensors(self.net.param_names());
        if let Some(ema) = &self.ema {
            let names = self.net.param_names().iter().map(|n| ema_name(n));
            extra.extend(names.zip(ema.iter().cloned()));
        }
        let mut meta = HashMap::new();
        meta.insert(META_STEP.to_string(), self.step().to_string());
        let train = serde_json::to_string(&self.config).map_err(|e| {
            NetsError::InvalidConfig(format!("cannot serialise the training config: {e}"))
        })?;
        meta.insert(META_TRAIN.to_string(), train);
        if let Some(data) = &self.data {
            meta.insert(META_DATA.to_string(), data.clone());
        }
        self.net.write_file(path.as_ref(), extra, meta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Batch, ContextConfig, ModelConfig};

    #[test]
    fn the_weight_average_resumes_and_loads_from_a_checkpoint() {
        let dir = std::env::temp_dir().join(format!("envfield-ema-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (batch, targets) = crate::train::loss::tests::dense_room();
        let mut obstacles = vec![0.0; 9];
        (obstacles[1], obstacles[4]) = (1.0, 1.0);
        let batch = Batch { obstacles, ..batch };
        let model = ModelConfig::Context(ContextConfig::default());
        let config = TrainConfig {
            lr: 1e-2,
            ema_decay: 0.5,
            dense: true,
            descent_weight: 1.0,
            ..TrainConfig::default()
        };
        let mut a = Trainer::new(FieldNet::new(model, 3).unwrap(), config).unwrap();
        let raw = |t: &Trainer| t.net().forward(&batch).unwrap().to_vec1::<f32>().unwrap();
        let averaged = |t: &Trainer| {
            let net = t.averaged_net().unwrap();
            net.forward(&batch).unwrap().to_vec1::<f32>().unwrap()
        };
        for _ in 0..3 {
            a.train_batch(&batch, &targets).unwrap();
        }
        assert_ne!(raw(&a), averaged(&a), "the average lags the weights");
        let path = dir.join("ema.ckpt");
        a.save_checkpoint(&path).unwrap();
        // Loading a checkpoint as a network gives the average.
        let loaded = FieldNet::load(&path).unwrap();
        assert_eq!(
            loaded.forward(&batch).unwrap().to_vec1::<f32>().unwrap(),
            averaged(&a)
        );
        // A resumed run continues the same average.
        let mut b = Trainer::resume(&path).unwrap();
        a.train_batch(&batch, &targets).unwrap();
        b.train_batch(&batch, &targets).unwrap();
        assert_eq!(averaged(&a), averaged(&b));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_resumed_run_refuses_other_data_unless_told() {
        let dir = std::env::temp_dir().join(format!("envfield-data-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let model = ModelConfig::Context(ContextConfig::default());
        let mut fresh =
            Trainer::new(FieldNet::new(model, 1).unwrap(), TrainConfig::default()).unwrap();
        assert_eq!(
            fresh.continue_with_data("mazes A", false).unwrap(),
            DataCheck::Same
        );
        let path = dir.join("data.ckpt");
        fresh.save_checkpoint(&path).unwrap();
        let mut resumed = Trainer::resume(&path).unwrap();
        assert_eq!(resumed.data_description(), Some("mazes A"));
        let err = resumed.continue_with_data("mazes B", false).unwrap_err();
        assert!(matches!(err, NetsError::DataMismatch { .. }), "{err}");
        assert_eq!(resumed.data_description(), Some("mazes A"));
        assert_eq!(
            resumed.continue_with_data("mazes B", true).unwrap(),
            DataCheck::Changed {
                recorded: "mazes A".into()
            }
        );
        assert_eq!(resumed.data_description(), Some("mazes B"));
        std::fs::remove_dir_all(&dir).ok();
    }
}
