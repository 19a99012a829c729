//! Loading the learned models that planners by name need ([`envfield_plan::PlannerKind`]):
//! the rule the examples and benchmarks share for picking weight files.

use envfield_grid::{Ensemble, MoveRule, Symmetric};
use envfield_nets::{model_file, FieldNet, NetsError, Result, Vin, VinConfig};
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
    /// The move rule the agent walks by: a field with a shortest-path readout
    /// ([`envfield_nets::PathConfig`]) takes its moves from it.
    pub rule: MoveRule,
}

impl ModelSource {
    /// The weights in `dir`, one view.
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self {
            dir: dir.into(),
            explicit: None,
            views: 1,
            rule: MoveRule::Strict,
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

    /// The learned model of `family` (`context`, `hyper` or `vin`) for mazes of side `size`,
    /// ready for [`envfield_plan::PlannerKind::build`], with the file it came from. The field
    /// families read [`ModelSource::file`]. For `vin` an explicit file is taken when it is a
    /// VIN file; when it is a field model's file (one flag serving a run of both), VIN's own
    /// file in the folder is taken instead; anything else explicit is an error, never a quiet
    /// fall back.
    ///
    /// # Errors
    /// A missing or unreadable weight file (the error names it); an unknown family.
    pub fn load(&self, family: &str, size: usize) -> Result<(PathBuf, Learned)> {
        match family {
            "vin" => {
                let (file, vin) = match self.explicit.as_deref() {
                    Some(p) => match Vin::load(p) {
                        Ok(vin) => (p.to_path_buf(), vin),
                        Err(_) if first_is_field_file(p) => self.own_vin(size)?,
                        Err(e) => return Err(e),
                    },
                    None => self.own_vin(size)?,
                };
                Ok((file, Learned::Policy(Box::new(vin))))
            }
            "context" | "hyper" => {
                let file = self.file(family, size)?;
                let mut nets = file
                    .to_string_lossy()
                    .split(',')
                    .map(|f| {
                        let mut net = FieldNet::load(Path::new(f))?;
                        net.set_rule(self.rule);
                        Ok(net)
                    })
                    .collect::<Result<Vec<_>>>()?;
                let learned: BoxedField = match nets.len() {
                    1 => Box::new(nets.remove(0)),
                    _ => Box::new(Ensemble::new(nets)?),
                };
                let learned: BoxedField = match self.views {
                    1 => learned,
                    views => Box::new(Symmetric::new(learned, views)?),
                };
                Ok((file, Learned::Field(learned)))
            }
            other => Err(NetsError::InvalidInput(format!(
                "no learned model family `{other}` (context, hyper or vin)"
            ))),
        }
    }
}

impl ModelSource {
    /// VIN's own file for the size in the folder, loaded. A side without a file of its own
    /// gets the VIN trained on the nearest side (the larger one on a tie) with K set for its
    /// own side ([`VinConfig::for_size`]): VIN is convolutional, and its paper raises K with
    /// the map.
    fn own_vin(&self, size: usize) -> Result<(PathBuf, Vin)> {
        match model_file(&self.dir, "vin", size) {
            Ok(file) => {
                let vin = Vin::load(&file)?;
                Ok((file, vin))
            }
            Err(missing) => {
                let nearest = (1..=MAX_VIN_SIDE)
                    .map(|s| (s, self.dir.join(format!("vin_{s}.safetensors"))))
                    .filter(|(_, p)| p.is_file())
                    .min_by_key(|&(s, _)| (s.abs_diff(size), std::cmp::Reverse(s)));
                let Some((_, file)) = nearest else {
                    return Err(missing);
                };
                let vin =
                    Vin::load(&file)?.with_iterations(VinConfig::for_size(size).iterations)?;
                Ok((file, vin))
            }
        }
    }
}

/// The largest side a `vin_<side>.safetensors` file is looked for at.
const MAX_VIN_SIDE: usize = 512;

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
        let vin_file = |s: ModelSource| s.load("vin", 16).map(|(file, _)| file);
        // A field model's file: VIN's own file for the size.
        assert_eq!(
            vin_file(with(&context)).unwrap(),
            source.dir.join("vin_16.safetensors")
        );
        // A VIN file: that file.
        assert_eq!(vin_file(with(&vin8)).unwrap(), vin8);
        // A missing or truncated file: an error, never the default.
        assert!(vin_file(with(Path::new("no/such.safetensors"))).is_err());
        let dir = std::env::temp_dir().join(format!("envfield-models-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let broken = dir.join("broken.safetensors");
        let bytes = std::fs::read(&vin8).unwrap();
        std::fs::write(&broken, &bytes[..bytes.len() / 2]).unwrap();
        let err = with(&broken).load("vin", 16).err().unwrap().to_string();
        assert!(err.contains("broken.safetensors"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_side_without_its_vin_gets_the_nearest_trained_one_with_its_own_k() {
        let source = shipped();
        let (file, learned) = source.load("vin", 64).unwrap();
        assert_eq!(file, source.dir.join("vin_28.safetensors"));
        let Learned::Policy(policy) = learned else {
            panic!("VIN is a policy");
        };
        assert_eq!(policy.name(), "vin");
        let vin = source.own_vin(48).unwrap().1;
        assert_eq!(vin.config().iterations, VinConfig::for_size(48).iterations);
        assert_eq!(
            source.own_vin(14).unwrap().0,
            source.dir.join("vin_16.safetensors")
        );
        // 12 lies between 8 and 16: the larger wins the tie.
        assert_eq!(
            source.own_vin(12).unwrap().0,
            source.dir.join("vin_16.safetensors")
        );
        let empty = ModelSource::new(std::env::temp_dir().join("envfield-no-models-here"));
        assert!(empty.own_vin(16).is_err());
    }
}
