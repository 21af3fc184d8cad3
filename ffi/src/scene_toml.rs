//! Scenes from the core's scene description (`shikki::scene`): scene TOML text or files and the
//! default scene. The scene is kept as the core built it, except that the mesh files and the
//! environment map it names are loaded once, here, so a render needs no file access and a bad
//! file is reported by the call that named it.

use std::ffi::c_char;
use std::path::Path;
use std::sync::Arc;

use shikki::environment::{load_environment, EnvironmentSource};
use shikki::scene::parse::FileMesh;
use shikki::scene::{self, EnvironmentSpec, MeshSource, Scene};

use crate::boundary::{c_str, check_out, ffi_boundary, opt_c_str, write_out, FfiResult};
use crate::handles::{self, ShikkiScene};
use crate::status::ShikkiStatus;

/// `scene` with every file it names loaded into memory (built-in meshes stay built-in; a mesh
/// file keeps its path and what its loader changed, which its renders report).
pub fn loaded_scene(mut scene: Scene) -> FfiResult<Scene> {
    for object in &mut scene.objects {
        if let MeshSource::File(path) = &object.mesh {
            let file = FileMesh::load(path)?;
            object.mesh = MeshSource::Loaded {
                path: path.clone(),
                file,
            };
        }
    }
    if let EnvironmentSpec::Map { source, .. } = &mut scene.environment {
        if let EnvironmentSource::Named(name) = source {
            *source = EnvironmentSource::Loaded(Arc::new(load_environment(name)?));
        }
    }
    Ok(scene)
}

fn make(scene: Scene, out: *mut ShikkiScene) -> FfiResult {
    let handle = handles::insert::<ShikkiScene, _>(loaded_scene(scene)?);
    // SAFETY: every caller checked `out` with check_out and the C contract makes it writable.
    unsafe { write_out(out, "out", handle) }
}

/// shikki's default scene (`examples/default.toml`: a red and a black smooth lacquer bowl on the
/// built-in studio environment, 1024×1024, 4 samples) — the same as the CLI's.
///
/// # Safety
/// `out` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_create_default(out: *mut ShikkiScene) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        make(scene::default_scene(), out)
    })
}

/// A scene from scene TOML text (the scene-file format). `base_dir` (may be NULL: the current
/// directory) resolves relative mesh, environment and Fresnel paths.
///
/// # Safety
/// `toml` and `base_dir` (unless NULL) are NUL-terminated UTF-8 strings; `out` is valid for one
/// write.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_create_toml(
    toml: *const c_char,
    base_dir: *const c_char,
    out: *mut ShikkiScene,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        // SAFETY: the caller's contract above.
        let text = unsafe { c_str(toml, "toml") }?;
        // SAFETY: the caller's contract above.
        let base = unsafe { opt_c_str(base_dir, "base_dir") }?.unwrap_or(".");
        make(
            scene::parse_scene_str(text, "<toml string>", Path::new(base))?,
            out,
        )
    })
}

/// A scene from a scene TOML file; relative paths resolve against its directory.
///
/// # Safety
/// `path` is a NUL-terminated UTF-8 string; `out` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_load(
    path: *const c_char,
    out: *mut ShikkiScene,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        // SAFETY: the caller's contract above.
        let path = unsafe { c_str(path, "path") }?;
        make(scene::load_scene_file(Path::new(path))?, out)
    })
}
