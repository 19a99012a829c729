#![no_main]
//! The maze text format: any bytes, read as text, give mazes or a clean error.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = envfield::grid::parse_mazes(&String::from_utf8_lossy(data));
});
