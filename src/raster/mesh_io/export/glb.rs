//! The GLB encoder (glTF 2.0 §4.4): a 12-byte header, a JSON chunk padded with spaces and a BIN
//! chunk padded with zeros, both to 4 bytes.
//!
//! The BIN chunk holds three tightly packed, 4-byte-aligned blocks: positions (VEC3 float, with
//! the min/max the specification requires for POSITION), normals (VEC3 float) and indices
//! (SCALAR unsigned int), each in its own bufferView with its target (ARRAY_BUFFER for the
//! vertex attributes, ELEMENT_ARRAY_BUFFER for the indices). One scene with one node (identity
//! transform) draws the one mesh with one TRIANGLES primitive. The JSON is written with
//! serde_json; the `gltf` crate (built without its export feature here) only reads.

use serde_json::json;

use crate::raster::mesh::Mesh;
use crate::{Error, Result};

const GLB_MAGIC: &[u8; 4] = b"glTF";
const GLB_VERSION: u32 = 2;
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// glTF enumerations (the OpenGL constants the specification reuses).
const COMPONENT_FLOAT: u32 = 5126;
const COMPONENT_UNSIGNED_INT: u32 = 5125;
const TARGET_ARRAY_BUFFER: u32 = 34962;
const TARGET_ELEMENT_ARRAY_BUFFER: u32 = 34963;
const MODE_TRIANGLES: u32 = 4;

pub(super) fn encode(mesh: &Mesh, name: &str) -> Result<Vec<u8>> {
    let mut bin = Vec::with_capacity(24 * mesh.positions.len() + 4 * mesh.indices.len());
    for p in mesh.positions.iter().chain(&mesh.normals) {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in &mesh.indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let vertex_bytes = 12 * mesh.positions.len();
    let index_bytes = 4 * mesh.indices.len();
    let (min, max) = bounds(&mesh.positions);

    let document = json!({
        "asset": {
            "version": "2.0",
            "generator": concat!("shikki ", env!("CARGO_PKG_VERSION")),
        },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "name": name }],
        "meshes": [{
            "name": name,
            "primitives": [{
                "attributes": { "POSITION": 0, "NORMAL": 1 },
                "indices": 2,
                "mode": MODE_TRIANGLES,
            }],
        }],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": COMPONENT_FLOAT,
                "count": mesh.positions.len(),
                "type": "VEC3",
                "min": min,
                "max": max,
            },
            {
                "bufferView": 1,
                "componentType": COMPONENT_FLOAT,
                "count": mesh.normals.len(),
                "type": "VEC3",
            },
            {
                "bufferView": 2,
                "componentType": COMPONENT_UNSIGNED_INT,
                "count": mesh.indices.len(),
                "type": "SCALAR",
            },
        ],
        "bufferViews": [
            {
                "buffer": 0,
                "byteOffset": 0,
                "byteLength": vertex_bytes,
                "target": TARGET_ARRAY_BUFFER,
            },
            {
                "buffer": 0,
                "byteOffset": vertex_bytes,
                "byteLength": vertex_bytes,
                "target": TARGET_ARRAY_BUFFER,
            },
            {
                "buffer": 0,
                "byteOffset": 2 * vertex_bytes,
                "byteLength": index_bytes,
                "target": TARGET_ELEMENT_ARRAY_BUFFER,
            },
        ],
        "buffers": [{ "byteLength": bin.len() }],
    });
    let json = serde_json::to_vec(&document).map_err(|e| too_large(e.to_string()))?;
    container(json, bin)
}

/// Per-component min and max of the positions (the mesh is validated, so not empty).
fn bounds(positions: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let first = positions.first().copied().unwrap_or([0.0; 3]);
    positions
        .iter()
        .fold((first, first), |(mut lo, mut hi), p| {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            (lo, hi)
        })
}

/// Header + JSON chunk + BIN chunk, every chunk padded to a multiple of 4 bytes.
fn container(mut json: Vec<u8>, mut bin: Vec<u8>) -> Result<Vec<u8>> {
    // The JSON chunk is padded with spaces (trailing whitespace is still valid JSON), the BIN
    // chunk with zeros (§4.4.3.1).
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let length = |bytes: usize| {
        u32::try_from(bytes).map_err(|_| {
            too_large(format!(
                "{bytes} bytes do not fit GLB's 32-bit lengths; use fewer segments or .obj"
            ))
        })
    };
    let total = length(12 + 8 + json.len() + 8 + bin.len())?;
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&GLB_VERSION.to_le_bytes());
    out.extend_from_slice(&total.to_le_bytes());
    for (kind, chunk) in [(CHUNK_JSON, &json), (CHUNK_BIN, &bin)] {
        out.extend_from_slice(&length(chunk.len())?.to_le_bytes());
        out.extend_from_slice(&kind.to_le_bytes());
        out.extend_from_slice(chunk);
    }
    Ok(out)
}

fn too_large(reason: String) -> Error {
    Error::invalid("mesh", "GLB", reason)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn word(bytes: &[u8], at: usize) -> u32 {
        u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
    }

    #[test]
    fn the_container_is_aligned_and_its_lengths_add_up() {
        let glb = encode(&crate::raster::mesh::board(), "board").unwrap();
        assert_eq!(&glb[..4], b"glTF");
        assert_eq!(word(&glb, 4), 2);
        assert_eq!(word(&glb, 8) as usize, glb.len());
        let json_length = word(&glb, 12) as usize;
        assert_eq!(word(&glb, 16), CHUNK_JSON);
        assert_eq!(json_length % 4, 0);
        let bin_at = 20 + json_length;
        let bin_length = word(&glb, bin_at) as usize;
        assert_eq!(word(&glb, bin_at + 4), CHUNK_BIN);
        // 4 positions + 4 normals (12 bytes each) + 6 indices (4 bytes each).
        assert_eq!(bin_length, 4 * 12 * 2 + 6 * 4);
        assert_eq!(bin_at + 8 + bin_length, glb.len());

        let json: serde_json::Value = serde_json::from_slice(&glb[20..bin_at]).unwrap();
        let position = &json["accessors"][0];
        assert_eq!(position["min"], json!([-1.0, 0.0, -1.0]));
        assert_eq!(position["max"], json!([1.0, 0.0, 1.0]));
        let views = json["bufferViews"].as_array().unwrap();
        let targets: Vec<u64> = views
            .iter()
            .map(|v| v["target"].as_u64().unwrap())
            .collect();
        assert_eq!(targets, [34962, 34962, 34963]);
        for view in views {
            assert_eq!(view["byteOffset"].as_u64().unwrap() % 4, 0);
        }
        assert_eq!(json["buffers"][0]["byteLength"], json!(bin_length));
    }

    #[test]
    fn bounds_are_per_component() {
        let (lo, hi) = bounds(&[[1.0, -2.0, 3.0], [-1.0, 5.0, 0.5]]);
        assert_eq!((lo, hi), ([-1.0, -2.0, 0.5], [1.0, 5.0, 3.0]));
    }
}
