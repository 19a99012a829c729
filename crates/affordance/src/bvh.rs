//! Pose sequences out as BVH (Biovision Hierarchy), the motion-capture tools' format: SMPL's
//! joint tree with each joint's offset from its parent, and per frame the root's position and
//! every joint's rotation (Euler angles, Z Y X, degrees). In the frame most BVH readers
//! expect: +y up, metres.
//!
//! Poses here are joint positions; BVH wants rotations. The rest pose is a standing body
//! facing +x whose bones have the sequence's mean lengths; each frame's rotation of a joint
//! is the smallest turn, from its parent's, that points its bone where the pose has it (a
//! joint with several children, the pelvis and the upper spine, fits all of them at once;
//! one without children keeps its parent's turn). Forward kinematics of the file gives the
//! pose back to within the bones' change of length between frames (none in the library's
//! own sequences) and, at the pelvis and the upper spine, the change of the angles between
//! their children.

use std::fmt::Write as _;
use std::path::Path;

use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::error::{AffordanceError, Result};
use crate::motion::standing_pose;
use crate::skeleton::{Joint, PoseSequence, JOINT_COUNT};

/// The library's frame (z up) to BVH's (y up).
fn to_bvh(v: Vector3<f32>) -> Vector3<f32> {
    Vector3::new(v.x, v.z, -v.y)
}

/// The turn taking the vectors `from` to `to` best (Kabsch), the smallest one for one pair.
fn fit(from: &[Vector3<f32>], to: &[Vector3<f32>]) -> Rotation3<f32> {
    if from.len() == 1 {
        return Rotation3::rotation_between(&from[0], &to[0]).unwrap_or_else(|| {
            // Opposite: a half turn about any axis across it.
            let axis = from[0]
                .cross(&Vector3::x())
                .try_normalize(1e-6)
                .unwrap_or(Vector3::y());
            Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(axis), std::f32::consts::PI)
        });
    }
    let h: Matrix3<f32> = from.iter().zip(to).map(|(a, b)| b * a.transpose()).sum();
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u.expect("u"), svd.v_t.expect("v_t"));
    let mut d = Matrix3::identity();
    if (u * v_t).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    Rotation3::from_matrix_unchecked(u * d * v_t)
}

/// The BVH text of `poses`.
///
/// # Errors
/// [`AffordanceError::InvalidInput`] for a sequence that is not one [`PoseSequence::new`] would
/// make (no frames, a frame rate that is not positive, a support per frame missing, a
/// non-finite joint), or with a bone of no length.
pub fn bvh_text(poses: &PoseSequence) -> Result<String> {
    poses.validate().map_err(|e| e.within("BVH"))?;
    let frames = &poses.frames;
    let bone = |k: usize, j: Joint, p: Joint| to_bvh(frames[k].joint(j) - frames[k].joint(p));
    // The rest pose: the standing body's directions, the sequence's mean lengths.
    let rest = standing_pose();
    let mut offsets = [Vector3::zeros(); JOINT_COUNT];
    for joint in Joint::ALL {
        let Some(parent) = joint.parent() else {
            continue;
        };
        let mean = frames
            .iter()
            .enumerate()
            .map(|(k, _)| bone(k, joint, parent).norm())
            .sum::<f32>()
            / frames.len() as f32;
        let dir = to_bvh(rest.joint(joint) - rest.joint(parent));
        if mean <= 1e-6 || dir.norm() <= 1e-6 {
            return Err(AffordanceError::InvalidInput(format!(
                "BVH: the bone {}-{} has no length",
                parent.name(),
                joint.name()
            )));
        }
        offsets[joint.index()] = dir.normalize() * mean;
    }

    let mut text = String::from("HIERARCHY\n");
    write_joint(&mut text, Joint::Pelvis, &offsets, 0);
    let _ = write!(
        text,
        "MOTION\nFrames: {}\nFrame Time: {:.8}\n",
        frames.len(),
        1.0 / poses.fps
    );
    let order = bvh_order();
    for k in 0..frames.len() {
        // Global turns in SMPL order (a parent comes before its children).
        let mut global = [Rotation3::identity(); JOINT_COUNT];
        let mut line = Vec::with_capacity(3 + 3 * JOINT_COUNT);
        let root = to_bvh(frames[k].joint(Joint::Pelvis).coords);
        line.extend([root.x, root.y, root.z]);
        for joint in Joint::ALL {
            let parent_turn = joint
                .parent()
                .map_or(Rotation3::identity(), |p| global[p.index()]);
            let kids: Vec<Joint> = joint.children().collect();
            let turn = if kids.is_empty() {
                parent_turn
            } else {
                let from: Vec<_> = kids
                    .iter()
                    .map(|c| parent_turn * offsets[c.index()])
                    .collect();
                let to: Vec<_> = kids.iter().map(|&c| bone(k, c, joint)).collect();
                fit(&from, &to) * parent_turn
            };
            global[joint.index()] = turn;
        }
        for &joint in &order {
            let parent_turn = joint
                .parent()
                .map_or(Rotation3::identity(), |p| global[p.index()]);
            let local = parent_turn.inverse() * global[joint.index()];
            // R = Rz(yaw) Ry(pitch) Rx(roll): channels Zrotation Yrotation Xrotation.
            let (roll, pitch, yaw) = local.euler_angles();
            line.extend([yaw, pitch, roll].map(f32::to_degrees));
        }
        let words: Vec<String> = line.iter().map(|v| format!("{v:.5}")).collect();
        text.push_str(&words.join(" "));
        text.push('\n');
    }
    Ok(text)
}

/// One joint's block and, depth first, its children's: the order [`bvh_order`] gives.
fn write_joint(
    text: &mut String,
    joint: Joint,
    offsets: &[Vector3<f32>; JOINT_COUNT],
    depth: usize,
) {
    let pad = "  ".repeat(depth);
    let o = offsets[joint.index()];
    if joint.parent().is_none() {
        let _ = writeln!(text, "{pad}ROOT {}", joint.name());
    } else {
        let _ = writeln!(text, "{pad}JOINT {}", joint.name());
    }
    let _ = writeln!(text, "{pad}{{");
    let _ = writeln!(text, "{pad}  OFFSET {:.6} {:.6} {:.6}", o.x, o.y, o.z);
    if joint.parent().is_none() {
        let _ = writeln!(
            text,
            "{pad}  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation"
        );
    } else {
        let _ = writeln!(text, "{pad}  CHANNELS 3 Zrotation Yrotation Xrotation");
    }
    let kids: Vec<Joint> = joint.children().collect();
    if kids.is_empty() {
        let _ = writeln!(
            text,
            "{pad}  End Site\n{pad}  {{\n{pad}    OFFSET 0 0 0\n{pad}  }}"
        );
    }
    for c in kids {
        write_joint(text, c, offsets, depth + 1);
    }
    let _ = writeln!(text, "{pad}}}");
}

/// The joints in the order their blocks (and so their channels) appear in the file: depth
/// first from the pelvis, children in SMPL order.
pub fn bvh_order() -> Vec<Joint> {
    fn visit(j: Joint, out: &mut Vec<Joint>) {
        out.push(j);
        for c in j.children() {
            visit(c, out);
        }
    }
    let mut out = Vec::with_capacity(JOINT_COUNT);
    visit(Joint::Pelvis, &mut out);
    out
}

/// Writes [`bvh_text`] to `path`, atomically.
///
/// # Errors
/// As [`bvh_text`]; I/O errors.
pub fn write_bvh(path: impl AsRef<Path>, poses: &PoseSequence) -> Result<()> {
    let text = bvh_text(poses)?;
    envfield_grid::write_atomic(path, text.as_bytes()).map_err(|e| AffordanceError::Scene(e.into()))
}
