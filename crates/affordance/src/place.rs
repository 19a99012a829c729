//! A body placed on a piece of furniture: sitting down onto a seat, lying down on a bed or
//! sofa, from the furniture's own description (its seat height and front).

use crate::{lie_down, sit_down, LieConfig, PoseSequence, Result, SitConfig};
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::{Furniture, ObjectKind};

/// `seq` turned so that its +x faces `front` (about the origin), then moved by `to`.
fn placed(seq: &PoseSequence, front: [f32; 2], to: Vector3<f32>) -> Result<PoseSequence> {
    let angle = front[1].atan2(front[0]);
    let frames = seq
        .frames
        .iter()
        .map(|f| f.rotated_about_z(angle, &Point3::origin()).translated(&to))
        .collect();
    PoseSequence::new(seq.fps, seq.activity, frames, seq.supports.clone())
}

/// The direction a piece of furniture's front faces.
fn front(f: &Furniture) -> [f32; 2] {
    let (s, c) = f.yaw.sin_cos();
    [-s, c]
}

/// Sitting down onto the middle of `seat` (facing its front), when it has a seat between 0.3
/// and 0.75 m (`None` for a piece with no seat, or one outside that range).
///
/// # Errors
/// As [`sit_down`].
pub fn sit_on(seat: &Furniture) -> Result<Option<PoseSequence>> {
    let (Some(h), Some(c)) = (seat.seat_height, seat.seat_center()) else {
        return Ok(None);
    };
    if !(0.3..=0.75).contains(&h) {
        return Ok(None);
    }
    let seq = sit_down(&SitConfig {
        seat_height: h,
        ..SitConfig::default()
    })?;
    Ok(Some(placed(
        &seq,
        front(seat),
        Vector3::new(c.x, c.y, 0.0),
    )?))
}

/// Lying down on `bed`: seated on its front edge, facing out, then on the back towards its
/// head end (`None` unless it is a bed or sofa with a seat of 0.3-0.75 m).
///
/// # Errors
/// As [`lie_down`].
pub fn lie_on(bed: &Furniture) -> Result<Option<PoseSequence>> {
    let (Some(h), Some(c)) = (bed.seat_height, bed.seat_center()) else {
        return Ok(None);
    };
    if !(0.3..=0.75).contains(&h) || !matches!(bed.kind, ObjectKind::Bed | ObjectKind::Sofa) {
        return Ok(None);
    }
    let f = front(bed);
    // From the front edge, a quarter of the depth back in; slide half the depth.
    let edge = bed.size[1] / 2.0 - 0.25;
    let seq = lie_down(&LieConfig {
        seat_height: h,
        slide: (bed.size[1] / 2.0).clamp(0.0, 1.0),
        ..LieConfig::default()
    })?;
    let to = Vector3::new(c.x + f[0] * edge, c.y + f[1] * edge, 0.0);
    Ok(Some(placed(&seq, f, to)?))
}
