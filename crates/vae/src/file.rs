//! The VAE's weight files: safetensors with the config in the metadata, written atomically,
//! every tensor's name and shape checked on load.

use crate::{Cvae, Result, VaeConfig, VaeError};
use candle_core::Tensor;
use envfield_nets::params::{weight_metadata, write_weights, TensorFile, META_CONFIG};
use std::collections::HashMap;
use std::path::Path;

/// The format of envfield-vae's weight files and checkpoints.
pub(crate) const FORMAT: &str = "envfield-vae/1";

/// Named tensors and a file's metadata.
pub(crate) type Named = (Vec<(String, Tensor)>, HashMap<String, String>);

impl Cvae {
    /// The weights as named tensors and the file's metadata (format and config).
    pub(crate) fn named(&self) -> Result<Named> {
        let meta = weight_metadata(FORMAT, &self.config)?;
        Ok((self.store.named_tensors(), meta))
    }

    /// Saves the weights and config as safetensors, atomically (a temporary file, then a
    /// rename).
    ///
    /// # Errors
    /// I/O errors, naming the file.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let (tensors, meta) = self.named()?;
        Ok(write_weights(path.as_ref(), &tensors, meta)?)
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
        vae.store.load_from(path, file)?;
        Ok(vae)
    }
}
