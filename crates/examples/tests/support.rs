//! The navigation-mesh baseline and the scene flags, tested on their own.

use clap::Parser;
use envfield_affordance::{walk, WalkConfig};
use envfield_examples::{Navmesh, NavmeshConfig, SceneArgs};
use envfield_rooms::harness::FloorPlanner;
use envfield_scene::nalgebra::Isometry3;
use envfield_scene::{ObjectKind, Primitive, RoomConfig, Scene, SceneObject};

/// A floor 6 x 4 m with a wall 0.2 m thick across x = 3 from y = 0 to y = 3: a way round it
/// at y > 3 only.
fn walled() -> Scene {
    let mut s = Scene::new();
    let floor = SceneObject::new("floor", ObjectKind::Floor)
        .with(
            Primitive::cuboid([6.0, 4.0, 0.1]),
            Isometry3::translation(3.0, 2.0, -0.05),
        )
        .unwrap();
    let wall = SceneObject::new("wall", ObjectKind::Wall)
        .with(
            Primitive::cuboid([0.2, 3.0, 2.4]),
            Isometry3::translation(3.0, 1.5, 1.2),
        )
        .unwrap();
    s.add(floor).unwrap();
    s.add(wall).unwrap();
    s
}

#[test]
fn the_navigation_mesh_goes_round_a_wall_and_not_through_it() {
    let gait = walk(&WalkConfig::default(), 0).unwrap();
    let mesh = Navmesh::build(&walled(), &NavmeshConfig::for_gait(&gait)).unwrap();
    assert!(mesh.polygons > 0 && mesh.bytes() > 0);
    let (start, goal) = ([1.0, 1.0, 0.93], [5.0, 1.0, 0.93]);
    let path = mesh
        .floor_path(start, goal)
        .unwrap()
        .expect("a path round the wall");
    assert_eq!(path.first(), Some(&start));
    assert_eq!(path.last(), Some(&goal));
    // Round the wall's end at y = 3 (plus the body's radius): from (1, 1) up past (3, 3) and
    // down to (5, 1) is 5.7 m at least, where the straight line through the wall is 4 m.
    let length: f32 = path
        .windows(2)
        .map(|w| {
            (0..3)
                .map(|a| (w[1][a] - w[0][a]).powi(2))
                .sum::<f32>()
                .sqrt()
        })
        .sum();
    assert!(length > 5.6, "{length} m: {path:?}");
    assert!(path.iter().any(|p| p[1] > 3.0), "{path:?}");
}

#[test]
fn a_start_off_the_mesh_has_no_path_rather_than_an_error() {
    let gait = walk(&WalkConfig::default(), 0).unwrap();
    let mesh = Navmesh::build(&walled(), &NavmeshConfig::for_gait(&gait)).unwrap();
    let outside = mesh
        .floor_path([20.0, 20.0, 0.93], [1.0, 1.0, 0.93])
        .unwrap();
    assert!(outside.is_none());
}

/// A scene wound the other way (as some exporters write it: every triangle's vertices in the
/// opposite order) gives the navigation mesh the same floor and the same path round the wall:
/// once only upward-facing triangles were walkable, and it reached nothing.
#[test]
fn the_navigation_mesh_does_not_care_how_the_scene_is_wound() {
    let gait = walk(&WalkConfig::default(), 0).unwrap();
    let config = NavmeshConfig::for_gait(&gait);
    let mut flipped = walled().to_mesh();
    for t in &mut flipped.triangles {
        t.swap(1, 2);
    }
    let flipped = Scene::from_mesh("flipped", &flipped).unwrap();
    let (a, b) = (
        Navmesh::build(&walled(), &config).unwrap(),
        Navmesh::build(&flipped, &config).unwrap(),
    );
    assert!(b.polygons > 0, "no walkable floor when wound the other way");
    let (start, goal) = ([1.0, 1.0, 0.93], [5.0, 1.0, 0.93]);
    let length = |m: &Navmesh| {
        let path = m.floor_path(start, goal).unwrap().expect("a path");
        path.windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum::<f32>()
    };
    let (la, lb) = (length(&a), length(&b));
    assert!((la - lb).abs() < 0.05, "{la} m against {lb} m");
}

#[derive(Parser)]
struct Args {
    #[command(flatten)]
    scene: SceneArgs,
}

#[test]
fn the_scene_flags_read_a_file_and_make_rooms() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("walled.obj");
    walled().to_mesh().write(&file).unwrap();
    let args = Args::parse_from(["x", "--scene", file.to_str().unwrap()]);
    let scene = args.scene.read(None).unwrap().expect("a scene");
    assert!(!scene.objects().is_empty());
    // `--room` is the same flag (birdseye_multi's old name).
    let old = Args::parse_from(["x", "--room", file.to_str().unwrap()]);
    assert_eq!(old.scene.scene, args.scene.scene);
    let generated = Args::parse_from(["x"]);
    let rooms = generated.scene.rooms(RoomConfig::default()).unwrap();
    let (_, room) = generated.scene.scene(&rooms, 3, None).unwrap();
    assert!(room.is_some_and(|r| !r.furniture.is_empty()));
    let missing = Args::parse_from(["x", "--scene", "no/such/file.obj"]);
    let e = missing.scene.read(None).unwrap_err();
    assert!(format!("{e:#}").contains("no/such/file.obj"), "{e:#}");
}
