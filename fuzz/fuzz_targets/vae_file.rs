#![no_main]
//! VAE weight files and checkpoints: any bytes, as a file, load as a VAE or a VAE trainer, or
//! give a clean error.
use std::path::PathBuf;

fn probe() -> PathBuf {
    std::env::temp_dir().join(format!(
        "envfield-fuzz-vae-{}.safetensors",
        std::process::id()
    ))
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let path = probe();
    if std::fs::write(&path, data).is_ok() {
        let _ = envfield::vae::Cvae::load(&path);
        let _ = envfield::vae::VaeTrainer::resume(&path);
    }
});
