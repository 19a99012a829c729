//! The bird's-eye field's training data: walkable maps of generated rooms, changed the way
//! other people change them, each with a goal and its exact distance field.

use super::{BODY, RESOLUTION, SIDE};
use crate::Result;
use envfield_grid::{Cell2, Grid2, MoveRule, Point2, SplitMix64};
use envfield_mazes::{target_field, Dataset, Sample, TargetKind};
use envfield_plan::crowd::mark_discs;
use envfield_scene::{floor_map, generate_room, FloorMapConfig, RoomConfig};

/// The walkable 64 x 64 map of generated bird's-eye room `seed` for bodies of [`BODY`].
///
/// # Errors
/// Errors of the room and its floor map.
pub fn walkable_map(seed: u64) -> Result<Grid2> {
    let room = generate_room(&RoomConfig::birdseye(), seed)?;
    let map = floor_map(
        &room.scene,
        &FloorMapConfig {
            resolution: RESOLUTION,
            ..FloorMapConfig::default()
        },
    )?;
    Ok(map.walkable(BODY, Some([SIDE, SIDE]))?)
}

/// `grid` changed as other people change it: up to `max_people` discs (two body radii, in
/// centre space) at random free cells and a random fraction below `max_extra` of the free
/// cells turned into obstacles. A grid without a free cell comes back unchanged.
///
/// # Errors
/// Errors of the marking.
pub fn changed_map(
    grid: &Grid2,
    rng: &mut SplitMix64,
    max_people: usize,
    max_extra: f32,
) -> Result<Grid2> {
    let free: Vec<Cell2> = grid.free_cells().collect();
    if free.is_empty() {
        return Ok(grid.clone());
    }
    let people = rng.below(max_people + 1);
    let centres: Vec<Point2> = (0..people)
        .map(|_| {
            let c = free[rng.below(free.len())];
            Point2::new(c.row as f32, c.col as f32)
        })
        .collect();
    let mut out = mark_discs(grid, centres.into_iter(), 2.0 * BODY / RESOLUTION)?;
    let extra = rng.next_f32() * max_extra;
    for &c in &free {
        if rng.next_f32() < extra {
            out.set_obstacle(c, true)?;
        }
    }
    Ok(out)
}

/// A random free cell of `grid` in its largest connected region (4-connected);
/// `None` without a free cell.
pub fn goal_cell(grid: &Grid2, rng: &mut SplitMix64) -> Option<Cell2> {
    let components = grid.free_components();
    let largest = components.largest()?;
    let cells: Vec<usize> = (0..components.labels.len())
        .filter(|&i| components.labels[i] == largest)
        .collect();
    Some(grid.cell(cells[rng.below(cells.len())]))
}

/// The training maps of rooms `rooms`: `goals` changed maps per room (up to 7 people, up to
/// 8% extra obstacles), each with a goal and its exact graph distance (strict moves). Seeded.
///
/// # Errors
/// Errors of the rooms and the fields.
pub fn training_maps(rooms: std::ops::Range<u64>, goals: usize, seed: u64) -> Result<Dataset> {
    let target = TargetKind::Graph(MoveRule::Strict);
    let mut samples = Vec::new();
    for (k, room) in rooms.enumerate() {
        let grid = walkable_map(room)?;
        let mut rng = SplitMix64::new(seed ^ room.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        for _ in 0..goals {
            let map = changed_map(&grid, &mut rng, 7, 0.08)?;
            let Some(goal) = goal_cell(&map, &mut rng) else {
                continue;
            };
            let distance = target_field(&map, goal, target)?.into_values();
            samples.push(Sample {
                maze: k,
                grid: map,
                goal,
                distance,
            });
        }
    }
    Ok(Dataset { samples })
}
