//! Pictures of rooms: a top view of the accessible region with paths, a ray-cast view of the
//! room from above one wall with paths and poses, and a top view of a 3D field.

use crate::harness::{RoomPlanner, Run};
use crate::nav::point;
use crate::{AccessibleRegion, Result, RoomsError};
use envfield_affordance::{Joint, Pose};
use envfield_grid::{height_colour, Canvas, Cell3, ContinuousField3, HeatMapStyle, Point3m};
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::{write_polyline_obj, ObjectKind, Scene};
use rayon::prelude::*;
use std::path::Path;

/// Each planner's colour in the pictures.
pub fn planner_colour(planner: RoomPlanner) -> [u8; 3] {
    match planner {
        RoomPlanner::Ours => [220, 30, 30],
        RoomPlanner::OursRaw => [140, 20, 20],
        RoomPlanner::OursNoAff => [250, 150, 30],
        RoomPlanner::OursExact => [30, 160, 60],
        RoomPlanner::Rrt => [40, 90, 220],
        RoomPlanner::RrtStar => [130, 60, 200],
        RoomPlanner::RrtStarBig => [200, 80, 200],
        RoomPlanner::Prm => [20, 170, 190],
        RoomPlanner::Line => [90, 90, 90],
        RoomPlanner::Navmesh => [240, 200, 40],
    }
}

/// A top view, 6 pixels a voxel: accessible columns light, the rest dark, every planner's
/// path in its colour, the first path's start green and goal magenta.
pub fn top_view(region: &AccessibleRegion, paths: &[(RoomPlanner, Vec<Point3m>)]) -> Canvas {
    plan_view(region, 6, paths, Ends::First, |_| [225, 232, 220])
}

/// A top view for a scene of several levels, `scale` pixels a voxel: each accessible column
/// coloured by the height of its highest accessible voxel (dark blue low, yellow high), every
/// path in its planner's colour, each path's start green and goal magenta.
pub fn height_view(
    region: &AccessibleRegion,
    scale: u32,
    paths: &[(RoomPlanner, Vec<Point3m>)],
) -> Canvas {
    // Colours span the region's own heights, not the scene's box.
    let nz = region.frame.shape[2];
    let (lo, hi) = region
        .free_indices()
        .iter()
        .fold((usize::MAX, 0), |(lo, hi), &i| {
            (lo.min(i % nz), hi.max(i % nz))
        });
    let span = hi.saturating_sub(lo).max(1) as f32;
    plan_view(region, scale.max(1), paths, Ends::Every, |z| {
        height_colour(z.saturating_sub(lo) as f32 / span)
    })
}

/// A world point's pixel in a top view of `scale` pixels a voxel.
fn pixel_of(region: &AccessibleRegion, scale: u32) -> impl Fn(Point3m) -> (f32, f32) + '_ {
    let ny = region.frame.shape[1];
    move |p: Point3m| {
        let s = scale as f32;
        let x = (p[0] - region.frame.origin.x) / region.frame.voxel * s;
        let y = (ny as f32 * s) - (p[1] - region.frame.origin.y) / region.frame.voxel * s;
        (x, y)
    }
}

/// Which paths' starts and goals a plan view marks.
#[derive(Clone, Copy, PartialEq)]
enum Ends {
    /// The first path's (every planner's path of one pair).
    First,
    /// Every path's (one planner's paths of many pairs).
    Every,
}

/// The region from above, `s` pixels a voxel, each accessible column in `colour` of its
/// highest accessible voxel's index, every path in its planner's colour, starts green and
/// goals magenta as `ends` says.
fn plan_view(
    region: &AccessibleRegion,
    s: u32,
    paths: &[(RoomPlanner, Vec<Point3m>)],
    ends: Ends,
    colour: impl Fn(usize) -> [u8; 3],
) -> Canvas {
    let [nx, ny, nz] = region.frame.shape;
    let mut img = Canvas::new(nx as u32 * s, ny as u32 * s, [40, 40, 48]);
    for x in 0..nx {
        for y in 0..ny {
            if let Some(z) = (0..nz)
                .rev()
                .find(|&z| region.grid.is_free(Cell3::new(x, y, z)))
            {
                let (px, py) = (x as i64 * s as i64, (ny - 1 - y) as i64 * s as i64);
                img.fill(px, py, s, s, colour(z));
            }
        }
    }
    let to_px = pixel_of(region, s);
    for (planner, pts) in paths {
        let c = planner_colour(*planner);
        for w in pts.windows(2) {
            img.segment(to_px(w[0]), to_px(w[1]), 1, c);
        }
    }
    let (marked, dot) = match ends {
        Ends::First => (paths.len().min(1), 4),
        Ends::Every => (paths.len(), 3),
    };
    for (_, pts) in &paths[..marked] {
        if let (Some(&a), Some(&b)) = (pts.first(), pts.last()) {
            let (a, b) = (to_px(a), to_px(b));
            img.dot(a.0, a.1, dot, [30, 200, 30]);
            img.dot(b.0, b.1, dot, [220, 30, 220]);
        }
    }
    img
}

/// The colour of a surface of `kind` in [`room_view`].
fn surface_colour(kind: ObjectKind) -> [f32; 3] {
    match kind {
        ObjectKind::Floor => [0.78, 0.74, 0.68],
        ObjectKind::Wall => [0.86, 0.86, 0.88],
        ObjectKind::Bed => [0.45, 0.55, 0.75],
        ObjectKind::Sofa => [0.65, 0.40, 0.35],
        ObjectKind::Chair => [0.55, 0.45, 0.30],
        _ => [0.60, 0.52, 0.42],
    }
}

/// The room seen from above and behind its near (low y) wall, 640 x 440 pixels: each pixel
/// one ray cast with the scene's own ray queries, surfaces shaded by a light from above and
/// coloured by what they are; every planner's path and the skeletons of `poses` drawn where
/// the room does not hide them.
///
/// # Errors
/// [`RoomsError::InvalidInput`] for an empty scene.
pub fn room_view(
    scene: &Scene,
    paths: &[(RoomPlanner, Vec<Point3m>)],
    poses: &[Pose],
) -> Result<Canvas> {
    let aabb = scene
        .aabb()
        .ok_or_else(|| RoomsError::InvalidInput("the scene is empty".into()))?;
    let (lo, hi) = (aabb.mins, aabb.maxs);
    let centre = Point3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0 + 0.3, 0.3);
    // Above and behind the near wall, high enough to see over it into the room.
    let eye = Point3::new(centre.x, lo.y - 0.8, hi.z + 3.5);
    let forward = (centre - eye).normalize();
    let right = forward.cross(&Vector3::z()).normalize();
    let up = right.cross(&forward);
    let (w, h) = (640usize, 440usize);
    let focal = 0.75 * w as f32;
    let ray = |px: f32, py: f32| {
        (forward + right * ((px - w as f32 / 2.0) / focal) - up * ((py - h as f32 / 2.0) / focal))
            .normalize()
    };
    let light = Vector3::new(0.3, -0.4, 1.0).normalize();
    let hits: Vec<(f32, [u8; 3])> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let d = ray((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            match scene.cast_ray(&eye, &d, 50.0).ok().flatten() {
                Some(hit) => {
                    let base = surface_colour(scene.objects()[hit.object].kind);
                    let shade = 0.35 + 0.65 * hit.normal.dot(&light).abs();
                    (
                        hit.distance,
                        base.map(|c| (255.0 * c * shade).min(255.0) as u8),
                    )
                }
                None => (f32::INFINITY, [30, 30, 36]),
            }
        })
        .collect();
    let mut img = Canvas::new(w as u32, h as u32, [0, 0, 0]);
    for (i, (_, c)) in hits.iter().enumerate() {
        img.put((i % w) as i64, (i / w) as i64, *c);
    }
    // A point's pixel and depth along its ray, when in front of the camera.
    let project = |p: Point3<f32>| -> Option<(f32, f32, f32)> {
        let v = p - eye;
        let z = v.dot(&forward);
        (z > 0.05).then(|| {
            (
                w as f32 / 2.0 + focal * v.dot(&right) / z,
                h as f32 / 2.0 - focal * v.dot(&up) / z,
                v.norm(),
            )
        })
    };
    // A segment as 41 points, each a 2x2 square where nothing nearer hides it.
    let segment = |img: &mut Canvas, a: Point3<f32>, b: Point3<f32>, c: [u8; 3]| {
        let n = 40;
        for k in 0..=n {
            let p = a + (b - a) * (k as f32 / n as f32);
            let Some((x, y, depth)) = project(p) else {
                continue;
            };
            let (xi, yi) = (x as i64, y as i64);
            if xi < 0 || yi < 0 || xi >= w as i64 || yi >= h as i64 {
                continue;
            }
            if depth <= hits[yi as usize * w + xi as usize].0 + 0.05 {
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (px, py) = ((xi + dx).min(w as i64 - 1), (yi + dy).min(h as i64 - 1));
                    img.put(px, py, c);
                }
            }
        }
    };
    for (planner, pts) in paths {
        let c = planner_colour(*planner);
        for pair in pts.windows(2) {
            segment(&mut img, point(pair[0]), point(pair[1]), c);
        }
    }
    for pose in poses {
        for j in Joint::ALL {
            if let Some(parent) = j.parent() {
                segment(&mut img, pose.joint(j), pose.joint(parent), [20, 20, 20]);
            }
        }
    }
    Ok(img)
}

/// A top view of a 3D field, 6 pixels a voxel, as a heat map: each column's value at its
/// highest accessible voxel.
///
/// # Errors
/// Errors of the field's queries and of the file.
pub fn write_field_view(
    region: &AccessibleRegion,
    field: &dyn ContinuousField3,
    path: impl AsRef<Path>,
) -> Result<()> {
    let values = region.plan_view(|c| Ok(field.value(Point3m::from(region.frame.center(c)))?))?;
    values.write_png(
        path,
        &HeatMapStyle {
            scale: 6,
            ..HeatMapStyle::default()
        },
    )?;
    Ok(())
}

/// One pair's files in `out`: the scene (`scene.obj`), the region (`region.ply`), every
/// planner's path (`path_<planner>.obj`) and aligned poses (`poses_<planner>.json`), the top
/// view of every path (`top.png`) and the ray-cast room with five of the first run's poses
/// (`room.png`).
///
/// # Errors
/// I/O errors naming the file; errors of the ray casts.
pub fn write_run_files(
    out: &Path,
    scene: &Scene,
    region: &AccessibleRegion,
    runs: &[Run],
) -> Result<()> {
    scene.to_mesh().write(out.join("scene.obj"))?;
    region.write_ply(out.join("region.ply"))?;
    for run in runs {
        let line: Vec<Point3<f32>> = run.path.iter().map(|&p| point(p)).collect();
        if line.len() > 1 {
            write_polyline_obj(&line, out.join(format!("path_{}.obj", run.planner)))?;
        }
        run.poses
            .write(out.join(format!("poses_{}.json", run.planner)))?;
    }
    let drawn: Vec<_> = runs.iter().map(|r| (r.planner, r.path.clone())).collect();
    top_view(region, &drawn).write_png(out.join("top.png"))?;
    // A few of the first run's poses, evenly along its path.
    let skeletons: Vec<Pose> = match runs.first() {
        Some(run) if !run.poses.frames.is_empty() => {
            let frames = &run.poses.frames;
            (0..5).map(|j| frames[j * (frames.len() - 1) / 4]).collect()
        }
        _ => Vec::new(),
    };
    room_view(scene, &drawn, &skeletons)?.write_png(out.join("room.png"))?;
    Ok(())
}
