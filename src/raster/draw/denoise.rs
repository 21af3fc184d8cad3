//! The optional denoise of SPEC §6's integral term alone (issue 17): a joint-bilateral filter of
//! the difference the ray-traced objects make, guided by the same draw without it.
//!
//! ```text
//!  full  = the draw with the integral            ┐
//!  base  = the same draw with bounces = 0        ├─► integral = full − base (per pixel)
//!          (lights with visibility + environment)┘
//!  out   = max(base + Σ w·integral / Σ w, 0),  w = spatial Gaussian(σ) × guide similarity(base)
//! ```
//! The base image has no noise and keeps every edge the objects and their lighting make, so the
//! filter averages the integral's noise across a surface without carrying it over an edge. It is
//! deterministic (plain sums in a fixed order, no state between draws). σ shrinks as 1/√rays, so
//! the error against the converged integral still falls as `rays` grows: from 256 rays on the
//! filter is off and the image is the draw itself. Where the integral is 0 (nothing to meet) the
//! output is the draw bit for bit: base + 0.

use crate::output::HdrImage;

/// σ of the spatial Gaussian at 8 rays, in pixels; at other counts σ = this · √(8/rays).
/// Measured in BENCHMARKS.md ("Light between objects").
pub const DENOISE_SIGMA_AT_8_RAYS: f64 = 2.0;
/// The guide difference (per channel, relative: |a − b|/(a + b)) at which a neighbour's weight
/// falls to e^{−½}.
pub const DENOISE_GUIDE_TOLERANCE: f64 = 0.1;
/// Below this σ (pixels) the filter is off (from 256 rays): the noise is under the blur it adds.
const SMALLEST_SIGMA: f64 = 0.5;

/// The filter's σ in pixels for `rays` rays per shaded point; `None` where it is off.
pub fn denoise_sigma(rays: u32) -> Option<f64> {
    let sigma = DENOISE_SIGMA_AT_8_RAYS * (8.0 / f64::from(rays.max(1))).sqrt();
    (sigma >= SMALLEST_SIGMA).then_some(sigma)
}

/// The composite of `full` (the draw with the integral) and `base` (the same draw without it,
/// same size) with the integral filtered at `sigma` pixels. Pixels that no object covers (alpha
/// 0 in `base`) are `full`'s, and only covered neighbours enter a covered pixel's average.
pub fn denoise(full: &HdrImage, base: &HdrImage, sigma: f64) -> HdrImage {
    let width = full.width as usize;
    let radius = (2.0 * sigma).ceil() as usize;
    let spatial: Vec<f32> = (0..=radius)
        .map(|d| (-((d * d) as f64) / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let integral: Vec<[f32; 3]> = full
        .pixels
        .iter()
        .zip(&base.pixels)
        .map(|(f, b)| std::array::from_fn(|c| f[c] - b[c]))
        .collect();
    // ln of the guide: a difference of logs is the relative difference, 2(a − b)/(a + b) for
    // small ones, so the tolerance doubles; None where no object covers the pixel.
    let guide: Vec<Option<[f32; 3]>> = base
        .pixels
        .iter()
        .map(|b| (b[3] > 0.0).then(|| std::array::from_fn(|c| (b[c].max(0.0) + 1e-6).ln())))
        .collect();
    let tolerance = 2.0 * DENOISE_GUIDE_TOLERANCE as f32;
    let inv_tolerance2 = 1.0 / (2.0 * tolerance * tolerance);
    let mut out = full.clone();
    let filter_row = |y: usize, row: &mut [[f32; 4]]| {
        let rows = y.saturating_sub(radius)..(y + radius + 1).min(full.height as usize);
        for (x, pixel) in row.iter_mut().enumerate() {
            let Some(own) = guide[y * width + x] else {
                continue;
            };
            let (mut sum, mut weights) = ([0.0f32; 3], 0.0f32);
            for qy in rows.clone() {
                let wy = spatial[qy.abs_diff(y)];
                for qx in x.saturating_sub(radius)..(x + radius + 1).min(width) {
                    let q = qy * width + qx;
                    let Some(other) = guide[q] else {
                        continue;
                    };
                    let difference: f32 = (0..3).map(|c| (own[c] - other[c]).powi(2)).sum();
                    let w = wy * spatial[qx.abs_diff(x)] * (-difference * inv_tolerance2).exp();
                    for c in 0..3 {
                        sum[c] += w * integral[q][c];
                    }
                    weights += w;
                }
            }
            // The pixel itself weighs 1 (covered, no guide difference): weights ≥ 1.
            let b = base.pixels[y * width + x];
            for c in 0..3 {
                pixel[c] = (b[c] + sum[c] / weights).max(0.0);
            }
        }
    };
    // One thread, the caller's: a thread the library started (or std's handle for a scoped
    // one's parent) would outlive the call in a C caller's process, which valgrind reports
    // through the C API. The filter is a small share of a ray-traced draw (BENCHMARKS.md).
    let width = width.max(1);
    for (y, row) in out.pixels.chunks_mut(width).enumerate() {
        filter_row(y, row);
    }
    out
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
        let out = denoise(&base, &base, 2.0);
        assert!(out.pixels == base.pixels);
    }

    #[test]
    fn noise_on_one_surface_is_averaged_and_its_mean_kept() {
        // One flat surface (constant guide), integral 0.2 ± 0.1 noise: the filter leaves the
        // mean and cuts the spread by about the kernel's effective tap count (4πσ² ≈ 50 at σ 2).
        let base = image(64, 64, |_, _| [0.3, 0.3, 0.3, 1.0]);
        let full = image(64, 64, |x, y| {
            let v = 0.5 + 0.1 * noise(x, y);
            [v, v, v, 1.0]
        });
        let out = denoise(&full, &base, 2.0);
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
        // the right: each side keeps its own, up to the edge.
        let base = image(32, 8, |x, _| match x < 16 {
            true => [0.1, 0.1, 0.1, 1.0],
            false => [0.8, 0.8, 0.8, 1.0],
        });
        let full = image(32, 8, |x, _| match x < 16 {
            true => [0.15, 0.15, 0.15, 1.0],
            false => [0.6, 0.6, 0.6, 1.0],
        });
        let out = denoise(&full, &base, 2.0);
        for y in 0..8 {
            let (left, right) = (out.pixels[y * 32 + 15], out.pixels[y * 32 + 16]);
            // Guide difference 0.78 relative: weight e^{−30} across the edge.
            assert!((left[0] - 0.15).abs() < 1e-6, "{left:?}");
            assert!((right[0] - 0.6).abs() < 1e-6, "{right:?}");
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
        let out = denoise(&full, &base, 2.0);
        for (p, f) in out.pixels.iter().zip(&full.pixels) {
            assert!((p[0] - f[0]).abs() < 1e-6, "{p:?} vs {f:?}");
        }
    }

    #[test]
    fn a_negative_estimate_is_clamped_after_the_filter() {
        let base = image(8, 8, |_, _| [0.01, 0.01, 0.01, 1.0]);
        let full = image(8, 8, |_, _| [0.0, 0.0, 0.0, 1.0]);
        let mut full = full;
        // One pixel's integral far below −base: the average of the neighbourhood stays negative.
        full.pixels[27] = [-1.0, -1.0, -1.0, 1.0];
        let out = denoise(&full, &base, 2.0);
        assert!(out.pixels.iter().all(|p| p[0] >= 0.0));
    }
}
