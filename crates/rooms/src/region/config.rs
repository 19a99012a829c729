//! [`RegionConfig`]: how samples are filtered and voxelised.

use crate::{Result, RoomsError};
use envfield_affordance::FilterConfig;
use serde::{Deserialize, Serialize};

/// How samples are filtered (the torso filter of
/// [`envfield_affordance::afford`]) and voxelised. Its JSON form is flat: the filter's
/// fields beside `voxel`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionConfig {
    /// The torso filter: the torso sphere, headings, tolerances, plausibility and settling.
    #[serde(flatten)]
    pub filter: FilterConfig,
    /// Voxel side of the region, metres.
    pub voxel: f32,
}

impl Default for RegionConfig {
    fn default() -> Self {
        Self {
            filter: FilterConfig::default(),
            voxel: 0.1,
        }
    }
}

impl RegionConfig {
    /// The same filter, each torso judged where it is (no settling).
    pub fn in_place(&self) -> Self {
        Self {
            filter: self.filter.in_place(),
            ..*self
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`RoomsError::InvalidConfig`] naming the settings that cannot work.
    pub fn validate(&self) -> Result<()> {
        self.filter
            .validate()
            .map_err(|e| RoomsError::InvalidConfig(e.to_string()))?;
        if self.voxel.is_finite() && self.voxel >= 0.02 {
            Ok(())
        } else {
            Err(RoomsError::InvalidConfig(format!(
                "region: a voxel of at least 2 cm (got {})",
                self.voxel
            )))
        }
    }
}
