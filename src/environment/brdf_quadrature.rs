//! SPEC §4's `brdf` environment model as a fixed quadrature on the CPU: the twin of the shader's
//! (shaders/common/brdf_environment.glsl), formula by formula, in f64. The specular integral
//! ∫ f_spec·L·(N·s) dω is estimated with the same `samples` points for every pixel (a Fibonacci
//! lattice: no noise, no per-pixel random numbers), each a half vector drawn from the Beckmann lobe,
//! so the weight of the reflected direction s is F·G·(V·H)/(nv·nh). Each s reads the prefiltered
//! layers at the blur whose lobe covers the sample's share of the sphere, 1/(samples·pdf(s))
//! (filtered importance sampling, Křivánek & Colbert, GPU Gems 3 ch. 20), which is what keeps a
//! sharp layer from aliasing. The lookups are bilinear over texel centres with one seam rule: a
//! tap beyond its face reads the texel holding the tap's direction on the face that direction
//! selects (the shaders read it from each face's apron, [`apron_texels`]), and every texel is
//! read as the shaders store it, its channels rounded to `LAYER_CODE_BITS` bits
//! (`layer_pair.rs`). `brdf_definition.rs` is the brute-force ground truth it converges to.

use glam::DVec3;
use std::f64::consts::PI;

use super::brdf_definition::specular_albedo;
use super::brdf_lattice::specular_lattice;
use super::bright::BrightLight;
use super::cube::{direction_to_face, face_direction};
use super::image::{CubeImage, PrefilteredEnvironment};
use super::layer_pair;
use super::params::{layer_blend, texel_read_variance};
use super::sharp_source::SharpSource;
use crate::gpu::shaders::interface::{
    ALBEDO_KNOTS, BRIGHT_LOBE_CULL, ENV_VARIATE_SAMPLES, FIBONACCI_STEP,
};
use crate::model::brdf::cook_torrance_g;
use crate::model::{BrdfParams, FresnelTable};

/// Lobe samples per point the camera sees (the shaders' `ENV_SAMPLES`), for the materials
/// filtered importance sampling serves (m above `LATTICE_M_LO`): the cost and accuracy are
/// measured in BENCHMARKS.md ("The `brdf` environment model"). At 32 a rough sphere under a
/// studio map was 6 % off in its inner part; at 128, 2.3 %. At 128 the courtyard's 112 points
/// were still 2.5 % off on average at m = 0.5 (p99 18 %), at 512 1.0 % (5.7 %), at 1,024 0.46 %
/// (3.9 %), at 2,048 0.23 % (1.2 %): the lookups' blur widens the lobe by a share that falls as
/// 1/samples. 1,024 left the top of a sphere in perspective, which reflects the courtyard's dark
/// zenith with bright walls in the lobe's tails, +10 % off (p99 5.1 % on a 32² view; 2.7 % at
/// 2,048, 1.4 % at 4,096) for 1.8× the draw's time (a 512² m = 0.5 sphere on lavapipe, whole
/// process, 2.45 → 4.5 s). Only the materials above `FIS_M_LO` pay for it (the presets use the
/// lattice and the grid).
pub const BRDF_SAMPLES: u32 = 2048;

/// Lobe samples at the hits of the light between objects' paths (`ENV_HIT_SAMPLES`): every
/// ray pays them, and the paths' own noise is larger than the quadrature's error at 32.
pub const BRDF_HIT_SAMPLES: u32 = 32;

/// The specular directional albedo A(nv) = ∫ f_spec·(N·s) dω_s of a material at the
/// `ALBEDO_KNOTS` knots nv = (k/(ALBEDO_KNOTS − 1))², as the shaders read them: (nv, A_r, A_g,
/// A_b). The knots crowd towards grazing, where A changes fastest.
/// The quadrature is normalised by it (see [`specular_quadrature`]); computed with
/// `brdf_definition::specular_albedo` at 256 × 64 half vectors (within 1e-4 of 2048 × 256, which
/// agrees with the brute force to 5e-6).
pub fn albedo_knots(brdf: &BrdfParams, fresnel: &FresnelTable) -> Vec<[f32; 4]> {
    let last = (ALBEDO_KNOTS - 1) as f64;
    (0..ALBEDO_KNOTS)
        .map(|k| {
            let nv = (k as f64 / last).powi(2);
            let a = specular_albedo(brdf, fresnel, nv, 256, 64);
            [nv as f32, a[0] as f32, a[1] as f32, a[2] as f32]
        })
        .collect()
}

/// A(nv) from [`albedo_knots`], linear in √nv between knots (twin of brdf_environment.glsl's
/// `albedo_at`).
pub fn albedo_at(knots: &[[f32; 4]], nv: f64) -> [f64; 3] {
    let last = knots.len().saturating_sub(1);
    if last == 0 {
        return [0.0; 3];
    }
    let x = nv.clamp(0.0, 1.0).sqrt() * last as f64;
    let k = (x.floor() as usize).min(last - 1);
    let t = x - k as f64;
    std::array::from_fn(|c| {
        let (a, b) = (f64::from(knots[k][c + 1]), f64::from(knots[k + 1][c + 1]));
        a + (b - a) * t
    })
}

/// Albedo knots per material, kept by the renderer: only m and the Fresnel table change them,
/// and computing them (~1 M BRDF evaluations) costs more than a small render.
#[derive(Default)]
pub struct AlbedoCache {
    entries: Vec<(Vec<u64>, Vec<[f32; 4]>)>,
}

impl AlbedoCache {
    /// Distinct materials kept; the oldest goes first.
    const CAPACITY: usize = 64;

    pub fn knots(&mut self, brdf: &BrdfParams, fresnel: &FresnelTable) -> Vec<[f32; 4]> {
        let key: Vec<u64> = std::iter::once(brdf.beckmann_m.to_bits())
            .chain(fresnel.angles_deg().iter().map(|a| a.to_bits()))
            .chain(fresnel.rgb().iter().flat_map(|c| c.map(f64::to_bits)))
            .collect();
        if let Some((_, knots)) = self.entries.iter().find(|(k, _)| *k == key) {
            return knots.clone();
        }
        let knots = albedo_knots(brdf, fresnel);
        if self.entries.len() >= Self::CAPACITY {
            self.entries.remove(0);
        }
        self.entries.push((key, knots.clone()));
        knots
    }
}

/// Point i of n of the Fibonacci lattice: ((i + ½)/n, frac(i·(√5 − 1)/2)). Against the Hammersley
/// set (radical inverse of i in base 2) it cut the rough materials' error on the courtyard by a
/// fifth at the same count (BENCHMARKS.md, "The `brdf` environment model"). The azimuth is the
/// golden fraction's multiple in fixed point (`FIBONACCI_STEP`), the top 24 bits of i·step mod
/// 2³², which the shader holds exactly in f32.
pub fn fibonacci_point(i: u32, n: u32) -> (f64, f64) {
    let u = (f64::from(i) + 0.5) / f64::from(n);
    let turn = i.wrapping_mul(FIBONACCI_STEP) >> 8;
    (u, f64::from(turn) / f64::from(1u32 << 24))
}

/// The specular part of the `brdf` model at a surface point with `samples` lobe samples (unit
/// `n`, `v`, world frame; the cubes are in the world frame already, rotated and scaled by the
/// prefilter), `albedo` the material's [`albedo_knots`]. The weighted mean of the lookups is
/// scaled by A(nv), Σ w·L / Σ w · A(nv) per channel: a ratio estimator, exact in a white furnace
/// at every nv (the plain mean misses A by up to 11 % at grazing, where the lobe samples meet the
/// horizon unevenly).
pub fn specular_quadrature(
    env: &PrefilteredEnvironment,
    samples: u32,
    (brdf, fresnel, albedo): (&BrdfParams, &FresnelTable, &[[f32; 4]]),
    n: DVec3,
    v: DVec3,
) -> [f64; 3] {
    let Some(Incidence {
        nv,
        tangent,
        bitangent,
    }) = incidence(n, v)
    else {
        return [0.0; 3];
    };
    let m2 = brdf.beckmann_m * brdf.beckmann_m;
    let count = samples.max(1);
    let mut sums = LookupSums::default();
    for i in 0..count {
        let (u, w) = fibonacci_point(i, count);
        // u = 1 − exp(−tan²θ_H/m²): the Beckmann lobe's distribution of D·cos θ_H.
        let rest = 1.0 - u;
        let tan2 = -m2 * rest.ln();
        let cos_h = 1.0 / (1.0 + tan2).sqrt();
        let sin_h = tan2.sqrt() * cos_h;
        let (sin_phi, cos_phi) = (2.0 * PI * w).sin_cos();
        let h = tangent * (sin_h * cos_phi) + bitangent * (sin_h * sin_phi) + n * cos_h;
        // pdf(s) = D·cos θ_H/(4·V·H) with D = (1 − u)/(π m² cos⁴θ_H); the lookup's lobe 2πβ²
        // covers 1/(samples·pdf).
        let beta = |vh: f64| {
            let pdf = rest / (4.0 * PI * m2 * cos_h * cos_h * cos_h * vh);
            (1.0 / (2.0 * PI * f64::from(count) * pdf)).sqrt()
        };
        sums.add(env, fresnel, (n, v, nv), h, 1.0, beta);
    }
    sums.normalized(albedo, nv)
}

/// A quadrature's weighted sums per channel: Σ w·Lpre(s, β) and Σ w.
#[derive(Default)]
pub(super) struct LookupSums {
    sum: [f64; 3],
    weights: [f64; 3],
}

impl LookupSums {
    /// One [`lookup`] of the layers at `beta(V·H)`, added to the sums.
    fn add(
        &mut self,
        env: &PrefilteredEnvironment,
        fresnel: &FresnelTable,
        incidence: (DVec3, DVec3, f64),
        h: DVec3,
        scale: f64,
        beta: impl FnOnce(f64) -> f64,
    ) {
        let read = |s: DVec3, vh: f64| layered_radiance(env, s, beta(vh));
        self.add_read(fresnel, incidence, h, scale, read);
    }

    /// One [`lookup`] with the radiance at s from `read(s, V·H)`, added to the sums.
    fn add_read(
        &mut self,
        fresnel: &FresnelTable,
        incidence: (DVec3, DVec3, f64),
        h: DVec3,
        scale: f64,
        read: impl FnOnce(DVec3, f64) -> [f64; 3],
    ) {
        if let Some((weight, radiance)) = lookup(fresnel, incidence, h, scale, read) {
            self.push(weight, radiance, 1.0);
        }
    }

    /// One lookup's weight and radiance, each weight times `factor`.
    pub(super) fn push(&mut self, weight: [f64; 3], radiance: [f64; 3], factor: f64) {
        for c in 0..3 {
            self.sum[c] += factor * weight[c] * radiance[c];
            self.weights[c] += factor * weight[c];
        }
    }

    /// The sums with each lookup's weight times (1 − tilt·p), from `moments`, the same lookups
    /// pushed with factor p.
    pub(super) fn tilted(&self, moments: &LookupSums, tilt: f64) -> LookupSums {
        LookupSums {
            sum: std::array::from_fn(|c| self.sum[c] - tilt * moments.sum[c]),
            weights: std::array::from_fn(|c| self.weights[c] - tilt * moments.weights[c]),
        }
    }

    /// Σ w·L / Σ w · A(nv) per channel: exact in a white furnace.
    pub(super) fn normalized(&self, albedo: &[[f32; 4]], nv: f64) -> [f64; 3] {
        let a = albedo_at(albedo, nv);
        std::array::from_fn(|c| match self.weights[c] > 0.0 {
            true => self.sum[c] / self.weights[c] * a[c],
            false => 0.0,
        })
    }
}

/// One lookup: the reflection s of V about the half vector h, its weight per channel
/// scale·F(acos V·H)·G·(V·H)/(nv·nh) and its radiance `read(s, V·H)`; None where s or h is
/// below the surface.
pub(super) fn lookup(
    fresnel: &FresnelTable,
    (n, v, nv): (DVec3, DVec3, f64),
    h: DVec3,
    scale: f64,
    read: impl FnOnce(DVec3, f64) -> [f64; 3],
) -> Option<([f64; 3], [f64; 3])> {
    let cos_h = n.dot(h);
    let vh = v.dot(h);
    let s = 2.0 * vh * h - v;
    let nl = n.dot(s);
    if !(scale > 0.0 && vh > 0.0 && nl > 0.0) {
        return None;
    }
    let g = cook_torrance_g(cos_h, nv, nl, vh);
    let f = fresnel.eval(vh.min(1.0).acos().to_degrees());
    let weight = scale * g * vh / (nv * cos_h);
    Some((f.map(|f| f * weight), read(s, vh)))
}

/// The share of the reach over which the node weights fall to 0 ([`lattice_taper`]; the lattice
/// and the grid).
pub const LATTICE_TAPER: f64 = 0.2;
/// The roughness bands of the hand-overs (`Frame::env_lattice_band`): the lattice alone up to
/// `LATTICE_M_LO`, then blended linearly in m into the grid, alone from `LATTICE_M_HI`; the grid
/// blended into filtered importance sampling from `FIS_M_LO`, which is alone from `FIS_M_HI`.
/// Measured in BENCHMARKS.md: the smooth preset (m = 0.05) keeps the lattice and its cost, the
/// rough one (0.2) gets the grid, m = 0.5 filtered importance sampling. At m = 0.05 a grid (blur
/// share 0.5) would meet the p99, which the lattice misses even with exact lookups, but
/// took the default scene's `brdf` draw from 1.4 to 6× `paper`'s ("The smooth preset's error").
pub const LATTICE_M_LO: f64 = 0.06;
pub const LATTICE_M_HI: f64 = 0.07;
/// Where the camera looks the lattice reads the rough split (its blocks all lights, so no light
/// box is left in the layers for the lattice's tails to meet) when the split's blocks are at most
/// `ROUGH_LATTICE_BLOCK`·m across; below that a block as a point light is too wide for the
/// lobe and the lattice keeps the first split. Measured in BENCHMARKS.md ("The lattice on the
/// rough split").
pub const ROUGH_LATTICE_BLOCK: f64 = 1.5;
pub const FIS_M_LO: f64 = 0.22;
pub const FIS_M_HI: f64 = 0.3;
/// The deconvolved slope grid's constants (`specular_grid`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridConstants {
    /// t, the share of the lobe's width across the plane of incidence that the lookups' blur
    /// supplies.
    pub blur_share: f64,
    /// The node spacing in units of the blur.
    pub spacing: f64,
    /// The reach in standard deviations of the nodes' distribution.
    pub reach: f64,
    /// Most nodes on each side along the plane.
    pub max_half: u32,
}

/// The grid of the points the camera sees. Measured in BENCHMARKS.md ("The grid's blur and
/// reach"); packed into `Frame::env_grid`.
/// The blur is a Gaussian in directions, which is a Gaussian in slopes only near the mirror
/// direction: with lookups at exactly the blur asked (brute force over the map's pixels) the grid
/// at t = 0.45 was still 1.14 % off on the courtyard's 112 points at m = 0.2 (one dark point
/// +13 %), however far it reached. With less of the lobe in the blur the nodes carry its tails, where a
/// dark point's light is: nodes reading single pixels at t = 0.05 were −13 % off at the board seen
/// 10° from its normal with a reach of 3.6 σ, −0.8 % at 5. From t = 0.45, spacing 1.7, reach 3.6
/// and 32 nodes a side (57 lookups face-on, 431 at most) to these (377 face-on; 2,205 at most, at
/// grazing) the 112 points at m = 0.2 went from 1.08 / 6.5 % (mean / p99) to 0.28 / 1.9 % on the
/// courtyard, 0.64 / 4.3 to 0.32 / 2.8 % on the studio. Fewer than 64 nodes a side hold the step
/// wider than the blur at grazing (at 48 one of the courtyard's points was 6.8 % off, against 3.3 %
/// at 64, in the residual's term alone). The blur share then went from 0.2 to 0.15 (2026-12-06):
/// the top of a sphere in perspective reflects the courtyard's dark zenith, with bright walls in
/// the lobe's tails, and there the grid read +7 % at 0.2 (the error grows as the share squared:
/// +22 % at 0.4, +1.5 % at 0.1), p99 5.6 % on a 32² view, 2.8 % at 0.15; the 112 points at
/// m = 0.2 0.28 / 1.9 → 0.22 / 1.6 % (courtyard), 0.32 / 2.7 % (studio, with the share kept at
/// 0.2 towards grazing by [`GRID_GRAZING`]; 2.9 % without). It costs
/// (0.2/0.15)² the lookups face-on (681 at nv = 1, 1,747 at 0.4, 2,967 at most): a 512² sphere
/// at m = 0.2, whole process on lavapipe, 2.18 → 3.12 s. At 0.1 the p99 of a 40² view was 1.0 %
/// for 4× the lookups; 0.1 at a spacing of 3 (the same count as
/// 0.15 at 2) rippled (studio 112 points 0.48 %), and at 4 more so (BENCHMARKS.md, "A dark zenith").
pub const GRID: GridConstants = GridConstants {
    blur_share: 0.15,
    spacing: 2.0,
    reach: 4.5,
    max_half: 64,
};
/// The least blur share of a grid towards grazing ([`grid_blur_share`]): `share` up to nv =
/// `nv_full`, nothing from `nv_none`, a smoothstep between.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GrazingShare {
    pub share: f64,
    pub nv_full: f64,
    pub nv_none: f64,
}

/// [`GRID`]'s blur share of 0.2 where it was measured best at grazing: at 0.15 the studio board
/// seen 80° from its normal (nv = 0.17) at m = 0.2 read 1.01 / 3.4 % (mean / p99) instead of
/// 0.94 / 2.8 %, at 0.1 1.07 / 4.4 %. The dark zenith the smaller share is for is seen at nv ≈
/// 0.45–0.65. Below `VARIATE_GRID`'s share, so that grid is unchanged. Packed into
/// `Frame::env_grid_grazing` (BENCHMARKS.md, "A dark zenith").
pub const GRID_GRAZING: GrazingShare = GrazingShare {
    share: 0.2,
    nv_full: 0.25,
    nv_none: 0.45,
};

/// A grid's blur share at nv: its own, but at least [`GRID_GRAZING`]'s towards grazing (twin of
/// brdf_environment.glsl's `grid_blur_share`); continuous in nv.
pub fn grid_blur_share(grid: &GridConstants, nv: f64) -> f64 {
    let g = &GRID_GRAZING;
    let x = ((nv - g.nv_full) / (g.nv_none - g.nv_full)).clamp(0.0, 1.0);
    let floor = g.share * (1.0 - smoothstep01(x));
    grid.blur_share.max(floor)
}

/// The grid of `paper`'s control variate (`ENV_VARIATE_SAMPLES`), which needs only an estimate of
/// the integral and should not pay the `brdf` model's accuracy: the grid before [`GRID`]. With
/// [`GRID`] there a ray-traced `paper` render of the default scene with rough bowls at 512² took
/// 3.9–4.1 s instead of 3.2–3.4 s (BENCHMARKS.md). Packed into `Frame::env_variate_grid`.
pub const VARIATE_GRID: GridConstants = GridConstants {
    blur_share: 0.45,
    spacing: 1.7,
    reach: 3.6,
    max_half: 32,
};

/// The grid a `brdf_specular` with `samples` lobe samples reads (twin of brdf_environment.glsl's
/// choice): [`VARIATE_GRID`] for `paper`'s control variate, [`GRID`] otherwise.
pub fn grid_for(samples: u32) -> &'static GridConstants {
    match samples == ENV_VARIATE_SAMPLES {
        true => &VARIATE_GRID,
        false => &GRID,
    }
}

/// The least m whose lattice reads the rough split, for blocks `block_angle` radians across
/// ([`ROUGH_LATTICE_BLOCK`]), as `Frame::env_lattice_share.y` holds it: the shader compares the
/// material's m in f32 with it, and so does [`brdf_specular`].
pub fn rough_lattice_m(block_angle: f64) -> f32 {
    (block_angle / ROUGH_LATTICE_BLOCK) as f32
}

/// Each quadrature's share of the `brdf` model's lookups for roughness m (lattice, grid,
/// filtered importance sampling; they sum to 1). `camera`: the point the camera sees; at a
/// path's hit (false) filtered importance sampling with its few samples takes the grid's share,
/// since every ray would pay the grid's 377–2,205 lookups and the path's own noise is larger than
/// either quadrature's error.
pub fn quadrature_shares(m: f64, camera: bool) -> [f64; 3] {
    let lattice = ((LATTICE_M_HI - m) / (LATTICE_M_HI - LATTICE_M_LO)).clamp(0.0, 1.0);
    let fis = ((m - FIS_M_LO) / (FIS_M_HI - FIS_M_LO)).clamp(0.0, 1.0);
    match camera {
        true => [lattice, 1.0 - lattice - fis, fis],
        false => [lattice, 0.0, 1.0 - lattice],
    }
}

/// The node weights' taper over the last `LATTICE_TAPER` of the reach (x = |p| / reach): 1 inside, a
/// smoothstep down to 0 at the reach, so a node that enters the lattice as nv changes enters with
/// weight 0 and the estimate stays continuous in nv.
pub fn lattice_taper(x: f64) -> f64 {
    smoothstep01(((1.0 - x) / LATTICE_TAPER).clamp(0.0, 1.0))
}

/// 3t² − 2t³ on [0, 1], as the shaders write it out (`smoothstep01`).
pub(super) fn smoothstep01(t: f64) -> f64 {
    t * t * (3.0 - 2.0 * t)
}

/// The specular part of the `brdf` model for a wider lobe, by a grid of Beckmann slopes whose
/// Gaussian is the lobe's less the lookups' blur (a deconvolution). The integral is the mean over
/// the slope distribution (Gaussian, σ² = m²/2 per axis) of F·G·(V·H)/(nv·nh)·L(s). A lookup
/// blurred by β in directions is, near the mirror direction, a slope blur of β/2 along the plane
/// of incidence and β/(2·nv) across it (the reflection's Jacobian: 2 and 2·nv), so nodes drawn
/// from a Gaussian of variances σ² − (β/2)² and σ² − (β/(2nv))², each read at β, sum to the lobe
/// with the blur's width restored instead of added (filtered importance sampling adds it). β =
/// t·2·nv·σ (t = `grid.blur_share`); the nodes lie on a regular grid `grid.spacing`·β apart in
/// directions (no ripple from a grid that fine under a Gaussian that wide), out to `grid.reach`
/// deviations, tapered like the lattice. Away from the mirror direction the Jacobian changes, so
/// each node reads the blur that is the same slope blur there: β scaled by the geometric mean of
/// its Jacobian's two axes against theirs at the centre ([`node_blur`]). Normalised by A(nv) like
/// [`specular_quadrature`].
pub fn specular_grid(
    env: &PrefilteredEnvironment,
    grid: &GridConstants,
    (brdf, fresnel, albedo): (&BrdfParams, &FresnelTable, &[[f32; 4]]),
    n: DVec3,
    v: DVec3,
) -> [f64; 3] {
    let Some(Incidence {
        nv,
        tangent,
        bitangent,
    }) = incidence(n, v)
    else {
        return [0.0; 3];
    };
    let sigma = brdf.beckmann_m / std::f64::consts::SQRT_2;
    let beta = 2.0 * nv * sigma * grid_blur_share(grid, nv);
    // The nodes' variances along and across the plane: the lobe's less the lookups' blur.
    let var_along = sigma * sigma - (0.5 * beta).powi(2);
    let var_across = sigma * sigma - (0.5 * beta / nv).powi(2);
    let step_across = grid.spacing * 0.5 * beta / nv;
    let step_along =
        (grid.spacing * 0.5 * beta).max(grid.reach * var_along.sqrt() / f64::from(grid.max_half));
    let half_along = (grid.reach * var_along.sqrt() / step_along).ceil() as i32;
    let half_across = (grid.reach * var_across.sqrt() / step_across).ceil() as i32;
    let mut sums = LookupSums::default();
    for i in -half_along..=half_along {
        for j in -half_across..=half_across {
            let (x, y) = (f64::from(i) * step_along, f64::from(j) * step_across);
            let r = (x * x / var_along + y * y / var_across).sqrt();
            if r >= grid.reach {
                continue;
            }
            let scale = (-0.5 * r * r).exp() * lattice_taper(r / grid.reach);
            let h = (n + tangent * x + bitangent * y).normalize();
            let vh = v.dot(h);
            if vh > 0.0 {
                let blur = node_blur(v, h, (tangent, bitangent), (x, y), beta, nv);
                sums.add(env, fresnel, (n, v, nv), h, scale, |_| blur);
            }
        }
    }
    sums.normalized(albedo, nv)
}

/// The blur of the grid's node at slopes (x, y), half vector h = normalize(n + x·tangent +
/// y·bitangent): β·√(J_x·J_y / (2·2·nv)), J the lengths of ∂s/∂x and ∂s/∂y (2 and 2·nv at the
/// centre). With ∂h = (a − h·(h·a))/√(1 + x² + y²) for axis a, ∂s = 2·((V·∂h)·h + (V·H)·∂h), and ∂h ⊥ h.
fn node_blur(
    v: DVec3,
    h: DVec3,
    (tangent, bitangent): (DVec3, DVec3),
    (x, y): (f64, f64),
    beta: f64,
    nv: f64,
) -> f64 {
    let inv_len = 1.0 / (1.0 + x * x + y * y).sqrt();
    let vh = v.dot(h);
    let jacobian = |axis: DVec3| {
        let dh = (axis - h * h.dot(axis)) * inv_len;
        2.0 * (v.dot(dh).powi(2) + vh * vh * dh.length_squared()).sqrt()
    };
    beta * (jacobian(tangent) * jacobian(bitangent) / (4.0 * nv)).sqrt()
}

/// Where every quadrature starts: nv and the frame of the plane of incidence.
pub(super) struct Incidence {
    pub(super) nv: f64,
    /// Towards V's projection (any axis at normal incidence): the quadratures' patterns are
    /// symmetric about it and move continuously with V.
    pub(super) tangent: DVec3,
    /// N × tangent.
    pub(super) bitangent: DVec3,
}

/// The incidence at unit `n`, `v`; None where V is at or below the surface (or NaN).
pub(super) fn incidence(n: DVec3, v: DVec3) -> Option<Incidence> {
    let nv = n.dot(v);
    if nv.is_nan() || nv <= 0.0 {
        return None;
    }
    let along = v - nv * n;
    let other = if n.x.abs() < 0.5 { DVec3::X } else { DVec3::Y };
    let tangent = if along.length_squared() > 1e-12 {
        along.normalize()
    } else {
        n.cross(other).normalize()
    };
    Some(Incidence {
        nv,
        tangent,
        bitangent: n.cross(tangent),
    })
}

/// The map's bright lights (bright.rs) through the specular lobe, Σ f_spec·E·(N·l) with each
/// light's spread folded into the lobe ([`bright_light`]), each light beyond [`light_cull_cos`]
/// of the mirror direction skipped: the twin of brdf_environment.glsl's `bright_specular`.
pub fn bright_specular(
    lights: &[BrightLight],
    brdf: &BrdfParams,
    fresnel: &FresnelTable,
    n: DVec3,
    v: DVec3,
) -> [f64; 3] {
    let nv = n.dot(v);
    let mut sum = [0.0; 3];
    if nv <= 0.0 {
        return sum;
    }
    let r = 2.0 * nv * n - v;
    for light in lights {
        let cull = light_cull_cos(brdf.beckmann_m, light.spread);
        if r.dot(light.direction) < cull {
            continue;
        }
        let term = bright_light(brdf, fresnel, (n, v, nv), light);
        for c in 0..3 {
            sum[c] += term[c];
        }
    }
    sum
}

/// One bright light through the specular lobe, f_spec·E·(N·l) = F·D'·G·E/(4·nv), where D' is
/// Beckmann's D convolved with the light's spread σ² (`BrightLight::spread`): in slope space D is
/// a Gaussian of variance m²/2 per axis, and a light spread by σ² per axis about l spreads the
/// half vector by σ²/4 along the plane of V and l (H bisects V and l) and by σ²/(4·(V·H)²)
/// across it (|V + l| = 2·V·H), so D' = exp(−x²/m_x² − y²/m_y²)/(π·m_x·m_y·(N·H)⁴) with
/// m_x² = m² + σ²/2, m_y² = m² + σ²/(2·(V·H)²) and (x, y) H's slope along and across that
/// plane. With σ² = 0 it is D (SPEC §2); for a block as wide as the lobe it keeps the second
/// moment a point light loses (BENCHMARKS.md, "Lights with a spread").
pub fn bright_light(
    brdf: &BrdfParams,
    fresnel: &FresnelTable,
    (n, v, nv): (DVec3, DVec3, f64),
    light: &BrightLight,
) -> [f64; 3] {
    let l = light.direction;
    let nl = n.dot(l);
    let half = v + l;
    let half_len = half.length();
    if nl <= 0.0 || half_len <= 0.0 {
        return [0.0; 3];
    }
    let h = half / half_len;
    let (nh, vh) = (n.dot(h), v.dot(h));
    if nh <= 0.0 || vh <= 0.0 {
        return [0.0; 3];
    }
    let d = spread_beckmann_d(
        brdf.beckmann_m,
        light.spread,
        (n, v, l),
        (nh, vh),
        n.cross(h),
    );
    let g = cook_torrance_g(nh, nv, nl, vh);
    let f = fresnel.eval(vh.min(1.0).acos().to_degrees());
    std::array::from_fn(|c| f[c] * (d * g / (4.0 * nv)) * light.irradiance[c])
}

/// D' of [`bright_light`]: `c` = N × H. The slope across the plane of V and l (unit normal e) is
/// −N·e/√(1 − (N·e)²), as H lies in that plane; the rest of tan²θ_H is along it.
fn spread_beckmann_d(
    m: f64,
    spread: f64,
    (n, v, l): (DVec3, DVec3, DVec3),
    (nh, vh): (f64, f64),
    c: DVec3,
) -> f64 {
    let nh2 = nh * nh;
    let tan2 = c.length_squared() / nh2;
    let across = v.cross(l);
    let across2 = across.length_squared();
    let ne2 = match across2 > 0.0 {
        true => n.dot(across).powi(2) / across2,
        false => 0.0,
    };
    // V ∥ l (no plane: H = V) leaves all of tan²θ_H along.
    let y2 = match ne2 < 1.0 {
        true => (ne2 / (1.0 - ne2)).min(tan2),
        false => 0.0,
    };
    let x2 = tan2 - y2;
    let m2 = m * m;
    let mx2 = m2 + 0.5 * spread;
    let my2 = m2 + 0.5 * spread / (vh * vh);
    (-x2 / mx2 - y2 / my2).exp() / (PI * (mx2 * my2).sqrt() * nh2 * nh2)
}

/// cos of the largest angle between the mirror direction R and a light of spread σ² that
/// [`bright_specular`] keeps for roughness m: 2·θ_max with tan²θ_max = `BRIGHT_LOBE_CULL`·(m² +
/// σ²/2), the slopes where the widened D' of [`bright_light`] is above e^-9 of its peak along the
/// plane (reflection about H is reflection about N turned by 2·∠(N, H); across the plane D' is
/// wider in slopes by 1/(V·H), and the reflection narrower by V·H, the same reach in
/// directions). cos 2θ = (1 − tan²θ)/(1 + tan²θ), without trigonometry, as the shader's
/// `light_cull_cos`.
pub fn light_cull_cos(m: f64, spread: f64) -> f64 {
    let t2 = f64::from(BRIGHT_LOBE_CULL) * (m * m + 0.5 * spread);
    (1.0 - t2) / (1.0 + t2)
}

/// What the `brdf` model reads on the CPU, as a draw does on the device
/// (`GpuEnvironment::brdf_sources`): the bright split's residual layers and lights
/// (`bright::split_bright`), and the rough split's (`bright::split_bright_rough`) with the size of
/// its blocks, whose layers the grid and filtered importance sampling read where the camera
/// looks, and the lattice from [`rough_lattice_m`] up.
#[derive(Clone, Copy)]
pub struct BrdfSources<'a> {
    pub residual: &'a PrefilteredEnvironment,
    pub lights: &'a [BrightLight],
    pub rough_residual: &'a PrefilteredEnvironment,
    pub rough_lights: &'a [BrightLight],
    /// The rough split's blocks' size (radians, `BrightSplit::block_angle`).
    pub rough_block_angle: f64,
    /// The two residuals' own pixels for the lattice's sharp reads (`None` for a map too wide
    /// for them, or without them: the layers alone).
    pub sharp: Option<&'a SharpSource>,
    pub rough_sharp: Option<&'a SharpSource>,
}

impl<'a> BrdfSources<'a> {
    /// A map read as it is, for every quadrature, with no lights (a map with no bright part).
    pub fn unsplit(env: &'a PrefilteredEnvironment) -> Self {
        Self {
            residual: env,
            lights: &[],
            rough_residual: env,
            rough_lights: &[],
            rough_block_angle: 0.0,
            sharp: None,
            rough_sharp: None,
        }
    }
}

/// The `brdf` model's specular term as the renderer computes it: lookups by the lattice, the grid,
/// filtered importance sampling with `samples` samples, or two of them blended, as
/// [`quadrature_shares`] says for the material's m, plus the bright lights. The grid serves the
/// points the camera sees (`samples` above `BRDF_HIT_SAMPLES`: `BRDF_SAMPLES`, or
/// `ENV_VARIATE_SAMPLES` for `paper`'s control variate, each with its grid, [`grid_for`]); at a
/// path's hit (`BRDF_HIT_SAMPLES`) filtered importance sampling takes its share. Where the camera
/// looks the grid and filtered importance sampling read the rough split, and the lattice does from
/// [`rough_lattice_m`] up; each split's lights take the share of the lookups that read its
/// residual. Everything at a path's hit reads the bright split.
pub fn brdf_specular(
    sources: BrdfSources<'_>,
    samples: u32,
    material: (&BrdfParams, &FresnelTable, &[[f32; 4]]),
    n: DVec3,
    v: DVec3,
) -> [f64; 3] {
    let camera = samples > BRDF_HIT_SAMPLES;
    let m = material.0.beckmann_m;
    let shares = quadrature_shares(m, camera);
    let lattice_rough = camera && m as f32 >= rough_lattice_m(sources.rough_block_angle);
    let (rough, rough_share) = match camera {
        true => (sources.rough_residual, shares[1] + shares[2]),
        false => (sources.residual, 0.0),
    };
    let (lattice_residual, rough_share) = match lattice_rough {
        true => (
            (sources.rough_residual, sources.rough_sharp),
            rough_share + shares[0],
        ),
        false => ((sources.residual, sources.sharp), rough_share),
    };
    let mut lookups = [0.0; 3];
    let mut add = |share: f64, quadrature: &dyn Fn() -> [f64; 3]| {
        if share > 0.0 {
            let value = quadrature();
            for c in 0..3 {
                lookups[c] += share * value[c];
            }
        }
    };
    add(shares[0], &|| {
        specular_lattice(lattice_residual, material, n, v)
    });
    add(shares[1], &|| {
        specular_grid(rough, grid_for(samples), material, n, v)
    });
    add(shares[2], &|| {
        specular_quadrature(rough, samples, material, n, v)
    });
    let mut bright = [0.0; 3];
    for (share, lights) in [
        (1.0 - rough_share, sources.lights),
        (rough_share, sources.rough_lights),
    ] {
        if share > 0.0 {
            let term = bright_specular(lights, material.0, material.1, n, v);
            for c in 0..3 {
                bright[c] += share * term[c];
            }
        }
    }
    std::array::from_fn(|c| lookups[c] + bright[c])
}

/// A lookup at blur β from the layers, each read by [`cube_bilinear`]: the two layers around β
/// (SPEC §4's pair), blended in variance so that the blend's variance is β², (1 − t)·β_k² +
/// t·β_(k+1)² = β², where SPEC's `paper` blends in log β, whose mixture is wider than the β between
/// (by 4 % in variance at the `brdf` layers' ratio 1.32, by 1/t between layer 0 and layer 1).
/// Layer 0, the sharp map, counts as blurred by its texels' read ([`texel_read_variance`]): a
/// lookup narrower than that reads layer 0 alone. Measured in BENCHMARKS.md ("Lookups at the blur
/// they ask for"): with the lattice's reach at 3 σ the courtyard's 112 points at m = 0.02 went
/// from 1.60 to 1.05 % mean.
pub fn layered_radiance(env: &PrefilteredEnvironment, d: DVec3, beta: f64) -> [f64; 3] {
    let (k, t) = layer_blend(&env.betas, beta);
    let t = match t > 0.0 {
        true => {
            let lo = match k {
                0 => texel_read_variance(env.layers[0].face_size),
                _ => env.betas[k] * env.betas[k],
            };
            let hi = env.betas[k + 1] * env.betas[k + 1];
            // A layer 1 no wider than layer 0's texels (a tiny source): the nearer of the two.
            ((beta * beta - lo) / (hi - lo).max(1e-30)).clamp(0.0, 1.0)
        }
        false => 0.0,
    };
    let lo = cube_bilinear(&env.layers[k], d);
    if t == 0.0 {
        return lo;
    }
    let hi = cube_bilinear(&env.layers[(k + 1).min(env.layers.len() - 1)], d);
    std::array::from_fn(|c| lo[c] + (hi[c] - lo[c]) * t)
}

/// The texel of `cube` holding direction `d`, as the shaders' layer texels store it
/// ([`layer_pair::stored`]).
fn cube_texel(cube: &CubeImage, d: DVec3) -> [f64; 3] {
    cube_texel_rgb(cube, d).map(|x| f64::from(layer_pair::stored(x)))
}

/// The texel of `cube` holding direction `d`, as the cube holds it.
fn cube_texel_rgb(cube: &CubeImage, d: DVec3) -> [f32; 3] {
    let size = cube.face_size;
    let (face, sc, tc) = direction_to_face(d);
    let index = |c: f64| {
        (((c + 1.0) * 0.5 * f64::from(size)).floor() as i64).clamp(0, i64::from(size) - 1) as u32
    };
    let texel = cube.get(face, index(sc), index(tc));
    [texel[0], texel[1], texel[2]]
}

/// The texels of `cube` with a one-texel apron around each face, as the shaders read a layer
/// (layer_apron.comp, its GPU twin): face after face, row after row, (M + 2)² texels a face, texel
/// (i, j) for i, j ∈ [−1, M] holding the texel of the direction through (i, j)'s centre on the
/// face that direction selects, which is the tap [`cube_bilinear`] reads there, and the next one
/// in its row, (i + 1, j) (0 beyond the apron), packed by [`layer_pair::pack`].
pub fn apron_texels(cube: &CubeImage) -> Vec<[u32; 4]> {
    let size = cube.face_size;
    let coord = |k: i64| 2.0 * (k as f64 + 0.5) / f64::from(size) - 1.0;
    let last = i64::from(size);
    let mut texels = Vec::with_capacity(6 * (size as usize + 2).pow(2));
    for face in 0..6 {
        let texel = |i: i64, j: i64| match i <= last {
            true => cube_texel_rgb(cube, face_direction(face, coord(i), coord(j))),
            false => [0.0; 3],
        };
        for j in -1..=last {
            for i in -1..=last {
                texels.push(layer_pair::pack(texel(i, j), texel(i + 1, j)));
            }
        }
    }
    texels
}

/// Bilinear filtering of a cube at `d` over the four texel centres around it; each tap is looked
/// up by its direction (inside the face that is the texel itself; beyond an edge, the texel of the
/// neighbouring face holding the tap's direction).
pub fn cube_bilinear(cube: &CubeImage, d: DVec3) -> [f64; 3] {
    let size = f64::from(cube.face_size);
    let (face, sc, tc) = direction_to_face(d);
    let x = (sc + 1.0) * 0.5 * size - 0.5;
    let y = (tc + 1.0) * 0.5 * size - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let coord = |k: f64| 2.0 * (k + 0.5) / size - 1.0;
    let tap = |i: f64, j: f64| cube_texel(cube, face_direction(face, coord(i), coord(j)));
    let (a, b) = (tap(x0, y0), tap(x0 + 1.0, y0));
    let (c, e) = (tap(x0, y0 + 1.0), tap(x0 + 1.0, y0 + 1.0));
    std::array::from_fn(|k| {
        let top = a[k] + (b[k] - a[k]) * fx;
        let bottom = c[k] + (e[k] - c[k]) * fx;
        top + (bottom - top) * fy
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fibonacci_points_step_by_the_golden_fraction() {
        // The fixed-point azimuth is within 2^-24 of i·(√5 − 1)/2 mod 1.
        let close = |a: (f64, f64), b: (f64, f64)| {
            (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1.0 / f64::from(1u32 << 24)
        };
        assert!(close(fibonacci_point(0, 4), (0.125, 0.0)));
        assert!(close(
            fibonacci_point(1, 4),
            (0.375, 0.618_033_988_749_894_8)
        ));
        assert!(close(
            fibonacci_point(2, 4),
            (0.625, 0.236_067_977_499_789_7)
        ));
        assert!(close(
            fibonacci_point(3, 4),
            (0.875, 0.854_101_966_249_684_5)
        ));
    }

    #[test]
    fn bilinear_lookups_reproduce_a_linear_field_across_faces() {
        // Texels hold 3 + d.x + 2·d.y − d.z at their centres (positive, like radiance: a layer
        // texel stores a negative value as 0). Inside a face, bilinear interpolation of that
        // field is close to it; across an edge the tap from the neighbour face must be
        // the one holding the same direction, or the result jumps.
        let size = 32;
        let mut cube = CubeImage::new(size);
        for face in 0..6 {
            for j in 0..size {
                for i in 0..size {
                    let d = super::super::cube::texel_direction(face, i, j, size);
                    let value = (3.0 + d.x + 2.0 * d.y - d.z) as f32;
                    let index = cube.index(face, i, j);
                    cube.texels[index] = [value, value, value, 1.0];
                }
            }
        }
        let mut worst: f64 = 0.0;
        for k in 0..2000 {
            let t = k as f64 * 0.618_033_988_75;
            let d = DVec3::new((t * 7.1).sin(), (t * 3.3).cos(), (t * 5.7).sin()).normalize();
            let want = 3.0 + d.x + 2.0 * d.y - d.z;
            let got = cube_bilinear(&cube, d)[0];
            worst = worst.max((got - want).abs());
        }
        // Measured 0.0154: bilinear interpolation's curvature error on 32² faces (texels ~0.05
        // rad); the stored texels' rounding adds at most 5.5·2⁻¹⁴ ≈ 3e-4. A tap from the wrong
        // texel at an edge costs up to a texel's step of the field, ≈ √6·0.05 ≈ 0.12, so 0.03
        // would catch it.
        assert!(worst < 0.03, "{worst}");
    }

    /// The shaders' bilinear read of a layer with aprons (brdf_environment.glsl
    /// `layer_bilinear`): four texels of the face's padded rows in two pairs, in f64 as
    /// `cube_bilinear`.
    fn apron_bilinear(texels: &[[u32; 4]], size: u32, d: DVec3) -> [f64; 3] {
        let (face, sc, tc) = direction_to_face(d);
        let m = f64::from(size);
        let (x, y) = ((sc + 1.0) * 0.5 * m - 0.5, (tc + 1.0) * 0.5 * m - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let stride = size as usize + 2;
        let row = (face * stride + (y0 as i64 + 1) as usize) * stride + (x0 as i64 + 1) as usize;
        let pair = |k: usize| {
            let (first, second) = layer_pair::unpack(texels[k]);
            (first.map(f64::from), second.map(f64::from))
        };
        let ((a, b), (c, e)) = (pair(row), pair(row + stride));
        std::array::from_fn(|k| {
            let top = a[k] + (b[k] - a[k]) * fx;
            let bottom = c[k] + (e[k] - c[k]) * fx;
            top + (bottom - top) * fy
        })
    }

    #[test]
    fn the_aprons_give_every_tap_the_seam_rule_gives() {
        // Every texel a different value, so a tap from any other texel shows.
        for size in [1, 2, 5, 8] {
            let mut cube = CubeImage::new(size);
            for (k, texel) in cube.texels.iter_mut().enumerate() {
                *texel = [k as f32, 0.5 * k as f32 + 1.0, (k * k) as f32, 1.0];
            }
            let texels = apron_texels(&cube);
            let stride = size as usize + 2;
            assert_eq!(texels.len(), 6 * stride * stride);
            // Inside each face, the face itself.
            for face in 0..6 {
                for j in 0..size {
                    for i in 0..size {
                        let padded = (face * stride + j as usize + 1) * stride + i as usize + 1;
                        let texel = cube.get(face, i, j);
                        let stored = [texel[0], texel[1], texel[2]].map(layer_pair::stored);
                        assert_eq!(layer_pair::unpack(texels[padded]).0, stored);
                    }
                }
            }
            // Directions near every edge and corner of every face, and a spread of others.
            let mut directions = Vec::new();
            let m = f64::from(size);
            for face in 0..6 {
                for &sc in &[-1.0, -1.0 + 0.3 / m, -0.2, 0.0, 0.45, 1.0 - 0.3 / m, 1.0] {
                    for &tc in &[-1.0, -1.0 + 0.2 / m, 0.1, 1.0 - 0.4 / m, 1.0] {
                        directions.push(face_direction(face, sc, tc).normalize());
                    }
                }
            }
            for k in 0..3000 {
                let t = k as f64 * 0.618_033_988_75;
                directions.push(
                    DVec3::new((t * 7.1).sin(), (t * 3.3).cos(), (t * 5.7).sin()).normalize(),
                );
            }
            for d in directions {
                // The same taps and the same arithmetic: exactly equal.
                assert_eq!(
                    apron_bilinear(&texels, size, d),
                    cube_bilinear(&cube, d),
                    "{d}"
                );
            }
        }
    }

    fn smooth() -> (BrdfParams, FresnelTable) {
        let p = BrdfParams {
            beckmann_m: 0.05,
            diffuse_a: 0.01,
            diffuse_b: 0.96,
            lacquer_g: 1.0159,
            albedo: [0.5, 0.06, 0.03],
        };
        (p, FresnelTable::dielectric(1.5, 0.0045).unwrap())
    }

    /// With no spread a bright light is SPEC §2's f_spec·E·(N·l) (`lacquer_specular`): D' is
    /// Beckmann's D written in slopes. 1e-12: two f64 roundings of the same formula.
    #[test]
    fn a_light_without_spread_is_the_brdf() {
        let (p, fresnel) = smooth();
        let n = DVec3::new(0.1, 1.0, -0.2).normalize();
        let v = DVec3::new(0.6, 0.7, 0.2).normalize();
        let nv = n.dot(v);
        for k in 0..50 {
            let t = f64::from(k) * 0.37;
            let l = (2.0 * nv * n - v
                + 0.08 * DVec3::new(t.sin(), (1.3 * t).cos(), (0.7 * t).sin()))
            .normalize();
            let light = BrightLight {
                direction: l,
                irradiance: [1.0, 2.0, 3.0],
                spread: 0.0,
            };
            let got = bright_light(&p, &fresnel, (n, v, nv), &light);
            let f = crate::model::lacquer_specular(&p, &fresnel, n, v, l);
            for c in 0..3 {
                let want = f[c] * n.dot(l) * light.irradiance[c];
                assert!(
                    (got[c] - want).abs() <= 1e-12 * want.abs().max(1e-30),
                    "{k}: {got:?}"
                );
            }
        }
    }

    /// What the spread is for: a square block of light as wide as the lobe (a rough split's
    /// block on a 1k map, 2.8°, under m = 0.05) through the lobe, summed pixel by pixel (64²
    /// points), against one light at its centroid with and without its spread. Measured (relative
    /// to the block; view elevation, block's offset from the mirror direction): the point light
    /// 4.7 % (60°, 0°), 4.2 % (60°, 2°), 10 % (30°, 1.5°), 2.1 % (80°, 4°) off, the spread light
    /// 0.03, 0.01, 0.37, 0.01 %; at (10°, 3°), where the lobe across the plane is 6× narrower
    /// than the block, 91 and 13 %. Bounds: within 1 % from 30° up, and at most a fifth of the
    /// point light's error everywhere.
    #[test]
    fn a_spread_light_is_the_block_it_stands_for() {
        let (p, fresnel) = smooth();
        let n = DVec3::Y;
        let width = 2.8f64.to_radians();
        let count = 64;
        for (elevation, offset) in [
            (60.0f64, 0.0f64),
            (60.0, 2.0),
            (30.0, 1.5),
            (10.0, 3.0),
            (80.0, 4.0),
        ] {
            let (s, c) = elevation.to_radians().sin_cos();
            let v = DVec3::new(-c, s, 0.0);
            let nv = s;
            // The block: centred `offset`° from the mirror direction along the plane.
            let r = 2.0 * nv * n - v;
            let tilt = offset.to_radians();
            let centre = (r * tilt.cos() + DVec3::new(r.y, -r.x, 0.0) * tilt.sin()).normalize();
            let (a, b) = (DVec3::Z, centre.cross(DVec3::Z).normalize());
            let mut sum = [0.0; 3];
            let (mut centroid, mut second) = (DVec3::ZERO, 0.0);
            let share = 1.0 / f64::from(count * count);
            for i in 0..count {
                for j in 0..count {
                    let x = (f64::from(i) + 0.5) / f64::from(count) - 0.5;
                    let y = (f64::from(j) + 0.5) / f64::from(count) - 0.5;
                    let d = (centre + width * (x * a + y * b)).normalize();
                    let point = BrightLight {
                        direction: d,
                        irradiance: [share; 3],
                        spread: 0.0,
                    };
                    let term = bright_light(&p, &fresnel, (n, v, nv), &point);
                    for ch in 0..3 {
                        sum[ch] += term[ch];
                    }
                    centroid += share * d;
                    second += share;
                }
            }
            // Σw·|d − ĉ|² = 2·(W − |Σw·d|): per axis, the half (as bright.rs has it).
            let spread = 1.0 - centroid.length() / second;
            let light = |spread| BrightLight {
                direction: centroid.normalize(),
                irradiance: [1.0; 3],
                spread,
            };
            let point = bright_light(&p, &fresnel, (n, v, nv), &light(0.0))[1];
            let spread = bright_light(&p, &fresnel, (n, v, nv), &light(spread))[1];
            let point_error = (point - sum[1]).abs() / sum[1];
            let spread_error = (spread - sum[1]).abs() / sum[1];
            println!(
                "{elevation}°, {offset}° off: point {point_error:.4}, spread {spread_error:.4}"
            );
            assert!(
                spread_error <= 0.2 * point_error,
                "{elevation}: {spread_error} {point_error}"
            );
            assert!(
                elevation < 30.0 || spread_error <= 0.01,
                "{elevation}: {spread_error}"
            );
        }
    }

    /// The cull angle is twice the half vector's limit at the widened m: against the same angle
    /// with trigonometry.
    #[test]
    fn the_cull_is_twice_the_half_vector_limit() {
        for m in [0.02, 0.06, 0.3, 2.0] {
            for spread in [0.0, 1e-4, 0.01, 1.0] {
                let t = (f64::from(BRIGHT_LOBE_CULL) * (m * m + 0.5 * spread)).sqrt();
                let want = (2.0 * t.atan()).cos();
                let got = light_cull_cos(m, spread);
                assert!(
                    (got - want).abs() < 1e-12,
                    "m {m}, spread {spread}: {got} {want}"
                );
            }
        }
    }
}
