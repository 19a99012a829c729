//! The region of a scene too large to draw: a standing torso over every surface that faces up.
//!
//! A region drawn from the VAE needs samples in proportion to the floor's area
//! ([`SAMPLES_PER_M2`](crate::sampling::SAMPLES_PER_M2)); a game level of 75 x 100 m would need a
//! million. Here the candidates come from the scene's own surfaces instead, as Recast's
//! heightfield does: rays cast straight down on a lattice of columns find every surface of
//! each column, floors above floors included, and a standing body's torso is placed over each
//! one that faces up within [`MAX_SLOPE_DEG`]. The region's filter then judges them like
//! drawn samples, so a torso under a low ceiling, against a wall or on a table top is dropped
//! for the same reasons. Only standing: nothing here places a seated or lying torso.

use crate::{AccessibleRegion, RegionConfig, Result, RoomsError};
use envfield_affordance::standing_pose;
use envfield_grid::Point3m;
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::Scene;
use rayon::prelude::*;

/// The steepest surface a torso is placed over, degrees from level (Recast's default).
pub const MAX_SLOPE_DEG: f32 = 45.0;

/// At most this many columns: 16 million, a 400 x 400 m scene at 0.1 m.
pub const MAX_COLUMNS: usize = 16_000_000;

/// At most this many surfaces a column (a stack of 64 floors).
const MAX_LAYERS: usize = 64;

/// The torso of a standing body over every up-facing surface of `scene`, on a lattice of
/// columns `spacing` metres apart (column centres, the scene's box from its minimum corner),
/// top surface first in each column. Cost: a ray cast per surface met, in parallel.
///
/// # Errors
/// [`RoomsError::InvalidConfig`] for a spacing under 2 cm or not finite, or more than
/// [`MAX_COLUMNS`] columns (naming the spacing that fits); [`RoomsError::InvalidInput`] for an
/// empty scene.
pub fn standing_torsos(scene: &Scene, spacing: f32) -> Result<Vec<Point3m>> {
    if !(spacing.is_finite() && spacing >= 0.02) {
        return Err(RoomsError::InvalidConfig(format!(
            "standing torsos: a column spacing of at least 0.02 m (got {spacing})"
        )));
    }
    let aabb = scene
        .aabb()
        .ok_or_else(|| RoomsError::InvalidInput("the scene is empty".into()))?;
    let (lo, hi) = (aabb.mins, aabb.maxs);
    let count = |a: usize| ((hi[a] - lo[a]) / spacing).ceil().max(1.0) as usize;
    let (nx, ny) = (count(0), count(1));
    if nx.saturating_mul(ny) > MAX_COLUMNS {
        // Rounded up to the centimetre, so the spacing named fits.
        let fits = ((hi.x - lo.x) * (hi.y - lo.y) / MAX_COLUMNS as f32).sqrt();
        let fits = (fits * 100.0).ceil() / 100.0 + 0.01;
        return Err(RoomsError::InvalidConfig(format!(
            "standing torsos: {nx} x {ny} columns at {spacing} m is more than {MAX_COLUMNS}; \
             a spacing of {fits:.2} m or more fits (is the scene in centimetres? --units cm)"
        )));
    }
    // The torso's height over the surface the standing pose's feet rest on.
    let pose = standing_pose();
    let torso_up = pose.torso().z - pose.lowest();
    let top = hi.z + 0.1;
    let range = hi.z - lo.z + 0.2;
    let down = Vector3::new(0.0, 0.0, -1.0);
    let level = MAX_SLOPE_DEG.to_radians().cos();
    let columns: Vec<Vec<Point3m>> = (0..nx * ny)
        .into_par_iter()
        .map(|k| -> Result<Vec<Point3m>> {
            let x = lo.x + ((k / ny) as f32 + 0.5) * spacing;
            let y = lo.y + ((k % ny) as f32 + 0.5) * spacing;
            let hits = scene.surfaces_along(&Point3::new(x, y, top), &down, range, MAX_LAYERS)?;
            // Normals are not trusted to point out (see the scene's `solid`): a surface level
            // enough either way carries a torso, and the filter drops one in a slab or under
            // a ceiling.
            Ok(hits
                .iter()
                .filter(|h| h.normal.z.abs() >= level)
                .map(|h| [x, y, h.point.z + torso_up])
                .collect())
        })
        .collect::<Result<_>>()?;
    Ok(columns.into_iter().flatten().collect())
}

impl AccessibleRegion {
    /// The region where a body can stand: [`standing_torsos`] on columns one voxel apart,
    /// judged by `config`'s filter where they are (no settling), voxelised as
    /// [`AccessibleRegion::from_kept`] does.
    ///
    /// # Errors
    /// As [`standing_torsos`] and [`AccessibleRegion::from_drawn`].
    pub fn standing(scene: &Scene, config: &RegionConfig) -> Result<Self> {
        let torsos = standing_torsos(scene, config.voxel)?;
        Self::from_drawn(scene, &torsos, &config.in_place())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use envfield_scene::nalgebra::{Isometry3, Translation3, UnitQuaternion};
    use envfield_scene::{ObjectKind, Primitive, SceneObject};

    fn slab(scene: &mut Scene, name: &str, size: Point3m, at: Point3m, pitch: f32) {
        let pose = Isometry3::from_parts(
            Translation3::new(at[0], at[1], at[2]),
            UnitQuaternion::from_euler_angles(0.0, pitch, 0.0),
        );
        let object = SceneObject::new(name, ObjectKind::Floor)
            .with(Primitive::cuboid(size), pose)
            .expect("slab");
        scene.add(object).expect("add");
    }

    #[test]
    fn every_floor_of_a_column_carries_a_torso() {
        // A floor at z = 0 and a 0.2 m slab over half of it, its top at 2.5 m.
        let mut scene = Scene::new();
        slab(&mut scene, "floor", [4.0, 2.0, 0.1], [2.0, 1.0, -0.05], 0.0);
        slab(&mut scene, "upper", [2.0, 2.0, 0.2], [3.0, 1.0, 2.4], 0.0);
        let torsos = standing_torsos(&scene, 0.25).expect("torsos");
        let up = standing_pose().torso().z;
        let over = |x: f32, z: f32| {
            torsos
                .iter()
                .filter(|t| (t[0] - x).abs() < 0.13 && (t[2] - z).abs() < 0.05)
                .count()
        };
        // Eight columns across the slab's 2 m in y, at x = 1.125 and 3.125.
        assert_eq!(over(1.125, up), 8, "the open floor");
        assert_eq!(over(3.125, 2.5 + up), 8, "the slab's top");
        assert_eq!(over(3.125, up), 8, "the floor under the slab");
        // The filter: under the slab's 2.3 m ceiling a body stands; over the slab's underside
        // its feet would be in the slab. The two floors are not joined (no stairs), so the
        // region is the larger, lower one and the slab's top is a component of its own.
        let region =
            AccessibleRegion::from_drawn(&scene, &torsos, &RegionConfig::default().in_place())
                .expect("region");
        assert!(region.contains([3.125, 1.125, up]));
        assert!(!region.contains([3.125, 1.125, 2.5 + up]));
        assert!(!region.contains([3.125, 1.125, 2.3 + up]));
        assert_eq!(region.components, 2);
        // The slab's top (2 x 2 m, its region kept clear of the edges) is left out, too small
        // a storey to be named: a bed or a table top left out is no news.
        assert_eq!(region.left_out[0].min[..2], [2.0, 0.0]);
        assert!(region.left_out_warning().is_none());
    }

    /// Issue 56: two 3 x 3 m rooms joined by a 0.2 m slot. The region keeps one and says
    /// where the other lies, that nothing joins it; a slot a body fits through joins them.
    #[test]
    fn a_room_the_region_leaves_out_is_named() {
        // Torsos 5 cm apart: some stand in the slot, turned sideways.
        let two_rooms = |slot: f32| {
            let mut scene = Scene::new();
            slab(
                &mut scene,
                "floor",
                [6.3, 3.0, 0.1],
                [3.15, 1.5, -0.05],
                0.0,
            );
            // The dividing wall, 0.3 m thick at x = 3..3.3, open for `slot` around y = 1.5.
            let side = (3.0 - slot) / 2.0;
            slab(
                &mut scene,
                "wall a",
                [0.3, side, 2.5],
                [3.15, side / 2.0, 1.25],
                0.0,
            );
            slab(
                &mut scene,
                "wall b",
                [0.3, side, 2.5],
                [3.15, 3.0 - side / 2.0, 1.25],
                0.0,
            );
            let torsos = standing_torsos(&scene, 0.05).expect("torsos");
            AccessibleRegion::from_drawn(&scene, &torsos, &RegionConfig::default().in_place())
                .expect("region")
        };
        let apart = two_rooms(0.2);
        let warning = apart.left_out_warning().expect("the other room is named");
        let other = &apart.left_out[0];
        assert!(other.area_m2 > 4.0, "{other:?}");
        // The kept room is one side of the wall; the named one the other.
        let xs: Vec<f32> = apart.voxel_centres().iter().map(|p| p[0]).collect();
        // (The slot's voxels go to the room nearer them.)
        let kept_left = xs.iter().all(|&x| x < 3.2);
        assert!(
            kept_left || xs.iter().all(|&x| x > 3.1),
            "{:?}",
            xs.iter()
                .fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)))
        );
        let beyond = if kept_left {
            other.min[0] >= 3.0
        } else {
            other.max[0] <= 3.3
        };
        assert!(beyond, "{other:?}");
        assert!(
            warning.contains("left out") && warning.contains("narrower than the body"),
            "{warning}"
        );
        // A body turned sideways passes the 0.2 m slot joint by joint (its bones clear the
        // wall), but not its chest: the slot parts the rooms. 0.35 m joins them, as a doorway.
        let slot_at = |p: &Point3m| (3.05..3.25).contains(&p[0]) && (p[1] - 1.5).abs() < 0.1;
        let in_slot = |r: &AccessibleRegion| r.voxel_centres().iter().any(slot_at);
        assert!(
            apart.samples.iter().any(slot_at),
            "torsos standing in the 0.2 m slot are kept"
        );
        for slot in [0.35, 1.0] {
            let joined = two_rooms(slot);
            assert!(
                joined.left_out_warning().is_none(),
                "{slot}: {:?}",
                joined.left_out
            );
            assert!(in_slot(&joined), "{slot}: a way through the slot");
        }
    }

    #[test]
    fn a_spacing_too_fine_for_the_scene_is_refused_with_one_that_fits() {
        let mut scene = Scene::new();
        slab(
            &mut scene,
            "floor",
            [500.0, 500.0, 0.1],
            [250.0, 250.0, -0.05],
            0.0,
        );
        let e = standing_torsos(&scene, 0.1).unwrap_err().to_string();
        assert!(e.contains("spacing of 0.14 m"), "{e}");
        assert!(standing_torsos(&scene, f32::NAN).is_err());
    }
}
