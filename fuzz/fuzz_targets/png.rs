#![no_main]
//! PNG grids: any bytes give a grid or a clean error, with the size checked before decoding.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = envfield::grid::Grid2::from_png_bytes(data, "fuzz.png");
});
