//! The crowd loops: a doorway crossed in both directions, bad problems refused, and the
//! collision counts checked against hand-made motions.

use envfield_eikonal::FastMarching;
use envfield_grid::{Cell2, Grid2, Point2};
use envfield_plan::crowd::{
    check_trips, closest_approach, grid_pibt, lacam_crowd, orca_crowd, pibt_crowd, plan_crowd,
    shortest_lengths, walk_crowd, CrowdConfig, CrowdRun, Ending, OrcaConfig, Trip,
};

mod doorway;
use doorway::{opposite_trips, two_rooms};

fn check_doorway(run: &CrowdRun, grid: &Grid2, config: &CrowdConfig, what: &str) {
    assert!(
        run.arrived_at.iter().all(Option::is_some),
        "{what}: not everyone arrived: {:?}",
        run.arrived_at
    );
    assert_eq!(
        run.person_collisions(config.body_radius),
        0,
        "{what}: people collided"
    );
    assert_eq!(
        run.obstacle_collisions(grid),
        0,
        "{what}: someone walked into a wall"
    );
}

#[test]
fn two_people_cross_a_doorway_in_opposite_directions() {
    let grid = two_rooms();
    let config = CrowdConfig::default();
    let run = walk_crowd(&grid, &opposite_trips(), &FastMarching::default(), &config).unwrap();
    check_doorway(&run, &grid, &config, "exact loop");
    // Someone had to give way: the doorway holds one body at a time.
    assert!(run.waits + run.yields > 0, "nobody waited or yielded");
    let shortest = shortest_lengths(&grid, &opposite_trips()).unwrap();
    for (i, s) in shortest.iter().enumerate() {
        let ratio = run.path_length(i) / s;
        assert!(
            (0.99..2.0).contains(&ratio),
            "person {i}: path ratio {ratio}"
        );
    }
}

#[test]
fn the_doorway_standoff_is_broken_whoever_is_nearer() {
    // Symmetric starts: equal remaining distances, the tie goes to the lower index.
    let grid = two_rooms();
    let config = CrowdConfig::default();
    let trips = vec![
        Trip {
            start: Cell2::new(10, 14),
            goal: Cell2::new(10, 36),
        },
        Trip {
            start: Cell2::new(10, 26),
            goal: Cell2::new(10, 4),
        },
    ];
    let run = walk_crowd(&grid, &trips, &FastMarching::default(), &config).unwrap();
    check_doorway(&run, &grid, &config, "face to face at the doorway");
}

#[test]
fn a_lone_walker_follows_the_shortest_path() {
    let grid = two_rooms();
    let config = CrowdConfig::default();
    let trips = [Trip {
        start: Cell2::new(3, 3),
        goal: Cell2::new(17, 37),
    }];
    let run = walk_crowd(&grid, &trips, &FastMarching::default(), &config).unwrap();
    assert!(run.arrived_at[0].is_some());
    let ratio = run.path_length(0) / shortest_lengths(&grid, &trips).unwrap()[0];
    assert!((0.98..1.12).contains(&ratio), "path ratio {ratio}");
    assert_eq!(run.waits + run.yields, 0);
}

#[test]
fn orca_runs_the_same_problem_and_its_collisions_are_counted() {
    let grid = two_rooms();
    let config = CrowdConfig::default();
    let trips = [Trip {
        start: Cell2::new(3, 3),
        goal: Cell2::new(17, 37),
    }];
    let run = orca_crowd(&grid, &trips, &config, &OrcaConfig::default()).unwrap();
    assert!(
        run.arrived_at[0].is_some(),
        "a lone ORCA agent did not arrive"
    );
    assert_eq!(run.person_collisions(config.body_radius), 0);
}

#[test]
fn closest_approach_sees_a_crossing_between_frames() {
    // Both end farther apart than they start, but pass through the same point midway.
    let (a0, a1) = (Point2::new(0.0, 0.0), Point2::new(4.0, 4.0));
    let (b0, b1) = (Point2::new(4.0, 0.0), Point2::new(0.0, 4.0));
    assert!(closest_approach(a0, a1, b0, b1) < 1e-5);
    // Parallel motion keeps the distance.
    let d = closest_approach(a0, a1, Point2::new(0.0, 3.0), Point2::new(4.0, 7.0));
    assert!((d - 3.0).abs() < 1e-5);
    let run = CrowdRun {
        frames: vec![vec![a0, b0], vec![a1, b1]],
        arrived_at: vec![None, None],
        waits: 0,
        yields: 0,
        stay_on_map: false,
        ending: Ending::StepBudget,
    };
    assert_eq!(run.person_collisions(1.0), 1);
}

#[test]
fn bad_problems_get_clear_errors() {
    let grid = two_rooms();
    let config = CrowdConfig::default();
    let err = |trips: &[Trip]| check_trips(&grid, trips, &config).unwrap_err().to_string();
    let ok = Trip {
        start: Cell2::new(5, 5),
        goal: Cell2::new(15, 35),
    };
    let e = err(&[Trip {
        goal: Cell2::new(0, 0),
        ..ok
    }]);
    assert!(
        e.contains("person 0's goal") && e.contains("furniture"),
        "{e}"
    );
    let e = err(&[
        ok,
        Trip {
            start: Cell2::new(99, 5),
            ..ok
        },
    ]);
    assert!(
        e.contains("person 1's start") && e.contains("outside"),
        "{e}"
    );
    let e = err(&[
        ok,
        Trip {
            start: Cell2::new(6, 6),
            ..ok
        },
    ]);
    assert!(
        e.contains("persons 0 and 1") && e.contains("overlap"),
        "{e}"
    );
    let crowd: Vec<Trip> = (0..200)
        .map(|k| Trip {
            start: Cell2::new(3 + k % 14, 3),
            ..ok
        })
        .collect();
    let e = err(&crowd);
    assert!(e.contains("do not fit"), "{e}");
    assert!(err(&[]).contains("at least one person"));
    let e = check_trips(
        &grid,
        &[ok],
        &CrowdConfig {
            step_length: 0.0,
            ..config
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("step length"), "{e}");
    // A goal in a closed-off part of the map.
    let mut walled = grid.clone();
    for r in 0..21 {
        walled.set_obstacle(Cell2::new(r, 30), true).unwrap();
    }
    let e = check_trips(&walled, &[ok], &config)
        .unwrap_err()
        .to_string();
    assert!(e.contains("cannot be reached"), "{e}");
}

#[test]
fn pibt_crosses_the_doorway_both_ways() {
    let grid = two_rooms();
    let config = CrowdConfig::default();
    let run = pibt_crowd(&grid, &opposite_trips(), &FastMarching::default(), &config).unwrap();
    check_doorway(&run, &grid, &config, "PIBT");
    assert_eq!(run.ending, Ending::Arrived);
}

#[test]
fn someone_standing_on_their_goal_in_the_doorway_is_pushed_through_and_walks_back() {
    let grid = two_rooms();
    let config = CrowdConfig::default();
    let trips = [
        // Reaches the doorway's middle at once and stands there.
        Trip {
            start: Cell2::new(10, 14),
            goal: Cell2::new(10, 20),
        },
        // Needs to pass through it.
        Trip {
            start: Cell2::new(4, 4),
            goal: Cell2::new(10, 36),
        },
    ];
    let run = pibt_crowd(&grid, &trips, &FastMarching::default(), &config).unwrap();
    check_doorway(&run, &grid, &config, "goal in the doorway");
    // Person 0 stood on the goal and left it again to let person 1 by.
    let first_home = run
        .frames
        .iter()
        .position(|f| f[0] == Point2::new(10.0, 20.0));
    let home_at_end = run.arrived_at[0].unwrap();
    assert!(
        first_home.is_some_and(|t| t < home_at_end),
        "person 0 never stepped aside: home at {first_home:?}, at the end since {home_at_end}"
    );
}

#[test]
fn eight_people_swap_rooms_through_one_door_without_gridlock() {
    let grid = two_rooms();
    let config = CrowdConfig::default();
    let left = [(4, 4), (4, 10), (10, 4), (16, 4), (16, 10), (10, 10)];
    let right = [(4, 36), (4, 30), (10, 36), (16, 36), (16, 30), (10, 30)];
    let cell = |(r, c): (usize, usize)| Cell2::new(r, c);
    let trips: Vec<Trip> = (0..4)
        .map(|k| Trip {
            start: cell(left[k]),
            goal: cell(right[k]),
        })
        .chain((0..4).map(|k| Trip {
            start: cell(right[k + 2]),
            goal: cell(left[k + 2]),
        }))
        .collect();
    let run = pibt_crowd(&grid, &trips, &FastMarching::default(), &config).unwrap();
    check_doorway(&run, &grid, &config, "eight through one door");
    assert_eq!(run.ending, Ending::Arrived);
}

#[test]
fn grid_pibt_swaps_the_rooms_on_its_lattice() {
    let grid = two_rooms();
    let config = CrowdConfig::default();
    let run = grid_pibt(&grid, &opposite_trips(), &config, 1).unwrap();
    assert_eq!(run.ending, Ending::Arrived, "{:?}", run.arrived_at);
    assert_eq!(run.obstacle_collisions(&grid), 0);
    // One body per 5-cell vertex: every frame's people stand a diameter apart or more.
    for frame in &run.frames[1..] {
        assert!(frame[0].distance(frame[1]) >= 5.0 - 1e-3);
    }
}

/// Two rooms joined by a corridor one body wide and 5 long (the walkable map's one free row).
fn corridor() -> Grid2 {
    let mut obstacles = vec![false; 30 * 41];
    for row in 0..30 {
        for col in 18..23 {
            obstacles[row * 41 + col] = row != 15;
        }
    }
    Grid2::from_obstacles(30, 41, obstacles).unwrap()
}

#[test]
fn the_search_swaps_two_people_through_a_corridor_where_pibt_alone_stalls() {
    let grid = corridor();
    let config = CrowdConfig::default();
    let trips = [
        Trip {
            start: Cell2::new(15, 5),
            goal: Cell2::new(15, 35),
        },
        Trip {
            start: Cell2::new(15, 35),
            goal: Cell2::new(15, 5),
        },
    ];
    let walked = pibt_crowd(&grid, &trips, &FastMarching::default(), &config).unwrap();
    let planned = plan_crowd(&grid, &trips, &FastMarching::default(), &config).unwrap();
    let searched = lacam_crowd(&grid, &trips, &FastMarching::default(), &config).unwrap();
    // PIBT alone: the one pushed back into the corridor cannot step aside in time.
    assert_eq!(walked.ending, Ending::StepBudget);
    for run in [&planned, &searched] {
        check_doorway(run, &grid, &config, "through the corridor");
        assert_eq!(run.ending, Ending::Arrived);
        // Every step within the step length.
        for t in 0..run.steps() {
            for i in 0..2 {
                let d = run.frames[t][i].distance(run.frames[t + 1][i]);
                assert!(d <= config.step_length + 1e-4, "step of {d} cells");
            }
        }
    }
}
