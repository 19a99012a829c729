//! From a VAE to an accessible region: the VAE's cloud of a scene, torso samples drawn as a
//! VAE draws them or next to another VAE's samples, and the region they give.

use crate::{AccessibleRegion, RegionConfig, Result, RoomsError};
use envfield_grid::{normals, Point3m};
use envfield_scene::{sample_surface, Scene};
use envfield_vae::{Cvae, SampleOptions, NORMAL_SALT};

/// The VAE's cloud of a scene: as many surface points as it reads
/// ([`Cvae::cloud_points`]), seeded.
///
/// # Errors
/// Errors of the surface sampling (an empty scene).
pub fn vae_cloud(vae: &Cvae, scene: &Scene, seed: u64) -> Result<Vec<Point3m>> {
    Ok(sample_surface(scene, vae.cloud_points(), seed)?
        .iter()
        .map(|p| Point3m::from(*p))
        .collect())
}

/// Torso samples of `vae` in `scene` with `options`. With `anchors_from`, a local `vae` draws
/// next to that VAE's samples (drawn with `options.n` and the seed `options.seed ^ 0xF1F1`)
/// instead of uniform anchors, each moved by the local VAE's training jitter: anchors where
/// people are likely keep the decoder on the anchors it learned.
///
/// # Errors
/// [`RoomsError::InvalidInput`] for `anchors_from` with a `vae` that is not local; errors of
/// the sampling.
pub fn draw_torsos(
    vae: &Cvae,
    scene: &Scene,
    options: &SampleOptions,
    anchors_from: Option<&Cvae>,
) -> Result<Vec<Point3m>> {
    let cloud = vae_cloud(vae, scene, options.seed)?;
    let Some(first) = anchors_from else {
        return Ok(vae.sample(&cloud, options)?);
    };
    let local = vae.as_local().ok_or_else(|| {
        RoomsError::InvalidInput(
            "anchors from another VAE: this VAE reads the whole scene, not neighbourhoods".into(),
        )
    })?;
    let jitter = vae.config().local.map_or(0.0, |l| l.jitter);
    let firsts = first.sample(
        &vae_cloud(first, scene, options.seed)?,
        &SampleOptions::new(options.n, options.seed ^ 0xF1F1),
    )?;
    // Moved as in training: a standard-normal step of `jitter` in x and y.
    let g = normals(2 * firsts.len(), options.seed ^ 0x7E77 ^ NORMAL_SALT);
    let at: Vec<[f32; 2]> = firsts
        .iter()
        .zip(g.chunks_exact(2))
        .map(|(t, g)| [t[0] + jitter * g[0], t[1] + jitter * g[1]])
        .collect();
    Ok(local.sample_around(&cloud, &at, options.seed, options.temperature)?)
}

/// The accessible region of `scene` from `samples` draws of `vae` (seeded), with the default
/// filter: the region the room tables plan in.
///
/// # Errors
/// As [`draw_torsos`] and [`AccessibleRegion::from_drawn`].
pub fn sample_region(
    vae: &Cvae,
    scene: &Scene,
    samples: usize,
    seed: u64,
) -> Result<AccessibleRegion> {
    let drawn = draw_torsos(vae, scene, &SampleOptions::new(samples, seed), None)?;
    AccessibleRegion::from_drawn(scene, &drawn, &RegionConfig::default())
}

/// The x and y extents of `scene`'s box and its area (at least 1 m²).
fn floor_extent(scene: &Scene) -> Result<([f32; 2], f32)> {
    let aabb = scene
        .aabb()
        .ok_or_else(|| RoomsError::InvalidInput("the scene is empty".into()))?;
    let extent = aabb.maxs - aabb.mins;
    Ok(([extent.x, extent.y], (extent.x * extent.y).max(1.0)))
}

/// The torso samples the shipped setup draws for `scene`: [`SAMPLES_PER_M2`] over its box's
/// floor.
///
/// # Errors
/// [`RoomsError::InvalidInput`] for an empty scene.
pub fn samples_for(scene: &Scene) -> Result<usize> {
    let (_, area) = floor_extent(scene)?;
    Ok((area * SAMPLES_PER_M2).ceil() as usize)
}

/// Torso samples per square metre of floor the shipped setup draws (6000 in a generated room
/// of about 25 m²): fewer leave the region in specks.
pub const SAMPLES_PER_M2: f32 = 240.0;

/// The most torso samples a region is drawn from.
pub const MAX_SAMPLES: usize = 1_000_000;

/// Whether `samples` torso draws can cover `scene`'s floor (its x-y box): `Ok(None)` when they
/// reach a quarter of [`SAMPLES_PER_M2`], `Ok(Some(warning))` naming `--samples` and the
/// count that would when they do not, and an error when even [`MAX_SAMPLES`] would not (a
/// game level or a building: a region drawn from samples does not scale to it).
///
/// # Errors
/// [`RoomsError::InvalidInput`] for a scene whose floor needs more than [`MAX_SAMPLES`], or
/// an empty scene.
pub fn check_sample_density(scene: &Scene, samples: usize) -> Result<Option<String>> {
    let (extent, area) = floor_extent(scene)?;
    let needed = (area * SAMPLES_PER_M2).ceil();
    if needed > MAX_SAMPLES as f32 {
        return Err(RoomsError::InvalidInput(format!(
            "the scene's floor spans {:.0} x {:.0} m ({area:.0} m²): a region drawn from torso \
             samples needs about {needed:.0} of them ({SAMPLES_PER_M2} a square metre), more than \
             the {MAX_SAMPLES} allowed: build a scene this large's region from its surfaces \
             instead (the `level` example, AccessibleRegion::standing), or is it in \
             centimetres? (--units cm)",
            extent[0], extent[1]
        )));
    }
    let density = samples as f32 / area;
    Ok((density < 0.25 * SAMPLES_PER_M2).then(|| {
        format!(
            "{samples} samples over {area:.0} m² of floor are {density:.0} a square metre: the \
             region will fall apart in specks (set --samples {needed:.0})"
        )
    }))
}

/// A goal for pictures: the kept sample nearest the region's middle in x-y.
pub fn middle_goal(region: &AccessibleRegion) -> Point3m {
    let n = region.samples.len() as f32;
    let mean = region.samples.iter().fold([0.0f32; 3], |a, s| {
        [a[0] + s[0] / n, a[1] + s[1] / n, a[2] + s[2] / n]
    });
    region
        .samples
        .iter()
        .filter(|s| region.contains(**s))
        .min_by(|a, b| {
            let d = |s: &Point3m| (s[0] - mean[0]).powi(2) + (s[1] - mean[1]).powi(2);
            d(a).total_cmp(&d(b))
        })
        .or(region.samples.first())
        .copied()
        .unwrap_or([0.0; 3])
}

/// A fingerprint of the region's voxels (FNV-1a over its shape and accessible voxels), so a
/// kept field is loaded again only for the very region it was trained on.
pub fn region_key(region: &AccessibleRegion) -> u64 {
    let shape = region.frame.shape;
    fnv1a(
        shape
            .iter()
            .chain(region.free_indices())
            .flat_map(|v| (*v as u64).to_le_bytes()),
    )
}

/// FNV-1a (64-bit) of `bytes`: the fingerprints of kept fields.
pub(crate) fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}
