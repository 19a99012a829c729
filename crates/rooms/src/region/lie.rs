//! The lie-downs that carry the region from the edge of a bed or sofa onto its length: a
//! sit-down the region found, then [`lie_down`] on the same surface, the torso tipping back
//! and sliding onto it.

use super::{RegionConfig, SitDown};
use crate::Result;
use envfield_affordance::{check_pose, lie_down, plausible, LieConfig, PoseSequence, Support};
use envfield_grid::Point3m;
use envfield_scene::nalgebra::Vector3;
use envfield_scene::Scene;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// How far a lie-down slides the pelvis back from where it sat, metres, longest first: the
/// first whose every pose holds is taken (a bed's length takes the longest, a sofa's depth a
/// shorter one).
pub const LIE_SLIDES: [f32; 4] = [1.0, 0.8, 0.6, 0.4];

/// The share of a lie-down's duration in which the legs come up onto the bed before the body
/// slides back ([`LieConfig::lift`]): with both together the shanks, still hanging as the
/// knees come over the edge, sweep through the bed's side.
pub const LIE_LIFT: f32 = 0.5;

/// A lie-down the region found ([`AccessibleRegion::lie_downs`](super::AccessibleRegion::lie_downs)):
/// one of its sit-downs, then [`lie_down`] from that seated pose on the same surface, the
/// pelvis sliding `slide` metres back, every pose valid and plausible where it was found.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LieDown {
    /// The sit-down onto the edge it starts from (standing beside the bed or sofa).
    pub sit: SitDown,
    /// How far the pelvis slides back as the body lies down, metres.
    pub slide: f32,
    /// The torso where it ends, lying on the back, metres.
    pub lying: Point3m,
}

impl LieDown {
    /// From seated to lying: [`lie_down`] placed where its sit-down ends.
    ///
    /// # Errors
    /// As [`lie_down`] and [`SitDown::sequence`].
    pub fn lying_down(&self) -> Result<PoseSequence> {
        lying_part(&self.sit, self.slide)
    }

    /// Its poses, placed: the sit-down from standing, then lying down (the seated frame once),
    /// each frame with its support.
    ///
    /// # Errors
    /// As [`LieDown::lying_down`].
    pub fn sequence(&self) -> Result<PoseSequence> {
        let sit = self.sit.sequence()?;
        let lie = self.lying_down()?;
        let mut frames = sit.frames;
        let mut supports = sit.supports;
        frames.extend(lie.frames.into_iter().skip(1));
        supports.extend(lie.supports.into_iter().skip(1));
        Ok(PoseSequence::new(lie.fps, lie.activity, frames, supports)?)
    }
}

/// [`lie_down`] onto `sit`'s seat, sliding `slide` metres, turned and moved as `sit`'s poses are
/// so that its seated first frame is `sit`'s last.
fn lying_part(sit: &SitDown, slide: f32) -> Result<PoseSequence> {
    let seq = lie_down(&LieConfig {
        seat_height: sit.seat_height,
        slide,
        lift: LIE_LIFT,
        ..LieConfig::default()
    })?;
    let first = seq
        .frames
        .first()
        .map(|f| f.torso().coords)
        .unwrap_or_default();
    let to = Vector3::from(sit.seated);
    let frames = seq
        .frames
        .iter()
        .map(|p| {
            p.translated(&-first)
                .rotated_about_z(sit.yaw, &envfield_scene::nalgebra::Point3::origin())
                .translated(&to)
        })
        .collect();
    Ok(PoseSequence::new(
        seq.fps,
        seq.activity,
        frames,
        seq.supports,
    )?)
}

/// The lie-down that follows `sit`: the longest slide of [`LIE_SLIDES`] whose every pose is
/// valid and [`plausible`] (a frame still tipping back may rest its back on the surface, as a
/// lying one does); `None` where none holds (a chair: nothing bears the head).
///
/// # Errors
/// Errors of the scene's queries and of [`lie_down`].
pub(crate) fn lie_down_from(
    scene: &Scene,
    sit: &SitDown,
    config: &RegionConfig,
) -> Result<Option<LieDown>> {
    let affordance = &config.filter.affordance;
    'slides: for slide in LIE_SLIDES {
        let seq = lying_part(sit, slide)?;
        let n = seq.frames.len();
        // Lying first: on a chair or a stool the head rests on nothing and the try ends at once.
        for i in std::iter::once(n - 1).chain(1..n - 1) {
            let (pose, support) = (&seq.frames[i], seq.supports[i]);
            let rests = |s| plausible(scene, pose, s, affordance);
            if !check_pose(scene, pose, support, affordance)?.valid()
                || !(rests(support)? || rests(Support::Lying)?)
            {
                continue 'slides;
            }
        }
        let lying = seq.frames[n - 1].torso().into();
        return Ok(Some(LieDown {
            sit: *sit,
            slide,
            lying,
        }));
    }
    Ok(None)
}

/// The lie-downs from `sit_downs` ([`lie_down_from`] on each, in parallel), in their order.
///
/// # Errors
/// As [`lie_down_from`].
pub(super) fn lie_downs(
    scene: &Scene,
    sit_downs: &[SitDown],
    config: &RegionConfig,
) -> Result<Vec<LieDown>> {
    let found = sit_downs
        .par_iter()
        .map(|s| lie_down_from(scene, s, config))
        .collect::<Result<Vec<_>>>()?;
    Ok(found.into_iter().flatten().collect())
}
