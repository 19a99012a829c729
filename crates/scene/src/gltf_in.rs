//! glTF 2.0 scenes in: `.gltf` (buffers external or embedded as data URIs) and `.glb`, with
//! the `gltf` crate reading the document and its buffers. Every mesh primitive of the
//! default scene (the first scene without one) is read with its node transforms composed down
//! the tree; triangles, triangle strips and fans, indexed or not; points and lines hold no
//! surface and are skipped. Coordinates stay in the file's frame (+y up, metres, by the
//! specification): [`crate::import_mesh`] turns them.
//!
//! Every accessor is read with checked offsets and lengths against its buffer, so a file whose
//! numbers do not fit is refused, naming the part, never read out of bounds.

use std::path::Path;

use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use nalgebra::{Matrix4, Point3};

use crate::error::{Result, SceneError};
use crate::mesh::{io, MeshPart};
use crate::TriangleMesh;

/// Extensions whose data this reader cannot decode, and what each is.
const UNREADABLE: [(&str, &str); 3] = [
    ("KHR_draco_mesh_compression", "Draco-compressed meshes"),
    ("EXT_meshopt_compression", "meshopt-compressed buffers"),
    (
        "KHR_mesh_quantization",
        "quantized (integer) vertex positions",
    ),
];

/// Nodes nested deeper than this are refused (a cycle, or a file built to exhaust the stack).
const DEEPEST: usize = 256;

/// Reads a `.gltf` or `.glb` file: the triangles of its default scene in the file's frame,
/// and one [`MeshPart`] per node that holds a mesh, named after the node (or its mesh).
///
/// # Errors
/// [`SceneError::Io`] when the file cannot be read; [`SceneError::Gltf`] naming the part for
/// a malformed document, a missing or short buffer, compressed or quantized geometry
/// (Draco, meshopt), sparse accessors, indices out of range, a node tree that loops;
/// [`SceneError::EmptyMesh`] when the scene holds no triangles.
pub fn read_gltf(path: impl AsRef<Path>) -> Result<(TriangleMesh, Vec<MeshPart>)> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| io(path, source))?;
    parse_gltf(&bytes, path.parent(), path)
}

/// Parses glTF bytes (JSON or binary) as [`read_gltf`] does; external buffers are read from
/// `base` (none allowed without it); `source` names the file in errors.
///
/// # Errors
/// As [`read_gltf`].
pub fn parse_gltf(
    bytes: &[u8],
    base: Option<&Path>,
    source: impl AsRef<Path>,
) -> Result<(TriangleMesh, Vec<MeshPart>)> {
    let path = source.as_ref();
    let err = |part: &str, reason: String| SceneError::Gltf {
        path: path.to_path_buf(),
        part: part.to_string(),
        reason,
    };
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| err("document", e.to_string()))?;
    for required in gltf.extensions_required() {
        if let Some((_, what)) = UNREADABLE.iter().find(|(name, _)| *name == required) {
            return Err(err(
                "extensionsRequired",
                format!("{required}: {what} cannot be read; export the scene without it"),
            ));
        }
    }
    validate(gltf.document.as_json()).map_err(|reason| err("document", reason))?;
    let document = &gltf.document;
    // A buffer's file must be a plain file beside the scene: never a device or a folder.
    for buffer in document.buffers() {
        if let gltf::buffer::Source::Uri(uri) = buffer.source() {
            if uri.starts_with("data:") {
                continue;
            }
            let part = format!("buffer {}", buffer.index());
            let Some(base) = base else {
                return Err(err(
                    &part,
                    format!("`{uri}` is a file, and no folder was given"),
                ));
            };
            let file = base.join(uri);
            match std::fs::metadata(&file) {
                Ok(m) if m.is_file() => {}
                Ok(_) => return Err(err(&part, format!("`{}` is not a file", file.display()))),
                Err(e) => return Err(err(&part, format!("`{}`: {e}", file.display()))),
            }
        }
    }
    let buffers = gltf::import_buffers(document, base, gltf.blob.clone())
        .map_err(|e| err("buffers", e.to_string()))?;
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .ok_or_else(|| err("scenes", "the file holds no scene".into()))?;

    let mut mesh = TriangleMesh::default();
    let mut parts = Vec::new();
    let mut skipped = 0;
    let mut stack: Vec<(gltf::Node, Matrix4<f32>, usize)> =
        scene.nodes().map(|n| (n, Matrix4::identity(), 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > DEEPEST {
            return Err(err(
                &format!("node {}", node.index()),
                format!("nodes nested more than {DEEPEST} deep: does the tree loop?"),
            ));
        }
        let local = Matrix4::from_column_slice(node.transform().matrix().as_flattened());
        let world = parent * local;
        if let Some(m) = node.mesh() {
            let first = mesh.triangles.len();
            for primitive in m.primitives() {
                let part = format!(
                    "mesh {} (`{}`) primitive {}",
                    m.index(),
                    m.name().unwrap_or(""),
                    primitive.index()
                );
                if !read_primitive(&primitive, &buffers, &world, &mut mesh)
                    .map_err(|reason| err(&part, reason))?
                {
                    skipped += 1;
                }
            }
            let name = node
                .name()
                .or(m.name())
                .map_or_else(|| format!("node {}", node.index()), str::to_string);
            parts.push(MeshPart {
                name,
                triangles: first..mesh.triangles.len(),
            });
        }
        stack.extend(node.children().map(|c| (c, world, depth + 1)));
    }
    if mesh.triangles.is_empty() && skipped > 0 {
        return Err(err(
            "meshes",
            format!("its {skipped} primitives are all points or lines: no surface to stand on"),
        ));
    }
    mesh.validate(&path.display().to_string())?;
    Ok((mesh, parts))
}

/// The glTF crate's checks of the document (every index in range, required fields there,
/// required extensions supported), but for the `min` and `max` of vertex positions, which
/// many exporters leave out and nothing here reads. The first few problems, and how many.
fn validate(root: &gltf::json::Root) -> std::result::Result<(), String> {
    use gltf::json::validation::{Error, Validate};
    // The crate's check of a primitive's POSITION reads its accessor before checking that the
    // accessor exists (gltf-json 1.4.1, mesh.rs): check every accessor a primitive names first.
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let named = primitive
                .attributes
                .values()
                .chain(primitive.indices.as_ref());
            if let Some(bad) = named.map(|i| i.value()).find(|&i| i >= accessors) {
                return Err(format!(
                    "invalid glTF: meshes[{m}].primitives[{p}] names accessor {bad} of {accessors}"
                ));
            }
        }
    }
    let mut problems = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path().to_string();
        let bounds = path.ends_with("[\"POSITION\"].min") || path.ends_with("[\"POSITION\"].max");
        if !(bounds && matches!(error, Error::Missing)) {
            problems.push(format!("{path}: {error}"));
        }
    });
    if problems.is_empty() {
        return Ok(());
    }
    let shown = problems.len().min(3);
    let mut text = problems[..shown].join("; ");
    if problems.len() > shown {
        text.push_str(&format!("; and {} more", problems.len() - shown));
    }
    Err(format!("invalid glTF: {text}"))
}

/// Appends one primitive's triangles, its positions moved by `world`; `false` for points
/// and lines, which hold no surface and are skipped.
fn read_primitive(
    primitive: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    world: &Matrix4<f32>,
    mesh: &mut TriangleMesh,
) -> std::result::Result<bool, String> {
    let mode = primitive.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(false);
    }
    let positions = primitive
        .get(&gltf::Semantic::Positions)
        .ok_or("no POSITION attribute")?;
    if positions.data_type() != DataType::F32 || positions.dimensions() != Dimensions::Vec3 {
        return Err(format!(
            "POSITION is {:?} of {:?}: expected VEC3 of floats",
            positions.dimensions(),
            positions.data_type()
        ));
    }
    let bytes = accessor_elements(&positions, buffers, 12).map_err(|e| format!("POSITION: {e}"))?;
    let base = mesh.vertices.len();
    for e in &bytes {
        let c = |k: usize| f32::from_le_bytes([e[4 * k], e[4 * k + 1], e[4 * k + 2], e[4 * k + 3]]);
        let p = world.transform_point(&Point3::new(c(0), c(1), c(2)));
        mesh.vertices.push(p);
    }
    let count = bytes.len();
    let indices: Vec<u32> = match primitive.indices() {
        None => (0..count as u32).collect(),
        Some(acc) => {
            if acc.dimensions() != Dimensions::Scalar {
                return Err(format!(
                    "indices are {:?}: expected SCALAR",
                    acc.dimensions()
                ));
            }
            let size = match acc.data_type() {
                DataType::U8 => 1,
                DataType::U16 => 2,
                DataType::U32 => 4,
                t => return Err(format!("indices of {t:?}: expected unsigned integers")),
            };
            let elements =
                accessor_elements(&acc, buffers, size).map_err(|e| format!("indices: {e}"))?;
            elements
                .iter()
                .map(|e| match size {
                    1 => u32::from(e[0]),
                    2 => u32::from(u16::from_le_bytes([e[0], e[1]])),
                    _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
                })
                .collect()
        }
    };
    if let Some((k, &i)) = indices
        .iter()
        .enumerate()
        .find(|(_, &i)| i as usize >= count)
    {
        return Err(format!("index {k} is {i}, beyond the {count} vertices"));
    }
    let tri = |a: u32, b: u32, c: u32| [a, b, c].map(|i| (base + i as usize) as u32);
    let n = indices.len();
    match mode {
        Mode::Triangles => {
            for t in indices.chunks_exact(3) {
                mesh.triangles.push(tri(t[0], t[1], t[2]));
            }
        }
        Mode::TriangleStrip => {
            for i in 0..n.saturating_sub(2) {
                let (a, b) = if i % 2 == 0 { (i, i + 1) } else { (i + 1, i) };
                mesh.triangles
                    .push(tri(indices[a], indices[b], indices[i + 2]));
            }
        }
        _ => {
            for i in 1..n.saturating_sub(1) {
                mesh.triangles
                    .push(tri(indices[0], indices[i], indices[i + 1]));
            }
        }
    }
    if u32::try_from(mesh.vertices.len()).is_err() {
        return Err("more than 4 billion vertices".into());
    }
    Ok(true)
}

/// The accessor's elements, `size` bytes each, every offset and length checked against its
/// buffer view and buffer.
fn accessor_elements<'a>(
    accessor: &gltf::Accessor,
    buffers: &'a [gltf::buffer::Data],
    size: usize,
) -> std::result::Result<Vec<&'a [u8]>, String> {
    if accessor.sparse().is_some() {
        return Err("sparse accessors are not read".into());
    }
    let count = accessor.count();
    if count == 0 {
        return Ok(Vec::new());
    }
    let view = accessor
        .view()
        .ok_or("no buffer view (compressed data, or all zeros): not read")?;
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "byteStride {stride} is below the element size {size}"
        ));
    }
    let buffer = buffers
        .get(view.buffer().index())
        .ok_or("its buffer is missing")?;
    let span = stride
        .checked_mul(count - 1)
        .and_then(|s| s.checked_add(size))
        .ok_or("its length overflows")?;
    let start = view
        .offset()
        .checked_add(accessor.offset())
        .ok_or("offset overflows")?;
    let view_end = view
        .offset()
        .checked_add(view.length())
        .ok_or("view overflows")?;
    let end = start.checked_add(span).ok_or("its end overflows")?;
    if end > view_end || view_end > buffer.len() {
        return Err(format!(
            "{count} elements at byte {start} need {span} bytes, past its buffer view \
             (bytes {}..{view_end}) or its buffer ({} bytes)",
            view.offset(),
            buffer.len()
        ));
    }
    Ok((0..count)
        .map(|i| &buffer[start + i * stride..start + i * stride + size])
        .collect())
}
