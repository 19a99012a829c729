//! Inputs the fuzzer found (`fuzz/run.sh`), kept as regressions: each must be a clean error.

use envfield_scene::TriangleMesh;

#[test]
fn fuzzer_findings_are_clean_errors() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/regressions");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let bytes = std::fs::read(&path).unwrap();
        let result = match path.extension().and_then(|e| e.to_str()) {
            Some("ply") => TriangleMesh::parse_ply(&bytes, &path),
            Some("obj") => TriangleMesh::parse_obj(&String::from_utf8_lossy(&bytes), &path),
            _ => continue,
        };
        let err = result.expect_err("a fuzzer finding parsed").to_string();
        assert!(err.contains(&*path.to_string_lossy()), "{err}");
        seen += 1;
    }
    assert!(seen >= 1, "no regression inputs in {}", dir.display());
}

/// The two shapes of the first finding, written out: a list length read as a float, and an
/// element that holds nothing but claims a huge count.
#[test]
fn list_lengths_and_counts_are_checked_before_they_are_trusted() {
    let header = |face: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\n{face}end_header\n0 0 0\n1 0 0\n0 1 0\n"
        )
    };
    let float_len =
        header("element face 1\nproperty list float int vertex_indices\n") + "3e30 0 1 2\n";
    let err = TriangleMesh::parse_ply(float_len.as_bytes(), "a.ply")
        .unwrap_err()
        .to_string();
    assert!(err.contains("bad list length"), "{err}");
    let empty = header("element face 1\nproperty list uchar int vertex_indices\nelement junk 18446744073709551615\n")
        + "3 0 1 2\n";
    let mesh = TriangleMesh::parse_ply(empty.as_bytes(), "b.ply").unwrap();
    assert_eq!(mesh.triangles.len(), 1);
}
