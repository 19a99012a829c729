//! Triangle meshes and their OBJ / PLY input and output.

use std::fmt::Write as _;
use std::path::Path;

use nalgebra::Point3;

use crate::error::{Result, SceneError};

/// A named run of a mesh's triangles: an OBJ file's object or group (`o`, `g`), a glTF node
/// that holds a mesh. Reading a file keeps them ([`TriangleMesh::read_parts`]) so later steps
/// can tell the pieces of a scene apart.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MeshPart {
    /// The object's, group's or node's name (a glTF node without one: its mesh's, or
    /// `node N`).
    pub name: String,
    /// Its triangles, indices into [`TriangleMesh::triangles`].
    pub triangles: std::ops::Range<usize>,
}

/// The largest coordinate a scene in metres may hold on any axis
/// ([`TriangleMesh::check_extent`]): 1e6, a thousand kilometres, past which `f32` steps are coarser than 6 cm and the
/// geometry library's bounding volumes lose their meaning.
pub const MAX_COORDINATE: f32 = 1.0e6;

/// A triangle soup with shared vertices: what OBJ and PLY files hold.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions in metres.
    pub vertices: Vec<Point3<f32>>,
    /// Counter-clockwise (seen from outside) vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// An axis-aligned cube of side `side` centred at the origin, normals outwards.
    pub fn cube(side: f32) -> Self {
        let h = side / 2.0;
        let vertices = (0..8)
            .map(|i| {
                Point3::new(
                    if i & 1 == 0 { -h } else { h },
                    if i & 2 == 0 { -h } else { h },
                    if i & 4 == 0 { -h } else { h },
                )
            })
            .collect();
        let triangles = vec![
            [0, 2, 1],
            [1, 2, 3], // z = -h
            [4, 5, 6],
            [5, 7, 6], // z = +h
            [0, 1, 4],
            [1, 5, 4], // y = -h
            [2, 6, 3],
            [3, 6, 7], // y = +h
            [0, 4, 2],
            [2, 4, 6], // x = -h
            [1, 3, 5],
            [3, 7, 5], // x = +h
        ];
        Self {
            vertices,
            triangles,
        }
    }

    /// Appends another mesh (its indices shifted).
    pub fn append(&mut self, other: &TriangleMesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }

    /// Total surface area in square metres.
    pub fn area(&self) -> f32 {
        self.triangles.iter().map(|t| self.triangle_area(t)).sum()
    }

    pub(crate) fn triangle_area(&self, t: &[u32; 3]) -> f32 {
        let [a, b, c] = t.map(|i| self.vertices[i as usize]);
        (b - a).cross(&(c - a)).norm() / 2.0
    }

    /// Checks that there is a triangle, every vertex is finite and every index in range.
    ///
    /// # Errors
    /// [`SceneError::EmptyMesh`] or [`SceneError::InvalidGeometry`] naming the vertex or triangle.
    pub fn validate(&self, what: &str) -> Result<()> {
        if self.triangles.is_empty() {
            return Err(SceneError::EmptyMesh(what.to_string()));
        }
        if let Some(i) = self
            .vertices
            .iter()
            .position(|v| !v.iter().all(|c| c.is_finite()))
        {
            return Err(SceneError::InvalidGeometry(format!(
                "{what}: vertex {i} is not finite"
            )));
        }

        let n = self.vertices.len() as u32;
        if let Some(i) = self
            .triangles
            .iter()
            .position(|t| t.iter().any(|&v| v >= n))
        {
            return Err(SceneError::InvalidGeometry(format!(
                "{what}: triangle {i} {:?} refers to a vertex beyond the {n} vertices",
                self.triangles[i]
            )));
        }
        Ok(())
    }

    /// Checks that every vertex lies within [`MAX_COORDINATE`] metres of the origin on each
    /// axis: what a scene in metres must hold before the geometry library sees it
    /// ([`Part::mesh`](crate::Part::mesh) and [`import_mesh`](crate::import_mesh) call it).
    ///
    /// # Errors
    /// [`SceneError::InvalidGeometry`] naming the first vertex beyond, and where it is.
    pub fn check_extent(&self, what: &str) -> Result<()> {
        match self
            .vertices
            .iter()
            .enumerate()
            .find(|(_, v)| v.iter().any(|c| c.abs() > MAX_COORDINATE))
        {
            Some((i, v)) => Err(SceneError::InvalidGeometry(format!(
                "{what}: vertex {i} at ({:e}, {:e}, {:e}) m lies beyond {MAX_COORDINATE:e} m on \
                 an axis, where single precision cannot tell a centimetre apart: remove the \
                 stray piece, or give the right --units",
                v.x, v.y, v.z
            ))),
            None => Ok(()),
        }
    }

    /// Reads an OBJ, PLY or glTF (`.gltf`, `.glb`) file, chosen by the extension, in the
    /// file's own frame (a glTF file's is +y up, [`UpAxis::for_file`](crate::UpAxis::for_file)).
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for another extension, and the errors of
    /// [`TriangleMesh::read_obj`], [`TriangleMesh::read_ply`] and [`crate::read_gltf`].
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        Ok(Self::read_parts(path)?.0)
    }

    /// [`TriangleMesh::read`] with the file's named parts: OBJ objects and groups, glTF nodes
    /// holding meshes (a PLY file is one part, named after the file).
    ///
    /// # Errors
    /// As [`TriangleMesh::read`].
    pub fn read_parts(path: impl AsRef<Path>) -> Result<(Self, Vec<MeshPart>)> {
        let path = path.as_ref();
        match extension(path).as_deref() {
            Some("obj") => {
                let bytes = std::fs::read(path).map_err(|source| io(path, source))?;
                Self::parse_obj_parts(&String::from_utf8_lossy(&bytes), path)
            }
            Some("ply") => {
                let mesh = Self::read_ply(path)?;
                let name = path
                    .file_stem()
                    .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
                let part = MeshPart {
                    name,
                    triangles: 0..mesh.triangles.len(),
                };
                Ok((mesh, vec![part]))
            }
            Some("gltf" | "glb") => crate::read_gltf(path),
            _ => Err(SceneError::InvalidInput(format!(
                "{}: expected a .obj, .ply, .gltf or .glb scene",
                path.display()
            ))),
        }
    }

    /// Writes an OBJ or PLY file (chosen by the extension), atomically.
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for another extension; I/O errors.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        match extension(path).as_deref() {
            Some("obj") => self.write_obj(path),
            Some("ply") => self.write_ply(path),
            _ => Err(SceneError::InvalidInput(format!(
                "{}: expected a .obj or .ply mesh",
                path.display()
            ))),
        }
    }

    /// Reads the vertices (`v`) and faces (`f`, polygons fanned into triangles, `v/vt/vn` and
    /// negative indices accepted) of a Wavefront OBJ file; other statements are ignored, and
    /// so are faces of one or two vertices, which some exporters write for lines and points
    /// (they hold no surface).
    ///
    /// # Errors
    /// [`SceneError::Parse`] naming the line of a malformed vertex or face, or a face index out
    /// of range; [`SceneError::EmptyMesh`] without faces; [`SceneError::Io`].
    pub fn read_obj(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        // Bytes that are not UTF-8 (a Latin-1 comment or material name) are never numbers.
        let bytes = std::fs::read(path).map_err(|source| io(path, source))?;
        Self::parse_obj(&String::from_utf8_lossy(&bytes), path)
    }

    /// Parses OBJ text as [`TriangleMesh::read_obj`] does; `source` names it in errors.
    ///
    /// # Errors
    /// As [`TriangleMesh::read_obj`], without the I/O.
    pub fn parse_obj(text: &str, source: impl AsRef<Path>) -> Result<Self> {
        Ok(Self::parse_obj_parts(text, source)?.0)
    }

    /// [`TriangleMesh::parse_obj`] with the file's objects and groups (`o`, `g`; the faces
    /// before the first are a part named after nothing, kept only if it holds any).
    ///
    /// # Errors
    /// As [`TriangleMesh::parse_obj`].
    pub fn parse_obj_parts(text: &str, source: impl AsRef<Path>) -> Result<(Self, Vec<MeshPart>)> {
        let path = source.as_ref();
        let mut parts = vec![MeshPart {
            name: String::new(),
            triangles: 0..0,
        }];
        let err = |line: usize, reason: String| SceneError::Parse {
            path: path.to_path_buf(),
            line,
            reason,
        };
        let mut mesh = TriangleMesh::default();
        for (n, line) in text.lines().enumerate() {
            let n = n + 1;
            let mut words = line.split_whitespace();
            match words.next() {
                Some("v") => {
                    let c: Vec<f32> = words
                        .take(3)
                        .map(|w| w.parse::<f32>())
                        .collect::<std::result::Result<_, _>>()
                        .map_err(|e| err(n, format!("bad vertex coordinate: {e}")))?;
                    if c.len() != 3 || !c.iter().all(|v| v.is_finite()) {
                        return Err(err(
                            n,
                            format!("a vertex needs 3 finite coordinates: `{line}`"),
                        ));
                    }
                    mesh.vertices.push(Point3::new(c[0], c[1], c[2]));
                }
                Some("f") => {
                    let count = mesh.vertices.len() as i64;
                    let idx: Vec<u32> = words
                        .map(|w| {
                            let first = w.split('/').next().unwrap_or("");
                            let i: i64 = first
                                .parse()
                                .map_err(|_| err(n, format!("bad face index `{w}`")))?;
                            let i = if i < 0 { count + i } else { i - 1 };
                            if i < 0 || i >= count {
                                return Err(err(
                                    n,
                                    format!("face index `{w}` is outside the {count} vertices read so far"),
                                ));
                            }
                            Ok(i as u32)
                        })
                        .collect::<Result<_>>()?;
                    if idx.is_empty() {
                        return Err(err(n, format!("a face without vertices: `{line}`")));
                    }
                    for k in 1..idx.len() - 1 {
                        mesh.triangles.push([idx[0], idx[k], idx[k + 1]]);
                    }
                }
                Some("o" | "g") => {
                    let name = words.collect::<Vec<_>>().join(" ");
                    let at = mesh.triangles.len();
                    if let Some(last) = parts.last_mut() {
                        last.triangles.end = at;
                    }
                    parts.push(MeshPart {
                        name,
                        triangles: at..at,
                    });
                }
                _ => {}
            }
        }
        mesh.validate(&path.display().to_string())?;
        if let Some(last) = parts.last_mut() {
            last.triangles.end = mesh.triangles.len();
        }
        parts.retain(|p| !p.triangles.is_empty());
        Ok((mesh, parts))
    }

    /// Reads a PLY file: ASCII or binary little/big endian, a `vertex` element with float or
    /// double `x`, `y`, `z` (other properties skipped), and a `face` element whose first list
    /// property holds the vertex indices (polygons fanned into triangles).
    ///
    /// # Errors
    /// [`SceneError::Parse`] for a malformed header or body (line 0 in binary bodies);
    /// [`SceneError::EmptyMesh`] without faces; [`SceneError::Io`].
    pub fn read_ply(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|source| io(path, source))?;
        crate::ply::parse(&bytes, path)
    }

    /// Parses PLY bytes as [`TriangleMesh::read_ply`] does; `source` names them in errors.
    ///
    /// # Errors
    /// As [`TriangleMesh::read_ply`], without the I/O.
    pub fn parse_ply(bytes: &[u8], source: impl AsRef<Path>) -> Result<Self> {
        crate::ply::parse(bytes, source.as_ref())
    }

    /// Writes a Wavefront OBJ file atomically.
    ///
    /// # Errors
    /// I/O errors.
    pub fn write_obj(&self, path: impl AsRef<Path>) -> Result<()> {
        let mut s = String::from("# envfield-scene\n");
        for v in &self.vertices {
            let _ = writeln!(s, "v {} {} {}", v.x, v.y, v.z);
        }
        for t in &self.triangles {
            let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        envfield_grid::write_atomic(path, s.as_bytes())?;
        Ok(())
    }

    /// Writes a binary little-endian PLY file atomically.
    ///
    /// # Errors
    /// I/O errors.
    pub fn write_ply(&self, path: impl AsRef<Path>) -> Result<()> {
        let mut out = format!(
            "ply\nformat binary_little_endian 1.0\ncomment envfield-scene\nelement vertex {}\n\
             property float x\nproperty float y\nproperty float z\nelement face {}\n\
             property list uchar int vertex_indices\nend_header\n",
            self.vertices.len(),
            self.triangles.len()
        )
        .into_bytes();
        for v in &self.vertices {
            for c in v.iter() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        for t in &self.triangles {
            out.push(3);
            for &i in t {
                out.extend_from_slice(&(i as i32).to_le_bytes());
            }
        }
        envfield_grid::write_atomic(path, &out)?;
        Ok(())
    }
}

/// Writes points (a sampled point cloud, a region's voxels) as an ASCII PLY file, atomically;
/// with `colours`, one RGB colour per point as `red`, `green`, `blue`.
///
/// # Errors
/// [`SceneError::InvalidInput`] for colours that are not one per point; I/O errors.
pub fn write_point_cloud(
    points: &[Point3<f32>],
    colours: Option<&[[u8; 3]]>,
    path: impl AsRef<Path>,
) -> Result<()> {
    if let Some(c) = colours.filter(|c| c.len() != points.len()) {
        return Err(SceneError::InvalidInput(format!(
            "a point cloud of {} points given {} colours",
            points.len(),
            c.len()
        )));
    }
    let colour_header = if colours.is_some() {
        "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    } else {
        ""
    };
    let mut s = format!(
        "ply\nformat ascii 1.0\ncomment envfield-scene points\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n{colour_header}end_header\n",
        points.len()
    );
    for (i, p) in points.iter().enumerate() {
        let _ = write!(s, "{} {} {}", p.x, p.y, p.z);
        if let Some([r, g, b]) = colours.map(|c| c[i]) {
            let _ = write!(s, " {r} {g} {b}");
        }
        s.push('\n');
    }
    envfield_grid::write_atomic(path, s.as_bytes())?;
    Ok(())
}

/// Writes a path (a polyline through `points`) as an OBJ file with one `l` element, atomically.
///
/// # Errors
/// [`SceneError::InvalidInput`] for fewer than 2 points; I/O errors.
pub fn write_polyline_obj(points: &[Point3<f32>], path: impl AsRef<Path>) -> Result<()> {
    if points.len() < 2 {
        return Err(SceneError::InvalidInput(format!(
            "a polyline needs at least 2 points, got {}",
            points.len()
        )));
    }
    let mut s = String::from("# envfield-scene path\n");
    for p in points {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    }
    s.push('l');
    for i in 1..=points.len() {
        let _ = write!(s, " {i}");
    }
    s.push('\n');
    envfield_grid::write_atomic(path, s.as_bytes())?;
    Ok(())
}

fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
}

pub(crate) fn io(path: &Path, source: std::io::Error) -> SceneError {
    SceneError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// The corners `(min, max)` of the box around `points` (infinite and inverted for none).
pub(crate) fn bounds(points: &[Point3<f32>]) -> (Point3<f32>, Point3<f32>) {
    let mut lo = Point3::from([f32::INFINITY; 3]);
    let mut hi = Point3::from([f32::NEG_INFINITY; 3]);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_faces_are_fanned_and_checked() {
        let p = Path::new("t.obj");
        let m =
            TriangleMesh::parse_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3/3 -1\n", p)
                .unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        let e = TriangleMesh::parse_obj("v 0 0 0\nv 1 0 0\nf 1 2 3\n", p).unwrap_err();
        assert!(e.to_string().contains("line 3"), "{e}");
        let e = TriangleMesh::parse_obj("v 0 0 nan\n", p).unwrap_err();
        assert!(e.to_string().contains("line 1"), "{e}");
        let e = TriangleMesh::parse_obj("# nothing\n", p).unwrap_err();
        assert!(matches!(e, SceneError::EmptyMesh(_)), "{e}");
    }
}
