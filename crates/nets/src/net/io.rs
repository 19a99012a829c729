//! Weight files: a network's parameters and its config in one safetensors file.

use super::FieldNet;
use crate::params::{
    weight_metadata, write_weights, TensorFile, FORMAT, META_CONFIG, OPTIMISER_PREFIX,
};
use crate::{ModelConfig, NetsError, Result};
use candle_core::{Device, Tensor};
use std::collections::HashMap;
use std::path::Path;

impl FieldNet {
    pub(crate) fn write_file(
        &self,
        path: &Path,
        extra: Vec<(String, Tensor)>,
        mut metadata: HashMap<String, String>,
    ) -> Result<()> {
        metadata.extend(weight_metadata(FORMAT, &self.config)?);
        let mut tensors = self.store.named_tensors();
        tensors.extend(extra);
        write_weights(path, &tensors, metadata)
    }

    /// Saves the weights and the config as one safetensors file (written atomically).
    ///
    /// # Errors
    /// I/O errors naming the file.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        self.write_file(path.as_ref(), Vec::new(), HashMap::new())
    }

    /// [`FieldNet::save`] with `tags` added to the file's metadata (under keys of the caller's,
    /// which must not start with `envfield.`): what the weights were trained on, for a cache
    /// to check before it loads them ([`FieldNet::read_tags`]).
    ///
    /// # Errors
    /// [`NetsError::InvalidInput`] for a reserved key; I/O errors naming the file.
    pub fn save_tagged(&self, path: impl AsRef<Path>, tags: &[(&str, String)]) -> Result<()> {
        if let Some((k, _)) = tags.iter().find(|(k, _)| k.starts_with("envfield.")) {
            return Err(NetsError::InvalidInput(format!(
                "metadata key `{k}` is reserved"
            )));
        }
        let metadata = tags
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect();
        self.write_file(path.as_ref(), Vec::new(), metadata)
    }

    /// The value of metadata key `key` in the weight file at `path` (written by
    /// [`FieldNet::save_tagged`]), `None` when the file has none.
    ///
    /// # Errors
    /// [`NetsError::Checkpoint`] for an unreadable or foreign file.
    pub fn read_tags(path: impl AsRef<Path>, key: &str) -> Result<Option<String>> {
        Ok(TensorFile::read(path.as_ref())?.metadata.get(key).cloned())
    }

    /// Loads a network saved by [`FieldNet::save`] (or a training checkpoint), rebuilding it
    /// from the config in the file. A checkpoint that keeps a moving average of the weights
    /// ([`crate::TrainConfig::ema_decay`]) loads the average: the network that training
    /// would export at that step.
    ///
    /// # Errors
    /// [`NetsError::Checkpoint`] for an unreadable, truncated or foreign file; the errors of
    /// [`FieldNet::load_weights`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        Self::load_on(path, &Device::Cpu)
    }

    /// As [`FieldNet::load`] on `device`.
    ///
    /// # Errors
    /// As [`FieldNet::load`].
    pub fn load_on(path: impl AsRef<Path>, device: &Device) -> Result<Self> {
        let path = path.as_ref();
        let mut file = TensorFile::read(path)?;
        let config = read_config(path, &file)?;
        let mut net = Self::new_on(config, 0, device)?;
        let average = file.take_average(path, &net.store, device, false)?;
        net.take_weights(path, &mut file)?;
        for (var, t) in net.store.vars().iter().zip(average.into_iter().flatten()) {
            var.set(&t)?;
        }
        Ok(net)
    }

    /// Overwrites this network's weights with those in `path`, checking that every parameter
    /// is there with the same shape and that the file holds nothing else (optimiser state of a
    /// training checkpoint aside).
    ///
    /// # Errors
    /// [`NetsError::Checkpoint`], [`NetsError::MissingWeight`], [`NetsError::ShapeMismatch`],
    /// [`NetsError::UnexpectedWeight`].
    pub fn load_weights(&mut self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let mut file = TensorFile::read(path)?;
        self.take_weights(path, &mut file)
    }

    pub(crate) fn take_weights(&mut self, path: &Path, file: &mut TensorFile) -> Result<()> {
        let mut loaded = Vec::with_capacity(self.store.vars().len());
        for (name, var) in self.store.names().iter().zip(self.store.vars()) {
            loaded.push(file.take(path, name, var.dims(), &self.device)?);
        }
        if let Some(name) = file
            .tensors
            .keys()
            .filter(|k| !k.starts_with(OPTIMISER_PREFIX))
            .min()
        {
            return Err(NetsError::UnexpectedWeight {
                path: path.to_path_buf(),
                name: name.clone(),
            });
        }
        for (var, t) in self.store.vars().iter().zip(loaded) {
            var.set(&t)?;
        }
        Ok(())
    }
}

pub(crate) fn read_config(path: &Path, file: &TensorFile) -> Result<ModelConfig> {
    let json = file
        .metadata
        .get(META_CONFIG)
        .ok_or_else(|| NetsError::Checkpoint {
            path: path.to_path_buf(),
            reason: format!("no `{META_CONFIG}` metadata"),
        })?;
    serde_json::from_str(json).map_err(|e| NetsError::Checkpoint {
        path: path.to_path_buf(),
        reason: format!("bad model config: {e}"),
    })
}
