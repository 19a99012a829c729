//! glTF scenes in: the glTF 2.0 test models of Debian's `assimp-testmodels` (fetched by
//! `scripts/fetch_assimp_gltf.sh`; where absent the sweep says by name that it did not run,
//! and under CI, `CI=true`, it fails), each read or refused with a clear error and none
//! panicking; and scenes written here as glTF, y up, that must read back as the same scene.

use envfield_scene::{
    import_mesh, parse_gltf, read_scene, ImportConfig, SceneError, TriangleMesh, UpAxis,
};
use std::path::{Path, PathBuf};

fn assimp_models(test: &str) -> Option<Vec<PathBuf>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/assimp-gltf");
    if !dir.is_dir() {
        let reason = "the glTF test models are not fetched (scripts/fetch_assimp_gltf.sh)";
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true: {reason}"
        );
        eprintln!("{test} did not run: {reason}");
        return None;
    }
    let mut files = Vec::new();
    let mut stack = vec![dir];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) {
                files.push(p);
            }
        }
    }
    files.sort();
    Some(files)
}

/// Every file is read or refused with an error naming the file and the part; none panics.
/// The ones a reader must read are read, the ones built to break it refused for their reason.
#[test]
fn every_assimp_test_model_is_read_or_refused_by_name() {
    let Some(files) = assimp_models("every_assimp_test_model_is_read_or_refused_by_name") else {
        return;
    };
    assert!(files.len() >= 40, "{} files", files.len());
    let mut read = 0;
    let mut outcome = std::collections::BTreeMap::new();
    for file in &files {
        let config = ImportConfig::for_file(file, None, None);
        assert_eq!(config.up, UpAxis::Y);
        let result = std::panic::catch_unwind(|| read_scene(file, &config));
        let result = result.unwrap_or_else(|_| panic!("{} panicked", file.display()));
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let key = format!(
            "{}/{name}",
            file.parent()
                .unwrap()
                .file_name()
                .unwrap()
                .to_string_lossy()
        );
        match &result {
            Ok((_, report)) => {
                read += 1;
                assert!(report.triangles > 0);
                assert!(!report.parts.is_empty(), "{name}: no parts");
            }
            Err(e) => {
                let text = e.to_string();
                assert!(
                    text.contains(&name) || text.contains(&*file.to_string_lossy()),
                    "{name}: the error does not name the file: {text}"
                );
            }
        }
        eprintln!(
            "{name}: {}",
            match &result {
                Ok((_, r)) => format!("read, {} triangles, {} parts", r.triangles, r.parts.len()),
                Err(e) => format!("refused: {e}"),
            }
        );
        outcome.insert(
            key,
            result.map(|(_, r)| r.triangles).map_err(|e| e.to_string()),
        );
    }
    let get = |n: &str| outcome.get(n).unwrap_or_else(|| panic!("{n} not found"));
    // Binary, embedded and external buffers, node hierarchies: read.
    for name in [
        "2CylinderEngine-glTF-Binary/2CylinderEngine.glb",
        "BoxTextured-glTF-Binary/BoxTextured.glb",
        "BoxTextured-glTF-Embedded/BoxTextured.gltf",
        "BoxTextured-glTF/BoxTextured.gltf",
        "AnimatedMorphCube-glTF/AnimatedMorphCube.gltf",
        "IncorrectVertexArrays/Cube.gltf",
        "Mesh_PrimitiveMode/Mesh_PrimitiveMode_04.gltf",
        "Mesh_PrimitiveMode/Mesh_PrimitiveMode_05.gltf",
        "Mesh_PrimitiveMode/Mesh_PrimitiveMode_06.gltf",
    ] {
        assert!(get(name).is_ok(), "{name}: {:?}", get(name));
    }
    assert_eq!(
        get("BoxTextured-glTF-Binary/BoxTextured.glb")
            .as_ref()
            .unwrap(),
        &12
    );
    // Built to break importers: refused, for their reason.
    let refused = |name: &str, why: &str| {
        let e = get(name).as_ref().expect_err(name);
        assert!(e.contains(why), "{name}: `{e}` does not say `{why}`");
    };
    refused("IndexOutOfRange/IndexOutOfRange.gltf", "beyond the");
    refused("IndexOutOfRange/AllIndicesOutOfRange.gltf", "beyond the");
    refused("draco/2CylinderEngine.gltf", "Draco");
    refused("TestNoRootNode/NoScene.gltf", "scene: Index out of bounds");
    refused("MissingBin/BoxTextured.gltf", "buffer 0");
    refused("RecursiveNodes/RecursiveNodes.gltf", "does the tree loop");
    refused(
        "BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
        "not finite",
    );
    refused(
        "Mesh_PrimitiveMode/Mesh_PrimitiveMode_00.gltf",
        "points or lines",
    );
    eprintln!("{read} of {} read", files.len());
    // 23 read; the other 23 are points or lines (8), JSON of the wrong types (6), no scene or
    // a scene without nodes (2), indices out of range (2), a missing buffer, a looping tree,
    // Draco, a required extension not supported (KHR_technique_webgl), infinite coordinates.
    assert!(read >= 23, "only {read} read");
}

/// A box and a table top, y up, written as glTF with nested node transforms (a translation
/// and a rotation above the meshes): read without a flag, it is the same scene as the z-up
/// mesh it was made from.
#[test]
fn a_nested_y_up_gltf_reads_as_its_z_up_mesh() {
    let json = r#"{
      "asset": {"version": "2.0"},
      "scene": 0,
      "scenes": [{"nodes": [0]}],
      "nodes": [
        {"name": "room", "translation": [10, 0, 0], "children": [1]},
        {"name": "turned", "rotation": [0, 0.7071068, 0, 0.7071068], "children": [2, 3]},
        {"name": "floor", "mesh": 0},
        {"name": "top", "mesh": 0, "translation": [0, 0.75, 0], "scale": [0.25, 1, 0.25]}
      ],
      "meshes": [{"name": "quad", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
      "buffers": [{"byteLength": 60, "uri": "data:application/octet-stream;base64,AAAAwAAAAAAAAADAAAAAQAAAAAAAAADAAAAAQAAAAAAAAABAAAAAwAAAAAAAAABAAAACAAEAAAADAAIA"}],
      "bufferViews": [
        {"buffer": 0, "byteOffset": 0, "byteLength": 48},
        {"buffer": 0, "byteOffset": 48, "byteLength": 12}
      ],
      "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
         "min": [-2, 0, -2], "max": [2, 0, 2]},
        {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}
      ]
    }"#;
    let (mesh, parts) = parse_gltf(json.as_bytes(), None, "nested.gltf").unwrap();
    assert_eq!(mesh.triangles.len(), 4);
    let names: Vec<&str> = parts.iter().map(|p| p.name.as_str()).collect();
    assert!(
        names.contains(&"floor") && names.contains(&"top"),
        "{names:?}"
    );
    let (z_up, report) =
        import_mesh(&mesh, &ImportConfig::for_file("nested.gltf", None, None)).unwrap();
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    // A 4 x 4 m floor at z = 0 and a 1 x 1 m top 0.75 m above it.
    let top: Vec<f32> = z_up.vertices.iter().map(|v| v.z).collect();
    assert!(
        top.iter()
            .all(|&z| z.abs() < 1e-5 || (z - 0.75).abs() < 1e-5),
        "{top:?}"
    );
    assert!((report.bounds[1][0] - 4.0).abs() < 1e-4 && (report.bounds[1][1] - 4.0).abs() < 1e-4);
    let raised: Vec<_> = z_up.vertices.iter().filter(|v| v.z > 0.5).collect();
    let span = raised.iter().map(|v| v.x).fold(f32::MIN, f32::max)
        - raised.iter().map(|v| v.x).fold(f32::MAX, f32::min);
    assert!((span - 1.0).abs() < 1e-4, "{span}");
}

/// What the reader cannot read is refused, naming the part: a missing buffer file, a
/// buffer shorter than it says, indices past the vertices, a loop in the node tree.
#[test]
fn broken_gltf_files_are_refused_naming_the_part() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scene.gltf");
    let doc = |buffer: &str, nodes: &str, indices: &str| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}], "nodes": {nodes},
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
            "buffers": [{buffer}],
            "bufferViews": [{{"buffer": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}],
            "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}},
                          {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}]{indices}}}"#
        )
    };
    let tri = base64_triangle([0, 1, 2]);
    let cases = [
        (
            doc(
                r#"{"byteLength": 44, "uri": "missing.bin"}"#,
                r#"[{"mesh": 0}]"#,
                "",
            ),
            "buffer 0",
        ),
        (
            doc(
                &format!(
                    r#"{{"byteLength": 44, "uri": "{}"}}"#,
                    base64_triangle([0, 1, 7])
                ),
                r#"[{"mesh": 0}]"#,
                "",
            ),
            "beyond the 3 vertices",
        ),
        (
            doc(
                &format!(r#"{{"byteLength": 44, "uri": "{tri}"}}"#),
                r#"[{"mesh": 0, "children": [0]}]"#,
                "",
            ),
            "node 0",
        ),
        (
            doc(
                &format!(r#"{{"byteLength": 400, "uri": "{tri}"}}"#),
                r#"[{"mesh": 0}]"#,
                "",
            ),
            "buffers",
        ),
        (
            doc(
                &format!(r#"{{"byteLength": 44, "uri": "{tri}"}}"#),
                r#"[{"mesh": 0}]"#,
                r#", "extensionsRequired": ["KHR_draco_mesh_compression"], "extensionsUsed": ["KHR_draco_mesh_compression"]"#,
            ),
            "Draco",
        ),
    ];
    for (text, part) in cases {
        std::fs::write(&file, &text).unwrap();
        let e = TriangleMesh::read(&file).expect_err(part);
        let msg = e.to_string();
        assert!(
            matches!(e, SceneError::Gltf { .. })
                && msg.contains(part)
                && msg.contains("scene.gltf"),
            "{msg}"
        );
    }
    // Found by the fuzzer: a primitive naming an accessor the file lacks once panicked inside
    // the gltf crate's own checks.
    let text = r#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]}"#;
    std::fs::write(&file, text).unwrap();
    let e = TriangleMesh::read(&file).unwrap_err().to_string();
    assert!(e.contains("names accessor 0 of 0"), "{e}");
    // The good one reads.
    std::fs::write(
        &file,
        doc(
            &format!(r#"{{"byteLength": 44, "uri": "{tri}"}}"#),
            r#"[{"mesh": 0}]"#,
            "",
        ),
    )
    .unwrap();
    assert_eq!(TriangleMesh::read(&file).unwrap().triangles.len(), 1);
}

/// A data URI of a triangle's three vertices and the given u16 indices (44 bytes).
fn base64_triangle(indices: [u16; 3]) -> String {
    let mut bytes = Vec::new();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for c in v {
            bytes.extend(c.to_le_bytes());
        }
    }
    for i in indices {
        bytes.extend(i.to_le_bytes());
    }
    bytes.extend([0, 0]);
    format!(
        "data:application/octet-stream;base64,{}",
        base64::encode(&bytes)
    )
}

/// OBJ objects and groups come back as named parts over their faces; faces before the first
/// name are a part of their own.
#[test]
fn obj_objects_and_groups_are_kept_as_named_parts() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\no table\ng table top\nf 2 4 3\nf 1 2 4\ng\no chair\nf 1 3 4\n";
    let (mesh, parts) = TriangleMesh::parse_obj_parts(text, "room.obj").unwrap();
    assert_eq!(mesh.triangles.len(), 4);
    let got: Vec<(&str, std::ops::Range<usize>)> = parts
        .iter()
        .map(|p| (p.name.as_str(), p.triangles.clone()))
        .collect();
    assert_eq!(got, vec![("", 0..1), ("table top", 1..3), ("chair", 3..4)]);
}

/// The fuzz target's seeds (fuzz/seeds/gltf/: triangles, strips and fans under nested nodes
/// as .gltf, and the triangles as .glb) read: six indices are two triangles, or four as a
/// strip or a fan, under each of the two nodes.
#[test]
fn the_fuzz_seeds_read() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds/gltf");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        let bytes = std::fs::read(&p).unwrap();
        let (mesh, parts) = parse_gltf(&bytes, None, &p).unwrap();
        assert_eq!(parts.len(), 2, "{}", p.display());
        let name = p.file_name().unwrap().to_string_lossy();
        let per_node = if name.contains("mode5") || name.contains("mode6") {
            4
        } else {
            2
        };
        assert_eq!(mesh.triangles.len(), 2 * per_node, "{name}");
        n += 1;
    }
    assert_eq!(n, 4);
}
