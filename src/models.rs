//! Loading the learned models that planners by name need ([`envfield_plan::PlannerKind`]):
//! the rule the examples and benchmarks share for picking weight files.

use envfield_grid::{Ensemble, Symmetric};
use envfield_nets::{model_file, FieldNet, NetsError, Result, Vin};
use envfield_plan::{BoxedField, Learned};
use std::path::{Path, PathBuf};

/// Where the weights of learned planners come from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModelSource {
    /// The folder of weight files (the repository's `models/` for the shipped ones).
    pub dir: PathBuf,
    /// A file that wins over the folder: one weight file, or several separated by commas (an
    /// ensemble, the mean of their fields). VIN takes it only when it is a VIN file, so one
    /// flag can serve a run of both a field and VIN.
    pub explicit: Option<PathBuf>,
    /// Average a learned field over this many symmetric views of the maze (1 to 8).
    pub views: usize,
}

impl ModelSource {
    /// The weights in `dir`, one view.
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self {
            dir: dir.into(),
            explicit: None,
            views: 1,
        }
    }

    /// The weight file of `family` for mazes of side `size`: the explicit file, else
    /// [`model_file`]'s rule in the folder (`<family>_<size>`, else `<family>`).
    ///
    /// # Errors
    /// [`NetsError::ModelNotFound`] naming the files looked for.
    pub fn file(&self, family: &str, size: usize) -> Result<PathBuf> {
        match &self.explicit {
            Some(p) => Ok(p.clone()),
            None => model_file(&self.dir, family, size),
        }
    }

    /// The weight file that [`ModelSource::load`] reads for `family` and mazes of side `size`.
    /// For `vin` an explicit file is taken when it is a VIN file; when it is a field model's
    /// file (one flag serving a run of both), VIN's own file in the folder is taken instead.
    ///
    /// # Errors
    /// [`NetsError::ModelNotFound`]; for `vin`, the error reading an explicit file that is
    /// neither a VIN nor a field model's file (missing, truncated, foreign).
    pub fn resolve(&self, family: &str, size: usize) -> Result<PathBuf> {
        match (family, self.explicit.as_deref()) {
            ("vin", Some(p)) => match Vin::load(p) {
                Ok(_) => Ok(p.to_path_buf()),
                Err(_) if first_is_field_file(p) => model_file(&self.dir, "vin", size),
                Err(e) => Err(e),
            },
            _ => self.file(family, size),
        }
    }

    /// The learned model of `family` (`context`, `hyper` or `vin`) for mazes of side `size`,
    /// ready for [`envfield_plan::PlannerKind::build`]; the file is [`ModelSource::resolve`]'s.
    ///
    /// # Errors
    /// A missing or unreadable weight file (the error names it); an unknown family.
    pub fn load(&self, family: &str, size: usize) -> Result<Learned> {
        match family {
            "vin" => Ok(Learned::Policy(Box::new(Vin::load(
                self.resolve("vin", size)?,
            )?))),
            "context" | "hyper" => {
                let file = self.file(family, size)?;
                let mut nets = file
                    .to_string_lossy()
                    .split(',')
                    .map(|f| FieldNet::load(Path::new(f)))
                    .collect::<Result<Vec<_>>>()?;
                let learned: BoxedField = match nets.len() {
                    1 => Box::new(nets.remove(0)),
                    _ => Box::new(Ensemble::new(nets)?),
                };
                Ok(Learned::Field(match self.views {
                    1 => learned,
                    views => Box::new(Symmetric::new(learned, views)?),
                }))
            }
            other => Err(NetsError::InvalidInput(format!(
                "no learned model family `{other}` (context, hyper or vin)"
            ))),
        }
    }
}

/// Whether the first of the comma-separated files `p` is a field model's weight file.
fn first_is_field_file(p: &Path) -> bool {
    let first = p
        .to_string_lossy()
        .split(',')
        .next()
        .unwrap_or_default()
        .to_string();
    FieldNet::load(Path::new(&first)).is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped() -> ModelSource {
        ModelSource::new(Path::new(env!("CARGO_MANIFEST_DIR")).join("models"))
    }

    #[test]
    fn vin_takes_its_own_file_only_beside_a_field_model_and_never_a_broken_one() {
        let source = shipped();
        let context = source.dir.join("context.safetensors");
        let vin8 = source.dir.join("vin_8.safetensors");
        let with = |explicit: &Path| ModelSource {
            explicit: Some(explicit.to_path_buf()),
            ..shipped()
        };
        // A field model's file: VIN's own file for the size.
        assert_eq!(
            with(&context).resolve("vin", 16).unwrap(),
            source.dir.join("vin_16.safetensors")
        );
        // A VIN file: that file.
        assert_eq!(with(&vin8).resolve("vin", 16).unwrap(), vin8);
        // A missing or truncated file: an error, never the default.
        assert!(with(Path::new("no/such.safetensors"))
            .resolve("vin", 16)
            .is_err());
        let dir = std::env::temp_dir().join(format!("envfield-models-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let broken = dir.join("broken.safetensors");
        let bytes = std::fs::read(&vin8).unwrap();
        std::fs::write(&broken, &bytes[..bytes.len() / 2]).unwrap();
        let err = with(&broken).load("vin", 16).err().unwrap().to_string();
        assert!(err.contains("broken.safetensors"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
