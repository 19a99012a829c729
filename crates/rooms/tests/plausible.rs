//! Plausible poses and the implausibility measure, against a known answer: a table in an
//! otherwise empty room. A body standing with the table top between its knees and hips has
//! every joint clear, so the joint checks pass it; the bone check does not.

use envfield_affordance::{afford, plausible, FilterConfig};
use envfield_affordance::{
    bones_clear, check_pose, sit_down, standing_pose, AffordanceConfig, Pose, SitConfig, Support,
};
use envfield_plan::space3::straight_line;
use envfield_rooms::harness::{pairs, PairKind, PairOptions};
use envfield_rooms::nav::clear_beneath;
use envfield_rooms::quality::implausible;
use envfield_rooms::{AccessibleRegion, PoseFilter, RegionConfig, SitDown};
use envfield_scene::nalgebra::{Isometry3, Point3, Vector3};
use envfield_scene::{Furniture, ObjectKind, Primitive, Room, Scene, SceneObject};

fn at(x: f32, y: f32, z: f32) -> Isometry3<f32> {
    Isometry3::translation(x, y, z)
}

/// A 4 x 4 m floor and one piece of furniture, `piece`, known to the room as a box of `size`
/// centred at (2, 2).
fn room_with(piece: SceneObject, size: [f32; 3], seat_height: Option<f32>) -> Room {
    let mut scene = Scene::new();
    let floor = SceneObject::new("floor", ObjectKind::Floor)
        .with(Primitive::cuboid([4.0, 4.0, 0.1]), at(2.0, 2.0, -0.05))
        .unwrap();
    scene.add(floor).unwrap();
    let kind = piece.kind;
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
            seat_height,
            seat_forward: None,
        }],
    }
}

/// A 1.2 x 0.8 m table, its 4 cm top at 0.70-0.74 m, centred at (2, 2), on a 4 x 4 m floor.
fn table_room() -> Room {
    let mut table = SceneObject::new("table", ObjectKind::Table)
        .with(Primitive::cuboid([1.2, 0.8, 0.04]), at(2.0, 2.0, 0.72))
        .unwrap();
    for (dx, dy) in [(-0.55, -0.35), (0.55, -0.35), (-0.55, 0.35), (0.55, 0.35)] {
        table = table
            .with(
                Primitive::cuboid([0.05, 0.05, 0.7]),
                at(2.0 + dx, 2.0 + dy, 0.35),
            )
            .unwrap();
    }
    room_with(table, [1.2, 0.8, 0.74], None)
}

/// `pose` moved so its torso is at `(x, y)` and its lowest joint at height `low`.
fn placed(pose: Pose, x: f32, y: f32, low: f32) -> Pose {
    let t = pose.torso();
    pose.translated(&Vector3::new(x - t.x, y - t.y, low - pose.lowest()))
}

#[test]
fn a_body_standing_through_a_table_top_passes_the_joints_but_not_the_bones() {
    let room = table_room();
    let config = AffordanceConfig::default();
    // Feet on the floor under the table's middle: the top lies between knees and hips.
    let through = placed(standing_pose(), 2.0, 2.0, 0.05);
    let r = check_pose(&room.scene, &through, Support::Standing, &config).unwrap();
    assert!(r.valid(), "the joint checks should not see it: {r:?}");
    assert!(!bones_clear(
        &room.scene,
        &through,
        Support::Standing,
        &config,
        0.03,
        0.02
    )
    .unwrap());
    assert!(!plausible(&room.scene, &through, Support::Standing, &config).unwrap());
    let torso: [f32; 3] = through.torso().into();
    assert_eq!(implausible(&room, torso).unwrap(), Some(ObjectKind::Table));
    // The filter keeps that torso only with the rule off.
    let on = FilterConfig::default();
    let off = FilterConfig {
        plausible: false,
        settle: 0.0,
        ..on
    };
    assert!(afford(&room.scene, torso, &off).unwrap().kept());
    assert!(!afford(&room.scene, torso, &on).unwrap().kept());

    // The same body on the open floor is plausible, and so is its torso.
    let open = placed(standing_pose(), 0.8, 0.8, 0.05);
    assert!(plausible(&room.scene, &open, Support::Standing, &config).unwrap());
    assert_eq!(implausible(&room, open.torso().into()).unwrap(), None);
    assert!(afford(&room.scene, open.torso().into(), &on)
        .unwrap()
        .kept());
}

#[test]
fn a_body_seated_on_a_table_top_hangs_its_feet_and_is_implausible() {
    let room = table_room();
    let config = AffordanceConfig::default();
    let seated = *sit_down(&SitConfig::default())
        .unwrap()
        .frames
        .last()
        .unwrap();
    // Hips on the top's middle, 0.1 m above it (where a pelvis joint sits on a seat).
    let t = seated.torso();
    let on_top = seated.translated(&Vector3::new(2.0 - t.x, 2.0 - t.y, 0.84 - t.z));
    let r = check_pose(&room.scene, &on_top, Support::Sitting, &config).unwrap();
    assert!(r.supported, "{r:?}");
    assert!(!plausible(&room.scene, &on_top, Support::Sitting, &config).unwrap());
    assert_eq!(
        implausible(&room, on_top.torso().into()).unwrap(),
        Some(ObjectKind::Table)
    );
    // Implausible is judged by the known furniture: inside the table's box too.
    assert_eq!(
        implausible(&room, [2.3, 2.1, 0.4]).unwrap(),
        Some(ObjectKind::Table)
    );
    assert!(implausible(&room, [f32::NAN, 0.0, 0.0]).is_err());
}

#[test]
fn a_pelvis_over_the_tables_edge_has_the_top_beneath_it() {
    let room = table_room();
    // The table's top spans x in [1.4, 2.6]: a pelvis 3 cm inside its edge has the top
    // straight beneath it, above the knees; 10 cm outside, air down to the knees.
    let over = placed(standing_pose(), 1.43, 2.0, 0.0);
    let beside = placed(standing_pose(), 1.30, 2.0, 0.0);
    assert!(!clear_beneath(&room.scene, &over).unwrap());
    assert!(clear_beneath(&room.scene, &beside).unwrap());
    assert_eq!(
        implausible(&room, over.torso().into()).unwrap(),
        Some(ObjectKind::Table)
    );
    assert_eq!(implausible(&room, beside.torso().into()).unwrap(), None);
    // In the open room, nothing beneath.
    let open = placed(standing_pose(), 0.8, 0.8, 0.0);
    assert!(clear_beneath(&room.scene, &open).unwrap());
}

#[test]
fn over_a_chairs_base_a_body_stands_on_the_floor_and_on_its_seat_it_stands_on_a_seat() {
    // An office chair: a wide base 3 cm high, a column, a 0.45 m seat 0.5 m square.
    let chair = SceneObject::new("chair", ObjectKind::Chair)
        .with(Primitive::cuboid([0.7, 0.7, 0.03]), at(2.0, 2.0, 0.015))
        .unwrap()
        .with(Primitive::cuboid([0.05, 0.05, 0.4]), at(2.0, 2.0, 0.23))
        .unwrap()
        .with(Primitive::cuboid([0.5, 0.5, 0.05]), at(2.0, 2.0, 0.425))
        .unwrap();
    let room = room_with(chair, [0.7, 0.7, 0.45], Some(0.45));
    // A standing torso over the base's rim, beside the seat: the base lies between the feet.
    let beside = placed(standing_pose(), 2.31, 2.0, 0.0);
    assert_eq!(implausible(&room, beside.torso().into()).unwrap(), None);
    // Standing on the seat is standing on a seat.
    let on_seat = placed(standing_pose(), 2.0, 2.0, 0.45);
    assert_eq!(
        implausible(&room, on_seat.torso().into()).unwrap(),
        Some(ObjectKind::Chair)
    );
    // Seated on it is what a chair is for.
    assert_eq!(implausible(&room, [2.0, 2.0, 0.55]).unwrap(), None);
}

#[test]
fn a_bar_between_the_legs_below_the_shins_is_not_clear_beneath() {
    // A stool's footrest bar 0.23 m up, beside its 0.45 m seat: half the seat's height, below
    // a standing body's shins. The body stands with the bar between its legs.
    let stool = SceneObject::new("stool", ObjectKind::Chair)
        .with(Primitive::cuboid([0.4, 0.4, 0.05]), at(2.0, 2.0, 0.425))
        .unwrap()
        .with(Primitive::cuboid([0.05, 0.05, 0.4]), at(2.0, 2.0, 0.2))
        .unwrap()
        .with(Primitive::cuboid([0.03, 0.8, 0.03]), at(2.0, 2.0, 0.23))
        .unwrap();
    let room = room_with(stool, [0.4, 0.8, 0.45], Some(0.45));
    let over_bar = placed(standing_pose(), 2.0, 2.36, 0.0);
    assert!(!clear_beneath(&room.scene, &over_bar).unwrap());
    assert_eq!(
        implausible(&room, over_bar.torso().into()).unwrap(),
        Some(ObjectKind::Chair)
    );
    // A step to the side, only the floor beneath: 5 cm above the soles is where it stops.
    let beside = placed(standing_pose(), 2.3, 2.36, 0.0);
    assert!(clear_beneath(&room.scene, &beside).unwrap());
    // The same body lifted 4 cm off the floor still counts the floor as beneath its feet.
    let lifted = placed(standing_pose(), 2.3, 2.36, 0.04);
    assert!(clear_beneath(&room.scene, &lifted).unwrap());
}

/// A room with a 0.5 m box seat, 0.45 m high, in the middle of its floor, and its region from
/// standing torsos over the floor and seated ones over the seat, as the filter keeps them; the
/// standing and the seated torsos' heights.
fn seat_region() -> (Room, AccessibleRegion, f32, f32) {
    let seat = SceneObject::new("seat", ObjectKind::Chair)
        .with(Primitive::cuboid([0.5, 0.5, 0.45]), at(2.0, 2.0, 0.225))
        .unwrap();
    let room = room_with(seat, [0.5, 0.5, 0.45], Some(0.45));
    let standing = placed(standing_pose(), 0.0, 0.0, 0.0).torso().z;
    let sit = sit_down(&SitConfig::default()).unwrap();
    let seated = sit.frames.last().unwrap().torso().z;
    let config = RegionConfig::default();
    // The premise: a seated torso's voxel is two voxels or more below a standing one's, so the
    // seat's voxels do not touch the floor's.
    assert!(
        standing - seated > 2.0 * config.voxel,
        "{standing} {seated}"
    );
    let mut drawn = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            drawn.push([0.05 + 0.1 * i as f32, 0.05 + 0.1 * j as f32, standing]);
        }
    }
    for i in -1..=1 {
        for j in -1..=1 {
            drawn.push([2.0 + 0.08 * i as f32, 2.0 + 0.08 * j as f32, seated]);
        }
    }
    let kept: Vec<[f32; 3]> = drawn
        .iter()
        .map(|&p| afford(&room.scene, p, &config.filter).unwrap())
        .filter(|a| a.kept())
        .map(|a| a.at)
        .collect();
    assert!(
        kept.iter().any(|p| p[2] < standing - 0.2),
        "a seated torso is kept"
    );
    let region = AccessibleRegion::from_kept(&room.scene, kept, &config).unwrap();
    (room, region, standing, seated)
}

#[test]
fn a_seat_joins_the_region_through_a_sit_down() {
    let (room, region, standing, seated) = seat_region();
    let config = RegionConfig::default();
    assert!(
        region.contains([0.55, 0.55, standing]),
        "the floor is in the region"
    );
    assert!(
        region.contains([2.0, 2.0, seated]),
        "the seat is joined to the floor's set"
    );
    // The sit-downs that joined it: each starts standing in the region, ends seated in it
    // where it says, and every pose of it is valid.
    assert!(!region.sit_downs.is_empty());
    for sit in &region.sit_downs {
        assert!(
            region.contains(sit.start) && region.contains(sit.seated),
            "{sit:?}"
        );
        let seq = sit.sequence().unwrap();
        let (first, last) = (seq.frames[0].torso(), seq.frames.last().unwrap().torso());
        assert!((first - Point3::from(sit.start)).norm() < 1e-4, "{sit:?}");
        assert!((last - Point3::from(sit.seated)).norm() < 1e-4, "{sit:?}");
        assert!(sit.seated[2] < sit.start[2] - 0.2, "it sits down: {sit:?}");
        for (pose, &support) in seq.frames.iter().zip(&seq.supports) {
            let r = check_pose(&room.scene, pose, support, &config.filter.affordance).unwrap();
            assert!(r.valid(), "{sit:?}: {r:?}");
        }
    }
}

#[test]
fn a_sit_down_off_its_range_or_not_finite_is_an_error() {
    let sit = SitDown {
        start: [0.0; 3],
        seated: [1.0, 1.0, 0.55],
        seat_height: 0.45,
        yaw: 0.5,
    };
    assert_eq!(sit.sequence().unwrap().frames.len(), 60);
    let high = SitDown {
        seat_height: 0.9,
        ..sit
    };
    let e = high.sequence().unwrap_err().to_string();
    assert!(e.contains("seat height"), "{e}");
    for bad in [
        SitDown {
            seated: [f32::NAN, 1.0, 0.55],
            ..sit
        },
        SitDown {
            yaw: f32::INFINITY,
            ..sit
        },
    ] {
        let e = bad.sequence().unwrap_err().to_string();
        assert!(e.contains("frame 0"), "{e}");
    }
}

/// A sit-down played in place wears, at each point, the frame whose torso lies nearest: along
/// its own recording it gives back its recorded poses, and a path of fewer steps than the
/// recording still arrives seated, where counting steps would arrive still lowering.
#[test]
fn a_sit_down_played_in_place_follows_where_its_torso_is() {
    let (room, region, _, _) = seat_region();
    let sit = &region.sit_downs[0];
    let seq = sit.sequence().unwrap();
    let mut filter = PoseFilter {
        scene: &room.scene,
        region: &region,
        sequence: &seq,
        repeat: false,
        face_the_move: false,
        affordance: Default::default(),
        clear_beneath: false,
        in_place: true,
        tables: None,
    };
    let recorded: Vec<[f32; 3]> = seq.frames.iter().map(|f| f.torso().into()).collect();
    let (poses, _) = filter.poses_along(&recorded).unwrap();
    for (k, (a, b)) in poses.frames.iter().zip(&seq.frames).enumerate() {
        let off = (0..a.joints.len())
            .map(|j| (a.joints[j] - b.joints[j]).norm())
            .fold(0.0f32, f32::max);
        assert!(off < 1e-4, "frame {k}: {off}");
    }
    // The chord from standing to seated in fewer steps than the recording's.
    let chord = straight_line(sit.start, sit.seated, 1.5 * seq.step_length()).unwrap();
    assert!(
        chord.len() < 2 * seq.frames.len() / 3 + 2,
        "{}",
        chord.len()
    );
    let (in_place, reports) = filter.poses_along(&chord).unwrap();
    let seated = seq.frames.last().unwrap();
    let off = |a: &Pose| {
        (0..a.joints.len())
            .map(|j| (a.joints[j] - seated.joints[j]).norm())
            .fold(0.0f32, f32::max)
    };
    assert!(off(in_place.frames.last().unwrap()) < 1e-4);
    assert_eq!(*in_place.supports.last().unwrap(), Support::Sitting);
    assert!(reports.last().unwrap().valid(), "{:?}", reports.last());
    filter.in_place = false;
    let (by_steps, _) = filter.poses_along(&chord).unwrap();
    assert!(
        off(by_steps.frames.last().unwrap()) > 0.02,
        "counting steps, the chord ends on an earlier frame: {} of {} points, {}",
        chord.len(),
        seq.frames.len(),
        off(by_steps.frames.last().unwrap())
    );
}

/// In a scene read without its furniture list, the sit-down pairs come from the region's own
/// sit-downs: one a seat, each starting standing in the region and ending seated in it.
#[test]
fn a_scene_without_a_furniture_list_still_gets_its_sit_downs() {
    let (room, region, _, _) = seat_region();
    let options = PairOptions {
        walks: 0,
        ..PairOptions::default()
    };
    let unknown = pairs(None, &room.scene, &region, &options).unwrap();
    let known = pairs(Some(&room), &room.scene, &region, &options).unwrap();
    assert_eq!(unknown.len(), 1, "one seat, one sit-down pair");
    assert_eq!(known.len(), 1);
    for p in &unknown {
        assert_eq!(p.kind, PairKind::Sit);
        assert!(region.contains(p.start) && region.contains(p.goal), "{p:?}");
        assert!(region.sit_downs.iter().any(|s| s.seated == p.goal));
    }
    // Without sit-downs asked for, none.
    let none = PairOptions {
        sit_downs: false,
        ..options
    };
    assert!(pairs(None, &room.scene, &region, &none).unwrap().is_empty());
}

/// With the scene's rooms known, every other walk (the first included) goes from one room to
/// another.
#[test]
fn walks_go_between_rooms_when_the_rooms_are_known() {
    let (room, region, _, _) = seat_region();
    let halves = [[0.0, 0.0, 2.0, 4.0], [2.0, 0.0, 4.0, 4.0]];
    let options = PairOptions {
        walks: 6,
        sit_downs: false,
        rooms: &halves,
        seed: 5,
        ..PairOptions::default()
    };
    let walks = pairs(None, &room.scene, &region, &options).unwrap();
    assert_eq!(walks.len(), 6);
    let side = |p: [f32; 3]| p[0] < 2.0;
    for (k, w) in walks.iter().enumerate() {
        if k % 2 == 0 {
            assert_ne!(side(w.start), side(w.goal), "walk {k}: {w:?}");
        }
    }
}

/// A seat is judged by every place over its footprint where the filter seats a body: the box
/// seat has places, all over it, and the region holds them.
#[test]
fn a_seat_is_judged_by_every_place_on_it() {
    let (room, region, _, seated) = seat_region();
    let places = envfield_rooms::torsos::seat_places(&room, 0.1).unwrap();
    assert_eq!(places.len(), 1, "one seat");
    let (k, ps) = &places[0];
    assert_eq!(*k, 0);
    assert!(!ps.is_empty());
    for p in ps {
        assert!(room.furniture[0].covers(p[0], p[1]), "{p:?}");
        assert!((p[2] - seated).abs() < 0.3, "{p:?} vs {seated}");
    }
    assert!(ps.iter().any(|p| region.contains(*p)));
    assert!(envfield_rooms::torsos::seat_places(&room, 0.0).is_err());
}
