//! Inside and outside for meshes as they come: open shells, overlapping parts, hollow carcasses,
//! inconsistent or inverted winding.
//!
//! A sign read from the faces' normals (parry's pseudo-normals) is only right for one closed,
//! outward-wound surface: a wardrobe wound inside out makes the whole room "inside", an open
//! table top makes the air under it solid. Here the sign ignores normals. The mesh is
//! rasterised into a lattice of cells (cells a triangle passes through are *surface*), and air
//! is flooded in from outside the mesh's box through the cells no triangle touches. Cells the
//! flood cannot reach are *inside*: the solid of a closed carcass, whatever its winding, a
//! closed cabinet's hollow, the inside of two overlapping boxes. Open shells enclose nothing,
//! so they stay thin obstacles: the distance to them is unsigned.
//!
//! One exception: a mesh of a whole room (walls, floor and ceiling all closed) encloses the
//! room itself. An enclosed cavity that spans at least three quarters of the mesh's box in x
//! and in y, at least [`ROOM_SPAN`] in each, and is at least [`ROOM_HEIGHT`] tall is taken to
//! be that room, and is air.

use nalgebra::{Point3, Vector3};

use crate::TriangleMesh;

/// Finest cell side, metres: a 3 cm table top keeps an inside.
const FINEST: f32 = 0.01;
/// At most this many cells per mesh; larger meshes get coarser cells.
const MAX_CELLS: f32 = 16.0e6;
/// An enclosed cavity at least this tall (metres) spanning the mesh is a room, not a solid.
pub const ROOM_HEIGHT: f32 = 1.0;
/// ...and at least this wide and deep (metres): a wardrobe's hollow is not a room.
pub const ROOM_SPAN: f32 = 1.5;

const AIR: u8 = 0;
const SURFACE: u8 = 1;
const INSIDE: u8 = 2;

/// Which cells of a mesh's box are inside it.
#[derive(Clone, Debug)]
pub(crate) struct Occupancy {
    origin: Point3<f32>,
    cell: f32,
    dims: [usize; 3],
    state: Vec<u8>,
    /// Enclosed cavities taken as rooms (see the module).
    pub(crate) rooms: usize,
}

impl Occupancy {
    /// The occupancy of `mesh` (validated: finite, indices in range).
    pub(crate) fn of(mesh: &TriangleMesh) -> Self {
        let (lo, hi) = crate::mesh::bounds(&mesh.vertices);
        let extent = hi - lo;
        let volume =
            (extent.x + 2.0 * FINEST) * (extent.y + 2.0 * FINEST) * (extent.z + 2.0 * FINEST);
        let cell = FINEST.max((volume / MAX_CELLS).cbrt());
        // One cell of air on every side, so the flood starts all around.
        let origin = lo - Vector3::repeat(cell);
        let dims = [0, 1, 2].map(|a| ((extent[a] / cell).ceil() as usize + 3).max(3));
        let mut occ = Self {
            origin,
            cell,
            dims,
            state: vec![AIR; dims[0] * dims[1] * dims[2]],
            rooms: 0,
        };
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            occ.rasterise(&a, &b, &c);
        }
        occ.flood();
        occ
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    fn centre(&self, c: [usize; 3]) -> Point3<f32> {
        self.origin
            + Vector3::new(c[0] as f32 + 0.5, c[1] as f32 + 0.5, c[2] as f32 + 0.5) * self.cell
    }

    /// Marks the cells whose centre lies within half a cell diagonal of the triangle.
    fn rasterise(&mut self, a: &Point3<f32>, b: &Point3<f32>, c: &Point3<f32>) {
        let reach = self.cell * 0.5 * 3f32.sqrt();
        let lo = a.inf(b).inf(c) - Vector3::repeat(reach);
        let hi = a.sup(b).sup(c) + Vector3::repeat(reach);
        let to_cell = |v: f32, axis: usize| {
            (((v - self.origin[axis]) / self.cell).floor().max(0.0) as usize)
                .min(self.dims[axis] - 1)
        };
        let n = (b - a).cross(&(c - a));
        let normal = n.try_normalize(1e-20);
        for z in to_cell(lo.z, 2)..=to_cell(hi.z, 2) {
            for y in to_cell(lo.y, 1)..=to_cell(hi.y, 1) {
                for x in to_cell(lo.x, 0)..=to_cell(hi.x, 0) {
                    let p = self.centre([x, y, z]);
                    // The plane first: most cells of a big triangle's box are far from it.
                    if let Some(u) = normal {
                        if (p - a).dot(&u).abs() > reach {
                            continue;
                        }
                    }
                    if (closest_on_triangle(&p, a, b, c) - p).norm() <= reach {
                        let i = self.index([x, y, z]);
                        self.state[i] = SURFACE;
                    }
                }
            }
        }
    }

    /// Air from the box's faces through non-surface cells (6-connected); the rest is inside,
    /// except cavities that are rooms.
    fn flood(&mut self) {
        let [nx, ny, nz] = self.dims;
        // Everything not surface starts inside; the flood turns what it reaches to air.
        for s in &mut self.state {
            if *s == AIR {
                *s = INSIDE;
            }
        }
        let mut queue = Vec::new();
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let edge =
                        x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1;
                    if edge {
                        queue.push([x, y, z]);
                    }
                }
            }
        }
        self.fill(queue, INSIDE, AIR, false);
        // Each enclosed cavity, labelled in turn; one that spans the mesh like a room is air.
        let mut label = 3u8;
        for start in 0..self.state.len() {
            if self.state[start] != INSIDE {
                continue;
            }
            let c = [start % nx, (start / nx) % ny, start / (nx * ny)];
            let cells = self.fill(vec![c], INSIDE, label, true);
            let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
            for c in &cells {
                for a in 0..3 {
                    lo[a] = lo[a].min(c[a]);
                    hi[a] = hi[a].max(c[a]);
                }
            }
            let span = |a: usize| (hi[a] + 1 - lo[a]) as f32;
            let room = span(0) >= 0.75 * (nx - 2) as f32
                && span(1) >= 0.75 * (ny - 2) as f32
                && span(0).min(span(1)) * self.cell >= ROOM_SPAN
                && span(2) * self.cell >= ROOM_HEIGHT;
            let to = if room { AIR } else { label };
            self.rooms += usize::from(room);
            for c in cells {
                let i = self.index(c);
                self.state[i] = to;
            }
            // Labels only keep the cavities apart while they are found; 3..=254 cycle.
            label = if label == 254 { 3 } else { label + 1 };
        }
        for s in &mut self.state {
            if *s >= 3 {
                *s = INSIDE;
            }
        }
    }

    /// Turns the 6-connected cells of state `from` reached from `seeds` into `to`; returns them
    /// when `collect`.
    fn fill(&mut self, seeds: Vec<[usize; 3]>, from: u8, to: u8, collect: bool) -> Vec<[usize; 3]> {
        let [nx, ny, nz] = self.dims;
        let mut done = Vec::new();
        let mut queue: Vec<u32> = Vec::new();
        for c in seeds {
            let i = self.index(c);
            if self.state[i] == from {
                self.state[i] = to;
                queue.push(i as u32);
            }
        }
        let (sx, sy) = (1, nx);
        let sz = nx * ny;
        while let Some(i) = queue.pop() {
            let i = i as usize;
            let c = [i % nx, (i / nx) % ny, i / sz];
            if collect {
                done.push(c);
            }
            let mut visit = |j: usize, state: &mut Vec<u8>| {
                if state[j] == from {
                    state[j] = to;
                    queue.push(j as u32);
                }
            };
            if c[0] > 0 {
                visit(i - sx, &mut self.state);
            }
            if c[0] + 1 < nx {
                visit(i + sx, &mut self.state);
            }
            if c[1] > 0 {
                visit(i - sy, &mut self.state);
            }
            if c[1] + 1 < ny {
                visit(i + sy, &mut self.state);
            }
            if c[2] > 0 {
                visit(i - sz, &mut self.state);
            }
            if c[2] + 1 < nz {
                visit(i + sz, &mut self.state);
            }
        }
        done
    }

    /// Whether `p` lies in an inside cell.
    pub(crate) fn inside(&self, p: &Point3<f32>) -> bool {
        let mut c = [0usize; 3];
        for a in 0..3 {
            let v = (p[a] - self.origin[a]) / self.cell;
            if !(v >= 0.0 && v < self.dims[a] as f32) {
                return false;
            }
            c[a] = v as usize;
        }
        self.state[self.index(c)] == INSIDE
    }

    /// The share of the box's cells that are inside.
    pub(crate) fn inside_share(&self) -> f32 {
        self.state.iter().filter(|&&s| s == INSIDE).count() as f32 / self.state.len() as f32
    }

    /// The side of a cell, metres.
    pub(crate) fn cell(&self) -> f32 {
        self.cell
    }
}

/// The point of triangle `abc` nearest to `p` (Ericson, Real-Time Collision Detection 5.1.5).
fn closest_on_triangle(
    p: &Point3<f32>,
    a: &Point3<f32>,
    b: &Point3<f32>,
    c: &Point3<f32>,
) -> Point3<f32> {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom.abs() < 1e-30 {
        // A degenerate triangle: its nearest vertex will do.
        return *[a, b, c]
            .into_iter()
            .min_by(|x, y| (*x - p).norm().total_cmp(&(*y - p).norm()))
            .unwrap_or(a);
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An axis-aligned box from `lo` to `hi`, wound outward (or inward with `flip`).
    pub(crate) fn box_mesh(lo: [f32; 3], hi: [f32; 3], flip: bool) -> TriangleMesh {
        let mut m = TriangleMesh::cube(1.0);
        for v in &mut m.vertices {
            for a in 0..3 {
                v[a] = lo[a] + (v[a] + 0.5) * (hi[a] - lo[a]);
            }
        }
        if flip {
            for t in &mut m.triangles {
                t.swap(1, 2);
            }
        }
        m
    }

    #[test]
    fn a_box_is_solid_whatever_its_winding() {
        for flip in [false, true] {
            let occ = Occupancy::of(&box_mesh([0.0; 3], [1.0, 0.5, 0.8], flip));
            assert!(occ.inside(&Point3::new(0.5, 0.25, 0.4)), "flip {flip}");
            assert!(!occ.inside(&Point3::new(1.5, 0.25, 0.4)));
            assert!(!occ.inside(&Point3::new(0.5, 0.25, 0.9)));
        }
    }

    #[test]
    fn overlapping_boxes_are_solid_where_they_overlap() {
        let mut m = box_mesh([0.0; 3], [1.0, 1.0, 1.0], false);
        m.append(&box_mesh([0.5, 0.0, 0.0], [1.5, 1.0, 1.0], true));
        let occ = Occupancy::of(&m);
        for x in [0.25, 0.75, 1.25] {
            assert!(occ.inside(&Point3::new(x, 0.5, 0.5)), "x {x}");
        }
    }

    #[test]
    fn open_shells_enclose_nothing_and_a_table_leaves_air_beneath() {
        // A table: a 10 cm top on four legs. Under the top is air; the top is solid.
        let mut table = box_mesh([0.0, 0.0, 0.64], [1.2, 0.8, 0.74], false);
        for (x, y) in [(0.0, 0.0), (1.15, 0.0), (0.0, 0.75), (1.15, 0.75)] {
            table.append(&box_mesh([x, y, 0.0], [x + 0.05, y + 0.05, 0.64], false));
        }
        let occ = Occupancy::of(&table);
        assert!(!occ.inside(&Point3::new(0.6, 0.4, 0.35)));
        assert!(occ.inside(&Point3::new(0.6, 0.4, 0.69)));
        // A box missing its top face: open, so hollow.
        let mut open = box_mesh([0.0; 3], [1.0, 1.0, 1.0], false);
        open.triangles
            .retain(|t| !t.iter().all(|&i| open.vertices[i as usize].z > 0.99));
        let occ = Occupancy::of(&open);
        assert!(!occ.inside(&Point3::new(0.5, 0.5, 0.5)));
        assert_eq!(occ.inside_share(), 0.0);
    }

    #[test]
    fn a_closed_carcass_is_inside_and_a_closed_room_is_not() {
        // A cabinet of six 2 cm panels (separate closed boxes): its hollow is inside.
        let t = 0.02;
        let (w, d, h) = (0.8, 0.5, 1.8);
        let mut cabinet = TriangleMesh::default();
        for (lo, hi) in [
            ([0.0, 0.0, 0.0], [w, d, t]),
            ([0.0, 0.0, h - t], [w, d, h]),
            ([0.0, 0.0, 0.0], [t, d, h]),
            ([w - t, 0.0, 0.0], [w, d, h]),
            ([0.0, 0.0, 0.0], [w, t, h]),
            ([0.0, d - t, 0.0], [w, d, h]),
        ] {
            cabinet.append(&box_mesh(lo, hi, false));
        }
        let occ = Occupancy::of(&cabinet);
        assert!(occ.inside(&Point3::new(w / 2.0, d / 2.0, h / 2.0)));
        assert_eq!(occ.rooms, 0);
        // The same, room-sized, with the furniture inside: the room is air, the box solid.
        let (w, d, h) = (5.0, 4.0, 2.5);
        let mut room = TriangleMesh::default();
        for (lo, hi) in [
            ([0.0, 0.0, -0.1], [w, d, 0.0]),
            ([0.0, 0.0, h], [w, d, h + 0.1]),
            ([-0.1, 0.0, 0.0], [0.0, d, h]),
            ([w, 0.0, 0.0], [w + 0.1, d, h]),
            ([0.0, -0.1, 0.0], [w, 0.0, h]),
            ([0.0, d, 0.0], [w, d + 0.1, h]),
        ] {
            room.append(&box_mesh(lo, hi, true));
        }
        room.append(&box_mesh([1.0, 1.0, 0.0], [2.0, 1.5, 0.8], true));
        let occ = Occupancy::of(&room);
        assert_eq!(occ.rooms, 1);
        assert!(!occ.inside(&Point3::new(3.0, 3.0, 1.0)));
        assert!(occ.inside(&Point3::new(1.5, 1.25, 0.4)));
        assert!(occ.inside(&Point3::new(2.5, 2.0, -0.05)));
    }
}
