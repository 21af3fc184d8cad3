//! Scenes from the core's scene description (`shikki::scene`): scene TOML text or files and the
//! default scene. The core `Scene` names its meshes and environment by source; here they are
//! loaded once into the handle's `SceneState`, so a render needs no file access.

use std::collections::HashMap;
use std::ffi::c_char;
use std::path::Path;
use std::sync::Arc;

use shikki::environment::load_environment;
use shikki::raster::mesh_io::load_mesh;
use shikki::raster::Mesh;
use shikki::scene::{self, EnvironmentSpec, MeshSource, Scene};

use crate::boundary::{c_str, check_out, ffi_boundary, opt_c_str, write_out, FfiResult};
use crate::handles::{self, ShikkiScene};
use crate::scene::{EnvironmentState, ObjectState, SceneState};
use crate::status::ShikkiStatus;

/// Loads every mesh and the environment a core scene names.
pub fn scene_state(scene: Scene) -> FfiResult<SceneState> {
    let mut builtins: HashMap<String, Arc<Mesh>> = HashMap::new();
    let mut objects = Vec::with_capacity(scene.objects.len());
    for object in scene.objects {
        let mesh = match object.mesh {
            MeshSource::Builtin(builtin) => Arc::clone(
                builtins
                    .entry(format!("{builtin:?}"))
                    .or_insert_with(|| Arc::new(builtin.mesh())),
            ),
            MeshSource::File(path) => Arc::new(load_mesh(&path)?),
            MeshSource::Inline(mesh) => mesh,
        };
        objects.push(ObjectState {
            mesh,
            transform: object.transform,
            material: object.material,
        });
    }
    let environment = match scene.environment {
        EnvironmentSpec::None => None,
        EnvironmentSpec::Map {
            source,
            intensity,
            rotation_deg,
        } => Some(EnvironmentState {
            image: Arc::new(load_environment(&source)?.image),
            intensity,
            rotation_deg,
        }),
    };
    let output = scene.output;
    Ok(SceneState {
        objects,
        lights: scene.lights,
        camera: scene.camera,
        environment,
        background: output.background,
        width: output.width,
        height: output.height,
        samples: output.samples,
        exposure_ev: output.exposure_ev,
        tone_curve: output.tone_curve,
    })
}

fn make(scene: Scene, out: *mut ShikkiScene) -> FfiResult {
    let handle = handles::insert::<ShikkiScene, _>(scene_state(scene)?);
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
