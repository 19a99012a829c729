//! Finding a shipped or trained weight file by model family and maze size.

use crate::{NetsError, Result};
use std::path::{Path, PathBuf};

/// The weight file of the model family `name` (such as `"context"`, `"hyper"` or `"vin"`) for
/// mazes of side `size` in `dir`: `<name>_<size>.safetensors` when it exists (a model trained
/// for that size), else `<name>.safetensors` (one for all sizes). This is the rule the
/// `maze_nav` example, the planning benchmark and the protocol tests use to pick a model from
/// `models/`.
///
/// # Errors
/// [`NetsError::ModelNotFound`], naming both paths it looked for, when neither is a file.
///
/// ```
/// let dir = std::env::temp_dir().join("envfield-model-file-doc");
/// std::fs::create_dir_all(&dir)?;
/// std::fs::write(dir.join("context.safetensors"), b"")?;
/// let picked = envfield_nets::model_file(&dir, "context", 28)?;
/// assert_eq!(picked, dir.join("context.safetensors"));
/// assert!(envfield_nets::model_file(&dir, "hyper", 28).is_err());
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn model_file(dir: impl AsRef<Path>, name: &str, size: usize) -> Result<PathBuf> {
    let dir = dir.as_ref();
    let looked = vec![
        dir.join(format!("{name}_{size}.safetensors")),
        dir.join(format!("{name}.safetensors")),
    ];
    match looked.iter().find(|p| p.is_file()) {
        Some(p) => Ok(p.clone()),
        None => Err(NetsError::ModelNotFound {
            name: name.to_string(),
            size,
            looked,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefers_the_sized_file_then_the_general_one() {
        let dir = std::env::temp_dir().join(format!("envfield-model-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let general = dir.join("context.safetensors");
        let sized = dir.join("context_28.safetensors");
        std::fs::write(&general, b"").unwrap();
        assert_eq!(model_file(&dir, "context", 28).unwrap(), general);
        std::fs::write(&sized, b"").unwrap();
        assert_eq!(model_file(&dir, "context", 28).unwrap(), sized);
        assert_eq!(model_file(&dir, "context", 16).unwrap(), general);
        let err = model_file(&dir, "vin", 8).unwrap_err().to_string();
        assert!(
            err.contains("vin_8.safetensors") && err.contains("vin.safetensors"),
            "{err}"
        );
        assert!(err.contains("8x8"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
