//! Behaviour of the networks: fitting, saving and loading, bad files, input gradients,
//! resuming training.

use envfield_eikonal::dijkstra2;
use envfield_grid::{
    descent_move, octile_distance, Cell2, Field2, FieldModel, Grid2, MoveRule, Neighbourhood2,
    Point2,
};
use envfield_mazes::{Dataset, DatasetConfig, GeneratorKind, MazeGenerator, Sample, TargetKind};
use envfield_nets::{
    Activation, Batch, ContextConfig, ConvSpec, FieldNet, GoalConfig, HyperConfig, MlpConfig,
    ModelConfig, NetsError, PlainConfig, PropagationConfig, TargetEncoding, TrainConfig, Trainer,
};

/// Whether descent on `field` walks from `start` to `goal` within `max_steps` moves (never
/// entering a cell twice, as the planners' descent).
fn descends_to_goal(
    grid: &Grid2,
    field: &Field2,
    start: Cell2,
    goal: Cell2,
    max_steps: usize,
) -> bool {
    let mut seen = std::collections::HashSet::from([start]);
    let mut here = start;
    for _ in 0..max_steps {
        if here == goal {
            break;
        }
        match descent_move(grid, field, MoveRule::Strict, here) {
            Some(next) if seen.insert(next) => here = next,
            _ => break,
        }
    }
    here == goal
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("envfield-nets-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn small_context() -> ContextConfig {
    ContextConfig {
        encoder: vec![ConvSpec::new(8, 1), ConvSpec::new(8, 2)],
        mlp: MlpConfig {
            hidden: 16,
            layers: 2,
            ..MlpConfig::default()
        },
        ..ContextConfig::default()
    }
}

fn small_hyper() -> HyperConfig {
    HyperConfig {
        encoder: vec![
            ConvSpec {
                channels: 8,
                dilation: 1,
                stride: 2,
            },
            ConvSpec {
                channels: 8,
                dilation: 1,
                stride: 2,
            },
        ],
        fc: vec![16],
        hypo_hidden: 8,
        hypo_layers: 2,
        ..HyperConfig::default()
    }
}

fn dataset(size: usize, mazes: usize, goals: usize, seed: u64) -> Dataset {
    Dataset::generate(&DatasetConfig {
        generator: MazeGenerator::new(GeneratorKind::Gridworld, size).unwrap(),
        mazes,
        goals_per_maze: goals,
        target: TargetKind::Graph(MoveRule::Strict),
        extra_obstacles: 0.0,
        seed,
    })
    .unwrap()
}

/// The plain field learns one 8x8 maze and goal well enough that descent on it reaches the
/// goal from every free cell connected to it.
#[test]
fn plain_field_fits_one_maze_for_descent_from_every_cell() {
    let data = dataset(8, 1, 1, 3);
    let s = &data.samples[0];
    let net = FieldNet::new(
        ModelConfig::Plain(PlainConfig {
            extent: vec![8, 8],
            goal: vec![s.goal.row, s.goal.col],
            mlp: MlpConfig {
                hidden: 64,
                layers: 3,
                fourier: 3,
                ..MlpConfig::default()
            },
            encoding: TargetEncoding::Reciprocal,
        }),
        1,
    )
    .unwrap();
    let cfg = TrainConfig {
        lr: 3e-3,
        final_lr_fraction: 0.05,
        batch_items: 1,
        queries_per_item: 64,
        steps: 1500,
        validate_every: 0,
        checkpoint_every: 0,
        ..TrainConfig::default()
    };
    let mut trainer = Trainer::new(net, cfg).unwrap();
    let summary = trainer
        .run(std::slice::from_ref(&data), Some(&data), None, |_| true)
        .unwrap();
    assert!(
        summary.validation.unwrap() < 0.01,
        "L1 {:?}",
        summary.validation
    );
    let net = trainer.into_net();
    let field = net.predict(&s.grid, s.goal).unwrap();
    let mut starts = 0;
    for start in s.grid.free_cells() {
        let i = s.grid.index(start).unwrap();
        if start == s.goal || !s.distance[i].is_finite() {
            continue;
        }
        starts += 1;
        assert!(
            descends_to_goal(&s.grid, &field, start, s.goal, 200),
            "descent from {start:?} failed"
        );
    }
    assert!(starts > 20, "only {starts} starts");
}

fn all_configs() -> Vec<ModelConfig> {
    vec![
        ModelConfig::Plain(PlainConfig {
            extent: vec![6, 7],
            goal: vec![1, 2],
            mlp: MlpConfig {
                hidden: 8,
                layers: 2,
                fourier: 2,
                ..MlpConfig::default()
            },
            encoding: TargetEncoding::Linear { scale: 20.0 },
        }),
        ModelConfig::Goal(GoalConfig {
            detour: false,
            extent: vec![6, 7],
            mlp: MlpConfig {
                hidden: 8,
                layers: 2,
                activation: Activation::Sine { omega0: 30.0 },
                fourier: 0,
            },
            encoding: TargetEncoding::Reciprocal,
        }),
        ModelConfig::Context(small_context()),
        ModelConfig::Context(ContextConfig {
            residual: true,
            ..small_context()
        }),
        ModelConfig::Hyper(small_hyper()),
        ModelConfig::Context(ContextConfig {
            propagation: Some(PropagationConfig {
                q_channels: 3,
                iterations_per_cell: 0.5,
            }),
            ..small_context()
        }),
    ]
}

fn grid67() -> Grid2 {
    let mut g = Grid2::new(6, 7).unwrap();
    for c in [Cell2::new(2, 2), Cell2::new(2, 3), Cell2::new(4, 5)] {
        g.set_obstacle(c, true).unwrap();
    }
    g
}

#[test]
fn save_load_gives_identical_predictions_for_every_arch() {
    let grid = grid67();
    let goal = Cell2::new(1, 2);
    for (k, cfg) in all_configs().into_iter().enumerate() {
        let net = FieldNet::new(cfg.clone(), 5).unwrap();
        let path = tmp(&format!("roundtrip{k}.safetensors"));
        net.save(&path).unwrap();
        let back = FieldNet::load(&path).unwrap();
        assert_eq!(back.config(), &cfg);
        let a = net.predict(&grid, goal).unwrap();
        let b = back.predict(&grid, goal).unwrap();
        assert_eq!(a.values(), b.values(), "{}", cfg.arch());
        // A different seed gives a different network (the load really replaced the weights).
        let other = FieldNet::new(cfg.clone(), 6).unwrap();
        assert_ne!(
            other.predict(&grid, goal).unwrap().values(),
            a.values(),
            "{}",
            cfg.arch()
        );
    }
}

#[test]
fn wrong_shape_truncated_and_foreign_files_are_errors() {
    let net = FieldNet::new(ModelConfig::Context(small_context()), 1).unwrap();
    let path = tmp("shape.safetensors");
    net.save(&path).unwrap();
    let mut wider_cfg = small_context();
    wider_cfg.mlp.hidden = 32;
    let mut wider = FieldNet::new(ModelConfig::Context(wider_cfg), 1).unwrap();
    match wider.load_weights(&path) {
        Err(NetsError::ShapeMismatch {
            name,
            expected,
            found,
            ..
        }) => {
            assert!(name.starts_with("mlp."), "{name}");
            assert_ne!(expected, found);
        }
        other => panic!("expected a shape mismatch, got {other:?}"),
    }
    let hyper_path = tmp("hyper.safetensors");
    FieldNet::new(ModelConfig::Hyper(small_hyper()), 1)
        .unwrap()
        .save(&hyper_path)
        .unwrap();
    let mut ctx = FieldNet::new(ModelConfig::Context(small_context()), 1).unwrap();
    assert!(matches!(
        ctx.load_weights(&hyper_path),
        Err(NetsError::MissingWeight { .. } | NetsError::ShapeMismatch { .. })
    ));

    let bytes = std::fs::read(&path).unwrap();
    let truncated = tmp("truncated.safetensors");
    for cut in [bytes.len() / 2, 7, 0] {
        std::fs::write(&truncated, &bytes[..cut]).unwrap();
        let err = FieldNet::load(&truncated).unwrap_err();
        assert!(matches!(err, NetsError::Checkpoint { .. }), "{err}");
        assert!(err.to_string().contains("truncated.safetensors"), "{err}");
    }
    assert!(matches!(
        FieldNet::load(tmp("missing.safetensors")),
        Err(NetsError::Checkpoint { .. })
    ));
    // A weight file is not a training checkpoint.
    assert!(matches!(
        Trainer::resume(&path),
        Err(NetsError::Checkpoint { .. })
    ));
}

/// Reverse-mode gradients with respect to the query agree with central differences.
#[test]
fn input_gradient_matches_finite_differences() {
    let grid = grid67();
    let goal = Cell2::new(1, 2);
    let points = [
        Point2::new(0.3, 4.6),
        Point2::new(3.4, 1.7),
        Point2::new(4.55, 5.2),
    ];
    for cfg in all_configs().into_iter().skip(1) {
        let net = FieldNet::new(cfg.clone(), 11).unwrap();
        let batch = Batch::points(&grid, goal, &points);
        let (_, grad) = net.predict_with_gradient(&batch).unwrap();
        let h = 1e-2f32;
        for (i, p) in points.iter().enumerate() {
            for axis in 0..2 {
                let shift = |s: f32| {
                    let mut q = *p;
                    if axis == 0 {
                        q.row += s
                    } else {
                        q.col += s
                    }
                    net.predict_encoded(&Batch::points(&grid, goal, &[q]))
                        .unwrap()[0]
                };
                let fd = (shift(h) - shift(-h)) / (2.0 * h);
                let g = grad[2 * i + axis];
                assert!(
                    (fd - g).abs() <= 2e-3 + 0.05 * fd.abs().max(g.abs()),
                    "{} point {i} axis {axis}: analytic {g}, finite difference {fd}",
                    cfg.arch()
                );
            }
        }
    }
}

/// Training 6 steps, or 3 steps + checkpoint + resume + 3 steps, ends at the same weights.
#[test]
fn training_resumes_exactly_from_a_checkpoint() {
    let data = dataset(8, 6, 2, 9);
    let cfg = TrainConfig {
        lr: 1e-3,
        batch_items: 4,
        queries_per_item: 32,
        steps: 6,
        checkpoint_every: 3,
        validate_every: 0,
        ..TrainConfig::default()
    };
    let make = || {
        Trainer::new(
            FieldNet::new(ModelConfig::Context(small_context()), 2).unwrap(),
            cfg.clone(),
        )
        .unwrap()
    };
    let mut straight = make();
    straight
        .run(std::slice::from_ref(&data), None, None, |_| true)
        .unwrap();

    let ckpt = tmp("resume.ckpt");
    let mut first = make();
    first
        .continue_with_data("8x8 gridworld, 6 mazes x 2 goals, seed 9", false)
        .unwrap();
    first
        .run(std::slice::from_ref(&data), None, Some(&ckpt), |p| {
            p.step < 3
        })
        .unwrap();
    assert_eq!(first.step(), 3);
    let mut resumed = Trainer::resume(&ckpt).unwrap();
    assert_eq!(resumed.step(), 3);
    assert_eq!(
        resumed.data_description(),
        Some("8x8 gridworld, 6 mazes x 2 goals, seed 9")
    );
    assert_eq!(straight.data_description(), None);
    resumed
        .run(std::slice::from_ref(&data), None, Some(&ckpt), |_| true)
        .unwrap();
    assert_eq!(resumed.step(), 6);

    let s = &data.samples[0];
    let a = straight.net().predict(&s.grid, s.goal).unwrap();
    let b = resumed.net().predict(&s.grid, s.goal).unwrap();
    assert_eq!(a.values(), b.values());
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let grid = grid67();
    let ctx = FieldNet::new(ModelConfig::Context(small_context()), 1).unwrap();
    let bad_points = [Point2::new(f32::NAN, 1.0)];
    assert!(matches!(
        ctx.predict_encoded(&Batch::points(&grid, Cell2::new(0, 0), &bad_points)),
        Err(NetsError::InvalidInput(_))
    ));
    let outside = [Point2::new(6.5, 1.0)];
    assert!(matches!(
        ctx.predict_encoded(&Batch::points(&grid, Cell2::new(0, 0), &outside)),
        Err(NetsError::InvalidInput(_))
    ));
    assert!(
        ctx.predict(&grid, Cell2::new(2, 2)).is_err(),
        "goal on an obstacle"
    );
    let plain = FieldNet::new(all_configs().remove(0), 1).unwrap();
    let err = plain.predict(&grid, Cell2::new(0, 0)).unwrap_err();
    assert!(err.to_string().contains("plain field was trained"), "{err}");
    assert!(plain
        .predict(&Grid2::new(5, 5).unwrap(), Cell2::new(1, 2))
        .is_err());
    let mut bad = small_context();
    bad.encoder[0].stride = 2;
    assert!(matches!(
        FieldNet::new(ModelConfig::Context(bad), 0),
        Err(NetsError::InvalidConfig(_))
    ));
    assert!(Trainer::new(
        ctx,
        TrainConfig {
            lr: -1.0,
            ..TrainConfig::default()
        }
    )
    .is_err());
}

#[test]
fn same_seed_same_network() {
    let grid = grid67();
    let a = FieldNet::new(ModelConfig::Hyper(small_hyper()), 4).unwrap();
    let b = FieldNet::new(ModelConfig::Hyper(small_hyper()), 4).unwrap();
    assert_eq!(
        a.predict(&grid, Cell2::new(0, 0)).unwrap().values(),
        b.predict(&grid, Cell2::new(0, 0)).unwrap().values()
    );
}

/// With a neighbour weight, batches hold (cell, neighbour) pairs and training still works.
#[test]
fn neighbour_loss_pairs_adjacent_cells() {
    let data = dataset(8, 4, 2, 5);
    let cfg = TrainConfig {
        lr: 1e-3,
        batch_items: 3,
        queries_per_item: 10,
        steps: 3,
        neighbour_weight: 2.0,
        checkpoint_every: 0,
        validate_every: 0,
        ..TrainConfig::default()
    };
    let odd = TrainConfig {
        queries_per_item: 9,
        ..cfg.clone()
    };
    let net = || FieldNet::new(ModelConfig::Context(small_context()), 3).unwrap();
    assert!(matches!(
        Trainer::new(net(), odd),
        Err(NetsError::InvalidConfig(_))
    ));
    let mut trainer = Trainer::new(net(), cfg).unwrap();
    let (batch, targets) = trainer.sample_batch(&data, 0).unwrap();
    assert_eq!(targets.len(), 30);
    for pair in batch.queries.chunks_exact(4) {
        let (dr, dc) = ((pair[0] - pair[2]).abs(), (pair[1] - pair[3]).abs());
        assert!(dr <= 1.0 && dc <= 1.0 && dr + dc > 0.0, "{pair:?}");
    }
    let summary = trainer
        .run(std::slice::from_ref(&data), None, None, |_| true)
        .unwrap();
    assert!(summary.loss.is_finite());
}

/// With `detour_fraction` 1, every query is a cell whose distance exceeds its octile distance
/// to the goal; out of range it is a config error.
#[test]
fn detour_sampling_draws_cells_behind_obstacles() {
    let data = dataset(16, 6, 2, 8);
    let cfg = TrainConfig {
        batch_items: 6,
        queries_per_item: 40,
        detour_fraction: 1.0,
        ..TrainConfig::default()
    };
    let net = || FieldNet::new(ModelConfig::Context(small_context()), 3).unwrap();
    assert!(matches!(
        Trainer::new(
            net(),
            TrainConfig {
                detour_fraction: 1.5,
                ..cfg.clone()
            }
        ),
        Err(NetsError::InvalidConfig(_))
    ));
    let trainer = Trainer::new(net(), cfg).unwrap();
    let queries = sampled_queries(&trainer, &data, 5);
    assert_eq!(queries.len(), 5 * 6 * 40);
    for (sample, r, c) in queries {
        let d = sample.distance[r * 16 + c];
        let octile = octile_distance(Cell2::new(r, c), sample.goal);
        assert!(
            d.is_finite() && d > octile + 0.5,
            "({r}, {c}): {d} vs {octile}"
        );
    }
}

/// Every query of the batches of steps `0..steps` (16x16 mazes, single queries) as
/// `(sample it was drawn for, row, col)`: the batch's item is matched to its sample by goal and
/// obstacles.
fn sampled_queries<'a>(
    trainer: &Trainer,
    data: &'a Dataset,
    steps: u64,
) -> Vec<(&'a Sample, usize, usize)> {
    let mut out = Vec::new();
    for step in 0..steps {
        let (batch, _) = trainer.sample_batch(data, step).unwrap();
        let per_item = 2 * batch.per_item;
        for (item, queries) in batch.queries.chunks_exact(per_item).enumerate() {
            let goal = (batch.goals[2 * item], batch.goals[2 * item + 1]);
            let obstacles = &batch.obstacles[item * 256..(item + 1) * 256];
            let sample = data
                .samples
                .iter()
                .find(|s| {
                    (s.goal.row as f32, s.goal.col as f32) == goal
                        && s.grid
                            .obstacles()
                            .iter()
                            .map(|&o| o as u8 as f32)
                            .eq(obstacles.iter().copied())
                })
                .expect("the item's sample");
            out.extend(
                queries
                    .chunks_exact(2)
                    .map(|q| (sample, q[0] as usize, q[1] as usize)),
            );
        }
    }
    out
}

/// With `far_fraction` 1 every query lies at least half the maze's largest reachable distance
/// from the goal; out of range it is a config error.
#[test]
fn far_sampling_draws_cells_far_from_the_goal() {
    let data = dataset(16, 6, 2, 9);
    let cfg = TrainConfig {
        batch_items: 6,
        queries_per_item: 40,
        far_fraction: 1.0,
        ..TrainConfig::default()
    };
    let net = || FieldNet::new(ModelConfig::Context(small_context()), 3).unwrap();
    let bad = TrainConfig {
        far_fraction: -0.1,
        ..cfg.clone()
    };
    assert!(matches!(
        Trainer::new(net(), bad),
        Err(NetsError::InvalidConfig(_))
    ));
    let trainer = Trainer::new(net(), cfg).unwrap();
    let queries = sampled_queries(&trainer, &data, 5);
    assert_eq!(queries.len(), 5 * 6 * 40);
    for (sample, r, c) in queries {
        let max = sample
            .distance
            .iter()
            .filter(|d| d.is_finite())
            .fold(0f32, |m, &d| m.max(d));
        let d = sample.distance[r * 16 + c];
        assert!(d.is_finite() && d >= 0.5 * max, "{d} of at most {max}");
    }
}

/// With `hard_fraction` 1 every query is a reachable cell where descent on the network's
/// current field (as the planner walks it) steps to a move that is not a shortest move, judged
/// by Dijkstra here; a network that does not read the grid or a fraction out of range is a
/// config error.
#[test]
fn hard_sampling_draws_cells_where_the_move_is_wrong() {
    let data = dataset(16, 6, 2, 9);
    let cfg = TrainConfig {
        batch_items: 6,
        queries_per_item: 40,
        hard_fraction: 1.0,
        ..TrainConfig::default()
    };
    let net = || FieldNet::new(ModelConfig::Context(small_context()), 3).unwrap();
    let bad = TrainConfig {
        hard_fraction: 1.5,
        ..cfg.clone()
    };
    assert!(matches!(
        Trainer::new(net(), bad),
        Err(NetsError::InvalidConfig(_))
    ));
    let plain = FieldNet::new(
        ModelConfig::Plain(PlainConfig {
            extent: vec![16, 16],
            goal: vec![0, 0],
            mlp: MlpConfig::default(),
            encoding: Default::default(),
        }),
        0,
    )
    .unwrap();
    assert!(matches!(
        Trainer::new(plain, cfg.clone()),
        Err(NetsError::InvalidConfig(_))
    ));
    let trainer = Trainer::new(net(), cfg).unwrap();
    let queries = sampled_queries(&trainer, &data, 3);
    assert_eq!(queries.len(), 3 * 6 * 40);
    let nb = Neighbourhood2::Eight(MoveRule::Strict);
    for (sample, r, c) in queries {
        let cell = Cell2::new(r, c);
        let truth = dijkstra2(&sample.grid, &[sample.goal], nb, 2f32.sqrt()).unwrap();
        let dist = |c: Cell2| truth.get(c).unwrap_or(f32::INFINITY);
        assert!(dist(cell).is_finite() && cell != sample.goal, "({r}, {c})");
        let field = trainer.net().field(&sample.grid, sample.goal).unwrap();
        let next = descent_move(&sample.grid, &field, MoveRule::Strict, cell);
        let best = sample
            .grid
            .neighbours(cell, nb)
            .map(|(n, _)| dist(n))
            .fold(f32::INFINITY, f32::min);
        let taken = next.map_or(f32::INFINITY, dist);
        assert!(
            taken > best + 1e-3,
            "({r}, {c}): move to {taken}, best {best}"
        );
    }
}

/// With a descent weight, queries come in groups of nine: an anchor, then each neighbour in
/// `DIRECTIONS_8` order that the rule allows as a move, the anchor itself in the other slots;
/// a query count not divisible by 9 is a config error, and training runs.
#[test]
fn descent_loss_groups_an_anchor_with_its_moves() {
    let data = dataset(8, 4, 2, 5);
    let cfg = TrainConfig {
        lr: 1e-3,
        batch_items: 3,
        queries_per_item: 18,
        steps: 3,
        neighbour_weight: 2.0,
        descent_weight: 5.0,
        descent_rule: MoveRule::Strict,
        checkpoint_every: 0,
        validate_every: 0,
        ..TrainConfig::default()
    };
    let net = || FieldNet::new(ModelConfig::Context(small_context()), 3).unwrap();
    for bad in [
        TrainConfig {
            queries_per_item: 20,
            ..cfg.clone()
        },
        TrainConfig {
            descent_margin: 0.0,
            ..cfg.clone()
        },
    ] {
        assert!(matches!(
            Trainer::new(net(), bad),
            Err(NetsError::InvalidConfig(_))
        ));
    }
    // Groups make the neighbour-difference pairs, so an odd count of nine is fine.
    let odd = TrainConfig {
        queries_per_item: 27,
        ..cfg.clone()
    };
    assert!(Trainer::new(net(), odd).is_ok());
    let mut trainer = Trainer::new(net(), cfg).unwrap();
    let (batch, targets) = trainer.sample_batch(&data, 0).unwrap();
    assert_eq!(targets.len(), 54);
    let mut moves = 0;
    for (k, group) in batch.queries.chunks_exact(18).enumerate() {
        let item = k / 2;
        let grid = data
            .samples
            .iter()
            .map(|s| &s.grid)
            .find(|g| {
                g.obstacles()
                    .iter()
                    .map(|&o| o as u8 as f32)
                    .eq(batch.obstacles[item * 64..(item + 1) * 64].iter().copied())
            })
            .expect("the item's grid");
        let anchor = Cell2::new(group[0] as usize, group[1] as usize);
        for (j, &(dr, dc)) in envfield_grid::DIRECTIONS_8.iter().enumerate() {
            let slot = (group[2 * j + 2], group[2 * j + 3]);
            if MoveRule::Strict.allows(grid, anchor, dr, dc) {
                let want = (anchor.row as isize + dr, anchor.col as isize + dc);
                assert_eq!(slot, (want.0 as f32, want.1 as f32), "group {k} slot {j}");
                moves += 1;
            } else {
                assert_eq!(slot, (group[0], group[1]), "group {k} slot {j}");
            }
        }
    }
    assert!(moves > 0);
    let summary = trainer
        .run(std::slice::from_ref(&data), None, None, |_| true)
        .unwrap();
    assert!(summary.loss.is_finite());
}

/// Sizes past what a machine can hold are refused before anything is allocated.
#[test]
fn oversized_requests_are_refused_before_they_allocate() {
    let net = FieldNet::new(ModelConfig::Context(small_context()), 1).unwrap();
    let huge = Grid2::new(2048, 1024).unwrap();
    let err = net.field(&huge, Cell2::new(0, 0)).unwrap_err().to_string();
    assert!(
        err.contains("2048x1024") && err.contains("1048576"),
        "{err}"
    );
    for spec in [
        "100000000x[16:1]",
        "16:1,2000x[8:2]",
        "99999999:1",
        "16:99999999",
    ] {
        let err = match envfield_nets::parse_convs(spec) {
            Err(e) => e.to_string(),
            Ok(convs) => {
                let cfg = ContextConfig {
                    encoder: convs,
                    ..small_context()
                };
                FieldNet::new(ModelConfig::Context(cfg), 0)
                    .unwrap_err()
                    .to_string()
            }
        };
        assert!(
            err.contains("more than") || err.contains("1..="),
            "{spec}: {err}"
        );
    }
    let too_big = TrainConfig {
        batch_items: 1 << 20,
        queries_per_item: 1 << 20,
        ..TrainConfig::default()
    };
    let err = too_big.validate().unwrap_err().to_string();
    assert!(err.contains("batch_items x queries_per_item"), "{err}");
    // One field named, not the whole config.
    let bad_lr = TrainConfig {
        lr: -1.0,
        ..TrainConfig::default()
    };
    let err = bad_lr.validate().unwrap_err().to_string();
    assert!(
        err.contains("lr must be positive") && !err.contains("batch_items"),
        "{err}"
    );
}
