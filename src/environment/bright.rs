//! The `brdf` model's bright split: the few brightest parts of a map (a sun, a studio lamp) taken
//! out of it as directional lights, whose specular term is then evaluated exactly, f_spec·E·(N·l),
//! instead of through the lobe quadrature's lookups. A lookup blurs a source into its footprint and
//! finds a small one only when a sample's footprint happens to cover it; one light per bright
//! block has neither problem. Everything else (the residual, bright pixels cut down to what
//! `Residual` leaves) is prefiltered and read by the quadrature as before. Residual plus lights
//! is the map exactly: each bright pixel p of luminance Y keeps p·K/Y (K = T, the threshold, in
//! the first split; from T down to 0 at 2T in the rough one) and gives its light (p − p·K/Y)·dω.
//! Measured in BENCHMARKS.md ("The `brdf` environment model").
//!
//! Two splits of one map: [`split_bright`] (at most `MAX_ENV_LIGHTS` blocks, the brightest) for
//! the paths' hits and the narrowest lobes, and [`split_bright_rough`] (every bright block, in
//! blocks grown until there are at most `ROUGH_MAX_ENV_LIGHTS`) for every lobe the camera sees
//! whose width its blocks allow: a studio's light boxes are hundreds of blocks, and those left in
//! the layers were what a lobe's tails met from dark pixels (studio, m = 0.2: mean error 4.3 →
//! 1.1 %; m = 0.05, sphere relative RMSE 3.1 → 0.40 %). Each light keeps its block's spread, which
//! the lobe is widened by (`brdf_quadrature::bright_light`), so a block as wide as the lobe is
//! still a good light.

use glam::DVec3;
use std::f64::consts::PI;

use super::cube::{equirect_row_solid_angle, equirect_to_direction, world_to_environment};
use super::image::Equirect;
use super::params::EnvironmentLight;
use crate::gpu::shaders::interface::{MAX_ENV_LIGHTS, ROUGH_MAX_ENV_LIGHTS};

/// A pixel is bright when its luminance exceeds this many times the map's mean luminance (over the
/// sphere). Above it a source is small and bright enough for the quadrature to alias it; below it
/// the residual's contrast is what the lookups handle (BENCHMARKS.md).
pub const BRIGHT_THRESHOLD: f64 = 16.0;

/// Maps wider than this are split in blocks of `width / BRIGHT_GRID_WIDTH` pixels square, so a sun
/// takes as few lights at 8k as at 1k.
const BRIGHT_GRID_WIDTH: u32 = 512;

/// A bright block as a directional light: towards it, its irradiance at normal incidence, and
/// how far its radiance spreads about that direction: the variance per axis (rad²) of its pixels'
/// directions (their excess luminance the weights, each pixel's own extent included), by which
/// `brdf_quadrature::bright_specular` widens the lobe it meets (a block as wide as the lobe is
/// then still a good light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrightLight {
    pub direction: DVec3,
    pub irradiance: [f64; 3],
    pub spread: f64,
}

/// A map split into its residual and at most `MAX_ENV_LIGHTS` bright lights (map frame, before the
/// environment's intensity and rotation).
#[derive(Clone, Debug, PartialEq)]
pub struct BrightSplit {
    pub residual: Equirect,
    pub lights: Vec<BrightLight>,
    /// The size of its blocks (radians): the larger of a block's height and its width at the
    /// equator, which a block as a point light must be small against.
    pub block_angle: f64,
}

impl BrightSplit {
    /// The lights as the scene sees them: × intensity, turned by the rotation about +Y (SPEC §4).
    pub fn lights_in_world(&self, light: EnvironmentLight) -> Vec<BrightLight> {
        self.lights
            .iter()
            .map(|l| BrightLight {
                // world_to_environment turns by −ρ; by +ρ is the way back.
                direction: world_to_environment(l.direction, -light.rotation_deg),
                irradiance: l.irradiance.map(|e| e * light.intensity),
                spread: l.spread,
            })
            .collect()
    }
}

/// Luminance of a map pixel.
fn luminance(p: [f32; 3]) -> f64 {
    crate::model::spectral::luminance(p.map(f64::from))
}

/// The direction of pixel (x, y)'s centre.
fn pixel_direction(x: u32, y: u32, width: u32, height: u32) -> DVec3 {
    let u = (f64::from(x) + 0.5) / f64::from(width);
    let v = (f64::from(y) + 0.5) / f64::from(height);
    equirect_to_direction(u, v)
}

/// The variance per axis (rad²) of directions spread evenly over a pixel of row y: the mean of
/// its height's and its width's (at that row's latitude) squares over 12.
fn pixel_variance(y: u32, width: u32, height: u32) -> f64 {
    let tall = PI / f64::from(height);
    let wide = 2.0 * PI / f64::from(width) * (PI * (f64::from(y) + 0.5) / f64::from(height)).sin();
    (tall * tall + wide * wide) / 24.0
}

/// One block's share of the bright part: which pixels, what they give.
struct Block {
    pixels: Vec<(usize, [f32; 3])>,
    irradiance: [f64; 3],
    /// Σ luminance-of-excess × direction: the light's direction, normalised.
    centroid: DVec3,
    weight: f64,
    /// Σ luminance-of-excess × each pixel's own variance per axis.
    pixel_spread: f64,
}

/// Splits `map` (see the module doc). Pixels above `BRIGHT_THRESHOLD` × the mean luminance are
/// bright; they are grouped in blocks (one pixel up to `BRIGHT_GRID_WIDTH` wide), and the
/// `MAX_ENV_LIGHTS` blocks with the most excess become lights. Bright pixels of the blocks not
/// kept stay in the residual as they are, so nothing is lost either way.
pub fn split_bright(map: &Equirect) -> BrightSplit {
    let block = (map.width / BRIGHT_GRID_WIDTH).max(1);
    split_in_blocks(
        map,
        bright_threshold(map),
        (block, MAX_ENV_LIGHTS),
        Residual::Threshold,
    )
}

/// The split the quadratures read where the camera looks (the grid's and filtered importance
/// sampling's, and the lattice's where its blocks are at most `ROUGH_LATTICE_BLOCK`·m across):
/// every bright block a light, so the residual holds nothing above the threshold (and nothing at
/// all of a pixel above twice it: `Residual::Ramp`). The blocks start as [`split_bright`]'s and
/// double in size until there are at most `ROUGH_MAX_ENV_LIGHTS` of them; a block is then a few
/// degrees across, and its spread widens the lobe it meets (BENCHMARKS.md, "Where the remaining
/// error is").
pub fn split_bright_rough(map: &Equirect) -> BrightSplit {
    let threshold = bright_threshold(map);
    let bright: Vec<(u32, u32)> = (0..map.height)
        .flat_map(|y| (0..map.width).map(move |x| (x, y)))
        .filter(|&(x, y)| is_bright(map.pixels[(y * map.width + x) as usize], threshold))
        .collect();
    // How many `block`-pixel blocks hold a bright pixel.
    let blocks = |block: u32| {
        let ids: std::collections::HashSet<(u32, u32)> = bright
            .iter()
            .map(|&(x, y)| (x / block, y / block))
            .collect();
        ids.len()
    };
    let mut block = (map.width / BRIGHT_GRID_WIDTH).max(1);
    while blocks(block) > ROUGH_MAX_ENV_LIGHTS && block < map.width {
        block *= 2;
    }
    split_in_blocks(
        map,
        threshold,
        (block, ROUGH_MAX_ENV_LIGHTS),
        Residual::Ramp,
    )
}

/// Whether pixel `p` is bright. Written so that a NaN pixel (load replaces them) or a zero
/// threshold is not bright.
fn is_bright(p: [f32; 3], threshold: f64) -> bool {
    threshold > 0.0 && luminance(p) > threshold
}

/// The luminance above which a pixel of `map` is bright: `BRIGHT_THRESHOLD` × the map's mean
/// over the sphere.
fn bright_threshold(map: &Equirect) -> f64 {
    let (w, h) = (map.width, map.height);
    let mut total = 0.0;
    for y in 0..h {
        let dw = equirect_row_solid_angle(y, w, h);
        for x in 0..w {
            total += luminance(map.pixels[(y * w + x) as usize]) * dw;
        }
    }
    BRIGHT_THRESHOLD * total / (4.0 * PI)
}

/// What a bright pixel leaves in the residual; the rest goes to its block's light.
#[derive(Clone, Copy)]
enum Residual {
    /// The threshold T: a bright region stays in the layers as a plateau at T.
    Threshold,
    /// T at the threshold falling to 0 at 2T, nothing above: a light box leaves no plateau whose
    /// edges the lookups would alias, and a region just above T no new edge (the residual is
    /// continuous in the pixel's luminance). Measured in BENCHMARKS.md ("The rough split leaves
    /// no plateau").
    Ramp,
}

impl Residual {
    /// The luminance a pixel of luminance `y` > `threshold` keeps.
    fn kept(self, y: f64, threshold: f64) -> f64 {
        match self {
            Residual::Threshold => threshold,
            Residual::Ramp => (2.0 * threshold - y).clamp(0.0, threshold),
        }
    }
}

/// The split with `block`-pixel blocks and at most `max_lights` lights (see [`split_bright`]),
/// bright above `threshold` ([`bright_threshold`]), each bright pixel leaving `leaves` behind.
fn split_in_blocks(
    map: &Equirect,
    threshold: f64,
    (block, max_lights): (u32, usize),
    leaves: Residual,
) -> BrightSplit {
    let (w, h) = (map.width, map.height);
    let blocks_x = w.div_ceil(block);
    let mut blocks: Vec<(u32, Block)> = Vec::new();
    let mut slots: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
    for y in 0..h {
        let dw = equirect_row_solid_angle(y, w, h);
        for x in 0..w {
            let index = (y * w + x) as usize;
            let p = map.pixels[index];
            if !is_bright(p, threshold) {
                continue;
            }
            let y_lum = luminance(p);
            let kept_lum = leaves.kept(y_lum, threshold);
            let keep = kept_lum / y_lum;
            let kept = p.map(|c| (f64::from(c) * keep) as f32);
            let excess: [f64; 3] =
                std::array::from_fn(|c| (f64::from(p[c]) - f64::from(kept[c])) * dw);
            let id = (y / block) * blocks_x + x / block;
            let slot = *slots.entry(id).or_insert_with(|| {
                blocks.push((
                    id,
                    Block {
                        pixels: Vec::new(),
                        irradiance: [0.0; 3],
                        centroid: DVec3::ZERO,
                        weight: 0.0,
                        pixel_spread: 0.0,
                    },
                ));
                blocks.len() - 1
            });
            let b = &mut blocks[slot].1;
            let weight = (y_lum - kept_lum) * dw;
            b.pixels.push((index, kept));
            b.centroid += weight * pixel_direction(x, y, w, h);
            b.weight += weight;
            b.pixel_spread += weight * pixel_variance(y, w, h);
            for (sum, e) in b.irradiance.iter_mut().zip(excess) {
                *sum += e;
            }
        }
    }
    // The brightest blocks first; equal weights in map order, so the split is deterministic.
    blocks.sort_by(|a, b| b.1.weight.total_cmp(&a.1.weight).then(a.0.cmp(&b.0)));
    blocks.truncate(max_lights);
    let mut residual = map.clone();
    let lights = blocks
        .into_iter()
        .map(|(_, b)| {
            for (index, kept) in b.pixels {
                residual.pixels[index] = kept;
            }
            // Σw·|d − ĉ|² = 2·(W − |Σw·d|) over unit d about ĉ = Σw·d/|Σw·d|: two axes' worth.
            let spread = match b.weight > 0.0 {
                true => (1.0 - b.centroid.length() / b.weight).max(0.0) + b.pixel_spread / b.weight,
                false => 0.0,
            };
            BrightLight {
                direction: b.centroid.normalize_or_zero(),
                irradiance: b.irradiance,
                spread,
            }
        })
        .collect();
    let block_angle =
        (PI * f64::from(block) / f64::from(h)).max(2.0 * PI * f64::from(block) / f64::from(w));
    BrightSplit {
        residual,
        lights,
        block_angle,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grey map with a 3 × 2-pixel lamp 1000× brighter.
    fn lamp_map() -> Equirect {
        let mut map = Equirect::constant(64, 32, [0.5, 0.5, 0.5]);
        for y in 10..12 {
            for x in 20..23 {
                map.pixels[y * 64 + x] = [500.0, 400.0, 300.0];
            }
        }
        map
    }

    #[test]
    fn residual_plus_lights_is_the_map() {
        let map = lamp_map();
        let split = split_bright(&map);
        assert_eq!(
            split.lights.len(),
            6,
            "one light per bright pixel at this width"
        );
        // Energy of the bright pixels = what the residual keeps of them + the lights.
        let mut original = [0.0; 3];
        let mut kept = [0.0; 3];
        for y in 10..12u32 {
            let dw = equirect_row_solid_angle(y, 64, 32);
            for x in 20..23u32 {
                let i = (y * 64 + x) as usize;
                for c in 0..3 {
                    original[c] += f64::from(map.pixels[i][c]) * dw;
                    kept[c] += f64::from(split.residual.pixels[i][c]) * dw;
                }
            }
        }
        for c in 0..3 {
            let lights: f64 = split.lights.iter().map(|l| l.irradiance[c]).sum();
            assert!((kept[c] + lights - original[c]).abs() <= 1e-6 * original[c]);
        }
        // The rest of the map is untouched, and the lamp keeps its colour at the threshold.
        assert_eq!(split.residual.pixels[0], map.pixels[0]);
        let kept = split.residual.pixels[10 * 64 + 20];
        assert!((kept[0] / kept[2] - 500.0 / 300.0).abs() < 1e-5);
    }

    #[test]
    fn a_constant_map_has_no_lights() {
        let map = Equirect::constant(64, 32, [2.0, 1.0, 0.5]);
        let split = split_bright(&map);
        assert!(split.lights.is_empty());
        assert_eq!(split.residual, map);
    }

    #[test]
    fn lights_turn_with_the_environment() {
        let split = split_bright(&lamp_map());
        let light = EnvironmentLight::new(2.0, 90.0);
        let world = split.lights_in_world(light);
        for (a, b) in split.lights.iter().zip(&world) {
            // The world direction seen through the environment's rotation is the map's.
            assert!((world_to_environment(b.direction, 90.0) - a.direction).length() < 1e-12);
            assert_eq!(b.irradiance, a.irradiance.map(|e| 2.0 * e));
        }
    }

    /// Between the threshold and twice it, the rough split's residual falls from T to 0, so it is
    /// continuous in the pixel's luminance; the first split's stays at T.
    #[test]
    fn the_rough_residual_ramps_down_to_nothing_at_twice_the_threshold() {
        let t = 2.0;
        for (y, want) in [(2.0, 2.0), (2.5, 1.5), (3.0, 1.0), (4.0, 0.0), (100.0, 0.0)] {
            assert_eq!(Residual::Ramp.kept(y, t), want, "{y}");
            assert_eq!(Residual::Threshold.kept(y, t), t, "{y}");
        }
    }

    #[test]
    fn the_rough_split_takes_every_bright_block_in_few_lights() {
        // 40 × 20 bright pixels in one patch and 600 scattered ones: far more blocks than
        // ROUGH_MAX_ENV_LIGHTS at 1 px, so the blocks grow until every bright pixel is in a light.
        let mut map = Equirect::constant(512, 256, [0.1; 3]);
        for y in 100..120 {
            for x in 200..240 {
                map.pixels[y * 512 + x] = [500.0, 400.0, 300.0];
            }
        }
        for k in 0..600usize {
            map.pixels[(10 + k / 100 * 20) * 512 + (k % 100) * 5] = [300.0; 3];
        }
        let split = split_bright_rough(&map);
        assert!(split.lights.len() <= ROUGH_MAX_ENV_LIGHTS);
        assert!(
            split.lights.len() > MAX_ENV_LIGHTS,
            "{}",
            split.lights.len()
        );
        // Nothing above the threshold is left in the residual.
        let threshold = bright_threshold(&map);
        let brightest = split.residual.pixels.iter().map(|&p| luminance(p));
        assert!(brightest.fold(0.0, f64::max) <= threshold * (1.0 + 1e-6));
        // Residual plus lights is the map.
        for c in 0..3 {
            let (mut map_sum, mut kept) = (0.0, 0.0);
            for y in 0..256u32 {
                let dw = equirect_row_solid_angle(y, 512, 256);
                for x in 0..512u32 {
                    let i = (y * 512 + x) as usize;
                    map_sum += f64::from(map.pixels[i][c]) * dw;
                    kept += f64::from(split.residual.pixels[i][c]) * dw;
                }
            }
            let lights: f64 = split.lights.iter().map(|l| l.irradiance[c]).sum();
            assert!((kept + lights - map_sum).abs() <= 1e-6 * map_sum);
        }
        // The patch and the scattered pixels, far above twice the threshold, leave nothing.
        assert_eq!(split.residual.pixels[110 * 512 + 220], [0.0; 3]);
        assert_eq!(split.residual.pixels[10 * 512], [0.0; 3]);
        // A map the bright split already takes whole gives the same lights in the same places,
        // each with its whole pixel now (the first split leaves the threshold in the residual).
        let lamp = lamp_map();
        let (rough, first) = (split_bright_rough(&lamp), split_bright(&lamp));
        assert_eq!(rough.lights.len(), first.lights.len());
        for (r, f) in rough.lights.iter().zip(&first.lights) {
            assert!((r.direction - f.direction).length() < 1e-12);
            assert!(r.irradiance[0] > f.irradiance[0]);
        }
    }

    #[test]
    fn at_most_max_env_lights_and_the_brightest_first() {
        // 40 separate bright pixels of rising brightness: the MAX_ENV_LIGHTS brightest are kept.
        let mut map = Equirect::constant(256, 128, [0.1; 3]);
        for k in 0..40u32 {
            let i = (64 * 256 + k * 5) as usize;
            map.pixels[i] = [100.0 + k as f32; 3];
        }
        let split = split_bright(&map);
        assert_eq!(split.lights.len(), MAX_ENV_LIGHTS);
        let first = split.lights[0].irradiance[0];
        assert!(split.lights.iter().all(|l| l.irradiance[0] <= first));
        // The dimmest stay in the residual unclamped.
        assert_eq!(split.residual.pixels[64 * 256], [100.0; 3]);
    }
}
