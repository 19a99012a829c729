//! Apartments: 2 to 4 rooms joined by doors, each furnished for what it is from a
//! [`Catalogue`].
//!
//! [`apartment`] lays a rectangle out as rooms by cutting the largest room in two, again and
//! again, with an interior wall along each cut; a door of 0.8-0.9 m joins the rooms along a
//! tree over their shared walls, so every room is reached. The largest room is the living
//! room; the others are a bedroom, a kitchen and a study. Each room is furnished by its own
//! rules: a bed with its head to a wall between two bedside tables, and a wardrobe; a sofa, an
//! armchair, a coffee table in front of the sofa, a TV unit, shelves and a plant; a dining
//! table with chairs around it, their seats 5-15 cm under its top, and cabinets along the
//! walls; a desk with a chair pushed under it and bookcases. Pieces keep clear of the doorways and of each
//! other (but for a piece and what belongs to it), and the free floor of the whole apartment
//! stays one connected piece for a body.

use std::f32::consts::{FRAC_PI_2, PI};

use envfield_grid::SplitMix64;
use serde::{Deserialize, Serialize};

use crate::catalogue::{Catalogue, Role};
use crate::error::{Result, SceneError};
use crate::object::{ObjectKind, Part, Primitive, SceneObject};
use crate::room::{at, footprint, shuffle, Furniture, Room};
use crate::scene::Scene;
use crate::TriangleMesh;

/// What [`apartment`] builds. Sizes in metres; ranges are `[min, max]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ApartmentConfig {
    /// How many rooms (2 to 4).
    pub rooms: [usize; 2],
    /// Floor area inside the outer walls, square metres.
    pub area: [f32; 2],
    /// Wall height.
    pub wall_height: f32,
    /// Wall thickness, outer and inner.
    pub wall_thickness: f32,
    /// Width of a door.
    pub door_width: [f32; 2],
    /// Free floor kept between pieces that do not belong together, and in front of doors.
    pub clearance: f32,
}

impl Default for ApartmentConfig {
    fn default() -> Self {
        Self {
            rooms: [2, 4],
            area: [45.0, 80.0],
            wall_height: 2.5,
            wall_thickness: 0.1,
            door_width: [0.8, 0.9],
            clearance: 0.6,
        }
    }
}

impl ApartmentConfig {
    fn validate(&self) -> Result<()> {
        let range = |r: [f32; 2], min: f32| {
            r[0].is_finite() && r[1].is_finite() && min <= r[0] && r[0] <= r[1]
        };
        let ok = (2..=4).contains(&self.rooms[0])
            && self.rooms[0] <= self.rooms[1]
            && self.rooms[1] <= 4
            && range(self.area, 10.0 * self.rooms[1] as f32)
            && self.area[1] <= 400.0
            && range(self.door_width, 0.3)
            && self.door_width[1] <= 1.5
            && self.wall_height.is_finite()
            && self.wall_height >= 2.0
            && self.wall_thickness.is_finite()
            && (0.02..=0.5).contains(&self.wall_thickness)
            && self.clearance.is_finite()
            && self.clearance >= 0.3;
        if ok {
            Ok(())
        } else {
            Err(SceneError::InvalidInput(format!(
                "apartment config: 2 to 4 rooms, 10 m² a room at least and 400 m² at most, doors \
                 of 0.3 to 1.5 m, walls 2 m high or more and 2 to 50 cm thick, clearance >= 0.3 m, \
                 ranges with min <= max (got {self:?})"
            )))
        }
    }
}

/// What a room of an apartment is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum RoomType {
    /// Sofa, armchairs, coffee table, TV unit, shelves.
    Living,
    /// Bed, bedside tables, wardrobe.
    Bedroom,
    /// Dining table and chairs, cabinets.
    Kitchen,
    /// Desk and chair, bookcases.
    Study,
}

/// One room of an apartment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ApartmentRoom {
    /// What it is.
    pub kind: RoomType,
    /// Its interior `[x_min, y_min, x_max, y_max]`, walls excluded.
    pub bounds: [f32; 4],
}

impl ApartmentRoom {
    /// Whether the world point `(x, y)` lies inside it.
    pub fn contains(&self, x: f32, y: f32) -> bool {
        let b = self.bounds;
        x >= b[0] && x <= b[2] && y >= b[1] && y <= b[3]
    }
}

/// A door through an interior wall.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Door {
    /// The middle of its opening, on the wall's centre line.
    pub center: [f32; 2],
    /// Its width.
    pub width: f32,
    /// Whether the wall runs along x (the door is passed along y).
    pub along_x: bool,
    /// The rooms it joins, by index.
    pub rooms: [usize; 2],
}

/// A generated apartment.
#[derive(Clone, Debug)]
pub struct Apartment {
    /// The whole apartment as one room: its scene (floor, outer and inner walls, furniture),
    /// its interior box from the origin and every piece of furniture, so whatever judges a
    /// room judges it.
    pub home: Room,
    /// Its rooms.
    pub rooms: Vec<ApartmentRoom>,
    /// Its doors, one per pair of rooms they join.
    pub doors: Vec<Door>,
    /// The catalogue item of each piece of [`Room::furniture`], in the same order.
    pub items: Vec<usize>,
}

impl Apartment {
    /// The room that holds the world point `(x, y)`, if any (none inside a wall).
    pub fn room_at(&self, x: f32, y: f32) -> Option<usize> {
        self.rooms.iter().position(|r| r.contains(x, y))
    }
}

/// An interior wall along a cut: from `a` to `b` on the line `at`, along x or y.
struct Cut {
    along_x: bool,
    at: f32,
    from: f32,
    to: f32,
}

/// Generates a furnished apartment from `catalogue`, seeded (see the module's description).
///
/// # Errors
/// [`SceneError::InvalidInput`] for a bad config or a catalogue without beds, sofas, chairs
/// and tables; errors of reading a model.
pub fn apartment(catalogue: &Catalogue, config: &ApartmentConfig, seed: u64) -> Result<Apartment> {
    config.validate()?;
    for role in [Role::Bed, Role::Sofa, Role::Chair, Role::DiningTable] {
        if catalogue.of_role(role).is_empty() {
            return Err(SceneError::InvalidInput(format!(
                "apartment: the catalogue has no {role:?} to furnish with"
            )));
        }
    }
    let mut rng = SplitMix64::new(seed ^ 0xA9A7_0000);
    let t = config.wall_thickness;
    // A plan whose rooms a door cannot all join (a shared wall too short) is drawn again.
    let mut plan = None;
    for _ in 0..LAYOUT_TRIES {
        let drawn = layout(config, &mut rng);
        if drawn.doors.len() + 1 == drawn.rooms.len() {
            plan = Some(drawn);
            break;
        }
    }
    let Layout {
        w,
        d,
        rooms,
        cuts,
        doors,
    } = plan.ok_or_else(|| {
        SceneError::InvalidInput(format!(
            "apartment: no plan of {LAYOUT_TRIES} drawn joins every room by a door of \
             {:?} m (seed {seed})",
            config.door_width
        ))
    })?;
    let mut scene = shell(w, d, &cuts, &doors, config)?;

    // Furniture, room by room.
    let mut furnisher = Furnisher {
        catalogue,
        rng: &mut rng,
        clearance: config.clearance,
        taken: Vec::new(),
        furniture: Vec::new(),
        group: Vec::new(),
        items: Vec::new(),
        walls: wall_rects(w, d, &cuts, &doors, t),
        size: [w, d],
    };
    // Keep-out zones on both sides of each door: 0.8 m deep.
    for door in &doors {
        let h = door.width / 2.0;
        let [x, y] = door.center;
        let zone = if door.along_x {
            [x - h, y - 0.8 - t / 2.0, x + h, y + 0.8 + t / 2.0]
        } else {
            [x - 0.8 - t / 2.0, y - h, x + 0.8 + t / 2.0, y + h]
        };
        furnisher.taken.push((zone, None));
    }
    for room in &rooms {
        furnisher.furnish(room, &mut scene)?;
    }
    let Furnisher {
        furniture, items, ..
    } = furnisher;
    Ok(Apartment {
        home: Room {
            scene,
            size: [w, d],
            furniture,
        },
        rooms,
        doors,
        items,
    })
}

/// How many plans [`apartment`] draws before it gives up on one whose rooms doors join.
const LAYOUT_TRIES: usize = 50;

/// A plan: the outer size, the rooms, the cuts' walls and the doors.
struct Layout {
    w: f32,
    d: f32,
    rooms: Vec<ApartmentRoom>,
    cuts: Vec<Cut>,
    doors: Vec<Door>,
}

/// Draws a plan: rooms cut from the rectangle, their types, and a door on every edge of a
/// tree over their shared walls (fewer when a room shares no wall long enough).
fn layout(config: &ApartmentConfig, rng: &mut SplitMix64) -> Layout {
    let range = |rng: &mut SplitMix64, r: [f32; 2]| r[0] + (r[1] - r[0]) * rng.next_f32();
    let n = config.rooms[0] + rng.below(config.rooms[1] - config.rooms[0] + 1);
    let area = range(rng, config.area);
    let aspect = range(rng, [1.0, 1.6]);
    let (w, d) = ((area * aspect).sqrt(), (area / aspect).sqrt());
    let t = config.wall_thickness;

    // Rooms: cut the largest along its longer side until there are n.
    let mut rects = vec![[0.0, 0.0, w, d]];
    let mut cuts = Vec::new();
    while rects.len() < n {
        let (i, r) = rects
            .iter()
            .enumerate()
            .max_by(|a, b| area_of(a.1).total_cmp(&area_of(b.1)))
            .map(|(i, r)| (i, *r))
            .expect("one room at least");
        let along_x = r[3] - r[1] > r[2] - r[0]; // a deep room is cut by a wall along x
        let (lo, hi) = if along_x { (r[1], r[3]) } else { (r[0], r[2]) };
        let c = lo + (hi - lo) * range(rng, [0.4, 0.6]);
        let (a, b) = if along_x {
            (
                [r[0], r[1], r[2], c - t / 2.0],
                [r[0], c + t / 2.0, r[2], r[3]],
            )
        } else {
            (
                [r[0], r[1], c - t / 2.0, r[3]],
                [c + t / 2.0, r[1], r[2], r[3]],
            )
        };
        cuts.push(Cut {
            along_x,
            at: c,
            from: if along_x { r[0] } else { r[1] },
            to: if along_x { r[2] } else { r[3] },
        });
        rects[i] = a;
        rects.push(b);
    }
    // The largest room is the living room; the others what is left, in a random order.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| area_of(&rects[b]).total_cmp(&area_of(&rects[a])));
    let mut others = vec![RoomType::Bedroom, RoomType::Kitchen, RoomType::Study];
    others.truncate(n - 1);
    shuffle(&mut others, rng);
    let mut kinds = vec![RoomType::Living; n];
    for (k, &room) in order.iter().enumerate().skip(1) {
        kinds[room] = others[k - 1];
    }
    let rooms: Vec<ApartmentRoom> = rects
        .iter()
        .zip(&kinds)
        .map(|(&bounds, &kind)| ApartmentRoom { kind, bounds })
        .collect();

    let doors = place_doors(&rooms, config, rng, order[0]);
    Layout {
        w,
        d,
        rooms,
        cuts,
        doors,
    }
}

fn area_of(r: &[f32; 4]) -> f32 {
    (r[2] - r[0]) * (r[3] - r[1])
}

/// A door on every edge of a tree over the rooms' shared walls, grown from the living room.
fn place_doors(
    rooms: &[ApartmentRoom],
    config: &ApartmentConfig,
    rng: &mut SplitMix64,
    living: usize,
) -> Vec<Door> {
    let t = config.wall_thickness;
    let widest = config.door_width[1];
    // Rooms a and b share a wall where one's side lies a wall's thickness from the other's.
    let shared = |a: &ApartmentRoom, b: &ApartmentRoom| -> Option<(bool, f32, f32, f32)> {
        let (p, q) = (a.bounds, b.bounds);
        let near = |u: f32, v: f32| (u + t - v).abs() < 1e-3;
        let overlap = |lo1: f32, hi1: f32, lo2: f32, hi2: f32| (lo1.max(lo2), hi1.min(hi2));
        let wide = |(lo, hi): (f32, f32)| hi - lo >= widest + 0.4;
        if near(p[2], q[0]) || near(q[2], p[0]) {
            let x = if near(p[2], q[0]) {
                p[2] + t / 2.0
            } else {
                q[2] + t / 2.0
            };
            let o = overlap(p[1], p[3], q[1], q[3]);
            return wide(o).then_some((false, x, o.0, o.1));
        }
        if near(p[3], q[1]) || near(q[3], p[1]) {
            let y = if near(p[3], q[1]) {
                p[3] + t / 2.0
            } else {
                q[3] + t / 2.0
            };
            let o = overlap(p[0], p[2], q[0], q[2]);
            return wide(o).then_some((true, y, o.0, o.1));
        }
        None
    };
    let mut reached = vec![false; rooms.len()];
    reached[living] = true;
    let mut doors = Vec::new();
    let mut queue = vec![living];
    while let Some(a) = queue.pop() {
        let mut next: Vec<usize> = (0..rooms.len()).filter(|&b| !reached[b]).collect();
        shuffle(&mut next, rng);
        for b in next {
            if reached[b] {
                continue;
            }
            let Some((along_x, line, lo, hi)) = shared(&rooms[a], &rooms[b]) else {
                continue;
            };
            let width = config.door_width[0]
                + (config.door_width[1] - config.door_width[0]) * rng.next_f32();
            let c = lo + 0.2 + width / 2.0 + (hi - lo - 0.4 - width) * rng.next_f32();
            doors.push(Door {
                center: if along_x { [c, line] } else { [line, c] },
                width,
                along_x,
                rooms: [a, b],
            });
            reached[b] = true;
            queue.push(b);
        }
    }
    doors
}

/// Floor and walls: the outer four and one along each cut, with the doors' openings.
fn shell(w: f32, d: f32, cuts: &[Cut], doors: &[Door], config: &ApartmentConfig) -> Result<Scene> {
    let t = config.wall_thickness;
    let h = config.wall_height;
    let mut scene = Scene::new();
    scene.add(SceneObject::new("floor", ObjectKind::Floor).with(
        Primitive::cuboid([w + 2.0 * t, d + 2.0 * t, 0.1]),
        at(w / 2.0, d / 2.0, -0.05, 0.0),
    )?)?;
    let mut outer = SceneObject::new("outer walls", ObjectKind::Wall);
    for (pose, size) in [
        (at(w / 2.0, -t / 2.0, h / 2.0, 0.0), [w + 2.0 * t, t, h]),
        (at(w / 2.0, d + t / 2.0, h / 2.0, 0.0), [w + 2.0 * t, t, h]),
        (at(-t / 2.0, d / 2.0, h / 2.0, 0.0), [t, d, h]),
        (at(w + t / 2.0, d / 2.0, h / 2.0, 0.0), [t, d, h]),
    ] {
        outer.push(Part::primitive(Primitive::cuboid(size), pose)?);
    }
    scene.add(outer)?;
    for (k, [x0, y0, x1, y1]) in wall_rects(w, d, cuts, doors, t).into_iter().enumerate() {
        if k < 4 {
            continue; // the outer walls, added above
        }
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        scene.add(
            SceneObject::new(format!("wall {k}"), ObjectKind::Wall).with(
                Primitive::cuboid([x1 - x0, y1 - y0, h]),
                at(cx, cy, h / 2.0, 0.0),
            )?,
        )?;
    }
    Ok(scene)
}

/// Every wall's footprint `[x0, y0, x1, y1]`: the four outer walls first, then the inner walls'
/// pieces between their doors.
fn wall_rects(w: f32, d: f32, cuts: &[Cut], doors: &[Door], t: f32) -> Vec<[f32; 4]> {
    let mut out = vec![
        [-t, -t, w + t, 0.0],
        [-t, d, w + t, d + t],
        [-t, 0.0, 0.0, d],
        [w, 0.0, w + t, d],
    ];
    for cut in cuts {
        let mut gaps: Vec<(f32, f32)> = doors
            .iter()
            .filter(|dr| dr.along_x == cut.along_x)
            .filter_map(|dr| {
                let (line, c) = if dr.along_x {
                    (dr.center[1], dr.center[0])
                } else {
                    (dr.center[0], dr.center[1])
                };
                let on = (line - cut.at).abs() < 1e-3 && c > cut.from && c < cut.to;
                on.then_some((c - dr.width / 2.0, c + dr.width / 2.0))
            })
            .collect();
        gaps.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut start = cut.from;
        for (a, b) in gaps.into_iter().chain([(cut.to, cut.to)]) {
            if a - start > 1e-3 {
                out.push(if cut.along_x {
                    [start, cut.at - t / 2.0, a, cut.at + t / 2.0]
                } else {
                    [cut.at - t / 2.0, start, cut.at + t / 2.0, a]
                });
            }
            start = b;
        }
    }
    out
}

/// How a piece stands in its room.
#[derive(Clone, Copy)]
enum Place {
    /// Back to a wall, facing the room.
    Wall,
    /// Anywhere, turned by a quarter turn.
    Free,
}

struct Furnisher<'a> {
    catalogue: &'a Catalogue,
    rng: &'a mut SplitMix64,
    clearance: f32,
    /// Footprints pieces keep `clearance` from, each with the group of furniture it belongs
    /// to (`None` for a door's zone).
    taken: Vec<([f32; 4], Option<usize>)>,
    furniture: Vec<Furniture>,
    /// The group each piece belongs to: the index of the piece it was placed with, or its own.
    group: Vec<usize>,
    items: Vec<usize>,
    walls: Vec<[f32; 4]>,
    size: [f32; 2],
}

/// The radius a body's centre keeps from furniture and walls on the free-floor check, metres.
const BODY: f32 = 0.25;
/// The free-floor check's cell, metres.
const CELL: f32 = 0.1;

impl Furnisher<'_> {
    fn pick(&mut self, role: Role) -> Option<usize> {
        let of = self.catalogue.of_role(role);
        (!of.is_empty()).then(|| of[self.rng.below(of.len())])
    }

    fn chance(&mut self, p: f32) -> bool {
        self.rng.next_f32() < p
    }

    /// Furnishes `room` by its type's rules.
    fn furnish(&mut self, room: &ApartmentRoom, scene: &mut Scene) -> Result<()> {
        let b = room.bounds;
        match room.kind {
            RoomType::Bedroom => {
                if let Some(bed) = self.try_place(scene, b, Role::Bed, Place::Wall)? {
                    for side in [-1.0, 1.0] {
                        self.beside(scene, b, bed, Role::BedsideTable, side)?;
                    }
                }
                self.try_place(scene, b, Role::Wardrobe, Place::Wall)?;
                if self.chance(0.5) {
                    self.try_place(scene, b, Role::Cabinet, Place::Wall)?;
                }
                if self.chance(0.5) {
                    self.try_place(scene, b, Role::Armchair, Place::Wall)?;
                }
            }
            RoomType::Living => {
                if let Some(sofa) = self.try_place(scene, b, Role::Sofa, Place::Wall)? {
                    self.in_front(scene, b, sofa, Role::CoffeeTable)?;
                }
                self.try_place(scene, b, Role::TvUnit, Place::Wall)?;
                for _ in 0..1 + self.rng.below(2) {
                    self.try_place(scene, b, Role::Armchair, Place::Wall)?;
                }
                self.try_place(scene, b, Role::Bookcase, Place::Wall)?;
                self.try_place(scene, b, Role::Plant, Place::Wall)?;
                if self.chance(0.3) {
                    self.try_place(scene, b, Role::Piano, Place::Wall)?;
                }
                if self.chance(0.4) {
                    self.try_place(scene, b, Role::Bench, Place::Wall)?;
                }
            }
            RoomType::Kitchen => {
                if let Some(table) = self.try_place(scene, b, Role::DiningTable, Place::Free)? {
                    self.around(scene, b, table)?;
                }
                for _ in 0..2 + self.rng.below(2) {
                    self.try_place(scene, b, Role::Cabinet, Place::Wall)?;
                }
                if self.chance(0.5) {
                    self.try_place(scene, b, Role::Stool, Place::Wall)?;
                }
            }
            RoomType::Study => {
                if let Some(desk) = self.try_place(scene, b, Role::Desk, Place::Wall)? {
                    self.tucked(scene, b, desk, 0.0)?;
                }
                for _ in 0..1 + self.rng.below(2) {
                    self.try_place(scene, b, Role::Bookcase, Place::Wall)?;
                }
                if self.chance(0.5) {
                    self.try_place(scene, b, Role::Armchair, Place::Wall)?;
                }
                if self.chance(0.5) {
                    self.try_place(scene, b, Role::Plant, Place::Wall)?;
                }
            }
        }
        Ok(())
    }

    /// Places a piece of `role` in the room `b` (up to 60 tries); its index in the furniture.
    fn try_place(
        &mut self,
        scene: &mut Scene,
        b: [f32; 4],
        role: Role,
        place: Place,
    ) -> Result<Option<usize>> {
        let Some(item) = self.pick(role) else {
            return Ok(None);
        };
        let size = self.catalogue.items[item].size;
        let gap = self.clearance;
        for _ in 0..60 {
            let (center, yaw) = match place {
                Place::Wall => {
                    let along = |rng: &mut SplitMix64, lo: f32, hi: f32| {
                        lo + size[0] / 2.0 + (hi - lo - size[0]).max(0.0) * rng.next_f32()
                    };
                    let back = size[1] / 2.0 + 0.01;
                    match self.rng.below(4) {
                        0 => ([along(self.rng, b[0], b[2]), b[1] + back], 0.0),
                        1 => ([along(self.rng, b[0], b[2]), b[3] - back], PI),
                        2 => ([b[0] + back, along(self.rng, b[1], b[3])], -FRAC_PI_2),
                        _ => ([b[2] - back, along(self.rng, b[1], b[3])], FRAC_PI_2),
                    }
                }
                Place::Free => {
                    let yaw = self.rng.below(4) as f32 * FRAC_PI_2;
                    let f = footprint([0.0, 0.0], yaw, size);
                    let span = [
                        b[2] - b[0] - 2.0 * (f[2] + gap),
                        b[3] - b[1] - 2.0 * (f[3] + gap),
                    ];
                    if span[0] <= 0.0 || span[1] <= 0.0 {
                        return Ok(None);
                    }
                    (
                        [
                            b[0] + f[2] + gap + span[0] * self.rng.next_f32(),
                            b[1] + f[3] + gap + span[1] * self.rng.next_f32(),
                        ],
                        yaw,
                    )
                }
            };
            if let Some(k) = self.put(scene, b, item, center, yaw, None)? {
                return Ok(Some(k));
            }
        }
        Ok(None)
    }

    /// A piece of `role` against the same wall as piece `of`, beside its back on `side`.
    fn beside(
        &mut self,
        scene: &mut Scene,
        b: [f32; 4],
        of: usize,
        role: Role,
        side: f32,
    ) -> Result<()> {
        let Some(item) = self.pick(role) else {
            return Ok(());
        };
        let host = self.furniture[of].clone();
        let size = self.catalogue.items[item].size;
        let (s, c) = host.yaw.sin_cos();
        // In the host's frame: beside it (x), backs level with each other (y).
        let lx = side * (host.size[0] / 2.0 + size[0] / 2.0 + 0.03);
        let ly = -host.size[1] / 2.0 + size[1] / 2.0;
        let center = [
            host.center[0] + c * lx - s * ly,
            host.center[1] + s * lx + c * ly,
        ];
        self.put(scene, b, item, center, host.yaw, Some(of))?;
        Ok(())
    }

    /// A piece of `role` facing piece `of`'s front, a step's width (0.45 m) before it.
    fn in_front(&mut self, scene: &mut Scene, b: [f32; 4], of: usize, role: Role) -> Result<()> {
        let Some(item) = self.pick(role) else {
            return Ok(());
        };
        let host = self.furniture[of].clone();
        let size = self.catalogue.items[item].size;
        let (s, c) = host.yaw.sin_cos();
        let ly = host.size[1] / 2.0 + 0.45 + size[1] / 2.0;
        let center = [host.center[0] - s * ly, host.center[1] + c * ly];
        // Only the sofa is allowed so near: the coffee table belongs to it.
        self.put(scene, b, item, center, host.yaw, Some(of))?;
        Ok(())
    }

    /// Chairs around the table `of`: one or two along each long side, sometimes one at an
    /// end, each facing the table and pushed under its top by 5-15 cm.
    fn around(&mut self, scene: &mut Scene, b: [f32; 4], of: usize) -> Result<()> {
        let tw = self.furniture[of].size[0];
        // In the table's frame: (along its width, which side, the chair's turn).
        let mut spots: Vec<(f32, f32, f32)> = Vec::new();
        let per_side = if tw >= 1.2 { 2 } else { 1 };
        for k in 0..per_side {
            let x = if per_side == 1 {
                0.0
            } else {
                (k as f32 - 0.5) * tw / 2.0
            };
            spots.push((x, -1.0, 0.0)); // south side, facing +y
            spots.push((x, 1.0, PI)); // north side, facing -y
        }
        if tw >= 1.4 && self.chance(0.5) {
            spots.push((-1.0, 0.0, -FRAC_PI_2));
        }
        for (lx, side, local_yaw) in spots {
            self.tucked_at(scene, b, of, lx, side, local_yaw)?;
        }
        Ok(())
    }

    /// A chair facing the front of piece `of` (a desk), pushed under it, `lx` along.
    fn tucked(&mut self, scene: &mut Scene, b: [f32; 4], of: usize, lx: f32) -> Result<()> {
        self.tucked_at(scene, b, of, lx, 1.0, PI)
    }

    /// A chair on side `side` of piece `of` (-1 its back half's edge, +1 its front's; with
    /// `lx` of -1 or 1 on its ends when `side` is 0) facing it by `local_yaw` in its frame.
    fn tucked_at(
        &mut self,
        scene: &mut Scene,
        b: [f32; 4],
        of: usize,
        lx: f32,
        side: f32,
        local_yaw: f32,
    ) -> Result<()> {
        let Some(item) = self.pick(Role::Chair) else {
            return Ok(());
        };
        let host = self.furniture[of].clone();
        let size = self.catalogue.items[item].size;
        let tuck = 0.05 + 0.1 * self.rng.next_f32();
        let (x, y) = if side == 0.0 {
            (lx * (host.size[0] / 2.0 + size[1] / 2.0 - tuck), 0.0)
        } else {
            (lx, side * (host.size[1] / 2.0 + size[1] / 2.0 - tuck))
        };
        // A desk's front faces +y in its frame, so its chair comes from +y facing -y.
        let (s, c) = host.yaw.sin_cos();
        let center = [
            host.center[0] + c * x - s * y,
            host.center[1] + s * x + c * y,
        ];
        self.put(scene, b, item, center, host.yaw + local_yaw, Some(of))?;
        Ok(())
    }

    /// Places catalogue item `item` at `center` turned by `yaw` if it fits: inside the room
    /// `b`, clear of the walls, `clearance` from every footprint taken (but `host`'s, which it
    /// belongs to and only may not overlap by more than a chair's tuck), and the apartment's
    /// free floor still one piece. Its index in the furniture when placed.
    fn put(
        &mut self,
        scene: &mut Scene,
        b: [f32; 4],
        item: usize,
        center: [f32; 2],
        yaw: f32,
        host: Option<usize>,
    ) -> Result<Option<usize>> {
        let it = &self.catalogue.items[item];
        let f = footprint(center, yaw, it.size);
        let inside = f[0] >= b[0] - 1e-3
            && f[1] >= b[1] - 1e-3
            && f[2] <= b[2] + 1e-3
            && f[3] <= b[3] + 1e-3;
        if !inside {
            return Ok(None);
        }
        let host_rect = host.map(|h| self.furniture[h].footprint());
        let group = host.map(|h| self.group[h]);
        let gap = self.clearance;
        let apart = |o: &[f32; 4], g: f32| {
            f[0] >= o[2] + g || o[0] >= f[2] + g || f[1] >= o[3] + g || o[1] >= f[3] + g
        };
        // Within a group (a table and its chairs, a bed and its tables) pieces keep 3 cm
        // apart, but for the host, which a chair may be pushed under.
        let clear = self.taken.iter().all(|(o, g)| {
            if host_rect.as_ref() == Some(o) {
                true
            } else if group.is_some() && *g == group {
                apart(o, 0.03)
            } else {
                apart(o, gap)
            }
        });
        if !clear {
            return Ok(None);
        }
        if !self.floor_connected(&f) {
            return Ok(None);
        }
        let model = self.catalogue.model(item)?;
        let place = at(center[0], center[1], 0.0, yaw);
        let placed = TriangleMesh {
            vertices: model.vertices.iter().map(|v| place * v).collect(),
            triangles: model.triangles.clone(),
        };
        let n = self.furniture.len();
        let mut object = SceneObject::new(format!("{} {n}", it.name).to_lowercase(), it.kind);
        object.push(Part::mesh(&placed)?);
        let object = scene.add(object)?;
        let seat_forward = it
            .seat_height
            .and_then(|h| self.catalogue.seat_forward(item, h).ok().flatten());
        self.furniture.push(Furniture {
            kind: it.kind,
            object,
            center,
            yaw,
            size: it.size,
            seat_height: it.seat_height,
            seat_forward,
        });
        self.items.push(item);
        let group = group.unwrap_or(n);
        self.taken.push((f, Some(group)));
        self.group.push(group);
        Ok(Some(n))
    }

    /// Whether the apartment's floor where a body's centre may stand (0.25 m from walls and
    /// furniture, `extra` counted as furniture) stays one connected piece, on 0.1 m cells.
    fn floor_connected(&self, extra: &[f32; 4]) -> bool {
        let [w, d] = self.size;
        let (nx, ny) = ((w / CELL).ceil() as usize, (d / CELL).ceil() as usize);
        let mut blocked = vec![false; nx * ny];
        let rects = self
            .walls
            .iter()
            .chain(
                self.taken
                    .iter()
                    .filter(|(_, g)| g.is_some())
                    .map(|(r, _)| r),
            )
            .chain([extra]);
        for r in rects {
            let lo = |v: f32| ((v - BODY) / CELL).floor().max(0.0) as usize;
            let hi = |v: f32, n: usize| (((v + BODY) / CELL).ceil().max(0.0) as usize).min(n);
            for i in lo(r[0])..hi(r[2], nx) {
                for j in lo(r[1])..hi(r[3], ny) {
                    // A cell is blocked when its centre is within the grown box.
                    let (x, y) = ((i as f32 + 0.5) * CELL, (j as f32 + 0.5) * CELL);
                    if x > r[0] - BODY && x < r[2] + BODY && y > r[1] - BODY && y < r[3] + BODY {
                        blocked[i * ny + j] = true;
                    }
                }
            }
        }
        let Some(start) = blocked.iter().position(|b| !b) else {
            return false;
        };
        let mut seen = blocked.clone();
        seen[start] = true;
        let mut stack = vec![start];
        let mut reached = 1;
        while let Some(c) = stack.pop() {
            let (i, j) = (c / ny, c % ny);
            let mut visit = |i: usize, j: usize| {
                let k = i * ny + j;
                if !seen[k] {
                    seen[k] = true;
                    reached += 1;
                    stack.push(k);
                }
            };
            if i > 0 {
                visit(i - 1, j);
            }
            if i + 1 < nx {
                visit(i + 1, j);
            }
            if j > 0 {
                visit(i, j - 1);
            }
            if j + 1 < ny {
                visit(i, j + 1);
            }
        }
        reached == blocked.iter().filter(|b| !**b).count()
    }
}
