#![no_main]
//! Scene import: any OBJ bytes, read with any up axis and units (the first byte picks them),
//! import as a mesh in the library's frame with a report, or give a clean error.
use envfield::scene::{import_mesh, ImportConfig, TriangleMesh, Units, UpAxis};

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Some((&flags, rest)) = data.split_first() else {
        return;
    };
    let up = if flags & 1 == 0 { UpAxis::Z } else { UpAxis::Y };
    let units = match (flags >> 1) % 4 {
        0 => Units::Metres,
        1 => Units::Centimetres,
        2 => Units::Millimetres,
        _ => Units::Scale(f32::from(flags) * 0.37),
    };
    let text = String::from_utf8_lossy(rest);
    if let Ok(mesh) = TriangleMesh::parse_obj(&text, "fuzz.obj") {
        if let Ok((out, report)) = import_mesh(&mesh, &ImportConfig::new(up, units)) {
            assert_eq!(out.triangles.len(), report.triangles);
            let _ = report.to_string();
        }
    }
});
