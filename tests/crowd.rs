//! Several people on generated floor maps with the shipped bird's-eye field: the batched
//! prediction matches one-by-one prediction, two people cross a doorway in opposite
//! directions, and a small crowd in a room it never saw arrives without touching.

use envfield::eikonal::FastMarching;
use envfield::grid::{Cell2, FieldModel, Grid2};
use envfield::nets::FieldNet;
use envfield::plan::crowd::{plan_crowd, random_trips, walk_crowd, CrowdConfig, Ending, Trip};
use envfield::scene::{floor_map, generate_room, FloorMapConfig, RoomConfig};
use std::path::Path;

fn shipped() -> FieldNet {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/birdseye.safetensors");
    FieldNet::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[path = "../crates/plan/tests/doorway/mod.rs"]
mod doorway;
use doorway::{opposite_trips, two_rooms};

fn room_map(seed: u64) -> Grid2 {
    let room = generate_room(&RoomConfig::birdseye(), seed).unwrap();
    let config = FloorMapConfig {
        resolution: 0.1,
        ..FloorMapConfig::default()
    };
    floor_map(&room.scene, &config)
        .unwrap()
        .walkable(0.25, Some([64, 64]))
        .unwrap()
}

/// `predict_many` on `maps` and `goals` gives what `field` gives for each.
fn assert_batched_is_one_by_one(net: &FieldNet, maps: &[Grid2], goals: &[Cell2]) {
    let problems: Vec<(&Grid2, Cell2)> = maps.iter().zip(goals.iter().copied()).collect();
    let batched = net.predict_many(&problems).unwrap();
    for ((map, goal), field) in problems.iter().zip(&batched) {
        let single = net.field(map, *goal).unwrap();
        for (a, b) in single.values().iter().zip(field.values()) {
            assert!(a == b || (a - b).abs() < 1e-4, "{a} vs {b}");
        }
    }
}

#[test]
fn one_batched_pass_gives_the_fields_of_one_by_one_prediction() {
    let net = shipped();
    let maps: Vec<Grid2> = (0..3).map(|k| room_map(7_000 + k)).collect();
    let goals: Vec<Cell2> = maps
        .iter()
        .map(|m| m.free_cells().nth(40).unwrap())
        .collect();
    assert_batched_is_one_by_one(&net, &maps, &goals);
}

#[test]
fn the_windowed_batch_of_one_step_matches_one_by_one_prediction() {
    // One time step's maps: a room with everyone else's disc marked, which the network
    // answers from its union and a window per map. Discs at the map's edge too.
    let net = shipped();
    let room = room_map(7_100);
    let free: Vec<Cell2> = room.free_cells().collect();
    let people: Vec<envfield::grid::Point2> = [0, free.len() / 3, free.len() / 2, free.len() - 1]
        .iter()
        .map(|&k| envfield::grid::Point2::new(free[k].row as f32, free[k].col as f32))
        .collect();
    let maps: Vec<Grid2> = (0..people.len())
        .map(|i| {
            let others = (0..people.len()).filter(|&j| j != i).map(|j| people[j]);
            envfield::plan::crowd::mark_discs(&room, others, 5.0).unwrap()
        })
        .collect();
    let goals: Vec<Cell2> = people
        .iter()
        .map(|p| Cell2::new(p.row as usize, p.col as usize))
        .collect();
    assert_batched_is_one_by_one(&net, &maps, &goals);
}

#[test]
fn two_people_cross_a_doorway_on_the_learned_field() {
    let grid = two_rooms();
    let config = CrowdConfig::default();
    let trips = opposite_trips();
    let run = walk_crowd(&grid, &trips, &shipped(), &config).unwrap();
    assert!(
        run.arrived_at.iter().all(Option::is_some),
        "{:?}",
        run.arrived_at
    );
    assert_eq!(run.person_collisions(config.body_radius), 0);
    assert_eq!(run.obstacle_collisions(&grid), 0);
    assert!(
        run.waits + run.yields > 0,
        "the doorway holds one body: someone gave way"
    );
}

#[test]
fn a_crowd_in_an_unseen_room_arrives_without_touching() {
    // Room seeds far from the training rooms (0..1500).
    let net = shipped();
    let config = CrowdConfig::default();
    let (mut people, mut arrived) = (0, 0);
    for seed in 900_000..900_005 {
        let map = room_map(seed);
        let trips = random_trips(&map, 4, &config, 10.0, seed).unwrap();
        let run = walk_crowd(&map, &trips, &net, &config).unwrap();
        assert_eq!(run.person_collisions(config.body_radius), 0, "room {seed}");
        assert_eq!(run.obstacle_collisions(&map), 0, "room {seed}");
        people += trips.len();
        arrived += run.arrived_at.iter().flatten().count();
        // The exact loop on the same problem for comparison: the learned one is no worse.
        let exact = walk_crowd(&map, &trips, &FastMarching::default(), &config).unwrap();
        assert!(
            run.arrived_at.iter().flatten().count() + 1
                >= exact.arrived_at.iter().flatten().count()
        );
    }
    assert!(
        arrived * 100 >= people * 95,
        "{arrived} of {people} arrived"
    );
}

#[test]
fn sixteen_people_in_a_room_it_never_saw_all_arrive_with_ours_on_the_shipped_field() {
    // Room 3,000,001 of the held-out crowd table (the field trained on rooms 0-1,499).
    let map = room_map(3_000_001);
    let config = CrowdConfig::default();
    let trips = random_trips(&map, 16, &config, 10.0, 3_000_001).unwrap();
    let run = plan_crowd(&map, &trips, &shipped(), &config).unwrap();
    assert_eq!(run.ending, Ending::Arrived, "{:?}", run.arrived_at);
    assert_eq!(run.person_collisions(config.body_radius), 0);
    assert_eq!(run.obstacle_collisions(&map), 0);
    // People stay on the map after arriving: the last frame has everyone on their goal.
    let last = run.frames.last().unwrap();
    for (i, trip) in trips.iter().enumerate() {
        assert_eq!(last[i].round(), Some(trip.goal), "person {i}");
    }
}
