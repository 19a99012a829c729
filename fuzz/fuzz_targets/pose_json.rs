#![no_main]
//! Pose sequences in JSON: any bytes, read as text, give a sequence or a clean error.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = envfield::affordance::PoseSequence::from_json(&String::from_utf8_lossy(data));
});
