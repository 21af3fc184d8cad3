//! The render targets of one image size, sample count and kind of draw, with the host-visible
//! readback buffer, kept between renders so a batch of same-sized images allocates them once.
//!
//! - The lacquer draw is deferred: a G-buffer (position + object, normal; RGBA32F, multisampled)
//!   and depth, and the single-sampled image the shading pass writes, copied to the readback
//!   buffer. A ray-traced draw's shading pass also writes the integral's estimate (SPEC §6)
//!   into a second image with its own readback buffer, made by the first such draw.
//! - The forward draw (the benchmark's trivial shader) has a colour target, its MSAA resolve and
//!   depth, copied to the readback buffer.
//!
//! Tall images are drawn in horizontal strips (one submit each) into targets of
//! [`MAX_COLOR_TARGET_BYTES`] at most per colour attachment, each strip landing in its rows of the
//! full-size readback buffer: a 4× MSAA RGBA32F attachment of a 1024² image alone would be 64 MiB,
//! most of the render's peak memory. Images up to 512² with 4× MSAA fit one strip.
//!
//! Reuse across submits is safe because every render starts with barriers whose first scope is
//! the previous render's last use of each target (pipeline barriers order against all earlier
//! submissions on the queue), and every render clears what it draws into.

use super::get_or_try_insert;
use crate::gpu::{Buffer, BufferDesc, GpuContext, Image, ImageDesc, ImageUsage};
use crate::Result;

/// Largest multisampled colour attachment (bytes); the depth target is a quarter of it.
pub const MAX_COLOR_TARGET_BYTES: u64 = 16 << 20;

/// Rows per strip for an image `width` wide with `samples` per pixel (RGBA32F samples), each
/// colour attachment holding at most `budget` bytes.
pub fn strip_rows(width: u32, height: u32, samples: u32, budget: u64) -> u32 {
    let row_bytes = u64::from(width) * u64::from(samples) * 16;
    let rows = (budget / row_bytes.max(1)).max(1);
    rows.min(u64::from(height)) as u32
}

/// Paths (rays × bounces per shaded point, summed over a strip's pixels) one submit traces at
/// most: about 8 s of lavapipe on two cores (~1 M rays/s, each path ray with its shadow ray),
/// far inside the submit timeout (600 s) on a loaded machine too. Without it a 512² image at 128
/// rays was one submit of ~10 minutes.
pub const PATHS_PER_SUBMIT: u64 = 8 << 20;

/// Rows per submit of a ray-traced draw `width` wide tracing `paths` paths per pixel (at least
/// one row).
pub fn traced_strip_rows(width: u32, paths: u64) -> u32 {
    let row_paths = u64::from(width) * paths.max(1);
    (PATHS_PER_SUBMIT / row_paths.max(1)).clamp(1, u64::from(u32::MAX)) as u32
}

/// Width, height, samples.
pub(crate) type TargetSize = (u32, u32, u32);

/// The colour attachments of one kind of draw, made for a strip of `rows` rows.
pub(crate) trait Attachments: Sized {
    fn new(gpu: &GpuContext, width: u32, rows: u32, samples: u32) -> Result<Self>;
}

/// The lacquer draw's attachments.
pub(crate) struct Deferred {
    /// xyz: interpolated position; w: object index + 1 (0 where no mesh covers the sample).
    pub position: Image,
    /// xyz: interpolated normal.
    pub normal: Image,
    /// The shaded, sample-averaged strip (single-sampled).
    pub output: Image,
    /// Single-sampled depth of the shading pass: 0 where a G-buffer sample is covered.
    pub coverage: Image,
    /// The ray-traced shading pass's second output (shade_body.glsl's `out_integral`).
    pub integral: Option<IntegralTarget>,
}

/// The ray-traced draw's integral image: its strip and the whole image's readback buffer.
pub(crate) struct IntegralTarget {
    pub image: Image,
    pub readback: Buffer,
    /// Whether a draw used it before (then the first barriers wait for that use).
    pub used: bool,
}

impl Attachments for Deferred {
    fn new(gpu: &GpuContext, width: u32, rows: u32, samples: u32) -> Result<Self> {
        let gbuffer =
            |name| gpu.create_image(ImageDesc::sampled_target(name, width, rows, samples));
        Ok(Deferred {
            position: gbuffer("g-buffer position")?,
            normal: gbuffer("g-buffer normal")?,
            output: gpu.create_image(shaded_target(gpu, "shaded", width, rows))?,
            coverage: gpu.create_image(ImageDesc::depth_target("coverage", width, rows, 1))?,
            integral: None,
        })
    }
}

/// The shading pass's single-sampled output (the image or the integral image): a colour target,
/// and on a device that shades ray-traced draws in a ray-tracing pipeline also a storage image
/// (shade_rt_pipeline.glsl writes it).
fn shaded_target(gpu: &GpuContext, name: &str, width: u32, rows: u32) -> ImageDesc {
    let desc = ImageDesc::color_target(name, width, rows, 1);
    match gpu.info().ray_query.uses_pipeline() {
        true => {
            let usage = ImageUsage::COLOR_ATTACHMENT | ImageUsage::TRANSFER_SRC;
            desc.usage(usage | ImageUsage::STORAGE)
        }
        false => desc,
    }
}

impl DrawTargets<Deferred> {
    /// The integral image of these targets, made on first use.
    pub fn integral(&mut self, gpu: &GpuContext) -> Result<&mut IntegralTarget> {
        let (width, height, _) = self.size;
        let rows = self.strip_rows;
        get_or_try_insert(&mut self.attachments.integral, || {
            let image_bytes = u64::from(width) * u64::from(height) * 16;
            Ok(IntegralTarget {
                image: gpu.create_image(shaded_target(gpu, "integral", width, rows))?,
                readback: gpu
                    .create_buffer(BufferDesc::readback("integral readback", image_bytes))?,
                used: false,
            })
        })
    }
}

/// The forward draw's attachments (the benchmark's trivial shader).
pub(crate) struct Forward {
    pub color: Image,
    /// The single-sampled image the MSAA colour resolves into (None without MSAA).
    pub resolve: Option<Image>,
}

impl Attachments for Forward {
    fn new(gpu: &GpuContext, width: u32, rows: u32, samples: u32) -> Result<Self> {
        Ok(Forward {
            color: gpu.create_image(ImageDesc::color_target("color", width, rows, samples))?,
            resolve: if samples > 1 {
                Some(gpu.create_image(ImageDesc::color_target("resolve", width, rows, 1))?)
            } else {
                None
            },
        })
    }
}

/// The targets of one kind of draw: its attachments, depth and the readback buffer.
pub(crate) struct DrawTargets<A> {
    pub size: TargetSize,
    /// Rows of the image each target holds (the last strip may use fewer).
    pub strip_rows: u32,
    pub attachments: A,
    pub depth: Image,
    pub readback: Buffer,
    /// Whether a render used these targets before (then the first barriers wait for that use).
    pub used: bool,
}

impl<A: Attachments> DrawTargets<A> {
    fn new(gpu: &GpuContext, size: TargetSize, budget: u64) -> Result<Self> {
        let (width, height, samples) = size;
        let rows = strip_rows(width, height, samples, budget);
        let attachments = A::new(gpu, width, rows, samples)?;
        let depth = gpu.create_image(ImageDesc::depth_target("depth", width, rows, samples))?;
        let image_bytes = u64::from(width) * u64::from(height) * 16;
        let readback = gpu.create_buffer(BufferDesc::readback("readback", image_bytes))?;
        Ok(DrawTargets {
            size,
            strip_rows: rows,
            attachments,
            depth,
            readback,
            used: false,
        })
    }
}

/// Holds the targets of the last size used for each kind of draw: a new size replaces them
/// (batches render one size; keeping several 100 MB sets would only raise peak memory). Real
/// renders are all deferred, so they hold one set; the benchmark alternates both kinds.
pub(crate) struct TargetCache {
    deferred: Option<DrawTargets<Deferred>>,
    forward: Option<DrawTargets<Forward>>,
    /// Colour attachment budget in bytes ([`MAX_COLOR_TARGET_BYTES`]; smaller in tests).
    pub color_budget: u64,
}

impl Default for TargetCache {
    fn default() -> Self {
        TargetCache {
            deferred: None,
            forward: None,
            color_budget: MAX_COLOR_TARGET_BYTES,
        }
    }
}

impl TargetCache {
    pub fn deferred(
        &mut self,
        gpu: &GpuContext,
        size: TargetSize,
    ) -> Result<&mut DrawTargets<Deferred>> {
        of_size(&mut self.deferred, gpu, size, self.color_budget)
    }

    pub fn forward(
        &mut self,
        gpu: &GpuContext,
        size: TargetSize,
    ) -> Result<&mut DrawTargets<Forward>> {
        of_size(&mut self.forward, gpu, size, self.color_budget)
    }
}

/// The targets in `slot` if they have `size`, else new ones in their place.
fn of_size<'a, A: Attachments>(
    slot: &'a mut Option<DrawTargets<A>>,
    gpu: &GpuContext,
    size: TargetSize,
    budget: u64,
) -> Result<&'a mut DrawTargets<A>> {
    if slot.as_ref().is_some_and(|t| t.size != size) {
        // Free the old set before allocating the new one: peak memory is one set.
        *slot = None;
    }
    get_or_try_insert(slot, || DrawTargets::new(gpu, size, budget))
}

#[cfg(test)]
mod tests {
    use crate::environment::params::ViewBlur;
    use crate::gpu::{ContextOptions, GpuContext};
    use crate::model::LacquerMaterial;
    use crate::raster::draw::{Background, DrawObject, DrawScene, LacquerRenderer, RenderSettings};
    use crate::raster::mesh::BuiltinMesh;
    use crate::raster::Camera;

    /// A submit traces at most `PATHS_PER_SUBMIT` paths, and at least one row.
    #[test]
    fn a_traced_strip_holds_a_submits_share_of_paths() {
        use super::{traced_strip_rows, PATHS_PER_SUBMIT};
        assert_eq!(traced_strip_rows(512, 128), 128);
        assert_eq!(traced_strip_rows(1024, 8), 1024);
        assert_eq!(traced_strip_rows(8192, 4096 * 4), 1);
        assert_eq!(traced_strip_rows(1, 0), PATHS_PER_SUBMIT as u32);
        for (width, paths) in [(512, 128), (1000, 24), (64, 4096)] {
            let rows = u64::from(traced_strip_rows(width, paths));
            assert!(rows * u64::from(width) * paths <= PATHS_PER_SUBMIT);
        }
    }

    /// A tall image drawn in strips (one submit each, viewport moved per strip) equals the same
    /// image drawn in one pass, under synchronisation validation: every sample keeps its window
    /// position, so coverage is identical and shading differs only by rounding.
    #[test]
    fn strips_draw_the_same_image_as_one_pass() {
        let gpu = GpuContext::new(&ContextOptions {
            validation: true,
            synchronization_validation: true,
            ..ContextOptions::default()
        })
        .expect("validated Vulkan context");
        let mesh = BuiltinMesh::Bowl.mesh();
        let material = LacquerMaterial::preset("smooth-red").unwrap();
        let (brdf, fresnel) = (
            material.brdf_params().unwrap(),
            material.fresnel_table().unwrap(),
        );
        let camera = Camera {
            eye: glam::DVec3::new(0.0, 2.2, 3.2),
            target: glam::DVec3::new(0.0, 0.3, 0.0),
            up: glam::DVec3::Y,
            fov_deg: 30.0,
        };
        let lights = crate::raster::default_lights();
        let objects = [DrawObject {
            mesh: &mesh,
            brdf: &brdf,
            fresnel: &fresnel,
            view_blur: ViewBlur::of(&material),
        }];
        let scene = DrawScene {
            objects: &objects,
            camera: &camera,
            lights: &lights,
            environment: None,
            environment_model: Default::default(),
            ray_tracing: None,
            background: Background::Color([0.1, 0.2, 0.3]),
        };
        let settings = RenderSettings {
            width: 64,
            height: 50,
            samples: 4,
        };
        let whole = LacquerRenderer::new()
            .render(&gpu, &scene, &settings)
            .unwrap();
        let mut strips = LacquerRenderer::new();
        // 7 rows per strip: 8 submits, the last one partial.
        strips.set_color_target_budget(64 * 4 * 16 * 7);
        let striped = strips.render(&gpu, &scene, &settings).unwrap();
        // Twice: the second draw reuses the targets (barriers against the previous use).
        let again = strips.render(&gpu, &scene, &settings).unwrap();
        gpu.check_validation().unwrap();
        let covered = whole.pixels.iter().filter(|p| p[3] > 0.0).count();
        assert!(
            covered > 200,
            "the bowl covers the image ({covered} pixels)"
        );
        // Not bit-identical: llvmpipe sets up each triangle's attribute planes relative to the
        // render area, so interpolated normals and positions differ in the last bits (measured:
        // ≤ 1.1e-4 relative on radiance ~0.1–1, the specular lobe amplifying the normal's last
        // bits). Coverage must not change at all, and the colour only at that rounding level:
        // 1e-3 relative, ~10× the measured worst case and 10× below the oracle bound (1 %).
        for (i, (a, b)) in whole.pixels.iter().zip(&striped.pixels).enumerate() {
            assert_eq!(a[3], b[3], "coverage of pixel {i} changed: {a:?} vs {b:?}");
            for c in 0..3 {
                let scale = a[c].abs().max(b[c].abs()).max(1e-3);
                assert!(
                    (a[c] - b[c]).abs() <= 1e-3 * scale,
                    "pixel {i} channel {c}: one pass {} vs strips {}",
                    a[c],
                    b[c]
                );
            }
        }
        assert!(
            striped.pixels == again.pixels,
            "a second striped draw differs"
        );
    }
}
