//! Renderer handles and the render calls. A renderer owns one Vulkan device (`GpuContext`) and
//! the core's `SceneRenderer` — the one renderer the CLI, scene files and batches use — so a C
//! caller gets the CLI's pixels, environment preparation included (prefilter parameters clamped
//! to the device, the disk cache once a directory is set). Unlike the CLI's it keeps one
//! prefiltered environment at a time (environments can be large), collects validation messages
//! instead of failing on them, and hands warnings to the program's callback instead of printing.

use std::ffi::{c_char, c_void, CString};
use std::path::Path;

use shikki::environment::disk_cache::EnvironmentDiskCache;
use shikki::gpu::{ContextOptions, GpuContext};
use shikki::output::{self, HdrImage, PngSettings};
use shikki::scene::{Scene, SceneRenderer};
use shikki::Warning;

use crate::boundary::{
    c_str, check_out, ffi_boundary, opt_c_str, slice, slice_mut, write_out, FfiError, FfiResult,
};
use crate::handles::{self, ShikkiRenderer, ShikkiScene};
use crate::scene::{check_image_size, tone_curve_from_c};
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

/// Receives a renderer's warnings (`shikki_renderer_set_warning_callback`): `user_data` as given,
/// and one warning as a NUL-terminated UTF-8 sentence, valid only during the call.
pub type ShikkiWarningCallback =
    Option<unsafe extern "C" fn(user_data: *mut c_void, message: *const c_char)>;

/// A program's warning callback and its pointer.
#[derive(Clone, Copy)]
struct WarningSink {
    callback: unsafe extern "C" fn(*mut c_void, *const c_char),
    user_data: *mut c_void,
}

// SAFETY: `user_data` is never dereferenced here, only handed back to the program's own
// callback, which the contract of `shikki_renderer_set_warning_callback` lets us call from any
// thread that renders with the renderer.
unsafe impl Send for WarningSink {}

impl WarningSink {
    fn deliver(self, warning: &Warning) {
        // Our sentences hold no NUL; a path quoted in one might.
        let text = CString::new(warning.to_string().replace('\0', "\\0")).unwrap_or_default();
        // SAFETY: the program's callback with its own pointer, as its contract allows; `text` is
        // NUL-terminated and outlives the call.
        unsafe { (self.callback)(self.user_data, text.as_ptr()) };
    }
}

/// A renderer handle's object. Field order is drop order: every GPU object before the context.
pub struct RendererState {
    renderer: SceneRenderer,
    validation_messages: Vec<String>,
    warning_sink: Option<WarningSink>,
    gpu: GpuContext,
}

impl RendererState {
    pub fn new(options: &ContextOptions) -> FfiResult<Self> {
        let gpu = GpuContext::new(options).map_err(shikki::Error::from)?;
        let mut renderer = SceneRenderer::with_disk_cache(None);
        renderer.set_environment_capacity(1);
        renderer.set_validation_fails_render(false);
        Ok(RendererState {
            renderer,
            validation_messages: Vec::new(),
            warning_sink: None,
            gpu,
        })
    }

    /// Renders `scene` to linear radiance (premultiplied by coverage, row 0 at the top).
    fn render(&mut self, scene: &Scene) -> FfiResult<HdrImage> {
        let image = self.renderer.render(&self.gpu, scene);
        // Collected after failures too: a validation message often explains one.
        self.collect_validation_messages();
        Ok(image?)
    }

    fn collect_validation_messages(&mut self) {
        let fresh = self.gpu.take_validation_messages();
        self.validation_messages.extend(fresh);
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
        if let Some(problem) = ContextOptions::ray_tracing_env_problem() {
            return Err(problem.into());
        }
        let ray_tracing = ContextOptions::ray_tracing_by_env();
        let context = if options.is_null() {
            ContextOptions {
                ray_tracing,
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
                ray_tracing,
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
        state.collect_validation_messages();
        let n = state.validation_messages.len();
        // SAFETY: checked non-NULL; writable by contract.
        unsafe { write_out(count, "count", n) }
    })
}

/// Passes each warning of this renderer's renders (replaced environment pixels, an environment
/// cache file ignored or not written: nothing that stops a render) to `callback` with
/// `user_data`, on the rendering thread, before the render call returns and with the renderer
/// unlocked. NULL (the default) drops warnings: the library never prints.
///
/// # Safety
/// Unless NULL, `callback` must be safe to call with `user_data` and a message from any thread
/// that renders with this renderer, until it is replaced or the renderer destroyed, and must
/// return normally (no `longjmp`, no C++ exception).
#[no_mangle]
pub unsafe extern "C" fn shikki_renderer_set_warning_callback(
    renderer: ShikkiRenderer,
    callback: ShikkiWarningCallback,
    user_data: *mut c_void,
) -> ShikkiStatus {
    ffi_boundary!({
        let object = handles::get::<_, RendererState>(renderer)?;
        let mut state = handles::lock(&object)?;
        state.warning_sink = callback.map(|callback| WarningSink {
            callback,
            user_data,
        });
        Ok(())
    })
}

/// Caches prefiltered environments in `directory` (created when first written): a later render
/// of the same map with the same intensity and rotation on the same kind of device, by any
/// renderer or process (the CLI's cache is `~/.cache/shikki/environments`), loads it instead of
/// prefiltering again. Files are named by a hash of the map's pixels and every parameter, and are
/// checked before use. NULL or "" (the default) turns the cache off.
///
/// # Safety
/// `directory` is NULL or a NUL-terminated UTF-8 string.
#[no_mangle]
pub unsafe extern "C" fn shikki_renderer_set_environment_cache(
    renderer: ShikkiRenderer,
    directory: *const c_char,
) -> ShikkiStatus {
    ffi_boundary!({
        // SAFETY: the caller's contract above.
        let directory = unsafe { opt_c_str(directory, "directory") }?;
        let cache = directory
            .filter(|d| !d.is_empty())
            .map(EnvironmentDiskCache::new);
        let object = handles::get::<_, RendererState>(renderer)?;
        let mut state = handles::lock(&object)?;
        state.renderer.set_disk_cache(cache);
        Ok(())
    })
}

/// A copy of the scene as it is now (cheap: meshes and environments are shared), so that its
/// lock is not held through the render. The buffer check and the render use this one copy: a
/// `shikki_scene_set_output` from another thread between the two cannot make the image a size
/// other than the buffer's.
fn snapshot(scene: ShikkiScene) -> FfiResult<Scene> {
    handles::read::<_, Scene>(scene)
}

/// Renders with the renderer locked, then hands the render's warnings (failed renders have them
/// too) to the program's callback with the lock released, so the callback may call the library,
/// this renderer included.
fn render_snapshot(renderer: ShikkiRenderer, scene: &Scene) -> FfiResult<HdrImage> {
    let object = handles::get::<_, RendererState>(renderer)?;
    let (image, warnings, sink) = {
        let mut state = handles::lock(&object)?;
        let image = state.render(scene);
        (image, state.renderer.take_warnings(), state.warning_sink)
    };
    if let Some(sink) = sink {
        for warning in &warnings {
            sink.deliver(warning);
        }
    }
    image
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
        check_len("rgba", len, scene.output.width, scene.output.height, 4)?;
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
        check_len("rgba", len, scene.output.width, scene.output.height, 4)?;
        // SAFETY: the caller's contract above.
        let out = unsafe { slice_mut(rgba, len, "rgba") }?;
        let image = render_snapshot(renderer, &scene)?;
        let settings = PngSettings {
            exposure_ev: scene.output.exposure_ev,
            tone_curve: scene.output.tone_curve,
        };
        let encoder = shikki::output::tonemap::Srgb8Encoder::new(&settings);
        copy_pixels(out, &image, |pixel| {
            shikki::output::png::straight_srgb8_with(pixel, &encoder)
        });
        Ok(())
    })
}

/// Renders and writes `path`: `.png` (the scene's exposure and tone curve) or `.exr` (linear).
/// The file is written atomically. A `path` that is refused (another extension, a directory, a
/// missing directory, a name over 255 bytes, a device) is left alone; any later failure leaves
/// no file at `path` (an earlier one there is removed, and the message says so).
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
        let written = snapshot(scene).and_then(|scene| {
            let image = render_snapshot(renderer, &scene)?;
            let settings = PngSettings {
                exposure_ev: scene.output.exposure_ev,
                tone_curve: scene.output.tone_curve,
            };
            Ok(output::write_image(path, &image, &settings)?)
        });
        // The path is one this call writes (checked above): an earlier file there would pass
        // for this call's output, so any failure from here on removes it and says so.
        written.map_err(|mut error| {
            error
                .message
                .push_str(&output::atomic::discard_stale_saying(path));
            error
        })
    })
}

/// Writes a caller's RGBA32F image (linear, premultiplied, row 0 at the top; `len` = width ×
/// height × 4 floats) as `.png` (exposure, tone curve) or `.exr` (linear) — the encoder
/// `shikki_render_to_file` uses. Invalid arguments (the size, `len`, a NaN or infinite pixel or
/// exposure, the tone curve, the path's extension) are SHIKKI_STATUS_INVALID_ARGUMENT and leave
/// `path` as it was; a failure while writing leaves no file at `path`.
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
