//! Signed distances against analytic values and parry3d, meshes, rooms and their maps.

use approx::assert_relative_eq;
use envfield_grid::Cell3;
use envfield_grid::SplitMix64;
use envfield_scene::parry3d::query::PointQuery;
use envfield_scene::parry3d::shape::Cuboid;
use envfield_scene::{
    floor_map, generate_room, sample_surface, voxelize, FloorMapConfig, ObjectKind, Part,
    Primitive, RoomConfig, Scene, SceneError, SceneObject, TriangleMesh, VoxelFrame,
};
use nalgebra::{Isometry3, Point3, Vector3};

fn rand(rng: &mut SplitMix64, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * rng.next_f32()
}

fn random_point(rng: &mut SplitMix64, r: f32) -> Point3<f32> {
    Point3::new(rand(rng, -r, r), rand(rng, -r, r), rand(rng, -r, r))
}

fn one(primitive: Primitive, pose: Isometry3<f32>) -> Scene {
    let mut scene = Scene::new();
    scene
        .add(
            SceneObject::new("it", ObjectKind::Other)
                .with(primitive, pose)
                .unwrap(),
        )
        .unwrap();
    scene
}

fn box_sdf(local: Vector3<f32>, half: Vector3<f32>) -> f32 {
    let q = local.abs() - half;
    let outside = q.map(|v| v.max(0.0)).norm();
    outside + q.max().min(0.0)
}

#[test]
fn box_distances_match_the_analytic_formula_and_parry_inside_and_out() {
    let half = Vector3::new(0.4, 0.25, 0.6);
    let pose = Isometry3::new(Vector3::new(0.3, -0.2, 0.5), Vector3::new(0.2, -0.4, 0.9));
    let scene = one(
        Primitive::Cuboid {
            half_extents: half.into(),
        },
        pose,
    );
    let cuboid = Cuboid::new(half);
    let mut rng = SplitMix64::new(1);
    let mut inside = 0;
    for _ in 0..2000 {
        let p = random_point(&mut rng, 1.0) + Vector3::new(0.3, -0.2, 0.5);
        let d = scene.signed_distance(&p).unwrap();
        let local = pose.inverse_transform_point(&p).coords;
        assert_relative_eq!(d, box_sdf(local, half), epsilon = 1e-5);
        // parry's own queries: solid distance outside, containment inside.
        let contains = cuboid.contains_point(&pose, &p);
        assert_eq!(d < 0.0, contains, "sign at {p:?}");
        if contains {
            inside += 1;
        } else {
            assert_relative_eq!(d, cuboid.distance_to_point(&pose, &p, true), epsilon = 1e-5);
        }
    }
    assert!(
        inside > 50,
        "the test should probe the inside ({inside} points)"
    );
}

#[test]
fn balls_capsules_and_cylinders_have_the_analytic_distance() {
    let mut rng = SplitMix64::new(2);
    let c = Vector3::new(0.1, 0.2, -0.3);
    let ball = one(
        Primitive::Ball { radius: 0.5 },
        Isometry3::translation(c.x, c.y, c.z),
    );
    let capsule = one(
        Primitive::Capsule {
            half_height: 0.4,
            radius: 0.2,
        },
        Isometry3::translation(c.x, c.y, c.z),
    );
    let cylinder = one(
        Primitive::Cylinder {
            half_height: 0.4,
            radius: 0.3,
        },
        Isometry3::translation(c.x, c.y, c.z),
    );
    for _ in 0..2000 {
        let p = random_point(&mut rng, 1.2);
        let l = p.coords - c;
        assert_relative_eq!(
            ball.signed_distance(&p).unwrap(),
            l.norm() - 0.5,
            epsilon = 1e-5
        );
        // Capsule: distance to its z segment minus the radius.
        let on_axis = Vector3::new(0.0, 0.0, l.z.clamp(-0.4, 0.4));
        assert_relative_eq!(
            capsule.signed_distance(&p).unwrap(),
            (l - on_axis).norm() - 0.2,
            epsilon = 1e-5
        );
        // Cylinder along z (parry's are along y: the scene turns them).
        let radial = (l.x * l.x + l.y * l.y).sqrt() - 0.3;
        let axial = l.z.abs() - 0.4;
        let expected =
            radial.max(axial).min(0.0) + Vector3::new(radial.max(0.0), axial.max(0.0), 0.0).norm();
        assert_relative_eq!(
            cylinder.signed_distance(&p).unwrap(),
            expected,
            epsilon = 1e-4
        );
    }
}

#[test]
fn a_scene_is_the_union_of_its_parts() {
    let a = Primitive::Ball { radius: 0.3 };
    let pa = Isometry3::translation(-0.5, 0.0, 0.0);
    let pb = Isometry3::translation(0.6, 0.1, 0.0);
    let mut scene = Scene::new();
    scene
        .add(
            SceneObject::new("a", ObjectKind::Other)
                .with(a, pa)
                .unwrap(),
        )
        .unwrap();
    scene
        .add(
            SceneObject::new("b", ObjectKind::Other)
                .with(Primitive::cuboid([0.4, 0.4, 0.4]), pb)
                .unwrap(),
        )
        .unwrap();
    let sa = one(a, pa);
    let sb = one(Primitive::cuboid([0.4, 0.4, 0.4]), pb);
    let mut rng = SplitMix64::new(3);
    let points: Vec<_> = (0..3000).map(|_| random_point(&mut rng, 2.0)).collect();
    let batched = scene.signed_distances(&points).unwrap();
    for (p, d) in points.iter().zip(batched) {
        let expected = sa
            .signed_distance(p)
            .unwrap()
            .min(sb.signed_distance(p).unwrap());
        assert_eq!(d, expected);
        assert_eq!(d, scene.signed_distance(p).unwrap());
    }
}

#[test]
fn closest_points_normals_and_rays() {
    let scene = one(Primitive::cuboid([2.0, 2.0, 2.0]), Isometry3::identity());
    let s = scene.closest(&Point3::new(0.2, 0.3, 3.0)).unwrap().unwrap();
    assert_relative_eq!(s.point, Point3::new(0.2, 0.3, 1.0), epsilon = 1e-6);
    assert_relative_eq!(s.normal, Vector3::z(), epsilon = 1e-6);
    assert_relative_eq!(s.signed_distance, 2.0, epsilon = 1e-6);
    // Inside, the normal still points out of the solid.
    let s = scene.closest(&Point3::new(0.9, 0.0, 0.1)).unwrap().unwrap();
    assert_relative_eq!(s.normal, Vector3::x(), epsilon = 1e-6);
    assert_relative_eq!(s.signed_distance, -0.1, epsilon = 1e-6);
    // On the surface, from the gradient.
    let s = scene
        .closest(&Point3::new(0.0, -1.0, 0.2))
        .unwrap()
        .unwrap();
    assert_relative_eq!(s.normal, -Vector3::y(), epsilon = 1e-3);

    let hit = scene
        .cast_ray(
            &Point3::new(0.5, 0.5, 5.0),
            &Vector3::new(0.0, 0.0, -2.0),
            10.0,
        )
        .unwrap()
        .unwrap();
    assert_relative_eq!(hit.distance, 4.0, epsilon = 1e-5);
    assert_relative_eq!(hit.normal, Vector3::z(), epsilon = 1e-5);
    let miss = scene
        .cast_ray(&Point3::new(0.5, 0.5, 5.0), &Vector3::z(), 10.0)
        .unwrap();
    assert!(miss.is_none());
    assert!(scene
        .cast_ray(&Point3::new(0.5, 0.5, 5.0), &-Vector3::z(), 3.0)
        .unwrap()
        .is_none());
}

#[test]
fn bad_queries_and_shapes_are_errors() {
    let scene = one(Primitive::Ball { radius: 1.0 }, Isometry3::identity());
    let nan = Point3::new(f32::NAN, 0.0, 0.0);
    assert!(matches!(
        scene.signed_distance(&nan),
        Err(SceneError::InvalidInput(_))
    ));
    let e = scene
        .signed_distances(&[Point3::origin(), nan])
        .unwrap_err()
        .to_string();
    assert!(e.contains("point 1"), "{e}");
    assert!(scene
        .cast_ray(&Point3::origin(), &Vector3::zeros(), 1.0)
        .is_err());
    assert!(scene
        .cast_ray(&Point3::origin(), &Vector3::z(), -1.0)
        .is_err());
    assert!(Part::primitive(Primitive::Ball { radius: -1.0 }, Isometry3::identity()).is_err());
    assert!(Part::primitive(
        Primitive::cuboid([1.0, f32::NAN, 1.0]),
        Isometry3::identity()
    )
    .is_err());
    assert!(Scene::new()
        .add(SceneObject::new("empty", ObjectKind::Other))
        .is_err());
    assert_eq!(
        Scene::new().signed_distance(&Point3::origin()).unwrap(),
        f32::INFINITY
    );
    let bad = TriangleMesh {
        vertices: vec![Point3::origin(); 3],
        triangles: vec![[0, 1, 5]],
    };
    assert!(Part::mesh(&bad)
        .unwrap_err()
        .to_string()
        .contains("triangle 0"));
    assert!(matches!(
        Part::mesh(&TriangleMesh::default()),
        Err(SceneError::EmptyMesh(_))
    ));
}

#[test]
fn a_cube_mesh_round_trips_and_has_the_box_distance() {
    let dir = std::env::temp_dir().join(format!("envfield-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cube = TriangleMesh::cube(1.0);
    for name in ["cube.obj", "cube.ply"] {
        let path = dir.join(name);
        cube.write(&path).unwrap();
        assert_eq!(TriangleMesh::read(&path).unwrap(), cube, "{name}");
    }
    // An ASCII PLY with a quad face and an extra vertex property.
    let ascii = dir.join("quad.ply");
    std::fs::write(
        &ascii,
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n\
         property double z\nproperty uchar red\nelement face 1\nproperty list uchar uint vertex_indices\n\
         end_header\n0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n4 0 1 2 3\n",
    )
    .unwrap();
    let quad = TriangleMesh::read(&ascii).unwrap();
    assert_eq!(quad.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert_relative_eq!(quad.area(), 1.0);
    // Truncated binary data, a bad header and a face beyond the vertices are errors.
    let bytes = std::fs::read(dir.join("cube.ply")).unwrap();
    let cut = dir.join("cut.ply");
    std::fs::write(&cut, &bytes[..bytes.len() - 7]).unwrap();
    let e = TriangleMesh::read(&cut).unwrap_err().to_string();
    assert!(e.contains("face 11") && e.contains("ends early"), "{e}");
    std::fs::write(
        &cut,
        "ply\nformat ascii 1.0\nelement vertex 1\nbogus\nend_header\n",
    )
    .unwrap();
    assert!(TriangleMesh::read(&cut)
        .unwrap_err()
        .to_string()
        .contains("line 4"));
    std::fs::write(&cut, "").unwrap();
    assert!(TriangleMesh::read(&cut).is_err());
    assert!(TriangleMesh::read(dir.join("missing.obj")).is_err());
    assert!(TriangleMesh::read(dir.join("cube.stl")).is_err());
    std::fs::remove_dir_all(&dir).unwrap();

    // The closed cube, wound either way, gives the box's signed distance: the sign comes from
    // its shape, and within a cell (1 cm) of the surface the distance is unsigned.
    let mut inverted = cube.clone();
    for t in &mut inverted.triangles {
        t.swap(1, 2);
    }
    for mesh in [&cube, &inverted] {
        let mesh_scene = Scene::from_mesh("cube", mesh).unwrap();
        let (share, cell, rooms) = mesh_scene.objects()[0].parts()[0].mesh_solidity().unwrap();
        assert!(
            share > 0.5 && cell == 0.01 && rooms == 0,
            "{share} {cell} {rooms}"
        );
        let mut rng = SplitMix64::new(4);
        for _ in 0..2000 {
            let p = random_point(&mut rng, 1.0);
            let expected = box_sdf(p.coords, Vector3::repeat(0.5));
            let got = mesh_scene.signed_distance(&p).unwrap();
            if expected.abs() > 2.0 * cell {
                assert_relative_eq!(got, expected, epsilon = 1e-5);
            } else {
                assert_relative_eq!(got.abs(), expected.abs(), epsilon = 1e-5);
            }
        }
    }
}

#[test]
fn rooms_keep_one_connected_floor_and_mark_furniture() {
    for seed in 0..6 {
        let room = generate_room(&RoomConfig::default(), seed).unwrap();
        assert!(
            room.furniture.len() >= 3,
            "seed {seed}: {} pieces",
            room.furniture.len()
        );
        let map = floor_map(&room.scene, &FloorMapConfig::default()).unwrap();
        assert!(map.floor_height.abs() < 1e-4);
        let envfield_grid::Components { labels, sizes } = map.grid.free_components();
        assert_eq!(
            sizes.len(),
            1,
            "seed {seed}: the free floor is split: {sizes:?}"
        );
        // The free floor covers most of the interior, and every footprint is an obstacle.
        let interior = room.size[0] * room.size[1] / 0.05f32.powi(2);
        assert!(sizes[0] as f32 > 0.3 * interior, "seed {seed}");
        for f in &room.furniture {
            let [x0, y0, x1, y1] = f.footprint();
            let (x, y) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
            let cell = map
                .frame
                .cell_of(x, y, map.grid.rows(), map.grid.cols())
                .unwrap();
            assert!(
                map.grid.is_obstacle(cell),
                "seed {seed}: {:?} centre is free",
                f.kind
            );
            // Just outside the footprint's front, plus clearance, is floor.
            let _ = labels.len();
            if let Some(seat) = f.seat_center() {
                let d = room.scene.signed_distance(&seat).unwrap();
                assert!(
                    d.abs() < 0.02,
                    "seed {seed}: {:?} seat at {seat:?} is {d} m off",
                    f.kind
                );
            }
        }
        // Growing obstacles by a body radius only removes free cells.
        let grown = map.inflated(0.25).unwrap();
        assert!(grown.free_count() < map.grid.free_count());
        assert!(grown.free_cells().all(|c| map.grid.is_free(c)));
        assert_eq!(map.inflated(0.0).unwrap(), map.grid);
        assert!(map.inflated(-1.0).is_err());
        // The middle of the free floor is free space just above the floor.
        let i = labels.iter().position(|&l| l == 0).unwrap();
        let [x, y] = map.frame.center(map.grid.cell(i));
        assert!(room.scene.signed_distance(&Point3::new(x, y, 0.5)).unwrap() > 0.0);
    }
    let kinds: std::collections::HashSet<_> = (0..6)
        .flat_map(|s| generate_room(&RoomConfig::default(), s).unwrap().furniture)
        .map(|f| f.kind)
        .collect();
    assert!(
        kinds.len() >= 5,
        "rooms should hold varied furniture: {kinds:?}"
    );
    assert!(generate_room(
        &RoomConfig {
            doors: 0,
            ..RoomConfig::default()
        },
        0
    )
    .is_err());
}

#[test]
fn surface_samples_lie_on_the_outer_surface() {
    let room = generate_room(&RoomConfig::default(), 11).unwrap();
    let points = sample_surface(&room.scene, 5000, 5).unwrap();
    assert_eq!(points.len(), 5000);
    assert_eq!(points, sample_surface(&room.scene, 5000, 5).unwrap());
    let d = room.scene.signed_distances(&points).unwrap();
    assert!(
        d.iter().all(|d| d.abs() < 2e-3),
        "max {:?}",
        d.iter().fold(0f32, |a, b| a.max(b.abs()))
    );
}

#[test]
fn voxels_cover_a_box_by_its_volume() {
    let scene = one(
        Primitive::cuboid([1.0, 0.6, 0.4]),
        Isometry3::translation(0.5, 0.3, 0.2),
    );
    let frame = VoxelFrame::covering(scene.aabb().unwrap(), 0.05).unwrap();
    assert_eq!(frame.shape, [20, 12, 8]);
    let grid = voxelize(&scene, &frame).unwrap();
    // Every voxel centre lies inside the box, so all are occupied.
    assert_eq!(grid.free_count(), 0);
    // A larger frame: the occupied voxels are the box's plus a half-voxel shell.
    let mut wide = frame;
    wide.origin -= Vector3::repeat(0.5);
    wide.shape = [40, 32, 28];
    let grid = voxelize(&scene, &wide).unwrap();
    let occupied = grid.len() - grid.free_count();
    assert!(
        (20 * 12 * 8..=22 * 14 * 10).contains(&occupied),
        "{occupied}"
    );
    assert!(grid.is_free(Cell3::new(0, 0, 0)));
    assert_eq!(
        wide.cell_of(&Point3::new(0.51, 0.31, 0.21)),
        Some(Cell3::new(20, 16, 14))
    );
    assert!(VoxelFrame::covering(scene.aabb().unwrap(), 0.0).is_err());
}

#[test]
fn an_open_scan_is_a_thin_obstacle_whatever_its_normals() {
    // A floor quad (normal up) and a wall quad at x = 2 facing -x: an open "scan".
    let mesh = TriangleMesh {
        vertices: vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(2.0, 0.0, 0.0),
            Point3::new(2.0, 2.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
            Point3::new(2.0, 0.0, 2.0),
            Point3::new(2.0, 2.0, 2.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3], [1, 5, 2], [1, 4, 5]],
    };
    let scene = Scene::from_mesh("scan", &mesh).unwrap();
    let d = |x, y, z| scene.signed_distance(&Point3::new(x, y, z)).unwrap();
    assert_relative_eq!(d(1.0, 1.0, 0.3), 0.3, epsilon = 1e-6);
    // Open sheets enclose nothing: behind them the distance is positive, whichever way they
    // face, so a scan wound inside out reads the same.
    assert_relative_eq!(d(1.0, 1.0, -0.2), 0.2, epsilon = 1e-6);
    assert_relative_eq!(d(1.5, 1.0, 1.0), 0.5, epsilon = 1e-6);
    assert_relative_eq!(d(2.25, 1.0, 1.0), 0.25, epsilon = 1e-6);
    let s = scene.closest(&Point3::new(1.0, 1.0, 0.3)).unwrap().unwrap();
    assert_relative_eq!(s.normal, Vector3::z(), epsilon = 1e-5);
    // The floor map of the scan: the floor is free, the wall's top edge is not seen as floor.
    let map = floor_map(
        &scene,
        &FloorMapConfig {
            resolution: 0.1,
            ..FloorMapConfig::default()
        },
    )
    .unwrap();
    assert!(map.grid.free_count() > 300);
}
