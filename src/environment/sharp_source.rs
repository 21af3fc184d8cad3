//! The `brdf` model's sharp reads: the residual map's own pixels, read through a Gaussian of
//! width β narrower than the first blurred layer. Across the plane of incidence a smooth lobe
//! towards grazing is narrower than a pixel of a 1k map (at m = 0.02 and N·V = 0.15, 4.2 mrad
//! against 6.1), and the integral SPEC §4 defines sums the map's pixels as the pieces of constant
//! radiance they are. Layer 0, resampled onto a cube and read bilinearly, moves and smears a
//! one-pixel line by up to a pixel, and a dark point beside it reads it through the lookup's
//! tails: on the studio's light stand, +60 % at the lattice's nodes and +30 % on the board seen
//! 80° from its normal (BENCHMARKS.md, "Reading the map itself below the first blurred layer").
//!
//! A read is the Gaussian of the map's piecewise-constant pixels, separable in the map's columns
//! and rows near the direction d. Pixel (i, j) weighs
//!
//! ```text
//! [Φ((i + 1 − x)/σx) − Φ((i − x)/σx)] · [Φ((j + 1 − y)/σy) − Φ((j − y)/σy)]
//! ```
//!
//! with (x, y) = (u·W, v·H) d's place in pixels, σy = β·H/π and σx = β·W/(2π·sin θ) the
//! Gaussian's width in rows and columns, Φ the normal distribution (erfc of A&S 7.1.26, as the
//! visible-normal sampler has it). The reads go out to
//! `SHARP_REACH`·σ; the lattice asks for β up to `SHARP_SIGMA` pixels of the map there
//! ([`SharpSource::widest_beta`]), so a read covers at most 7 rows of 4 texels (8 pixels).
//!
//! The pixels are stored as the layer texels are (× the environment's intensity, two of a row in
//! one texel, `layer_pair`), after the layers in the same texel buffer; the GPU twin is
//! `sharp_radiance` in shaders/common/brdf_environment.glsl.

use glam::DVec3;

use super::cube::{direction_to_equirect, world_to_environment};
use super::image::Equirect;
use super::layer_pair;
use super::params::EnvironmentLight;
use crate::oracle::visible_normals::erfc_positive;

/// The widest Gaussian a sharp read takes, in the map's pixels (rows, and columns where they
/// are narrower than rows): 1, so that a read at `SHARP_REACH` = 3 covers at most 7 rows of 4
/// texels.
/// On the issue's 112 points at m = 0.02 0.7 of β_1 (6 mrad at 1k, one pixel) and all of it
/// (8.6 mrad) measured the same (studio 0.52 / 6.0 % and 0.50 / 6.0 %), 0.5 of it worse (0.68 /
/// 7.0 %).
pub const SHARP_SIGMA: f64 = 1.0;

/// How far a read reaches, in its σ: 3 (0.3 % of a Gaussian's weight beyond it). At 2 and 2.5
/// the courtyard's board at 80° read 6 % low at one point of the 112 (2.7 % at 3).
pub const SHARP_REACH: f64 = 3.0;

/// The widest map the sharp reads serve: 4096 pixels, whose two residuals take 2 × 64 MiB of
/// texels. Wider maps keep the layers alone: their pixels are under 1.5 mrad, a third of the lobe
/// across the plane at m = 0.02 and N·V = 0.15, and their residuals would take 2 × 128 MiB and
/// more.
pub const SHARP_MAX_WIDTH: u32 = 4096;

/// The lattice's sharp reads, blended out by its node count: all of them up to
/// `SHARP_NODES.0` nodes on each side of the mirror direction, none from `SHARP_NODES.1` (the
/// node count is continuous in `reach/step`, which is what is compared). A lattice that long is
/// a smooth lobe within a few degrees of grazing, whose lookups along the plane average a thin
/// line out: at m = 0.05 (the smooth preset) the lattice's β falls below layer 1's only below
/// N·V = 0.12, with 16.4 nodes a side and more, where the sharp reads changed the 112 points by
/// nothing that matters (courtyard 0.81 → 0.79 %, studio 0.87 → 0.83 %) and cost 7 % of the
/// default scene's `brdf` draw (BENCHMARKS.md). From 16 the smooth preset never reads them; at
/// m = 0.02 they serve every view from N·V = 0.14, blended out down to 0.125.
pub const SHARP_NODES: (f64, f64) = (14.0, 16.0);

/// A residual map as the sharp reads see it: its pixels × intensity, stored as the layer texels
/// are, in the environment's frame (turned by `rotation_deg` about +Y).
#[derive(Clone, Debug, PartialEq)]
pub struct SharpSource {
    pub width: u32,
    pub height: u32,
    /// Row after row, pixels (2i, 2i + 1) in texel i of the row (`layer_pair::pack`).
    pub texels: Vec<[u32; 4]>,
    pub rotation_deg: f64,
}

impl SharpSource {
    /// `residual` lit by `light`; `None` for a map wider than [`SHARP_MAX_WIDTH`] or of odd width.
    pub fn new(residual: &Equirect, light: EnvironmentLight) -> Option<Self> {
        let (width, height) = (residual.width, residual.height);
        if width > SHARP_MAX_WIDTH || width % 2 != 0 || height == 0 {
            return None;
        }
        let scale = |p: [f32; 3]| p.map(|c| (f64::from(c) * light.intensity) as f32);
        let texels = residual
            .pixels
            .chunks_exact(2)
            .map(|pair| layer_pair::pack(scale(pair[0]), scale(pair[1])))
            .collect();
        Some(Self {
            width,
            height,
            texels,
            rotation_deg: light.rotation_deg,
        })
    }

    /// Pixel (x, y) as stored; x wraps around.
    fn pixel(&self, x: i64, y: i64) -> [f64; 3] {
        let x = x.rem_euclid(i64::from(self.width)) as usize;
        let texel = self.texels[y as usize * (self.width as usize / 2) + x / 2];
        let (first, second) = layer_pair::unpack(texel);
        let p = if x % 2 == 0 { first } else { second };
        p.map(f64::from)
    }

    /// The widest β a read at `d` (world frame) takes: `SHARP_SIGMA` of its row's height or of
    /// its column's width there, whichever is narrower.
    pub fn widest_beta(&self, d: DVec3) -> f64 {
        let e = world_to_environment(d, self.rotation_deg);
        let row = std::f64::consts::PI / f64::from(self.height);
        let column = std::f64::consts::TAU / f64::from(self.width) * e.x.hypot(e.z);
        SHARP_SIGMA * row.min(column)
    }

    /// The map's pixels at `d` (world frame, unit) through a Gaussian of width β, 0 < β ≤
    /// [`widest_beta`](Self::widest_beta)(d) (module doc).
    pub fn radiance(&self, d: DVec3, beta: f64) -> [f64; 3] {
        let e = world_to_environment(d, self.rotation_deg);
        let (u, v) = direction_to_equirect(e);
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let (x, y) = (u * w, v * h);
        let sigma_y = beta * h / std::f64::consts::PI;
        let sigma_x = beta * w / (std::f64::consts::TAU * e.x.hypot(e.z));
        let span = |at: f64, sigma: f64| {
            let first = (at - SHARP_REACH * sigma).floor() as i64;
            let last = (at + SHARP_REACH * sigma).floor() as i64;
            (first, last)
        };
        let weight = |k: i64, at: f64, sigma: f64| {
            normal_cdf((k as f64 + 1.0 - at) / sigma) - normal_cdf((k as f64 - at) / sigma)
        };
        let mut sum = [0.0; 3];
        let mut total = 0.0;
        // Rows beyond the poles are no pixels: the weights of those inside are normalised.
        let (top, bottom) = span(y, sigma_y);
        // Whole texels: the columns from the first's pair to the last's.
        let (first, last) = span(x, sigma_x);
        let columns = 2 * first.div_euclid(2)..=2 * last.div_euclid(2) + 1;
        for j in (top..=bottom).filter(|&j| j >= 0 && j < i64::from(self.height)) {
            let wy = weight(j, y, sigma_y);
            for i in columns.clone() {
                let wxy = wy * weight(i, x, sigma_x);
                let p = self.pixel(i, j);
                for c in 0..3 {
                    sum[c] += wxy * p[c];
                }
                total += wxy;
            }
        }
        match total > 0.0 {
            true => sum.map(|s| s / total),
            false => [0.0; 3],
        }
    }
}

/// Φ(x), the standard normal distribution, from erfc.
fn normal_cdf(x: f64) -> f64 {
    let tail = 0.5 * erfc_positive(x.abs() * std::f64::consts::FRAC_1_SQRT_2);
    match x >= 0.0 {
        true => 1.0 - tail,
        false => tail,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::environment::cube::equirect_to_direction;

    /// A map of pixels drawn from 1:30 contrasts, a thin line's worst case.
    fn speckled(width: u32, height: u32) -> Equirect {
        let mut state = 0x2545_f491_u32;
        let pixels = (0..width * height)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 17;
                state ^= state << 5;
                let bright = state % 5 == 0;
                [
                    if bright { 3.0 } else { 0.1 },
                    0.5,
                    (state % 7) as f32 * 0.1 + 0.05,
                ]
            })
            .collect();
        Equirect {
            width,
            height,
            pixels,
        }
    }

    /// SPEC §4's Gaussian w_β over the map's pixels as pieces of constant radiance: each pixel
    /// split into `cells`² cells at their centres, every pixel within 6β.
    fn brute_force(map: &Equirect, d: DVec3, beta: f64, cells: u32) -> [f64; 3] {
        let (mut sum, mut total) = ([0.0; 3], 0.0);
        let (w, h) = (f64::from(map.width), f64::from(map.height));
        for y in 0..map.height {
            for x in 0..map.width {
                let mut weight = 0.0;
                for b in 0..cells {
                    for a in 0..cells {
                        let u = (f64::from(x) + (f64::from(a) + 0.5) / f64::from(cells)) / w;
                        let v = (f64::from(y) + (f64::from(b) + 0.5) / f64::from(cells)) / h;
                        let s = equirect_to_direction(u, v);
                        let c = d.dot(s);
                        if c > (6.0 * beta).cos() {
                            let solid = (std::f64::consts::PI * v).sin();
                            weight += ((c - 1.0) / (beta * beta)).exp() * solid;
                        }
                    }
                }
                let p = map.get(x, y);
                for c in 0..3 {
                    sum[c] += weight * f64::from(layer_pair::stored(p[c]));
                }
                total += weight;
            }
        }
        sum.map(|s| s / total)
    }

    #[test]
    fn a_sharp_read_is_the_gaussian_of_the_maps_pixels() {
        let map = speckled(256, 128);
        let light = EnvironmentLight::default();
        let source = SharpSource::new(&map, light).expect("a 256-wide map has a sharp source");
        let mut worst = 0.0_f64;
        for k in 0..24 {
            // Directions from 70° above to 70° below the horizon, at odd places in their pixels.
            let z = 0.94 - 1.88 * (f64::from(k) + 0.37) / 24.0;
            let phi = f64::from(k) * 2.399_963;
            let r = (1.0 - z * z).sqrt();
            let d = DVec3::new(r * phi.cos(), z, r * phi.sin());
            let widest = source.widest_beta(d);
            for share in [0.3, 0.6, 1.0] {
                let beta = share * widest;
                let got = source.radiance(d, beta);
                let want = brute_force(&map, d, beta, 16);
                for c in 0..3 {
                    worst = worst.max((got[c] - want[c]).abs() / want[c]);
                }
            }
        }
        // The read is separable in the map's rows and columns, as the Gaussian is on the
        // tangent plane, and stops at 3σ (0.3 % of the weight): measured 0.89 % at worst on these
        // 1:30 pixels, where a read half a pixel off is tens of percent off.
        assert!(worst < 0.012, "worst relative difference {worst:e}");
    }

    /// A read sees the map × intensity, turned by the rotation about +Y as SPEC §4 turns it: the
    /// turned map's read at d is the unturned one's at d turned back, exactly.
    #[test]
    fn a_sharp_read_sees_the_maps_intensity_and_rotation() {
        let map = speckled(256, 128);
        let plain = SharpSource::new(&map, EnvironmentLight::default()).expect("256 wide");
        let lit = SharpSource::new(&map, EnvironmentLight::new(2.0, 40.0)).expect("256 wide");
        for k in 0..12 {
            let z = 0.8 - 1.6 * f64::from(k) / 11.0;
            let phi = f64::from(k) * 1.7;
            let r = (1.0 - z * z).sqrt();
            let d = DVec3::new(r * phi.cos(), z, r * phi.sin());
            let beta = 0.8 * lit.widest_beta(d);
            let got = lit.radiance(d, beta);
            let want = plain.radiance(world_to_environment(d, 40.0), beta);
            for c in 0..3 {
                assert!(
                    (got[c] - 2.0 * want[c]).abs() <= 1e-12 * want[c],
                    "{k} {c}: {} against 2 × {}",
                    got[c],
                    want[c]
                );
            }
        }
    }

    #[test]
    fn maps_too_wide_or_of_odd_width_have_no_sharp_source() {
        let light = EnvironmentLight::default();
        assert!(SharpSource::new(&Equirect::constant(8192, 4096, [1.0; 3]), light).is_none());
        assert!(SharpSource::new(&Equirect::constant(255, 128, [1.0; 3]), light).is_none());
        assert!(SharpSource::new(&Equirect::constant(4096, 2048, [1.0; 3]), light).is_some());
    }
}
