//! A seeded generator of furnished rooms: floor, walls with open doors, and furniture that
//! people walk around, sit or lie on.

use std::f32::consts::{FRAC_PI_2, PI};

use envfield_grid::SplitMix64;
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::{Result, SceneError};
use crate::floor::{floor_map, FloorMapConfig};
use crate::object::{ObjectKind, Primitive, SceneObject};
use crate::scene::Scene;

/// What [`generate_room`] builds. Sizes are in metres; ranges are `[min, max]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoomConfig {
    /// Interior size along x.
    pub width: [f32; 2],
    /// Interior size along y.
    pub depth: [f32; 2],
    /// Wall height.
    pub wall_height: f32,
    /// Wall thickness.
    pub wall_thickness: f32,
    /// Door openings (1 to 4, one per wall at most).
    pub doors: usize,
    /// Width of a door opening.
    pub door_width: f32,
    /// How many pieces of furniture to try to place.
    pub furniture: [usize; 2],
    /// Free floor kept between pieces, and between free-standing pieces and walls.
    pub clearance: f32,
}

impl Default for RoomConfig {
    fn default() -> Self {
        Self {
            width: [4.0, 7.0],
            depth: [3.5, 6.0],
            wall_height: 2.5,
            wall_thickness: 0.1,
            doors: 1,
            door_width: 0.9,
            furniture: [4, 7],
            clearance: 0.6,
        }
    }
}

impl RoomConfig {
    /// Rooms whose floor map fits 64x64 cells at 0.1 m, walls included (interiors 4-6 m by
    /// 3.5-6 m): the bird's-eye rooms of several people walking at once.
    pub fn birdseye() -> Self {
        Self {
            width: [4.0, 6.0],
            depth: [3.5, 6.0],
            ..Self::default()
        }
    }

    /// Rooms furnished from a catalogue ([`catalogue_room`](crate::catalogue_room)): the
    /// default walls and doors, 6 to 9 pieces (a catalogue holds eight kinds).
    pub fn catalogue() -> Self {
        Self {
            furniture: [6, 9],
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<()> {
        let ok = |r: [f32; 2], min: f32| {
            r[0].is_finite() && r[1].is_finite() && r[0] >= min && r[0] <= r[1]
        };
        let positive = [self.wall_height, self.wall_thickness, self.door_width]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0);
        let valid = ok(self.width, 2.5)
            && ok(self.depth, 2.5)
            && positive
            && self.clearance.is_finite()
            && self.clearance >= 0.3
            && (1..=4).contains(&self.doors)
            && self.furniture[0] <= self.furniture[1]
            && self.door_width <= self.width[0].min(self.depth[0]) - 0.4;
        if !valid {
            return Err(SceneError::InvalidInput(format!(
                "room config: sizes >= 2.5 m with min <= max, positive wall and door sizes, a door \
                 narrower than a wall, clearance >= 0.3 m and 1-4 doors (got {self:?})"
            )));
        }
        Ok(())
    }
}

/// One placed piece of furniture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Furniture {
    /// What it is.
    pub kind: ObjectKind,
    /// Its index in [`Room::scene`]'s objects.
    pub object: usize,
    /// World `(x, y)` of its footprint's centre.
    pub center: [f32; 2],
    /// Rotation about z; the front (where a person sits or stands) faces
    /// `(-sin yaw, cos yaw)`.
    pub yaw: f32,
    /// Width, depth and height in its own frame.
    pub size: [f32; 3],
    /// Height of the surface a person sits or lies on (chairs, sofas, beds).
    pub seat_height: Option<f32>,
    /// How far in front of the footprint's centre the seat's middle lies, in its own frame
    /// (`None`: a tenth of the half-depth for sofas and chairs, whose backs take the rest).
    #[serde(default)]
    pub seat_forward: Option<f32>,
}

impl Furniture {
    /// The world point at the middle of its seat or mattress, if it has one.
    pub fn seat_center(&self) -> Option<Point3<f32>> {
        let h = self.seat_height?;
        // Sofas and chairs have a back: the seat's middle sits a little in front of the centre.
        let forward = match (self.seat_forward, self.kind) {
            (Some(f), _) => f,
            (None, ObjectKind::Sofa | ObjectKind::Chair) => 0.1 * self.size[1] / 2.0,
            _ => 0.0,
        };
        let (s, c) = self.yaw.sin_cos();
        Some(Point3::new(
            self.center[0] - s * forward,
            self.center[1] + c * forward,
            h,
        ))
    }

    /// Its world footprint `[x_min, y_min, x_max, y_max]`.
    pub fn footprint(&self) -> [f32; 4] {
        footprint(self.center, self.yaw, self.size)
    }

    /// Whether the world point `(x, y)` lies over its (turned) footprint.
    pub fn covers(&self, x: f32, y: f32) -> bool {
        // Into its own frame: the footprint centred, width along x, depth along y.
        let (s, c) = self.yaw.sin_cos();
        let (dx, dy) = (x - self.center[0], y - self.center[1]);
        let (lx, ly) = (c * dx + s * dy, -s * dx + c * dy);
        lx.abs() < self.size[0] / 2.0 && ly.abs() < self.size[1] / 2.0
    }
}

pub(crate) fn footprint(center: [f32; 2], yaw: f32, size: [f32; 3]) -> [f32; 4] {
    let quarter = ((yaw / FRAC_PI_2).round() as i64).rem_euclid(2) == 1;
    let (hx, hy) = if quarter {
        (size[1] / 2.0, size[0] / 2.0)
    } else {
        (size[0] / 2.0, size[1] / 2.0)
    };
    [
        center[0] - hx,
        center[1] - hy,
        center[0] + hx,
        center[1] + hy,
    ]
}

/// A generated room.
#[derive(Clone, Debug)]
pub struct Room {
    /// Floor, walls and furniture.
    pub scene: Scene,
    /// Interior size `(x, y)`; the interior spans `[0, size[0]] x [0, size[1]]`, floor at z = 0.
    pub size: [f32; 2],
    /// The furniture placed.
    pub furniture: Vec<Furniture>,
}

/// Generates a furnished room, seeded: a floor (top at z = 0), four walls with `doors` open
/// doorways, and pieces of furniture (beds, sofas, chairs, tables, desks, cabinets) of
/// plausible sizes. Beds, sofas, desks and cabinets stand against a wall facing the room;
/// tables and chairs stand free. Pieces keep `clearance` between each other and the doors, and
/// the generator checks on the bird's-eye map that the free floor stays one connected region,
/// dropping a piece that would break it.
///
/// # Errors
/// [`SceneError::InvalidInput`] for a bad config.
pub fn generate_room(config: &RoomConfig, seed: u64) -> Result<Room> {
    furnish(config, seed, &mut Boxes::default())
}

/// One piece a [`Pieces`] source chose: what it is and how big.
#[derive(Clone, Debug)]
pub(crate) struct Piece {
    pub(crate) kind: ObjectKind,
    pub(crate) size: [f32; 3],
    pub(crate) seat_height: Option<f32>,
    pub(crate) seat_forward: Option<f32>,
    /// The source's own handle (a catalogue item).
    pub(crate) item: usize,
}

/// Where a room's furniture comes from: the generator's boxes or a catalogue's models.
pub(crate) trait Pieces {
    /// How many pieces to try, drawn once per room (after the walls).
    fn count(&mut self, config: &RoomConfig, rng: &mut SplitMix64) -> usize;
    /// The `n`th piece to try.
    fn pick(&mut self, n: usize, rng: &mut SplitMix64) -> Piece;
    /// Its geometry, placed with its footprint centred on `center`, turned by `yaw`.
    fn build(&self, piece: &Piece, n: usize, center: [f32; 2], yaw: f32) -> Result<SceneObject>;
}

/// Shuffles `kinds` (the order pieces are tried in) and draws how many pieces to try.
pub(crate) fn kind_order(
    kinds: &mut [ObjectKind],
    config: &RoomConfig,
    rng: &mut SplitMix64,
) -> usize {
    shuffle(kinds, rng);
    config.furniture[0] + rng.below(config.furniture[1] - config.furniture[0] + 1)
}

/// The `n`th piece's kind: each kind once in the shuffled order, then any at random.
pub(crate) fn kind_at(kinds: &[ObjectKind], n: usize, rng: &mut SplitMix64) -> ObjectKind {
    if n < kinds.len() {
        kinds[n]
    } else {
        kinds[rng.below(kinds.len())]
    }
}

/// Whether a piece of `kind` stands with its back to a wall, facing the room.
pub(crate) fn against_wall(kind: ObjectKind) -> bool {
    !matches!(kind, ObjectKind::Chair | ObjectKind::Table)
}

/// The generator's own pieces: boxes, cylinders and capsules of plausible sizes.
#[derive(Default)]
struct Boxes {
    kinds: Vec<ObjectKind>,
}

impl Pieces for Boxes {
    fn count(&mut self, config: &RoomConfig, rng: &mut SplitMix64) -> usize {
        self.kinds = vec![
            ObjectKind::Bed,
            ObjectKind::Sofa,
            ObjectKind::Chair,
            ObjectKind::Table,
            ObjectKind::Desk,
            ObjectKind::Cabinet,
        ];
        kind_order(&mut self.kinds, config, rng)
    }

    fn pick(&mut self, n: usize, rng: &mut SplitMix64) -> Piece {
        let kind = kind_at(&self.kinds, n, rng);
        Piece {
            kind,
            size: furniture_size(kind, rng),
            seat_height: seat_height(kind),
            seat_forward: None,
            item: 0,
        }
    }

    fn build(&self, piece: &Piece, n: usize, center: [f32; 2], yaw: f32) -> Result<SceneObject> {
        build_furniture(piece.kind, n, center, yaw, piece.size)
    }
}

/// A room of `config`'s size and walls, furnished from `pieces`: see [`generate_room`].
pub(crate) fn furnish(config: &RoomConfig, seed: u64, pieces: &mut dyn Pieces) -> Result<Room> {
    config.validate()?;
    let mut rng = SplitMix64::new(seed);
    let range = |rng: &mut SplitMix64, r: [f32; 2]| r[0] + (r[1] - r[0]) * rng.next_f32();
    let w = range(&mut rng, config.width);
    let d = range(&mut rng, config.depth);
    let t = config.wall_thickness;
    let h = config.wall_height;
    let mut scene = Scene::new();
    scene.add(SceneObject::new("floor", ObjectKind::Floor).with(
        Primitive::cuboid([w + 2.0 * t, d + 2.0 * t, 0.1]),
        at(w / 2.0, d / 2.0, -0.05, 0.0),
    )?)?;

    // Walls: 0 south (y = 0), 1 north, 2 west (x = 0), 3 east; doors pick distinct walls.
    let mut walls: Vec<usize> = vec![0, 1, 2, 3];
    shuffle(&mut walls, &mut rng);
    let door_walls = &walls[..config.doors];
    let mut doors = Vec::new(); // (wall, centre along the wall)
    for wall in 0..4 {
        let length = if wall < 2 { w } else { d };
        let mut wall_object = SceneObject::new(format!("wall {wall}"), ObjectKind::Wall);
        let mut segments = vec![(-t, length + t)];
        if door_walls.contains(&wall) {
            let half = config.door_width / 2.0;
            let c = 0.2 + half + (length - 0.4 - 2.0 * half) * rng.next_f32();
            doors.push((wall, c));
            segments = vec![(-t, c - half), (c + half, length + t)];
        }
        for (a, b) in segments {
            let mid = (a + b) / 2.0;
            let len = b - a;
            let (pose, size) = match wall {
                0 => (at(mid, -t / 2.0, h / 2.0, 0.0), [len, t, h]),
                1 => (at(mid, d + t / 2.0, h / 2.0, 0.0), [len, t, h]),
                2 => (at(-t / 2.0, mid, h / 2.0, 0.0), [t, len, h]),
                _ => (at(w + t / 2.0, mid, h / 2.0, 0.0), [t, len, h]),
            };
            wall_object.push(crate::object::Part::primitive(
                Primitive::cuboid(size),
                pose,
            )?);
        }
        scene.add(wall_object)?;
    }

    // Keep-out zones in front of the doors.
    let mut taken: Vec<[f32; 4]> = doors
        .iter()
        .map(|&(wall, c)| {
            let half = config.door_width / 2.0;
            match wall {
                0 => [c - half, 0.0, c + half, 0.8],
                1 => [c - half, d - 0.8, c + half, d],
                2 => [0.0, c - half, 0.8, c + half],
                _ => [w - 0.8, c - half, w, c + half],
            }
        })
        .collect();

    let count = pieces.count(config, &mut rng);
    let mut furniture = Vec::new();
    let gap = config.clearance;
    for n in 0..count {
        let piece = pieces.pick(n, &mut rng);
        let (kind, size) = (piece.kind, piece.size);
        for _attempt in 0..100 {
            let (center, yaw) = if against_wall(kind) {
                // The back touches the wall, the front faces the room.
                let wall = rng.below(4);
                let along = |rng: &mut SplitMix64, length: f32| {
                    size[0] / 2.0 + (length - size[0]).max(0.0) * rng.next_f32()
                };
                let back = size[1] / 2.0 + 0.01;
                match wall {
                    0 => ([along(&mut rng, w), back], 0.0),
                    1 => ([along(&mut rng, w), d - back], PI),
                    2 => ([back, along(&mut rng, d)], -FRAC_PI_2),
                    _ => ([w - back, along(&mut rng, d)], FRAC_PI_2),
                }
            } else {
                let yaw = rng.below(4) as f32 * FRAC_PI_2;
                let f = footprint([0.0, 0.0], yaw, size);
                let (hx, hy) = (f[2], f[3]);
                let span_x = w - 2.0 * (hx + gap);
                let span_y = d - 2.0 * (hy + gap);
                if span_x <= 0.0 || span_y <= 0.0 {
                    break;
                }
                (
                    [
                        hx + gap + span_x * rng.next_f32(),
                        hy + gap + span_y * rng.next_f32(),
                    ],
                    yaw,
                )
            };
            let f = footprint(center, yaw, size);
            let inside = f[0] >= -1e-3 && f[1] >= -1e-3 && f[2] <= w + 1e-3 && f[3] <= d + 1e-3;
            let clear = taken.iter().all(|o| {
                f[0] >= o[2] + gap || o[0] >= f[2] + gap || f[1] >= o[3] + gap || o[1] >= f[3] + gap
            });
            if !(inside && clear) {
                continue;
            }
            let object = pieces.build(&piece, n, center, yaw)?;
            let mut trial = scene.clone();
            let index = trial.add(object)?;
            if !floor_connected(&trial)? {
                continue;
            }
            scene = trial;
            taken.push(f);
            furniture.push(Furniture {
                kind,
                object: index,
                center,
                yaw,
                size,
                seat_height: piece.seat_height,
                seat_forward: piece.seat_forward,
            });
            break;
        }
    }
    Ok(Room {
        scene,
        size: [w, d],
        furniture,
    })
}

fn floor_connected(scene: &Scene) -> Result<bool> {
    let map = floor_map(
        scene,
        &FloorMapConfig {
            resolution: 0.1,
            ..FloorMapConfig::default()
        },
    )?;
    Ok(map.grid.free_components().count() == 1)
}

pub(crate) fn shuffle<T>(items: &mut [T], rng: &mut SplitMix64) {
    for i in (1..items.len()).rev() {
        items.swap(i, rng.below(i + 1));
    }
}

pub(crate) fn at(x: f32, y: f32, z: f32, yaw: f32) -> Isometry3<f32> {
    Isometry3::new(Vector3::new(x, y, z), Vector3::z() * yaw)
}

/// Width (x), depth (y), height of each kind, drawn from plausible ranges.
fn furniture_size(kind: ObjectKind, rng: &mut SplitMix64) -> [f32; 3] {
    let mut r = |a: f32, b: f32| a + (b - a) * rng.next_f32();
    match kind {
        ObjectKind::Bed => [r(1.4, 1.8), r(1.95, 2.1), 1.0],
        ObjectKind::Sofa => [r(1.8, 2.2), r(0.85, 0.95), 0.85],
        ObjectKind::Chair => [0.46, 0.48, 0.9],
        ObjectKind::Table => [r(0.9, 1.6), r(0.8, 1.0), 0.75],
        ObjectKind::Desk => [r(1.2, 1.4), r(0.6, 0.7), 0.75],
        _ => [r(0.8, 1.2), r(0.4, 0.5), r(0.9, 2.0)],
    }
}

fn seat_height(kind: ObjectKind) -> Option<f32> {
    match kind {
        ObjectKind::Bed => Some(0.5),
        ObjectKind::Sofa | ObjectKind::Chair => Some(0.45),
        _ => None,
    }
}

/// Builds the parts of a piece in its own frame (front towards +y), then places it.
fn build_furniture(
    kind: ObjectKind,
    n: usize,
    center: [f32; 2],
    yaw: f32,
    size: [f32; 3],
) -> Result<SceneObject> {
    let [sw, sd, sh] = size;
    let name = format!("{kind:?} {n}").to_lowercase();
    let place = at(center[0], center[1], 0.0, yaw);
    let local = |x: f32, y: f32, z: f32| place * at(x, y, z, 0.0);
    let mut o = SceneObject::new(name, kind);
    let cuboid = |o: SceneObject, s: [f32; 3], x: f32, y: f32, z: f32| {
        o.with(Primitive::cuboid(s), local(x, y, z))
    };
    let legs = |mut o: SceneObject, inset: f32, radius: f32, height: f32| -> Result<SceneObject> {
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
            o = o.with(
                Primitive::Cylinder {
                    half_height: height / 2.0,
                    radius,
                },
                local(
                    sx * (sw / 2.0 - inset),
                    sy * (sd / 2.0 - inset),
                    height / 2.0,
                ),
            )?;
        }
        Ok(o)
    };
    match kind {
        ObjectKind::Bed => {
            o = cuboid(o, [sw, sd, 0.5], 0.0, 0.0, 0.25)?;
            o = cuboid(o, [sw, 0.08, sh], 0.0, -sd / 2.0 + 0.04, sh / 2.0)?;
        }
        ObjectKind::Sofa => {
            o = cuboid(o, [sw, sd, 0.45], 0.0, 0.0, 0.225)?;
            o = cuboid(o, [sw, 0.2, sh], 0.0, -sd / 2.0 + 0.1, sh / 2.0)?;
            // Round armrests: capsules along the depth.
            let arm = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), FRAC_PI_2);
            for side in [-1.0, 1.0] {
                let pose = local(side * (sw / 2.0 - 0.1), 0.05, 0.55)
                    * Isometry3::from_parts(nalgebra::Translation3::identity(), arm);
                o = o.with(
                    Primitive::Capsule {
                        half_height: sd / 2.0 - 0.15,
                        radius: 0.1,
                    },
                    pose,
                )?;
            }
        }
        ObjectKind::Chair => {
            o = legs(o, 0.03, 0.02, 0.42)?;
            o = cuboid(o, [sw, sd, 0.03], 0.0, 0.0, 0.435)?;
            o = cuboid(
                o,
                [sw, 0.04, sh - 0.45],
                0.0,
                -sd / 2.0 + 0.02,
                (sh + 0.45) / 2.0,
            )?;
        }
        ObjectKind::Table => {
            o = legs(o, 0.06, 0.03, sh - 0.04)?;
            o = cuboid(o, [sw, sd, 0.04], 0.0, 0.0, sh - 0.02)?;
        }
        ObjectKind::Desk => {
            for side in [-1.0, 1.0] {
                o = cuboid(
                    o,
                    [0.04, sd, sh - 0.03],
                    side * (sw / 2.0 - 0.02),
                    0.0,
                    (sh - 0.03) / 2.0,
                )?;
            }
            o = cuboid(o, [sw, sd, 0.03], 0.0, 0.0, sh - 0.015)?;
        }
        _ => {
            o = cuboid(o, size, 0.0, 0.0, sh / 2.0)?;
        }
    }
    Ok(o)
}
