#![no_main]
//! `.npy` arrays: any bytes give an array or a clean error.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = envfield::grid::NpyArray::from_bytes(data);
});
