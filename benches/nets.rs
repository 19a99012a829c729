#![allow(missing_docs)]
//! Training and inference speed of the four field networks at 28x28:
//! `train_step/<arch>` is one AdamW step (forward, backward, update) on the batch the example
//! trains with; `field_28/<arch>` predicts one whole 28x28 field (encoder once, 784 queries).

use criterion::{criterion_group, criterion_main, Criterion};
use envfield_grid::{FieldModel, MoveRule};
use envfield_mazes::{Dataset, DatasetConfig, GeneratorKind, MazeGenerator, TargetKind};
use envfield_nets::{
    ContextConfig, FieldNet, GoalConfig, HyperConfig, MlpConfig, ModelConfig, PlainConfig,
    TargetEncoding, TrainConfig, Trainer,
};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn configs(extent: Vec<usize>, goal: Vec<usize>) -> Vec<(ModelConfig, usize, usize)> {
    let mlp = MlpConfig {
        hidden: 128,
        layers: 4,
        fourier: 4,
        ..MlpConfig::default()
    };
    vec![
        (
            ModelConfig::Plain(PlainConfig {
                extent: extent.clone(),
                goal,
                mlp,
                encoding: TargetEncoding::Reciprocal,
            }),
            1,
            784,
        ),
        (
            ModelConfig::Goal(GoalConfig {
                extent,
                mlp,
                encoding: TargetEncoding::Reciprocal,
            }),
            32,
            256,
        ),
        (ModelConfig::Context(ContextConfig::default()), 32, 256),
        (ModelConfig::Hyper(HyperConfig::default()), 32, 256),
    ]
}

fn bench(c: &mut Criterion) {
    let data = Dataset::generate(&DatasetConfig {
        generator: MazeGenerator::new(GeneratorKind::Gridworld, 28).unwrap(),
        mazes: 64,
        goals_per_maze: 1,
        target: TargetKind::Graph(MoveRule::Vin),
        extra_obstacles: 0.0,
        seed: 1,
    })
    .unwrap();
    let s = data.samples[0].clone();
    let one = Dataset {
        samples: vec![s.clone()],
    };
    let mut train = c.benchmark_group("train_step");
    train.sample_size(10);
    for (cfg, items, queries) in configs(vec![28, 28], vec![s.goal.row, s.goal.col]) {
        let arch = cfg.arch();
        let tc = TrainConfig {
            lr: 1e-4,
            batch_items: items,
            queries_per_item: queries,
            ..TrainConfig::default()
        };
        let mut trainer = Trainer::new(FieldNet::new(cfg, 0).unwrap(), tc).unwrap();
        let source = if arch == "plain" || arch == "goal" {
            &one
        } else {
            &data
        };
        let mut step = 0;
        train.bench_function(arch, |b| {
            b.iter(|| {
                let (batch, targets) = trainer.sample_batch(source, step).unwrap();
                step += 1;
                trainer.train_batch(&batch, &targets).unwrap()
            })
        });
    }
    train.finish();
    let mut infer = c.benchmark_group("field_28");
    for (cfg, _, _) in configs(vec![28, 28], vec![s.goal.row, s.goal.col]) {
        let arch = cfg.arch();
        let net = FieldNet::new(cfg, 0).unwrap();
        infer.bench_function(arch, |b| b.iter(|| net.predict(&s.grid, s.goal).unwrap()));
    }
    infer.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
