//! A level of two floors joined by a ramp, as a game level has them: the region built from the
//! scene's surfaces holds both floors and the ramp in one set, and a walk from the lower floor
//! to the upper one climbs the ramp with every pose supported.

use envfield_affordance::{standing_pose, walk, WalkConfig};
use envfield_grid::ContinuousField3;
use envfield_rooms::harness::{run_pair, Pair, PairKind, RoomContext, RoomPlanner, RunSettings};
use envfield_rooms::{standing_torsos, AccessibleRegion, ExactField3, RegionConfig};
use envfield_scene::nalgebra::{Isometry3, Translation3, UnitQuaternion};
use envfield_scene::{ObjectKind, Primitive, Scene, SceneObject};

/// A floor 9 x 3 m at z = 0; a platform over x in [5, 9] with its top at 1 m; a ramp from
/// x = 2 (on the floor) to x = 5 (the platform's edge), 18 degrees.
fn two_floors() -> Scene {
    let mut s = Scene::new();
    let mut add = |name: &str, size: [f32; 3], at: [f32; 3], pitch: f32| {
        let pose = Isometry3::from_parts(
            Translation3::new(at[0], at[1], at[2]),
            UnitQuaternion::from_euler_angles(0.0, pitch, 0.0),
        );
        let o = SceneObject::new(name, ObjectKind::Floor)
            .with(Primitive::cuboid(size), pose)
            .unwrap();
        s.add(o).unwrap();
    };
    add("floor", [9.0, 3.0, 0.1], [4.5, 1.5, -0.05], 0.0);
    add("platform", [4.0, 3.0, 1.0], [7.0, 1.5, 0.5], 0.0);
    // Its top surface runs from (2, 0) to (5, 1): the box's centre half its thickness below.
    let pitch = (1.0f32 / 3.0).atan();
    let (len, t) = (10f32.sqrt(), 0.1);
    add(
        "ramp",
        [len, 3.0, t],
        [
            3.5 + 0.5 * t * pitch.sin(),
            1.5,
            0.5 - 0.5 * t * pitch.cos(),
        ],
        -pitch,
    );
    s
}

#[test]
fn the_standing_region_joins_two_floors_by_their_ramp_and_ours_climbs_it() {
    let scene = two_floors();
    // The torso's height over the surface the standing pose's soles rest on.
    let pose = standing_pose();
    let up = pose.torso().z - pose.lowest();
    let torsos = standing_torsos(&scene, 0.1).unwrap();
    // Each column over the floor alone carries one torso; over the platform, its top and the
    // floor beneath it (inside the platform: the filter drops it).
    assert!(torsos.iter().any(|t| (t[2] - (1.0 + up)).abs() < 0.01));
    let region = AccessibleRegion::standing(&scene, &RegionConfig::default()).unwrap();
    let (low, high) = ([1.0, 1.5, up], [7.5, 1.5, 1.0 + up]);
    assert!(region.contains(low), "the lower floor");
    assert!(region.contains(high), "the platform");
    assert!(
        !region.contains([7.5, 1.5, up]),
        "no torso inside the platform"
    );
    // Joined through the ramp: the exact field climbs it, longer than the straight line.
    let field = ExactField3::new(&region, high).unwrap();
    let d = field.value(low).unwrap();
    let straight = ((high[0] - low[0]).powi(2) + (high[2] - low[2]).powi(2)).sqrt();
    assert!(d.is_finite() && d >= straight && d < straight + 1.0, "{d}");

    let pair = Pair {
        start: low,
        goal: high,
        sequence: walk(&WalkConfig::default(), 1).unwrap(),
        repeat: true,
        kind: PairKind::Walk,
    };
    let room = RoomContext::bare(&scene, &region);
    let settings = RunSettings {
        budget: 5.0,
        big_budget: 0,
        sampler_budget: 500,
        seed: 1,
        ..RunSettings::default()
    };
    let runs = run_pair(&room, &pair, &[RoomPlanner::OursExact], &settings).unwrap();
    let ours = &runs[0];
    assert!(ours.outcome.reached, "{:?}", ours.outcome);
    assert!(ours.outcome.poses.valid >= 95.0, "{:?}", ours.outcome.poses);
    // Up the ramp: every torso of the path stands over the surface beneath it (the floor,
    // the ramp's slope, the platform), within the region's voxel.
    let surface = |x: f32| ((x - 2.0) / 3.0).clamp(0.0, 1.0);
    for p in &ours.path {
        let over = p[2] - up - surface(p[0]);
        assert!(
            (-0.1..=0.15).contains(&over),
            "{p:?} is {over} m over the surface"
        );
    }
    // Without a net, the planners that descend the learned field say so.
    let e = run_pair(&room, &pair, &[RoomPlanner::Ours], &settings)
        .unwrap_err()
        .to_string();
    assert!(e.contains("needs a field"), "{e}");
}
