//! The search's own tests: its order, its limits and its shortcuts.
use super::super::{straight_line, AnyStep};
use super::*;

/// A search of step `step` and `max_steps` expansions, 2 cm from its goal, no other limit.
fn settings(step: f32, max_steps: usize) -> FieldSearch3 {
    FieldSearch3 {
        step,
        tolerance: 0.02,
        max_steps,
        max_checks: 0,
        near_stall: 0,
    }
}

/// The distance to a goal point in open space.
struct Cone(Point3m);

impl ContinuousField3 for Cone {
    fn value(&self, p: Point3m) -> envfield_grid::Result<f32> {
        Ok(distance(p, self.0))
    }
    fn gradient(&self, _: Point3m) -> envfield_grid::Result<Option<Point3m>> {
        Ok(None)
    }
}

/// No candidate with z below 0.5 (a floor the torso must stay above).
struct Above(f32);

impl StepFilter for Above {
    fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
        Ok(c.iter().map(|p| p[2] >= self.0).collect())
    }
}

/// A walled-in start: the search opens every point of the box and says so.
#[test]
fn a_start_walled_in_by_the_filter_exhausts_the_search() {
    struct Cube;
    impl StepFilter for Cube {
        fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
            Ok(c.iter().map(|p| p.iter().all(|v| v.abs() <= 0.3)).collect())
        }
    }
    let goal = [1.0, 0.0, 0.0];
    let search = settings(0.1, 100_000);
    let path = search.search(&Cone(goal), &Cube, [0.0; 3], goal).unwrap();
    assert!(!path.reached && path.exhausted, "{path:?}");
    assert!((path.final_distance - 0.7).abs() < 0.05, "{path:?}");
    let open = search
        .search(&Cone(goal), &AnyStep, [0.0; 3], goal)
        .unwrap();
    assert!(open.reached && !open.exhausted);
}

#[test]
fn the_search_walks_a_cone_to_its_goal_near_the_straight_line() {
    let goal = [2.0, 1.0, 1.0];
    let search = settings(0.1, 200);
    let path = search
        .search(&Cone(goal), &AnyStep, [0.0, 0.0, 1.0], goal)
        .unwrap();
    assert!(path.reached, "{path:?}");
    assert!(distance(*path.points.last().unwrap(), goal) <= 0.02);
    let straight = distance([0.0, 0.0, 1.0], goal);
    assert!(
        path.length() < 1.1 * straight,
        "{} against {straight}",
        path.length()
    );
    // Every step is s long but the last.
    for w in path.points[..path.points.len() - 1].windows(2) {
        assert!((distance(w[0], w[1]) - 0.1).abs() < 1e-5);
    }
}

#[test]
fn the_filter_is_obeyed_and_a_dead_end_stops_the_walk() {
    let goal = [1.0, 0.0, 0.0];
    let search = settings(0.1, 100);
    let path = search
        .search(&Cone(goal), &Above(0.5), [0.0, 0.0, 1.0], goal)
        .unwrap();
    assert!(!path.reached);
    assert!(
        !path.exhausted,
        "the half-space above z = 0.5 has points left to open"
    );
    assert!(path.points.iter().all(|p| p[2] >= 0.5 - 1e-6));
    assert!(path.final_distance > 0.4);
    let bad = FieldSearch3 {
        step: 0.0,
        ..search
    };
    let e = bad
        .search(&Cone(goal), &AnyStep, [0.0; 3], goal)
        .unwrap_err()
        .to_string();
    assert!(e.contains("step length 0"), "{e}");
    assert!(search
        .search(&Cone(goal), &AnyStep, [f32::NAN, 0.0, 0.0], goal)
        .is_err());
}

/// A box across the straight line: the search walks round it; the shortcut keeps every
/// step allowed, keeps the ends and comes close to the shortest way round (1.2 m).
#[test]
fn the_shortcut_straightens_a_detour_and_keeps_every_step_allowed() {
    struct Outside;
    impl StepFilter for Outside {
        fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
            Ok(c.iter()
                .map(|p| !((p[0] - 0.5).abs() < 0.1 && p[1].abs() < 0.3))
                .collect())
        }
    }
    let (start, goal) = ([0.0, 0.0, 1.0], [1.0, 0.0, 1.0]);
    let search = settings(0.05, 10_000);
    let raw = search.search(&Cone(goal), &Outside, start, goal).unwrap();
    assert!(raw.reached, "{raw:?}");
    let cut = search.shortcut(&Outside, &raw, goal).unwrap();
    assert!(cut.reached);
    assert_eq!(cut.points[0], start);
    assert_eq!(*cut.points.last().unwrap(), *raw.points.last().unwrap());
    for (k, w) in cut.points.windows(2).enumerate() {
        assert!(
            Outside.keep(k, w[0], &[w[1]]).unwrap()[0],
            "step {k}: {w:?}"
        );
        assert!(distance(w[0], w[1]) <= 0.05 + 1e-5);
    }
    assert!(
        cut.length() < raw.length() && cut.length() < 1.25,
        "raw {} cut {}",
        raw.length(),
        cut.length()
    );
    // Nothing to cut on a straight walk.
    let open = search.search(&Cone(goal), &AnyStep, start, goal).unwrap();
    let same = search.shortcut(&AnyStep, &open, goal).unwrap();
    assert!((same.length() - open.length()).abs() < 1e-4);
}

/// A start walled in by the strict filter: the relaxed search takes the looser one and
/// says so; where the strict filter has a route, it is the strict path, cut straight.
#[test]
fn the_relaxed_search_leaves_a_pocket_the_strict_filter_cannot() {
    struct Pocket;
    impl StepFilter for Pocket {
        fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
            // A shell at 0.3 m round the origin that the strict filter never allows.
            Ok(c.iter()
                .map(|&p| (distance(p, [0.0; 3]) - 0.3).abs() > 0.1)
                .collect())
        }
    }
    let goal = [1.0, 0.0, 0.0];
    let search = settings(0.1, 5_000);
    let strict = search.search(&Cone(goal), &Pocket, [0.0; 3], goal).unwrap();
    assert!(!strict.reached);
    let path = search
        .search_relaxed(&Cone(goal), &Pocket, &AnyStep, [0.0; 3], goal)
        .unwrap();
    assert!(path.reached && path.relaxed && path.exhausted, "{path:?}");
    assert!(path.length() < 1.1, "{}", path.length());
    // Outside the shell the strict filter has its way.
    let start = [0.0, 0.8, 0.0];
    let free = search
        .search_relaxed(&Cone(goal), &Pocket, &AnyStep, start, goal)
        .unwrap();
    assert!(free.reached && !free.relaxed);
    for (k, w) in free.points.windows(2).enumerate() {
        assert!(Pocket.keep(k, w[0], &[w[1]]).unwrap()[0]);
    }
}

/// A goal the filter never lets a step land on, in open space: without a limit the search
/// spends its whole budget of checks on the space round it; with `near_stall` it ends
/// that many checks after it last came nearer, close to the goal.
#[test]
fn a_goal_no_step_lands_on_ends_the_search_near_it() {
    struct Barred(std::cell::Cell<usize>);
    impl StepFilter for Barred {
        fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
            self.0.set(self.0.get() + c.len());
            // Nothing within 3 cm of the goal.
            Ok(c.iter()
                .map(|&p| distance(p, [1.0, 0.0, 0.0]) > 0.03)
                .collect())
        }
    }
    let goal = [1.0, 0.0, 0.0];
    let search = FieldSearch3 {
        max_checks: 5_000,
        ..settings(0.05, 100_000)
    };
    let calls = |near_stall: usize| {
        let filter = Barred(Default::default());
        let s = FieldSearch3 {
            near_stall,
            ..search
        };
        let path = s.search(&Cone(goal), &filter, [0.0; 3], goal).unwrap();
        assert!(!path.reached && !path.exhausted, "{path:?}");
        assert!(path.final_distance < 0.1, "{path:?}");
        filter.0.get()
    };
    // The landing tries count too: a few more calls than the budget's checks.
    let (all, limited) = (calls(0), calls(100));
    assert!(all >= 5_000, "{all}");
    assert!(limited < 1_000, "{limited}");
    // Where the goal is reached, the limit changes nothing.
    let open = FieldSearch3 {
        near_stall: 100,
        ..search
    };
    let path = open.search(&Cone(goal), &AnyStep, [0.0; 3], goal).unwrap();
    assert!(path.reached);
}

/// Where every candidate ties (a flat field), the search takes them in the directions'
/// order, the oldest expansion's first: the start's 26 candidates are checked before any
/// of its children's.
#[test]
fn tied_candidates_come_off_in_the_directions_order() {
    struct Flat;
    impl ContinuousField3 for Flat {
        fn value(&self, _: Point3m) -> envfield_grid::Result<f32> {
            Ok(1.0)
        }
        fn gradient(&self, _: Point3m) -> envfield_grid::Result<Option<Point3m>> {
            Ok(None)
        }
    }
    struct Record(std::cell::RefCell<Vec<Point3m>>);
    impl StepFilter for Record {
        fn keep(&self, _: usize, _: Point3m, c: &[Point3m]) -> Result<Vec<bool>> {
            self.0.borrow_mut().extend_from_slice(c);
            Ok(vec![true; c.len()])
        }
    }
    let search = settings(0.1, 40);
    let record = Record(Default::default());
    search
        .search(&Flat, &record, [0.0; 3], [5.0, 0.0, 0.0])
        .unwrap();
    let checked = record.0.into_inner();
    assert!(checked.len() > 26);
    for (k, d) in directions26().iter().enumerate() {
        let want = d.map(|v| 0.1 * v);
        assert!(distance(checked[k], want) < 1e-6, "{k}: {:?}", checked[k]);
    }
}

/// The open list's packed entries order as the (value by `total_cmp`, expansion,
/// candidate) triples they pack, negative values, zeros and infinities included.
#[test]
fn open_entries_order_as_their_triples() {
    let values = [
        f32::NEG_INFINITY,
        -3.5,
        -1e-30,
        -0.0,
        0.0,
        1e-30,
        0.25,
        0.2500001,
        7.0,
        f32::INFINITY,
    ];
    let mut triples = Vec::new();
    for &v in &values {
        for e in [0usize, 1, 70_000, 1 << 40] {
            for k in [0usize, 1, 25] {
                triples.push((v, e, k));
            }
        }
    }
    for &a in &triples {
        for &b in &triples {
            let want = a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2));
            let (pa, pb) = (pack_open(a.0, a.1, a.2), pack_open(b.0, b.1, b.2));
            assert_eq!(pa.cmp(&pb), want, "{a:?} {b:?}");
        }
        assert_eq!(unpack_open(pack_open(a.0, a.1, a.2)), (a.1, a.2));
    }
}

/// The packed key is the rounded lattice cell: equal within a cell, apart across cells,
/// on both sides of zero.
#[test]
fn lattice_keys_round_to_the_nearest_cell() {
    let k = |x: f32, y: f32, z: f32| lattice_key([x, y, z], 0.02);
    assert_eq!(k(0.0, 0.0, 0.0), k(0.009, -0.009, 0.0));
    assert_ne!(k(0.0, 0.0, 0.0), k(0.011, 0.0, 0.0));
    assert_ne!(k(-0.011, 0.0, 0.0), k(0.011, 0.0, 0.0));
    assert_eq!(k(-1.0, 2.0, -3.0), k(-1.005, 2.005, -2.995));
    let mut keys: Vec<u64> = (-30..30)
        .flat_map(|i| (-3..3).map(move |j| k(0.02 * i as f32, 0.02 * j as f32, 1.0)))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(keys.len(), 60 * 6);
}

#[test]
fn the_straight_line_ends_on_the_goal() {
    let line = straight_line([0.0; 3], [1.0, 0.0, 0.0], 0.3).unwrap();
    assert_eq!(line.len(), 5);
    assert_eq!(*line.last().unwrap(), [1.0, 0.0, 0.0]);
    assert!(straight_line([0.0; 3], [1.0; 3], 0.0).is_err());
}
