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

/// A room wider than this (metres) is probably not in metres.
const WIDEST_ROOM: f32 = 200.0;

/// `mesh` in the library's frame: rotated so `config.up` is +z, scaled to metres, moved so its
/// floor lies at z = 0 and its x-y box starts at the origin. The floor is the lowest height
/// holding at least a tenth of the upward-facing horizontal area (2 cm bins); without one the
/// lowest point serves, and a warning says so. Other warnings: a scene whose flat surfaces
/// mostly face another axis than up (`--up`), one hundreds of metres wide (`--units`), a floor
/// far above the lowest point.
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
    // Flat surfaces by the axis they face: a scene is mostly floors, seats and table tops.
    let mut facing = [0f32; 3];
    let mut floor_bins: Vec<(i64, f32, f32)> = Vec::new();
    for t in &out.triangles {
        let [a, b, c] = t.map(|i| out.vertices[i as usize]);
        let n: Vector3<f32> = (b - a).cross(&(c - a));
        let area = 0.5 * n.norm();
        if area <= 0.0 || !area.is_finite() {
            continue;
        }
        let u = n / (2.0 * area);
        for (axis, f) in facing.iter_mut().enumerate() {
            if u[axis].abs() > 0.95 {
                *f += area;
            }
        }
        // An upward (or, wound the other way, downward) horizontal face: a floor candidate.
        if u.z.abs() > 0.95 {
            let z = (a.z + b.z + c.z) / 3.0;
            floor_bins.push(((z / 0.02).floor() as i64, area, z));
        }
    }
    // In the library's frame, most flat surfaces should face up.
    if facing[1] > 2.0 * facing[2] && facing[1] > facing[0] {
        warnings.push(
            match config.up {
                UpAxis::Z => "most flat surfaces face along y, not z: is the scene y-up? (--up y)",
                UpAxis::Y => {
                    "read as y-up, most flat surfaces face along the file's z: is it z-up? \
                          (--up z)"
                }
            }
            .to_string(),
        );
    }
    let (lo, hi) = bounds(&out.vertices);
    let floor = floor_height(&mut floor_bins);
    let floor_z = floor.unwrap_or(lo.z);
    if floor.is_none() {
        warnings.push("no horizontal floor found: the lowest point is taken as the floor".into());
    } else if floor_z - lo.z > 0.5 {
        warnings.push(format!(
            "the floor found lies {:.2} m above the lowest point: is the up axis right (--up)?",
            floor_z - lo.z
        ));
    }
    let width = (hi.x - lo.x).max(hi.y - lo.y);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 x 3 m floor, a 0.75 m table top and a low wall, z up, in metres.
    fn room() -> TriangleMesh {
        let mut m = TriangleMesh::default();
        let mut quad = |p: [[f32; 3]; 4]| {
            let base = m.vertices.len() as u32;
            m.vertices
                .extend(p.iter().map(|v| Point3::new(v[0], v[1], v[2])));
            m.triangles.push([base, base + 1, base + 2]);
            m.triangles.push([base, base + 2, base + 3]);
        };
        quad([[0., 0., 0.], [4., 0., 0.], [4., 3., 0.], [0., 3., 0.]]);
        quad([
            [1., 1., 0.75],
            [2., 1., 0.75],
            [2., 2., 0.75],
            [1., 2., 0.75],
        ]);
        quad([[0., 0., 0.], [4., 0., 0.], [4., 0., 1.0], [0., 0., 1.0]]);
        m
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
        assert!(lo.z.abs() < 0.02 && (hi.z - 1.0).abs() < 0.02, "{lo} {hi}");
        assert!(
            (hi.x - 4.0).abs() < 1e-3 && (hi.y - 3.0).abs() < 1e-3,
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
}
