#![no_main]
//! Weight files and checkpoints: any bytes, as a file, load as a field network, VIN or
//! training checkpoint, or give a clean error.
use std::path::PathBuf;

fn probe() -> PathBuf {
    std::env::temp_dir().join(format!(
        "envfield-fuzz-weights-{}.safetensors",
        std::process::id()
    ))
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let path = probe();
    if std::fs::write(&path, data).is_ok() {
        let _ = envfield::nets::FieldNet::load(&path);
        let _ = envfield::nets::Vin::load(&path);
        let _ = envfield::nets::Trainer::resume(&path);
    }
});
