//! `shikki mesh`: every built-in, written as OBJ and as GLB by the binary, loads back through
//! shikki's own mesh loader to the same triangles, and each file holds the mesh bit for bit.
//! Bad requests fail with a message naming what is valid, and leave no file behind.
//!
//! Tolerances: the files have none. OBJ numbers are the shortest decimal that parses back to the
//! same f32 and GLB holds the f32 bytes, so both files are compared with the mesh bit for bit.
//! What the loader returns: positions equal as f32 values, exactly (its glTF node transform,
//! the identity here applied in f64, turns −0 into +0, the same number). Normals within
//! [`NORMAL_ROUNDING`]: the loader renormalises each file normal in f64 and rounds it back to
//! f32 (once for OBJ; twice for glTF, in the node transform and in the clean-up), and each
//! rounding of an already unit vector can move a component by one f32 ulp.

use std::path::Path;
use std::process::{Command, Output};

use glam::DVec3;
use shikki::raster::mesh::{BuiltinMesh, Mesh, BUILTIN_SEGMENTS};
use shikki::raster::mesh_io::load_mesh_with_report;

fn shikki(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shikki"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the shikki binary runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs `shikki mesh ARGS…` and loads the file it wrote, checking the loader changed nothing.
fn export_and_load(dir: &Path, args: &[&str], file: &str) -> Mesh {
    let mut full = vec!["mesh"];
    full.extend_from_slice(args);
    full.extend_from_slice(&["-o", file]);
    let out = shikki(dir, &full);
    assert!(out.status.success(), "{full:?} failed: {}", stderr(&out));
    let (mesh, report) = load_mesh_with_report(&dir.join(file)).unwrap();
    assert!(
        report.notes().is_empty(),
        "{file}: the loader changed the mesh: {:?}",
        report.notes()
    );
    mesh
}

/// Two f32 ulps at 1 (2·2⁻²³): the loader's two renormalisations of a unit normal, one ulp each
/// at most, components being at most 1 in magnitude.
const NORMAL_ROUNDING: f64 = 2.0 * f32::EPSILON as f64;

fn v(p: [f32; 3]) -> DVec3 {
    DVec3::from_array(p.map(f64::from))
}

fn bits(v: [f32; 3]) -> [u32; 3] {
    v.map(f32::to_bits)
}

/// Same vertex count, and triangle by triangle (in order, corner by corner, so the winding too)
/// the same positions and normals. The loader renumbers vertices in first-use order, so corners
/// are compared through each mesh's own indices.
fn assert_same_triangles(loaded: &Mesh, expected: &Mesh, what: &str) {
    assert_eq!(loaded.triangle_count(), expected.triangle_count(), "{what}");
    assert_eq!(loaded.positions.len(), expected.positions.len(), "{what}");
    for (t, (a, b)) in loaded
        .indices
        .iter()
        .zip(&expected.indices)
        .enumerate()
        .map(|(k, pair)| (k / 3, pair))
    {
        let (a, b) = (*a as usize, *b as usize);
        assert_eq!(
            loaded.positions[a], expected.positions[b],
            "{what}: triangle {t} position"
        );
        let difference = (v(loaded.normals[a]) - v(expected.normals[b])).abs();
        assert!(
            difference.max_element() <= NORMAL_ROUNDING,
            "{what}: triangle {t} normal {:?} vs {:?}",
            loaded.normals[a],
            expected.normals[b]
        );
    }
}

#[test]
fn every_builtin_exports_to_obj_and_glb_and_loads_back_to_the_same_triangles() {
    let dir = tempfile::tempdir().unwrap();
    for builtin in BuiltinMesh::ALL {
        let expected = builtin.mesh();
        for extension in ["obj", "glb"] {
            let file = format!("{}.{extension}", builtin.name());
            let loaded = export_and_load(dir.path(), &[&builtin.spec()], &file);
            assert_same_triangles(&loaded, &expected, &file);
        }
    }
}

#[test]
fn segments_choose_the_tessellation_and_load_back() {
    let dir = tempfile::tempdir().unwrap();
    let coarsest = BUILTIN_SEGMENTS.start().to_string();
    for builtin in BuiltinMesh::ALL {
        if builtin.default_segments().is_none() {
            continue;
        }
        for segments in [coarsest.as_str(), "12"] {
            let expected = builtin
                .mesh_with_segments(segments.parse().unwrap())
                .unwrap();
            assert_ne!(expected, builtin.mesh());
            for extension in ["obj", "glb"] {
                let file = format!("{}-{segments}.{extension}", builtin.name());
                let loaded = export_and_load(
                    dir.path(),
                    &[&builtin.spec(), "--segments", segments],
                    &file,
                );
                assert_same_triangles(&loaded, &expected, &file);
            }
        }
    }
}

/// The OBJ text parsed here, independently of tobj: `v`, `vn` and `f a//a b//b c//c` lines.
fn parse_obj(text: &str) -> Mesh {
    let mut mesh = Mesh {
        positions: Vec::new(),
        normals: Vec::new(),
        indices: Vec::new(),
    };
    let triple = |words: &[&str]| -> [f32; 3] {
        assert_eq!(words.len(), 3, "{words:?}");
        [0, 1, 2].map(|k| words[k].parse::<f32>().unwrap())
    };
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.first().copied() {
            Some("v") => mesh.positions.push(triple(&words[1..])),
            Some("vn") => mesh.normals.push(triple(&words[1..])),
            Some("f") => {
                assert_eq!(words.len(), 4, "{line}");
                for corner in &words[1..] {
                    let (v, vn) = corner.split_once("//").unwrap();
                    assert_eq!(v, vn, "{line}: the normal index is the vertex index");
                    mesh.indices.push(v.parse::<u32>().unwrap() - 1);
                }
            }
            Some("o") | None => {}
            Some(word) => assert!(word.starts_with('#'), "unexpected line {line:?}"),
        }
    }
    mesh
}

#[test]
fn the_obj_file_holds_every_f32_exactly() {
    let dir = tempfile::tempdir().unwrap();
    for builtin in BuiltinMesh::ALL {
        let file = format!("{}.obj", builtin.name());
        let out = shikki(dir.path(), &["mesh", &builtin.spec(), "-o", &file]);
        assert!(out.status.success(), "{}", stderr(&out));
        let text = std::fs::read_to_string(dir.path().join(&file)).unwrap();
        // Exponent notation is left out: some OBJ readers do not take it.
        let mut numbers = text.lines().filter(|l| l.starts_with('v'));
        assert!(numbers.all(|l| !l[2..].contains('e')), "{file}");
        let parsed = parse_obj(&text);
        let expected = builtin.mesh();
        assert_eq!(parsed.indices, expected.indices, "{file}");
        assert_eq!(
            parsed
                .positions
                .iter()
                .map(|p| bits(*p))
                .collect::<Vec<_>>(),
            expected
                .positions
                .iter()
                .map(|p| bits(*p))
                .collect::<Vec<_>>(),
            "{file}"
        );
        assert_eq!(
            parsed.normals.iter().map(|n| bits(*n)).collect::<Vec<_>>(),
            expected
                .normals
                .iter()
                .map(|n| bits(*n))
                .collect::<Vec<_>>(),
            "{file}"
        );
    }
}

fn word(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap())
}

/// The GLB container read here, independently of the gltf crate: (JSON, BIN), with every
/// length and alignment rule of glTF 2.0 §4.4 checked.
fn split_glb(bytes: &[u8]) -> (serde_json::Value, &[u8]) {
    assert_eq!(&bytes[..4], b"glTF");
    assert_eq!(word(bytes, 4), 2, "GLB version");
    assert_eq!(word(bytes, 8) as usize, bytes.len(), "header length");
    let json_length = word(bytes, 12) as usize;
    assert_eq!(word(bytes, 16), 0x4E4F_534A, "first chunk is JSON");
    assert_eq!(json_length % 4, 0, "JSON chunk padded to 4 bytes");
    let bin_at = 20 + json_length;
    let bin_length = word(bytes, bin_at) as usize;
    assert_eq!(word(bytes, bin_at + 4), 0x004E_4942, "second chunk is BIN");
    assert_eq!(bin_length % 4, 0, "BIN chunk padded to 4 bytes");
    assert_eq!(bin_at + 8 + bin_length, bytes.len(), "nothing after BIN");
    let json = serde_json::from_slice(&bytes[20..bin_at]).unwrap();
    (json, &bytes[bin_at + 8..])
}

/// Accessor `index`'s bytes, checking it is tightly packed in an aligned, targeted view.
fn accessor_bytes<'b>(
    json: &serde_json::Value,
    bin: &'b [u8],
    index: u64,
    component_type: u64,
    kind: &str,
    target: u64,
) -> &'b [u8] {
    let accessor = &json["accessors"][index as usize];
    assert_eq!(accessor["componentType"], component_type);
    assert_eq!(accessor["type"], kind);
    assert_eq!(
        accessor
            .get("byteOffset")
            .map_or(0, |o| o.as_u64().unwrap()),
        0
    );
    let view = &json["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
    assert_eq!(view["buffer"], 0);
    assert_eq!(view["target"], target);
    assert!(view.get("byteStride").is_none());
    let offset = view["byteOffset"].as_u64().unwrap() as usize;
    let length = view["byteLength"].as_u64().unwrap() as usize;
    assert_eq!(offset % 4, 0);
    let components = match kind {
        "VEC3" => 3,
        _ => 1,
    };
    assert_eq!(
        length,
        4 * components * accessor["count"].as_u64().unwrap() as usize
    );
    &bin[offset..offset + length]
}

fn vec3s(bytes: &[u8]) -> Vec<[f32; 3]> {
    bytes
        .chunks_exact(12)
        .map(|c| [0, 4, 8].map(|k| f32::from_le_bytes(c[k..k + 4].try_into().unwrap())))
        .collect()
}

#[test]
fn the_glb_file_is_valid_gltf_and_holds_the_mesh_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    for builtin in BuiltinMesh::ALL {
        let file = format!("{}.glb", builtin.name());
        let out = shikki(dir.path(), &["mesh", &builtin.spec(), "-o", &file]);
        assert!(out.status.success(), "{}", stderr(&out));
        let bytes = std::fs::read(dir.path().join(&file)).unwrap();
        let (json, bin) = split_glb(&bytes);
        assert_eq!(json["asset"]["version"], "2.0");
        assert_eq!(
            json["buffers"][0]["byteLength"].as_u64(),
            Some(bin.len() as u64)
        );
        assert!(
            json["buffers"][0].get("uri").is_none(),
            "GLB uses its BIN chunk"
        );
        let primitive = &json["meshes"][0]["primitives"][0];
        assert_eq!(primitive["mode"], 4, "TRIANGLES");
        let id = |v: &serde_json::Value| v.as_u64().unwrap();
        let positions = vec3s(accessor_bytes(
            &json,
            bin,
            id(&primitive["attributes"]["POSITION"]),
            5126,
            "VEC3",
            34962,
        ));
        let normals = vec3s(accessor_bytes(
            &json,
            bin,
            id(&primitive["attributes"]["NORMAL"]),
            5126,
            "VEC3",
            34962,
        ));
        let indices: Vec<u32> =
            accessor_bytes(&json, bin, id(&primitive["indices"]), 5125, "SCALAR", 34963)
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
                .collect();

        let expected = builtin.mesh();
        assert_eq!(indices, expected.indices, "{file}");
        assert_eq!(
            positions.iter().map(|p| bits(*p)).collect::<Vec<_>>(),
            expected
                .positions
                .iter()
                .map(|p| bits(*p))
                .collect::<Vec<_>>(),
            "{file}"
        );
        assert_eq!(
            normals.iter().map(|n| bits(*n)).collect::<Vec<_>>(),
            expected
                .normals
                .iter()
                .map(|n| bits(*n))
                .collect::<Vec<_>>(),
            "{file}"
        );
        // POSITION's min and max are exactly the bounds of the f32 positions.
        let accessor = &json["accessors"][id(&primitive["attributes"]["POSITION"]) as usize];
        for k in 0..3 {
            let lo = positions.iter().map(|p| p[k]).fold(f32::INFINITY, f32::min);
            let hi = positions
                .iter()
                .map(|p| p[k])
                .fold(f32::NEG_INFINITY, f32::max);
            assert_eq!(
                accessor["min"][k].as_f64().unwrap() as f32,
                lo,
                "{file} min"
            );
            assert_eq!(
                accessor["max"][k].as_f64().unwrap() as f32,
                hi,
                "{file} max"
            );
        }
    }
}

/// Runs a failing `shikki mesh` and checks: exit 1, stderr names every `expected` fragment.
fn assert_fails(dir: &Path, args: &[&str], expected: &[&str]) {
    let mut full = vec!["mesh"];
    full.extend_from_slice(args);
    let out = shikki(dir, &full);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{full:?}: {err}");
    for fragment in expected {
        assert!(
            err.contains(fragment),
            "{full:?}: stderr lacks {fragment:?}:\n{err}"
        );
    }
}

#[test]
fn bad_requests_name_what_is_valid_and_leave_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let every_builtin: Vec<String> = BuiltinMesh::ALL.map(BuiltinMesh::spec).to_vec();
    let every: Vec<&str> = every_builtin.iter().map(String::as_str).collect();
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec!["builtin:bowl", "-o", "x.stl"],
            vec!["x.stl", ".obj, .glb"],
        ),
        (vec!["builtin:bowl", "-o", "x"], vec![".obj, .glb"]),
        (
            vec!["builtin:teapot", "-o", "x.obj"],
            [vec!["teapot"], every.clone()].concat(),
        ),
        // A built-in's name alone is the built-in (`bowl`); an unknown one lists them all.
        (vec!["cube", "-o", "x.obj"], every.clone()),
        (
            vec!["builtin:sphere", "--segments", "3", "-o", "x.obj"],
            vec!["segments = 3", "4..=2048"],
        ),
        (
            vec!["builtin:plate", "--segments", "2049", "-o", "x.glb"],
            vec!["segments = 2049", "4..=2048"],
        ),
        (
            vec!["builtin:board", "--segments", "16", "-o", "x.obj"],
            vec!["builtin:board", "no segments", "builtin:sphere"],
        ),
    ];
    for (args, expected) in &cases {
        assert_fails(dir.path(), args, expected);
        for leftover in ["x.stl", "x", "x.obj", "x.glb"] {
            assert!(
                !dir.path().join(leftover).exists(),
                "{args:?} left {leftover}"
            );
        }
    }
    assert!(
        std::fs::read_dir(dir.path()).unwrap().next().is_none(),
        "no temporary file is left either"
    );
}

#[test]
fn a_failed_export_removes_a_stale_file_but_not_one_it_could_not_have_written() {
    let dir = tempfile::tempdir().unwrap();
    // An earlier run's bowl.obj would pass for this run's output: removed, and said so.
    std::fs::write(dir.path().join("bowl.obj"), "stale").unwrap();
    assert_fails(
        dir.path(),
        &["builtin:bowl", "--segments", "1", "-o", "bowl.obj"],
        &["segments", "removed bowl.obj"],
    );
    assert!(!dir.path().join("bowl.obj").exists());
    // A file shikki never writes (wrong extension) is left alone.
    std::fs::write(dir.path().join("notes.txt"), "mine").unwrap();
    assert_fails(
        dir.path(),
        &["builtin:bowl", "-o", "notes.txt"],
        &[".obj, .glb"],
    );
    assert_eq!(
        std::fs::read_to_string(dir.path().join("notes.txt")).unwrap(),
        "mine"
    );
    // A successful export replaces an existing file, as `shikki render` does.
    std::fs::write(dir.path().join("board.glb"), "old").unwrap();
    let out = shikki(dir.path(), &["mesh", "builtin:board", "-o", "board.glb"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(std::fs::read(dir.path().join("board.glb"))
        .unwrap()
        .starts_with(b"glTF"));
}

#[test]
fn help_lists_every_builtin_and_the_segment_range() {
    let dir = tempfile::tempdir().unwrap();
    let out = shikki(dir.path(), &["mesh", "--help"]);
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for builtin in BuiltinMesh::ALL {
        assert!(help.contains(&builtin.spec()), "{help}");
    }
    assert!(help.contains("4..=2048") && help.contains(".glb"), "{help}");
    let top = String::from_utf8_lossy(&shikki(dir.path(), &["--help"]).stdout).into_owned();
    assert!(top.contains("mesh"), "{top}");
}
