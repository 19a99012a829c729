//! The VIN baseline learns to plan on small mazes, and its files round-trip.

use envfield::grid::{Cell2, MoveRule};
use envfield::mazes::{GeneratorKind, MazeGenerator};
use envfield::nets::{
    ContextConfig, FieldNet, ModelConfig, NetsError, Vin, VinConfig, VinData, VinTrainConfig,
    VinTrainer,
};
use envfield::plan::{evaluate, EvalConfig, PolicyWalk};

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("envfield-vin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Six hundred imitation steps on 8x8 gridworlds (VIN's data and optimiser) give a VIN that
/// solves most held-out mazes and picks an optimal action at most states (an untrained one
/// does neither), and a checkpoint resumes to the same weights.
#[test]
fn vin_learns_8x8_mazes_and_resumes() {
    let generator = MazeGenerator::new(GeneratorKind::Gridworld, 8).unwrap();
    let mazes = generator.generate_many(300, 1).unwrap();
    let data = VinData::generate(&mazes, MoveRule::Vin, 7, 1).unwrap();
    assert_eq!(data.maps(), 300);
    assert!(data.rows() >= 300 && data.states() > 2000, "{data:?}");
    let cfg = VinTrainConfig::default();
    let held_out = generator.generate_many(40, 99).unwrap();
    let eval = EvalConfig {
        rule: MoveRule::Vin,
        pairs_per_maze: 1,
        seed: 3,
    };
    let untrained = Vin::new(VinConfig::for_size(8), 0).unwrap();
    let before = evaluate(&PolicyWalk(&untrained), &held_out, &eval, &mut |_, _| {}).unwrap();

    let mut trainer =
        VinTrainer::new(Vin::new(VinConfig::for_size(8), 0).unwrap(), cfg.clone()).unwrap();
    let ckpt = tmp("vin.ckpt");
    for _ in 0..150 {
        trainer.train_step(&data).unwrap();
    }
    trainer.save_checkpoint(&ckpt).unwrap();
    let mut resumed = VinTrainer::resume(&ckpt, cfg).unwrap();
    assert_eq!(resumed.step(), 150);
    for _ in 0..450 {
        trainer.train_step(&data).unwrap();
        resumed.train_step(&data).unwrap();
    }
    let (a, b) = (trainer.into_net(), resumed.into_net());
    let maze = &held_out[0];
    let goal = maze.goal.unwrap();
    let start = maze.grid.free_cells().find(|&c| c != goal).unwrap();
    assert_eq!(
        a.action_logits(&maze.grid, goal, start).unwrap(),
        b.action_logits(&maze.grid, goal, start).unwrap()
    );

    let after = evaluate(&PolicyWalk(&a), &held_out, &eval, &mut |_, _| {}).unwrap();
    let test = VinData::generate(&held_out, MoveRule::Vin, 1, 5).unwrap();
    let accuracy = (
        test.action_accuracy(&untrained).unwrap(),
        test.action_accuracy(&a).unwrap(),
    );
    assert!(
        accuracy.1 >= 0.8 && accuracy.1 > accuracy.0 + 0.3,
        "action accuracy before {} after {}",
        accuracy.0,
        accuracy.1
    );
    assert!(
        after.summary.success_rate >= 80.0
            && after.summary.success_rate > before.summary.success_rate + 20.0,
        "success before {} after {}",
        before.summary.success_rate,
        after.summary.success_rate
    );
}

#[test]
fn vin_files_round_trip_and_foreign_files_fail() {
    let vin = Vin::new(
        VinConfig {
            hidden: 8,
            ..VinConfig::for_size(8)
        },
        5,
    )
    .unwrap();
    let path = tmp("vin.safetensors");
    vin.save(&path).unwrap();
    let back = Vin::load(&path).unwrap();
    let maze = MazeGenerator::new(GeneratorKind::Gridworld, 8)
        .unwrap()
        .generate(4)
        .unwrap();
    let goal = maze.goal.unwrap();
    let start = maze.grid.free_cells().find(|&c| c != goal).unwrap();
    assert_eq!(back.config(), vin.config());
    assert_eq!(
        vin.action_logits(&maze.grid, goal, start).unwrap(),
        back.action_logits(&maze.grid, goal, start).unwrap()
    );
    assert!(vin
        .action_logits(&maze.grid, goal, Cell2::new(99, 0))
        .is_err());
    // A field network's file is not a VIN file, and the other way round.
    let field = tmp("field.safetensors");
    FieldNet::new(ModelConfig::Context(ContextConfig::default()), 0)
        .unwrap()
        .save(&field)
        .unwrap();
    assert!(matches!(
        Vin::load(&field),
        Err(NetsError::Checkpoint { .. })
    ));
    assert!(matches!(
        FieldNet::load(&path),
        Err(NetsError::Checkpoint { .. })
    ));
    assert!(VinTrainer::resume(&path, VinTrainConfig::default()).is_err());
}
