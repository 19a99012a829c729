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

    /// The learned model of `family` (`context`, `hyper` or `vin`) for mazes of side `size`,
    /// ready for [`envfield_plan::PlannerKind::build`].
    ///
    /// # Errors
    /// A missing or unreadable weight file (the error names it); an unknown family.
    pub fn load(&self, family: &str, size: usize) -> Result<Learned> {
        match family {
            "vin" => {
                let file = match self.explicit.as_deref().filter(|p| Vin::load(p).is_ok()) {
                    Some(p) => p.to_path_buf(),
                    None => model_file(&self.dir, "vin", size)?,
                };
                Ok(Learned::Policy(Box::new(Vin::load(&file)?)))
            }
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
