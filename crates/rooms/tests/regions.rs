//! The accessible region, the 3D fields and the VAEs trained on rooms: behaviour checked
//! against known answers, and bad input refused with a clear error.

use envfield_affordance::afford;
use envfield_grid::{Cell3, ContinuousField3, Grid3};
use envfield_rooms::torsos::{room_torsos, TorsoDataConfig};
use envfield_rooms::{AccessibleRegion, ExactField3, Field3Config, LearnedField3, RegionConfig};
use envfield_scene::{generate_room, RoomConfig, Scene, TriangleMesh, VoxelFrame};
use envfield_vae::{
    Cvae, Gate, SampleOptions, TorsoSource, VaeConfig, VaeError, VaeTrainConfig, VaeTrainer,
};

fn small() -> VaeConfig {
    VaeConfig {
        pointnet: vec![16, 32],
        points: 64,
        latent: 4,
        hidden: 32,
        layers: 2,
        ..VaeConfig::default()
    }
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("envfield-vae-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A scene with no floor affords nothing: its region is refused with a clear error.
#[test]
fn a_scene_with_no_floor_has_no_accessible_region() {
    // A cube floating 3 m up: no surface to stand or sit on near the samples.
    let mut mesh = TriangleMesh::cube(1.0);
    for v in &mut mesh.vertices {
        v.z += 3.0;
    }
    let scene = Scene::from_mesh("cube", &mesh).unwrap();
    let samples = [[0.0, 0.0, 1.0], [0.3, 0.2, 0.9], [-0.2, 0.1, 1.1]];
    let config = RegionConfig::default();
    let kept: Vec<_> = samples
        .iter()
        .filter(|&&s| afford(&scene, s, &config.filter).unwrap().kept())
        .copied()
        .collect();
    assert!(kept.is_empty());
    let e = AccessibleRegion::from_samples(&scene, kept, 0.1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no floor"), "{e}");
    assert!(afford(&scene, [f32::NAN, 0.0, 1.0], &config.filter).is_err());
}

/// In a room, a torso at standing height over open floor is kept and affords standing; one
/// inside a wall is not kept.
#[test]
fn the_filter_keeps_standing_torsos_and_drops_ones_in_walls() {
    let room = generate_room(&RoomConfig::default(), 5).unwrap();
    let data = room_torsos(&room, &TorsoDataConfig::default(), 5).unwrap();
    let config = RegionConfig::default();
    let standing = data
        .torsos
        .iter()
        .zip(&data.sources)
        .find(|(_, s)| **s == TorsoSource::Stand)
        .map(|(t, _)| *t)
        .unwrap();
    let a = afford(&room.scene, standing, &config.filter).unwrap();
    assert!(a.kept() && a.valid.is_some(), "{a:?}");
    let in_wall = [-0.05, room.size[1] / 2.0, 1.0];
    assert!(!afford(&room.scene, in_wall, &config.filter).unwrap().kept());
}

/// A region built by hand: an open 3 x 2 x 1 box of voxels.
fn box_region(shape: [usize; 3], voxel: f32) -> AccessibleRegion {
    let frame = VoxelFrame {
        origin: envfield_scene::nalgebra::Point3::new(0.0, 0.0, 0.0),
        voxel,
        shape,
    };
    let grid = Grid3::new(shape[0], shape[1], shape[2]).unwrap();
    AccessibleRegion::new(frame, grid, vec![[0.05, 0.05, 0.05]], 1).unwrap()
}

/// The exact field of an open box is the straight-line distance (fast marching, first order,
/// within its known error), in metres; a goal outside the region is refused.
#[test]
fn the_exact_field_of_an_open_box_is_the_distance() {
    let region = box_region([40, 30, 6], 0.1);
    let field = ExactField3::at_cell(&region, Cell3::new(5, 5, 2)).unwrap();
    let goal = region.frame.center(Cell3::new(5, 5, 2));
    for c in [
        Cell3::new(35, 5, 2),
        Cell3::new(5, 25, 2),
        Cell3::new(30, 20, 4),
    ] {
        let p = region.frame.center(c);
        let d = (p - goal).norm();
        let v = field.value(<[f32; 3]>::from(p)).unwrap();
        assert!((v - d).abs() < 0.08 * d + 0.02, "{c:?}: {v} against {d}");
    }
    let g = field.gradient([2.0, 0.55, 0.25]).unwrap().unwrap();
    assert!(g[0] > 0.9 && g[1].abs() < 0.2, "{g:?}");
    assert!(ExactField3::new(&region, [10.0, 0.0, 0.0]).is_err());
    assert!(field.value([f32::NAN, 0.0, 0.0]).is_err());

    // Marched toward one start 2 m from the goal, a band of 0.5 m: the same values on the
    // ways from the start at most 0.5 m longer than the straight one, nothing off them
    // (past the start by 0.35 m, behind the goal, far off).
    let start = region.frame.center(Cell3::new(25, 5, 2));
    let near = ExactField3::toward(&region, Cell3::new(5, 5, 2), start.into(), 0.5).unwrap();
    for p in [
        [2.5, 0.55, 0.25],
        [1.0, 0.55, 0.25],
        [2.6, 0.75, 0.25],
        [1.5, 0.9, 0.35],
    ] {
        assert_eq!(near.value(p).unwrap(), field.value(p).unwrap(), "{p:?}");
    }
    for p in [
        [2.9, 0.55, 0.25],
        [0.15, 0.55, 0.25],
        [3.8, 0.55, 0.25],
        [1.5, 2.5, 0.25],
    ] {
        assert!(near.value(p).unwrap().is_infinite(), "{p:?}");
        assert!(field.value(p).unwrap().is_finite(), "{p:?}");
    }
    for band in [f32::NAN, -0.1] {
        assert!(ExactField3::toward(&region, Cell3::new(5, 5, 2), start.into(), band).is_err());
    }
    assert!(ExactField3::toward(&region, Cell3::new(5, 5, 2), [10.0, 0.0, 0.0], 0.5).is_err());
}

/// A field pinned to its goal is 0 there, lies between its own value and the straight-line
/// distance within the radius, and is unchanged beyond it; a bad radius is an error.
#[test]
fn a_pinned_field_is_zero_at_its_goal_and_unchanged_beyond_its_radius() {
    // Two rooms joined by a door in a wall at x = 2 m: behind the wall the way round is
    // longer than the straight line.
    let shape = [40, 30, 3];
    let frame = VoxelFrame {
        origin: envfield_scene::nalgebra::Point3::new(0.0, 0.0, 0.0),
        voxel: 0.1,
        shape,
    };
    let mut grid = Grid3::new(shape[0], shape[1], shape[2]).unwrap();
    for y in 0..25 {
        for z in 0..3 {
            grid.set_obstacle(Cell3::new(20, y, z), true).unwrap();
        }
    }
    let region = AccessibleRegion::new(frame, grid, vec![[0.05, 0.05, 0.05]], 1).unwrap();
    let goal = Cell3::new(22, 5, 1);
    let exact = ExactField3::at_cell(&region, goal).unwrap();
    let pinned = exact.clone().pinned(0.6).unwrap();
    assert_eq!(pinned.at(goal), 0.0);
    let centre = region.frame.center(goal);
    let mut pulled = 0;
    for &i in region.free_indices() {
        let c = region.grid.cell(i);
        let r = (region.frame.center(c) - centre).norm();
        let (v, p) = (exact.at(c), pinned.at(c));
        if r >= 0.6 {
            assert_eq!(v.to_bits(), p.to_bits(), "{c:?}");
        } else {
            assert!(
                p >= v.min(r) - 1e-5 && p <= v.max(r) + 1e-5,
                "{c:?}: {p} {v} {r}"
            );
            pulled += usize::from(p < v - 0.05);
        }
    }
    assert!(
        pulled > 0,
        "behind the wall the straight line pulls the field down"
    );
    for bad in [f32::NAN, -0.1, f32::INFINITY] {
        assert!(exact.clone().pinned(bad).is_err(), "{bad}");
    }
    let same = exact.clone().pinned(0.0).unwrap();
    assert_eq!(
        same.at(Cell3::new(23, 6, 1)),
        exact.at(Cell3::new(23, 6, 1))
    );
}

/// Near a wall the exact field stays finite in every accessible voxel (trilinear over the
/// accessible corners) and infinite in the wall, and matches plain trilinear in the open.
#[test]
fn the_exact_field_is_finite_up_to_the_regions_faces() {
    let mut region = box_region([10, 6, 3], 0.1);
    let mut grid = region.grid.clone();
    for y in 0..6 {
        for z in 0..3 {
            grid.set_obstacle(Cell3::new(7, y, z), true).unwrap();
        }
    }
    region = AccessibleRegion::new(region.frame, grid, region.samples.clone(), 1).unwrap();
    let field = ExactField3::at_cell(&region, Cell3::new(1, 3, 1)).unwrap();
    // x = 0.68 m is in voxel 6 (accessible), between its centre (0.65) and the wall's (0.75).
    let near_wall = field.value([0.68, 0.35, 0.15]).unwrap();
    let centre = field.value([0.65, 0.35, 0.15]).unwrap();
    assert!(
        near_wall.is_finite() && (near_wall - centre).abs() < 1e-4,
        "{near_wall} {centre}"
    );
    assert!(field.value([0.695, 0.35, 0.15]).unwrap().is_finite());
    assert!(field.value([0.76, 0.35, 0.15]).unwrap().is_infinite());
    // In the open, the mean of the corners.
    let (a, b) = (
        field.value([0.35, 0.35, 0.15]).unwrap(),
        field.value([0.45, 0.35, 0.15]).unwrap(),
    );
    let mid = field.value([0.40, 0.35, 0.15]).unwrap();
    assert!((mid - 0.5 * (a + b)).abs() < 1e-4, "{mid} {a} {b}");
}

/// A short training of the learned field on a small box gets within a few voxels of the exact
/// field on held-out goals; a network of another lattice is refused.
#[test]
fn the_learned_field_approaches_the_exact_one() {
    let region = box_region([12, 10, 4], 0.1);
    let config = Field3Config {
        goals: 48,
        held_out_goals: 4,
        steps: 400,
        goals_per_step: 8,
        queries_per_goal: 64,
        ..Field3Config::default()
    };
    let (net, report) = envfield_rooms::train_field3(&region, &config, None, |_, _, _| {}).unwrap();
    assert!(report.pairs > 100);
    assert!(report.median_err_m < 0.15, "{report:?}");
    let field = LearnedField3::new(&net, &region, Cell3::new(1, 1, 1)).unwrap();
    let v = field
        .values(&[[0.15, 0.15, 0.15], [1.05, 0.85, 0.15]])
        .unwrap();
    assert!(v[0] < v[1], "{v:?}");
    let other = box_region([8, 8, 4], 0.1);
    assert!(LearnedField3::new(&net, &other, Cell3::new(1, 1, 1)).is_err());
}

/// The training's shares are checked by name, and its fingerprint follows every setting.
#[test]
fn the_fields_training_refuses_shares_out_of_range_and_fingerprints_its_settings() {
    let region = box_region([6, 5, 3], 0.1);
    for (bad, name) in [
        (
            Field3Config {
                sit_goal_share: 1.5,
                ..Field3Config::default()
            },
            "sit_goal_share",
        ),
        (
            Field3Config {
                near_query_share: f32::NAN,
                ..Field3Config::default()
            },
            "near_query_share",
        ),
        (
            Field3Config {
                near_query_share: 0.95,
                ..Field3Config::default()
            },
            "blocked_fraction + near_query_share",
        ),
    ] {
        let e = envfield_rooms::train_field3(&region, &bad, None, |_, _, _| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains(name), "{e}");
    }
    let base = Field3Config::default();
    let other = Field3Config {
        near_query_share: 0.0,
        ..base.clone()
    };
    assert_eq!(base.key(), Field3Config::default().key());
    assert_ne!(base.key(), other.key());
}

/// The local VAE: it learns from neighbourhoods, samples over the whole room at anchors, keeps
/// its samples near the anchors' neighbourhoods, and refuses the whole-scene APIs.
#[test]
fn the_local_vae_trains_samples_over_the_room_and_refuses_whole_scene_calls() {
    let local = VaeConfig {
        pointnet: vec![16, 32],
        latent: 4,
        hidden: 32,
        ..VaeConfig::local()
    };
    let room = generate_room(&RoomConfig::default(), 3).unwrap();
    let data = vec![room_torsos(
        &room,
        &TorsoDataConfig {
            walks: 1,
            cloud_points: 4096,
            ..TorsoDataConfig::default()
        },
        3,
    )
    .unwrap()];
    let config = VaeTrainConfig {
        lr: 1e-3,
        steps: 60,
        scenes_per_step: 2,
        torsos_per_scene: 16,
        checkpoint_every: 0,
        ..VaeTrainConfig::default()
    };
    let mut trainer = VaeTrainer::new(Cvae::new(local.clone(), 1).unwrap(), config).unwrap();
    let mut losses = Vec::new();
    trainer
        .run(&data, None, |p| {
            losses.push(p.recon);
            true
        })
        .unwrap();
    assert!(
        losses[50..].iter().sum::<f32>() < losses[..10].iter().sum::<f32>(),
        "{losses:?}"
    );
    let vae = trainer.vae();
    assert_eq!(vae.cloud_points(), 8192);
    let samples = vae
        .sample(&data[0].cloud, &SampleOptions::new(400, 5))
        .unwrap();
    assert_eq!(
        samples,
        vae.sample(&data[0].cloud, &SampleOptions::new(400, 5))
            .unwrap(),
        "seeded"
    );
    // Anchors cover the room: samples spread over both halves of it in x and y.
    let [w, d] = room.size;
    for (axis, size) in [(0, w), (1, d)] {
        let low = samples.iter().filter(|s| s[axis] < size / 2.0).count();
        assert!(
            (40..360).contains(&low),
            "axis {axis}: {low} of 400 in the lower half"
        );
    }
    // The whole-scene calls do not exist on a local VAE.
    assert!(vae.as_whole().is_none());
    assert!(vae.as_gated().is_none());
    assert!(vae.sample(&[], &SampleOptions::new(5, 0)).is_err());
    assert!(vae
        .sample(&[[0.0, f32::NAN, 0.0]], &SampleOptions::new(5, 0))
        .is_err());
    // Anchors of one's own: every torso lands near its anchor (the decoder's offsets are
    // bounded by the neighbourhood), and bad anchors or a whole-scene VAE are refused.
    let anchors = [[1.0, 1.0], [w - 1.0, d - 1.0]];
    let near = vae
        .as_local()
        .unwrap()
        .sample_around(&data[0].cloud, &anchors, 7, 1.0)
        .unwrap();
    for (t, a) in near.iter().zip(&anchors) {
        let off = (t[0] - a[0]).hypot(t[1] - a[1]);
        assert!(off < 1.5, "torso {t:?} is {off} m from its anchor {a:?}");
    }
    let e = |r: Result<Vec<[f32; 3]>, VaeError>| r.unwrap_err().to_string();
    assert!(e(vae
        .as_local()
        .unwrap()
        .sample_around(&data[0].cloud, &[], 7, 1.0))
    .contains("anchors"));
    assert!(e(vae
        .as_local()
        .unwrap()
        .sample_around(&data[0].cloud, &[[0.0, f32::NAN]], 7, 1.0))
    .contains("anchor 0"));
    assert!(e(vae
        .as_local()
        .unwrap()
        .sample_around(&data[0].cloud, &anchors, 7, 0.0))
    .contains("temperature"));
    assert!(Cvae::new(small(), 0).unwrap().as_local().is_none());
    let bad = VaeConfig {
        points: 32,
        ..VaeConfig::local()
    };
    assert!(Cvae::new(bad, 0).unwrap_err().to_string().contains("local"));
}

/// The shipped local VAE loads as a local VAE and, on a room it never saw, puts most of its
/// kept samples where a pose is supported and collision-free and some within 0.15 m of a
/// seat's sitting torso (the README's figures are over 20 rooms and 6000 samples).
#[test]
fn the_shipped_local_vae_samples_an_unseen_room() {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/vae_local.safetensors");
    let vae = Cvae::load(&file).unwrap();
    assert!(vae.config().local.is_some());
    let room = generate_room(&RoomConfig::default(), 10_003).unwrap();
    let points: Vec<[f32; 3]> = envfield_scene::sample_surface(&room.scene, vae.cloud_points(), 3)
        .unwrap()
        .iter()
        .map(|p| <[f32; 3]>::from(*p))
        .collect();
    let samples = vae.sample(&points, &SampleOptions::new(3000, 3)).unwrap();
    let q =
        envfield_rooms::quality::region_quality(&room, &samples, &RegionConfig::default()).unwrap();
    assert!(q.affordable_pct > 60.0, "{q:?}");
    assert!(q.floor_coverage_pct > 90.0, "{q:?}");
    assert!(q.seat_coverage_pct > 0.0, "{q:?}");
}

/// The gated local VAE: its gate and pose-kind heads learn (their cross-entropies fall), its
/// file keeps them,
/// it samples as many torsos as asked with the gate on or off, and it refuses, naming the
/// gate, a scene where the gate passes no anchor, as it does a bad gate configuration and
/// occupancy queries to a VAE without a gate.
#[test]
fn the_gated_vae_learns_its_gate_and_refuses_a_scene_where_nobody_can_be() {
    let gated = VaeConfig {
        pointnet: vec![16, 32],
        latent: 4,
        hidden: 32,
        ..VaeConfig::local_gated()
    };
    let room = generate_room(&RoomConfig::default(), 4).unwrap();
    let data = vec![room_torsos(
        &room,
        &TorsoDataConfig {
            walks: 1,
            cloud_points: 4096,
            floor_spacing: 0.1,
            affordable_only: true,
            ..TorsoDataConfig::default()
        },
        4,
    )
    .unwrap()];
    assert!(data[0].kinds.iter().all(Option::is_some));
    let config = VaeTrainConfig {
        lr: 1e-3,
        steps: 80,
        scenes_per_step: 2,
        torsos_per_scene: 16,
        checkpoint_every: 0,
        ..VaeTrainConfig::default()
    };
    let mut trainer =
        VaeTrainer::new(Cvae::new(gated.clone(), 2).unwrap(), config.clone()).unwrap();
    let (mut gate, mut kind) = (Vec::new(), Vec::new());
    trainer
        .run(&data, None, |p| {
            gate.push(p.gate);
            kind.push(p.kind);
            true
        })
        .unwrap();
    for losses in [&gate, &kind] {
        assert!(
            losses[70..].iter().sum::<f32>() < losses[..10].iter().sum::<f32>(),
            "{losses:?}"
        );
    }
    let vae = trainer.vae();
    assert!(vae.gated() && vae.has_kinds());
    // Pose kinds train only on torsos labelled by the pose they afford.
    let mut unlabelled = data.clone();
    unlabelled[0].kinds[0] = None;
    let mut fresh = VaeTrainer::new(Cvae::new(gated.clone(), 2).unwrap(), config.clone()).unwrap();
    let e = fresh
        .run(&unlabelled, None, |_| true)
        .unwrap_err()
        .to_string();
    assert!(e.contains("affordable_only"), "{e}");
    let points = &data[0].cloud;
    let anchors = [[1.0, 1.0], [2.0, 1.5], [0.5, 3.0]];
    let p = vae.as_gated().unwrap().occupancy(points, &anchors).unwrap();
    assert_eq!(p.len(), 3);
    assert!(p.iter().all(|p| (0.0..=1.0).contains(p)), "{p:?}");
    let path = tmp("gated.safetensors");
    vae.save(&path).unwrap();
    let loaded = Cvae::load(&path).unwrap();
    assert!(loaded.gated());
    assert_eq!(
        loaded
            .as_gated()
            .unwrap()
            .occupancy(points, &anchors)
            .unwrap(),
        p
    );
    for gate in [Gate::Threshold(0.5), Gate::Threshold(0.2), Gate::Off] {
        let options = SampleOptions::new(300, 5).with_gate(gate);
        let s = vae.sample(points, &options).unwrap();
        assert_eq!(s.len(), 300);
        assert_eq!(s, vae.sample(points, &options).unwrap());
    }
    // A gate that passes nothing: the sampler stops and says why.
    let mut shut = gated.clone();
    if let Some(l) = shut.local.as_mut() {
        l.gate.as_mut().unwrap().threshold = 0.999_999;
    }
    let e = Cvae::new(shut, 2)
        .unwrap()
        .sample(points, &SampleOptions::new(10, 0))
        .unwrap_err()
        .to_string();
    assert!(e.contains("occupancy gate passed 0"), "{e}");
    // Bad input and bad configurations.
    let err = |r: Result<Vec<f32>, VaeError>| r.unwrap_err().to_string();
    assert!(vae
        .sample(
            points,
            &SampleOptions::new(10, 0).with_gate(Gate::Threshold(1.0))
        )
        .unwrap_err()
        .to_string()
        .contains("gate threshold"));
    assert!(err(vae.as_gated().unwrap().occupancy(points, &[])).contains("anchors"));
    assert!(err(vae
        .as_gated()
        .unwrap()
        .occupancy(points, &[[f32::NAN, 0.0]]))
    .contains("anchor 0"));
    assert!(err(vae.as_gated().unwrap().occupancy(&[], &anchors)).contains("cloud"));
    assert!(Cvae::new(small(), 0).unwrap().as_gated().is_none());
    for (radius, threshold) in [(0.0, 0.5), (0.08, 1.0), (f32::NAN, 0.5)] {
        let mut bad = gated.clone();
        if let Some(l) = bad.local.as_mut() {
            let g = l.gate.as_mut().unwrap();
            (g.radius, g.threshold) = (radius, threshold);
        }
        let e = Cvae::new(bad, 0).unwrap_err().to_string();
        assert!(e.contains("gate"), "{e}");
    }
}

/// The seat grid: every place it gives affords the sitting or lying pose it names, and each
/// seat whose sitting torso affords a pose has one of its places within 0.15 m.
#[test]
fn the_seat_grid_finds_a_place_on_every_seat() {
    use envfield_affordance::Support;
    let config = RegionConfig::default();
    for seed in [5, 6] {
        let room = generate_room(&RoomConfig::default(), seed).unwrap();
        let grid = envfield_rooms::torsos::seat_grid(&room, 0.1).unwrap();
        assert!(!grid.is_empty());
        for (t, kind) in &grid {
            assert!(matches!(kind, Support::Sitting | Support::Lying));
            let a = afford(&room.scene, *t, &config.filter).unwrap();
            assert!(a.kept() && a.valid == Some(*kind), "{t:?}: {a:?}");
        }
        for s in envfield_rooms::torsos::seat_torsos(&room).unwrap() {
            if afford(&room.scene, s, &config.filter)
                .unwrap()
                .valid
                .is_none()
            {
                continue;
            }
            let near = grid.iter().map(|(t, _)| {
                ((t[0] - s[0]).powi(2) + (t[1] - s[1]).powi(2) + (t[2] - s[2]).powi(2)).sqrt()
            });
            let d = near.fold(f32::INFINITY, f32::min);
            assert!(
                d < 0.15,
                "room {seed}: seat torso {s:?} is {d} m from the grid"
            );
        }
    }
    assert!(envfield_rooms::torsos::seat_grid(
        &generate_room(&RoomConfig::default(), 5).unwrap(),
        0.0
    )
    .unwrap_err()
    .to_string()
    .contains("spacing"));
}

/// The shipped gated VAE, on a room it never saw: nearly every kept sample affords a pose, the
/// standing floor is covered, and so is every seat's sitting torso (the README's figures are
/// over 20 rooms and 6000 samples each).
#[test]
fn the_shipped_gated_vae_samples_an_unseen_room() {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/vae_gated.safetensors");
    let vae = Cvae::load(&file).unwrap();
    assert!(vae.gated() && vae.has_kinds());
    let room = generate_room(&RoomConfig::default(), 10_003).unwrap();
    let points: Vec<[f32; 3]> = envfield_scene::sample_surface(&room.scene, vae.cloud_points(), 3)
        .unwrap()
        .iter()
        .map(|p| <[f32; 3]>::from(*p))
        .collect();
    let samples = vae.sample(&points, &SampleOptions::new(3000, 3)).unwrap();
    let q =
        envfield_rooms::quality::region_quality(&room, &samples, &RegionConfig::default()).unwrap();
    assert!(q.affordable_pct > 90.0, "{q:?}");
    assert!(q.floor_coverage_pct > 95.0, "{q:?}");
    assert!(q.seat_coverage_pct >= 50.0, "{q:?}");
}
