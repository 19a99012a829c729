//! The pictures of a crowd run: one frame per time step, seen from above.

use crate::Result;
use envfield_grid::{tint, Canvas, Cell2, Field2, FieldModel, Grid2, Point2};
use envfield_plan::crowd::{mark_discs, CrowdConfig, CrowdRun, Trip};

/// The people's colours, in turn.
const COLOURS: [[u8; 3]; 8] = [
    [230, 25, 75],
    [60, 180, 75],
    [0, 130, 200],
    [245, 130, 48],
    [145, 30, 180],
    [70, 200, 200],
    [240, 50, 230],
    [150, 120, 30],
];

/// Pixels a map cell.
const SCALE: u32 = 8;

/// Pixel centre of map point `p`.
fn pixel(p: Point2) -> (f32, f32) {
    ((p.col + 0.5) * SCALE as f32, (p.row + 0.5) * SCALE as f32)
}

/// One picture per time step of `run`: the walkable map, each walking person's field
/// contours every half metre of reaching distance within 2 m of them (on the map as they see
/// it, the others marked, predicted by `model` in one batch), trails, bodies and goals,
/// cropped to the room.
///
/// # Errors
/// Errors of the marking and of the model.
pub fn crowd_frames(
    walkable: &Grid2,
    trips: &[Trip],
    run: &CrowdRun,
    model: &dyn FieldModel,
    config: &CrowdConfig,
) -> Result<Vec<Canvas>> {
    let (rows, cols) = (walkable.rows(), walkable.cols());
    let mut frames = Vec::new();
    for t in 0..run.frames.len() {
        let positions = &run.frames[t];
        let walking: Vec<usize> = (0..trips.len())
            .filter(|&i| run.arrived_at[i].is_none_or(|a| t < a))
            .collect();
        let maps: Vec<Grid2> = walking
            .iter()
            .map(|&i| {
                let others = walking.iter().filter(|&&j| j != i).map(|&j| positions[j]);
                mark_discs(walkable, others, 2.0 * config.body_radius)
            })
            .collect::<envfield_plan::Result<_>>()?;
        let asked: Vec<(&Grid2, Cell2)> = walking
            .iter()
            .zip(&maps)
            .filter(|(&i, m)| m.is_free(trips[i].goal))
            .map(|(&i, m)| (m, trips[i].goal))
            .collect();
        let fields: Vec<Field2> = model.predict_many(&asked)?;
        let mut img = Canvas::new(cols as u32 * SCALE, rows as u32 * SCALE, [250, 250, 250]);
        for r in 0..rows {
            for c in (0..cols).filter(|&c| walkable.is_obstacle(Cell2::new(r, c))) {
                let (x, y) = (c as i64 * SCALE as i64, r as i64 * SCALE as i64);
                img.fill(x, y, SCALE, SCALE, [70, 70, 80]);
            }
        }
        let mut k = 0;
        for (&i, m) in walking.iter().zip(&maps) {
            if !m.is_free(trips[i].goal) {
                continue;
            }
            contours(
                &mut img,
                &fields[k],
                positions[i],
                tint(COLOURS[i % 8], 0.7),
            );
            k += 1;
        }
        for (i, trip) in trips.iter().enumerate() {
            let colour = COLOURS[i % 8];
            let g = pixel(Point2::new(trip.goal.row as f32, trip.goal.col as f32));
            img.cross(g.0, g.1, 5, colour);
            for s in 1..=t {
                let (a, b) = (run.frames[s - 1][i], run.frames[s][i]);
                img.line(pixel(a), pixel(b), tint(colour, 0.35));
            }
            if run.arrived_at[i].is_none_or(|a| t <= a) {
                let (x, y) = pixel(positions[i]);
                img.disc(
                    x,
                    y,
                    config.body_radius * SCALE as f32,
                    colour,
                    [20, 20, 20],
                );
            }
        }
        frames.push(room_only(&img, walkable));
    }
    Ok(frames)
}

/// Contours of `field` within 2 m (20 cells) of `at`, every 0.5 m: how it bends round the
/// others. A cell is on one where the field crosses a level against its right or lower
/// neighbour; the cell on the lower level gets the mark.
fn contours(img: &mut Canvas, field: &Field2, at: Point2, colour: [u8; 3]) {
    let (rows, cols) = (field.rows(), field.cols());
    let band = |cell: Cell2| {
        field
            .get(cell)
            .filter(|v| v.is_finite())
            .map(|v| (v / 5.0) as i32)
    };
    for r in 0..rows {
        for c in 0..cols.saturating_sub(1) {
            if Point2::new(r as f32, c as f32).distance(at) > 20.0 {
                continue;
            }
            let (a, b) = (band(Cell2::new(r, c)), band(Cell2::new(r, c + 1)));
            let down = (r + 1 < rows).then(|| band(Cell2::new(r + 1, c))).flatten();
            if a.is_some() && ((b.is_some() && a < b) || (down.is_some() && a < down)) {
                let (x, y) = (
                    c as u32 * SCALE + SCALE / 2 - 1,
                    r as u32 * SCALE + SCALE / 2 - 1,
                );
                img.fill(x as i64, y as i64, 3, 3, colour);
            }
        }
    }
}

/// Only the room: the free cells' bounding box and a cell around it.
fn room_only(img: &Canvas, walkable: &Grid2) -> Canvas {
    let (rows, cols) = (walkable.rows(), walkable.cols());
    let (r0, r1, c0, c1) = walkable
        .free_cells()
        .fold((rows, 0, cols, 0), |(r0, r1, c0, c1), c| {
            (r0.min(c.row), r1.max(c.row), c0.min(c.col), c1.max(c.col))
        });
    let (r0, c0) = (r0.saturating_sub(1) as u32, c0.saturating_sub(1) as u32);
    let (r1, c1) = ((r1 + 2).min(rows) as u32, (c1 + 2).min(cols) as u32);
    img.crop(
        c0 * SCALE,
        r0 * SCALE,
        c1.saturating_sub(c0) * SCALE,
        r1.saturating_sub(r0) * SCALE,
    )
}
