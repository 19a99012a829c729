#![no_main]
//! PLY meshes (ASCII and binary): any bytes give a mesh or a clean error.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = envfield::scene::TriangleMesh::parse_ply(data, "fuzz.ply");
});
