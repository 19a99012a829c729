#![allow(missing_docs)]
//! Training and inference speed of the four field networks at 28x28:
//! `train_step/<arch>` is one AdamW step (forward, backward, update) on the batch the example
//! trains with; `field_28/<arch>` predicts one whole 28x28 field (encoder once, 784 queries).

use criterion::{criterion_group, criterion_main, Criterion};
use envfield_grid::{FieldModel, MoveRule};
use envfield_mazes::{Dataset, DatasetConfig, GeneratorKind, MazeGenerator, TargetKind};
use envfield_nets::{Arch, FieldNet, ModelConfig, TargetEncoding, TrainConfig, Trainer};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The presets `train_maze` trains, with the batch it trains each on (items, queries).
fn configs(goal: [usize; 2]) -> Vec<(ModelConfig, usize, usize)> {
    let preset = |arch: Arch| arch.preset(28, 28, goal, TargetEncoding::Reciprocal);
    vec![
        (preset(Arch::Plain), 1, 784),
        (preset(Arch::Goal), 32, 256),
        (preset(Arch::Context), 32, 256),
        (preset(Arch::Hyper), 32, 256),
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
    for (cfg, items, queries) in configs([s.goal.row, s.goal.col]) {
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
    for (cfg, _, _) in configs([s.goal.row, s.goal.col]) {
        let arch = cfg.arch();
        let net = FieldNet::new(cfg, 0).unwrap();
        infer.bench_function(arch, |b| b.iter(|| net.predict(&s.grid, s.goal).unwrap()));
    }
    infer.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
