//! Training data made here: torso locations of people walking, sitting and lying in generated
//! rooms, and every place a standing pose is supported and collision-free (the paper's
//! augmentation, appendix "Network Training").

use crate::{Result, RoomsError};
use envfield_affordance::{
    afford_all, check_pose, check_sequence, lie_on, plausible, sit_on, standing_pose, walk,
    walk_along, AffordanceConfig, FilterConfig, Pose, PoseSequence, Support, WalkConfig,
};
use envfield_eikonal::FastMarching;
use envfield_grid::Point3m;
use envfield_grid::{MoveRule, SplitMix64};
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::{
    floor_map, generate_room, sample_surface, FloorMapConfig, Furniture, ObjectKind, Room,
    RoomConfig, Scene,
};
use envfield_vae::{PoseKind, RoomTorsos, TorsoSource};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// How [`room_torsos`] gathers a room's torso locations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TorsoDataConfig {
    /// Walks between random floor points per room.
    pub walks: usize,
    /// Spacing of the floor grid on which standing poses are tried (the augmentation), metres.
    pub floor_spacing: f32,
    /// Surface points sampled per room for its cloud.
    pub cloud_points: usize,
    /// Body radius kept from obstacles when planning the walks, metres.
    pub body_radius: f32,
    /// Resolution of the floor map the walks are planned on, metres.
    pub floor_resolution: f32,
    /// Keep only the torso locations where the accessible region's filter
    /// ([`afford`](envfield_affordance::afford) with the default [`FilterConfig`]) finds a
    /// full pose: the frames in the middle of sitting or lying down, valid as frames of their
    /// sequence, afford no standing, sitting or lying pose of their own, and a VAE trained on
    /// them draws torsos the filter then finds wanting.
    #[serde(default)]
    pub affordable_only: bool,
    /// Extend the augmentation to seats: every place on a grid of `floor_spacing` over each
    /// chair, sofa and bed, at heights 0 to 0.25 m above its seat in steps of 2.5 cm, where
    /// the region's filter finds a sitting or lying pose. The sitting-down sequences give a
    /// seat one torso location; the grid gives it the whole set a person can sit or lie at.
    #[serde(default)]
    pub seat_grid: bool,
}

impl Default for TorsoDataConfig {
    fn default() -> Self {
        Self {
            walks: 4,
            floor_spacing: 0.2,
            cloud_points: 2048,
            body_radius: 0.25,
            floor_resolution: 0.05,
            affordable_only: false,
            seat_grid: false,
        }
    }
}

/// The torso locations of a sequence's valid frames.
fn valid_torsos(scene: &Scene, seq: &PoseSequence) -> Result<Vec<Point3m>> {
    let reports = check_sequence(scene, seq, &AffordanceConfig::default())?;
    Ok(seq
        .frames
        .iter()
        .zip(reports)
        .filter(|(_, r)| r.valid())
        .map(|(f, _)| {
            let t = f.torso();
            Point3m::from(t)
        })
        .collect())
}

/// The standing pose with its torso at `(x, y)` over the floor, facing +x.
fn standing_at(x: f32, y: f32) -> Pose {
    let p = standing_pose();
    let t = p.torso();
    p.translated(&Vector3::new(x - t.x, y - t.y, 0.0))
}

/// The region's filter, each torso judged where it is (no settling): training data keeps
/// the torsos it judged.
fn judged_in_place() -> FilterConfig {
    FilterConfig::default().in_place()
}

/// The torso locations of every standing pose on a floor grid of `spacing` metres over
/// `bounds` (`[x_min, y_min, x_max, y_max]`, the floor at z = 0) that is supported,
/// collision-free and [`plausible`] (no bone through geometry: the floor
/// under a table, where the top would pass between the knees and the hips, is not standing
/// floor): the standing-affordable floor.
///
/// # Errors
/// [`RoomsError::InvalidConfig`] for a spacing under 1 cm or bounds that are not finite or hold
/// more than 4 million grid points.
pub fn standing_floor(scene: &Scene, bounds: [f32; 4], spacing: f32) -> Result<Vec<Point3m>> {
    if !(spacing.is_finite() && spacing > 0.01 && bounds.iter().all(|b| b.is_finite())) {
        return Err(RoomsError::InvalidConfig(format!(
            "floor grid: spacing above 0.01 m and finite bounds (got {spacing} and {bounds:?})"
        )));
    }
    let count = |lo: f32, hi: f32| ((hi - lo).max(0.0) / spacing) as usize;
    let (nx, ny) = (count(bounds[0], bounds[2]), count(bounds[1], bounds[3]));
    if nx.saturating_mul(ny) > 4_000_000 {
        return Err(RoomsError::InvalidConfig(format!(
            "floor grid: {nx} x {ny} points at {spacing} m is more than 4 million"
        )));
    }
    let cells: Vec<(usize, usize)> = (0..nx).flat_map(|i| (0..ny).map(move |j| (i, j))).collect();
    let found: Vec<Option<Point3m>> = cells
        .par_iter()
        .map(|&(i, j)| -> Result<Option<Point3m>> {
            let pose = standing_at(
                bounds[0] + (i as f32 + 0.5) * spacing,
                bounds[1] + (j as f32 + 0.5) * spacing,
            );
            let r = check_pose(
                scene,
                &pose,
                Support::Standing,
                &AffordanceConfig::default(),
            )?;
            let t = pose.torso();
            let fits = r.valid()
                && plausible(
                    scene,
                    &pose,
                    Support::Standing,
                    &AffordanceConfig::default(),
                )?;
            Ok(fits.then_some(Point3m::from(t)))
        })
        .collect::<Result<_>>()?;
    Ok(found.into_iter().flatten().collect())
}

/// Walks between random floor points along the exact floor path (fast marching on the
/// bird's-eye map, inflated by the body radius), each with a seeded gait: the torsos of the
/// valid frames.
fn walks(room: &Room, cfg: &TorsoDataConfig, seed: u64) -> Result<Vec<Point3m>> {
    let map = floor_map(
        &room.scene,
        &FloorMapConfig {
            resolution: cfg.floor_resolution,
            ..FloorMapConfig::default()
        },
    )?;
    let walkable = map.inflated(cfg.body_radius)?;
    let envfield_grid::Components { labels, sizes } = walkable.free_components();
    let Some(largest) = (0..sizes.len()).max_by_key(|&k| sizes[k]) else {
        return Ok(Vec::new());
    };
    let cells: Vec<usize> = (0..labels.len())
        .filter(|&i| labels[i] == largest)
        .collect();
    let mut rng = SplitMix64::new(seed ^ 0x3A1C);
    let mut out = Vec::new();
    let fmm = FastMarching::default();
    for w in 0..cfg.walks {
        let start = walkable.cell(cells[rng.below(cells.len())]);
        let goal = walkable.cell(cells[rng.below(cells.len())]);
        if start == goal {
            continue;
        }
        let field = fmm.solve2(&walkable, &[goal])?;
        let plan = descend_cells(&walkable, &field, start, goal);
        if plan.len() < 2 {
            continue;
        }
        let points: Vec<Point3<f32>> = plan
            .iter()
            .map(|&c| {
                let [x, y] = map.frame.center(c);
                Point3::new(x, y, 0.0)
            })
            .collect();
        let gait = walk(&WalkConfig::default(), seed.wrapping_add(w as u64))?;
        let step = gait.step_length().max(0.01);
        let (aligned, reports) = walk_along(&room.scene, &gait, &points, step)?;
        out.extend(
            aligned
                .frames
                .iter()
                .zip(&reports)
                .filter(|(_, r)| r.valid())
                .map(|(f, _)| {
                    let t = f.torso();
                    Point3m::from(t)
                }),
        );
    }
    Ok(out)
}

/// Descent on an exact floor field (8 moves, strict rule), as the cells it visits.
fn descend_cells(
    grid: &envfield_grid::Grid2,
    field: &envfield_grid::Field2,
    start: envfield_grid::Cell2,
    goal: envfield_grid::Cell2,
) -> Vec<envfield_grid::Cell2> {
    let mut path = vec![start];
    let mut here = start;
    for _ in 0..grid.len() {
        if here == goal {
            return path;
        }
        match envfield_grid::descent_move(grid, field, MoveRule::Strict, here) {
            Some(next) if field.get(next) < field.get(here) => {
                path.push(next);
                here = next;
            }
            _ => return Vec::new(),
        }
    }
    Vec::new()
}

/// One room's torso locations: walks along exact floor paths, sitting down on every seat,
/// lying down on every bed and sofa, and every supported standing pose on the floor grid.
/// Only frames that are supported and collision-free are kept. Seeded.
///
/// # Errors
/// Errors of the room's checks (they do not happen on generated rooms).
pub fn room_torsos(room: &Room, cfg: &TorsoDataConfig, seed: u64) -> Result<RoomTorsos> {
    let scene = &room.scene;
    let mut torsos = Vec::new();
    let mut sources = Vec::new();
    let mut push = |ts: Vec<Point3m>, s: TorsoSource| {
        sources.extend(std::iter::repeat_n(s, ts.len()));
        torsos.extend(ts);
    };
    push(walks(room, cfg, seed)?, TorsoSource::Walk);
    for f in &room.furniture {
        if let Some(seq) = sit_on(f)? {
            push(valid_torsos(scene, &seq)?, TorsoSource::Sit);
        }
        if let Some(seq) = lie_on(f)? {
            push(valid_torsos(scene, &seq)?, TorsoSource::Lie);
        }
    }
    let bounds = [0.0, 0.0, room.size[0], room.size[1]];
    push(
        standing_floor(scene, bounds, cfg.floor_spacing)?,
        TorsoSource::Stand,
    );
    let mut kinds: Vec<Option<PoseKind>> = afford_all(scene, &torsos, &judged_in_place())?
        .iter()
        .map(|a| a.valid.filter(|_| a.kept()).map(pose_kind))
        .collect();
    if cfg.affordable_only {
        let mut keep = kinds.iter().map(Option::is_some);
        torsos.retain(|_| keep.next().unwrap_or(false));
        let mut keep = kinds.iter().map(Option::is_some);
        sources.retain(|_| keep.next().unwrap_or(false));
        kinds.retain(Option::is_some);
    }
    // The seat grid's places come with the kind the filter found there: no second pass.
    if cfg.seat_grid {
        for (t, kind) in seat_grid(room, cfg.floor_spacing)? {
            torsos.push(t);
            sources.push(match kind {
                Support::Lying => TorsoSource::Lie,
                _ => TorsoSource::Sit,
            });
            kinds.push(Some(pose_kind(kind)));
        }
    }
    let cloud = sample_surface(scene, cfg.cloud_points, seed ^ 0xC10D)?
        .iter()
        .map(|p| Point3m::from(*p))
        .collect();
    Ok(RoomTorsos {
        cloud,
        torsos,
        sources,
        kinds,
    })
}

/// The torso locations on a grid of `spacing` over each chair, sofa and bed (its rotated
/// footprint's bounding box), at heights 0 to 0.25 m above its seat in steps of 2.5 cm,
/// where the region's filter ([`afford`](envfield_affordance::afford), default
/// [`FilterConfig`]) finds a sitting or lying pose, with that kind.
///
/// # Errors
/// [`RoomsError::InvalidConfig`] for a spacing under 1 cm; errors of the filter.
pub fn seat_grid(room: &Room, spacing: f32) -> Result<Vec<(Point3m, Support)>> {
    if !(spacing.is_finite() && spacing > 0.01) {
        return Err(RoomsError::InvalidConfig(format!(
            "seat grid: spacing above 0.01 m (got {spacing})"
        )));
    }
    let mut tries = Vec::new();
    for f in &room.furniture {
        tries.extend(seat_tries(f, spacing));
    }
    let affords = afford_all(&room.scene, &tries, &judged_in_place())?;
    Ok(tries
        .into_iter()
        .zip(affords)
        .filter_map(|(t, a)| match a.valid.filter(|_| a.kept()) {
            Some(k @ (Support::Sitting | Support::Lying)) => Some((t, k)),
            _ => None,
        })
        .collect())
}

/// The torso locations [`seat_grid`] tries over one piece of furniture (none for a piece
/// that is not a chair, sofa or bed with a seat height).
fn seat_tries(f: &Furniture, spacing: f32) -> Vec<Point3m> {
    let Some(h) = f.seat_height else {
        return Vec::new();
    };
    if !matches!(
        f.kind,
        ObjectKind::Chair | ObjectKind::Sofa | ObjectKind::Bed
    ) {
        return Vec::new();
    }
    let (sin, cos) = f.yaw.sin_cos();
    let half = [
        0.5 * (f.size[0] * cos.abs() + f.size[1] * sin.abs()),
        0.5 * (f.size[0] * sin.abs() + f.size[1] * cos.abs()),
    ];
    let steps = |h: f32| (2.0 * h / spacing).ceil() as usize;
    let mut tries = Vec::new();
    for i in 0..=steps(half[0]) {
        for j in 0..=steps(half[1]) {
            let x = f.center[0] - half[0] + i as f32 * spacing;
            let y = f.center[1] - half[1] + j as f32 * spacing;
            tries.extend((0..=10).map(|k| [x, y, h + 0.025 * k as f32]));
        }
    }
    tries
}

/// Every place a body sits or lies on each seat of `room` ([`seat_grid`]'s places, piece by
/// piece, over the piece's own footprint): a seat is judged by all of them, not by one point
/// whose place on the model a scan found.
///
/// # Errors
/// As [`seat_grid`].
pub fn seat_places(room: &Room, spacing: f32) -> Result<Vec<(usize, Vec<Point3m>)>> {
    if !(spacing.is_finite() && spacing > 0.01) {
        return Err(RoomsError::InvalidConfig(format!(
            "seat places: spacing above 0.01 m (got {spacing})"
        )));
    }
    let mut out = Vec::new();
    for (k, f) in room.furniture.iter().enumerate() {
        let tries = seat_tries(f, spacing);
        if tries.is_empty() {
            continue;
        }
        let affords = afford_all(&room.scene, &tries, &judged_in_place())?;
        let places = tries
            .into_iter()
            .zip(affords)
            .filter(|(t, a)| {
                a.kept()
                    && matches!(a.valid, Some(Support::Sitting | Support::Lying))
                    && f.covers(t[0], t[1])
            })
            .map(|(t, _)| t)
            .collect();
        out.push((k, places));
    }
    Ok(out)
}

/// The rooms of seeds `seeds` (generated with the default [`RoomConfig`]) and their torso
/// locations, in parallel.
///
/// # Errors
/// As [`room_torsos`] and [`generate_room`].
pub fn rooms_torsos(
    seeds: std::ops::Range<u64>,
    cfg: &TorsoDataConfig,
) -> Result<Vec<(Room, RoomTorsos)>> {
    seeds
        .collect::<Vec<_>>()
        .par_iter()
        .map(|&s| {
            let room = generate_room(&RoomConfig::default(), s)?;
            let data = room_torsos(&room, cfg, s)?;
            Ok((room, data))
        })
        .collect()
}

/// Which of a room's furniture someone can sit on, with the torso location of the sitting
/// pose at its seat (the last frame of [`sit_on`]), whether that pose is valid or not.
///
/// # Errors
/// As [`sit_on`].
pub fn seat_torsos(room: &Room) -> Result<Vec<Point3m>> {
    let mut out = Vec::new();
    for f in &room.furniture {
        if matches!(
            f.kind,
            ObjectKind::Chair | ObjectKind::Sofa | ObjectKind::Bed
        ) {
            if let Some(seq) = sit_on(f)? {
                let t = seq.frames.last().expect("a sequence has frames").torso();
                out.push(Point3m::from(t));
            }
        }
    }
    Ok(out)
}

/// The VAE's pose kind of a support.
pub fn pose_kind(support: Support) -> PoseKind {
    match support {
        Support::Standing => PoseKind::Standing,
        Support::Sitting => PoseKind::Sitting,
        Support::Lying => PoseKind::Lying,
    }
}
