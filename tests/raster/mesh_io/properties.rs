//! Property tests of the mesh loaders (OBJ, glTF, GLB): near-valid OBJ text built line by line,
//! glTF documents whose every structural number (counts, offsets, strides, lengths, component
//! types, modes, indices) is drawn at random, and byte mutations of valid files. Each returns a
//! mesh that passes `Mesh::validate` or a well-formed error; never a panic or a hang.
//! tests/raster/mesh_io/fuzz.rs keeps its fixed-seed corruption rounds; these add shrinking and structure.

use crate::common::prop as prop_support;

use std::path::PathBuf;
use std::sync::OnceLock;

use prop_support::*;
use proptest::prelude::*;
use shikki::raster::mesh_io::load_mesh;

fn dir() -> &'static tempfile::TempDir {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| tempfile::tempdir().expect("temp dir"))
}

/// Writes `bytes` as `name` (cases run one at a time per property; names are per property) and
/// checks the load.
fn check(name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    let path: PathBuf = dir().path().join(name);
    std::fs::write(&path, bytes).expect("write case");
    let result = within("load_mesh", move || load_mesh(&path));
    well_formed(&result)?;
    if let Ok(mesh) = &result {
        prop_assert!(mesh.validate().is_ok(), "{:?}", mesh.validate());
        prop_assert!(mesh.triangle_count() >= 1);
        prop_assert!(mesh.positions.iter().flatten().all(|c| c.is_finite()));
    }
    Ok(())
}

// ---- OBJ ------------------------------------------------------------------------------------

const OBJ_LINES: &[&str] = &[
    "v 0 0 0",
    "v 1 0 0",
    "v 0 1 0",
    "v 1 1 1",
    "v 0 0 1 2",
    "v 1 2 3 0.5 0.5 0.5",
    "v nan 0 0",
    "v 1e39 0 0",
    "v 1 1 1 0",
    "v 1 2",
    "vn 0 0 1",
    "vn 0 0 0",
    "vn nan 1 0",
    "vt 0 0",
    "vt 0.5 1 0",
    "f 1 2 3",
    "f 1 2 3 4",
    "f 1 2 3 4 5 6 7 8",
    "f -1 -2 -3",
    "f 1/1 2/1 3/1",
    "f 1//1 2//1 3//1",
    "f 1/1/1 2/1/1 3/1/1",
    "f 1//1 2 3",
    "f 1 1 1",
    "f 0 1 2",
    "f 99 1 2",
    "f 1 2",
    "f",
    "f 1/2/3/4 2 3",
    "f /1 2 3",
    "l 1 2",
    "p 1",
    "o part",
    "g group",
    "s 1",
    "usemtl red",
    "mtllib red.mtl",
    "# comment",
    "",
    "\t  ",
];

/// `v`/`vn` with random number text and `f` with random indices.
fn obj_generated_line() -> impl Strategy<Value = String> {
    prop_oneof![
        (number_text(), number_text(), number_text())
            .prop_map(|(x, y, z)| format!("v {x} {y} {z}")),
        (number_text(), number_text(), number_text())
            .prop_map(|(x, y, z)| format!("vn {x} {y} {z}")),
        prop::collection::vec(-6i64..12, 0..6).prop_map(|ix| {
            let corners: Vec<String> = ix.iter().map(i64::to_string).collect();
            format!("f {}", corners.join(" "))
        }),
        prop::collection::vec((-4i64..6, -4i64..6), 3..5).prop_map(|ix| {
            let corners: Vec<String> = ix.iter().map(|(v, n)| format!("{v}//{n}")).collect();
            format!("f {}", corners.join(" "))
        }),
    ]
}

fn obj_text() -> impl Strategy<Value = String> {
    let line = prop_oneof![
        3 => prop::sample::select(OBJ_LINES).prop_map(str::to_string),
        2 => obj_generated_line(),
        1 => "[ -~]{0,20}",
    ];
    prop::collection::vec(line, 0..40).prop_map(|lines| lines.join("\n"))
}

const VALID_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvn 0 0 1\n\
                         f 1/1/1 2/1/1 3/1/1\nf 2//1 4//1 3//1\nf -1 -2 -3 1\nl 1 2\no x\n";

// ---- glTF -----------------------------------------------------------------------------------

/// 3 positions (36 bytes) then 3 u16 indices (6 bytes) + 2 padding.
fn buffer() -> Vec<u8> {
    let floats = [0.0f32, 0., 0., 1., 0., 0., 0., 1., 0.];
    let mut bytes: Vec<u8> = floats.iter().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend([0u8, 0, 1, 0, 2, 0, 0, 0]);
    bytes
}

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
            out.push(if k <= chunk.len() {
                A[(n >> (18 - 6 * k) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    out
}

/// The structural numbers of a one-primitive glTF, each drawn at random.
#[derive(Clone, Debug)]
struct GltfKnobs {
    byte_length: u64,
    view_offset: [u64; 2],
    view_length: [u64; 2],
    stride: Option<u64>,
    accessor_offset: [u64; 2],
    count: [u64; 2],
    component_type: [u32; 2],
    kind: [&'static str; 2],
    mode: u32,
    position: u32,
    indices: Option<u32>,
    translation: [f64; 3],
    scale: [f64; 3],
}

fn interesting_u64() -> impl Strategy<Value = u64> {
    prop_oneof![
        0u64..100,
        prop::sample::select(
            &[
                0u64,
                1,
                2,
                3,
                4,
                12,
                36,
                40,
                44,
                255,
                65535,
                1 << 31,
                (1 << 31) - 2,
                1 << 32,
                u64::MAX >> 12
            ][..]
        ),
    ]
}

fn gltf_knobs() -> impl Strategy<Value = GltfKnobs> {
    let pair = || [interesting_u64(), interesting_u64()];
    let types = prop::sample::select(&[5120u32, 5121, 5122, 5123, 5125, 5126, 0, 9999][..]);
    let kinds = prop::sample::select(&["SCALAR", "VEC2", "VEC3", "VEC4", "MAT4", "X"][..]);
    let float = prop_oneof![-4.0..4.0f64, Just(0.0), Just(1e300), Just(-1e-300)];
    (
        (
            interesting_u64(),
            pair(),
            pair(),
            prop::option::of(interesting_u64()),
            pair(),
            pair(),
        ),
        (
            [types.clone(), types],
            [kinds.clone(), kinds],
            0u32..8,
            0u32..4,
            prop::option::of(0u32..4),
            [float.clone(), float.clone(), float.clone()],
            [float.clone(), float.clone(), float],
        ),
    )
        .prop_map(
            |(
                (byte_length, view_offset, view_length, stride, accessor_offset, count),
                (component_type, kind, mode, position, indices, translation, scale),
            )| GltfKnobs {
                byte_length,
                view_offset,
                view_length,
                stride,
                accessor_offset,
                count,
                component_type,
                kind,
                mode,
                position,
                indices,
                translation,
                scale,
            },
        )
}

fn gltf_json(k: &GltfKnobs, buffer_member: &str) -> String {
    let stride = k
        .stride
        .map_or(String::new(), |s| format!(r#","byteStride":{s}"#));
    let indices = k
        .indices
        .map_or(String::new(), |i| format!(r#","indices":{i}"#));
    format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{{buffer_member}"byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":{},"byteLength":{}{stride}}},{{"buffer":0,"byteOffset":{},"byteLength":{}}}],
"accessors":[{{"bufferView":0,"byteOffset":{},"componentType":{},"count":{},"type":"{}","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"byteOffset":{},"componentType":{},"count":{},"type":"{}"}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":{}}}{indices},"mode":{}}}]}}],
"nodes":[{{"mesh":0,"translation":[{},{},{}],"scale":[{},{},{}]}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#,
        k.byte_length,
        k.view_offset[0],
        k.view_length[0],
        k.view_offset[1],
        k.view_length[1],
        k.accessor_offset[0],
        k.component_type[0],
        k.count[0],
        k.kind[0],
        k.accessor_offset[1],
        k.component_type[1],
        k.count[1],
        k.kind[1],
        k.position,
        k.mode,
        k.translation[0],
        k.translation[1],
        k.translation[2],
        k.scale[0],
        k.scale[1],
        k.scale[2],
    )
}

fn valid_knobs() -> GltfKnobs {
    GltfKnobs {
        byte_length: 44,
        view_offset: [0, 36],
        view_length: [36, 6],
        stride: None,
        accessor_offset: [0, 0],
        count: [3, 3],
        component_type: [5126, 5123],
        kind: ["VEC3", "SCALAR"],
        mode: 4,
        position: 0,
        indices: Some(1),
        translation: [0.0; 3],
        scale: [1.0; 3],
    }
}

fn embedded(k: &GltfKnobs) -> String {
    gltf_json(
        k,
        &format!(
            r#""uri":"data:application/octet-stream;base64,{}","#,
            base64(&buffer())
        ),
    )
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while json.len() % 4 != 0 {
        json.push(b' ');
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
fn the_originals_load() {
    let d = dir().path();
    std::fs::write(d.join("v.obj"), VALID_OBJ).unwrap();
    assert_eq!(load_mesh(&d.join("v.obj")).unwrap().triangle_count(), 4);
    std::fs::write(d.join("v.gltf"), embedded(&valid_knobs())).unwrap();
    assert_eq!(load_mesh(&d.join("v.gltf")).unwrap().triangle_count(), 1);
    std::fs::write(
        d.join("v.glb"),
        glb(&gltf_json(&valid_knobs(), ""), &buffer()),
    )
    .unwrap();
    assert_eq!(load_mesh(&d.join("v.glb")).unwrap().triangle_count(), 1);
}

proptest! {
    #![proptest_config(config(1024))]

    #[test]
    fn obj_near_valid_text(text in obj_text()) {
        check("near.obj", text.as_bytes())?;
    }

    #[test]
    fn obj_mutations_of_a_valid_file(edits in mutations()) {
        check("mutated.obj", &apply(VALID_OBJ.as_bytes(), &edits))?;
    }

    #[test]
    fn obj_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        check("bytes.obj", &bytes)?;
    }

    #[test]
    fn gltf_with_random_structural_numbers(knobs in gltf_knobs()) {
        check("knobs.gltf", embedded(&knobs).as_bytes())?;
        check("knobs.glb", &glb(&gltf_json(&knobs, ""), &buffer()))?;
    }

    #[test]
    fn gltf_mutations_of_a_valid_file(edits in mutations()) {
        check("mutated.gltf", &apply(embedded(&valid_knobs()).as_bytes(), &edits))?;
    }

    #[test]
    fn glb_mutations_of_a_valid_file(edits in mutations()) {
        let original = glb(&gltf_json(&valid_knobs(), ""), &buffer());
        check("mutated.glb", &apply(&original, &edits))?;
    }

    #[test]
    fn glb_arbitrary_bytes_after_the_magic(bytes in prop::collection::vec(any::<u8>(), 0..256)) {
        let mut file = b"glTF\x02\0\0\0".to_vec();
        file.extend(bytes);
        check("bytes.glb", &file)?;
    }
}
