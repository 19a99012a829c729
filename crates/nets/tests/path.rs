//! The shortest-path readout (`PathConfig`): what its structure guarantees without training,
//! what training learns, and how it saves, loads and refuses bad settings.

use envfield_eikonal::dijkstra2;
use envfield_grid::{
    descent_move, Cell2, Field2, FieldModel, Grid2, MoveRule, Neighbourhood2, DIRECTIONS_8,
};
use envfield_mazes::{Dataset, DatasetConfig, GeneratorKind, MazeGenerator, TargetKind};
use envfield_nets::{
    ContextConfig, ConvSpec, FieldNet, ModelConfig, NetsError, PathConfig, PropagationConfig,
    TargetEncoding, TrainConfig, Trainer,
};

fn path_config(rule: MoveRule) -> ModelConfig {
    ModelConfig::Context(ContextConfig {
        encoder: vec![ConvSpec::new(8, 1), ConvSpec::new(8, 1)],
        goal_channel: false,
        encoding: TargetEncoding::Linear { scale: 100.0 },
        path: Some(PathConfig {
            rule,
            ..PathConfig::default()
        }),
        ..ContextConfig::default()
    })
}

/// Whether every reachable cell but the goal has a legal move to a strictly smaller value.
fn has_no_local_minimum(grid: &Grid2, field: &Field2, goal: Cell2, rule: MoveRule) -> bool {
    grid.free_cells().all(|cell| {
        let v = field.get(cell).unwrap();
        cell == goal
            || !v.is_finite()
            || grid
                .neighbours(cell, Neighbourhood2::Eight(rule))
                .any(|(n, _)| field.get(n).unwrap() < v)
    })
}

/// Untrained, with any seed, the field has no local minimum, and descent reaches the goal
/// from every reachable cell of a perfect maze and of rooms: the structure's guarantee, which
/// the suite's `untrained` column shows. Unreachable cells are infinite.
#[test]
fn untrained_fields_have_no_local_minimum() {
    for (kind, size) in [(GeneratorKind::Perfect, 21), (GeneratorKind::Rooms, 24)] {
        let mazes = MazeGenerator::new(kind, size)
            .unwrap()
            .generate_many(3, 5)
            .unwrap();
        for (seed, maze) in mazes.iter().enumerate() {
            let net = FieldNet::new(path_config(MoveRule::Strict), seed as u64).unwrap();
            let goal = maze.grid.free_cells().last().unwrap();
            let field = net.predict(&maze.grid, goal).unwrap();
            let exact = dijkstra2(
                &maze.grid,
                &[goal],
                Neighbourhood2::Eight(MoveRule::Strict),
                2f32.sqrt(),
            )
            .unwrap();
            assert!(has_no_local_minimum(
                &maze.grid,
                &field,
                goal,
                MoveRule::Strict
            ));
            for cell in maze.grid.free_cells() {
                let (v, e) = (field.get(cell).unwrap(), exact.get(cell).unwrap());
                assert_eq!(v.is_finite(), e.is_finite(), "{cell:?}");
                if !e.is_finite() {
                    continue;
                }
                // Descent from here reaches the goal.
                let mut here = cell;
                for _ in 0..maze.grid.len() {
                    if here == goal {
                        break;
                    }
                    here = descent_move(&maze.grid, &field, MoveRule::Strict, here).unwrap();
                }
                assert_eq!(here, goal, "{kind} maze {seed}: descent from {cell:?}");
            }
        }
    }
}

/// A short training on 8x8 gridworlds learns the exact move costs (1 and sqrt 2) and a field
/// within 1% of the graph distance on mazes of another family and size.
#[test]
fn training_learns_the_move_costs() {
    let data = Dataset::generate(&DatasetConfig {
        generator: MazeGenerator::new(GeneratorKind::Gridworld, 8).unwrap(),
        mazes: 200,
        goals_per_maze: 2,
        target: TargetKind::Graph(MoveRule::Vin),
        extra_obstacles: 0.0,
        seed: 3,
    })
    .unwrap();
    let net = FieldNet::new(path_config(MoveRule::Vin), 0).unwrap();
    let cfg = TrainConfig {
        lr: 3e-3,
        batch_items: 8,
        queries_per_item: 64,
        steps: 1000,
        ..TrainConfig::default()
    };
    let mut trainer = Trainer::new(net, cfg).unwrap();
    trainer
        .run(std::slice::from_ref(&data), None, None, |_| true)
        .unwrap();
    let net = trainer.net();
    let maze = &MazeGenerator::new(GeneratorKind::Rooms, 30)
        .unwrap()
        .generate_many(1, 9)
        .unwrap()[0];
    let costs = net.move_costs(&maze.grid).unwrap();
    for cell in maze.grid.free_cells() {
        let c = costs[cell.row * maze.grid.cols() + cell.col];
        for (k, &(dr, dc)) in DIRECTIONS_8.iter().enumerate() {
            let exact = if dr == 0 || dc == 0 { 1.0 } else { 2f32.sqrt() };
            if MoveRule::Vin.allows(&maze.grid, cell, dr, dc) {
                assert!((c[k] - exact).abs() < 0.05, "{cell:?} move {k}: {}", c[k]);
            }
        }
    }
    let goal = maze.grid.free_cells().next().unwrap();
    let field = net.predict(&maze.grid, goal).unwrap();
    let exact = dijkstra2(
        &maze.grid,
        &[goal],
        Neighbourhood2::Eight(MoveRule::Vin),
        2f32.sqrt(),
    )
    .unwrap();
    for cell in maze.grid.free_cells() {
        let (v, e) = (field.get(cell).unwrap(), exact.get(cell).unwrap());
        assert!(
            (v - e).abs() <= 0.01 * e.max(1.0),
            "{cell:?}: {v} against {e}"
        );
    }
}

/// The rule is the recurrence's: a diagonal gap between two walls is a path under `vin` and
/// not under `strict`, on the same weights; save and load keep the field.
#[test]
fn the_rule_decides_the_moves_and_files_keep_the_field() {
    // Two walls touching at a corner; the goal (0,0) is reached from (1,1) only diagonally.
    let grid = Grid2::from_obstacles(2, 2, vec![false, true, true, false]).unwrap();
    let goal = Cell2::new(0, 0);
    let mut net = FieldNet::new(path_config(MoveRule::Vin), 4).unwrap();
    assert!(net
        .predict(&grid, goal)
        .unwrap()
        .get(Cell2::new(1, 1))
        .unwrap()
        .is_finite());
    net.set_rule(MoveRule::Strict);
    assert_eq!(net.rule(), MoveRule::Strict);
    assert!(net
        .predict(&grid, goal)
        .unwrap()
        .get(Cell2::new(1, 1))
        .unwrap()
        .is_infinite());
    let file =
        std::env::temp_dir().join(format!("envfield-path-{}.safetensors", std::process::id()));
    net.save(&file).unwrap();
    let loaded = FieldNet::load(&file).unwrap();
    std::fs::remove_file(&file).unwrap();
    // The file records the config's rule; set_rule is the caller's.
    assert_eq!(loaded.rule(), MoveRule::Vin);
    let maze = &MazeGenerator::new(GeneratorKind::Gridworld, 12)
        .unwrap()
        .generate_many(1, 2)
        .unwrap()[0];
    let g = maze.grid.free_cells().next().unwrap();
    assert_eq!(
        FieldNet::new(path_config(MoveRule::Vin), 4)
            .unwrap()
            .predict(&maze.grid, g)
            .unwrap(),
        loaded.predict(&maze.grid, g).unwrap()
    );
}

/// Settings that cannot work are refused with the setting named.
#[test]
fn bad_path_settings_are_refused() {
    let ModelConfig::Context(base) = path_config(MoveRule::Strict) else {
        unreachable!()
    };
    let bad = [
        ContextConfig {
            propagation: Some(PropagationConfig::default()),
            ..base.clone()
        },
        ContextConfig {
            goal_channel: true,
            ..base.clone()
        },
        ContextConfig {
            path: Some(PathConfig {
                min_cost: 0.0,
                ..PathConfig::default()
            }),
            ..base.clone()
        },
    ];
    for config in bad {
        match FieldNet::new(ModelConfig::Context(config), 0) {
            Err(NetsError::InvalidConfig(m)) => assert!(m.contains("path"), "{m}"),
            other => panic!("accepted: {other:?}"),
        }
    }
    // A network without the readout has no move costs.
    let plain = FieldNet::new(ModelConfig::Context(ContextConfig::default()), 0).unwrap();
    let grid = Grid2::new(4, 4).unwrap();
    assert!(matches!(
        plain.move_costs(&grid),
        Err(NetsError::InvalidInput(_))
    ));
}
