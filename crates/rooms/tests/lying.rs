//! Lying down: the region carries a body from standing beside a bed, through sitting on its
//! edge, to lying on it, every pose valid and plausible; a chair gives no lie-down; the pairs
//! put a lie-down at every bed.

use envfield_affordance::{
    afford, check_pose, lie_down, plausible, sit_down, standing_pose, LieConfig, SitConfig, Support,
};
use envfield_rooms::harness::{pairs, PairKind, PairOptions};
use envfield_rooms::{AccessibleRegion, RegionConfig};
use envfield_scene::nalgebra::{Isometry3, Point3};
use envfield_scene::{Furniture, ObjectKind, Primitive, Room, Scene, SceneObject};

/// A 4 x 4 m floor and one box of `size` (x, y, height) standing centred at (2, 2), known to
/// the room as a `kind` with its seat on top.
fn room_with(kind: ObjectKind, size: [f32; 3]) -> Room {
    let mut scene = Scene::new();
    let floor = SceneObject::new("floor", ObjectKind::Floor)
        .with(
            Primitive::cuboid([4.0, 4.0, 0.1]),
            Isometry3::translation(2.0, 2.0, -0.05),
        )
        .unwrap();
    scene.add(floor).unwrap();
    let piece = SceneObject::new("piece", kind)
        .with(
            Primitive::cuboid(size),
            Isometry3::translation(2.0, 2.0, size[2] / 2.0),
        )
        .unwrap();
    let object = scene.add(piece).unwrap();
    Room {
        scene,
        size: [4.0, 4.0],
        furniture: vec![Furniture {
            kind,
            object,
            center: [2.0, 2.0],
            yaw: 0.0,
            size,
            seat_height: Some(size[2]),
            seat_forward: None,
        }],
    }
}

/// The region of `room` from standing torsos over its floor (10 cm apart) and seated ones over
/// its piece (10 cm apart), as the filter keeps them.
fn region_of(room: &Room) -> AccessibleRegion {
    let config = RegionConfig::default();
    let standing = standing_pose().torso().z - standing_pose().lowest();
    let seated = {
        let s = sit_down(&SitConfig {
            seat_height: room.furniture[0].size[2],
            ..SitConfig::default()
        })
        .unwrap();
        s.frames.last().unwrap().torso().z
    };
    let f = &room.furniture[0];
    let mut drawn = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            drawn.push([0.05 + 0.1 * i as f32, 0.05 + 0.1 * j as f32, standing]);
        }
    }
    let (nx, ny) = ((f.size[0] / 0.1) as i32, (f.size[1] / 0.1) as i32);
    for i in 0..nx {
        for j in 0..ny {
            drawn.push([
                2.0 - f.size[0] / 2.0 + 0.05 + 0.1 * i as f32,
                2.0 - f.size[1] / 2.0 + 0.05 + 0.1 * j as f32,
                seated,
            ]);
        }
    }
    let kept: Vec<[f32; 3]> = drawn
        .iter()
        .map(|&p| afford(&room.scene, p, &config.filter).unwrap())
        .filter(|a| a.kept())
        .map(|a| a.at)
        .collect();
    AccessibleRegion::from_kept(&room.scene, kept, &config).unwrap()
}

#[test]
fn a_bed_is_lain_on_from_standing_beside_it() {
    // A 2 m long, 1.4 m wide bed, as high as a generated room's (0.5 m) and higher than the
    // shank is long (0.62 m: the thighs slope down over its edge).
    for h in [0.5, 0.62] {
        lain_on(h);
    }
}

fn lain_on(h: f32) {
    let room = room_with(ObjectKind::Bed, [2.0, 1.4, h]);
    let region = region_of(&room);
    let config = RegionConfig::default();
    assert!(!region.lie_downs.is_empty(), "a bed gives lie-downs");
    let bed = &room.furniture[0];
    for lie in &region.lie_downs {
        let seq = lie.sequence().unwrap();
        let last = seq.frames.last().unwrap();
        // It starts standing where its sit-down does, in the region, and ends lying where it
        // says, on the bed, in the region.
        assert!((seq.frames[0].torso() - Point3::from(lie.sit.start)).norm() < 1e-4);
        assert!((last.torso() - Point3::from(lie.lying)).norm() < 1e-4);
        assert!(region.contains(lie.sit.start) && region.contains(lie.lying));
        assert!(bed.covers(lie.lying[0], lie.lying[1]), "{lie:?}");
        assert_eq!(*seq.supports.last().unwrap(), Support::Lying);
        assert_eq!(seq.supports[0], Support::Standing);
        // Lying: the head as low as the pelvis, both on the bed's top.
        let (head, pelvis) = (
            last.joint(envfield_affordance::Joint::Head),
            last.joint(envfield_affordance::Joint::Pelvis),
        );
        assert!((head.z - pelvis.z).abs() < 0.1, "{head} {pelvis}");
        assert!((pelvis.z - h).abs() < 0.15, "{pelvis}");
        // Every pose valid, and plausible as its support or lying.
        for (k, (pose, &support)) in seq.frames.iter().zip(&seq.supports).enumerate() {
            let a = &config.filter.affordance;
            assert!(
                check_pose(&room.scene, pose, support, a).unwrap().valid(),
                "frame {k}"
            );
            if k >= seq.frames.len() - 60 {
                let rests = |s| plausible(&room.scene, pose, s, a).unwrap();
                assert!(rests(support) || rests(Support::Lying), "frame {k}");
            }
        }
    }
    // The pairs: with the bed known, one lie-down pair for it; from the scene alone, at least
    // one; each from standing in the region to lying on the bed.
    let options = PairOptions {
        walks: 0,
        ..PairOptions::default()
    };
    for room_known in [Some(&room), None] {
        let lying: Vec<_> = pairs(room_known, &room.scene, &region, &options)
            .unwrap()
            .into_iter()
            .filter(|p| p.kind == PairKind::Lie)
            .collect();
        if room_known.is_some() {
            assert_eq!(lying.len(), 1);
        } else {
            assert!(!lying.is_empty());
        }
        for p in &lying {
            assert!(region.contains(p.start) && region.contains(p.goal));
            assert!(bed.covers(p.goal[0], p.goal[1]));
            assert!(!p.repeat);
        }
    }
}

#[test]
fn a_chair_gives_no_lie_down() {
    // A 0.5 m box seat: a body sits on it, and nothing bears its head lying back.
    let room = room_with(ObjectKind::Chair, [0.5, 0.5, 0.45]);
    let region = region_of(&room);
    assert!(!region.sit_downs.is_empty(), "the seat is sat on");
    assert!(region.lie_downs.is_empty(), "{:?}", region.lie_downs);
    let options = PairOptions {
        walks: 0,
        ..PairOptions::default()
    };
    let kinds: Vec<PairKind> = pairs(Some(&room), &room.scene, &region, &options)
        .unwrap()
        .iter()
        .map(|p| p.kind)
        .collect();
    assert_eq!(kinds, [PairKind::Sit]);
}

/// The lie-down played from a seated start is the motion's own: it begins where the sit-down
/// ends, so the two join without a jump.
#[test]
fn lying_down_begins_where_sitting_down_ends() {
    for h in [0.35, 0.45, 0.5, 0.6, 0.7] {
        let sit = sit_down(&SitConfig {
            seat_height: h,
            ..SitConfig::default()
        })
        .unwrap();
        let lie = lie_down(&LieConfig {
            seat_height: h,
            ..LieConfig::default()
        })
        .unwrap();
        let (a, b) = (sit.frames.last().unwrap(), &lie.frames[0]);
        let worst = a
            .joints
            .iter()
            .zip(&b.joints)
            .map(|(p, q)| (p - q).norm())
            .fold(0.0f32, f32::max);
        assert!(worst < 0.01, "seat {h}: {worst} m apart");
    }
}

/// Ours on the exact field plans a lie-down pair to the end: from standing beside the bed to
/// lying on it, every pose along its path valid.
#[test]
fn ours_plans_a_lie_down_to_the_end() {
    // A bed lain on straight back from its edge, and a 0.8 m deep daybed lain along: the
    // legs swung up with a quarter turn.
    for size in [[2.0, 1.4, 0.5], [2.1, 0.8, 0.45]] {
        plans_to_the_end(size);
    }
}

fn plans_to_the_end(size: [f32; 3]) {
    use envfield_rooms::harness::{run_pair, RoomContext, RoomPlanner, RunSettings};
    let room = room_with(ObjectKind::Bed, size);
    let region = region_of(&room);
    let options = PairOptions {
        walks: 0,
        ..PairOptions::default()
    };
    let pair = pairs(Some(&room), &room.scene, &region, &options)
        .unwrap()
        .into_iter()
        .find(|p| p.kind == PairKind::Lie)
        .expect("a lie-down pair");
    if size[1] < 1.0 {
        // Too narrow to lie across: sat on from its long side, a lie-down turns to lie along
        // it (from its short end it lies straight back).
        assert!(region.lie_downs.iter().any(|l| l.turn != 0.0));
        for l in &region.lie_downs {
            let across = (l.sit.yaw + l.turn).sin().abs();
            assert!(across < 0.1, "it lies along the daybed: {l:?}");
        }
    }
    let context = RoomContext::bare(&room.scene, &region);
    let runs = run_pair(
        &context,
        &pair,
        &[RoomPlanner::OursExact],
        &RunSettings::default(),
    )
    .unwrap();
    let o = &runs[0].outcome;
    assert!(o.reached && !o.relaxed, "{o:?}");
    assert!(o.poses.valid > 95.0, "{o:?}");
    let last = runs[0].poses.frames.last().unwrap();
    assert_eq!(*runs[0].poses.supports.last().unwrap(), Support::Lying);
    assert!((last.torso() - Point3::from(pair.goal)).norm() < 0.05);
}
