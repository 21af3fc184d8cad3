//! The CPU oracle of the prefilter: exactly the algorithm `gpu.rs` runs, step by step, in plain
//! f64 Rust, so that every GPU texel can be checked against it (1e-3 relative). Each step has the
//! name of its GPU twin (`GpuPrefilter::equirect_to_cube`, `downsample`, `blur_layer`,
//! `irradiance`). Owns nothing but these steps; the geometry is `cube.rs`'s, the plan (β_k, face
//! sizes, cut-off) `params.rs`'s.
//!
//! ```text
//! equirect ──equirect_to_cube──► base (face N) ──downsample──► mips N/2 … ──┬─ blur_layer(β_k) ─► layer k
//!                                   └──────────────────────────► layer 0     └─ irradiance ──────► E(n)
//! ```

use glam::DVec3;
use rayon::prelude::*;

use super::cube::{
    direction_to_equirect, face_direction, texel_direction, texel_solid_angle, world_to_environment,
};
use super::image::{CubeImage, Equirect, PrefilteredEnvironment};
use super::params::{EnvironmentLight, PrefilterParams, LOBE_CUTOFF};
use crate::{Error, Result};

/// Runs the whole prefilter: layer 0 is the base cube, layer k ≥ 1 the lobe blur of the mip of the
/// layer's face size with β_k, and the irradiance cube integrates the mip of
/// `params.irradiance_face()`.
pub fn prefilter_cpu(
    source: &Equirect,
    params: &PrefilterParams,
    light: EnvironmentLight,
) -> Result<PrefilteredEnvironment> {
    let EnvironmentLight {
        intensity,
        rotation_deg,
    } = light;
    params.validate()?;
    validate_source(source)?;
    if !(intensity.is_finite() && intensity >= 0.0) {
        return Err(Error::invalid(
            "env intensity",
            intensity,
            "must be finite and ≥ 0",
        ));
    }
    if !rotation_deg.is_finite() {
        return Err(Error::invalid(
            "env rotation",
            rotation_deg,
            "must be a finite angle in degrees",
        ));
    }
    let supersample = params.supersample(source.width);
    let base = equirect_to_cube(
        source,
        (params.face_size, supersample),
        intensity,
        rotation_deg,
    );
    let mips = mip_chain(&base, params);
    let mip_of_face = |face_size: u32| {
        mips.iter()
            .find(|m| m.face_size == face_size)
            .ok_or_else(|| {
                Error::invalid(
                    "face size",
                    face_size,
                    "no source mip has this face size (a bug in the plan)",
                )
            })
    };
    let plan = params.plan();
    let mut layers = Vec::with_capacity(plan.len());
    for (k, layer) in plan.iter().enumerate() {
        layers.push(if k == 0 {
            base.clone()
        } else {
            blur_layer(mip_of_face(layer.face_size)?, layer.blur)
        });
    }
    let irradiance = irradiance(mip_of_face(params.irradiance_face())?);
    Ok(PrefilteredEnvironment {
        betas: plan.iter().map(|l| l.beta).collect(),
        layers,
        irradiance,
    })
}

fn validate_source(source: &Equirect) -> Result<()> {
    let expected = (source.width as usize) * (source.height as usize);
    if source.width == 0 || source.height == 0 || source.pixels.len() != expected {
        return Err(Error::invalid(
            "environment",
            format!(
                "{}×{} with {} pixels",
                source.width,
                source.height,
                source.pixels.len()
            ),
            "must be a non-empty image with width·height pixels",
        ));
    }
    Ok(())
}

/// Step 1: texel (f, i, j) is the mean of S × S sub-samples (S =
/// [`PrefilterParams::supersample`](super::params::PrefilterParams::supersample), shared with the
/// GPU's `shaders/common/equirect_to_cube_body.glsl` through a push constant) at face coordinates
/// sc = 2(i + (a + ½)/S)/N − 1, tc = 2(j + (b + ½)/S)/N − 1; each looks along
/// normalize(face_direction(f, sc, tc)), turned into the environment's frame, and reads the source
/// pixel that contains its (u, v): column ⌊u·W⌋ wrapping around, row ⌊v·H⌋ clamped at the poles.
/// Times `intensity`. A box filter over the texel, so that a source finer than the cube is
/// averaged rather than point-sampled. GPU twin: `GpuPrefilter::equirect_to_cube`.
pub fn equirect_to_cube(
    source: &Equirect,
    (face_size, s): (u32, u32),
    intensity: f64,
    rotation_deg: f64,
) -> CubeImage {
    let mut cube = CubeImage::new(face_size);
    let m = face_size as usize;
    let coordinate = |texel: u32, sub: u32| {
        2.0 * (f64::from(texel) + (f64::from(sub) + 0.5) / f64::from(s)) / f64::from(face_size)
            - 1.0
    };
    cube.texels
        .par_iter_mut()
        .enumerate()
        .for_each(|(index, texel)| {
            let (face, i, j) = texel_of_index(index, m);
            let mut sum = [0.0; 3];
            for b in 0..s {
                for a in 0..s {
                    let world =
                        face_direction(face, coordinate(i, a), coordinate(j, b)).normalize();
                    let rgb = source_pixel(source, world_to_environment(world, rotation_deg));
                    add_weighted(&mut sum, 1.0, rgb);
                }
            }
            let scale = intensity / f64::from(s * s);
            *texel = rgba(sum.map(|c| c * scale));
        });
    cube
}

/// The source pixel that contains direction `d` (environment frame), as step 1 reads it.
pub fn source_pixel(source: &Equirect, d: DVec3) -> [f64; 3] {
    let (u, v) = direction_to_equirect(d);
    let (w, h) = (i64::from(source.width), i64::from(source.height));
    let x = ((u * w as f64).floor() as i64).rem_euclid(w) as u32;
    let y = ((v * h as f64).floor() as i64).clamp(0, h - 1) as u32;
    source.get(x, y).map(f64::from)
}

/// Step 2: each parent texel is the solid-angle-weighted mean of its 2×2 children, so a mip keeps
/// the radiance integral ∫L dω of the cube it came from (up to the texel solid-angle formula).
/// GPU twin: `GpuPrefilter::downsample`.
pub fn downsample(cube: &CubeImage) -> CubeImage {
    let child_size = cube.face_size;
    let mut parent = CubeImage::new(child_size / 2);
    let m = parent.face_size as usize;
    parent
        .texels
        .par_iter_mut()
        .enumerate()
        .for_each(|(index, texel)| {
            let (face, i, j) = texel_of_index(index, m);
            let mut sum = [0.0; 3];
            let mut weight = 0.0;
            for (ci, cj) in [
                (2 * i, 2 * j),
                (2 * i + 1, 2 * j),
                (2 * i, 2 * j + 1),
                (2 * i + 1, 2 * j + 1),
            ] {
                let d_omega = texel_solid_angle(ci, cj, child_size);
                let l = cube.get(face, ci, cj);
                add_weighted(&mut sum, d_omega, [l[0], l[1], l[2]].map(f64::from));
                weight += d_omega;
            }
            *texel = rgba(sum.map(|s| s / weight));
        });
    parent
}

/// The source mips for `params.mip_faces()`: the base cube, then each half of the one before.
pub fn mip_chain(base: &CubeImage, params: &PrefilterParams) -> Vec<CubeImage> {
    let mut mips = vec![base.clone()];
    for _ in 1..params.mip_faces().len() {
        if let Some(last) = mips.last() {
            let next = downsample(last);
            mips.push(next);
        }
    }
    mips
}

/// Step 3: Lpre(d, β) = Σ w·L_s / Σ w, w = exp(−q/β²)·dω_s, q = |d − s|²/2 = 1 − d·s, over the
/// texels s of `source` with q ≤ LOBE_CUTOFF·β². The sum runs over a conservative window per face
/// (see [`face_window`]) and equals the sum over every texel (tested); output face = source face.
/// GPU twin: `GpuPrefilter::blur_layer`.
pub fn blur_layer(source: &CubeImage, beta: f64) -> CubeImage {
    let m = source.face_size;
    let texels = SourceTexels::new(source);
    let q_max = LOBE_CUTOFF * beta * beta;
    let mut out = CubeImage::new(m);
    out.texels
        .par_iter_mut()
        .enumerate()
        .for_each(|(index, texel)| {
            let (face, i, j) = texel_of_index(index, m as usize);
            let d = texel_direction(face, i, j, m);
            let mut sum = [0.0; 3];
            let mut weight = 0.0;
            for s_face in 0..6 {
                let Some((is, js)) = face_window(d, q_max, s_face, m) else {
                    continue;
                };
                for sj in js.clone() {
                    for si in is.clone() {
                        let s = texels.index(s_face, si, sj);
                        let q = (d - texels.direction[s]).length_squared() / 2.0;
                        if q <= q_max {
                            let w = (-q / (beta * beta)).exp() * texels.solid_angle[s];
                            add_weighted(&mut sum, w, texels.radiance[s]);
                            weight += w;
                        }
                    }
                }
            }
            *texel = rgba(sum.map(|s| s / weight));
        });
    out
}

/// Step 4: E(n) = π·Σ L_s·max(n·s, 0)·dω_s / Σ max(n·s, 0)·dω_s over every texel of `source`. The
/// quadrature's own Σ max(n·s, 0)·dω_s stands in for ∫ max(n·s, 0) dω = π, so a constant c gives
/// exactly π·c; output face = source face. GPU twin: `GpuPrefilter::irradiance`.
pub fn irradiance(source: &CubeImage) -> CubeImage {
    let m = source.face_size;
    let texels = SourceTexels::new(source);
    let mut out = CubeImage::new(m);
    out.texels
        .par_iter_mut()
        .enumerate()
        .for_each(|(index, texel)| {
            let (face, i, j) = texel_of_index(index, m as usize);
            let n = texel_direction(face, i, j, m);
            let mut sum = [0.0; 3];
            let mut weight = 0.0;
            for s in 0..texels.direction.len() {
                let w = n.dot(texels.direction[s]).max(0.0) * texels.solid_angle[s];
                add_weighted(&mut sum, w, texels.radiance[s]);
                weight += w;
            }
            *texel = rgba(sum.map(|s| std::f64::consts::PI * s / weight));
        });
    out
}

/// Texel ranges (i, j) of face `face` (size m) that can hold a direction s with
/// |d − s|²/2 ≤ q_max, i.e. within the cone of half-angle θc = acos(1 − q_max) around d; `None`
/// when none can.
///
/// On face f with axis a and face axes e_s, e_t (sc = s·e_s / s·a, tc = s·e_t / s·a), sc = tan α
/// with α = atan2(s·e_s, s·a), the longitude of s about e_t. A spherical cap of radius θc whose
/// centre is at angle γ from the pole e_t spans longitudes α_d ± asin(sin θc / sin γ) when it does
/// not contain either pole (sin θc < sin γ), and all longitudes otherwise. Intersected with the
/// face's |α| ≤ 45°, that bounds sc; tc likewise about e_s. The box is widened by one texel so that
/// rounding never drops a texel the exact test would keep. A cap of θc ≥ 90° (q_max ≥ 1) always
/// contains a pole and gets the whole face.
pub fn face_window(
    d: DVec3,
    q_max: f64,
    face: usize,
    m: u32,
) -> Option<(std::ops::Range<u32>, std::ops::Range<u32>)> {
    let full = 0..m;
    if q_max >= 1.0 {
        return Some((full.clone(), full));
    }
    let axis = face_direction(face, 0.0, 0.0);
    let e_s = face_direction(face, 1.0, 0.0) - axis;
    let e_t = face_direction(face, 0.0, 1.0) - axis;
    // q_max < 1: θc < 90°, so sin θc < sin γ is exactly "the cap contains neither pole".
    let sin_cap = (q_max * (2.0 - q_max)).sqrt();
    let range = |e_along: DVec3, e_pole: DVec3| -> Option<std::ops::Range<u32>> {
        let sin_pole = (1.0 - d.dot(e_pole).powi(2)).max(0.0).sqrt();
        let (lo, hi) = if sin_cap < sin_pole {
            let half_width = (sin_cap / sin_pole).asin();
            let centre = d.dot(e_along).atan2(d.dot(axis));
            longitude_overlap(centre - half_width, centre + half_width)?
        } else {
            (-std::f64::consts::FRAC_PI_4, std::f64::consts::FRAC_PI_4)
        };
        Some(texel_range(lo.tan(), hi.tan(), m))
    };
    let is = range(e_s, e_t)?;
    let js = range(e_t, e_s)?;
    Some((is, js))
}

/// The part of the longitude interval [lo, hi] (width < 2π, possibly outside (−π, π]) that lies in
/// the face's [−π/4, π/4], as one interval.
fn longitude_overlap(lo: f64, hi: f64) -> Option<(f64, f64)> {
    let quarter = std::f64::consts::FRAC_PI_4;
    [-std::f64::consts::TAU, 0.0, std::f64::consts::TAU]
        .iter()
        .map(|shift| (lo + shift).max(-quarter)..=(hi + shift).min(quarter))
        .find(|r| r.start() <= r.end())
        .map(|r| (*r.start(), *r.end()))
}

/// Indices i whose centre 2(i + ½)/m − 1 lies in [lo, hi], widened by one texel each side.
fn texel_range(lo: f64, hi: f64, m: u32) -> std::ops::Range<u32> {
    let m_f = f64::from(m);
    let first = ((lo + 1.0) * m_f / 2.0 - 0.5).ceil() - 1.0;
    let last = ((hi + 1.0) * m_f / 2.0 - 0.5).floor() + 1.0;
    let first = first.clamp(0.0, m_f - 1.0) as u32;
    let last = last.clamp(0.0, m_f - 1.0) as u32;
    first..last + 1
}

/// Every texel's centre direction, solid angle and radiance, in the cube's index order.
struct SourceTexels {
    face_size: u32,
    direction: Vec<DVec3>,
    solid_angle: Vec<f64>,
    radiance: Vec<[f64; 3]>,
}

impl SourceTexels {
    fn new(cube: &CubeImage) -> Self {
        let m = cube.face_size;
        let coords: Vec<(usize, u32, u32)> = (0..cube.texels.len())
            .map(|index| texel_of_index(index, m as usize))
            .collect();
        Self {
            face_size: m,
            direction: coords
                .iter()
                .map(|&(f, i, j)| texel_direction(f, i, j, m))
                .collect(),
            solid_angle: coords
                .iter()
                .map(|&(_, i, j)| texel_solid_angle(i, j, m))
                .collect(),
            radiance: cube
                .texels
                .iter()
                .map(|t| [f64::from(t[0]), f64::from(t[1]), f64::from(t[2])])
                .collect(),
        }
    }

    fn index(&self, face: usize, i: u32, j: u32) -> usize {
        let m = self.face_size as usize;
        (face * m + j as usize) * m + i as usize
    }
}

/// (face, i, j) of a cube texel index (f·M + j)·M + i.
fn texel_of_index(index: usize, m: usize) -> (usize, u32, u32) {
    let face = index / (m * m);
    let j = (index / m) % m;
    let i = index % m;
    (face, i as u32, j as u32)
}

/// sum += w·rgb, channel by channel.
fn add_weighted(sum: &mut [f64; 3], w: f64, rgb: [f64; 3]) {
    for (s, l) in sum.iter_mut().zip(rgb) {
        *s += w * l;
    }
}

fn rgba(rgb: [f64; 3]) -> [f32; 4] {
    [rgb[0] as f32, rgb[1] as f32, rgb[2] as f32, 1.0]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic, uneven cube: every texel a different colour from a small integer hash.
    fn hashed_cube(m: u32) -> CubeImage {
        let mut cube = CubeImage::new(m);
        for (index, texel) in cube.texels.iter_mut().enumerate() {
            let h = (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
            let x = (h % 1000) as f32 / 100.0;
            *texel = [x, 10.0 - x, (h % 7) as f32, 1.0];
        }
        cube
    }

    #[test]
    fn white_furnace_every_layer_is_c_and_irradiance_is_pi_c() {
        let c = [0.7f32, 1.3, 2.5];
        let params = PrefilterParams {
            face_size: 32,
            layers: 6,
            beta_min: 0.02,
            beta_max: 1.0,
            layer_texel: 1.0,
            small_layer_texel: 1.0,
            fine_layers: 0,
            blur_net_of_read: false,
            supersample_scale: 1,
        };
        let env = prefilter_cpu(
            &Equirect::constant(64, 32, c),
            &params,
            EnvironmentLight::new(2.0, 30.0),
        )
        .unwrap();
        // Every step is a normalised weighted mean of equal values (× intensity 2): only f32
        // rounding of the stored texels remains (≤ 6e-8 relative); 1e-6 leaves margin.
        for (k, layer) in env.layers.iter().enumerate() {
            for t in &layer.texels {
                for ch in 0..3 {
                    let want = 2.0 * f64::from(c[ch]);
                    assert!(
                        (f64::from(t[ch]) - want).abs() <= 1e-6 * want,
                        "layer {k}: {t:?}"
                    );
                }
                assert_eq!(t[3], 1.0);
            }
        }
        for t in &env.irradiance.texels {
            for ch in 0..3 {
                let want = std::f64::consts::PI * 2.0 * f64::from(c[ch]);
                assert!(
                    (f64::from(t[ch]) - want).abs() <= 1e-6 * want,
                    "irradiance {t:?}"
                );
            }
        }
        assert_eq!(env.irradiance.face_size, 32);
        assert_eq!(env.betas.len(), 6);
    }

    #[test]
    fn base_texels_average_the_pixels_under_their_sub_samples() {
        // An 8 × 4 map of 45° pixels and a cube of face 1: the 16 sub-samples of a face sit at
        // sc, tc ∈ {±¼, ±¾}. By hand, from SPEC §4's (u, v):
        // +Y: polar angle θ = atan(√(sc² + tc²)) is 46.7° for the four (±¾, ±¾) samples (row 1)
        // and ≤ 38.3° for the other twelve (row 0). With L = 10·row + 1: (12·1 + 4·11)/16 = 3.5.
        let by_row = Equirect {
            width: 8,
            height: 4,
            pixels: (0..32).map(|p| [(10 * (p / 8) + 1) as f32; 3]).collect(),
        };
        let up = equirect_to_cube(&by_row, (1, 4), 2.0, 0.0).get(2, 0, 0);
        assert!((up[0] - 2.0 * 3.5).abs() < 1e-6, "{up:?}");
        // +Z: u = ½ + atan2(x, −1)/2π is in (0.88, 0.97) for x = sc > 0 (column 7) and in
        // (0.03, 0.11) for x < 0 (column 0, across the wrap). With L = column: (8·7 + 8·0)/16.
        let by_column = Equirect {
            width: 8,
            height: 4,
            pixels: (0..32).map(|p| [(p % 8) as f32; 3]).collect(),
        };
        let plus_z = equirect_to_cube(&by_column, (1, 4), 1.0, 0.0).get(4, 0, 0);
        assert!((plus_z[0] - 3.5).abs() < 1e-6, "{plus_z:?}");
        // Turning the environment by 90° about +Y shows world +X what +Z showed unturned:
        // world_to_environment maps (1, −tc, −sc) to (sc, −tc, 1), the +Z face's samples.
        let turned = equirect_to_cube(&by_column, (1, 4), 1.0, 90.0).get(0, 0, 0);
        assert!((turned[0] - 3.5).abs() < 1e-6, "{turned:?}");
        // −Z, the image centre: u = ½ − atan(sc)/2π, columns 3 (sc > 0) and 4 → 3.5 as well;
        // +X: u = ½ + atan2(1, sc)/2π, columns 5 (sc > 0) and 6 → 5.5.
        let minus_z = equirect_to_cube(&by_column, (1, 4), 1.0, 0.0).get(5, 0, 0);
        let plus_x = equirect_to_cube(&by_column, (1, 4), 1.0, 0.0).get(0, 0, 0);
        assert!((minus_z[0] - 3.5).abs() < 1e-6 && (plus_x[0] - 5.5).abs() < 1e-6);
    }

    #[test]
    fn downsample_is_the_solid_angle_weighted_mean_of_children() {
        let fine = hashed_cube(4);
        let coarse = downsample(&fine);
        assert_eq!(coarse.face_size, 2);
        // Parent (1, 0) of face 3: children i = 2, 3 (sc = 0.25, 0.75), j = 0, 1 (tc = −0.75,
        // −0.25); dω ∝ (1 + sc² + tc²)^(−3/2), written out here rather than taken from cube.rs.
        let mut sum = 0.0;
        let mut weights = 0.0;
        for (i, j, sc, tc) in [
            (2, 0, 0.25, -0.75),
            (3, 0, 0.75, -0.75),
            (2, 1, 0.25, -0.25),
            (3, 1, 0.75, -0.25),
        ] {
            let w = (1.0f64 + sc * sc + tc * tc).powf(-1.5);
            sum += w * f64::from(fine.get(3, i, j)[0]);
            weights += w;
        }
        let got = f64::from(coarse.get(3, 1, 0)[0]);
        assert!(
            (got - sum / weights).abs() < 1e-5,
            "{got} vs {}",
            sum / weights
        );
    }

    /// Step 3 without the window: every texel of the cube, the same cut-off and order.
    fn blur_every_texel(source: &CubeImage, beta: f64) -> CubeImage {
        let m = source.face_size;
        let texels = SourceTexels::new(source);
        let q_max = LOBE_CUTOFF * beta * beta;
        let mut out = CubeImage::new(m);
        for (index, texel) in out.texels.iter_mut().enumerate() {
            let (face, i, j) = texel_of_index(index, m as usize);
            let d = texel_direction(face, i, j, m);
            let mut sum = [0.0; 3];
            let mut weight = 0.0;
            for s in 0..texels.direction.len() {
                let q = (d - texels.direction[s]).length_squared() / 2.0;
                if q <= q_max {
                    let w = (-q / (beta * beta)).exp() * texels.solid_angle[s];
                    add_weighted(&mut sum, w, texels.radiance[s]);
                    weight += w;
                }
            }
            *texel = rgba(sum.map(|s| s / weight));
        }
        out
    }

    #[test]
    fn windowed_blur_equals_the_sum_over_every_texel() {
        // The window only skips texels the cut-off rejects, and visits the rest in the same order
        // (face, row, column), so the sums are the same terms added in the same order: equal bits.
        for (m, betas) in [
            (8, [0.05, 0.2, 0.45, 0.7, 1.5]),
            (16, [0.03, 0.08, 0.15, 0.28, 0.5]),
        ] {
            let cube = hashed_cube(m);
            for beta in betas {
                assert_eq!(
                    blur_layer(&cube, beta),
                    blur_every_texel(&cube, beta),
                    "M = {m}, β = {beta}"
                );
            }
        }
    }

    #[test]
    fn face_window_holds_every_texel_inside_the_cutoff() {
        // Directly: for texel-centre and off-grid directions d and many cap sizes, no texel with
        // q ≤ q_max lies outside the window (the test above would only see it through the sum).
        let m = 16;
        let mut directions: Vec<DVec3> = (0..6 * 16 * 16)
            .step_by(5)
            .map(|index| {
                let (f, i, j) = texel_of_index(index, 16);
                texel_direction(f, i, j, 16)
            })
            .collect();
        directions.extend(
            [
                DVec3::new(1.0, 1.0, 1.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(0.3, -1.0, 0.2),
            ]
            .map(DVec3::normalize),
        );
        for d in directions {
            for q_max in [1e-4, 3e-3, 0.02, 0.1, 0.3, 0.6, 0.95, 1.2] {
                for face in 0..6 {
                    let window = face_window(d, q_max, face, m);
                    for j in 0..m {
                        for i in 0..m {
                            let q = (d - texel_direction(face, i, j, m)).length_squared() / 2.0;
                            let inside = window
                                .as_ref()
                                .is_some_and(|(is, js)| is.contains(&i) && js.contains(&j));
                            assert!(
                                q > q_max || inside,
                                "d {d}, q_max {q_max}, face {face}, ({i}, {j})"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_linear_radiance_blurs_to_the_truncated_langevin_mean() {
        // L(s) = 1 + ½·s_x. For the lobe w = exp(−k·t), t = 1 − d·s, k = 1/β², restricted to
        // t ≤ Q = min(LOBE_CUTOFF·β², 2), symmetry gives Lpre(d) = 1 + ½·d_x·⟨d·s⟩ with
        // ⟨d·s⟩ = 1 − ⟨t⟩ and, since dω = 2π dt, ⟨t⟩ = 1/k − Q/(e^{kQ} − 1) (the mean of an
        // exponential truncated at Q). The cube quadrature, at a face where texels are ≤ β wide,
        // must reproduce that: tolerance 2e-4 absolute, the size of the O(h²) shrinkage of a
        // texel-averaged unit vector at face 32 (h²/24 ≈ 1.6e-4) that enters through the
        // stored texel values.
        let m = 32;
        let mut cube = CubeImage::new(m);
        for (index, texel) in cube.texels.iter_mut().enumerate() {
            let (f, i, j) = texel_of_index(index, m as usize);
            *texel = rgba([1.0 + 0.5 * texel_direction(f, i, j, m).x; 3]);
        }
        for beta in [0.07, 0.2, 0.5, 1.0] {
            let k = 1.0 / (beta * beta);
            let q_cut = (LOBE_CUTOFF * beta * beta).min(2.0);
            let mean_cos = 1.0 - 1.0 / k + q_cut / (k * q_cut).exp_m1();
            let blurred = blur_layer(&cube, beta);
            let mut worst = 0.0f64;
            for (index, texel) in blurred.texels.iter().enumerate() {
                let (f, i, j) = texel_of_index(index, m as usize);
                let want = 1.0 + 0.5 * texel_direction(f, i, j, m).x * mean_cos;
                worst = worst.max((f64::from(texel[0]) - want).abs());
            }
            println!("langevin β {beta}: {worst:e}");
            assert!(worst < 2e-4, "β = {beta}: worst {worst:e}");
        }
    }

    #[test]
    fn irradiance_of_a_linear_radiance_is_the_cosine_lobe_closed_form() {
        // L(s) = 1 + s_y: E(n) = π + ∫ s_y·max(n·s, 0) dω = π + (2π/3)·n_y (the second term: the
        // first moment of the clamped cosine is (2π/3)·n). The oracle normalises by its own
        // Σ max(n·s, 0)·dω, which scales the whole E; at face 32 both sums are second-order
        // accurate, so 1e-3 relative.
        let m = 32;
        let mut cube = CubeImage::new(m);
        for (index, texel) in cube.texels.iter_mut().enumerate() {
            let (f, i, j) = texel_of_index(index, m as usize);
            *texel = rgba([1.0 + texel_direction(f, i, j, m).y; 3]);
        }
        let e = irradiance(&cube);
        let pi = std::f64::consts::PI;
        for (index, texel) in e.texels.iter().enumerate() {
            let (f, i, j) = texel_of_index(index, m as usize);
            let want = pi + 2.0 * pi / 3.0 * texel_direction(f, i, j, m).y;
            assert!(
                (f64::from(texel[0]) - want).abs() < 1e-3 * want,
                "{texel:?} vs {want}"
            );
        }
    }

    #[test]
    fn invalid_inputs_are_errors() {
        let src = Equirect::constant(8, 4, [1.0; 3]);
        let good = PrefilterParams {
            face_size: 16,
            layers: 2,
            beta_min: 0.5,
            beta_max: 0.5,
            layer_texel: 1.0,
            small_layer_texel: 1.0,
            fine_layers: 0,
            blur_net_of_read: false,
            supersample_scale: 1,
        };
        assert!(prefilter_cpu(&src, &good, EnvironmentLight::new(f64::NAN, 0.0)).is_err());
        assert!(prefilter_cpu(&src, &good, EnvironmentLight::new(-1.0, 0.0)).is_err());
        assert!(prefilter_cpu(&src, &good, EnvironmentLight::new(1.0, f64::INFINITY)).is_err());
        assert!(prefilter_cpu(
            &src,
            &PrefilterParams {
                face_size: 12,
                ..good
            },
            EnvironmentLight::default()
        )
        .is_err());
        let broken = Equirect {
            width: 8,
            height: 4,
            pixels: vec![[1.0; 3]; 3],
        };
        assert!(prefilter_cpu(&broken, &good, EnvironmentLight::default()).is_err());
        assert!(prefilter_cpu(&src, &good, EnvironmentLight::default()).is_ok());
    }
}
