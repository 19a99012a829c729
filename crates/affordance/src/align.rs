//! Aligning a pose sequence to a trajectory (appendix A.2).

use envfield_scene::Scene;
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::check::{check_pose, AffordanceConfig, AffordanceReport};
use crate::error::{AffordanceError, Result};
use crate::skeleton::{Pose, PoseSequence};

/// How [`align_in_scene`] places poses.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AlignConfig {
    /// Also try rotations within +-this many degrees of the tangent-aligned one and keep the
    /// pose with the most supported, collision-free joints (the paper uses 6 for getting up;
    /// 0 turns the search off).
    pub search_degrees: f32,
    /// Spacing of the tried rotations, degrees.
    pub search_step_degrees: f32,
    /// Use only the trajectory's x and y; each frame keeps its own torso height (a path planned
    /// on a floor map).
    pub keep_height: bool,
    /// The checks the search scores with.
    pub affordance: AffordanceConfig,
}

impl Default for AlignConfig {
    fn default() -> Self {
        Self {
            search_degrees: 0.0,
            search_step_degrees: 1.0,
            keep_height: false,
            affordance: AffordanceConfig::default(),
        }
    }
}

fn heading(v: &Vector3<f32>) -> Option<f32> {
    (v.x.hypot(v.y) > 1e-6).then(|| v.y.atan2(v.x))
}

/// The yaw that turns frame `k`'s own torso motion (or facing, when it stands still) onto the
/// trajectory's tangent at `i`.
fn yaw_at(
    sequence: &PoseSequence,
    k: usize,
    trajectory: &[Point3<f32>],
    i: usize,
    last: f32,
) -> f32 {
    let tangent = if i + 1 < trajectory.len() {
        trajectory[i + 1] - trajectory[i]
    } else {
        trajectory[i] - trajectory[i.saturating_sub(1)]
    };
    let Some(want) = heading(&tangent) else {
        return last;
    };
    let frames = &sequence.frames;
    let own = if k + 1 < frames.len() {
        frames[k + 1].torso() - frames[k].torso()
    } else if k > 0 {
        frames[k].torso() - frames[k - 1].torso()
    } else {
        Vector3::zeros()
    };
    let have = heading(&own)
        .filter(|_| own.norm() > 1e-4)
        .or_else(|| heading(&frames[k].facing()))
        .unwrap_or(0.0);
    want - have
}

fn place(pose: &Pose, yaw: f32, target: &Point3<f32>, keep_height: bool) -> Pose {
    let torso = pose.torso();
    let mut offset = target - torso;
    if keep_height {
        offset.z = 0.0;
    }
    pose.rotated_about_z(yaw, &torso).translated(&offset)
}

fn check_trajectory(trajectory: &[Point3<f32>]) -> Result<()> {
    if trajectory.is_empty() {
        return Err(AffordanceError::InvalidInput(
            "the trajectory is empty".into(),
        ));
    }
    match trajectory
        .iter()
        .position(|p| !p.iter().all(|v| v.is_finite()))
    {
        None => Ok(()),
        Some(i) => Err(AffordanceError::InvalidInput(format!(
            "trajectory point {i} is not finite"
        ))),
    }
}

/// Places frame `i % frames` of `sequence` at trajectory point `i` (the torso goes there),
/// rotated about the vertical so that the frame's torso displacement follows the trajectory's
/// tangent. The sequence repeats when the trajectory is longer, as a gait cycle does. The
/// result has one frame per trajectory point.
///
/// # Errors
/// [`AffordanceError::InvalidInput`] for an empty or non-finite trajectory.
pub fn align_to_trajectory(
    sequence: &PoseSequence,
    trajectory: &[Point3<f32>],
    keep_height: bool,
) -> Result<PoseSequence> {
    check_trajectory(trajectory)?;
    let n = sequence.frames.len();
    let mut last = 0.0;
    let mut frames = Vec::with_capacity(trajectory.len());
    let mut supports = Vec::with_capacity(trajectory.len());
    for (i, target) in trajectory.iter().enumerate() {
        let k = i % n;
        last = yaw_at(sequence, k, trajectory, i, last);
        frames.push(place(&sequence.frames[k], last, target, keep_height));
        supports.push(sequence.supports[k]);
    }
    PoseSequence::new(sequence.fps, sequence.activity, frames, supports)
}

/// A walk along a floor path: `path` resampled every `step` metres ([`resample_path`]), then
/// `gait` placed along it with its own heights kept and each frame turned for the best fit in
/// `scene` ([`align_in_scene`] with [`AlignConfig::keep_height`]). Returns the placed
/// sequence and each frame's check.
///
/// # Errors
/// As [`resample_path`] and [`align_in_scene`].
pub fn walk_along(
    scene: &Scene,
    gait: &PoseSequence,
    path: &[Point3<f32>],
    step: f32,
) -> Result<(PoseSequence, Vec<AffordanceReport>)> {
    let trajectory = resample_path(path, step)?;
    let config = AlignConfig {
        keep_height: true,
        ..AlignConfig::default()
    };
    align_in_scene(scene, gait, &trajectory, &config)
}

/// [`align_to_trajectory`], then for each frame the rotation within
/// `+-config.search_degrees` of the aligned one that gives the most supported, collision-free
/// joints in `scene` (ties: the smallest change). Returns the placed sequence and each
/// frame's check. Cost: (2 * search / step + 1) x 22 signed-distance queries per frame.
///
/// # Errors
/// As [`align_to_trajectory`] and [`check_pose`]; a negative search or non-positive step.
pub fn align_in_scene(
    scene: &Scene,
    sequence: &PoseSequence,
    trajectory: &[Point3<f32>],
    config: &AlignConfig,
) -> Result<(PoseSequence, Vec<AffordanceReport>)> {
    let (search, step) = (config.search_degrees, config.search_step_degrees);
    if !(search.is_finite() && search >= 0.0 && step.is_finite() && step > 0.0) {
        return Err(AffordanceError::InvalidInput(format!(
            "alignment search: degrees >= 0 and step > 0, got {search} and {step}"
        )));
    }
    let mut aligned = align_to_trajectory(sequence, trajectory, config.keep_height)?;
    let tries = (search / step).floor() as i32;
    let mut reports = Vec::with_capacity(aligned.frames.len());
    for (pose, support) in aligned.frames.iter_mut().zip(&aligned.supports) {
        let torso = pose.torso();
        let mut best = (
            *pose,
            check_pose(scene, pose, *support, &config.affordance)?,
        );
        for t in 1..=tries {
            for sign in [-1.0f32, 1.0] {
                let candidate = pose.rotated_about_z(sign * (t as f32 * step).to_radians(), &torso);
                let r = check_pose(scene, &candidate, *support, &config.affordance)?;
                if r.good_joints() > best.1.good_joints() {
                    best = (candidate, r);
                }
            }
        }
        *pose = best.0;
        reports.push(best.1);
    }
    Ok((aligned, reports))
}
/// Points along the polyline `path` every `step` metres of arc length, starting at its first
/// point (the last point is kept only when it falls on a step): the positions of a gait that
/// covers `step` per frame, ready for [`align_in_scene`]. O(points + steps).
///
/// ```
/// use envfield_affordance::resample_path;
/// use nalgebra::Point3;
/// let path = [Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0), Point3::new(1.0, 1.0, 0.0)];
/// let points = resample_path(&path, 0.5)?;
/// assert_eq!(points.len(), 5);
/// assert!((points[3] - Point3::new(1.0, 0.5, 0.0)).norm() < 1e-6);
/// # Ok::<(), envfield_affordance::AffordanceError>(())
/// ```
///
/// # Errors
/// [`AffordanceError::InvalidInput`] for a step that is not positive and finite, or a path that
/// is empty or holds a point that is not finite.
pub fn resample_path(path: &[Point3<f32>], step: f32) -> Result<Vec<Point3<f32>>> {
    if !(step.is_finite() && step > 0.0) {
        return Err(AffordanceError::InvalidInput(format!(
            "resampling step must be positive and finite (got {step})"
        )));
    }
    let Some(&first) = path.first() else {
        return Err(AffordanceError::InvalidInput(
            "cannot resample an empty path".into(),
        ));
    };
    if let Some(i) = path.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(AffordanceError::InvalidInput(format!(
            "path point {i} is not finite"
        )));
    }
    let mut out = vec![first];
    // The arc length walked past the last emitted point, carried from one segment to the next.
    let mut carried = 0.0;
    for w in path.windows(2) {
        let d = nalgebra::distance(&w[0], &w[1]);
        let mut s = step - carried;
        while s <= d {
            out.push(w[0] + (w[1] - w[0]) * (s / d));
            s += step;
        }
        carried = d - (s - step);
    }
    Ok(out)
}
