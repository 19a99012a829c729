//! Affordance checks, procedural motions, JSON and alignment on a hand-built room.

use std::f32::consts::FRAC_PI_2;

use approx::assert_relative_eq;
use envfield_affordance::{
    afford, align_in_scene, align_to_trajectory, check_pose, check_sequence, get_up, lie_down,
    plausible, pose_supported, sit_down, standing_pose, walk, AffordanceConfig, AlignConfig,
    FilterConfig, Joint, LieConfig, Pose, PoseSequence, SitConfig, Support, WalkConfig,
    MAX_TORSO_RADIUS,
};
use envfield_scene::{ObjectKind, Primitive, Scene, SceneObject};
use nalgebra::{Isometry3, Point3, Vector3};

fn at(x: f32, y: f32, z: f32) -> Isometry3<f32> {
    Isometry3::translation(x, y, z)
}

/// A 10 x 10 m floor (top at z = 0), a chair at (2, 2) facing +x, a table at (5, 5) (top at
/// 0.71-0.75 m) and a bed at (8, 5) (mattress top at 0.5 m, 2 m long along x).
fn room() -> Scene {
    let mut s = Scene::new();
    let mut add = |name: &str, kind, parts: &[(Primitive, Isometry3<f32>)]| {
        let mut o = SceneObject::new(name, kind);
        for &(p, pose) in parts {
            o = o.with(p, pose).unwrap();
        }
        s.add(o).unwrap();
    };
    add(
        "floor",
        ObjectKind::Floor,
        &[(Primitive::cuboid([10.0, 10.0, 0.1]), at(5.0, 5.0, -0.05))],
    );
    let leg = |x, y, h: f32| {
        (
            Primitive::Cylinder {
                half_height: h / 2.0,
                radius: 0.02,
            },
            at(x, y, h / 2.0),
        )
    };
    add(
        "chair",
        ObjectKind::Chair,
        &[
            (Primitive::cuboid([0.48, 0.46, 0.03]), at(2.0, 2.0, 0.435)),
            (Primitive::cuboid([0.04, 0.46, 0.45]), at(1.78, 2.0, 0.675)),
            leg(1.79, 1.8, 0.42),
            leg(2.21, 1.8, 0.42),
            leg(1.79, 2.2, 0.42),
            leg(2.21, 2.2, 0.42),
        ],
    );
    add(
        "table",
        ObjectKind::Table,
        &[
            (Primitive::cuboid([1.2, 0.8, 0.04]), at(5.0, 5.0, 0.73)),
            leg(4.45, 4.65, 0.71),
            leg(5.55, 4.65, 0.71),
            leg(4.45, 5.35, 0.71),
            leg(5.55, 5.35, 0.71),
        ],
    );
    add(
        "bed",
        ObjectKind::Bed,
        &[
            (Primitive::cuboid([2.0, 1.6, 0.5]), at(8.0, 5.0, 0.25)),
            (Primitive::cuboid([0.08, 1.6, 1.0]), at(6.96, 5.0, 0.5)),
        ],
    );
    s
}

fn cfg() -> AffordanceConfig {
    AffordanceConfig::default()
}

#[test]
fn standing_on_the_floor_is_valid_and_sunk_into_a_table_is_not() {
    let scene = room();
    let pose = standing_pose().translated(&Vector3::new(3.0, 7.0, 0.0));
    let r = check_pose(&scene, &pose, Support::Standing, &cfg()).unwrap();
    assert!(r.supported && r.collision_free && r.valid(), "{r:?}");
    assert_eq!(r.good_joints(), 22);
    // The same pose at the table, lowered so the pelvis is in the table top.
    let drop = pose.torso().z - 0.73;
    let sunk = pose.translated(&Vector3::new(2.0, -2.0, -drop));
    let r = check_pose(&scene, &sunk, Support::Standing, &cfg()).unwrap();
    assert!(!r.collision_free, "{r:?}");
    assert!(r.distances[Joint::Pelvis.index()] < 0.0);
    // Joints, not bones, are checked (as in the paper): standing under the table, the 4 cm
    // top passes between the knees (0.5 m) and the hips (0.9 m) unseen.
    let under = pose.translated(&Vector3::new(2.0, -2.0, 0.0));
    assert!(
        check_pose(&scene, &under, Support::Standing, &cfg())
            .unwrap()
            .collision_free
    );
    // Floating 30 cm above the floor is not supported.
    let floating = pose.translated(&Vector3::new(0.0, 0.0, 0.3));
    assert!(
        !check_pose(&scene, &floating, Support::Standing, &cfg())
            .unwrap()
            .supported
    );
}

#[test]
fn sitting_on_the_chair_is_supported_and_in_mid_air_is_not() {
    let scene = room();
    let sit = sit_down(&SitConfig::default()).unwrap();
    let seated = sit.frames.last().unwrap();
    assert_eq!(*sit.supports.last().unwrap(), Support::Sitting);
    // The chair faces +x, as the body does; its seat centre is (2.0, 2.0) at 0.45 m.
    let on_chair = seated.translated(&Vector3::new(2.0, 2.0, 0.0));
    let r = check_pose(&scene, &on_chair, Support::Sitting, &cfg()).unwrap();
    assert!(r.supported, "{r:?}");
    assert!(r.collision_free, "{r:?}");
    let in_air = on_chair.translated(&Vector3::new(0.0, 0.0, 0.5));
    let r = check_pose(&scene, &in_air, Support::Sitting, &cfg()).unwrap();
    assert!(!r.supported, "{r:?}");
    // The whole motion, played onto the chair, keeps every frame valid.
    let played = align_to_trajectory(
        &sit,
        &sit.frames
            .iter()
            .map(|f| f.torso() + Vector3::new(2.0, 2.0, 0.0))
            .collect::<Vec<_>>(),
        false,
    )
    .unwrap();
    let reports = check_sequence(&scene, &played, &cfg()).unwrap();
    let bad: Vec<_> = reports
        .iter()
        .enumerate()
        .filter(|(_, r)| !r.valid())
        .map(|(i, _)| i)
        .collect();
    assert!(bad.is_empty(), "invalid frames {bad:?}");
}

#[test]
fn lying_down_on_the_bed_ends_supported_on_the_back() {
    let scene = room();
    let lie = lie_down(&LieConfig::default()).unwrap();
    // Sit on the bed's foot end (x = 9.0, the bed spans 7.0-9.0), facing +x away from the
    // headboard, then lie back towards it.
    let placed: Vec<_> = lie
        .frames
        .iter()
        .map(|f| f.translated(&Vector3::new(8.9, 5.0, 0.0)))
        .collect();
    let last = placed.last().unwrap();
    let r = check_pose(&scene, last, Support::Lying, &cfg()).unwrap();
    assert!(r.valid(), "{r:?}");
    assert!(last.joint(Joint::Head).x < 8.0 && last.joint(Joint::Head).x > 7.0);
    let first = check_pose(&scene, &placed[0], Support::Sitting, &cfg()).unwrap();
    assert!(first.supported, "{first:?}");
}

/// Sitting down on a seat higher than the shank is long (a bed's edge) ends with the hips on
/// the seat and the soles on the floor: the thighs slope down to the knees.
#[test]
fn sitting_on_a_high_seat_ends_with_the_hips_on_it() {
    for h in [0.35f32, 0.45, 0.5, 0.55, 0.65, 0.75] {
        let sit = sit_down(&SitConfig {
            seat_height: h,
            ..SitConfig::default()
        })
        .unwrap();
        let last = sit.frames.last().unwrap();
        let hips = (last.joint(Joint::LeftHip).z + last.joint(Joint::RightHip).z) / 2.0;
        assert!((hips - h).abs() < 0.01, "seat {h}: hips at {hips}");
        let ankle = last.joint(Joint::LeftAnkle).z;
        assert!(
            (ankle - sit.frames[0].joint(Joint::LeftAnkle).z).abs() < 0.01,
            "seat {h}"
        );
        assert!(last.joint(Joint::LeftKnee).z <= hips + 1e-3, "seat {h}");
    }
}

/// Lying down with the legs lifted first ([`LieConfig::lift`]) keeps every bone out of the
/// bed from the foot end; with the legs straightening as the body slides, the shanks still
/// hang when the knees come over the edge and pass through the bed's side.
#[test]
fn lying_down_legs_first_keeps_the_shanks_out_of_the_bed() {
    let scene = room();
    let bones_in_bed = |lift: f32| {
        let lie = lie_down(&LieConfig {
            lift,
            slide: 0.8,
            ..LieConfig::default()
        })
        .unwrap();
        lie.frames
            .iter()
            .zip(&lie.supports)
            .filter(|(f, &s)| {
                let placed = f.translated(&Vector3::new(8.9, 5.0, 0.0));
                let rests = |s| plausible(&scene, &placed, s, &cfg()).unwrap();
                !(rests(s) || rests(Support::Lying))
            })
            .count()
    };
    assert_eq!(bones_in_bed(0.5), 0);
    assert!(bones_in_bed(0.0) > 0);
    // Only the last frame lies; the lift must leave time to slide.
    let lie = lie_down(&LieConfig {
        lift: 0.5,
        ..LieConfig::default()
    })
    .unwrap();
    let lying = lie
        .supports
        .iter()
        .filter(|&&s| s == Support::Lying)
        .count();
    assert_eq!(lying, 1);
    let e = lie_down(&LieConfig {
        lift: 1.0,
        ..LieConfig::default()
    })
    .unwrap_err();
    assert!(e.to_string().contains("lift"), "{e}");
    for turn in [4.0, f32::NAN] {
        let e = lie_down(&LieConfig {
            turn,
            ..LieConfig::default()
        })
        .unwrap_err();
        assert!(e.to_string().contains("turn"), "{e}");
    }
}

#[test]
fn walking_keeps_bones_feet_and_step_length_plausible() {
    let config = WalkConfig {
        cycles: 2,
        ..WalkConfig::default()
    };
    let w = walk(&config, 9).unwrap();
    assert_eq!(w, walk(&config, 9).unwrap(), "seeded");
    assert_ne!(w, walk(&config, 10).unwrap());
    let scene = room();
    for (i, f) in w.frames.iter().enumerate() {
        for (a, b, len) in [
            (Joint::LeftHip, Joint::LeftKnee, 0.40),
            (Joint::RightKnee, Joint::RightAnkle, 0.42),
            (Joint::LeftShoulder, Joint::LeftElbow, 0.27),
        ] {
            assert_relative_eq!(
                nalgebra::distance(&f.joint(a), &f.joint(b)),
                len,
                epsilon = 1e-4
            );
        }
        let lowest = f
            .joint(Joint::LeftAnkle)
            .z
            .min(f.joint(Joint::RightAnkle).z);
        assert_relative_eq!(lowest, 0.08, epsilon = 1e-4);
        let placed = f.translated(&Vector3::new(1.0, 8.0, 0.0));
        let r = check_pose(&scene, &placed, Support::Standing, &cfg()).unwrap();
        assert!(r.valid(), "frame {i}: {r:?}");
    }
    // The torso advances at step length x cadence: between 0.65 and 1.45 m/s with +-10%.
    let speed = w.step_length() * w.fps;
    assert!(
        (0.65 * 1.8 * 0.8..0.65 * 1.8 * 1.22).contains(&speed),
        "{speed}"
    );
    assert!(walk(
        &WalkConfig {
            step_length: -1.0,
            ..config
        },
        0
    )
    .is_err());
}

#[test]
fn alignment_turns_the_walk_onto_the_path() {
    let w = walk(&WalkConfig::default(), 1).unwrap();
    let step = w.step_length();
    // A quarter circle of radius 2 m around (5, 2), walked at the gait's own step.
    let n = (2.0 * FRAC_PI_2 / step) as usize;
    let path: Vec<_> = (0..n)
        .map(|i| {
            let a = i as f32 * step / 2.0;
            Point3::new(5.0 + 2.0 * a.cos(), 2.0 + 2.0 * a.sin(), 0.0)
        })
        .collect();
    let aligned = align_to_trajectory(&w, &path, true).unwrap();
    assert_eq!(aligned.frames.len(), n);
    for (i, f) in aligned.frames.iter().enumerate() {
        let t = f.torso();
        assert_relative_eq!(t.x, path[i].x, epsilon = 1e-4);
        assert_relative_eq!(t.y, path[i].y, epsilon = 1e-4);
        assert!(t.z > 0.8, "keep_height keeps the torso up");
        // The body faces along the tangent (walking straight ahead).
        let a = i as f32 * step / 2.0;
        let tangent = Vector3::new(-a.sin(), a.cos(), 0.0);
        assert!(
            f.facing().dot(&tangent) > 0.97,
            "frame {i}: {:?}",
            f.facing()
        );
    }
    assert!(align_to_trajectory(&w, &[], false).is_err());
    assert!(align_to_trajectory(&w, &[Point3::new(f32::NAN, 0.0, 0.0)], false).is_err());
}

#[test]
fn the_getting_up_search_never_scores_worse() {
    let scene = room();
    let up = get_up(&SitConfig::default()).unwrap();
    assert_eq!(up.supports[0], Support::Sitting);
    // Rotate the chair's occupant 10 degrees off; the search may win some of it back.
    let pivot = Point3::origin();
    let turned = PoseSequence::new(
        up.fps,
        up.activity,
        up.frames
            .iter()
            .map(|f| f.rotated_about_z(0.17, &pivot))
            .collect(),
        up.supports.clone(),
    )
    .unwrap();
    let path: Vec<_> = turned
        .frames
        .iter()
        .map(|f| f.torso() + Vector3::new(2.0, 2.0, 0.0))
        .collect();
    let plain = AlignConfig::default();
    let search = AlignConfig {
        search_degrees: 6.0,
        ..AlignConfig::default()
    };
    let (_, before) = align_in_scene(&scene, &turned, &path, &plain).unwrap();
    let (_, after) = align_in_scene(&scene, &turned, &path, &search).unwrap();
    for (b, a) in before.iter().zip(&after) {
        assert!(a.good_joints() >= b.good_joints());
    }
    assert!(align_in_scene(
        &scene,
        &turned,
        &path,
        &AlignConfig {
            search_step_degrees: 0.0,
            ..search
        }
    )
    .is_err());
}

#[test]
fn sequences_round_trip_through_json_and_reject_bad_files() {
    let s = sit_down(&SitConfig::default()).unwrap();
    let back = PoseSequence::from_json(&s.to_json().unwrap()).unwrap();
    assert_eq!(back, s);
    let mut broken = s.clone();
    broken.frames[2].joints[4].x = f32::NAN;
    let e = broken.to_json().unwrap_err().to_string();
    assert!(e.contains("frame 2") && e.contains("left_knee"), "{e}");
    let dir = std::env::temp_dir().join(format!("envfield-aff-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("sit.json");
    s.write(&path).unwrap();
    assert_eq!(PoseSequence::read(&path).unwrap(), s);
    std::fs::write(&path, "{").unwrap();
    assert!(PoseSequence::read(&path)
        .unwrap_err()
        .to_string()
        .contains("sit.json"));
    std::fs::remove_dir_all(&dir).unwrap();

    let mut v: serde_json::Value = serde_json::from_str(&s.to_json().unwrap()).unwrap();
    v["joints"][3] = "tail".into();
    let e = PoseSequence::from_json(&v.to_string())
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown joint `tail`"), "{e}");
    let mut v: serde_json::Value = serde_json::from_str(&s.to_json().unwrap()).unwrap();
    v["frames"][5].as_array_mut().unwrap().pop();
    let e = PoseSequence::from_json(&v.to_string())
        .unwrap_err()
        .to_string();
    assert!(e.contains("frame 5 has 21 joints"), "{e}");
    let mut v: serde_json::Value = serde_json::from_str(&s.to_json().unwrap()).unwrap();
    v["fps"] = 0.0.into();
    assert!(PoseSequence::from_json(&v.to_string()).is_err());
    let mut v: serde_json::Value = serde_json::from_str(&s.to_json().unwrap()).unwrap();
    v["frames"] = serde_json::json!([]);
    assert!(PoseSequence::from_json(&v.to_string()).is_err());
    // Joints given in another order are mapped by name; supports default to standing.
    let mut v: serde_json::Value = serde_json::from_str(&s.to_json().unwrap()).unwrap();
    v["joints"].as_array_mut().unwrap().swap(0, 1);
    for f in v["frames"].as_array_mut().unwrap() {
        f.as_array_mut().unwrap().swap(0, 1);
    }
    v.as_object_mut().unwrap().remove("supports");
    let reordered = PoseSequence::from_json(&v.to_string()).unwrap();
    assert_eq!(reordered.frames, s.frames);
    assert!(reordered.supports.iter().all(|&x| x == Support::Standing));
}

/// The early-stopping check answers as the full report does, for standing, sitting and lying
/// frames placed all over the room (on the floor, in mid-air, sunk into furniture), on the
/// scene and on its distance grid.
#[test]
fn pose_valid_agrees_with_the_full_report() {
    use envfield_affordance::pose_valid;
    use envfield_scene::DistanceGrid;
    let scene = room();
    let grid = DistanceGrid::around(&scene, 0.2, 0.03).unwrap();
    let mut sequences = vec![walk(&WalkConfig::default(), 3).unwrap()];
    sequences.push(sit_down(&SitConfig::default()).unwrap());
    sequences.push(lie_down(&LieConfig::default()).unwrap());
    let mut rng = envfield_grid::SplitMix64::new(11);
    let (mut valid, mut total) = (0, 0);
    for seq in &sequences {
        for (frame, &support) in seq.frames.iter().zip(&seq.supports) {
            for _ in 0..40 {
                let shift = Vector3::new(
                    3.0 * rng.next_f32() - 1.0,
                    3.0 * rng.next_f32() - 1.0,
                    0.6 * rng.next_f32() - 0.3,
                );
                let pose = frame.translated(&shift);
                let full = check_pose(&scene, &pose, support, &cfg()).unwrap().valid();
                assert_eq!(pose_valid(&scene, &pose, support, &cfg()).unwrap(), full);
                let on_grid = check_pose(&grid, &pose, support, &cfg()).unwrap().valid();
                assert_eq!(pose_valid(&grid, &pose, support, &cfg()).unwrap(), on_grid);
                valid += usize::from(full);
                total += 1;
            }
        }
    }
    // Both answers occur.
    assert!(
        valid > total / 20 && valid < total - total / 20,
        "{valid} of {total}"
    );
}

#[test]
fn a_foot_rests_on_what_lies_beneath_it_not_on_a_side_it_touches() {
    // No floor: a 1 cm cube, and a wall 2 m tall. A standing body whose foot touches the
    // cube's side, or the wall, stands on nothing.
    let mut s = Scene::new();
    let cube = SceneObject::new("cube", ObjectKind::Other)
        .with(Primitive::cuboid([0.01, 0.01, 0.01]), at(0.0, 0.0, 0.005))
        .unwrap();
    let wall = SceneObject::new("wall", ObjectKind::Wall)
        .with(Primitive::cuboid([0.1, 1.0, 2.0]), at(3.0, 0.0, 1.0))
        .unwrap();
    s.add(cube).unwrap();
    s.add(wall).unwrap();
    let pose = standing_pose();
    let foot = pose.joints[Joint::LeftFoot.index()];
    // The left foot 4 cm beside the cube's side, level with it.
    let beside = pose.translated(&Vector3::new(-foot.x + 0.045, -foot.y, 0.005 - foot.z));
    let r = check_pose(&s, &beside, Support::Standing, &cfg()).unwrap();
    assert!(r.distances[Joint::LeftFoot.index()] < cfg().contact_tolerance);
    assert!(!r.supported, "{r:?}");
    // On the cube's top it stands (a foot on a 1 cm cube: the top is beneath it).
    let on_top = pose.translated(&Vector3::new(-foot.x, -foot.y, 0.03 - foot.z));
    assert!(
        check_pose(&s, &on_top, Support::Standing, &cfg())
            .unwrap()
            .supported
    );
    // Against the wall, 3 cm from it, no floor: nothing beneath.
    let at_wall = pose.translated(&Vector3::new(2.92 - foot.x, -foot.y, 1.0 - foot.z));
    assert!(
        !check_pose(&s, &at_wall, Support::Standing, &cfg())
            .unwrap()
            .supported
    );
    // With a floor, a foot 3 cm from the wall stands on it: the line down meets the floor,
    // the wall beside it does not hide it.
    let mut s = s;
    let floor = SceneObject::new("floor", ObjectKind::Floor)
        .with(Primitive::cuboid([2.0, 2.0, 0.1]), at(2.5, 0.0, -0.05))
        .unwrap();
    s.add(floor).unwrap();
    let by_wall = pose.translated(&Vector3::new(2.92 - foot.x, -foot.y, 0.03 - foot.z));
    for scene_or_grid in [true, false] {
        let r = if scene_or_grid {
            check_pose(&s, &by_wall, Support::Standing, &cfg()).unwrap()
        } else {
            let grid = envfield_scene::DistanceGrid::around(&s, 0.2, 0.05).unwrap();
            check_pose(&grid, &by_wall, Support::Standing, &cfg()).unwrap()
        };
        assert!(r.supported, "{r:?}");
    }
}

#[test]
fn a_foot_on_an_open_sheet_rests_on_it() {
    // A floor of one zero-thickness sheet (no inside: its distance is unsigned), as game
    // levels and scanned rooms often are. A foot on it, or just above it, rests on it.
    let mesh = envfield_scene::TriangleMesh {
        vertices: vec![
            Point3::new(-2.0, -2.0, 0.0),
            Point3::new(2.0, -2.0, 0.0),
            Point3::new(2.0, 2.0, 0.0),
            Point3::new(-2.0, 2.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    let scene = Scene::from_mesh("sheet", &mesh).unwrap();
    let pose = standing_pose();
    let sole = pose.lowest();
    for lift in [0.0, 0.005, 0.03, 0.1] {
        let p = pose.translated(&Vector3::new(0.0, 0.0, lift - sole));
        let r = check_pose(&scene, &p, Support::Standing, &cfg()).unwrap();
        assert!(r.supported, "{lift} m above the sheet: {r:?}");
    }
    let p = pose.translated(&Vector3::new(0.0, 0.0, 0.3 - sole));
    assert!(
        !check_pose(&scene, &p, Support::Standing, &cfg())
            .unwrap()
            .supported
    );
}

/// The support joints alone decide support: `pose_supported` says what `check_pose` says, for
/// poses of every kind placed all over the room (on the floor, the chair, the table, the bed,
/// in the air and sunk).
#[test]
fn pose_supported_agrees_with_check_pose() {
    let scene = room();
    let cfg = AffordanceConfig::default();
    let sit = sit_down(&SitConfig::default()).unwrap();
    let lie = lie_down(&LieConfig::default()).unwrap();
    let kinds = [
        (standing_pose(), Support::Standing),
        (*sit.frames.last().unwrap(), Support::Sitting),
        (*lie.frames.last().unwrap(), Support::Lying),
    ];
    let (mut agree, mut supported) = (0, 0);
    for (pose, support) in kinds {
        let t = pose.torso();
        for i in 0..20 {
            for j in 0..20 {
                for k in 0..6 {
                    let to = Vector3::new(
                        0.5 * i as f32 - t.x,
                        0.5 * j as f32 - t.y,
                        0.15 * k as f32 - 0.2,
                    );
                    let placed = pose
                        .rotated_about_z(0.3 * (i + j) as f32, &t)
                        .translated(&to);
                    let full = check_pose(&scene, &placed, support, &cfg).unwrap();
                    let quick = pose_supported(&scene, &placed, support, &cfg).unwrap();
                    assert_eq!(quick, full.supported, "{support:?} at {to:?}");
                    agree += 1;
                    supported += usize::from(quick);
                }
            }
        }
    }
    assert!(
        supported > 50 && supported < agree - 50,
        "{supported} of {agree}"
    );
}

/// The torso filter skips a pose kind when none of its headings can rest (one distance read
/// per support joint), and reads a plausible pose's collisions off its bones: what it finds
/// supported and valid is what trying every kind at every heading with every check finds, at
/// torsos all over the room.
#[test]
fn the_filters_shortcut_finds_what_every_try_finds() {
    let scene = room();
    let config = FilterConfig::default().in_place();
    let centre = |p: Pose| {
        let t = p.torso();
        p.translated(&Vector3::new(-t.x, -t.y, -t.z))
    };
    let low = sit_down(&SitConfig {
        seat_height: 0.32,
        ..SitConfig::default()
    })
    .unwrap();
    let kit = [
        (centre(standing_pose()), Support::Standing),
        (
            centre(
                *sit_down(&SitConfig::default())
                    .unwrap()
                    .frames
                    .last()
                    .unwrap(),
            ),
            Support::Sitting,
        ),
        (centre(*low.frames.last().unwrap()), Support::Sitting),
        (
            centre(
                *lie_down(&LieConfig::default())
                    .unwrap()
                    .frames
                    .last()
                    .unwrap(),
            ),
            Support::Lying,
        ),
    ];
    let mut found = 0;
    for i in 0..40 {
        for j in 0..40 {
            for k in 0..8 {
                let p = [0.25 * i as f32, 0.25 * j as f32, 0.15 * k as f32 + 0.3];
                let got = afford(&scene, p, &config).unwrap();
                let (mut want, mut want_valid) = (None, None);
                'tries: for (pose, support) in kit {
                    for y in 0..config.yaws {
                        let yaw = y as f32 * std::f32::consts::TAU / config.yaws as f32;
                        let placed = pose
                            .rotated_about_z(yaw, &Point3::origin())
                            .translated(&Vector3::from(p));
                        let r = check_pose(&scene, &placed, support, &config.affordance).unwrap();
                        if r.supported
                            && plausible(&scene, &placed, support, &config.affordance).unwrap()
                        {
                            want = want.or(Some(support));
                            if r.valid() {
                                want_valid = Some(support);
                                break 'tries;
                            }
                        }
                    }
                }
                assert_eq!(got.supported, want, "at {p:?}");
                assert_eq!(got.valid, want_valid, "at {p:?}");
                let got = got.supported;
                found += usize::from(got.is_some());
            }
        }
    }
    assert!(found > 100, "{found} supported torsos");
}

#[test]
fn a_torso_wider_than_the_bound_or_not_a_number_is_refused_naming_it() {
    for radius in [-0.1, f32::NAN, MAX_TORSO_RADIUS + 0.01, 5.0] {
        let config = FilterConfig {
            torso_radius: radius,
            ..FilterConfig::default()
        };
        let err = config.validate().unwrap_err().to_string();
        assert!(
            err.contains("torso_radius of 0 to 0.5 m"),
            "{radius}: {err}"
        );
    }
    let edge = FilterConfig {
        torso_radius: MAX_TORSO_RADIUS,
        ..FilterConfig::default()
    };
    assert!(edge.validate().is_ok());
}
