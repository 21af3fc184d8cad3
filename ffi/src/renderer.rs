//! Renderer handles and the render calls. A renderer owns one Vulkan device (`GpuContext`), the
//! lacquer pipelines, and the prefiltered environment it used last (GPU images belong to one
//! device, so environments are prefiltered here, with the parameters the CLI and the scene
//! renderer use: `PrefilterParams::for_source_width`).

use std::ffi::c_char;
use std::path::Path;
use std::sync::Arc;

use shikki::environment::gpu::{GpuEnvironment, GpuPrefilter};
use shikki::environment::params::ViewBlur;
use shikki::environment::{Equirect, PrefilterParams};
use shikki::gpu::{ContextOptions, GpuContext};
use shikki::output::{self, HdrImage, PngSettings};
use shikki::raster::draw::{DrawObject, DrawScene, LacquerRenderer, RenderSettings};
use shikki::raster::mesh_io::transform_mesh;
use shikki::raster::Mesh;

use crate::boundary::{
    c_str, check_out, ffi_boundary, opt_c_str, slice, slice_mut, write_out, FfiError, FfiResult,
};
use crate::handles::{self, ShikkiRenderer, ShikkiScene};
use crate::scene::{check_image_size, tone_curve_from_c, SceneState};
use crate::status::ShikkiStatus;

/// Options of `shikki_renderer_create`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ShikkiRendererOptions {
    /// Pick the first Vulkan device whose name contains this (case-insensitive); NULL or "" =
    /// the first suitable device.
    pub device_name: *const c_char,
    /// Enable VK_LAYER_KHRONOS_validation (with its synchronisation checks) and count its
    /// messages (`shikki_renderer_validation_message_count`).
    pub validation: bool,
}

struct CachedEnvironment {
    source: Arc<Equirect>,
    intensity: f64,
    rotation_deg: f64,
    prefiltered: GpuEnvironment,
}

/// A renderer handle's object. Field order is drop order: every GPU object before the context.
pub struct RendererState {
    environment: Option<CachedEnvironment>,
    renderer: LacquerRenderer,
    validation_messages: Vec<String>,
    gpu: GpuContext,
}

impl RendererState {
    pub fn new(options: &ContextOptions) -> FfiResult<Self> {
        Ok(RendererState {
            environment: None,
            renderer: LacquerRenderer::new(),
            validation_messages: Vec::new(),
            gpu: GpuContext::new(options).map_err(shikki::Error::from)?,
        })
    }

    /// The scene's environment prefiltered on this device; reuses the last one when the scene
    /// names the same map, intensity and rotation. Takes the fields it needs, not `self`, so the
    /// result can be borrowed alongside the renderer.
    fn prefiltered<'a>(
        cache: &'a mut Option<CachedEnvironment>,
        gpu: &GpuContext,
        scene: &SceneState,
    ) -> FfiResult<Option<&'a GpuEnvironment>> {
        let Some(wanted) = &scene.environment else {
            return Ok(None);
        };
        let hit = cache.as_ref().is_some_and(|c| {
            Arc::ptr_eq(&c.source, &wanted.image)
                && c.intensity == wanted.intensity
                && c.rotation_deg == wanted.rotation_deg
        });
        if !hit {
            // Free the old images before making new ones: environments can be large.
            *cache = None;
            let params = PrefilterParams::for_source_width(wanted.image.width);
            let prefiltered = GpuPrefilter::new(gpu)?.run(
                gpu,
                &wanted.image,
                &params,
                wanted.intensity,
                wanted.rotation_deg,
            )?;
            *cache = Some(CachedEnvironment {
                source: Arc::clone(&wanted.image),
                intensity: wanted.intensity,
                rotation_deg: wanted.rotation_deg,
                prefiltered,
            });
        }
        Ok(cache.as_ref().map(|c| &c.prefiltered))
    }

    /// Renders `scene` to linear radiance (premultiplied by coverage, row 0 at the top).
    pub fn render(&mut self, scene: &SceneState) -> FfiResult<HdrImage> {
        let materials = scene
            .objects
            .iter()
            .map(|o| Ok((o.material.brdf_params()?, o.material.fresnel_table()?)))
            .collect::<FfiResult<Vec<_>>>()?;
        let placed: Vec<Arc<Mesh>> = scene
            .objects
            .iter()
            .map(|o| {
                if o.transform == glam::DMat4::IDENTITY {
                    Ok(Arc::clone(&o.mesh))
                } else {
                    let placed = transform_mesh(&o.mesh, o.transform);
                    placed.validate()?;
                    Ok(Arc::new(placed))
                }
            })
            .collect::<FfiResult<Vec<_>>>()?;
        let objects: Vec<DrawObject<'_>> = scene
            .objects
            .iter()
            .zip(&placed)
            .zip(&materials)
            .map(|((object, mesh), (brdf, fresnel))| DrawObject {
                mesh,
                brdf,
                fresnel,
                view_blur: ViewBlur::of(&object.material),
            })
            .collect();
        let settings = RenderSettings {
            width: scene.width,
            height: scene.height,
            samples: scene.samples,
        };
        let image =
            Self::prefiltered(&mut self.environment, &self.gpu, scene).and_then(|environment| {
                let draw = DrawScene {
                    objects: &objects,
                    camera: &scene.camera,
                    lights: &scene.lights,
                    environment,
                    background: scene.background,
                };
                Ok(self.renderer.render(&self.gpu, &draw, &settings)?)
            });
        // Collected after failures too: a validation message often explains one.
        self.validation_messages
            .extend(self.gpu.take_validation_messages());
        image
    }
}

/// Creates a renderer: opens the Vulkan device. `options` NULL = defaults (first device, no
/// validation).
///
/// # Safety
/// `options` is NULL or valid for one read (its `device_name` NULL or a NUL-terminated UTF-8
/// string); `out` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_renderer_create(
    options: *const ShikkiRendererOptions,
    out: *mut ShikkiRenderer,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        let no_ray_query = std::env::var("SHIKKI_RAY_QUERY").is_ok_and(|v| v == "0");
        let context = if options.is_null() {
            ContextOptions {
                no_ray_query,
                ..ContextOptions::default()
            }
        } else {
            // SAFETY: non-NULL and readable by the caller's contract.
            let options = unsafe { &*options };
            // SAFETY: the caller's contract above.
            let device = unsafe { opt_c_str(options.device_name, "options.device_name") }?;
            ContextOptions {
                validation: options.validation,
                device_name: device.filter(|d| !d.is_empty()).map(str::to_string),
                no_ray_query,
                ..ContextOptions::default()
            }
        };
        let state = RendererState::new(&context)?;
        let handle = handles::insert::<ShikkiRenderer, _>(state);
        // SAFETY: checked non-NULL; valid for one write by contract.
        unsafe { write_out(out, "out", handle) }
    })
}

/// Destroys a renderer, waiting for its GPU work. 0 is a no-op.
#[no_mangle]
pub extern "C" fn shikki_renderer_destroy(renderer: ShikkiRenderer) -> ShikkiStatus {
    ffi_boundary!({ handles::remove(renderer) })
}

/// The number of validation-layer messages this renderer has collected (0 without validation).
///
/// # Safety
/// `count` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_renderer_validation_message_count(
    renderer: ShikkiRenderer,
    count: *mut usize,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(count, "count")?;
        let object = handles::get::<_, RendererState>(renderer)?;
        let mut state = handles::lock(&object)?;
        let fresh = state.gpu.take_validation_messages();
        state.validation_messages.extend(fresh);
        let n = state.validation_messages.len();
        // SAFETY: checked non-NULL; writable by contract.
        unsafe { write_out(count, "count", n) }
    })
}

/// A copy of the scene as it is now (cheap: meshes and environments are shared), so that its
/// lock is not held through the render. The buffer check and the render use this one copy: a
/// `shikki_scene_set_output` from another thread between the two cannot make the image a size
/// other than the buffer's.
fn snapshot(scene: ShikkiScene) -> FfiResult<SceneState> {
    handles::read::<_, SceneState>(scene)
}

fn render_snapshot(renderer: ShikkiRenderer, scene: &SceneState) -> FfiResult<HdrImage> {
    let object = handles::get::<_, RendererState>(renderer)?;
    let mut state = handles::lock(&object)?;
    state.render(scene)
}

/// `len` must be exactly `width × height × per_pixel`; computed without overflow, so a caller's
/// made-up size is a `BUFFER_SIZE` error, not a wrapped-around match.
fn check_len(what: &str, len: usize, width: u32, height: u32, per_pixel: usize) -> FfiResult {
    let needed = (width as usize)
        .checked_mul(height as usize)
        .and_then(|n| n.checked_mul(per_pixel));
    if needed == Some(len) {
        Ok(())
    } else {
        let needed = needed.map_or_else(|| "more than memory holds".to_string(), |n| n.to_string());
        Err(FfiError::new(
            ShikkiStatus::BufferSize,
            format!(
                "{what} holds {len} elements but a {width}×{height} image needs exactly {needed} \
                 ({per_pixel} per pixel; shikki_scene_get_output gives a scene's size)"
            ),
        ))
    }
}

/// The rendered pixels, as many as the buffer holds: `check_len` made them equal.
fn copy_pixels<T>(out: &mut [T], image: &HdrImage, convert: impl Fn([f32; 4]) -> [T; 4])
where
    T: Copy,
{
    for (dst, src) in out.chunks_exact_mut(4).zip(&image.pixels) {
        dst.copy_from_slice(&convert(*src));
    }
}

/// Renders into `rgba` (linear radiance, RGBA32F, alpha = coverage, colour premultiplied by it,
/// row 0 at the top); `len` must be width × height × 4 floats.
///
/// # Safety
/// `rgba` is valid for writes of `len` floats.
#[no_mangle]
pub unsafe extern "C" fn shikki_render_rgba32f(
    renderer: ShikkiRenderer,
    scene: ShikkiScene,
    rgba: *mut f32,
    len: usize,
) -> ShikkiStatus {
    ffi_boundary!({
        let scene = snapshot(scene)?;
        check_len("rgba", len, scene.width, scene.height, 4)?;
        // SAFETY: the caller's contract above.
        let out = unsafe { slice_mut(rgba, len, "rgba") }?;
        let image = render_snapshot(renderer, &scene)?;
        copy_pixels(out, &image, |pixel| pixel);
        Ok(())
    })
}

/// Renders into `rgba` as 8-bit sRGB with straight alpha, through the scene's exposure and tone
/// curve — the same bytes a PNG of the scene holds; `len` must be width × height × 4 bytes.
///
/// # Safety
/// `rgba` is valid for writes of `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn shikki_render_rgba8(
    renderer: ShikkiRenderer,
    scene: ShikkiScene,
    rgba: *mut u8,
    len: usize,
) -> ShikkiStatus {
    ffi_boundary!({
        let scene = snapshot(scene)?;
        check_len("rgba", len, scene.width, scene.height, 4)?;
        // SAFETY: the caller's contract above.
        let out = unsafe { slice_mut(rgba, len, "rgba") }?;
        let image = render_snapshot(renderer, &scene)?;
        let settings = PngSettings {
            exposure_ev: scene.exposure_ev,
            tone_curve: scene.tone_curve,
        };
        let encoder = shikki::output::tonemap::Srgb8Encoder::new(&settings);
        copy_pixels(out, &image, |pixel| {
            shikki::output::png::straight_srgb8_with(pixel, &encoder)
        });
        Ok(())
    })
}

/// Renders and writes `path`: `.png` (the scene's exposure and tone curve) or `.exr` (linear).
/// The file is written atomically; on failure no file is left at `path`.
///
/// # Safety
/// `path` is a NUL-terminated UTF-8 string.
#[no_mangle]
pub unsafe extern "C" fn shikki_render_to_file(
    renderer: ShikkiRenderer,
    scene: ShikkiScene,
    path: *const c_char,
) -> ShikkiStatus {
    ffi_boundary!({
        // SAFETY: the caller's contract above.
        let path = Path::new(unsafe { c_str(path, "path") }?);
        output::preflight_output(path)?;
        let scene = snapshot(scene)?;
        let image = render_snapshot(renderer, &scene)?;
        let settings = PngSettings {
            exposure_ev: scene.exposure_ev,
            tone_curve: scene.tone_curve,
        };
        output::write_image(path, &image, &settings)?;
        Ok(())
    })
}

/// Writes a caller's RGBA32F image (linear, premultiplied, row 0 at the top; `len` = width ×
/// height × 4 floats) as `.png` (exposure, tone curve) or `.exr` (linear) — the encoder
/// `shikki_render_to_file` uses.
///
/// # Safety
/// `rgba` is valid for reads of `len` floats; `path` is a NUL-terminated UTF-8 string.
#[no_mangle]
pub unsafe extern "C" fn shikki_image_write(
    rgba: *const f32,
    len: usize,
    width: u32,
    height: u32,
    exposure_ev: f32,
    tone_curve: u32,
    path: *const c_char,
) -> ShikkiStatus {
    ffi_boundary!({
        check_image_size(width, height)?;
        check_len("rgba", len, width, height, 4)?;
        // SAFETY: the caller's contract above.
        let pixels = unsafe { slice(rgba, len, "rgba") }?;
        // SAFETY: the caller's contract above.
        let path = Path::new(unsafe { c_str(path, "path") }?);
        let settings = PngSettings {
            exposure_ev,
            tone_curve: tone_curve_from_c(tone_curve)?,
        };
        let image = HdrImage {
            width,
            height,
            pixels: pixels
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
        };
        output::write_image(path, &image, &settings)?;
        Ok(())
    })
}
