//! The loaders never panic: thousands of deterministic random corruptions of valid OBJ, glTF
//! and GLB files must each load or fail with an error.

use crate::common;

use std::path::Path;

use common::Rng;
use shikki::raster::mesh_io::load_mesh;

const OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvn 0 0 1\n\
                   f 1/1/1 2/1/1 3/1/1\nf 2//1 4//1 3//1\nf -1 -2 -3 1\nl 1 2\no x\n";

/// A valid glTF: one triangle with normals and u16 indices, a parent node with a TRS transform
/// and a child, all in an embedded buffer (AAAA… is the base64 of the 80 bytes below).
fn gltf_json(buffer_member: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{{buffer_member}"byteLength":80}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36,"byteStride":12}},{{"buffer":0,"byteOffset":72,"byteLength":8}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}},{{"bufferView":2,"componentType":5123,"count":3,"type":"SCALAR"}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"indices":2,"mode":4}}]}}],
"nodes":[{{"mesh":0,"translation":[1,2,3],"children":[1]}},{{"mesh":0,"scale":[2,2,2]}}],
"scenes":[{{"nodes":[0]}}],"scene":0}}"#
    )
}

fn buffer() -> Vec<u8> {
    let floats = [
        0.0f32, 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 1., 0., 0., 1.,
    ];
    let mut bytes: Vec<u8> = floats.iter().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend([0u8, 0, 1, 0, 2, 0, 0, 0]);
    bytes
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

/// Overwrites 1–4 random bytes with random values, or with digits/structural characters for
/// text (more likely to stay parseable and reach the deeper checks).
fn corrupt(rng: &mut Rng, original: &[u8], text: bool) -> Vec<u8> {
    let mut bytes = original.to_vec();
    let edits = 1 + rng.next_u64() % 4;
    for _ in 0..edits {
        let at = (rng.next_u64() % bytes.len() as u64) as usize;
        bytes[at] = if text {
            const SYMBOLS: &[u8] = b"0123456789-.e,:[]{}\" \nfvln/";
            SYMBOLS[(rng.next_u64() % SYMBOLS.len() as u64) as usize]
        } else {
            rng.next_u64() as u8
        };
    }
    if rng.next_u64() % 8 == 0 {
        let keep = (rng.next_u64() % bytes.len() as u64) as usize;
        bytes.truncate(keep);
    }
    bytes
}

fn survive(dir: &Path, name: &str, original: &[u8], text: bool, seed: u64, rounds: u32) -> u32 {
    let mut rng = Rng::new(seed);
    let path = dir.join(name);
    let mut loaded = 0;
    for _ in 0..rounds {
        std::fs::write(&path, corrupt(&mut rng, original, text)).unwrap();
        // The property is only that this returns; either outcome is fine.
        if let Ok(mesh) = load_mesh(&path) {
            mesh.validate().unwrap();
            loaded += 1;
        }
    }
    loaded
}

#[test]
fn corrupted_files_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    // The originals load.
    std::fs::write(dir.path().join("ok.obj"), OBJ).unwrap();
    assert!(load_mesh(&dir.path().join("ok.obj")).is_ok());
    let b64 = {
        const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        buffer()
            .chunks(3)
            .flat_map(|c| {
                let n = u32::from(c[0]) << 16
                    | u32::from(*c.get(1).unwrap_or(&0)) << 8
                    | u32::from(*c.get(2).unwrap_or(&0));
                (0..4).map(move |k| {
                    if k <= c.len() {
                        A[(n >> (18 - 6 * k) & 63) as usize] as char
                    } else {
                        '='
                    }
                })
            })
            .collect::<String>()
    };
    let gltf = gltf_json(&format!(
        r#""uri":"data:application/octet-stream;base64,{b64}","#
    ));
    std::fs::write(dir.path().join("ok.gltf"), &gltf).unwrap();
    assert_eq!(
        load_mesh(&dir.path().join("ok.gltf"))
            .unwrap()
            .triangle_count(),
        2
    );
    let binary = glb(&gltf_json(""), &buffer());
    std::fs::write(dir.path().join("ok.glb"), &binary).unwrap();
    assert_eq!(
        load_mesh(&dir.path().join("ok.glb"))
            .unwrap()
            .triangle_count(),
        2
    );

    let obj = survive(dir.path(), "f.obj", OBJ.as_bytes(), true, 1, 1500);
    let text = survive(dir.path(), "f.gltf", gltf.as_bytes(), true, 2, 1500);
    let bin = survive(dir.path(), "f.glb", &binary, false, 3, 1500);
    eprintln!("loaded after corruption: obj {obj}, gltf {text}, glb {bin} of 1500 each");
}

/// Every number in `text`, one at a time, replaced by each extreme value.
fn number_variants(text: &str) -> Vec<String> {
    const EXTREMES: [&str; 12] = [
        "0",
        "-1",
        "1",
        "3",
        "255",
        "65535",
        "4294967295",
        "4294967296",
        "18446744073709551615",
        "1e308",
        "-0.5",
        "1e-40",
    ];
    let bytes = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() && (i == 0 || !bytes[i - 1].is_ascii_alphanumeric()) {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_digit() || b".e".contains(&bytes[i])) {
                i += 1;
            }
            spans.push((start, i));
        } else {
            i += 1;
        }
    }
    let mut variants = Vec::new();
    for (start, end) in spans {
        for value in EXTREMES {
            variants.push(format!("{}{value}{}", &text[..start], &text[end..]));
        }
    }
    variants
}

#[test]
fn extreme_numbers_in_every_field_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    // External buffer, so the JSON's numbers are all structural.
    std::fs::write(dir.path().join("b.bin"), buffer()).unwrap();
    let gltf = gltf_json(r#""uri":"b.bin","#);
    let path = dir.path().join("n.gltf");
    let mut tried = 0;
    for variant in number_variants(&gltf) {
        std::fs::write(&path, &variant).unwrap();
        if let Ok(mesh) = load_mesh(&path) {
            mesh.validate().unwrap();
        }
        tried += 1;
    }
    let path = dir.path().join("n.obj");
    for variant in number_variants(OBJ) {
        std::fs::write(&path, &variant).unwrap();
        if let Ok(mesh) = load_mesh(&path) {
            mesh.validate().unwrap();
        }
        tried += 1;
    }
    // 12 values × every number of both files: hundreds of variants actually ran.
    assert!(tried > 500, "{tried}");
}
