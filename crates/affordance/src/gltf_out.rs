//! Animated people out as glTF 2.0 binary (`.glb`): a scene's geometry and every person as a
//! node hierarchy of the skeleton's joints (SMPL's tree, each joint a node placed relative to
//! its parent, drawn as a ball) with a bone from each joint to each child (a cylinder node
//! turned and stretched to reach it), and one animation per person, its keys at the
//! sequence's frame rate. In glTF's frame: metres, +y up (the library's +z), +z towards the
//! viewer (the library's -y). three.js, Bevy and Blender play or import it as it is; the
//! Khronos glTF-Validator passes it with no error (`scripts/validate_gltf.sh`).

use std::path::Path;

use nalgebra::{Point3, Unit, UnitQuaternion, Vector3};
use serde_json::{json, Value};

use crate::error::{AffordanceError, Result};
use crate::skeleton::{Joint, PoseSequence, JOINT_COUNT};
use envfield_scene::TriangleMesh;

/// One person to animate: a name and the poses they move through (library frame: z up).
#[derive(Clone, Copy, Debug)]
pub struct Actor<'a> {
    /// The person's node and animation name.
    pub name: &'a str,
    /// Their poses at the sequence's frame rate; the animation starts at time 0.
    pub poses: &'a PoseSequence,
}

/// The library's frame (z up) to glTF's (y up): a right-handed turn about x.
fn to_gltf(p: Point3<f32>) -> [f32; 3] {
    [p.x, p.z, -p.y]
}

/// Colours the people wear, in turn (linear RGB).
const COLOURS: [[f32; 3]; 6] = [
    [0.85, 0.25, 0.15],
    [0.15, 0.40, 0.85],
    [0.15, 0.65, 0.25],
    [0.85, 0.60, 0.10],
    [0.55, 0.25, 0.75],
    [0.10, 0.65, 0.70],
];

/// Radius of a joint's ball and its bones (metres): the head larger, the trunk thicker.
fn radius(joint: Joint) -> f32 {
    use Joint::*;
    match joint {
        Head => 0.1,
        Pelvis | Spine1 | Spine2 | Spine3 | LeftHip | RightHip => 0.08,
        Neck | LeftCollar | RightCollar => 0.06,
        _ => 0.05,
    }
}

/// The binary buffer and its views and accessors, built together.
#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    /// A view over `bytes` (padded to 4 bytes), with its target when it holds vertices or
    /// indices.
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = t.into();
        }
        self.views.push(v);
        self.views.len() - 1
    }

    /// An accessor of float vectors of `width` components (`kind`: VEC3, VEC4, SCALAR), with
    /// their bounds.
    fn floats(&mut self, values: &[f32], width: usize, kind: &str, target: Option<u32>) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let mut min = vec![f32::INFINITY; width];
        let mut max = vec![f32::NEG_INFINITY; width];
        for chunk in values.chunks_exact(width) {
            for k in 0..width {
                min[k] = min[k].min(chunk[k]);
                max[k] = max[k].max(chunk[k]);
            }
        }
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5126, "count": values.len() / width,
            "type": kind, "min": min, "max": max,
        }));
        self.accessors.len() - 1
    }

    fn indices(&mut self, values: &[u32]) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(34963));
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5125, "count": values.len(), "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }

    /// A mesh's positions and indices: (POSITION accessor, indices accessor).
    fn mesh(&mut self, vertices: &[[f32; 3]], triangles: &[[u32; 3]]) -> (usize, usize) {
        let flat: Vec<f32> = vertices.iter().flatten().copied().collect();
        let positions = self.floats(&flat, 3, "VEC3", Some(34962));
        let flat: Vec<u32> = triangles.iter().flatten().copied().collect();
        (positions, self.indices(&flat))
    }
}

/// A ball of radius 1 at the origin.
fn ball() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let (rings, segments) = (8u32, 12u32);
    let mut v = Vec::new();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            v.push([
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            ]);
        }
    }
    let mut t = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b) = (i * segments + j, i * segments + (j + 1) % segments);
            let (c, d) = (a + segments, b + segments);
            if i > 0 {
                t.push([a, c, b]);
            }
            if i + 1 < rings {
                t.push([b, c, d]);
            }
        }
    }
    (v, t)
}

/// An open cylinder of radius 1 from y = 0 to y = 1.
fn cylinder() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let segments = 12u32;
    let mut v = Vec::new();
    for y in [0.0, 1.0] {
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            v.push([phi.cos(), y, -phi.sin()]);
        }
    }
    let mut t = Vec::new();
    for j in 0..segments {
        let (a, b) = (j, (j + 1) % segments);
        t.push([a, b, a + segments]);
        t.push([b, b + segments, a + segments]);
    }
    (v, t)
}

/// The turn taking +y to `d` (glTF frame), a half turn about x when `d` points down.
fn turn_to(d: Vector3<f32>) -> UnitQuaternion<f32> {
    UnitQuaternion::rotation_between(&Vector3::y(), &d).unwrap_or_else(|| {
        UnitQuaternion::from_axis_angle(&Unit::new_unchecked(Vector3::x()), std::f32::consts::PI)
    })
}

/// The GLB bytes of `scene` (optional), `points` (an accessible region's voxel centres, say,
/// drawn as points; none for an empty slice) and `actors`, each with one animation.
///
/// # Errors
/// [`AffordanceError::InvalidInput`] for an actor whose sequence is not one
/// [`PoseSequence::new`] would make (no frames, a frame rate that is not positive, a support
/// per frame missing, a non-finite joint; named), a point that is not finite, or a scene mesh
/// that does not validate.
pub fn glb_bytes(
    scene: Option<&TriangleMesh>,
    points: &[Point3<f32>],
    actors: &[Actor],
) -> Result<Vec<u8>> {
    let mut b = Builder::default();
    let mut meshes = Vec::new();
    let mut nodes: Vec<Value> = Vec::new();
    let mut roots = Vec::new();
    let mut materials = vec![json!({
        "name": "scene",
        "pbrMetallicRoughness": {"baseColorFactor": [0.78, 0.76, 0.72, 1.0],
                                  "metallicFactor": 0.0, "roughnessFactor": 0.9},
        "doubleSided": true,
    })];
    if let Some(mesh) = scene {
        mesh.validate("the scene").map_err(AffordanceError::Scene)?;
        let vertices: Vec<[f32; 3]> = mesh.vertices.iter().map(|&p| to_gltf(p)).collect();
        let (pos, idx) = b.mesh(&vertices, &mesh.triangles);
        meshes.push(json!({"name": "scene", "primitives": [
            {"attributes": {"POSITION": pos}, "indices": idx, "material": 0}]}));
        nodes.push(json!({"name": "scene", "mesh": 0}));
        roots.push(0);
    }
    if !points.is_empty() {
        if let Some(i) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(AffordanceError::InvalidInput(format!(
                "point {i} is not finite"
            )));
        }
        let flat: Vec<f32> = points.iter().flat_map(|&p| to_gltf(p)).collect();
        let pos = b.floats(&flat, 3, "VEC3", Some(34962));
        materials.push(json!({
            "name": "region",
            "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.45, 0.95, 1.0],
                                      "metallicFactor": 0.0, "roughnessFactor": 1.0},
        }));
        meshes.push(json!({"name": "region", "primitives": [
            {"attributes": {"POSITION": pos}, "mode": 0, "material": materials.len() - 1}]}));
        nodes.push(json!({"name": "region", "mesh": meshes.len() - 1}));
        roots.push(nodes.len() - 1);
    }
    let (bv, bt) = ball();
    let ball_acc = b.mesh(&bv, &bt);
    let (cv, ct) = cylinder();
    let cylinder_acc = b.mesh(&cv, &ct);
    let mut animations = Vec::new();
    for (p, actor) in actors.iter().enumerate() {
        let seq = actor.poses;
        seq.validate().map_err(|e| e.within(actor.name))?;
        let colour = COLOURS[p % COLOURS.len()];
        materials.push(json!({
            "name": actor.name,
            "pbrMetallicRoughness": {"baseColorFactor": [colour[0], colour[1], colour[2], 1.0],
                                      "metallicFactor": 0.0, "roughnessFactor": 0.6},
        }));
        let material = materials.len() - 1;
        let ball_mesh = meshes.len();
        meshes.push(json!({"name": format!("{} joint", actor.name), "primitives": [
            {"attributes": {"POSITION": ball_acc.0}, "indices": ball_acc.1, "material": material}]}));
        meshes.push(json!({"name": format!("{} bone", actor.name), "primitives": [
            {"attributes": {"POSITION": cylinder_acc.0}, "indices": cylinder_acc.1, "material": material}]}));
        let cylinder_mesh = ball_mesh + 1;

        let frames = &seq.frames;
        let times: Vec<f32> = (0..frames.len()).map(|k| k as f32 / seq.fps).collect();
        let input = b.floats(&times, 1, "SCALAR", None);
        let world = |k: usize, j: Joint| Point3::from(to_gltf(frames[k].joints[j.index()]));
        // Joint nodes first (their index: base + joint index), then the bones.
        let base = nodes.len() + 1;
        let person = nodes.len();
        nodes.push(json!({"name": actor.name, "children": [base]}));
        roots.push(person);
        let mut samplers = Vec::new();
        let mut channels = Vec::new();
        let mut animate = |b: &mut Builder, node: usize, path: &str, values: Vec<f32>, width| {
            let kind = if width == 4 { "VEC4" } else { "VEC3" };
            let output = b.floats(&values, width, kind, None);
            samplers.push(json!({"input": input, "output": output, "interpolation": "LINEAR"}));
            channels.push(json!({"sampler": samplers.len() - 1,
                                 "target": {"node": node, "path": path}}));
        };
        let mut bone_nodes = Vec::new();
        for joint in Joint::ALL {
            let offsets: Vec<f32> = (0..frames.len())
                .flat_map(|k| {
                    let here = world(k, joint);
                    let from = joint.parent().map_or(Point3::origin(), |q| world(k, q));
                    (here - from).iter().copied().collect::<Vec<_>>()
                })
                .collect();
            let children: Vec<Joint> = joint.children().collect();
            let mut kids: Vec<usize> = children.iter().map(|c| base + c.index()).collect();
            for &child in &children {
                kids.push(base + JOINT_COUNT + bone_nodes.len());
                bone_nodes.push((joint, child));
            }
            // The ball is a child of its own: a joint's scale would reach its children.
            kids.push(base + JOINT_COUNT + (JOINT_COUNT - 1) + joint.index());
            let node = json!({
                "name": format!("{}:{}", actor.name, joint.name()),
                "translation": offsets[..3], "children": kids,
            });
            nodes.push(node);
            animate(&mut b, base + joint.index(), "translation", offsets, 3);
        }
        for &(joint, child) in &bone_nodes {
            let r = radius(joint).min(radius(child)) * 0.8;
            let (mut rotations, mut scales) = (Vec::new(), Vec::new());
            let mut last: Option<UnitQuaternion<f32>> = None;
            for k in 0..frames.len() {
                let d = world(k, child) - world(k, joint);
                let mut q = turn_to(d);
                // The shorter way from the last key, so the turn between keys is the small one.
                if let Some(l) = last {
                    if l.coords.dot(&q.coords) < 0.0 {
                        q = UnitQuaternion::new_unchecked(-q.into_inner());
                    }
                }
                last = Some(q);
                rotations.extend([q.i, q.j, q.k, q.w]);
                scales.extend([r, d.norm().max(1e-3), r]);
            }
            let index = nodes.len();
            nodes.push(json!({
                "name": format!("{}:{}-{}", actor.name, joint.name(), child.name()),
                "mesh": cylinder_mesh,
                "rotation": rotations[..4], "scale": scales[..3],
            }));
            animate(&mut b, index, "rotation", rotations, 4);
            animate(&mut b, index, "scale", scales, 3);
        }
        for joint in Joint::ALL {
            let r = radius(joint);
            nodes.push(
                json!({"name": format!("{}:{} ball", actor.name, joint.name()),
                              "mesh": ball_mesh, "scale": [r, r, r]}),
            );
        }
        animations.push(json!({"name": actor.name, "samplers": samplers, "channels": channels}));
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "envfield"},
        "scene": 0,
        "scenes": [{"name": "envfield", "nodes": roots}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "buffers": [{"byteLength": b.bin.len()}],
        "bufferViews": b.views,
        "accessors": b.accessors,
    });
    if !animations.is_empty() {
        doc["animations"] = json!(animations);
    }
    let mut text = serde_json::to_vec(&doc)
        .map_err(|e| AffordanceError::InvalidInput(format!("glTF JSON: {e}")))?;
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len() + 8 + b.bin.len();
    let total = u32::try_from(total).map_err(|_| {
        AffordanceError::InvalidInput(format!("a GLB holds at most 4 GiB ({total} bytes)"))
    })?;
    let mut out = Vec::with_capacity(total as usize);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend(total.to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&text);
    out.extend((b.bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(&b.bin);
    Ok(out)
}

/// Writes [`glb_bytes`] to `path`, atomically.
///
/// # Errors
/// As [`glb_bytes`]; I/O errors.
pub fn write_glb(
    path: impl AsRef<Path>,
    scene: Option<&TriangleMesh>,
    points: &[Point3<f32>],
    actors: &[Actor],
) -> Result<()> {
    let bytes = glb_bytes(scene, points, actors)?;
    envfield_grid::write_atomic(path, &bytes).map_err(|e| AffordanceError::Scene(e.into()))
}
