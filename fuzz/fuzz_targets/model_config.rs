#![no_main]
//! Model and training configs in JSON: whatever parses builds a network or is refused, with
//! the memory a network may claim bounded.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(config) = serde_json::from_str::<envfield::nets::ModelConfig>(&text) {
        let _ = envfield::nets::FieldNet::new(config, 0);
    }
    if let Ok(config) = serde_json::from_str::<envfield::nets::TrainConfig>(&text) {
        let _ = config.validate();
    }
});
