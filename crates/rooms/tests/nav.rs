//! The pose-dependent search against RRT in a small room where the way to the goal turns
//! round a cabinet's corner: the accessible region (torsos kept by the filter) comes within a
//! few centimetres of it, closer than swinging arms allow. Both reach the goal; only the search
//! with affordance keeps every pose valid.

use envfield_affordance::{align_in_scene, resample_path, walk, AlignConfig, WalkConfig};
use envfield_plan::space3::{rrt, FieldSearch3, SamplingConfig};
use envfield_rooms::{afford, AccessibleRegion, ExactField3, PoseFilter, RegionConfig};
use envfield_scene::nalgebra::{Isometry3, Point3};
use envfield_scene::{ObjectKind, Primitive, Scene, SceneObject};

fn scene() -> Scene {
    let mut s = Scene::new();
    let floor = SceneObject::new("floor", ObjectKind::Floor)
        .with(
            Primitive::cuboid([4.0, 2.0, 0.1]),
            Isometry3::translation(2.0, 1.0, -0.05),
        )
        .unwrap();
    // A tall cabinet across half the room's width, open for y > 1.
    let bar = SceneObject::new("cabinet", ObjectKind::Cabinet)
        .with(
            Primitive::cuboid([0.3, 1.0, 2.0]),
            Isometry3::translation(2.0, 0.5, 1.0),
        )
        .unwrap();
    s.add(floor).unwrap();
    s.add(bar).unwrap();
    s
}

/// The share of walking poses aligned to `path` by envfield-affordance (tangent headings) that
/// are valid; `step` resamples the path first.
fn valid_share(scene: &Scene, path: &[[f32; 3]], step: Option<f32>) -> f64 {
    let gait = walk(&WalkConfig::default(), 1).unwrap();
    let pts: Vec<Point3<f32>> = path.iter().map(|p| Point3::from(*p)).collect();
    let traj = match step {
        Some(s) => resample_path(&pts, s).unwrap(),
        None => pts,
    };
    let (_, reports) = align_in_scene(scene, &gait, &traj, &AlignConfig::default()).unwrap();
    reports.iter().filter(|r| r.valid()).count() as f64 / reports.len() as f64
}

#[test]
fn only_the_search_with_affordance_keeps_every_pose_valid() {
    let scene = scene();
    let gait = walk(&WalkConfig::default(), 1).unwrap();
    let z = gait.frames[0].torso().z;
    // The region: every torso on a 5 cm grid at walking height that the filter keeps
    // (standing supported, torso clear), the space over the bar included.
    let config = RegionConfig::default();
    let mut kept = Vec::new();
    for i in 0..80 {
        for j in 0..40 {
            let p = [0.025 + 0.05 * i as f32, 0.025 + 0.05 * j as f32, z];
            if afford(&scene, p, &config).unwrap().kept() {
                kept.push(p);
            }
        }
    }
    let region = AccessibleRegion::from_samples(&scene, kept, 0.1).unwrap();
    // The straight line crosses the bar at y = 0.85.
    let (start, goal) = ([0.5, 0.2, z], [3.5, 1.5, z]);
    assert!(region.contains(start) && region.contains(goal));
    // The region reaches within 10 cm of the cabinet's corner (2.15, 1.0).
    assert!(region.contains([2.2, 1.1, z]));
    let step = gait.step_length();
    let field = ExactField3::new(&region, goal).unwrap();
    let filter = PoseFilter {
        scene: &scene,
        region: &region,
        sequence: &gait,
        repeat: true,
        face_the_move: true,
        affordance: Default::default(),
    };
    let search = FieldSearch3 {
        step,
        tolerance: 0.02,
        max_steps: 2000,
    };
    let ours = search.search(&field, &filter, start, goal).unwrap();
    assert!(
        ours.reached,
        "ours ends {} m from the goal at {:?} after {} points",
        ours.final_distance,
        ours.points.last(),
        ours.points.len()
    );
    let cfg = SamplingConfig {
        step: 0.1,
        budget: 2000,
        seed: 3,
        ..SamplingConfig::default()
    };
    let baseline = rrt(&region, start, goal, &cfg).unwrap();
    assert!(baseline.reached);
    let share = |path: &[[f32; 3]]| {
        let (_, reports) = filter.poses_along(path).unwrap();
        reports.iter().filter(|r| r.valid()).count() as f64 / reports.len() as f64
    };
    let ours_valid = share(&ours.points);
    let rrt_points: Vec<[f32; 3]> = {
        let pts: Vec<Point3<f32>> = baseline.points.iter().map(|p| Point3::from(*p)).collect();
        resample_path(&pts, step)
            .unwrap()
            .iter()
            .map(|p| <[f32; 3]>::from(*p))
            .collect()
    };
    let rrt_valid = share(&rrt_points);
    // The tangent-aligned fit of envfield-affordance agrees on the baseline.
    assert!(valid_share(&scene, &baseline.points, Some(step)) < 0.999);
    assert!(ours_valid > 0.999, "ours: {ours_valid}");
    assert!(rrt_valid < 0.999, "rrt: {rrt_valid}");
    // As room_nav runs ours: the pose filter finds the route, so no fallback is taken, and
    // the straight cuts shorten it without losing a valid pose.
    let cut = search
        .search_relaxed(&field, &filter, &region, start, goal)
        .unwrap();
    assert!(cut.reached && !cut.relaxed);
    assert!(cut.length() <= ours.length() + 1e-4);
    let cut_valid = share(&cut.points);
    assert!(cut_valid > 0.999, "ours with cuts: {cut_valid}");
}
