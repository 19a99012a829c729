//! Sweet Home 3D's furniture models read as solids: they need `scripts/fetch_sweethome3d.sh`
//! (the models are GPL and never committed). Where the catalogue is absent each test says by
//! name that it did not run; under CI (`CI=true`, where `.ci/run` fetches it first) a missing
//! catalogue fails.

use envfield_scene::nalgebra::Point3;
use envfield_scene::{
    catalogue_room, Catalogue, ObjectKind, Part, RoomConfig, Scene, SceneObject, TriangleMesh,
};

fn catalogue(test: &str) -> Option<Catalogue> {
    let found = Catalogue::find().or_else(|| {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/sweethome3d");
        dir.join("DefaultFurnitureCatalog.properties")
            .is_file()
            .then_some(dir)
    });
    match found {
        Some(dir) => Some(Catalogue::read(dir).expect("the catalogue reads")),
        None => {
            let reason =
                "the Sweet Home 3D catalogue is not fetched (scripts/fetch_sweethome3d.sh)";
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "CI=true: {reason}"
            );
            eprintln!("{test} did not run: {reason}");
            None
        }
    }
}

fn item(cat: &Catalogue, name: &str) -> usize {
    cat.items
        .iter()
        .position(|i| i.name == name)
        .unwrap_or_else(|| panic!("no `{name}` in the catalogue"))
}

fn m_depth(m: &TriangleMesh) -> f32 {
    let ys = m.vertices.iter().map(|v| v.y);
    ys.clone().fold(f32::MIN, f32::max) - ys.fold(f32::MAX, f32::min)
}

fn scene_of(mesh: &TriangleMesh) -> Scene {
    let mut object = SceneObject::new("model", ObjectKind::Other);
    object.push(Part::mesh(mesh).unwrap());
    let mut scene = Scene::new();
    scene.add(object).unwrap();
    scene
}

#[test]
fn catalogue_models_are_solid_where_closed_and_open_where_people_go() {
    let Some(cat) = catalogue("catalogue_models_are_solid_where_closed_and_open_where_people_go")
    else {
        return;
    };
    let kinds = cat.kinds();
    for k in [
        ObjectKind::Bed,
        ObjectKind::Sofa,
        ObjectKind::Chair,
        ObjectKind::Table,
        ObjectKind::Desk,
        ObjectKind::Cabinet,
        ObjectKind::Shelf,
        ObjectKind::Piano,
    ] {
        assert!(kinds.contains(&k), "{k:?} missing from {kinds:?}");
    }
    let d = |scene: &Scene, x: f32, y: f32, z: f32| {
        scene.signed_distance(&Point3::new(x, y, z)).unwrap()
    };
    // Each model stands on z = 0 at its catalogue size, footprint centred.
    for (i, it) in cat.items.iter().enumerate() {
        let m = cat.model(i).unwrap();
        let (mut lo, mut hi) = (Point3::from([f32::MAX; 3]), Point3::from([f32::MIN; 3]));
        for v in &m.vertices {
            lo = lo.inf(v);
            hi = hi.sup(v);
        }
        for a in 0..3 {
            assert!(
                ((hi[a] - lo[a]) - it.size[a]).abs() < 1e-3,
                "{}: {lo} {hi} {:?}",
                it.name,
                it.size
            );
        }
        assert!(
            lo.z.abs() < 1e-4 && (lo.x + hi.x).abs() < 1e-3,
            "{}",
            it.name
        );
    }
    // Tables: open space under the top, solid in the top.
    for name in ["Square table", "Round table", "Table"] {
        let it = &cat.items[item(&cat, name)];
        let table = scene_of(&cat.model(item(&cat, name)).unwrap());
        // Halfway between the middle (a round table's foot) and the corner (a leg).
        let (x, y) = (it.size[0] / 4.0, it.size[1] / 4.0);
        assert!(
            d(&table, x, y, 0.35) > 0.1,
            "{name}: under the top {}",
            d(&table, x, y, 0.35)
        );
        let top = table
            .cast_ray(
                &Point3::new(0.0, 0.0, 2.0),
                &-envfield_scene::nalgebra::Vector3::z(),
                3.0,
            )
            .unwrap()
            .unwrap();
        assert!(
            (top.point.z - it.size[2]).abs() < 0.03,
            "{name}: top at {}",
            top.point.z
        );
    }
    // Closed carcasses: the middle of a wardrobe, a chest, a kitchen cabinet and a piano's
    // body is inside, whatever their winding; the wardrobe's hollow too.
    for (name, z) in [
        ("Wardrobe", 1.0),
        ("Chest", 0.4),
        ("Kitchen cabinet", 0.45),
        ("Piano", 0.6),
    ] {
        let model = cat.model(item(&cat, name)).unwrap();
        for flip in [false, true] {
            let mut m = (*model).clone();
            if flip {
                for t in &mut m.triangles {
                    t.swap(1, 2);
                }
            }
            let s = scene_of(&m);
            // A little behind the middle: a piano's keys stand out in front.
            let y = -0.1 * m_depth(&m);
            assert!(
                d(&s, 0.0, y, z) < 0.0,
                "{name} (flipped {flip}): {}",
                d(&s, 0.0, y, z)
            );
        }
    }
    // A chair's seat is solid, the space in front of it is not.
    let chair = scene_of(&cat.model(item(&cat, "Chair")).unwrap());
    assert!(d(&chair, 0.0, 0.6, 0.45) > 0.1);
}

#[test]
fn catalogue_rooms_hold_every_kind_and_keep_their_floor() {
    let Some(cat) = catalogue("catalogue_rooms_hold_every_kind_and_keep_their_floor") else {
        return;
    };
    let config = RoomConfig {
        furniture: [8, 10],
        ..RoomConfig::default()
    };
    let mut seen = std::collections::HashSet::new();
    for seed in 0..4 {
        let room = catalogue_room(&cat, &config, seed).unwrap();
        assert!(
            room.furniture.len() >= 4,
            "seed {seed}: {:?}",
            room.furniture.len()
        );
        for f in &room.furniture {
            seen.insert(f.kind);
            let o = &room.scene.objects()[f.object];
            assert_eq!(o.kind, f.kind);
            // The piece stands inside the room, on the floor.
            let b = o.aabb().unwrap();
            assert!(b.mins.z.abs() < 0.01 && b.mins.x > -0.01 && b.maxs.x < room.size[0] + 0.01);
        }
        // A metre above the middle of the free floor is air.
        let floor = room
            .scene
            .signed_distance(&Point3::new(0.05, 0.05, 0.02))
            .unwrap();
        assert!(floor > 0.0 && floor < 0.05, "{floor}");
    }
    assert!(seen.len() >= 6, "{seen:?}");
}
