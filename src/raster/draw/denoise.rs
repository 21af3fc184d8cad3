//! The optional denoise of SPEC §6's integral term alone (issue 17): a joint-bilateral filter of
//! the integral image the ray-traced shading pass writes beside the image, guided by the image
//! without it and by the estimate's own variance.
//!
//! ```text
//!  image     = the draw (with the integral, unclamped) integral = its estimate I (rgb) and the
//!  base      = image − I (lights with visibility         variance v of its grey value
//!              + environment: no noise)                  (alpha; −1: no object)
//!  out       = max(base + Σ w·I / Σ w, 0)
//!  w(p, q)   = spatial Gaussian(σ) × guide similarity(base_p, base_q) × estimate similarity
//!  estimate similarity = exp(−(Ī_p − Ī_q)² / (2·k²·(v̄_p + v̄_q))), v̄ the 3×3 mean of v
//! ```
//! The base image has no noise and keeps every edge the objects and their lighting make, so the
//! filter averages the integral's noise across a surface without carrying it over an edge. The
//! variance keeps the edges the integral alone has (a bowl mirrored in the tray: the tray's base
//! is flat across the bowl's mirror image): a difference well above what the rays' noise
//! explains is structure and is not averaged. It is deterministic (plain sums in a fixed order,
//! no state between draws). σ shrinks as 1/√rays, so the error against the converged integral
//! still falls as `rays` grows: from 256 rays on the filter is off and the image is the draw
//! itself. Where the integral is 0 (nothing to meet) the output is the draw bit for bit.
//!
//! It runs on the device ([`DenoisePass`]: denoise_guide.comp, then denoise_filter.comp, over the
//! draw's readback buffers, the image filtered in place) so that a GPU's draw does not wait for a
//! host loop over every pixel (0.5 s at 1024², 8 rays, on one core); [`denoise`] is its CPU twin,
//! both driven by [`denoise_params`], and the host path where the image does not fit the
//! device's storage-buffer range.

use crate::gpu::shaders::interface::{
    DenoiseParams, DENOISE_GUIDE_BINDING, DENOISE_IMAGE_BINDING, DENOISE_INTEGRAL_BINDING,
    DENOISE_WORKGROUP,
};
use crate::gpu::{
    Access, Binding, BindingKind, Buffer, BufferDesc, BufferUsage, ComputePipeline, GpuContext,
    Resource, TimestampPool,
};
use crate::output::HdrImage;
use crate::Result;

/// σ of the spatial Gaussian at 8 rays, in pixels; at other counts σ = this · √(8/rays).
/// Measured in BENCHMARKS.md ("Light between objects").
pub const DENOISE_SIGMA_AT_8_RAYS: f64 = 2.0;
/// The guide difference (per channel, relative: |a − b|/(a + b)) at which a neighbour's weight
/// falls to e^{−½}.
pub const DENOISE_GUIDE_TOLERANCE: f64 = 0.1;
/// k: the estimate difference, in standard deviations of the difference the rays' noise gives,
/// at which a neighbour's weight falls to e^{−½}. Measured in BENCHMARKS.md.
pub const DENOISE_NOISE_TOLERANCE: f64 = 3.0;
/// Below this σ (pixels) the filter is off (from 256 rays): the noise is under the blur it adds.
const SMALLEST_SIGMA: f64 = 0.5;

/// The filter's σ in pixels for `rays` rays per shaded point; `None` where it is off.
pub fn denoise_sigma(rays: u32) -> Option<f64> {
    let sigma = DENOISE_SIGMA_AT_8_RAYS * (8.0 / f64::from(rays.max(1))).sqrt();
    (sigma >= SMALLEST_SIGMA).then_some(sigma)
}

/// −ln of the smallest weight a neighbour keeps.
const MAX_EXPONENT: f32 = 20.0;

/// The filter's constants for a `width` × `height` image at `sigma` pixels, as both the host
/// filter and the shaders read them: the radius 2σ (rounded up), 1/(2σ²), the guide's
/// 1/(2·tolerance²) (the tolerance doubled: a difference of logs is twice the relative one),
/// 2·k², and the largest −ln w kept.
pub fn denoise_params(width: u32, height: u32, sigma: f64) -> DenoiseParams {
    let tolerance = 2.0 * DENOISE_GUIDE_TOLERANCE as f32;
    DenoiseParams {
        size: [width, height, (2.0 * sigma).ceil() as u32, 0],
        weights: [
            (1.0 / (2.0 * sigma * sigma)) as f32,
            1.0 / (2.0 * tolerance * tolerance),
            2.0 * (DENOISE_NOISE_TOLERANCE * DENOISE_NOISE_TOLERANCE) as f32,
            MAX_EXPONENT,
        ],
    }
}

/// What the filter reads of a covered pixel.
struct Pixel {
    /// The image without the integral.
    base: [f32; 3],
    /// ln of `base`: a difference of logs is the relative difference, 2(a − b)/(a + b) for
    /// small ones (so the tolerance doubles).
    guide: [f32; 3],
    integral: [f32; 3],
    /// The integral's grey value (r + g + b)/3, what `variance` is of.
    grey: f32,
    variance: f32,
}

impl Pixel {
    fn new(image: &[f32; 4], integral: &[f32; 4], variance: f32) -> Self {
        let base: [f32; 3] = std::array::from_fn(|c| image[c] - integral[c]);
        Pixel {
            base,
            guide: base.map(|b| (b.max(0.0) + 1e-6).ln()),
            integral: [integral[0], integral[1], integral[2]],
            grey: (integral[0] + integral[1] + integral[2]) / 3.0,
            variance,
        }
    }
}

/// `image` (the draw, not yet clamped at 0) with its integral estimate (`integral`, the same
/// size: the draw's integral image, `LacquerRenderer::render_with_integral`) filtered at `sigma`
/// pixels, then clamped at 0: the clamp after the average, where a clamp of each noisy pixel
/// would bias dark surfaces upwards. Pixels that no object covers (alpha < 0 in `integral`) are
/// `image`'s, and only covered neighbours enter a covered pixel's average.
pub fn denoise(image: &HdrImage, integral: &HdrImage, sigma: f64) -> HdrImage {
    let (width, height) = (image.width as usize, image.height as usize);
    if width == 0 {
        return image.clone();
    }
    let params = denoise_params(image.width, image.height, sigma);
    let radius = params.size[2] as usize;
    let [spatial_scale, inv_tolerance2, noise_tolerance2, max_exponent] = params.weights;
    // −ln of the spatial Gaussian by distance along one axis.
    let spatial: Vec<f32> = (0..=radius)
        .map(|d| (d * d) as f32 * spatial_scale)
        .collect();
    let covered = |i: usize| integral.pixels[i][3] >= 0.0;
    // The variance's 3×3 mean over covered pixels: one pixel's few rays estimate it poorly.
    let variance = |i: usize| {
        let (x, y) = (i % width, i / width);
        let (mut sum, mut count) = (0.0f32, 0.0f32);
        for qy in y.saturating_sub(1)..(y + 2).min(height) {
            for qx in x.saturating_sub(1)..(x + 2).min(width) {
                let q = qy * width + qx;
                if covered(q) {
                    sum += integral.pixels[q][3];
                    count += 1.0;
                }
            }
        }
        sum / count.max(1.0)
    };
    let pixels: Vec<Option<Pixel>> = (0..image.pixels.len())
        .map(|i| covered(i).then(|| Pixel::new(&image.pixels[i], &integral.pixels[i], variance(i))))
        .collect();
    let mut out = image.clone();
    let filter_row = |y: usize, row: &mut [[f32; 4]]| {
        let rows = y.saturating_sub(radius)..(y + radius + 1).min(height);
        for (x, pixel) in row.iter_mut().enumerate() {
            let Some(own) = &pixels[y * width + x] else {
                continue;
            };
            let (mut sum, mut weights) = ([0.0f32; 3], 0.0f32);
            for qy in rows.clone() {
                let from_y = spatial[qy.abs_diff(y)];
                for qx in x.saturating_sub(radius)..(x + radius + 1).min(width) {
                    let Some(other) = &pixels[qy * width + qx] else {
                        continue;
                    };
                    let difference: f32 = (0..3)
                        .map(|c| (own.guide[c] - other.guide[c]).powi(2))
                        .sum();
                    let spread = noise_tolerance2 * (own.variance + other.variance);
                    let estimate = (own.grey - other.grey).powi(2);
                    // No noise on either side (every ray agreed): only an equal estimate joins.
                    let from_estimate = match (spread > 0.0, estimate == 0.0) {
                        (true, _) => estimate / spread,
                        (false, true) => 0.0,
                        (false, false) => continue,
                    };
                    // −ln w: the three factors' exponents, in one exp. A weight below e^−20
                    // (2e-9, against the pixel's own 1) is left out.
                    let exponent = from_y
                        + spatial[qx.abs_diff(x)]
                        + difference * inv_tolerance2
                        + from_estimate;
                    if exponent > max_exponent {
                        continue;
                    }
                    let w = (-exponent).exp();
                    for (sum, integral) in sum.iter_mut().zip(other.integral) {
                        *sum += w * integral;
                    }
                    weights += w;
                }
            }
            // The pixel itself weighs 1 (covered, no difference to itself): weights ≥ 1.
            for c in 0..3 {
                pixel[c] = (own.base[c] + sum[c] / weights).max(0.0);
            }
        }
    };
    // One thread, the caller's: a thread the library started (or std's handle for a scoped
    // one's parent) would outlive the call in a C caller's process, which valgrind reports
    // through the C API. The filter is a small share of a ray-traced draw (BENCHMARKS.md).
    for (y, row) in out.pixels.chunks_mut(width).enumerate() {
        filter_row(y, row);
    }
    out
}

/// The bindings of both steps (one layout): image, integral image, guide.
const BINDINGS: [Binding; 3] = [
    Binding::new(DENOISE_IMAGE_BINDING, BindingKind::StorageBuffer),
    Binding::new(DENOISE_INTEGRAL_BINDING, BindingKind::StorageBuffer),
    Binding::new(DENOISE_GUIDE_BINDING, BindingKind::StorageBuffer),
];

/// The denoise on the device, the twin of [`denoise`]: its two pipelines, made once, and the
/// guide buffer of the last image size.
pub(crate) struct DenoisePass {
    guide: ComputePipeline,
    filter: ComputePipeline,
    guide_buffer: Option<Buffer>,
}

impl DenoisePass {
    pub fn new(gpu: &GpuContext) -> Result<Self> {
        use crate::gpu::shaders::{DENOISE_FILTER_COMP, DENOISE_GUIDE_COMP};
        let push = std::mem::size_of::<DenoiseParams>() as u32;
        Ok(DenoisePass {
            guide: gpu.create_compute_pipeline(
                "denoise_guide.comp",
                DENOISE_GUIDE_COMP,
                &BINDINGS,
                push,
            )?,
            filter: gpu.create_compute_pipeline(
                "denoise_filter.comp",
                DENOISE_FILTER_COMP,
                &BINDINGS,
                push,
            )?,
            guide_buffer: None,
        })
    }

    /// Whether a `width` × `height` RGBA32F image fits one storage-buffer binding of `gpu`
    /// (otherwise the host filters it).
    pub fn fits(gpu: &GpuContext, width: u32, height: u32) -> bool {
        image_bytes(width, height) <= u64::from(gpu.info().max_storage_buffer_range)
    }

    /// Filters `image` (a draw's readback buffer, unclamped) in place with its `integral` image
    /// (the same size), as [`denoise`] does on the host; both buffers were last written by the
    /// strips' copy-outs. Submits and waits; the image is then ready for the host to read. With
    /// `stamps` (at least two), returns the pass's GPU time in seconds.
    pub fn run(
        &mut self,
        gpu: &GpuContext,
        (image, integral): (&Buffer, &Buffer),
        params: &DenoiseParams,
        stamps: Option<&TimestampPool>,
    ) -> Result<f64> {
        let (width, height) = (params.size[0], params.size[1]);
        let bytes = image_bytes(width, height);
        if self.guide_buffer.as_ref().map(Buffer::size) != Some(bytes) {
            // Another size: the old guide is freed before the new one is made.
            self.guide_buffer = None;
        }
        let guide = &*super::get_or_try_insert(&mut self.guide_buffer, || {
            let desc = BufferDesc::device_local("denoise guide", bytes, BufferUsage::STORAGE);
            Ok(gpu.create_buffer(desc)?)
        })?;
        let resources = [
            (DENOISE_IMAGE_BINDING, Resource::Buffer(image)),
            (DENOISE_INTEGRAL_BINDING, Resource::Buffer(integral)),
            (DENOISE_GUIDE_BINDING, Resource::Buffer(guide)),
        ];
        let guide_set = gpu.create_descriptor_set(self.guide.layout(), &resources)?;
        let filter_set = gpu.create_descriptor_set(self.filter.layout(), &resources)?;
        let groups = (
            width.div_ceil(DENOISE_WORKGROUP),
            height.div_ceil(DENOISE_WORKGROUP),
        );
        let constants = bytemuck::bytes_of(params);
        gpu.submit_and_wait(|rec| {
            if let Some(pool) = stamps {
                rec.reset_timestamps(pool);
                rec.timestamp(pool, 0);
            }
            // The copy-outs wrote both images (read by both steps, the image written by the
            // second); the last denoise read and wrote the guide.
            rec.memory_barrier(Access::TransferWrite, Access::ComputeShaderRead);
            rec.memory_barrier(Access::TransferWrite, Access::ComputeShaderWrite);
            rec.memory_barrier(Access::ComputeShaderWrite, Access::ComputeShaderWrite);
            rec.bind_compute(&self.guide, &guide_set);
            rec.push_constants(&self.guide, constants);
            rec.dispatch(groups.0, groups.1, 1);
            rec.memory_barrier(Access::ComputeShaderWrite, Access::ComputeShaderRead);
            rec.bind_compute(&self.filter, &filter_set);
            rec.push_constants(&self.filter, constants);
            rec.dispatch(groups.0, groups.1, 1);
            rec.memory_barrier(Access::ComputeShaderWrite, Access::HostRead);
            if let Some(pool) = stamps {
                rec.timestamp(pool, 1);
            }
            Ok(())
        })?;
        Ok(match stamps {
            Some(pool) => match pool.read_ns(2)?[..] {
                [start, end] => (end - start).max(0.0) * 1e-9,
                _ => 0.0,
            },
            None => 0.0,
        })
    }
}

fn image_bytes(width: u32, height: u32) -> u64 {
    u64::from(width) * u64::from(height) * 16
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, f: impl Fn(u32, u32) -> [f32; 4]) -> HdrImage {
        let mut image = HdrImage::new(width, height);
        for y in 0..height {
            for x in 0..width {
                image.pixels[(y * width + x) as usize] = f(x, y);
            }
        }
        image
    }

    /// The integral image of a draw `full` whose base is `base`: full − base, alpha `variance`
    /// where `base` is covered (alpha > 0), −1 elsewhere.
    fn integral_of(full: &HdrImage, base: &HdrImage, variance: f32) -> HdrImage {
        image(full.width, full.height, |x, y| {
            let i = (y * full.width + x) as usize;
            let (f, b) = (full.pixels[i], base.pixels[i]);
            match b[3] > 0.0 {
                true => [f[0] - b[0], f[1] - b[1], f[2] - b[2], variance],
                false => [0.0, 0.0, 0.0, -1.0],
            }
        })
    }

    /// A number in [−1, 1) from the pixel, the same on every run.
    fn noise(x: u32, y: u32) -> f32 {
        let h = crate::oracle::light_between::sequence::hash_u32(x ^ (y << 16));
        (h >> 8) as f32 / 8_388_608.0 - 1.0
    }

    #[test]
    fn sigma_narrows_with_rays_and_switches_off() {
        assert_eq!(denoise_sigma(8), Some(2.0));
        assert_eq!(denoise_sigma(32), Some(1.0));
        assert_eq!(denoise_sigma(128), Some(0.5));
        assert_eq!(denoise_sigma(256), None);
        assert!(denoise_sigma(1).unwrap() > denoise_sigma(2).unwrap());
    }

    #[test]
    fn no_integral_leaves_the_draw_bit_for_bit() {
        let base = image(16, 12, |x, y| [0.1 * x as f32, 0.05 * y as f32, 0.3, 1.0]);
        for variance in [0.0, 0.01] {
            let out = denoise(&base, &integral_of(&base, &base, variance), 2.0);
            assert!(out.pixels == base.pixels);
        }
    }

    #[test]
    fn noise_on_one_surface_is_averaged_and_its_mean_kept() {
        // One flat surface (constant guide), integral 0.2 ± 0.1 noise whose variance the rays
        // report (uniform on ±0.1: 0.1²/3): the filter leaves the mean and cuts the spread by
        // about the kernel's effective tap count (4πσ² ≈ 50 at σ 2).
        let base = image(64, 64, |_, _| [0.3, 0.3, 0.3, 1.0]);
        let full = image(64, 64, |x, y| {
            let v = 0.5 + 0.1 * noise(x, y);
            [v, v, v, 1.0]
        });
        let out = denoise(&full, &integral_of(&full, &base, 0.01 / 3.0), 2.0);
        let values: Vec<f64> = out.pixels.iter().map(|p| f64::from(p[0]) - 0.3).collect();
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let spread =
            (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / values.len() as f64).sqrt();
        // The input's spread: 0.1/√3 (uniform on ±0.1) = 0.058.
        assert!((mean - 0.2).abs() < 2e-3, "mean {mean}");
        assert!(spread < 0.058 / 4.0, "spread {spread}");
    }

    #[test]
    fn the_integral_does_not_cross_an_edge_of_the_guide() {
        // Two surfaces side by side (guide 0.1 | 0.8), the integral +0.05 on the left, −0.2 on
        // the right, as noisy as the difference: each side keeps its own, up to the edge.
        let base = image(32, 8, |x, _| match x < 16 {
            true => [0.1, 0.1, 0.1, 1.0],
            false => [0.8, 0.8, 0.8, 1.0],
        });
        let full = image(32, 8, |x, _| match x < 16 {
            true => [0.15, 0.15, 0.15, 1.0],
            false => [0.6, 0.6, 0.6, 1.0],
        });
        let out = denoise(&full, &integral_of(&full, &base, 0.1), 2.0);
        for y in 0..8 {
            let (left, right) = (out.pixels[y * 32 + 15], out.pixels[y * 32 + 16]);
            // Guide difference 0.78 relative: weight e^{−30} across the edge.
            assert!((left[0] - 0.15).abs() < 1e-6, "{left:?}");
            assert!((right[0] - 0.6).abs() < 1e-6, "{right:?}");
        }
    }

    #[test]
    fn an_edge_of_the_integral_alone_stays_where_the_rays_agree() {
        // A flat base (the tray) and an integral with an edge of its own (a bowl mirrored in
        // it): 0.05 | 0.3, each side's rays agreeing (variance 1e-6, σ 1e-3): a difference of
        // 250 σ is structure, not noise, and stays sharp. The same edge where the rays disagree
        // as much as the difference (variance 0.01) is averaged across.
        let base = image(32, 8, |_, _| [0.2, 0.2, 0.2, 1.0]);
        let full = image(32, 8, |x, _| match x < 16 {
            true => [0.25, 0.25, 0.25, 1.0],
            false => [0.5, 0.5, 0.5, 1.0],
        });
        let sharp = denoise(&full, &integral_of(&full, &base, 1e-6), 2.0);
        let blurred = denoise(&full, &integral_of(&full, &base, 0.01), 2.0);
        for y in 0..8 {
            let (left, right) = (sharp.pixels[y * 32 + 15], sharp.pixels[y * 32 + 16]);
            assert!((left[0] - 0.25).abs() < 1e-6, "{left:?}");
            assert!((right[0] - 0.5).abs() < 1e-6, "{right:?}");
            let (left, right) = (blurred.pixels[y * 32 + 15], blurred.pixels[y * 32 + 16]);
            assert!(left[0] > 0.3 && right[0] < 0.45, "{left:?} {right:?}");
        }
    }

    #[test]
    fn uncovered_pixels_are_the_draws_and_are_not_averaged_in() {
        let base = image(16, 16, |x, _| match x < 8 {
            true => [0.2, 0.2, 0.2, 0.0],
            false => [0.2, 0.2, 0.2, 1.0],
        });
        let full = image(16, 16, |x, _| match x < 8 {
            true => [0.2, 0.2, 0.2, 0.0],
            false => [0.3, 0.3, 0.3, 1.0],
        });
        let out = denoise(&full, &integral_of(&full, &base, 0.01), 2.0);
        for (p, f) in out.pixels.iter().zip(&full.pixels) {
            assert!((p[0] - f[0]).abs() < 1e-6, "{p:?} vs {f:?}");
        }
    }

    #[test]
    fn a_negative_estimate_is_clamped_after_the_filter() {
        let base = image(8, 8, |_, _| [0.01, 0.01, 0.01, 1.0]);
        let mut full = image(8, 8, |_, _| [0.0, 0.0, 0.0, 1.0]);
        // One pixel's integral far below −base: the average of the neighbourhood stays negative.
        full.pixels[27] = [-1.0, -1.0, -1.0, 1.0];
        let out = denoise(&full, &integral_of(&full, &base, 1.0), 2.0);
        assert!(out.pixels.iter().all(|p| p[0] >= 0.0));
    }
}
