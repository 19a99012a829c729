//! A room's learned field kept on disk ([`FieldStore`]): a field trained for a region is
//! tagged with a fingerprint of that region and of the training's settings, so a later run
//! loads it instead of training again, and a file left or planted under the name is not
//! taken for another region's.

use crate::sampling::region_key;
use crate::{train_field3, AccessibleRegion, Field3Config, Field3Report, Result, RoomsError};
use envfield_nets::{FieldNet, ModelConfig};
use std::path::{Path, PathBuf};

/// The metadata key of a kept field's region fingerprint and training steps.
pub const REGION_TAG: &str = "room_nav.region";

/// Where a room's learned field is looked for, in this order: a file the user named, a kept
/// one, the shipped one. `room_nav` reads its `--field`, `--fields` and the shipped model
/// through it.
#[derive(Clone, Debug, Default)]
pub struct FieldStore {
    /// A file the user named: it must fit the region.
    pub named: Option<PathBuf>,
    /// A folder of kept fields, `room_field_<seed>_<region>_<steps>.safetensors` (the room, a
    /// fingerprint of its region and the training's settings, and the training steps): a
    /// field of this region and these settings is loaded from it, and [`FieldStore::keep`]
    /// keeps one trained now there.
    pub kept: Option<PathBuf>,
    /// A shipped field: loaded when it fits the region, passed over (and trained anew) when
    /// it does not.
    pub shipped: Option<PathBuf>,
}

/// Which file a field came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FieldOrigin {
    /// [`FieldStore::named`].
    Named(PathBuf),
    /// A kept field of [`FieldStore::kept`].
    Kept(PathBuf),
    /// [`FieldStore::shipped`].
    Shipped(PathBuf),
}

/// How [`FieldStore::load_or_train`] got its field.
#[derive(Clone, Debug)]
pub enum Obtained {
    /// Loaded from this file.
    Loaded(FieldOrigin),
    /// Trained now, with its report, and kept in this file when there is a kept folder.
    Trained(Field3Report, Option<PathBuf>),
}

/// What a field is kept under: its region's fingerprint and the training's settings but its
/// steps, then the steps.
fn tag(region: &AccessibleRegion, config: &Field3Config) -> (String, String) {
    let settings = Field3Config {
        steps: 0,
        ..config.clone()
    };
    let fingerprint = format!("{:016x}{:08x}", region_key(region), settings.key() as u32);
    let key = format!("{fingerprint}_{}", config.steps);
    (fingerprint, key)
}

fn unfit(path: &Path, reason: &str) -> RoomsError {
    RoomsError::Checkpoint {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

impl FieldStore {
    /// The kept field's file for room `seed` trained with `config` on `region`.
    pub fn kept_file(
        &self,
        region: &AccessibleRegion,
        config: &Field3Config,
        seed: u64,
    ) -> Option<PathBuf> {
        let (_, key) = tag(region, config);
        self.kept
            .as_ref()
            .map(|d| d.join(format!("room_field_{seed}_{key}.safetensors")))
    }

    /// The field of room `seed`'s `region` trained with `config`, from the first file that
    /// holds one, and where it came from; `None` when no file does (train one) or the shipped
    /// one was trained on another region.
    ///
    /// # Errors
    /// [`RoomsError::Checkpoint`] for a named or kept file that does not fit the region (no
    /// or another fingerprint, another lattice); errors reading the weights.
    pub fn load(
        &self,
        region: &AccessibleRegion,
        config: &Field3Config,
        seed: u64,
    ) -> Result<Option<(FieldNet, FieldOrigin)>> {
        let (fingerprint, key) = tag(region, config);
        let kept = self.kept_file(region, config, seed).filter(|p| p.is_file());
        let origin = match (&self.named, kept, &self.shipped) {
            (Some(f), _, _) => FieldOrigin::Named(f.clone()),
            (None, Some(f), _) => FieldOrigin::Kept(f),
            (None, None, Some(f)) if f.is_file() => FieldOrigin::Shipped(f.clone()),
            _ => return Ok(None),
        };
        let (FieldOrigin::Named(f) | FieldOrigin::Kept(f) | FieldOrigin::Shipped(f)) = &origin;
        let tagged = FieldNet::read_tags(f, REGION_TAG)?;
        if matches!(origin, FieldOrigin::Kept(_)) && tagged.as_deref() != Some(key.as_str()) {
            return Err(unfit(
                f,
                "not a field of this region (no or another fingerprint); remove it",
            ));
        }
        let net = FieldNet::load(f)?;
        // A field that carries its region's fingerprint (a kept one, or the shipped one made
        // from it) fits only that region; one without, any region on a lattice of its shape.
        let same_region = tagged
            .as_deref()
            .is_none_or(|t| t.split('_').next() == Some(fingerprint.as_str()));
        // Why it does not fit, if it does not: another kind of network, another lattice,
        // another region.
        let misfit = match net.config() {
            ModelConfig::Goal(c) if c.extent != region.frame.shape.to_vec() => Some(format!(
                "this field was trained on a lattice of {:?} voxels, this region's is {:?} (another \
                 scene, room or VAE); train it again",
                c.extent, region.frame.shape
            )),
            ModelConfig::Goal(_) if !same_region => Some(
                "this field was trained on another region (the VAE or the room changed); train \
                 it again"
                    .to_string(),
            ),
            ModelConfig::Goal(_) => None,
            other => Some(format!(
                "a `{}` network, not a room field (a room's field is a `goal` network: room_nav \
                 --save-field or --fields write one)",
                other.arch()
            )),
        };
        match misfit {
            None => Ok(Some((net, origin))),
            Some(_) if matches!(origin, FieldOrigin::Shipped(_)) => Ok(None),
            Some(why) => Err(unfit(f, &why)),
        }
    }

    /// [`FieldStore::load`], or, when no file holds the field, [`train_field3`] (its steps
    /// reported to `on_step`) and [`FieldStore::keep`].
    ///
    /// # Errors
    /// As [`FieldStore::load`], [`train_field3`] and [`FieldStore::keep`].
    pub fn load_or_train(
        &self,
        region: &AccessibleRegion,
        config: &Field3Config,
        seed: u64,
        on_step: impl FnMut(u64, u64, f32),
    ) -> Result<(FieldNet, Obtained)> {
        if let Some((net, origin)) = self.load(region, config, seed)? {
            return Ok((net, Obtained::Loaded(origin)));
        }
        let (net, report) = train_field3(region, config, None, on_step)?;
        let kept = self.keep(&net, region, config, seed)?;
        Ok((net, Obtained::Trained(report, kept)))
    }

    /// Keeps `net`, trained with `config` on room `seed`'s `region`, in the kept folder (made
    /// if need be), tagged with its fingerprint; the file, or `None` without a folder.
    ///
    /// # Errors
    /// Errors making the folder or writing the weights, naming the file.
    pub fn keep(
        &self,
        net: &FieldNet,
        region: &AccessibleRegion,
        config: &Field3Config,
        seed: u64,
    ) -> Result<Option<PathBuf>> {
        let Some(file) = self.kept_file(region, config, seed) else {
            return Ok(None);
        };
        if let Some(dir) = file.parent() {
            std::fs::create_dir_all(dir).map_err(|e| RoomsError::Checkpoint {
                path: dir.to_path_buf(),
                reason: format!("creating the folder of kept fields: {e}"),
            })?;
        }
        save_tagged(net, &file, region, config)?;
        Ok(Some(file))
    }
}

/// Saves `net`, trained with `config` on `region`, to `path` tagged with its fingerprint, so
/// a later [`FieldStore::load`] knows which region it fits.
///
/// # Errors
/// Errors writing the weights, naming the file.
pub fn save_tagged(
    net: &FieldNet,
    path: &Path,
    region: &AccessibleRegion,
    config: &Field3Config,
) -> Result<()> {
    let (_, key) = tag(region, config);
    Ok(net.save_tagged(path, &[(REGION_TAG, key)])?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{standing_torsos, RegionConfig};
    use envfield_scene::nalgebra::Isometry3;
    use envfield_scene::{ObjectKind, Primitive, Scene, SceneObject};

    /// Issue 56: a file that is no room field is refused saying what it is (a bird's-eye
    /// context network: "a `context` network, not a room field"), where it was told "trained
    /// on another region".
    #[test]
    fn a_network_of_another_kind_is_named_as_such() {
        let mut scene = Scene::new();
        let slab = SceneObject::new("floor", ObjectKind::Floor)
            .with(
                Primitive::cuboid([3.0, 2.0, 0.1]),
                Isometry3::translation(1.5, 1.0, -0.05),
            )
            .unwrap();
        scene.add(slab).unwrap();
        let torsos = standing_torsos(&scene, 0.25).unwrap();
        let region =
            AccessibleRegion::from_drawn(&scene, &torsos, &RegionConfig::default().in_place())
                .unwrap();
        let context =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/context.safetensors");
        let store = FieldStore {
            named: Some(context),
            ..FieldStore::default()
        };
        let e = store
            .load(&region, &Field3Config::default(), 0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("a `context` network, not a room field"), "{e}");
    }
}
