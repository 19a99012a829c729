//! The accessible region of an apartment read from a user's file: a 3-room apartment of
//! evaluation models (seed 30000, written as one OBJ and read back), its torso samples drawn
//! by the shipped gated VAE at 240 per m², and the region built from them (the torso filter,
//! the gaps closed, the sit-down bridges, the voxels). Needs the contributed models
//! (`scripts/fetch_sweethome3d_contrib.sh`); without them it says so and measures nothing.
//!
//! `cargo bench --bench apartment_region`

// criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use envfield::rooms::sampling::SAMPLES_PER_M2;
use envfield::rooms::{draw_torsos, AccessibleRegion, RegionConfig};
use envfield::scene::{apartment, read_scene, ApartmentConfig, Catalogue, Half, ImportConfig};
use envfield::vae::{Cvae, SampleOptions};
use std::hint::black_box;
use std::path::Path;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench_apartment_region(c: &mut Criterion) {
    let Some(dir) = Catalogue::find_contrib() else {
        eprintln!("apartment_region: no contributed models (scripts/fetch_sweethome3d_contrib.sh)");
        return;
    };
    let models = Catalogue::read(dir).expect("models").only(Half::Evaluation);
    let apt = apartment(&models, &ApartmentConfig::default(), 30_000).expect("apartment");
    let file = std::env::temp_dir().join(format!("envfield-bench-{}.obj", std::process::id()));
    apt.home.scene.to_mesh().write(&file).expect("write");
    let (scene, _) = read_scene(&file, &ImportConfig::default()).expect("read");
    std::fs::remove_file(&file).ok();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let vae = Cvae::load(root.join("models/vae_gated.safetensors")).expect("vae");
    let n = (apt.home.size[0] * apt.home.size[1] * SAMPLES_PER_M2).round() as usize;
    let options = SampleOptions::new(n, 30_000);
    let drawn = draw_torsos(&vae, &scene, &options, None).expect("samples");
    let config = RegionConfig::default();
    let mut group = c.benchmark_group("apartment_region");
    group.sample_size(10);
    group.bench_function("samples", |b| {
        b.iter(|| black_box(draw_torsos(&vae, &scene, &options, None).expect("samples")))
    });
    group.bench_function("region_from_samples", |b| {
        b.iter(|| black_box(AccessibleRegion::from_drawn(&scene, &drawn, &config).expect("region")))
    });
    group.finish();
}

criterion_group!(benches, bench_apartment_region);
criterion_main!(benches);
