//! The render targets of one image size and sample count — colour (MSAA), resolve, depth and the
//! host-visible readback buffer — kept between renders so a batch of same-sized images allocates
//! them once (at 1024² with 4× MSAA they are ~110 MB; allocating and freeing them per image cost
//! more than the copy-out).
//!
//! Tall images are drawn in horizontal strips (one submit each) into targets of
//! [`MAX_COLOR_TARGET_BYTES`] at most, each strip copied to its rows of the full-size readback
//! buffer: the 4× MSAA RGBA32F colour target of a 1024² image alone would be 64 MiB, most of the
//! render's peak memory. Images up to 512² with 4× MSAA fit one strip and are drawn in one pass.
//!
//! Reuse across submits is safe because every render starts with barriers whose first scope is
//! the previous render's last use of each target (pipeline barriers order against all earlier
//! submissions on the queue), and every render clears what it draws into.

use crate::gpu::{Buffer, BufferDesc, GpuContext, Image, ImageDesc};
use crate::Result;

/// Width, height, samples.
pub(crate) type TargetKey = (u32, u32, u32);

/// Largest multisampled colour target (bytes); the depth target is a quarter of it.
pub const MAX_COLOR_TARGET_BYTES: u64 = 16 << 20;

/// Rows per strip for an image `width` wide with `samples` per pixel (RGBA32F samples), the
/// colour target holding at most `budget` bytes.
pub fn strip_rows(width: u32, height: u32, samples: u32, budget: u64) -> u32 {
    let row_bytes = u64::from(width) * u64::from(samples) * 16;
    let rows = (budget / row_bytes.max(1)).max(1);
    rows.min(u64::from(height)) as u32
}

pub(crate) struct DrawTargets {
    pub key: TargetKey,
    /// Rows of the image each target holds (the last strip may use fewer).
    pub strip_rows: u32,
    pub color: Image,
    /// The single-sampled image the MSAA colour resolves into (None without MSAA).
    pub resolve: Option<Image>,
    pub depth: Image,
    pub readback: Buffer,
    /// Whether a render used these targets before (then the first barriers wait for that use).
    pub used: bool,
}

impl DrawTargets {
    pub fn new(gpu: &GpuContext, (width, height, samples): TargetKey, budget: u64) -> Result<Self> {
        let rows = strip_rows(width, height, samples, budget);
        let color = gpu.create_image(ImageDesc::color_target("color", width, rows, samples))?;
        let resolve = if samples > 1 {
            Some(gpu.create_image(ImageDesc::color_target("resolve", width, rows, 1))?)
        } else {
            None
        };
        let depth = gpu.create_image(ImageDesc::depth_target("depth", width, rows, samples))?;
        let image_bytes = u64::from(width) * u64::from(height) * 16;
        let readback = gpu.create_buffer(BufferDesc::readback("readback", image_bytes))?;
        Ok(DrawTargets {
            key: (width, height, samples),
            strip_rows: rows,
            color,
            resolve,
            depth,
            readback,
            used: false,
        })
    }

    /// The single-sampled image copied to the readback buffer.
    pub fn output(&self) -> &Image {
        self.resolve.as_ref().unwrap_or(&self.color)
    }
}

/// Holds the targets of the last size used: a new size replaces them (batches render one size;
/// keeping several 100 MB sets would only raise peak memory).
pub(crate) struct TargetCache {
    current: Option<DrawTargets>,
    /// Colour target budget in bytes ([`MAX_COLOR_TARGET_BYTES`]; smaller in tests).
    pub color_budget: u64,
}

impl Default for TargetCache {
    fn default() -> Self {
        TargetCache {
            current: None,
            color_budget: MAX_COLOR_TARGET_BYTES,
        }
    }
}

impl TargetCache {
    pub fn get(&mut self, gpu: &GpuContext, key: TargetKey) -> Result<&mut DrawTargets> {
        if self.current.as_ref().map(|t| t.key) != Some(key) {
            // Free the old set before allocating the new one: peak memory is one set.
            self.current = None;
            self.current = Some(DrawTargets::new(gpu, key, self.color_budget)?);
        }
        match self.current.as_mut() {
            Some(targets) => Ok(targets),
            None => Err(crate::Error::invalid(
                "render targets",
                "missing",
                "internal error",
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::environment::params::ViewBlur;
    use crate::gpu::{ContextOptions, GpuContext};
    use crate::model::LacquerMaterial;
    use crate::raster::draw::{Background, DrawObject, DrawScene, LacquerRenderer, RenderSettings};
    use crate::raster::mesh::BuiltinMesh;
    use crate::raster::Camera;

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
