//! glTF 2.0 (`.gltf` with embedded base64 or external buffers, and `.glb`) through the `gltf`
//! crate.
//!
//! Walks the default scene (else the first scene, else every root node) applying node
//! transforms, and takes every triangle primitive of every mesh instance. The crate parses and
//! validates the JSON; `gltf_buffers` splits GLB and loads the buffers; this file reads the
//! accessors itself, with every offset, stride and count checked, because the crate's readers
//! assume well-formed data (they can overflow or assert on a hostile file). Owns nothing else;
//! the clean-up is `MeshBuilder`'s.
//!
//! Decisions the spec leaves open: POINTS and LINES* primitives are skipped with a note; strips
//! and fans become lists; a node whose transform is singular (scale 0, used to hide things) is
//! skipped with a note; sparse accessors, accessors without a buffer view and quantized
//! (non-float) positions/normals are errors; skins are ignored (bind pose, noted). Missing
//! normals are generated smooth across shared indices (the glTF spec asks for flat normals; a
//! non-indexed primitive shares nothing, so it does come out flat).

use std::path::Path;

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::{Mode, Semantic};
use ::gltf::{Accessor, Document, Gltf, Node, Primitive};
use glam::{DMat4, DVec3};

use super::{
    check_file_length, content_error, gltf_buffers, mirrors, reverse_winding, transform_normal,
    LoadReport, MeshBuilder, Part, MAX_TRIANGLES, MAX_VERTICES,
};
use crate::raster::mesh::Mesh;
use crate::{Error, Result};

/// How many of the crate's validation messages an error quotes.
const MAX_QUOTED_ERRORS: usize = 5;

/// One mesh drawn under one node.
struct Instance<'a> {
    mesh: ::gltf::Mesh<'a>,
    world: DMat4,
}

pub(super) fn load(path: &Path) -> Result<(Mesh, LoadReport)> {
    check_file_length(path).map_err(|message| content_error(path, message))?;
    let bytes = std::fs::read(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let (json, blob) = gltf_buffers::split_container(path, &bytes)?;
    let Gltf { document, .. } =
        Gltf::from_slice_without_validation(json).map_err(|e| crate_error(path, e))?;
    drop(bytes);
    check_position_references(path, document.as_json())?;
    let document = Document::from_json(document.into_json()).map_err(|e| crate_error(path, e))?;

    let mut builder = MeshBuilder::new(path);
    let instances = scene_instances(path, &document, &mut builder.report)?;
    check_limits(path, &instances)?;

    // Buffers only now: a file over the limits fails before its .bin is read.
    let buffers = gltf_buffers::load_buffers(path, &document, blob)?;
    let buffers: Vec<&[u8]> = buffers.iter().map(|b| &b[..]).collect();

    let mut skipped_modes = Vec::new();
    for instance in &instances {
        for primitive in instance.mesh.primitives() {
            let place = place(&instance.mesh, &primitive);
            if !matches!(
                primitive.mode(),
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                skipped_modes.push(format!("{place} ({:?})", primitive.mode()));
                continue;
            }
            let part = read_primitive(path, &place, &primitive, &buffers, instance.world)?;
            builder.add(part)?;
        }
    }
    skipped_modes.sort();
    skipped_modes.dedup();
    if !skipped_modes.is_empty() {
        builder.report.skipped.push(format!(
            "skipped {} point/line primitive(s): {}",
            skipped_modes.len(),
            skipped_modes.join(", ")
        ));
    }
    builder.finish()
}

/// gltf-json 1.4.1's validation indexes `accessors[POSITION]` before checking the index (and
/// panics on a dangling one), so those references are checked here first.
fn check_position_references(path: &Path, root: &::gltf::json::Root) -> Result<()> {
    use ::gltf::json::validation::Checked;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&Checked::Valid(Semantic::Positions));
            if let Some(index) = position.filter(|i| i.value() >= root.accessors.len()) {
                return Err(content_error(
                    path,
                    format!(
                        "invalid glTF: meshes[{m}].primitives[{p}].attributes.POSITION: accessor \
                         {} does not exist ({} accessors)",
                        index.value(),
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// "mesh 2 'Lid' primitive 0", the location every error names.
fn place(mesh: &::gltf::Mesh<'_>, primitive: &Primitive<'_>) -> String {
    match mesh.name() {
        Some(name) => format!(
            "mesh {} '{name}' primitive {}",
            mesh.index(),
            primitive.index()
        ),
        None => format!("mesh {} primitive {}", mesh.index(), primitive.index()),
    }
}

/// Every mesh under the chosen scene with its node's world matrix (parent · local, in f64).
fn scene_instances<'a>(
    path: &Path,
    document: &'a Document,
    report: &mut LoadReport,
) -> Result<Vec<Instance<'a>>> {
    let roots: Vec<Node<'a>> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; document.nodes().len()];
            for node in document.nodes() {
                for child in node.children() {
                    is_child[child.index()] = true;
                }
            }
            report
                .skipped
                .push("the file has no scene: drew every root node".to_string());
            document.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };

    let mut visited = vec![false; document.nodes().len()];
    let mut stack: Vec<(Node<'a>, DMat4)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DMat4::IDENTITY))
        .collect();
    let mut instances = Vec::new();
    let mut singular = Vec::new();
    let mut skinned = 0;
    while let Some((node, parent)) = stack.pop() {
        // An explicit stack and a visited flag: a cyclic file must fail, not overflow the stack.
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(content_error(
                path,
                format!(
                    "node {} is reached twice from the scene (a cycle, or a node with two \
                     parents); glTF node hierarchies must be trees",
                    node.index()
                ),
            ));
        }
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if !world.is_finite() {
            return Err(content_error(
                path,
                format!("node {}'s transform is not finite", node.index()),
            ));
        }
        let determinant = world
            .x_axis
            .truncate()
            .dot(world.y_axis.truncate().cross(world.z_axis.truncate()));
        if determinant == 0.0 {
            singular.push(node.index().to_string());
            continue;
        }
        if let Some(mesh) = node.mesh() {
            skinned += usize::from(node.skin().is_some());
            instances.push(Instance { mesh, world });
        }
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world));
        }
    }
    if !singular.is_empty() {
        report.skipped.push(format!(
            "skipped node(s) {} and their children: singular (zero-scale) transform",
            singular.join(", ")
        ));
    }
    if skinned > 0 {
        report.skipped.push(format!(
            "{skinned} skinned mesh instance(s) drawn in the bind pose (skins are not applied)"
        ));
    }
    Ok(instances)
}

/// Triangles and vertices from the declared accessor counts, before anything is read.
fn check_limits(path: &Path, instances: &[Instance<'_>]) -> Result<()> {
    let (mut triangles, mut vertices) = (0usize, 0usize);
    for instance in instances {
        for primitive in instance.mesh.primitives() {
            let place = place(&instance.mesh, &primitive);
            let Some(positions) = primitive.get(&Semantic::Positions) else {
                return Err(content_error(
                    path,
                    format!("{place} has no POSITION attribute"),
                ));
            };
            let (n, listed) = match primitive.indices() {
                Some(indices) => (indices.count(), "indices"),
                None => (positions.count(), "vertices (no indices)"),
            };
            let count = match primitive.mode() {
                Mode::Triangles if n % 3 != 0 => {
                    return Err(content_error(
                        path,
                        format!("{place}: {n} {listed} in TRIANGLES mode is not a multiple of 3"),
                    ))
                }
                Mode::Triangles => n / 3,
                Mode::TriangleStrip | Mode::TriangleFan => n.saturating_sub(2),
                _ => continue,
            };
            triangles = triangles.saturating_add(count);
            vertices = vertices.saturating_add(positions.count());
        }
    }
    if triangles > MAX_TRIANGLES {
        return Err(content_error(
            path,
            format!(
                "declares {triangles} triangles, more than shikki's limit of {MAX_TRIANGLES} for \
                 one mesh; split or decimate it"
            ),
        ));
    }
    if vertices > MAX_VERTICES {
        return Err(content_error(
            path,
            format!(
                "declares {vertices} vertices, more than shikki's limit of {MAX_VERTICES} for \
                 one mesh; split or decimate it"
            ),
        ));
    }
    Ok(())
}

/// One triangle primitive in world space.
fn read_primitive(
    path: &Path,
    place: &str,
    primitive: &Primitive<'_>,
    buffers: &[&[u8]],
    world: DMat4,
) -> Result<Part> {
    let fail = |message: String| content_error(path, format!("{place}: {message}"));
    let positions_accessor = primitive
        .get(&Semantic::Positions)
        .ok_or_else(|| fail("no POSITION attribute".to_string()))?;
    let positions = read_vec3(&positions_accessor, buffers, "POSITION").map_err(&fail)?;
    if let Some(i) = positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(fail(format!(
            "POSITION {i} = {:?} is not finite; every coordinate must be a finite number",
            positions[i]
        )));
    }
    let normals = match primitive.get(&Semantic::Normals) {
        Some(accessor) => {
            let normals = read_vec3(&accessor, buffers, "NORMAL").map_err(&fail)?;
            if normals.len() != positions.len() {
                return Err(fail(format!(
                    "{} NORMALs for {} POSITIONs; every attribute needs one value per vertex",
                    normals.len(),
                    positions.len()
                )));
            }
            Some(normals)
        }
        None => None,
    };
    let vertex_list = match primitive.indices() {
        Some(accessor) => read_indices(&accessor, buffers).map_err(&fail)?,
        None => (0..positions.len() as u32).collect(),
    };
    if let Some((k, &index)) = vertex_list
        .iter()
        .enumerate()
        .find(|(_, &i)| i as usize >= positions.len())
    {
        return Err(fail(format!(
            "index {k} is {index}, out of range for {} vertices",
            positions.len()
        )));
    }
    let mut indices = triangle_list(primitive.mode(), &vertex_list);

    let positions = positions
        .iter()
        .map(|&p| {
            let p = world.transform_point3(DVec3::new(
                f64::from(p[0]),
                f64::from(p[1]),
                f64::from(p[2]),
            ));
            [p.x as f32, p.y as f32, p.z as f32]
        })
        .collect::<Vec<_>>();
    if positions.iter().flatten().any(|c| !c.is_finite()) {
        return Err(fail("a transformed position overflows f32".to_string()));
    }
    let normals = normals.map(|n| n.iter().map(|&n| transform_normal(&world, n)).collect());
    if mirrors(&world) {
        reverse_winding(&mut indices);
    }
    Ok(Part {
        positions,
        normals,
        indices,
    })
}

/// The glTF 2.0 §3.7.2.1 primitive topologies as a triangle list (vertex_list already in range).
fn triangle_list(mode: Mode, v: &[u32]) -> Vec<u32> {
    let n = v.len();
    match mode {
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .flat_map(|i| [v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]])
            .collect(),
        Mode::TriangleFan => (0..n.saturating_sub(2))
            .flat_map(|i| [v[i + 1], v[i + 2], v[0]])
            .collect(),
        _ => v.to_vec(),
    }
}

/// The bytes of an accessor's elements: (view bytes, first element offset, stride, count),
/// with every range checked so that element k lies at `start + k·stride .. + size` inside the view.
fn accessor_layout<'b>(
    accessor: &Accessor<'_>,
    buffers: &[&'b [u8]],
    element_size: usize,
) -> std::result::Result<(&'b [u8], usize, usize, usize), String> {
    let index = accessor.index();
    if accessor.sparse().is_some() {
        return Err(format!(
            "accessor {index} is sparse, which shikki does not read; export without sparse accessors"
        ));
    }
    let Some(view) = accessor.view() else {
        return Err(format!(
            "accessor {index} has no bufferView (all zeros), which shikki does not read"
        ));
    };
    let count = accessor.count();
    if count == 0 {
        return Err(format!("accessor {index} has count 0"));
    }
    let stride = view.stride().unwrap_or(element_size);
    if stride < element_size {
        return Err(format!(
            "bufferView {}'s byteStride {stride} is smaller than accessor {index}'s element size {element_size}",
            view.index()
        ));
    }
    let buffer_index = view.buffer().index();
    let data = buffers
        .get(buffer_index)
        .ok_or_else(|| format!("buffer {buffer_index} was not loaded"))?;
    let view_bytes = view
        .offset()
        .checked_add(view.length())
        .and_then(|end| data.get(view.offset()..end))
        .ok_or_else(|| {
            format!(
                "bufferView {} (bytes {}+{}) lies outside buffer {buffer_index} ({} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                data.len()
            )
        })?;
    let start = accessor.offset();
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|last| last.checked_add(start))
        .and_then(|last| last.checked_add(element_size));
    match end {
        Some(end) if end <= view_bytes.len() => Ok((view_bytes, start, stride, count)),
        _ => Err(format!(
            "accessor {index} ({count} elements, stride {stride}, offset {start}) runs past the \
             end of bufferView {} ({} bytes)",
            view.index(),
            view_bytes.len()
        )),
    }
}

fn read_vec3(
    accessor: &Accessor<'_>,
    buffers: &[&[u8]],
    semantic: &str,
) -> std::result::Result<Vec<[f32; 3]>, String> {
    if accessor.dimensions() != Dimensions::Vec3 || accessor.data_type() != DataType::F32 {
        return Err(format!(
            "{semantic} accessor {} is {:?} of {:?}; shikki reads VEC3 of FLOAT only \
             (quantized meshes, KHR_mesh_quantization, are not supported)",
            accessor.index(),
            accessor.dimensions(),
            accessor.data_type()
        ));
    }
    let (bytes, start, stride, count) = accessor_layout(accessor, buffers, 12)?;
    Ok((0..count)
        .map(|k| {
            let at = start + k * stride;
            [0, 4, 8].map(|o| f32::from_le_bytes(le_bytes(&bytes[at + o..at + o + 4])))
        })
        .collect())
}

fn read_indices(
    accessor: &Accessor<'_>,
    buffers: &[&[u8]],
) -> std::result::Result<Vec<u32>, String> {
    let size = match (accessor.dimensions(), accessor.data_type()) {
        (Dimensions::Scalar, DataType::U8) => 1,
        (Dimensions::Scalar, DataType::U16) => 2,
        (Dimensions::Scalar, DataType::U32) => 4,
        (dimensions, data_type) => {
            return Err(format!(
                "index accessor {} is {dimensions:?} of {data_type:?}; indices must be SCALAR \
                 UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
                accessor.index()
            ))
        }
    };
    let (bytes, start, stride, count) = accessor_layout(accessor, buffers, size)?;
    Ok((0..count)
        .map(|k| {
            let at = start + k * stride;
            match size {
                1 => u32::from(bytes[at]),
                2 => u32::from(u16::from_le_bytes([bytes[at], bytes[at + 1]])),
                _ => u32::from_le_bytes(le_bytes(&bytes[at..at + 4])),
            }
        })
        .collect())
}

/// Four bytes as an array; `accessor_layout` guarantees the slice has them.
fn le_bytes(slice: &[u8]) -> [u8; 4] {
    let mut out = [0; 4];
    out.copy_from_slice(slice);
    out
}

/// The crate's parse and validation errors, with the JSON line where there is one.
fn crate_error(path: &Path, error: ::gltf::Error) -> Error {
    match error {
        ::gltf::Error::Deserialize(e) if e.line() > 0 => Error::parse(
            path.display().to_string(),
            e.line(),
            format!("column {}: not valid glTF JSON: {e}", e.column()),
        ),
        ::gltf::Error::Validation(errors) => {
            let quoted: Vec<String> = errors
                .iter()
                .take(MAX_QUOTED_ERRORS)
                .map(|(at, what)| format!("{at}: {what}"))
                .collect();
            let more = errors.len().saturating_sub(MAX_QUOTED_ERRORS);
            let tail = if more > 0 {
                format!(" (and {more} more)")
            } else {
                String::new()
            };
            // An extension the file requires is not an invalid file: say what to do about it.
            let unsupported = errors
                .iter()
                .any(|(_, what)| matches!(what, ::gltf::json::validation::Error::Unsupported));
            let hint = match unsupported {
                true => {
                    "; shikki reads core glTF 2.0: re-export without the extension (for \
                     KHR_mesh_quantization: `gltf-transform dequantize in.glb out.glb`)"
                }
                false => "",
            };
            content_error(
                path,
                format!("invalid glTF: {}{tail}{hint}", quoted.join("; ")),
            )
        }
        other => content_error(path, format!("not a readable glTF/GLB file: {other}")),
    }
}
