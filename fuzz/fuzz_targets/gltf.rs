#![no_main]
//! glTF scenes: any bytes, read as a `.gltf` or `.glb` file (no folder, so no external
//! buffer), give a mesh or a clean error; never a panic, a hang or an out-of-bounds read.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = envfield::scene::parse_gltf(data, None, "fuzz.glb");
});
