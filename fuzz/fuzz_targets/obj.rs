#![no_main]
//! OBJ meshes: any bytes, read as text, give a mesh or a clean error.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = envfield::scene::TriangleMesh::parse_obj(&String::from_utf8_lossy(data), "fuzz.obj");
});
