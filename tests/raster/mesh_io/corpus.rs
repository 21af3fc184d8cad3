//! Bad-input corpus, meshes (tests/common/corpus.md lists every case): truncated and corrupted
//! OBJ, glTF and GLB; out-of-range indices, degenerate triangles, NaN positions, zero triangles,
//! accessor counts of 2^31 and files far larger than any limit. Each case asserts the exact error
//! kind and that the message names the file, the place (OBJ line, glTF mesh/primitive/accessor)
//! and what is valid; the CLI cases render a scene naming the mesh and must exit 1 with nothing
//! written. Random corruption of valid files is tests/raster/mesh_io/fuzz.rs and tests/raster/mesh_io/properties.rs.

use crate::common::corpus as support;

use std::path::Path;
use std::time::Duration;

use shikki::raster::mesh_io::{load_mesh, MAX_MESH_FILE_BYTES, MAX_TRIANGLES, MAX_VERTICES};
use shikki::Error;
use support::*;

const HEADER_ONLY: Duration = Duration::from_secs(2);

/// The message of a mesh content error: `Error::Read` of `path` with an InvalidData cause.
fn content_error(result: shikki::Result<impl std::fmt::Debug>, path: &Path) -> String {
    let message = expect_read(result, path);
    assert!(message.contains(&path.display().to_string()), "{message}");
    message
}

/// `shikki render scene.toml -o out/r.png` with the scene's one object reading `mesh`: exit 1,
/// stderr names the scene line and every fragment, nothing in out/.
fn cli_refuses(ws: &Workspace, mesh: &str, fragments: &[&str]) {
    ws.file(
        "scene.toml",
        format!("[output]\nsize = \"16x16\"\n\n[[object]]\nmesh = \"{mesh}\"\n"),
    );
    let mut expected = vec!["scene.toml:5"];
    expected.extend_from_slice(fragments);
    assert_cli_fails(ws, &["render", "scene.toml", "-o", "out/r.png"], &expected);
}

// ---- OBJ ------------------------------------------------------------------------------------

#[test]
fn empty_obj_contains_no_triangles() {
    let ws = Workspace::new();
    let path = ws.file("empty.obj", b"");
    let message = content_error(load_mesh(&path), &path);
    assert_names(&message, &["contains no triangles"]);
    cli_refuses(&ws, "empty.obj", &["empty.obj", "contains no triangles"]);
}

#[test]
fn obj_with_vertices_but_no_faces_contains_no_triangles() {
    let ws = Workspace::new();
    let path = ws.file(
        "points.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1\nl 1 2\nf 1 2\n",
    );
    let message = content_error(load_mesh(&path), &path);
    assert_names(&message, &["contains no triangles", "skipped 3 point/line"]);
}

#[test]
fn obj_with_only_degenerate_triangles_names_the_dropped_count() {
    let ws = Workspace::new();
    // A repeated vertex, collinear points and a zero-area sliver.
    let path = ws.file(
        "degenerate.obj",
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 1 2\nf 1 2 3\nf 3 2 1\n",
    );
    let message = content_error(load_mesh(&path), &path);
    assert_names(
        &message,
        &["contains no triangles", "dropped 3 degenerate (zero-area)"],
    );
    cli_refuses(&ws, "degenerate.obj", &["dropped 3 degenerate"]);
}

#[test]
fn obj_degenerate_triangles_next_to_good_ones_are_dropped_not_fatal() {
    let ws = Workspace::new();
    let path = ws.file(
        "mixed.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n",
    );
    let (mesh, report) = shikki::raster::mesh_io::load_mesh_with_report(&path).unwrap();
    assert_eq!(mesh.triangle_count(), 1);
    assert_eq!(report.degenerate_triangles_dropped, 1);
}

#[test]
fn obj_truncated_mid_line_names_the_line() {
    let ws = Workspace::new();
    let path = ws.file("cut.obj", "v 0 0 0\nv 1 0 0\nv 0 1");
    let message = expect_parse(load_mesh(&path), "cut.obj", 3);
    assert_names(
        &message,
        &["a vertex needs three numbers: v x y z", "\"0 1\""],
    );
    cli_refuses(&ws, "cut.obj", &["cut.obj:3", "three numbers"]);
}

#[test]
fn obj_out_of_range_indices_name_the_line_and_the_valid_range() {
    let ws = Workspace::new();
    for (name, face, found) in [
        ("past_end.obj", "f 1 2 9", "vertex index 9 is out of range"),
        ("zero.obj", "f 0 1 2", "vertex index 0 is out of range"),
        ("back.obj", "f -1 -2 -4", "vertex index -4 is out of range"),
        (
            "normal.obj",
            "f 1//2 2//1 3//1",
            "normal index 2 is out of range",
        ),
        (
            "texcoord.obj",
            "f 1/5 2/1 3/1",
            "texture coordinate index 5",
        ),
    ] {
        let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n{face}\n");
        let path = ws.file(name, text);
        let message = expect_parse(load_mesh(&path), name, 6);
        assert_names(&message, &[found]);
    }
    let message = expect_parse(load_mesh(&ws.path().join("past_end.obj")), "past_end", 6);
    assert_names(&message, &["3 vertex(s) are defined", "indices are 1..=3"]);
    cli_refuses(&ws, "past_end.obj", &["past_end.obj:6", "out of range"]);
}

#[test]
fn obj_index_beyond_i64_is_not_an_integer() {
    let ws = Workspace::new();
    let path = ws.file(
        "huge_index.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n",
    );
    let message = expect_parse(load_mesh(&path), "huge_index.obj", 4);
    assert_names(
        &message,
        &["vertex index \"99999999999999999999999\" is not an integer"],
    );
}

#[test]
fn obj_nan_and_infinite_positions_name_the_vertex() {
    let ws = Workspace::new();
    for (name, vertex) in [
        ("nan.obj", "v nan 0 0"),
        ("inf.obj", "v inf 0 0"),
        ("overflow.obj", "v 1e39 0 0"),
        ("w_zero.obj", "v 1 1 1 0"),
    ] {
        let path = ws.file(name, format!("v 0 0 0\nv 1 0 0\n{vertex}\nf 1 2 3\n"));
        let message = expect_parse(load_mesh(&path), name, 3);
        assert_names(&message, &["vertex 3", "is not finite", "finite number"]);
    }
    cli_refuses(&ws, "nan.obj", &["nan.obj:3", "not finite"]);
}

#[test]
fn obj_binary_garbage_is_not_utf8_at_line_1() {
    let ws = Workspace::new();
    let path = ws.file("binary.obj", [0xFFu8, 0xFE, 0x00, 0x80, b'\n', b'v']);
    let message = expect_parse(load_mesh(&path), "binary.obj", 1);
    assert_names(&message, &["not valid UTF-8"]);
}

#[test]
fn obj_of_a_terabyte_without_line_ends_is_refused_at_the_line_limit() {
    let ws = Workspace::new();
    // A sparse 1 TiB file of zero bytes: one "line" longer than 1 MiB, refused after reading it.
    let path = ws.path().join("zeros.obj");
    sparse_file(&path, b"", 1 << 40);
    let message = quickly("zeros.obj", HEADER_ONLY, || {
        expect_parse(load_mesh(&path), "zeros.obj", 1)
    });
    assert_names(&message, &["longer than 1048576 bytes", "OBJ text file"]);
}

#[test]
fn unknown_extension_directory_and_missing_file() {
    let ws = Workspace::new();
    let path = ws.file("mesh.stl", b"solid x\n");
    let message = expect_invalid(load_mesh(&path), "mesh");
    assert_names(&message, &["mesh.stl", ".obj, .gltf, .glb"]);
    std::fs::create_dir(ws.path().join("dir.obj")).unwrap();
    let dir = ws.path().join("dir.obj");
    assert_names(
        &content_error(load_mesh(&dir), &dir),
        &["not a regular file"],
    );
    let missing = ws.path().join("missing.glb");
    assert_names(
        &expect_read(load_mesh(&missing), &missing),
        &["no such file"],
    );
    cli_refuses(&ws, "missing.glb", &["missing.glb"]);
}

// ---- glTF / GLB -----------------------------------------------------------------------------

/// RFC 4648 base64 with padding.
fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// The knobs of a one-primitive glTF: positions (f32 VEC3) and u32 indices in one buffer.
struct Gltf {
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
    /// Overrides the declared accessor counts (positions, indices).
    counts: Option<(u64, u64)>,
    mode: u32,
    /// Overrides the buffer's byteLength.
    byte_length: Option<u64>,
}

impl Gltf {
    fn triangle() -> Self {
        Gltf {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            indices: vec![0, 1, 2],
            counts: None,
            mode: 4,
            byte_length: None,
        }
    }

    fn buffer(&self) -> Vec<u8> {
        let mut bytes: Vec<u8> = self
            .positions
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        bytes.extend(self.indices.iter().flat_map(|i| i.to_le_bytes()));
        bytes
    }

    /// The JSON with `buffer_member` ("uri": …, or nothing for a GLB's BIN chunk).
    fn json(&self, buffer_member: &str) -> String {
        let positions_bytes = self.positions.len() * 12;
        let indices_bytes = self.indices.len() * 4;
        let (np, ni) = self
            .counts
            .unwrap_or((self.positions.len() as u64, self.indices.len() as u64));
        let length = self
            .byte_length
            .unwrap_or((positions_bytes + indices_bytes) as u64);
        format!(
            r#"{{"asset":{{"version":"2.0"}},
"buffers":[{{{buffer_member}"byteLength":{length}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{positions_bytes}}},
{{"buffer":0,"byteOffset":{positions_bytes},"byteLength":{indices_bytes}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{np},"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5125,"count":{ni},"type":"SCALAR"}}],
"meshes":[{{"name":"Lid","primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":{}}}]}}],
"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#,
            self.mode
        )
    }

    fn embedded(&self) -> String {
        self.json(&format!(
            r#""uri":"data:application/octet-stream;base64,{}","#,
            base64(&self.buffer())
        ))
    }

    fn glb(&self) -> Vec<u8> {
        glb(self.json("").as_bytes(), &self.buffer())
    }
}

fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut json = json.to_vec();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    for word in [2, total as u32, json.len() as u32, 0x4E4F_534A] {
        out.extend(word.to_le_bytes());
    }
    out.extend(json);
    for word in [bin.len() as u32, 0x004E_4942] {
        out.extend(word.to_le_bytes());
    }
    out.extend(bin);
    out
}

#[test]
fn valid_gltf_and_glb_load_so_the_corpus_cases_fail_for_their_own_reason() {
    let ws = Workspace::new();
    let gltf = Gltf::triangle();
    for (name, bytes) in [
        ("ok.gltf", gltf.embedded().into_bytes()),
        ("ok.glb", gltf.glb()),
    ] {
        let path = ws.file(name, bytes);
        assert_eq!(load_mesh(&path).unwrap().triangle_count(), 1, "{name}");
    }
}

#[test]
fn empty_gltf_and_glb_are_clear_errors() {
    let ws = Workspace::new();
    for name in ["empty.gltf", "empty.glb"] {
        let path = ws.file(name, b"");
        match load_mesh(&path) {
            Err(Error::Parse {
                file,
                line,
                message,
            }) => {
                assert!(file.contains(name) && line >= 1, "{file}:{line}");
                assert_names(&message, &["not valid glTF JSON"]);
            }
            other => {
                let message = content_error(other, &path);
                assert_names(&message, &["glTF"]);
            }
        }
    }
    cli_refuses(&ws, "empty.gltf", &["empty.gltf"]);
}

#[test]
fn gltf_truncated_json_names_the_line_and_column() {
    let ws = Workspace::new();
    let text = Gltf::triangle().embedded();
    // Cut inside the "meshes" line (line 7 of the JSON).
    let cut = text.find("\"meshes\"").unwrap() + 20;
    let path = ws.file("cut.gltf", &text[..cut]);
    let message = expect_parse(load_mesh(&path), "cut.gltf", 7);
    assert_names(&message, &["column", "not valid glTF JSON"]);
    cli_refuses(&ws, "cut.gltf", &["cut.gltf:7", "not valid glTF JSON"]);
}

#[test]
fn gltf_accessor_count_of_2_pow_31_is_refused_before_reading_buffers() {
    let ws = Workspace::new();
    // 2^31 − 2 indices (a multiple of 3): 715 827 882 triangles declared over 12 real bytes.
    let mut gltf = Gltf::triangle();
    gltf.counts = Some((3, (1 << 31) - 2));
    let path = ws.file("count.gltf", gltf.embedded());
    let message = quickly("count.gltf", HEADER_ONLY, || {
        content_error(load_mesh(&path), &path)
    });
    assert_names(
        &message,
        &[
            "declares 715827882 triangles",
            &format!("limit of {MAX_TRIANGLES}"),
            "split or decimate",
        ],
    );
    // 2^31 positions: the vertex limit.
    gltf.counts = Some((1 << 31, 3));
    let path = ws.file("vertices.glb", gltf.glb());
    let message = quickly("vertices.glb", HEADER_ONLY, || {
        content_error(load_mesh(&path), &path)
    });
    assert_names(
        &message,
        &["declares 2147483648 vertices", &format!("{MAX_VERTICES}")],
    );
    // A count of 2^31 itself is not a multiple of 3 in TRIANGLES mode.
    gltf.counts = Some((3, 1 << 31));
    let path = ws.file("odd.gltf", gltf.embedded());
    let message = content_error(load_mesh(&path), &path);
    assert_names(
        &message,
        &[
            "mesh 0 'Lid' primitive 0",
            "2147483648 indices",
            "not a multiple of 3",
        ],
    );
    // Under the limits but past the real data: refused by the range check, not allocated.
    gltf.counts = Some((3, 3_000_000));
    let path = ws.file("short.gltf", gltf.embedded());
    let message = quickly("short.gltf", HEADER_ONLY, || {
        content_error(load_mesh(&path), &path)
    });
    assert_names(
        &message,
        &[
            "accessor 1 (3000000 elements",
            "runs past the end of bufferView 1",
        ],
    );
    ws.file("count2.glb", {
        let mut g = Gltf::triangle();
        g.counts = Some((3, (1 << 31) - 2));
        g.glb()
    });
    let args = ["render", "scene.toml", "-o", "out/r.png"];
    ws.file(
        "scene.toml",
        "[output]\nsize = \"16x16\"\n\n[[object]]\nmesh = \"count2.glb\"\n",
    );
    let out = shikki_limited(ws.path(), &args, 512 * 1024);
    check_failure(&ws, &args, &out, &["scene.toml:5", "715827882 triangles"]);
}

#[test]
fn gltf_out_of_range_index_names_the_primitive_and_index() {
    let ws = Workspace::new();
    let mut gltf = Gltf::triangle();
    gltf.indices = vec![0, 1, 7];
    let path = ws.file("index.gltf", gltf.embedded());
    let message = content_error(load_mesh(&path), &path);
    assert_names(
        &message,
        &[
            "mesh 0 'Lid' primitive 0",
            "index 2 is 7",
            "out of range for 3 vertices",
        ],
    );
    gltf.indices = vec![0, 1, u32::MAX];
    let path = ws.file("index.glb", gltf.glb());
    let message = content_error(load_mesh(&path), &path);
    assert_names(&message, &["index 2 is 4294967295"]);
    cli_refuses(&ws, "index.gltf", &["index 2 is 7"]);
}

#[test]
fn gltf_nan_position_names_the_vertex() {
    let ws = Workspace::new();
    let mut gltf = Gltf::triangle();
    gltf.positions[1] = [f32::NAN, 0.0, 0.0];
    let path = ws.file("nan.glb", gltf.glb());
    let message = content_error(load_mesh(&path), &path);
    assert_names(
        &message,
        &["mesh 0 'Lid' primitive 0", "POSITION 1", "is not finite"],
    );
    gltf.positions[1] = [1.0, f32::INFINITY, 0.0];
    let path = ws.file("inf.gltf", gltf.embedded());
    assert_names(
        &content_error(load_mesh(&path), &path),
        &["POSITION 1", "not finite"],
    );
    cli_refuses(&ws, "nan.glb", &["POSITION 1", "not finite"]);
}

#[test]
fn gltf_with_only_degenerate_or_point_primitives_contains_no_triangles() {
    let ws = Workspace::new();
    let mut gltf = Gltf::triangle();
    gltf.positions[2] = [2.0, 0.0, 0.0]; // collinear
    let path = ws.file("flat.gltf", gltf.embedded());
    let message = content_error(load_mesh(&path), &path);
    assert_names(&message, &["contains no triangles", "dropped 1 degenerate"]);
    let mut gltf = Gltf::triangle();
    gltf.mode = 0; // POINTS
    let path = ws.file("points.glb", gltf.glb());
    let message = content_error(load_mesh(&path), &path);
    assert_names(
        &message,
        &["contains no triangles", "point/line primitive", "Points"],
    );
}

#[test]
fn gltf_buffer_problems_name_the_buffer() {
    let ws = Workspace::new();
    let gltf = Gltf::triangle();
    // External buffer missing.
    let path = ws.file("missing_bin.gltf", gltf.json(r#""uri":"nothere.bin","#));
    assert_names(
        &content_error(load_mesh(&path), &path),
        &["buffer 0", "cannot read", "nothere.bin"],
    );
    // byteLength larger than the data.
    let mut long = Gltf::triangle();
    long.byte_length = Some(1 << 40);
    let path = ws.file("long.gltf", long.embedded());
    assert_names(
        &content_error(load_mesh(&path), &path),
        &["buffer 0", "byteLength is 1099511627776 but only 48 bytes"],
    );
    // A remote URI and a bad base64 character.
    let path = ws.file(
        "remote.gltf",
        gltf.json(r#""uri":"https://example.com/b.bin","#),
    );
    assert_names(
        &content_error(load_mesh(&path), &path),
        &["scheme", "file next to the glTF"],
    );
    let path = ws.file(
        "b64.gltf",
        gltf.json(r#""uri":"data:application/octet-stream;base64,AAAA!AAA","#),
    );
    assert_names(
        &content_error(load_mesh(&path), &path),
        &["invalid character '!'"],
    );
    // A dangling POSITION accessor (the crate would panic on it).
    let text = gltf
        .embedded()
        .replace(r#""POSITION":0"#, r#""POSITION":99"#);
    let path = ws.file("dangling.gltf", text);
    assert_names(
        &content_error(load_mesh(&path), &path),
        &["POSITION", "accessor 99 does not exist"],
    );
}

#[test]
fn glb_container_corruption_is_refused_with_the_reason() {
    let ws = Workspace::new();
    let bytes = Gltf::triangle().glb();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "short.glb",
            bytes[..10].to_vec(),
            "12-byte header is cut short",
        ),
        ("cut.glb", bytes[..bytes.len() - 8].to_vec(), "declares"),
        (
            "version.glb",
            [&b"glTF\x01\0\0\0"[..], &bytes[8..]].concat(),
            "version 1",
        ),
        (
            "huge_length.glb",
            {
                let mut b = bytes.clone();
                b[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
                b
            },
            "declares 4294967295 bytes",
        ),
        (
            "chunk.glb",
            {
                let mut b = bytes.clone();
                b[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
                b
            },
            "runs past the end",
        ),
    ];
    for (name, bytes, fragment) in cases {
        let path = ws.file(name, bytes);
        let message = content_error(load_mesh(&path), &path);
        assert_names(&message, &["not a valid GLB file", fragment]);
    }
    cli_refuses(&ws, "chunk.glb", &["not a valid GLB file"]);
}

#[test]
fn mesh_file_larger_than_the_limit_is_refused_before_reading() {
    let ws = Workspace::new();
    for name in ["terabyte.glb", "terabyte.gltf"] {
        let path = ws.path().join(name);
        sparse_file(&path, b"glTF\x02\0\0\0", 1 << 40);
        let message = quickly(name, HEADER_ONLY, || content_error(load_mesh(&path), &path));
        assert_names(
            &message,
            &[&format!("{MAX_MESH_FILE_BYTES}"), "split or decimate"],
        );
    }
    // An external buffer of a terabyte, named by a small .gltf.
    let gltf = Gltf::triangle();
    sparse_file(&ws.path().join("big.bin"), &gltf.buffer(), 1 << 40);
    let path = ws.file("external.gltf", gltf.json(r#""uri":"big.bin","#));
    let message = quickly("external.gltf", HEADER_ONLY, || {
        content_error(load_mesh(&path), &path)
    });
    assert_names(
        &message,
        &["buffer 0", "big.bin", &format!("{MAX_MESH_FILE_BYTES}")],
    );
    cli_refuses(&ws, "terabyte.glb", &["terabyte.glb"]);
}

/// An extension the file requires (KHR_mesh_quantization here) gets the fix, not only the
/// crate's "Unsupported extension" (a probe, 2026-12-06).
#[test]
fn a_required_gltf_extension_names_the_fix() {
    let ws = Workspace::new();
    let text = Gltf::triangle().embedded();
    let required = text.replacen(
        '{',
        r#"{"extensionsUsed":["KHR_mesh_quantization"],"extensionsRequired":["KHR_mesh_quantization"],"#,
        1,
    );
    let path = ws.file("quantized.gltf", required);
    let message = content_error(load_mesh(&path), &path);
    assert_names(
        &message,
        &["KHR_mesh_quantization", "re-export without the extension"],
    );
}
