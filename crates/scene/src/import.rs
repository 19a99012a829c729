//! Meshes from elsewhere into the library's frame: metres, z up, the floor at z = 0 and the
//! scene near the origin. [`import_mesh`] converts as told ([`ImportConfig`]: up axis and
//! units), finds the floor, moves the scene onto it, and says what it read and what looks
//! wrong ([`ImportReport`]), naming the flag that would fix it.

use crate::error::{Result, SceneError};
use crate::mesh::bounds;
use crate::TriangleMesh;
use nalgebra::{Point3, Vector3};
use std::fmt;
use std::str::FromStr;

/// Which axis of the file points up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpAxis {
    /// +y up (glTF, Recast's levels, most game engines): y becomes z.
    Y,
    /// +z up (the library's frame, Blender, ROS).
    #[default]
    Z,
}

impl UpAxis {
    /// The up axis a file's format fixes: +y for glTF (`.gltf`, `.glb`; its specification's
    /// frame), +z (the library's) for anything else.
    pub fn for_file(path: impl AsRef<std::path::Path>) -> Self {
        let ext = path.as_ref().extension().and_then(|e| e.to_str());
        match ext.map(str::to_ascii_lowercase).as_deref() {
            Some("gltf" | "glb") => Self::Y,
            _ => Self::Z,
        }
    }
}

impl FromStr for UpAxis {
    type Err = SceneError;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "y" | "Y" => Ok(Self::Y),
            "z" | "Z" => Ok(Self::Z),
            _ => Err(SceneError::InvalidInput(format!("up axis `{s}`: y or z"))),
        }
    }
}

impl fmt::Display for UpAxis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Y => "y",
            Self::Z => "z",
        })
    }
}

/// The length unit of the file's coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Units {
    /// Metres.
    #[default]
    Metres,
    /// Centimetres.
    Centimetres,
    /// Millimetres.
    Millimetres,
    /// Any other: metres per file unit.
    Scale(f32),
}

impl Units {
    /// Metres per file unit.
    pub fn metres(self) -> f32 {
        match self {
            Self::Metres => 1.0,
            Self::Centimetres => 0.01,
            Self::Millimetres => 0.001,
            Self::Scale(s) => s,
        }
    }
}

impl FromStr for Units {
    type Err = SceneError;

    /// `m`, `cm`, `mm`, or a positive number of metres per unit.
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "m" => Ok(Self::Metres),
            "cm" => Ok(Self::Centimetres),
            "mm" => Ok(Self::Millimetres),
            _ => match s.parse::<f32>() {
                Ok(v) if v.is_finite() && v > 0.0 => Ok(Self::Scale(v)),
                _ => Err(SceneError::InvalidInput(format!(
                    "units `{s}`: m, cm, mm or a positive number of metres per unit"
                ))),
            },
        }
    }
}

/// How [`import_mesh`] reads a mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImportConfig {
    /// The file's up axis.
    pub up: UpAxis,
    /// The file's length unit.
    pub units: Units,
}

impl ImportConfig {
    /// A file with `up` as its up axis, in `units`.
    pub fn new(up: UpAxis, units: Units) -> Self {
        Self { up, units }
    }

    /// The frame a file's format fixes ([`UpAxis::for_file`], metres), each of `up` and
    /// `units` overriding it when given: what a scene flag left unset means.
    pub fn for_file(
        path: impl AsRef<std::path::Path>,
        up: Option<UpAxis>,
        units: Option<Units>,
    ) -> Self {
        Self {
            up: up.unwrap_or_else(|| UpAxis::for_file(path)),
            units: units.unwrap_or_default(),
        }
    }
}

/// What [`import_mesh`] read and did, in metres and the library's frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportReport {
    /// Triangles read.
    pub triangles: usize,
    /// The bounding box after the conversion and the move, `[min, max]`.
    pub bounds: [[f32; 3]; 2],
    /// The floor's height before the move (z, metres, after the up axis and units).
    pub floor_height: Option<f32>,
    /// How far the scene was moved: its floor onto z = 0, its x-y box to start at 0.
    pub shift: [f32; 3],
    /// What looks wrong, each naming the flag that would fix it.
    pub warnings: Vec<String>,
    /// The file's named parts (OBJ objects and groups, glTF nodes), filled by [`read_scene`];
    /// their triangle ranges index the imported mesh, whose triangles keep the file's order.
    pub parts: Vec<crate::MeshPart>,
}

impl fmt::Display for ImportReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [lo, hi] = self.bounds;
        write!(
            f,
            "{} triangles, {:.2} x {:.2} x {:.2} m",
            self.triangles,
            hi[0] - lo[0],
            hi[1] - lo[1],
            hi[2] - lo[2]
        )?;
        match self.floor_height {
            Some(h) => write!(f, ", floor found at z = {h:.3} m")?,
            None => write!(f, ", no floor found")?,
        }
        write!(
            f,
            ", moved by ({:.3}, {:.3}, {:.3}) m",
            self.shift[0], self.shift[1], self.shift[2]
        )?;
        for w in &self.warnings {
            write!(f, "\nwarning: {w}")?;
        }
        Ok(())
    }
}

/// How much more of the furniture (a share of its area) must stand on a floor with the other
/// up axis than as read for the import to warn that the axis looks wrong.
pub const AXIS_MARGIN: f32 = 0.1;

/// A scene narrower than this (metres) is probably not in the units it was read in.
const NARROWEST_SCENE: f32 = 0.3;

/// A room wider than this (metres) is probably not in metres.
const WIDEST_ROOM: f32 = 200.0;

/// `mesh` in the library's frame: rotated so `config.up` is +z, scaled to metres, moved so its
/// floor lies at z = 0 and its x-y box starts at the origin. The floor is the lowest height
/// holding at least a tenth of the upward-facing horizontal area (2 cm bins); without one the
/// lowest point serves.
///
/// Warnings, each naming what would fix it:
/// - **The up axis** (`--up`): the loose objects (pieces of welded triangles grouped where
///   their boxes touch; walls and the floor left out) mostly stand on the floor along the
///   other axis the flag offers than along the one told (by [`AXIS_MARGIN`] of their area or
///   more). A scene without three such objects (an empty corridor, one merged mesh) gets no
///   verdict: its walls say nothing about up.
/// - **Tilt**: the largest flat surface (a quarter or more of the horizontal area) is 2
///   degrees or more off level: the whole file off level (level it), or a ramp floor (the
///   `level` example walks slopes).
/// - **Units** (`--units`): a scene hundreds of metres wide (or one stray vertex far away,
///   named), or one narrower than 0.3 m.
/// - **The floor**: nothing facing up at all, or a floor found well above the lowest point
///   where most objects stand (a floor missing from the file).
///
/// # Errors
/// [`SceneError::InvalidInput`] for an empty mesh, a bad scale, or coordinates that are not
/// finite.
pub fn import_mesh(
    mesh: &TriangleMesh,
    config: &ImportConfig,
) -> Result<(TriangleMesh, ImportReport)> {
    mesh.validate("mesh")?;
    let scale = config.units.metres();
    if !(scale.is_finite() && scale > 0.0) {
        return Err(SceneError::InvalidInput(format!(
            "units: a positive scale (got {scale})"
        )));
    }
    let to_frame = |p: &Point3<f32>| match config.up {
        // y up: (x, y, z) -> (x, -z, y), a right-handed turn about x.
        UpAxis::Y => Point3::new(p.x, -p.z, p.y) * scale,
        UpAxis::Z => Point3::new(p.x, p.y, p.z) * scale,
    };
    let mut out = TriangleMesh {
        vertices: mesh.vertices.iter().map(to_frame).collect(),
        triangles: mesh.triangles.clone(),
    };
    out.validate("the mesh in metres")?;
    out.check_extent(&format!(
        "the mesh in metres (--units: {scale:e} m per unit)"
    ))?;
    let mut warnings = Vec::new();
    // Horizontal faces (facing up or, wound the other way, down): floor candidates; and
    // the area of everything that faces up within 45 degrees (what one could walk on).
    let mut floor_bins: Vec<(i64, f32, f32)> = Vec::new();
    let mut flat: Vec<(Vector3<f32>, f32)> = Vec::new();
    let (mut walkable, mut all_area) = (0.0f32, 0.0f32);
    for t in &out.triangles {
        let [a, b, c] = t.map(|i| out.vertices[i as usize]);
        let n: Vector3<f32> = (b - a).cross(&(c - a));
        let area = 0.5 * n.norm();
        if area <= 0.0 || !area.is_finite() {
            continue;
        }
        let u = n / (2.0 * area);
        all_area += area;
        if u.z.abs() > 0.7 {
            walkable += area;
        }
        if u.z.abs() > 0.95 {
            let z = (a.z + b.z + c.z) / 3.0;
            floor_bins.push(((z / 0.02).floor() as i64, area, z));
            flat.push((u * u.z.signum(), area));
        }
    }
    // The up axis: furniture stands on the floor. Compare how much of it stands on a floor
    // read as told with how much would along the other axis the flag offers.
    let (other, other_up) = match config.up {
        UpAxis::Z => (UpAxis::Y, Vector3::y()),
        // Read as y-up, the file's z is the frame's -y.
        UpAxis::Y => (UpAxis::Z, -Vector3::y()),
    };
    // A scene off level first: tilted, its furniture stands on no level floor either way.
    let tilt = tilt(&flat);
    // Judged in metres: a scene hundreds of metres wide is read as centimetres or
    // millimetres here (its own warning names --units), so the tolerances keep their sense.
    let (blo, bhi) = bounds(&out.vertices);
    let wide = (bhi.x - blo.x).max(bhi.y - blo.y);
    let guess = [1.0, 0.01, 0.001]
        .into_iter()
        .find(|g| wide * g <= WIDEST_ROOM)
        .unwrap_or(0.001);
    let judged = if guess < 1.0 {
        std::borrow::Cow::Owned(TriangleMesh {
            vertices: out.vertices.iter().map(|v| v * guess).collect(),
            triangles: out.triangles.clone(),
        })
    } else {
        std::borrow::Cow::Borrowed(&out)
    };
    let told = resting_share(&judged, &Vector3::z());
    if let Some(t) = &tilt {
        warnings.push(t.to_string());
    } else if let (Some(told), Some(turned)) = (told, resting_share(&judged, &other_up)) {
        if turned.0 - told.0 >= AXIS_MARGIN {
            warnings.push(format!(
                "read with {} up, {:.0}% of the furniture ({} objects, by area) stands on the \
                 floor; with {other} up, {:.0}%: is the scene {other}-up? (--up {other})",
                config.up,
                (100.0 * told.0).abs(),
                told.1,
                (100.0 * turned.0).abs(),
            ));
        }
    }
    let (lo, hi) = bounds(&out.vertices);
    let floor = floor_height(&mut floor_bins);
    let floor_z = floor.unwrap_or(lo.z);
    if floor.is_none() && tilt.is_none() && walkable < 0.1 * all_area {
        warnings.push(format!(
            "nothing faces up ({:.0}% of the surface within 45 degrees of up): is the up axis \
             right (--up)?",
            100.0 * walkable / all_area.max(f32::MIN_POSITIVE)
        ));
    } else if floor.is_some()
        && floor_z - lo.z > 0.5
        && told.is_some_and(|t| t.0 < 0.5 && t.1 >= 4)
        && resting_share_on(&judged, &Vector3::z(), Some(lo.z * guess)).is_some_and(|t| t.0 >= 0.5)
    {
        // Most furniture stands at the lowest point, below the floor found: a floor missing
        // from the file (a table top taken for it), or a scene upside down.
        warnings.push(format!(
            "the floor found lies {:.2} m above the lowest point, where most furniture stands: \
              is the floor missing from the file, or the up axis wrong (--up)?",
            floor_z - lo.z
        ));
    }
    let width = (hi.x - lo.x).max(hi.y - lo.y);
    if width < NARROWEST_SCENE {
        warnings.push(format!(
            "the scene is {:.3} mm wide, too small to walk in: is it in other units than \
             {scale:e} m per unit (--units)?",
            width * 1000.0
        ));
    }
    if width > WIDEST_ROOM {
        warnings.push(match stray_vertex(&out.vertices) {
            Some((i, p, core)) => format!(
                "the scene is {width:.0} m wide, but all but a few vertices lie within \
                 {core:.1} m: vertex {i} at ({:.1}, {:.1}, {:.1}) m is a stray piece far from the \
                 rest (remove it from the file)",
                p.x, p.y, p.z
            ),
            None => format!(
                "the scene is {width:.0} m wide: is it in centimetres (--units cm) or \
                 millimetres (--units mm)?"
            ),
        });
    }
    let shift = Vector3::new(-lo.x, -lo.y, -floor_z);
    for v in &mut out.vertices {
        *v += shift;
    }
    let report = ImportReport {
        triangles: out.triangles.len(),
        bounds: [(lo + shift).into(), (hi + shift).into()],
        floor_height: floor,
        shift: shift.into(),
        warnings,
        parts: Vec::new(),
    };
    Ok((out, report))
}

/// A scene read from an OBJ, PLY or glTF file and imported with `config` ([`import_mesh`];
/// [`ImportConfig::for_file`] gives the frame the format fixes), as one object of kind
/// [`ObjectKind::Mesh`](crate::ObjectKind), with the import's report and the file's named
/// parts in it.
///
/// # Errors
/// The errors of [`TriangleMesh::read_parts`], [`import_mesh`] and
/// [`Scene::from_mesh`](crate::Scene).
pub fn read_scene(
    path: impl AsRef<std::path::Path>,
    config: &ImportConfig,
) -> Result<(crate::Scene, ImportReport)> {
    let (mesh, parts) = TriangleMesh::read_parts(path)?;
    let (mesh, mut report) = import_mesh(&mesh, config)?;
    report.parts = parts;
    Ok((crate::Scene::from_mesh("scene", &mesh)?, report))
}

/// A scene whose largest flat surface is not level: how far it tilts, about which way, and
/// whether anything level is left (a file scanned or exported off level) or not (a ramp).
#[derive(Clone, Debug, PartialEq)]
struct Tilt {
    degrees: f32,
    normal: Vector3<f32>,
    area: f32,
    level_share: f32,
}

impl fmt::Display for Tilt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.normal;
        if self.level_share < 0.2 {
            write!(
                f,
                "the scene is not level: its flat surfaces ({:.1} m2) tilt {:.1} degrees off \
                 level (they face ({:.3}, {:.3}, {:.3})): a file scanned or exported off level \
                 (turn it level) or a ramp (the `level` example walks slopes)? The floor maps, \
                 the region and the planners need a level floor",
                self.area, self.degrees, n.x, n.y, n.z
            )
        } else {
            write!(
                f,
                "the largest flat surface ({:.1} m2) slopes {:.1} degrees (it faces ({:.3}, \
                 {:.3}, {:.3})): a ramp? The floor maps, the region and the planners need level \
                 floors; the `level` example walks slopes",
                self.area, self.degrees, n.x, n.y, n.z
            )
        }
    }
}

/// Off level by at least this many degrees, the largest flat surface is said to tilt.
const TILT_DEGREES: f32 = 2.0;

/// The largest flat surface by the way it faces (up-facing normals within 18 degrees of up,
/// binned every half degree or so), when it tilts by [`TILT_DEGREES`] or more.
fn tilt(flat: &[(Vector3<f32>, f32)]) -> Option<Tilt> {
    use std::collections::HashMap;
    let mut bins: HashMap<(i32, i32), f32> = HashMap::new();
    let key = |u: &Vector3<f32>| ((u.x * 100.0).round() as i32, (u.y * 100.0).round() as i32);
    for (u, area) in flat {
        *bins.entry(key(u)).or_default() += area;
    }
    let (&(bx, by), _) = bins
        .iter()
        .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(a.0)))?;
    let (mut sum, mut area, mut level, mut total) = (Vector3::zeros(), 0.0, 0.0, 0.0);
    for (u, a) in flat {
        let (x, y) = key(u);
        if (x - bx).abs() <= 1 && (y - by).abs() <= 1 {
            sum += u * *a;
            area += a;
        }
        if u.z > 0.9997 {
            level += a;
        }
        total += a;
    }
    // A terrain's small facets are no surface of their own.
    if area < 0.25 * total {
        return None;
    }
    let normal = sum.normalize();
    let degrees = normal.z.clamp(-1.0, 1.0).acos().to_degrees();
    (degrees >= TILT_DEGREES).then_some(Tilt {
        degrees,
        normal,
        area,
        level_share: level / total,
    })
}

/// When the scene's x-y extent comes from a few far vertices: the farthest from the middle of
/// the rest, where it is, and how wide the rest is (the 0.5th to 99.5th percentile on x and
/// y, under [`WIDEST_ROOM`]).
fn stray_vertex(vertices: &[Point3<f32>]) -> Option<(usize, Point3<f32>, f32)> {
    let band = |axis: usize| {
        let mut v: Vec<f32> = vertices.iter().map(|p| p[axis]).collect();
        v.sort_by(f32::total_cmp);
        let at = |q: f32| v[((v.len() - 1) as f32 * q).round() as usize];
        (at(0.005), at(0.995))
    };
    let (x, y) = (band(0), band(1));
    let core = (x.1 - x.0).max(y.1 - y.0);
    if core > WIDEST_ROOM {
        return None;
    }
    let middle = ((x.0 + x.1) / 2.0, (y.0 + y.1) / 2.0);
    let (i, p) = vertices.iter().enumerate().max_by(|a, b| {
        let d = |p: &Point3<f32>| (p.x - middle.0).hypot(p.y - middle.1);
        d(a.1).total_cmp(&d(b.1))
    })?;
    Some((i, *p, core))
}

/// The floor's height from the horizontal faces, binned every 2 cm: the lowest band holding
/// at least a tenth of the horizontal area, or, when that band is the underside of a slab (a
/// band within 0.5 m above it holds at least half as much), the highest such band: the side
/// one stands on. A band's height is its faces' area-weighted mean.
fn floor_height(bins: &mut [(i64, f32, f32)]) -> Option<f32> {
    bins.sort_by_key(|b| b.0);
    let total: f32 = bins.iter().map(|b| b.1).sum();
    if total <= 0.0 {
        return None;
    }
    // Bands as (bin, area, mean height), lowest first.
    let mut bands: Vec<(i64, f32, f32)> = Vec::new();
    for &(bin, area, z) in bins.iter() {
        match bands.last_mut() {
            Some(last) if last.0 == bin => {
                last.2 = (last.2 * last.1 + z * area) / (last.1 + area);
                last.1 += area;
            }
            _ => bands.push((bin, area, z)),
        }
    }
    let first = bands.iter().position(|b| b.1 >= 0.1 * total)?;
    let (_, area, z) = bands[first];
    let top = bands[first..]
        .iter()
        .take_while(|b| b.2 - z <= 0.5)
        .filter(|b| b.1 >= 0.5 * area)
        .last()
        .map_or(z, |b| b.2);
    Some(top)
}

/// A connected piece of a mesh (triangles joined by welded vertices): its area, its lowest
/// and highest point along the up being judged, and its box.
#[derive(Clone, Copy)]
struct Piece {
    area: f32,
    low: f32,
    high: f32,
    min: [f32; 3],
    max: [f32; 3],
}

impl Piece {
    const EMPTY: Self = Self {
        area: 0.0,
        low: f32::MAX,
        high: f32::MIN,
        min: [f32::MAX; 3],
        max: [f32::MIN; 3],
    };

    fn touches(&self, other: &Self) -> bool {
        (0..3).all(|k| self.min[k] <= other.max[k] + 0.01 && other.min[k] <= self.max[k] + 0.01)
    }
}

/// What [`pieces`] finds.
struct Pieces {
    pieces: Vec<Piece>,
    /// Horizontal faces along the up judged, as [`floor_height`] takes them.
    bins: Vec<(i64, f32, f32)>,
    /// The lowest and highest point along that up.
    low: f32,
    high: f32,
}

/// Union-find's root of `i`, halving the path.
fn root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// The mesh's connected pieces, its vertices welded at 1 mm, with the horizontal faces
/// along `up` binned as [`floor_height`] takes them, and the lowest and highest point.
fn pieces(mesh: &TriangleMesh, up: &Vector3<f32>) -> Pieces {
    use std::collections::HashMap;
    let mut weld: HashMap<[i32; 3], usize> = HashMap::with_capacity(mesh.vertices.len());
    let id: Vec<usize> = mesh
        .vertices
        .iter()
        .map(|p| {
            let key = [p.x, p.y, p.z].map(|c| (c * 1000.0).round() as i32);
            let next = weld.len();
            *weld.entry(key).or_insert(next)
        })
        .collect();
    let mut parent: Vec<usize> = (0..weld.len()).collect();
    for t in &mesh.triangles {
        let a = root(&mut parent, id[t[0] as usize]);
        for &v in &t[1..] {
            let b = root(&mut parent, id[v as usize]);
            parent[b] = a;
        }
    }
    let mut by_root: HashMap<usize, Piece> = HashMap::new();
    let mut bins = Vec::new();
    let (mut lo, mut hi) = (f32::MAX, f32::MIN);
    for t in &mesh.triangles {
        let corners = t.map(|i| mesh.vertices[i as usize]);
        let [a, b, c] = corners;
        let n: Vector3<f32> = (b - a).cross(&(c - a));
        let area = 0.5 * n.norm();
        if !(area > 0.0 && area.is_finite()) {
            continue;
        }
        let h = corners.map(|p| p.coords.dot(up));
        let piece = by_root
            .entry(root(&mut parent, id[t[0] as usize]))
            .or_insert(Piece::EMPTY);
        piece.area += area;
        for (p, h) in corners.iter().zip(h) {
            piece.low = piece.low.min(h);
            piece.high = piece.high.max(h);
            for k in 0..3 {
                piece.min[k] = piece.min[k].min(p[k]);
                piece.max[k] = piece.max[k].max(p[k]);
            }
        }
        lo = lo.min(piece.low);
        hi = hi.max(piece.high);
        if (n / (2.0 * area)).dot(up).abs() > 0.95 {
            let z = (h[0] + h[1] + h[2]) / 3.0;
            bins.push(((z / 0.02).floor() as i64, area, z));
        }
    }
    Pieces {
        pieces: by_root.into_values().collect(),
        bins,
        low: lo,
        high: hi,
    }
}

/// How well `up` explains a scene as things standing on a floor: of the loose objects (the
/// mesh's [`pieces`] grouped where their boxes touch, as a table's top and legs or a sofa and
/// its cushions; walls, spanning most of the scene's height, the floor's own slab and what
/// hangs from the top left out), the share by area whose lowest point lies on the floor
/// found along `up` (from 5 cm below to 3 cm above it), and how many objects there are.
/// Furniture stands on the floor; along a wrong axis only what stands against one wall does.
/// `None` when fewer than three objects count.
pub(crate) fn resting_share(mesh: &TriangleMesh, up: &Vector3<f32>) -> Option<(f32, usize)> {
    resting_share_on(mesh, up, None)
}

/// [`resting_share`] on a floor at `floor` (a height along `up`) rather than the one found.
fn resting_share_on(
    mesh: &TriangleMesh,
    up: &Vector3<f32>,
    floor: Option<f32>,
) -> Option<(f32, usize)> {
    use std::collections::HashMap;
    let Pieces {
        pieces,
        mut bins,
        low: lo,
        high: hi,
    } = pieces(mesh, up);
    let floor = match floor {
        Some(f) => f.max(lo),
        None => floor_height(&mut bins)?,
    };
    let tall = 0.8 * (hi - lo);
    let mut loose: Vec<Piece> = pieces
        .into_iter()
        .filter(|p| {
            let wall = p.high - p.low >= tall;
            let slab = p.high <= floor + 0.03 && p.low >= floor - 0.3;
            !(wall || slab || p.high >= hi - 0.03)
        })
        .collect();
    // Objects: pieces whose boxes touch, swept along x.
    loose.sort_by(|p, q| p.min[0].total_cmp(&q.min[0]));
    let mut group: Vec<usize> = (0..loose.len()).collect();
    for i in 0..loose.len() {
        for j in i + 1..loose.len() {
            if loose[j].min[0] > loose[i].max[0] + 0.01 {
                break;
            }
            if loose[i].touches(&loose[j]) {
                let (a, b) = (root(&mut group, i), root(&mut group, j));
                group[b] = a;
            }
        }
    }
    // Per object: its area and its lowest point.
    let mut objects: HashMap<usize, (f32, f32)> = HashMap::new();
    for (i, p) in loose.iter().enumerate() {
        let o = objects
            .entry(root(&mut group, i))
            .or_insert((0.0, f32::MAX));
        o.0 += p.area;
        o.1 = o.1.min(p.low);
    }
    let on_floor = floor - 0.05..=floor + 0.03;
    let all: f32 = objects.values().map(|o| o.0).sum();
    let resting: f32 = objects
        .values()
        .filter(|o| on_floor.contains(&o.1))
        .map(|o| o.0)
        .sum();
    (objects.len() >= 3).then(|| (resting / all, objects.len()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 x 3 m floor, two walls, a table (a 0.75 m top on four legs), a bed and a
    /// cabinet, z up, in metres.
    fn room() -> TriangleMesh {
        boxes(&[
            ([0.0, 0.0, -0.05], [4.0, 3.0, 0.0]),
            ([0.0, -0.1, 0.0], [4.0, 0.0, 2.5]),
            ([0.0, 3.0, 0.0], [4.0, 3.1, 2.5]),
            ([1.0, 1.0, 0.72], [2.0, 2.0, 0.75]),
            ([1.0, 1.0, 0.0], [1.05, 1.05, 0.72]),
            ([1.95, 1.0, 0.0], [2.0, 1.05, 0.72]),
            ([1.0, 1.95, 0.0], [1.05, 2.0, 0.72]),
            ([1.95, 1.95, 0.0], [2.0, 2.0, 0.72]),
            ([2.5, 0.5, 0.0], [3.9, 2.5, 0.5]),
            ([0.1, 2.4, 0.0], [0.7, 2.9, 0.9]),
        ])
    }

    #[test]
    fn a_z_up_room_in_metres_comes_back_as_it_was() {
        let (out, report) = import_mesh(&room(), &ImportConfig::default()).unwrap();
        assert!(report.warnings.is_empty(), "{:?}", report.warnings);
        assert!(report.floor_height.unwrap().abs() < 0.02);
        assert!((report.bounds[1][0] - 4.0).abs() < 1e-5);
        assert_eq!(out.triangles, room().triangles);
    }

    #[test]
    fn moved_turned_and_scaled_rooms_come_back_or_warn() {
        // The same room in centimetres, y up, its floor 1 m below the origin and far away.
        let mut far = room();
        for v in &mut far.vertices {
            *v = Point3::new(v.x + 1000.0, v.z - 1.0, -v.y) * 100.0;
        }
        let config = ImportConfig {
            up: UpAxis::Y,
            units: Units::Centimetres,
        };
        let (out, report) = import_mesh(&far, &config).unwrap();
        assert!(report.warnings.is_empty(), "{:?}", report.warnings);
        assert!((report.floor_height.unwrap() + 1.0).abs() < 0.02);
        let (lo, hi) = bounds(&out.vertices);
        assert!(
            (lo.z + 0.05).abs() < 0.02 && (hi.z - 2.5).abs() < 0.02,
            "{lo} {hi}"
        );
        assert!(
            (hi.x - 4.0).abs() < 1e-3 && (hi.y - 3.2).abs() < 1e-3,
            "{hi}"
        );
        // Read with the defaults, it warns, naming the flags.
        let (_, report) = import_mesh(&far, &ImportConfig::default()).unwrap();
        let all = report.warnings.join("\n");
        assert!(all.contains("--up y"), "{all}");
        assert!(all.contains("--units cm"), "{all}");
        assert!("q".parse::<Units>().is_err() && "x".parse::<UpAxis>().is_err());
        assert_eq!("0.0254".parse::<Units>().unwrap().metres(), 0.0254);
    }
    /// Boxes as one mesh: `[min, max]` corners, each box its own piece.
    fn boxes(list: &[([f32; 3], [f32; 3])]) -> TriangleMesh {
        let mut m = TriangleMesh::default();
        for (lo, hi) in list {
            let base = m.vertices.len() as u32;
            for k in 0..8 {
                let c = |bit: usize, axis: usize| {
                    if k >> bit & 1 == 1 {
                        hi[axis]
                    } else {
                        lo[axis]
                    }
                };
                m.vertices.push(Point3::new(c(0, 0), c(1, 1), c(2, 2)));
            }
            for [a, b, c, d] in [
                [0, 2, 3, 1],
                [4, 5, 7, 6],
                [0, 1, 5, 4],
                [2, 6, 7, 3],
                [0, 4, 6, 2],
                [1, 3, 7, 5],
            ] {
                m.triangles.push([base + a, base + b, base + c]);
                m.triangles.push([base + a, base + c, base + d]);
            }
        }
        m
    }

    fn turned(mesh: &TriangleMesh, degrees: f32) -> TriangleMesh {
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), degrees.to_radians());
        TriangleMesh {
            vertices: mesh.vertices.iter().map(|v| r * v).collect(),
            triangles: mesh.triangles.clone(),
        }
    }

    /// Issue 56: right files that the facing rule took for y-up (a corridor whose long walls
    /// face y, a staircase) give no warning; a room 10 degrees off level and a ramp floor are
    /// named as such, not blamed on the axis; a scene of micrometres names `--units`.
    #[test]
    fn corridors_and_stairs_read_right_and_tilt_is_named() {
        // A 10 x 1.2 m corridor, 2.5 m high, walls and floor 0.1 m thick, a bench and a bin.
        let corridor = boxes(&[
            ([0.0, 0.0, -0.1], [10.0, 1.2, 0.0]),
            ([0.0, -0.1, 0.0], [10.0, 0.0, 2.5]),
            ([0.0, 1.2, 0.0], [10.0, 1.3, 2.5]),
            ([0.0, 0.0, 2.5], [10.0, 1.2, 2.6]),
            ([2.0, 0.0, 0.0], [3.5, 0.4, 0.45]),
            ([6.0, 0.9, 0.0], [6.3, 1.2, 0.6]),
            ([8.0, 0.0, 0.0], [9.0, 0.5, 0.75]),
        ]);
        let (_, report) = import_mesh(&corridor, &ImportConfig::default()).unwrap();
        assert!(report.warnings.is_empty(), "{report}");
        // Read as y-up, it is named.
        let (_, report) =
            import_mesh(&corridor, &ImportConfig::new(UpAxis::Y, Units::Metres)).unwrap();
        assert!(
            report.warnings.iter().any(|w| w.contains("--up z")),
            "{report}"
        );
        // Ten solid steps of 0.18 x 0.3 m, 1 m wide, on a 4 x 1 m landing.
        let mut steps = vec![([0.0, 0.0, -0.1], [4.0, 1.0, 0.0])];
        steps.extend((0..10).map(|k| {
            (
                [1.0 + 0.3 * k as f32, 0.0, 0.0],
                [4.0, 1.0, 0.18 * (k + 1) as f32],
            )
        }));
        let (_, report) = import_mesh(&boxes(&steps), &ImportConfig::default()).unwrap();
        assert!(report.warnings.is_empty(), "{report}");
        // The corridor 10 degrees off level: its tilt is named, not the axis.
        let (_, report) = import_mesh(&turned(&corridor, 10.0), &ImportConfig::default()).unwrap();
        let all = report.warnings.join("\n");
        assert!(
            all.contains("not level") && all.contains("10.0 degrees"),
            "{all}"
        );
        assert!(!all.contains("--up"), "{all}");
        // A 4 x 3 m ramp rising 10 degrees beside a 2 x 3 m level landing.
        let mut ramp = boxes(&[([4.0, 0.0, -0.1], [6.0, 3.0, 0.0])]);
        let rise = 4.0 * 10f32.to_radians().tan();
        let base = ramp.vertices.len() as u32;
        for (x, z) in [(0.0, 0.0), (4.0, rise)] {
            ramp.vertices.push(Point3::new(x, 0.0, z - rise));
            ramp.vertices.push(Point3::new(x, 3.0, z - rise));
        }
        ramp.triangles
            .extend([[base, base + 2, base + 3], [base, base + 3, base + 1]]);
        let (_, report) = import_mesh(&ramp, &ImportConfig::default()).unwrap();
        let all = report.warnings.join("\n");
        assert!(
            all.contains("slopes 10.0 degrees") && all.contains("`level`"),
            "{all}"
        );
        // The room in micrometres read as metres.
        let (_, report) =
            import_mesh(&corridor, &ImportConfig::new(UpAxis::Z, Units::Scale(1e-6))).unwrap();
        assert!(
            report.warnings.iter().any(|w| w.contains("--units")),
            "{report}"
        );
    }
}
