//! Scene handles: what one picture shows (objects with transforms and materials, lights, camera,
//! environment, background), how light is computed (the environment model) and how it is output
//! (size, samples, exposure, tone curve). Built with calls here, or from scene TOML
//! (`scene_toml.rs`). A scene handle holds a `shikki::scene::Scene`, the value the CLI and scene
//! files build too, so the renderer cannot tell where a scene came from. It holds its own
//! references to meshes and environments and its own copy of each material, so those handles may
//! be destroyed once added.

use glam::{DMat4, DVec3};
use shikki::environment::{EnvironmentLight, EnvironmentSource};
use shikki::error::{show_number, show_numbers};
use shikki::model::limits;
use shikki::model::LacquerMaterial;
use shikki::output::ToneCurve;
use shikki::raster::draw::{Background, MAX_BOUNCES, MAX_RAYS, SUPPORTED_SAMPLES};
use shikki::raster::{default_lights, Camera, Light, MAX_LIGHTS};
use shikki::scene::{EnvironmentModel, EnvironmentSpec, Scene, SceneObject};

use crate::boundary::{array, check_out, ffi_boundary, write_out, FfiError, FfiResult};
use crate::handles::{self, ShikkiEnvironment, ShikkiMaterial, ShikkiMesh, ShikkiScene};
use crate::objects::{EnvironmentObject, MeshObject};
use crate::status::ShikkiStatus;
use crate::ShikkiEnvModel;

/// Tone curves by their C number (`ShikkiToneCurve`).
pub fn tone_curve_from_c(value: u32) -> FfiResult<ToneCurve> {
    match value {
        0 => Ok(ToneCurve::None),
        1 => Ok(ToneCurve::Reinhard),
        2 => Ok(ToneCurve::Aces),
        _ => Err(FfiError::invalid(format!(
            "tone_curve {value}: use SHIKKI_TONE_CURVE_NONE (0), _REINHARD (1) or _ACES (2)"
        ))),
    }
}

/// Environment models by their C number (`ShikkiEnvModel`).
fn environment_model_from_c(value: u32) -> FfiResult<EnvironmentModel> {
    match value {
        v if v == ShikkiEnvModel::Paper as u32 => Ok(EnvironmentModel::Paper),
        v if v == ShikkiEnvModel::Brdf as u32 => Ok(EnvironmentModel::Brdf),
        _ => Err(FfiError::invalid(format!(
            "environment model {value}: use SHIKKI_ENV_MODEL_PAPER (0) or _BRDF (1)"
        ))),
    }
}

/// The C number (`ShikkiEnvModel`) of an environment model.
fn environment_model_to_c(model: EnvironmentModel) -> u32 {
    match model {
        EnvironmentModel::Paper => ShikkiEnvModel::Paper as u32,
        EnvironmentModel::Brdf => ShikkiEnvModel::Brdf as u32,
    }
}

/// The largest image side rendered or written, as in scene files (`[output] size`).
pub const SHIKKI_MAX_IMAGE_SIDE: u32 = 16384;

/// An image size the renderer and the encoders accept: each side in 1..=[`SHIKKI_MAX_IMAGE_SIDE`].
pub fn check_image_size(width: u32, height: u32) -> FfiResult {
    if (1..=SHIKKI_MAX_IMAGE_SIDE).contains(&width) && (1..=SHIKKI_MAX_IMAGE_SIDE).contains(&height)
    {
        Ok(())
    } else {
        Err(FfiError::invalid(format!(
            "image size {width}×{height}: each side must be 1 to {SHIKKI_MAX_IMAGE_SIDE} pixels"
        )))
    }
}

/// Runs `change` on the scene behind `scene`.
pub fn with_scene<R>(
    scene: ShikkiScene,
    change: impl FnOnce(&mut Scene) -> FfiResult<R>,
) -> FfiResult<R> {
    let object = handles::get::<_, Scene>(scene)?;
    let mut state = handles::lock(&object)?;
    change(&mut state)
}

fn vec3(v: [f64; 3]) -> DVec3 {
    DVec3::from_array(v)
}

/// An empty scene: no objects, no lights, no environment, the default camera, 1024×1024 with 4
/// samples, ACES at 0 EV, the environment as background (black without one) and the paper
/// environment model — the scene-file defaults. Add objects, lights, an environment.
///
/// # Safety
/// `out` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_create(out: *mut ShikkiScene) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        let handle = handles::insert::<ShikkiScene, _>(Scene::default());
        // SAFETY: checked non-NULL; valid for one write by contract.
        unsafe { write_out(out, "out", handle) }
    })
}

/// Destroys a scene. 0 is a no-op.
#[no_mangle]
pub extern "C" fn shikki_scene_destroy(scene: ShikkiScene) -> ShikkiStatus {
    ffi_boundary!({ handles::remove(scene) })
}

/// Adds `mesh` placed by `transform` (4×4, column-major like OpenGL/glam: elements 12, 13, 14
/// are the translation) with a copy of `material` as it is now. `transform` NULL = identity.
///
/// # Safety
/// `transform` is NULL or valid for 16 doubles.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_add_object(
    scene: ShikkiScene,
    mesh: ShikkiMesh,
    material: ShikkiMaterial,
    transform: *const f64,
) -> ShikkiStatus {
    ffi_boundary!({
        let transform = if transform.is_null() {
            DMat4::IDENTITY
        } else {
            // SAFETY: the caller's contract above.
            DMat4::from_cols_array(&unsafe { array::<f64, 16>(transform, "transform") }?)
        };
        if let Some(reason) = limits::placement_problem(&transform) {
            return Err(FfiError::invalid(format!(
                "transform cannot place an object: {reason} (the last row is elements 3, 7, 11, \
                 15 in column-major order, the translation 12, 13, 14)"
            )));
        }
        let mesh = handles::read::<_, MeshObject>(mesh)?;
        let material = handles::read::<_, LacquerMaterial>(material)?;
        with_scene(scene, |state| {
            state.objects.push(SceneObject {
                mesh,
                transform,
                material,
            });
            Ok(())
        })
    })
}

fn add_light(scene: ShikkiScene, light: Light) -> FfiResult {
    add_lights(scene, vec![light])
}

/// Adds every one of `lights` or, on error, none: each is validated and the room for all of them
/// is checked under one lock before the first is pushed (adding the default rig one light at a
/// time to a scene with 15 once added one light and then failed).
fn add_lights(scene: ShikkiScene, lights: Vec<Light>) -> FfiResult {
    for light in &lights {
        light.validate()?;
    }
    with_scene(scene, |state| {
        let (have, adding) = (state.lights.len(), lights.len());
        if have + adding > MAX_LIGHTS {
            let message = match adding {
                1 => format!("the scene already has {have} lights, the most one draw takes"),
                _ => format!(
                    "the scene has {have} lights and {adding} more would make {}, above \
                     {MAX_LIGHTS}, the most one draw takes; nothing was added (remove lights \
                     with shikki_scene_clear_lights first)",
                    have + adding
                ),
            };
            return Err(FfiError::invalid(message));
        }
        state.lights.extend(lights);
        Ok(())
    })
}

/// Adds a directional light: `to_light` (towards the light; normalised here) and irradiance E
/// (linear RGB).
///
/// # Safety
/// `to_light` and `irradiance` are valid for 3 doubles each.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_add_directional_light(
    scene: ShikkiScene,
    to_light: *const f64,
    irradiance: *const f64,
) -> ShikkiStatus {
    ffi_boundary!({
        // SAFETY: the caller's contract above.
        let direction = vec3(unsafe { array(to_light, "to_light") }?);
        // SAFETY: the caller's contract above.
        let irradiance = vec3(unsafe { array(irradiance, "irradiance") }?);
        if let Some(reason) = limits::coordinate_problem(direction) {
            return Err(FfiError::invalid(format!(
                "to_light {}: {reason}",
                show_numbers(&direction.to_array())
            )));
        }
        let to_light = direction.try_normalize().ok_or_else(|| {
            FfiError::invalid(format!(
                "to_light {}: the direction must be finite and non-zero",
                show_numbers(&direction.to_array())
            ))
        })?;
        add_light(
            scene,
            Light::Directional {
                to_light,
                irradiance,
            },
        )
    })
}

/// Adds a point light at `position` with intensity I per steradian (linear RGB; E = I/d²).
///
/// # Safety
/// `position` and `intensity` are valid for 3 doubles each.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_add_point_light(
    scene: ShikkiScene,
    position: *const f64,
    intensity: *const f64,
) -> ShikkiStatus {
    ffi_boundary!({
        // SAFETY: the caller's contract above.
        let position = vec3(unsafe { array(position, "position") }?);
        // SAFETY: the caller's contract above.
        let intensity = vec3(unsafe { array(intensity, "intensity") }?);
        add_light(
            scene,
            Light::Point {
                position,
                intensity,
            },
        )
    })
}

/// Adds shikki's default three-light rig (the CLI's, when no light is given): all three, or
/// none where the scene has no room for three more (then SHIKKI_STATUS_INVALID_ARGUMENT and the
/// scene is unchanged).
#[no_mangle]
pub extern "C" fn shikki_scene_add_default_lights(scene: ShikkiScene) -> ShikkiStatus {
    ffi_boundary!({ add_lights(scene, default_lights()) })
}

/// Removes every light.
#[no_mangle]
pub extern "C" fn shikki_scene_clear_lights(scene: ShikkiScene) -> ShikkiStatus {
    ffi_boundary!({
        with_scene(scene, |state| {
            state.lights.clear();
            Ok(())
        })
    })
}

/// Sets the look-at camera; `up` NULL = +Y. `fov_deg` is the vertical field of view.
///
/// # Safety
/// `eye` and `target` are valid for 3 doubles each; `up` is NULL or valid for 3.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_set_camera(
    scene: ShikkiScene,
    eye: *const f64,
    target: *const f64,
    up: *const f64,
    fov_deg: f64,
) -> ShikkiStatus {
    ffi_boundary!({
        let camera = Camera {
            // SAFETY: the caller's contract above.
            eye: vec3(unsafe { array(eye, "eye") }?),
            // SAFETY: the caller's contract above.
            target: vec3(unsafe { array(target, "target") }?),
            up: if up.is_null() {
                DVec3::Y
            } else {
                // SAFETY: the caller's contract above.
                vec3(unsafe { array(up, "up") }?)
            },
            fov_deg,
        };
        camera.validate()?;
        with_scene(scene, |state| {
            state.camera = camera;
            Ok(())
        })
    })
}

/// Lights the scene with `environment` × `intensity`, rotated by `rotation_deg` about +Y.
/// Handle 0 removes the environment.
#[no_mangle]
pub extern "C" fn shikki_scene_set_environment(
    scene: ShikkiScene,
    environment: ShikkiEnvironment,
    intensity: f64,
    rotation_deg: f64,
) -> ShikkiStatus {
    ffi_boundary!({
        let environment = if environment.id == 0 {
            EnvironmentSpec::None
        } else {
            if !(intensity.is_finite() && intensity >= 0.0) {
                return Err(FfiError::invalid(format!(
                    "environment intensity {}: must be finite and ≥ 0 (1 = as stored)",
                    show_number(intensity)
                )));
            }
            if !rotation_deg.is_finite() {
                return Err(FfiError::invalid(format!(
                    "environment rotation {rotation_deg}°: must be a finite angle in degrees"
                )));
            }
            let loaded = handles::read::<_, EnvironmentObject>(environment)?;
            let light = EnvironmentLight {
                intensity,
                rotation_deg,
            };
            light.check_levels(&loaded.image, &loaded.source)?;
            EnvironmentSpec::Map {
                source: EnvironmentSource::Loaded(loaded),
                light,
            }
        };
        with_scene(scene, |state| {
            state.environment = environment;
            Ok(())
        })
    })
}

/// What fills uncovered pixels: `SHIKKI_BACKGROUND_TRANSPARENT` (alpha 0),
/// `SHIKKI_BACKGROUND_COLOR` (opaque linear `rgb`), `SHIKKI_BACKGROUND_ENVIRONMENT` (the sharp
/// environment; black without one). `rgb` is read only for `_COLOR`.
///
/// # Safety
/// `rgb` is valid for 3 floats when `kind` is `SHIKKI_BACKGROUND_COLOR`.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_set_background(
    scene: ShikkiScene,
    kind: u32,
    rgb: *const f32,
) -> ShikkiStatus {
    ffi_boundary!({
        let background = match kind {
            0 => Background::Transparent,
            1 => {
                // SAFETY: the caller's contract above.
                let color: [f32; 3] = unsafe { array(rgb, "rgb") }?;
                if color.iter().any(|c| !c.is_finite() || *c < 0.0) {
                    return Err(FfiError::invalid(format!(
                        "background colour {color:?}: components must be finite and ≥ 0"
                    )));
                }
                Background::Color(color)
            }
            2 => Background::Environment,
            _ => {
                return Err(FfiError::invalid(format!(
                    "background kind {kind}: use SHIKKI_BACKGROUND_TRANSPARENT (0), _COLOR (1) \
                     or _ENVIRONMENT (2)"
                )))
            }
        };
        with_scene(scene, |state| {
            state.output.background = background;
            Ok(())
        })
    })
}

/// Image size and MSAA samples (1 or 4) of renders of this scene.
#[no_mangle]
pub extern "C" fn shikki_scene_set_output(
    scene: ShikkiScene,
    width: u32,
    height: u32,
    samples: u32,
) -> ShikkiStatus {
    ffi_boundary!({
        check_image_size(width, height)?;
        if !SUPPORTED_SAMPLES.contains(&samples) {
            return Err(FfiError::invalid(format!(
                "samples {samples}: use one of {SUPPORTED_SAMPLES:?}"
            )));
        }
        with_scene(scene, |state| {
            state.output.width = width;
            state.output.height = height;
            state.output.samples = samples;
            Ok(())
        })
    })
}

/// The display transform of 8-bit and PNG output (SPEC §1): radiance × 2^exposure_ev → tone
/// curve (`ShikkiToneCurve`) → sRGB.
#[no_mangle]
pub extern "C" fn shikki_scene_set_display(
    scene: ShikkiScene,
    exposure_ev: f32,
    tone_curve: u32,
) -> ShikkiStatus {
    ffi_boundary!({
        if !exposure_ev.is_finite() {
            return Err(FfiError::invalid(format!(
                "exposure_ev {exposure_ev}: must be a finite number of stops"
            )));
        }
        let tone_curve = tone_curve_from_c(tone_curve)?;
        with_scene(scene, |state| {
            state.output.exposure_ev = exposure_ev;
            state.output.tone_curve = tone_curve;
            Ok(())
        })
    })
}

/// How the environment lights the scene's objects (scene files' `[render] environment_model`):
/// `SHIKKI_ENV_MODEL_PAPER` (SPEC §4's paper model, the default) or `SHIKKI_ENV_MODEL_BRDF` (the
/// BRDF itself integrated over the environment by a fixed quadrature).
#[no_mangle]
pub extern "C" fn shikki_scene_set_environment_model(
    scene: ShikkiScene,
    model: u32,
) -> ShikkiStatus {
    ffi_boundary!({
        let model = environment_model_from_c(model)?;
        with_scene(scene, |state| {
            state.render.environment_model = model;
            Ok(())
        })
    })
}

/// The scene's environment model (`ShikkiEnvModel`), as set by
/// `shikki_scene_set_environment_model` or the scene TOML's `[render] environment_model`.
///
/// # Safety
/// `model` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_get_environment_model(
    scene: ShikkiScene,
    model: *mut u32,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(model, "model")?;
        let value = with_scene(scene, |state| {
            Ok(environment_model_to_c(state.render.environment_model))
        })?;
        // SAFETY: checked non-NULL; writable by contract.
        unsafe { write_out(model, "model", value) }
    })
}

/// Light between objects (scene files' `[render] shadows` and `ray_tracing`, SPEC §6):
/// `shadows` non-zero traces shadow rays to the lights; `ray_tracing` zero shades every object as
/// if it were alone (the image of a device without ray queries). Both are on by default; on a
/// device without ray queries neither has an effect, and the renderer's warning callback says
/// so once.
#[no_mangle]
pub extern "C" fn shikki_scene_set_light_transport(
    scene: ShikkiScene,
    shadows: i32,
    ray_tracing: i32,
) -> ShikkiStatus {
    ffi_boundary!({
        with_scene(scene, |state| {
            state.render.shadows = shadows != 0;
            state.render.ray_tracing = ray_tracing != 0;
            Ok(())
        })
    })
}

/// The scene's light-transport switches (1 on, 0 off), as set by
/// `shikki_scene_set_light_transport` or the scene TOML's `[render]` table (either pointer may
/// be NULL).
///
/// # Safety
/// `shadows` and `ray_tracing` are NULL or valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_get_light_transport(
    scene: ShikkiScene,
    shadows: *mut i32,
    ray_tracing: *mut i32,
) -> ShikkiStatus {
    ffi_boundary!({
        let spec = with_scene(scene, |state| Ok(state.render))?;
        if !shadows.is_null() {
            // SAFETY: non-NULL; writable by contract.
            unsafe { write_out(shadows, "shadows", i32::from(spec.shadows)) }?;
        }
        if !ray_tracing.is_null() {
            // SAFETY: non-NULL; writable by contract.
            unsafe { write_out(ray_tracing, "ray_tracing", i32::from(spec.ray_tracing)) }?;
        }
        Ok(())
    })
}

/// The filter of the light between objects' noise (scene files' `[render] denoise`): non-zero
/// (the default) filters the estimate of SPEC §6's integral below 256 rays, guided by the image
/// without it and by the estimate's variance (docs/scene.md); zero gives the estimate as traced.
#[no_mangle]
pub extern "C" fn shikki_scene_set_denoise(scene: ShikkiScene, denoise: i32) -> ShikkiStatus {
    ffi_boundary!({
        with_scene(scene, |state| {
            state.render.denoise = denoise != 0;
            Ok(())
        })
    })
}

/// The scene's denoise switch (1 on, 0 off), as set by `shikki_scene_set_denoise` or the scene
/// TOML's `[render]` table.
///
/// # Safety
/// `denoise` is NULL (`SHIKKI_STATUS_NULL_ARGUMENT`) or valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_get_denoise(
    scene: ShikkiScene,
    denoise: *mut i32,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(denoise, "denoise")?;
        let spec = with_scene(scene, |state| Ok(state.render))?;
        // SAFETY: checked non-NULL; writable by contract.
        unsafe { write_out(denoise, "denoise", i32::from(spec.denoise)) }
    })
}

/// SPEC §6's integral (scene files' `[render] bounces`, `rays`, `seed`): `bounces` 0 (shadows
/// only) to 4, default 1; `rays` per shaded point 1 to 4096, default 8; `seed` of the sample
/// sequence (the same seed gives the same image). Out of range: INVALID_ARGUMENT naming the range,
/// the scene unchanged.
#[no_mangle]
pub extern "C" fn shikki_scene_set_light_paths(
    scene: ShikkiScene,
    bounces: u32,
    rays: u32,
    seed: u32,
) -> ShikkiStatus {
    ffi_boundary!({
        if bounces > MAX_BOUNCES {
            return Err(FfiError::invalid(format!(
                "bounces {bounces}: must be 0 to {MAX_BOUNCES}"
            )));
        }
        if !(1..=MAX_RAYS).contains(&rays) {
            return Err(FfiError::invalid(format!(
                "rays {rays}: must be 1 to {MAX_RAYS}"
            )));
        }
        with_scene(scene, |state| {
            state.render.bounces = bounces;
            state.render.rays = rays;
            state.render.seed = seed;
            Ok(())
        })
    })
}

/// The scene's bounces, rays and seed, as set by `shikki_scene_set_light_paths` or the scene
/// TOML's `[render]` table (any pointer may be NULL).
///
/// # Safety
/// Each pointer is NULL or valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_get_light_paths(
    scene: ShikkiScene,
    bounces: *mut u32,
    rays: *mut u32,
    seed: *mut u32,
) -> ShikkiStatus {
    ffi_boundary!({
        let spec = with_scene(scene, |state| Ok(state.render))?;
        for (ptr, name, value) in [
            (bounces, "bounces", spec.bounces),
            (rays, "rays", spec.rays),
            (seed, "seed", spec.seed),
        ] {
            if !ptr.is_null() {
                // SAFETY: non-NULL; writable by contract.
                unsafe { write_out(ptr, name, value) }?;
            }
        }
        Ok(())
    })
}

/// The render size of the scene, so the caller can size its buffer (either pointer may be NULL).
///
/// # Safety
/// `width` and `height` are NULL or valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_scene_get_output(
    scene: ShikkiScene,
    width: *mut u32,
    height: *mut u32,
) -> ShikkiStatus {
    ffi_boundary!({
        let (w, h) = with_scene(scene, |state| Ok((state.output.width, state.output.height)))?;
        if !width.is_null() {
            // SAFETY: non-NULL and writable by contract.
            unsafe { write_out(width, "width", w) }?;
        }
        if !height.is_null() {
            // SAFETY: non-NULL and writable by contract.
            unsafe { write_out(height, "height", h) }?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::last_error;

    fn light_count(scene: ShikkiScene) -> usize {
        with_scene(scene, |state| Ok(state.lights.len())).expect("the scene handle is live")
    }

    #[test]
    fn default_lights_are_added_all_three_or_none() {
        let _turn = handles::test_table_turn();
        let mut scene = ShikkiScene { id: 0 };
        // SAFETY: `scene` is valid for one write.
        assert_eq!(unsafe { shikki_scene_create(&mut scene) }, ShikkiStatus::Ok);
        let light = Light::Point {
            position: DVec3::new(0.0, 2.0, 0.0),
            intensity: DVec3::ONE,
        };
        let fill = MAX_LIGHTS - 1;
        for _ in 0..fill {
            add_light(scene, light).expect("room for one more light");
        }
        assert_eq!(
            shikki_scene_add_default_lights(scene),
            ShikkiStatus::InvalidArgument
        );
        let message = last_error();
        assert!(
            message.contains(&format!("has {fill} lights and 3 more would make")),
            "{message}"
        );
        assert!(message.contains("nothing was added"), "{message}");
        assert_eq!(light_count(scene), fill, "a refused rig adds no light");

        // With room for exactly three the rig goes in whole.
        assert_eq!(shikki_scene_clear_lights(scene), ShikkiStatus::Ok);
        for _ in 0..MAX_LIGHTS - 3 {
            add_light(scene, light).expect("room for one more light");
        }
        assert_eq!(shikki_scene_add_default_lights(scene), ShikkiStatus::Ok);
        assert_eq!(light_count(scene), MAX_LIGHTS);
        assert_eq!(shikki_scene_destroy(scene), ShikkiStatus::Ok);
    }
}
