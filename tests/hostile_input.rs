//! Every parser meets hostile input: arbitrary bytes and mutations of valid files (seeded), and
//! must answer `Ok` or a clean `Err`, never a panic, and never ask for an unbounded amount of
//! memory. The maze text, PNG, `.npy`, OBJ, PLY, pose JSON, weight files (field networks, VIN,
//! training checkpoints) and model configs are covered.
//!
//! The test binary's allocator refuses any single request above [`LIMIT`] (the process then
//! aborts, failing the test), so "bounded memory" is checked, not hoped for. The fuzz targets
//! in `fuzz/` run the same parsers for longer (`fuzz/run.sh`).

use envfield::affordance::{walk, PoseSequence, WalkConfig};
use envfield::grid::{parse_mazes, Grid2, NpyArray, NpyData};
use envfield::nets::{
    ContextConfig, ConvSpec, FieldNet, MlpConfig, ModelConfig, TrainConfig, Trainer, Vin, VinConfig,
};
use envfield::scene::TriangleMesh;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The largest single allocation a parser may ask for while it reads a small input.
const LIMIT: usize = 1 << 30;

/// The largest request seen, for the report.
static LARGEST: AtomicUsize = AtomicUsize::new(0);

struct Bounded;

// SAFETY: every call is forwarded to the system allocator unchanged, except requests above
// LIMIT, which get a null pointer (the documented way to report an allocation failure).
unsafe impl GlobalAlloc for Bounded {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        if layout.size() > LIMIT {
            return std::ptr::null_mut();
        }
        // SAFETY: the caller's layout contract is passed on as it is.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System.alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        if new_size > LIMIT {
            return std::ptr::null_mut();
        }
        // SAFETY: as for `alloc`; `ptr` and `layout` are the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Bounded = Bounded;

/// A seeded runner: the same cases on every machine.
fn runner(cases: u32, seed: u8) -> TestRunner {
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    TestRunner::new_with_rng(
        config,
        TestRng::from_seed(RngAlgorithm::ChaCha, &[seed; 32]),
    )
}

/// Byte strings: arbitrary ones, and `valid` with a few bytes changed, inserted or cut off.
fn hostile(valid: Vec<u8>) -> impl Strategy<Value = Vec<u8>> {
    let n = valid.len().max(1);
    let edits = proptest::collection::vec((0..n, any::<u8>(), 0u8..3), 1..8);
    let mutated = (edits, proptest::option::of(0..n)).prop_map(move |(edits, cut)| {
        let mut bytes = valid.clone();
        for (at, byte, kind) in edits {
            let at = at.min(bytes.len());
            match kind {
                0 if at < bytes.len() => bytes[at] = byte,
                1 => bytes.insert(at, byte),
                _ if at < bytes.len() => {
                    bytes.remove(at);
                }
                _ => bytes.push(byte),
            }
        }
        if let Some(cut) = cut {
            bytes.truncate(cut);
        }
        bytes
    });
    prop_oneof![
        1 => proptest::collection::vec(any::<u8>(), 0..600),
        3 => mutated,
    ]
}

/// Runs `parse` on `cases` hostile variants of `valid`; a panic fails the test with the input.
fn survive(name: &str, valid: Vec<u8>, cases: u32, parse: impl Fn(&[u8])) {
    let ran = AtomicUsize::new(0);
    runner(cases, name.len() as u8)
        .run(&hostile(valid), |bytes| {
            parse(&bytes);
            ran.fetch_add(1, Ordering::Relaxed);
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(ran.into_inner(), cases as usize, "{name}");
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("envfield-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn maze_text() {
    let valid = b"; two mazes\n#####\n#S..#\n#.#G#\n#####\n\n..G\nS..\n".to_vec();
    survive("maze text", valid, 2000, |b| {
        let _ = parse_mazes(&text(b));
    });
}

#[test]
fn png_grids() {
    let path = tmp("grid.png");
    let mut grid = Grid2::new(9, 7).unwrap();
    grid.set_obstacle(envfield::grid::Cell2::new(3, 3), true)
        .unwrap();
    grid.write_png(&path).unwrap();
    survive("png", std::fs::read(&path).unwrap(), 600, |b| {
        let _ = Grid2::from_png_bytes(b, "hostile.png");
    });
}

#[test]
fn npy_arrays() {
    let grid = NpyArray {
        shape: vec![4, 5],
        data: NpyData::Bool(vec![false; 20]),
    };
    let field = NpyArray {
        shape: vec![2, 3, 2],
        data: NpyData::F32(vec![1.5; 12]),
    };
    for (name, array) in [("npy grid", grid), ("npy field", field)] {
        survive(name, array.to_bytes().unwrap(), 1000, |b| {
            let _ = NpyArray::from_bytes(b);
        });
    }
}

#[test]
fn obj_and_ply_meshes() {
    let cube = TriangleMesh::cube(1.0);
    let (obj, ply) = (tmp("cube.obj"), tmp("cube.ply"));
    cube.write_obj(&obj).unwrap();
    cube.write_ply(&ply).unwrap();
    survive("obj", std::fs::read(&obj).unwrap(), 1000, |b| {
        let _ = TriangleMesh::parse_obj(&text(b), "hostile.obj");
    });
    survive("ply", std::fs::read(&ply).unwrap(), 1000, |b| {
        let _ = TriangleMesh::parse_ply(b, "hostile.ply");
    });
    // An ASCII PLY too, whose body the binary one does not exercise.
    let ascii = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
        .to_vec();
    assert!(TriangleMesh::parse_ply(&ascii, "ascii.ply").is_ok());
    survive("ascii ply", ascii, 1000, |b| {
        let _ = TriangleMesh::parse_ply(b, "hostile.ply");
    });
}

#[test]
fn pose_json() {
    let config = WalkConfig {
        cycles: 1,
        ..WalkConfig::default()
    };
    let json = walk(&config, 1).unwrap().to_json().unwrap();
    survive("pose json", json.into_bytes(), 300, |b| {
        let _ = PoseSequence::from_json(&text(b));
    });
}

fn tiny_context() -> ModelConfig {
    ModelConfig::Context(ContextConfig {
        encoder: vec![ConvSpec::new(4, 1), ConvSpec::new(4, 2)],
        mlp: MlpConfig {
            hidden: 8,
            layers: 1,
            ..MlpConfig::default()
        },
        ..ContextConfig::default()
    })
}

#[test]
fn weight_files_and_checkpoints() {
    let weights = tmp("field.safetensors");
    FieldNet::new(tiny_context(), 3)
        .unwrap()
        .save(&weights)
        .unwrap();
    let ckpt = tmp("field.ckpt");
    let trainer = Trainer::new(
        FieldNet::new(tiny_context(), 3).unwrap(),
        TrainConfig::default(),
    );
    trainer.unwrap().save_checkpoint(&ckpt).unwrap();
    let vin_file = tmp("vin.safetensors");
    let vin = VinConfig {
        hidden: 4,
        q_channels: 3,
        ..VinConfig::for_size(8)
    };
    Vin::new(vin, 1).unwrap().save(&vin_file).unwrap();
    let probe = tmp("probe.safetensors");
    for (name, source) in [
        ("weights", weights),
        ("checkpoint", ckpt),
        ("vin", vin_file),
    ] {
        survive(name, std::fs::read(&source).unwrap(), 150, |b| {
            std::fs::write(&probe, b).unwrap();
            let _ = FieldNet::load(&probe);
            let _ = Vin::load(&probe);
            let _ = Trainer::resume(&probe);
        });
    }
}

#[test]
fn model_configs() {
    let json = serde_json::to_string(&tiny_context()).unwrap();
    survive("model config", json.into_bytes(), 600, |b| {
        if let Ok(config) = serde_json::from_str::<ModelConfig>(&text(b)) {
            let _ = FieldNet::new(config, 0);
        }
    });
    let json = serde_json::to_string(&TrainConfig::default()).unwrap();
    survive("train config", json.into_bytes(), 600, |b| {
        if let Ok(config) = serde_json::from_str::<TrainConfig>(&text(b)) {
            let _ = config.validate();
        }
    });
}

#[test]
fn the_allocator_saw_no_request_above_the_limit() {
    // Runs beside the others: a request above the limit would have aborted the process first.
    assert!(LARGEST.load(Ordering::Relaxed) <= LIMIT);
}
