//! The brute-force path tracer's environment map: radiance by direction and a sampler of
//! directions in proportion to it, so that a real HDRI's small bright regions (a studio's light
//! boxes, a sun) are found by a few thousand paths instead of a few million.
//!
//! The map is piecewise constant over its pixels (nearest pixel, no filtering): the radiance SPEC
//! §4's brute-force definitions integrate (`environment::brdf_definition`,
//! `environment::definition`). A pixel is drawn with probability ∝ (mean of its rgb) × (its solid
//! angle), then a direction uniform in solid angle inside it (cos θ uniform between the row's
//! bounds, φ uniform across the column), so the density per steradian is exactly
//! p_pixel / Ω_pixel, constant over the pixel. Every pixel with any light has a positive weight
//! (the loader keeps no negative values), so the sampler alone is unbiased; the path tracer
//! combines it with its BRDF sampler by multiple importance sampling.

use std::f64::consts::{PI, TAU};

use glam::DVec3;

use crate::environment::cube::{
    direction_to_equirect, equirect_row_solid_angle, world_to_environment,
};
use crate::environment::{EnvironmentLight, Equirect};

/// A map prepared for the path tracer: the map, how it lights the world, and the cumulative
/// distributions of its pixels' weights (rows, then columns within each row).
pub struct MapSampler<'a> {
    image: &'a Equirect,
    light: EnvironmentLight,
    /// `rows[y]` = Σ of the weights of rows 0..=y, over the whole map's (the last is 1).
    rows: Vec<f64>,
    /// `columns[y·width + x]` = Σ of row y's weights of columns 0..=x over the row's.
    columns: Vec<f64>,
    /// Σ over pixels of weight, in units of (radiance × steradian).
    total: f64,
}

impl<'a> MapSampler<'a> {
    /// `None` where the map holds no light at all (every path then escapes to black).
    pub fn new(image: &'a Equirect, light: EnvironmentLight) -> Option<Self> {
        let (width, height) = (image.width as usize, image.height as usize);
        let mut rows = Vec::with_capacity(height);
        let mut columns = Vec::with_capacity(width * height);
        let mut total = 0.0;
        for y in 0..height {
            let solid_angle = equirect_row_solid_angle(y as u32, image.width, image.height);
            let row_start = columns.len();
            let mut row = 0.0;
            for x in 0..width {
                row += weight(image.get(x as u32, y as u32)) * solid_angle;
                columns.push(row);
            }
            if row > 0.0 {
                columns[row_start..].iter_mut().for_each(|c| *c /= row);
            }
            total += row;
            rows.push(total);
        }
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        rows.iter_mut().for_each(|r| *r /= total);
        Some(Self {
            image,
            light,
            rows,
            columns,
            total,
        })
    }

    /// L(s) for a unit world direction: the pixel holding it × the light's intensity.
    pub fn radiance(&self, world: DVec3) -> DVec3 {
        let (x, y) = self.pixel_of(world);
        let rgb = self.image.get(x, y).map(f64::from);
        DVec3::from_array(rgb) * self.light.intensity
    }

    /// The density per steradian with which [`sample`](Self::sample) draws `world`: the pixel's
    /// probability weight·Ω/total over its solid angle Ω.
    pub fn pdf(&self, world: DVec3) -> f64 {
        let (x, y) = self.pixel_of(world);
        weight(self.image.get(x, y)) / self.total
    }

    /// A unit world direction drawn from [`pdf`](Self::pdf) with the three uniform numbers `u`.
    pub fn sample(&self, u: [f64; 3]) -> DVec3 {
        let (width, height) = (self.image.width, self.image.height);
        let y = first_at_least(&self.rows, u[0]);
        let row = &self.columns[y * width as usize..(y + 1) * width as usize];
        let x = first_at_least(row, u[1]);
        let (top, bottom) = (
            (PI * y as f64 / f64::from(height)).cos(),
            (PI * (y + 1) as f64 / f64::from(height)).cos(),
        );
        let cos_theta = top + (bottom - top) * u[2];
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        // φ uniform across the column: the sub-position comes from where u[1] fell inside it.
        let (lo, hi) = (if x == 0 { 0.0 } else { row[x - 1] }, row[x]);
        let within = if hi > lo {
            ((u[1] - lo) / (hi - lo)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let phi = TAU * ((x as f64 + within) / f64::from(width) - 0.5);
        let local = DVec3::new(sin_theta * phi.sin(), cos_theta, -sin_theta * phi.cos());
        // The map's frame back to the world's: the inverse turn about +Y.
        world_to_environment(local, -self.light.rotation_deg)
    }

    /// The pixel holding a unit world direction.
    fn pixel_of(&self, world: DVec3) -> (u32, u32) {
        let local = world_to_environment(world, self.light.rotation_deg);
        let (u, v) = direction_to_equirect(local);
        let (width, height) = (self.image.width, self.image.height);
        let x = ((u * f64::from(width)).floor().max(0.0) as u32).min(width - 1);
        let y = ((v * f64::from(height)).floor().max(0.0) as u32).min(height - 1);
        (x, y)
    }
}

/// The first index whose cumulative value is at least `u` and that holds some probability, for a
/// non-decreasing `cdf` ending at 1 (the last index for u ≥ 1 and rounding).
fn first_at_least(cdf: &[f64], u: f64) -> usize {
    let before = |i: usize| if i == 0 { 0.0 } else { cdf[i - 1] };
    let mut i = cdf.partition_point(|&c| c < u).min(cdf.len() - 1);
    while i + 1 < cdf.len() && cdf[i] <= before(i) {
        i += 1;
    }
    i
}

/// A pixel's weight per steradian: the mean of its channels (never negative).
fn weight(rgb: [f32; 3]) -> f64 {
    ((f64::from(rgb[0]) + f64::from(rgb[1]) + f64::from(rgb[2])) / 3.0).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::environment::definition::irradiance_definition;

    /// A 64 × 32 map: a dim gradient, a row of black (which must never be drawn), and a disc
    /// ~10° across 500× brighter than the rest.
    fn map() -> Equirect {
        let sun = DVec3::new(0.5, 0.6, -0.3).normalize();
        let mut image = Equirect::from_fn(64, 32, |s| {
            let base = 0.2 + 0.1 * s.y;
            let bright = if s.dot(sun) > 0.9962 { 100.0 } else { 0.0 };
            [
                (base + bright) as f32,
                (0.8 * base + bright) as f32,
                base as f32,
            ]
        });
        for x in 0..64 {
            image.pixels[5 * 64 + x] = [0.0; 3];
        }
        image
    }

    fn uniform(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Each draw lands in a pixel with light, at a density the pdf states (the sample mean of
    /// 1/pdf is the solid angle of the pixels with light), and the estimate of the irradiance E(n) = E[L·max(n·s, 0)/pdf]
    /// matches SPEC §4's definition summed over the pixels, turned and scaled as the light says.
    /// Bounds: 4 standard errors of the sample mean, plus 2e-3 for the definition's pixel-centre
    /// cosine on a 5.6° grid.
    #[test]
    fn draws_follow_the_pdf_and_estimate_the_irradiance() {
        let image = map();
        let light = EnvironmentLight {
            intensity: 1.5,
            rotation_deg: 30.0,
        };
        let sampler = MapSampler::new(&image, light).unwrap();
        let normals = [DVec3::Y, DVec3::new(0.4, 0.3, -0.6).normalize(), -DVec3::X];
        let count = 400_000;
        let mut state = 1u64;
        let mut inverse = (0.0, 0.0);
        let mut irradiance = vec![(DVec3::ZERO, DVec3::ZERO); normals.len()];
        for _ in 0..count {
            let u = [(); 3].map(|_| uniform(&mut state));
            let s = sampler.sample(u);
            assert!((s.length() - 1.0).abs() < 1e-12);
            let pdf = sampler.pdf(s);
            assert!(pdf > 0.0, "drew a black pixel at {s}");
            inverse.0 += 1.0 / pdf;
            inverse.1 += 1.0 / (pdf * pdf);
            for (n, sums) in normals.iter().zip(&mut irradiance) {
                let x = sampler.radiance(s) * n.dot(s).max(0.0) / pdf;
                sums.0 += x;
                sums.1 += x * x;
            }
        }
        let count = f64::from(count);
        let mean_and_error = |(sum, squares): (f64, f64)| {
            let mean = sum / count;
            (mean, ((squares / count - mean * mean) / count).sqrt())
        };
        // E[1/pdf] is the solid angle the draws can reach: the sphere less the black row.
        let (sphere, error) = mean_and_error(inverse);
        let reach = 4.0 * PI - 64.0 * equirect_row_solid_angle(5, 64, 32);
        assert!(
            (sphere - reach).abs() < 4.0 * error,
            "{sphere} ± {error} vs {reach}"
        );
        for (n, sums) in normals.iter().zip(irradiance) {
            let local = world_to_environment(*n, light.rotation_deg);
            let want = irradiance_definition(&image, local).map(|e| e * light.intensity);
            for (c, want) in want.into_iter().enumerate() {
                let (got, error) = mean_and_error((sums.0[c], sums.1[c]));
                assert!(
                    (got - want).abs() < 4.0 * error + 2e-3 * want,
                    "n {n}, channel {c}: {got} ± {error} vs {want}"
                );
            }
        }
    }

    /// A direction drawn from a pixel is read back from that pixel: the draw and the lookup use
    /// one convention (SPEC §4's, turned by the light).
    #[test]
    fn a_draw_reads_back_the_pixel_it_came_from() {
        let image = Equirect::from_fn(16, 8, |s| [s.x as f32 + 2.0, s.y as f32 + 2.0, 1.0]);
        let light = EnvironmentLight {
            intensity: 1.0,
            rotation_deg: -70.0,
        };
        let sampler = MapSampler::new(&image, light).unwrap();
        let mut state = 9u64;
        for _ in 0..10_000 {
            let u = [(); 3].map(|_| uniform(&mut state));
            let s = sampler.sample(u);
            let (x, y) = sampler.pixel_of(s);
            assert_eq!(
                x as usize,
                first_at_least(&sampler.columns[y as usize * 16..][..16], u[1])
            );
            assert_eq!(y as usize, first_at_least(&sampler.rows, u[0]));
        }
    }

    #[test]
    fn a_black_map_has_no_sampler() {
        let image = Equirect::constant(8, 4, [0.0; 3]);
        assert!(MapSampler::new(&image, EnvironmentLight::default()).is_none());
    }
}
