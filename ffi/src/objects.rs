//! Environment and mesh handles: made from files or caller arrays, immutable afterwards.
//! The environment stays on the CPU here; each renderer prepares it on first use (the core's
//! `environment::prepare`, as for the CLI), since GPU images belong to one device.

use std::ffi::c_char;
use std::path::Path;
use std::sync::Arc;

use shikki::environment::gpu::{MIN_SOURCE_HEIGHT, MIN_SOURCE_WIDTH};
use shikki::environment::load::{MAX_PIXELS, MAX_SIDE};
use shikki::environment::{load_environment, Equirect, LoadedEnvironment};
use shikki::raster::mesh_io::{angle_weighted_normals, MAX_TRIANGLES, MAX_VERTICES};
use shikki::raster::{BuiltinMesh, Mesh};
use shikki::scene::parse::FileMesh;
use shikki::scene::MeshSource;

use crate::boundary::{c_str, check_out, ffi_boundary, slice, write_out, FfiError};
use crate::handles::{self, ShikkiEnvironment, ShikkiMesh};
use crate::status::ShikkiStatus;

/// An environment handle's object: the radiance map as loaded (with how many pixels were
/// replaced, which the renderer reports as a warning), shared with the scenes that use it.
pub type EnvironmentObject = Arc<LoadedEnvironment>;
/// A mesh handle's object, shared with the scenes that use it: a mesh in memory
/// (`MeshSource::Inline`) or a file loaded with what its loader changed (`MeshSource::Loaded`),
/// which the renders of a scene that uses it hand to the warning callback.
pub type MeshObject = MeshSource;

/// Loads an equirectangular radiance map (`.hdr` or `.exr`, or `builtin:studio`).
///
/// # Safety
/// `path` is a NUL-terminated UTF-8 string; `out` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_environment_load(
    path: *const c_char,
    out: *mut ShikkiEnvironment,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        // SAFETY: the caller's contract above.
        let path = unsafe { c_str(path, "path") }?;
        let loaded = load_environment(path)?;
        let handle = handles::insert::<ShikkiEnvironment, _>(Arc::new(loaded));
        // SAFETY: checked non-NULL; valid for one write by contract.
        unsafe { write_out(out, "out", handle) }
    })
}

/// Makes an environment from linear RGB radiance, `width × height` pixels, row 0 at the top
/// (+Y), 3 floats per pixel (SPEC §4 mapping). The data is copied. Limits (checked before `rgb`
/// is read): width 2 to 32768, height 1 to 32768 (at least 2 × 1 pixels, the smallest map the
/// renderer's prefilter takes), at most 2^28 pixels.
///
/// # Safety
/// `rgb` is valid for reads of `width * height * 3` floats; `out` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_environment_create_rgb(
    width: u32,
    height: u32,
    rgb: *const f32,
    out: *mut ShikkiEnvironment,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        // Checked against the file loader's limits before `rgb` is touched: a made-up size must
        // not send us reading gigabytes past the caller's array.
        // The least size is the prefilter's: refused here, or every render with this handle
        // would fail on it.
        let (w, h) = (width as usize, height as usize);
        let (min_w, min_h) = (MIN_SOURCE_WIDTH as usize, MIN_SOURCE_HEIGHT as usize);
        if !(min_w..=MAX_SIDE).contains(&w)
            || !(min_h..=MAX_SIDE).contains(&h)
            || w * h > MAX_PIXELS
        {
            return Err(FfiError::invalid(format!(
                "environment size {width}×{height}: the width must be {min_w} to {MAX_SIDE} \
                 pixels, the height {min_h} to {MAX_SIDE}, and the whole at most {MAX_PIXELS} \
                 pixels (2^28); downscale (or repeat) the map"
            )));
        }
        let count = w * h * 3;
        // SAFETY: the caller's contract above.
        let data = unsafe { slice(rgb, count, "rgb") }?;
        if let Some(i) = data.iter().position(|v| !v.is_finite() || *v < 0.0) {
            let pixel = i / 3;
            return Err(FfiError::invalid(format!(
                "environment pixel ({}, {}) has radiance {}: every value must be finite and ≥ 0",
                pixel % width as usize,
                pixel / width as usize,
                data[i]
            )));
        }
        let pixels = data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let loaded = LoadedEnvironment {
            image: Equirect {
                width,
                height,
                pixels,
            },
            replaced_pixels: 0,
            source: format!("the {width}×{height} environment from shikki_environment_create_rgb"),
        };
        let handle = handles::insert::<ShikkiEnvironment, _>(Arc::new(loaded));
        // SAFETY: checked non-NULL; valid for one write by contract.
        unsafe { write_out(out, "out", handle) }
    })
}

/// Destroys an environment. Scenes that use it keep their own reference. 0 is a no-op.
#[no_mangle]
pub extern "C" fn shikki_environment_destroy(environment: ShikkiEnvironment) -> ShikkiStatus {
    ffi_boundary!({ handles::remove(environment) })
}

/// Makes a mesh from caller arrays: `vertex_count` positions (xyz floats), normals (xyz floats,
/// or NULL to generate angle-weighted smooth normals), `index_count` u32 indices (a multiple of
/// 3, counter-clockwise seen from outside). The data is copied. Limits (checked before the arrays
/// are read): 1 to 150,000,000 vertices, 1 to 50,000,000 triangles.
///
/// # Safety
/// `positions` (and `normals` unless NULL) are valid for `vertex_count * 3` floats, `indices`
/// for `index_count` u32; `out` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_mesh_create(
    positions: *const f32,
    normals: *const f32,
    vertex_count: usize,
    indices: *const u32,
    index_count: usize,
    out: *mut ShikkiMesh,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        // The counts are checked against the mesh loader's limits before any array is read: a
        // made-up count must not send us reading past the caller's arrays.
        if vertex_count == 0 || vertex_count > MAX_VERTICES {
            return Err(FfiError::invalid(format!(
                "vertex_count {vertex_count}: must be 1 to {MAX_VERTICES}"
            )));
        }
        if index_count == 0 || index_count % 3 != 0 || index_count / 3 > MAX_TRIANGLES {
            return Err(FfiError::invalid(format!(
                "index_count {index_count}: must be a non-zero multiple of 3 (one triangle per 3 \
                 indices), at most {} ({MAX_TRIANGLES} triangles)",
                3 * MAX_TRIANGLES
            )));
        }
        let floats = vertex_count * 3;
        let triples = |data: &[f32]| data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        // SAFETY: the caller's contract above.
        let positions: Vec<[f32; 3]> = triples(unsafe { slice(positions, floats, "positions") }?);
        // SAFETY: the caller's contract above.
        let indices = unsafe { slice(indices, index_count, "indices") }?.to_vec();
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= vertex_count) {
            return Err(FfiError::invalid(format!(
                "index {bad} is out of range: there are {vertex_count} vertices"
            )));
        }
        let normals = if normals.is_null() {
            angle_weighted_normals(&positions, &indices)
        } else {
            // SAFETY: the caller's contract above.
            triples(unsafe { slice(normals, floats, "normals") }?)
        };
        let mesh = Mesh {
            positions,
            normals,
            indices,
        };
        mesh.validate()?;
        let handle = handles::insert::<ShikkiMesh, _>(MeshSource::Inline(Arc::new(mesh)));
        // SAFETY: checked non-NULL; valid for one write by contract.
        unsafe { write_out(out, "out", handle) }
    })
}

/// Loads a mesh file (OBJ, glTF/GLB; missing normals are generated). What the loader changed
/// (generated normals, degenerate triangles or point and line elements left out) is said by the
/// warning callback of each renderer that renders a scene with the mesh, once per file.
///
/// # Safety
/// `path` is a NUL-terminated UTF-8 string; `out` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_mesh_load(
    path: *const c_char,
    out: *mut ShikkiMesh,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        // SAFETY: the caller's contract above.
        let path = unsafe { c_str(path, "path") }?;
        let path = Path::new(path);
        let file = FileMesh::load(path)?;
        let handle = handles::insert::<ShikkiMesh, _>(MeshSource::Loaded {
            path: path.to_path_buf(),
            file,
        });
        // SAFETY: checked non-NULL; valid for one write by contract.
        unsafe { write_out(out, "out", handle) }
    })
}

/// A built-in mesh (SPEC §5): "sphere", "board", "bowl" or "plate" (a `builtin:` prefix is
/// accepted too).
///
/// # Safety
/// `name` is a NUL-terminated UTF-8 string; `out` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_mesh_create_builtin(
    name: *const c_char,
    out: *mut ShikkiMesh,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        // SAFETY: the caller's contract above.
        let name = unsafe { c_str(name, "name") }?;
        let mesh = BuiltinMesh::parse(name)?.mesh();
        let handle = handles::insert::<ShikkiMesh, _>(MeshSource::Inline(Arc::new(mesh)));
        // SAFETY: checked non-NULL; valid for one write by contract.
        unsafe { write_out(out, "out", handle) }
    })
}

/// The mesh's vertex and triangle counts (either pointer may be NULL).
///
/// # Safety
/// `vertex_count` and `triangle_count` are NULL or valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_mesh_counts(
    mesh: ShikkiMesh,
    vertex_count: *mut usize,
    triangle_count: *mut usize,
) -> ShikkiStatus {
    ffi_boundary!({
        // Every kind of mesh the C API makes is in memory: `load` only shares it.
        let mesh = handles::read::<_, MeshObject>(mesh)?.load()?;
        if !vertex_count.is_null() {
            // SAFETY: non-NULL and writable by contract.
            unsafe { write_out(vertex_count, "vertex_count", mesh.positions.len()) }?;
        }
        if !triangle_count.is_null() {
            // SAFETY: non-NULL and writable by contract.
            unsafe { write_out(triangle_count, "triangle_count", mesh.triangle_count()) }?;
        }
        Ok(())
    })
}

/// Destroys a mesh. Scenes that use it keep their own reference. 0 is a no-op.
#[no_mangle]
pub extern "C" fn shikki_mesh_destroy(mesh: ShikkiMesh) -> ShikkiStatus {
    ffi_boundary!({ handles::remove(mesh) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::last_error;

    #[test]
    fn create_rgb_refuses_maps_smaller_than_the_prefilter_takes() {
        let _turn = handles::test_table_turn();
        let pixels = [0.5_f32; 6];
        let mut environment = ShikkiEnvironment { id: 0 };
        for (width, height) in [(1, 1), (1, 2), (2, 0)] {
            // SAFETY: `pixels` holds width × height × 3 floats for each size tried (at most 6);
            // `environment` is valid for one write.
            let status = unsafe {
                shikki_environment_create_rgb(width, height, pixels.as_ptr(), &mut environment)
            };
            assert_eq!(status, ShikkiStatus::InvalidArgument, "{width}×{height}");
            let message = last_error();
            assert!(
                message.contains(&format!("environment size {width}×{height}"))
                    && message.contains("the width must be 2 to 32768 pixels, the height 1 to"),
                "{message}"
            );
            assert_eq!(environment.id, 0, "no handle is written on error");
        }
        // SAFETY: as above, 2 × 1 × 3 = 6 floats.
        let status =
            unsafe { shikki_environment_create_rgb(2, 1, pixels.as_ptr(), &mut environment) };
        assert_eq!(status, ShikkiStatus::Ok, "{}", last_error());
        assert_eq!(shikki_environment_destroy(environment), ShikkiStatus::Ok);
    }
}
