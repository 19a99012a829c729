//! Animated people out as GLB: the file is valid glTF (the `gltf` crate reads and validates
//! it), its node hierarchy at rest holds the first frame's pose, and its animation's keys
//! put every joint where the sequence has it at every frame.

use envfield_affordance::{
    glb_bytes, sit_down, walk, Actor, Joint, PoseSequence, SitConfig, WalkConfig, JOINT_COUNT,
};
use envfield_scene::{parse_gltf, TriangleMesh};
use nalgebra::{Point3, Vector3};
use serde_json::Value;

fn people() -> (PoseSequence, PoseSequence) {
    let walking = walk(&WalkConfig::default(), 3).unwrap();
    let mut seated = sit_down(&SitConfig::default()).unwrap();
    for f in &mut seated.frames {
        *f = f.translated(&Vector3::new(2.0, 1.0, 0.0));
    }
    (walking, seated)
}

/// The JSON chunk and the binary chunk of a GLB.
fn chunks(glb: &[u8]) -> (Value, Vec<u8>) {
    assert_eq!(&glb[..4], b"glTF");
    let u32_at = |i: usize| u32::from_le_bytes(glb[i..i + 4].try_into().unwrap()) as usize;
    assert_eq!(u32_at(8), glb.len());
    let json_len = u32_at(12);
    let json: Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    let bin = glb[bin_at + 8..bin_at + 8 + u32_at(bin_at)].to_vec();
    (json, bin)
}

fn floats(doc: &Value, bin: &[u8], accessor: usize) -> Vec<f32> {
    let a = &doc["accessors"][accessor];
    let v = &doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let start = v["byteOffset"].as_u64().unwrap() as usize;
    let len = v["byteLength"].as_u64().unwrap() as usize;
    bin[start..start + len]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

#[test]
fn a_glb_of_two_people_holds_their_poses_at_rest_and_in_every_key() {
    let (walking, seated) = people();
    let scene = TriangleMesh::cube(1.0);
    let actors = [
        Actor {
            name: "walker",
            poses: &walking,
        },
        Actor {
            name: "sitter",
            poses: &seated,
        },
    ];
    let glb = glb_bytes(Some(&scene), &[Point3::new(0.5, 0.5, 0.5)], &actors).unwrap();
    let gltf = envfield_scene_gltf_check(&glb);
    assert_eq!(gltf, 2);

    // At rest (the nodes' own transforms), each joint's ball is centred on frame 0's joint.
    let (mesh, parts) = parse_gltf(&glb, None, "people.glb").unwrap();
    let to_z_up = |p: &Point3<f32>| Point3::new(p.x, -p.z, p.y);
    let scene_part = parts.iter().find(|p| p.name == "scene").unwrap();
    assert_eq!(scene_part.triangles.len(), scene.triangles.len());
    for (actor, seq) in [("walker", &walking), ("sitter", &seated)] {
        for joint in Joint::ALL {
            let name = format!("{actor}:{} ball", joint.name());
            let part = parts.iter().find(|p| p.name == name).expect(&name);
            let tris = &mesh.triangles[part.triangles.clone()];
            let n = (tris.len() * 3) as f32;
            let centre = tris
                .iter()
                .flatten()
                .map(|&i| to_z_up(&mesh.vertices[i as usize]).coords)
                .sum::<Vector3<f32>>()
                / n;
            let want = seq.frames[0].joint(joint);
            assert!(
                (centre - want.coords).norm() < 0.02,
                "{name}: {centre} vs {want}"
            );
        }
    }

    // Every key: the translations down the tree add up to the joint, frame by frame.
    let (doc, bin) = chunks(&glb);
    for (a, seq) in [(0, &walking), (1, &seated)] {
        let anim = &doc["animations"][a];
        let channels = anim["channels"].as_array().unwrap();
        assert_eq!(channels.len(), JOINT_COUNT + 2 * (JOINT_COUNT - 1));
        let times = floats(
            &doc,
            &bin,
            anim["samplers"][0]["input"].as_u64().unwrap() as usize,
        );
        assert_eq!(times.len(), seq.frames.len());
        assert!((times[1] - 1.0 / seq.fps).abs() < 1e-6);
        // Joint i's channel is the i-th translation channel, in SMPL order.
        let offsets: Vec<Vec<f32>> = channels
            .iter()
            .filter(|c| c["target"]["path"] == "translation")
            .map(|c| {
                let s = c["sampler"].as_u64().unwrap() as usize;
                floats(
                    &doc,
                    &bin,
                    anim["samplers"][s]["output"].as_u64().unwrap() as usize,
                )
            })
            .collect();
        assert_eq!(offsets.len(), JOINT_COUNT);
        for (k, frame) in seq.frames.iter().enumerate() {
            for joint in Joint::ALL {
                let mut p = Vector3::zeros();
                let mut j = Some(joint);
                while let Some(q) = j {
                    let o = &offsets[q.index()][3 * k..3 * k + 3];
                    p += Vector3::new(o[0], o[1], o[2]);
                    j = q.parent();
                }
                let got = to_z_up(&Point3::from(p));
                assert!(
                    (got - frame.joint(joint)).norm() < 1e-4,
                    "frame {k} {joint:?}"
                );
            }
        }
    }
}

/// The `gltf` crate reads the GLB with its validation on: the animations it holds.
fn envfield_scene_gltf_check(glb: &[u8]) -> usize {
    let gltf = gltf::Gltf::from_slice(glb).expect("a valid glTF document");
    gltf.animations().count()
}

#[test]
fn people_without_frames_are_refused_by_name() {
    let (mut walking, _) = people();
    walking.frames[4].joints[3].x = f32::NAN;
    let e = glb_bytes(
        None,
        &[],
        &[Actor {
            name: "odd one",
            poses: &walking,
        }],
    )
    .unwrap_err();
    assert!(e.to_string().contains("odd one: frame 4"), "{e}");
}

/// The BVH file of a walk and a sit-down, read back by a BVH parser from the registry
/// (`bvh_anim`): 22 joints, one line of channels per frame, and its forward kinematics puts
/// every joint where the sequence has it.
#[test]
fn bvh_files_read_back_with_their_joints_frames_and_poses() {
    use envfield_affordance::{bvh_order, bvh_text};
    use nalgebra::Rotation3;
    let (walking, seated) = people();
    for seq in [&walking, &seated] {
        let text = bvh_text(seq).unwrap();
        let bvh = bvh_anim::from_str(&text).expect("bvh_anim reads it");
        let joints: Vec<_> = bvh.joints().collect();
        assert_eq!(joints.len(), JOINT_COUNT);
        assert_eq!(bvh.frames().len(), seq.frames.len());
        let order = bvh_order();
        for (j, want) in joints.iter().zip(&order) {
            assert_eq!(j.data().name(), want.name());
        }
        let mut worst = 0f32;
        for (k, frame) in bvh.frames().enumerate() {
            let values = frame.as_slice();
            let mut at = 3;
            let mut global: Vec<(Rotation3<f32>, Vector3<f32>)> = Vec::new();
            for (i, j) in joints.iter().enumerate() {
                let v = &values[at..at + 3];
                at += 3;
                let local = Rotation3::from_euler_angles(
                    v[2].to_radians(),
                    v[1].to_radians(),
                    v[0].to_radians(),
                );
                let o = j.data().offset();
                let offset = Vector3::new(o.x, o.y, o.z);
                let (turn, pos) = match j.data().parent_index() {
                    None => (local, Vector3::new(values[0], values[1], values[2])),
                    Some(p) => {
                        let (pt, pp) = global[p];
                        (pt * local, pp + pt * offset)
                    }
                };
                global.push((turn, pos));
                let want = seq.frames[k].joint(order[i]);
                let got = Point3::new(pos.x, -pos.z, pos.y);
                worst = worst.max((got - want).norm());
            }
        }
        // The library's sequences keep their bones' lengths; the pelvis and upper spine fit
        // three children each.
        assert!(
            worst < 0.005,
            "{:?}: worst joint {worst} m off",
            seq.activity
        );
        eprintln!("{:?}: worst joint {worst:.4} m off", seq.activity);
    }
}

/// A furnished room written as OBJ (z up) and as GLB (y up, from it), each read with no flag
/// (the format fixes the frame), is the same scene: the same triangles, the same move onto
/// the floor, the same floor map.
#[test]
fn a_room_as_obj_and_as_glb_reads_as_the_same_scene() {
    use envfield_scene::{
        floor_map, generate_room, read_scene, FloorMapConfig, ImportConfig, RoomConfig,
    };
    let room = generate_room(&RoomConfig::default(), 11).unwrap();
    let mesh = room.scene.to_mesh();
    let dir = tempfile::tempdir().unwrap();
    let (obj, glb) = (dir.path().join("room.obj"), dir.path().join("room.glb"));
    mesh.write(&obj).unwrap();
    std::fs::write(&glb, glb_bytes(Some(&mesh), &[], &[]).unwrap()).unwrap();
    let (a, ra) = read_scene(&obj, &ImportConfig::for_file(&obj, None, None)).unwrap();
    let (b, rb) = read_scene(&glb, &ImportConfig::for_file(&glb, None, None)).unwrap();
    assert!(
        ra.warnings.is_empty() && rb.warnings.is_empty(),
        "{ra} / {rb}"
    );
    assert_eq!((ra.triangles, ra.shift), (rb.triangles, rb.shift));
    let (ma, mb) = (a.to_mesh(), b.to_mesh());
    let worst = ma
        .vertices
        .iter()
        .zip(&mb.vertices)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "{worst}");
    let config = FloorMapConfig::default();
    let (fa, fb) = (
        floor_map(&a, &config).unwrap(),
        floor_map(&b, &config).unwrap(),
    );
    assert_eq!(fa.grid, fb.grid);
}
