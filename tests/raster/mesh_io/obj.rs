//! OBJ loading: files written by the test, checked against hand-computed positions, normals and
//! topology, and every error case naming the file and line.

use std::path::{Path, PathBuf};

use glam::DVec3;
use shikki::raster::mesh::Mesh;
use shikki::raster::mesh_io::{load_mesh, load_mesh_with_report};
use shikki::Error;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn v(p: [f32; 3]) -> DVec3 {
    DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]))
}

/// The unit cube [0,1]³ as quads, CCW from outside, no normals.
const CUBE: &str = "\
# unit cube, quads
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 0 0 1
v 1 0 1
v 0 1 1
v 1 1 1
f 1 3 4 2
f 5 6 8 7
f 1 2 6 5
f 3 7 8 4
f 1 5 7 3
f 2 4 8 6
";

/// Sum of triangle areas and the check that each face normal (from the winding) points away
/// from the cube's centre.
fn area_and_orientation(mesh: &Mesh, centre: DVec3) -> f64 {
    let mut area = 0.0;
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| v(mesh.positions[t[k] as usize]));
        let normal = (b - a).cross(c - a);
        assert!(
            normal.dot((a + b + c) / 3.0 - centre) > 0.0,
            "inward triangle {t:?}"
        );
        area += 0.5 * normal.length();
    }
    area
}

#[test]
fn cube_without_normals_gets_diagonal_corner_normals() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, report) = load_mesh_with_report(&write(dir.path(), "cube.obj", CUBE)).unwrap();
    // 8 shared corners (no texture coordinates or normals split them), 6 quads → 12 triangles.
    assert_eq!(mesh.positions.len(), 8);
    assert_eq!(mesh.triangle_count(), 12);
    // Exact: 6 unit faces, all f32-exact coordinates.
    assert_eq!(area_and_orientation(&mesh, DVec3::splat(0.5)), 6.0);
    // Angle-weighted: every corner sees three 90° face angles → (±1, ±1, ±1)/√3 outward.
    // 1e-6: one f32 rounding of a unit vector.
    let s = 1.0 / 3f64.sqrt();
    for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
        let expected = v(*p).map(|c| if c > 0.5 { s } else { -s });
        assert!((v(*n) - expected).length() < 1e-6, "{p:?}: {n:?}");
    }
    assert_eq!(report.generated_normals, 8);
    assert_eq!(report.degenerate_triangles_dropped, 0);
}

#[test]
fn cube_with_face_normals_keeps_them_and_splits_corners() {
    // Normals before the faces that use them (OBJ references must point backwards).
    let text = "vn 0 0 -1\nvn 0 0 1\nvn 0 -1 0\nvn 0 1 0\nvn -1 0 0\nvn 1 0 0\n".to_string() + CUBE;
    // Give face k the normal k (1-based) on all four corners.
    let mut lines: Vec<String> = Vec::new();
    let mut face = 0;
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("f ") {
            face += 1;
            let corners: Vec<String> = rest.split(' ').map(|c| format!("{c}//{face}")).collect();
            lines.push(format!("f {}", corners.join(" ")));
        } else {
            lines.push(line.to_string());
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let mesh = load_mesh(&write(dir.path(), "flat.obj", &lines.join("\n"))).unwrap();
    // Each corner is split into its three (v, vn) pairs: 24 vertices, still 12 triangles.
    assert_eq!(mesh.positions.len(), 24);
    assert_eq!(mesh.triangle_count(), 12);
    assert_eq!(area_and_orientation(&mesh, DVec3::splat(0.5)), 6.0);
    // Every vertex normal equals the normalised winding normal of its triangles, exactly (the
    // file's normals are axis-aligned unit vectors).
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| v(mesh.positions[t[k] as usize]));
        let face_normal = (b - a).cross(c - a).normalize();
        for &i in t {
            assert_eq!(v(mesh.normals[i as usize]), face_normal);
        }
    }
}

#[test]
fn relative_indices_texcoords_weights_comments_and_groups() {
    let text = "\
mtllib missing.mtl
o thing # a comment
v 2 0 0 2
v 0 4 0 2.0
vt 0.5 0.5
vn 0 0 2
g side
usemtl red
v 0 0 0
s 1
f -3/1/1 -2/1/1 -1/1/1
";
    let dir = tempfile::tempdir().unwrap();
    let mesh = load_mesh(&write(dir.path(), "misc.obj", text)).unwrap();
    // w divides: (2,0,0)/2 = (1,0,0), (0,4,0)/2 = (0,2,0); -3..-1 are vertices 1..3; the material
    // library is never opened. The file's normal (0,0,2) is renormalised.
    assert_eq!(mesh.triangle_count(), 1);
    let t = &mesh.indices;
    let corners: Vec<[f32; 3]> = t.iter().map(|&i| mesh.positions[i as usize]).collect();
    assert_eq!(
        corners,
        vec![[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 0.0]]
    );
    assert!(mesh.normals.iter().all(|n| *n == [0.0, 0.0, 1.0]));
}

#[test]
fn polygons_are_fanned_and_points_and_lines_are_skipped_with_a_note() {
    let text = "\
v 0 0 0
v 1 0 0
v 1 1 0
v 0.5 1.5 0
v 0 1 0
p 1
l 1 2 3
f 4 5
f 1 2 3 4 5
";
    let dir = tempfile::tempdir().unwrap();
    let (mesh, report) = load_mesh_with_report(&write(dir.path(), "pentagon.obj", text)).unwrap();
    // A pentagon → fan of 3 triangles; area = unit square + triangle (1,1),(0.5,1.5),(0,1) of
    // area 0.25 = 1.25 (shoelace), all facing +z.
    assert_eq!(mesh.triangle_count(), 3);
    let area: f64 = mesh
        .indices
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [0, 1, 2].map(|k| v(mesh.positions[t[k] as usize]));
            let n = (b - a).cross(c - a);
            assert!(n.z > 0.0);
            0.5 * n.length()
        })
        .sum();
    assert!((area - 1.25).abs() < 1e-12);
    let notes = report.notes().join("\n");
    assert!(notes.contains("skipped 3 point/line"), "{notes}");
}

#[test]
fn degenerate_triangles_are_dropped_and_counted() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 3\n";
    let dir = tempfile::tempdir().unwrap();
    let (mesh, report) = load_mesh_with_report(&write(dir.path(), "d.obj", text)).unwrap();
    // (1,2,4) is collinear and (1,1,3) repeats a vertex: both dropped; vertex 4 is then unused
    // and removed.
    assert_eq!(mesh.triangle_count(), 1);
    assert_eq!(mesh.positions.len(), 3);
    assert_eq!(report.degenerate_triangles_dropped, 2);
    assert!(mesh.normals.iter().all(|n| *n == [0.0, 0.0, 1.0]));
}

#[test]
fn mixed_normals_are_replaced_by_generated_ones_with_a_note() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 1 0 0\nf 1//1 2//1 3//1\nf 2 4 3\n";
    let dir = tempfile::tempdir().unwrap();
    let (mesh, report) = load_mesh_with_report(&write(dir.path(), "mixed.obj", text)).unwrap();
    // The file's (1,0,0) is not the plane's normal: it must not survive.
    assert!(
        mesh.normals.iter().all(|n| *n == [0.0, 0.0, 1.0]),
        "{:?}",
        mesh.normals
    );
    assert!(report
        .notes()
        .join(" ")
        .contains("ignored the file's normals"));
}

/// The parse error's line, or a panic describing what came instead.
fn parse_error_line(result: shikki::Result<Mesh>, file: &str) -> (usize, String) {
    match result {
        Err(Error::Parse {
            file: f,
            line,
            message,
        }) => {
            assert!(f.ends_with(file), "{f}");
            (line, message)
        }
        other => panic!("expected a parse error in {file}, got {other:?}"),
    }
}

#[test]
fn bad_lines_are_errors_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let cases = [
        ("f 1 2 4\n", 4, "out of range"),
        ("f 0 1 2\n", 4, "out of range"),
        ("f -4 1 2\n", 4, "out of range"),
        ("f 1 2 x\n", 4, "not an integer"),
        (
            "f 1/1 2 3\n",
            4,
            "texture coordinate index 1 is out of range",
        ),
        ("f 1//2 2//2 3//2\n", 4, "normal index 2 is out of range"),
        ("f 1/2/3/4 2 3\n", 4, "is not v, v/vt"),
        ("f 99999999999999999999 1 2\n", 4, "not an integer"),
        ("f -9223372036854775808 1 2\n", 4, "out of range"),
        ("f\n", 4, "at least three"),
        ("v 1 2\n", 4, "three numbers"),
        ("v 1 two 3\n", 4, "three numbers"),
        ("v nan 0 0\n", 4, "not finite"),
        ("v 1e39 0 0\n", 4, "not finite"),
        ("v 1 1 1 0\n", 4, "not finite"),
        ("vn 0 1\n", 4, "three numbers"),
        ("\nf 4 1 2\nv 1 1 1\n", 5, "out of range"),
    ];
    for (tail, expected_line, expected_message) in cases {
        let path = write(dir.path(), "bad.obj", &format!("{head}{tail}"));
        let (line, message) = parse_error_line(load_mesh(&path), "bad.obj");
        assert_eq!(line, expected_line, "{tail:?}: {message}");
        assert!(message.contains(expected_message), "{tail:?}: {message}");
    }
}

#[test]
fn binary_and_overlong_input_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("binary.obj");
    std::fs::write(&path, b"v 0 0 0\n\xff\xfe\x00garbage\n").unwrap();
    let (line, message) = parse_error_line(load_mesh(&path), "binary.obj");
    assert_eq!((line, message.contains("UTF-8")), (2, true), "{message}");

    let path = dir.path().join("long.obj");
    std::fs::write(&path, "#".repeat(2 << 20)).unwrap();
    let (line, message) = parse_error_line(load_mesh(&path), "long.obj");
    assert_eq!(
        (line, message.contains("longer than")),
        (1, true),
        "{message}"
    );
}

#[test]
fn files_without_triangles_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in [
        ("empty.obj", ""),
        ("lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n"),
        ("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"),
    ] {
        let path = write(dir.path(), name, text);
        let message = load_mesh(&path).unwrap_err().to_string();
        assert!(message.contains(name), "{message}");
        assert!(message.contains("no triangles"), "{message}");
    }
}

#[test]
fn missing_files_and_unknown_extensions_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nowhere.obj");
    match load_mesh(&missing) {
        Err(Error::Read { path, source }) => {
            assert_eq!(path, missing);
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("{other:?}"),
    }
    let stl = write(dir.path(), "model.stl", "solid x\n");
    let message = load_mesh(&stl).unwrap_err().to_string();
    assert!(message.contains("model.stl"), "{message}");
    for extension in [".obj", ".gltf", ".glb"] {
        assert!(message.contains(extension), "{message}");
    }
    // Extensions are case-insensitive; a directory is not a mesh.
    let upper = write(dir.path(), "CUBE.OBJ", CUBE);
    assert_eq!(load_mesh(&upper).unwrap().triangle_count(), 12);
    let folder = dir.path().join("folder.obj");
    std::fs::create_dir(&folder).unwrap();
    let message = load_mesh(&folder).unwrap_err().to_string();
    assert!(
        message.contains("folder.obj") && message.contains("not a regular file"),
        "{message}"
    );
}
