//! SPEC §4's `brdf` environment model by brute force, for tests: the specular integral
//! ∫ f_spec(N, V, s)·L(s)·(N·s) dω_s summed over the pixels of the full-resolution equirectangular
//! map, and the directional albedo ∫ f_spec·(N·s) dω_s of a white furnace. The ground truth any
//! faster quadrature of the `brdf` model (its CPU twin and the shader) must converge to. The
//! diffuse half of the model is exact already (`definition::irradiance_definition`).
//! Owns nothing else; reads no files.

use glam::DVec3;
use std::f64::consts::{PI, TAU};

use super::cube::{equirect_row_solid_angle, world_to_environment};
use super::image::Equirect;
use super::params::EnvironmentLight;
use crate::model::brdf::{cook_torrance_g, lacquer_specular};
use crate::model::{BrdfParams, FresnelTable};

/// Pixels whose centre is more than this many Beckmann widths from the mirror direction are left
/// out: there D is below e^−64·(1 + 64m²)² of its peak, under 1e-24 for every m ≤ 1, far below
/// what f64 sums of the rest can hold. Why it is safe: with R and s the half-turns of V about N
/// and about H, s is R rotated by 2·∠(N, H), so ∠(N, H) ≥ ∠(s, R)/2.
const LOBE_WIDTHS_SQUARED: f64 = 64.0;

/// The specular part of the `brdf` model at a surface point (world frame, unit `n` and `v`):
/// Σ over pixels p (each split into `subsamples`² equal (u, v) cells) of
/// f_spec(N, V, s_c)·L_p·max(N·s_c, 0)·dω_c, s_c the cell centre and dω_c its exact solid angle;
/// L is the map × `light.intensity`, turned by `light.rotation_deg` about +Y (SPEC §4).
pub fn specular_integral_definition(
    src: &Equirect,
    light: EnvironmentLight,
    brdf: &BrdfParams,
    fresnel: &FresnelTable,
    n: DVec3,
    v: DVec3,
    subsamples: u32,
) -> [f64; 3] {
    // f_spec depends only on angles: rotate N and V into the map's frame instead of every pixel.
    let n = world_to_environment(n.normalize(), light.rotation_deg);
    let v = world_to_environment(v.normalize(), light.rotation_deg);
    let nv = n.dot(v);
    if nv.is_nan() || nv <= 0.0 {
        return [0.0; 3];
    }
    let mirror = 2.0 * nv * n - v;
    let reach = lobe_reach(brdf.beckmann_m);
    let (w, h, s) = (src.width, src.height, subsamples.max(1));
    let (cells_x, cells_y) = (w * s, h * s);
    let columns: Vec<(f64, f64)> = (0..cells_x)
        .map(|x| (TAU * ((f64::from(x) + 0.5) / f64::from(cells_x) - 0.5)).sin_cos())
        .collect();
    let theta_mirror = mirror.x.hypot(mirror.z).atan2(mirror.y);
    let phi_mirror = mirror.x.atan2(-mirror.z);
    let mut sum = [0.0; 3];
    for y in 0..cells_y {
        let theta = PI * (f64::from(y) + 0.5) / f64::from(cells_y);
        // Every cell centre of this row is at least |θ − θ_R| from R.
        if (theta - theta_mirror).abs() > reach {
            continue;
        }
        let (sin_theta, cos_theta) = theta.sin_cos();
        let solid_angle = equirect_row_solid_angle(y, cells_x, cells_y);
        for x in row_columns(cells_x, theta, theta_mirror, phi_mirror, reach) {
            let (sin_phi, cos_phi) = columns[x as usize];
            let dir = DVec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi);
            let nl = n.dot(dir);
            if nl <= 0.0 {
                continue;
            }
            let f = lacquer_specular(brdf, fresnel, n, v, dir);
            let radiance = src.get(x / s, y / s);
            for c in 0..3 {
                sum[c] += f[c] * f64::from(radiance[c]) * nl * solid_angle;
            }
        }
    }
    sum.map(|x| x * light.intensity)
}

/// The cells per pixel side ([`specular_integral_definition`]'s `subsamples`) that resolve the
/// lobe where it is narrowest: across the plane of incidence the reflected directions of
/// Beckmann slopes (σ = m/√2 per axis) spread by 2·nv·σ = √2·nv·m, which at grazing is a small
/// share of a pixel (2π/`source_width` wide at the equator, the widest a pixel is). Cells at most
/// a twelfth of that wide, 1 to [`MAX_SUBSAMPLES`] a side: a pixel's radiance is a step, so where
/// an edge crosses the lobe the cells' midpoint sum converges only as their width, not as a smooth
/// integrand's would. Measured on the shipped 1024-pixel maps (tests/environment/brdf_model.rs):
/// doubling these cells moves none of the 112 points by more than 0.08 % at m = 0.02,
/// 0.05 or 0.2; cells a quarter of the width left a dark point 0.7 % off (studio, m = 0.05, nv =
/// 0.45), and 3 cells a side, the tests' rule before, the point at nv = 0.035 4.2–4.6 % below the
/// integral at m = 0.02 (this rule asks for 64 there).
pub fn converged_subsamples(source_width: u32, m: f64, nv: f64) -> u32 {
    let pixel = TAU / f64::from(source_width.max(1));
    let lobe = std::f64::consts::SQRT_2 * nv.max(0.0) * m;
    let cells = (12.0 * pixel / lobe).ceil();
    match cells.is_finite() {
        true => cells.clamp(1.0, f64::from(MAX_SUBSAMPLES)) as u32,
        false => MAX_SUBSAMPLES,
    }
}

/// The most cells a side [`converged_subsamples`] asks for: 64² cells a pixel, reached only
/// within a few degrees of the horizon at small m.
pub const MAX_SUBSAMPLES: u32 = 64;

/// The largest ∠(s, R) at which a pixel can still matter (see [`LOBE_WIDTHS_SQUARED`]).
fn lobe_reach(m: f64) -> f64 {
    let reach = 2.0 * (m * LOBE_WIDTHS_SQUARED.sqrt()).atan();
    reach.min(PI)
}

/// The columns of a row of cells whose centres can lie within `reach` of R (θ_R, φ_R): by the
/// spherical law of cosines, cos ∠ = cos θ cos θ_R + sin θ sin θ_R cos(φ − φ_R). One column of
/// margin on each side absorbs the rounding of the bound; including a cell never changes what it
/// adds.
fn row_columns(
    cells_x: u32,
    theta: f64,
    theta_mirror: f64,
    phi_mirror: f64,
    reach: f64,
) -> Box<dyn Iterator<Item = u32>> {
    let denominator = theta.sin() * theta_mirror.sin();
    let needed = (reach.cos() - theta.cos() * theta_mirror.cos()) / denominator;
    if reach >= PI || denominator <= 0.0 || needed <= -1.0 {
        return Box::new(0..cells_x);
    }
    let half_width = needed.min(1.0).acos();
    let cell = TAU / f64::from(cells_x);
    // Column x has its centre at φ = −π + (x + ½)·cell.
    let centre = (phi_mirror + PI) / cell - 0.5;
    let span = half_width / cell + 1.0;
    let (first, last) = (
        (centre - span).floor() as i64,
        (centre + span).ceil() as i64,
    );
    if last - first + 1 >= i64::from(cells_x) {
        return Box::new(0..cells_x);
    }
    let n = i64::from(cells_x);
    Box::new((first..=last).map(move |x| x.rem_euclid(n) as u32))
}

/// ∫ f_spec(N, V, s)·(N·s) dω_s at `nv`: what a white furnace of radiance 1 reflects specularly.
/// An independent quadrature in the half vector: with s the half-turn of V about H,
/// dω_s = 4·(V·H)·dω_H, and u = 1 − exp(−tan²θ_H/m²) (the Beckmann lobe's own distribution of
/// D·cos θ_H) with φ_H uniform turns the integral into the mean of F·G·(V·H)/(nv·nh) over the
/// unit square, a bounded integrand (G ≤ 2·nh·nv/vh), summed at `u_steps` × `phi_steps` midpoints.
pub fn specular_albedo(
    brdf: &BrdfParams,
    fresnel: &FresnelTable,
    nv: f64,
    u_steps: u32,
    phi_steps: u32,
) -> [f64; 3] {
    let nv = nv.clamp(1e-9, 1.0);
    let v = DVec3::new((1.0 - nv * nv).max(0.0).sqrt(), 0.0, nv);
    let m2 = brdf.beckmann_m * brdf.beckmann_m;
    let mut sum = [0.0; 3];
    for i in 0..u_steps {
        let u = (f64::from(i) + 0.5) / f64::from(u_steps);
        let tan2 = -m2 * (-u).ln_1p();
        let cos_h = 1.0 / (1.0 + tan2).sqrt();
        let sin_h = (tan2 / (1.0 + tan2)).sqrt();
        for j in 0..phi_steps {
            let phi = TAU * (f64::from(j) + 0.5) / f64::from(phi_steps);
            let half = DVec3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h);
            let vh = v.dot(half);
            if vh <= 0.0 {
                continue;
            }
            let nl = 2.0 * vh * cos_h - nv;
            if nl <= 0.0 {
                continue;
            }
            let g = cook_torrance_g(cos_h, nv, nl, vh);
            let f = fresnel.eval(vh.min(1.0).acos().to_degrees());
            let weight = g * vh / (nv * cos_h);
            for c in 0..3 {
                sum[c] += f[c] * weight;
            }
        }
    }
    let cells = f64::from(u_steps) * f64::from(phi_steps);
    sum.map(|x| x / cells)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(m: f64) -> BrdfParams {
        BrdfParams {
            beckmann_m: m,
            diffuse_a: 0.01,
            diffuse_b: 0.96,
            lacquer_g: 1.0159,
            albedo: [0.5, 0.06, 0.03],
        }
    }

    fn fresnel() -> FresnelTable {
        FresnelTable::dielectric(1.5, 0.0045).unwrap()
    }

    #[test]
    fn converged_subsamples_grow_towards_grazing_within_their_bounds() {
        // 1024-pixel map: a pixel 6.1 mrad; m = 0.2 face-on, the lobe 283 mrad: one cell.
        assert_eq!(converged_subsamples(1024, 0.2, 1.0), 1);
        // m = 0.02 at nv = 0.42: lobe 11.9 mrad, 12 × 6.14 / 11.9 = 6.2 → 7.
        assert_eq!(converged_subsamples(1024, 0.02, 0.42), 7);
        // No lobe (nv = 0, NaN) or one far below a pixel: the most.
        for nv in [0.0, f64::NAN, 1e-6] {
            assert_eq!(converged_subsamples(1024, 0.02, nv), MAX_SUBSAMPLES);
        }
        let mut last = MAX_SUBSAMPLES;
        for k in 1..=100 {
            let cells = converged_subsamples(1024, 0.05, f64::from(k) / 100.0);
            assert!(
                cells <= last && cells >= 1,
                "nv {k}/100: {cells} after {last}"
            );
            last = cells;
        }
    }

    #[test]
    fn lobe_reach_covers_the_lobe_and_stops_at_pi() {
        // m = 0.05: 2·atan(0.4) ≈ 0.761 rad; m = 1 reaches everything.
        assert!((lobe_reach(0.05) - 2.0 * 0.4_f64.atan()).abs() < 1e-15);
        assert_eq!(lobe_reach(1.0), 2.0 * 8.0_f64.atan());
        assert!(lobe_reach(1e9) <= PI && lobe_reach(1e9) > PI - 1e-6);
    }

    #[test]
    fn row_columns_hold_every_centre_within_reach() {
        // Against the plain test of every centre, for a few rows and mirror directions.
        let cells_x = 360;
        for (theta_r, phi_r, reach) in [(1.0, 0.3, 0.4), (0.2, -3.0, 0.7), (2.9, 3.1, 0.25)] {
            let r = DVec3::new(
                f64::sin(theta_r) * f64::sin(phi_r),
                f64::cos(theta_r),
                -f64::sin(theta_r) * f64::cos(phi_r),
            );
            for y in 0..180 {
                let theta = PI * (f64::from(y) + 0.5) / 180.0;
                let listed: Vec<u32> = row_columns(cells_x, theta, theta_r, phi_r, reach).collect();
                for x in 0..cells_x {
                    let phi = TAU * ((f64::from(x) + 0.5) / f64::from(cells_x) - 0.5);
                    let d = DVec3::new(
                        theta.sin() * phi.sin(),
                        theta.cos(),
                        -theta.sin() * phi.cos(),
                    );
                    if d.dot(r).clamp(-1.0, 1.0).acos() <= reach {
                        assert!(listed.contains(&x), "θ {theta}, column {x}");
                    }
                }
            }
        }
    }

    /// Two independent quadratures of one integral: pixel sums in s over a constant map and the
    /// half-vector grid of `specular_albedo`. 5e-5: both are midpoint rules of smooth integrands
    /// on fine grids (the sharpest lobe, m = 0.05, spans ~20 cells of 1024 × 512 × 3²); they
    /// agree to 5.3e-6 here; the tolerance leaves a factor of ten.
    #[test]
    fn white_furnace_pixel_sum_equals_the_directional_albedo() {
        let white = Equirect::constant(1024, 512, [1.0; 3]);
        let table = fresnel();
        let n = DVec3::new(0.3, 0.8, -0.2).normalize();
        for m in [0.05, 0.2, 0.5] {
            let p = params(m);
            for nv in [0.95, 0.6, 0.25] {
                let tangent = n.any_orthonormal_vector();
                let v = nv * n + (1.0 - nv * nv).sqrt() * tangent;
                let sum = specular_integral_definition(
                    &white,
                    EnvironmentLight::default(),
                    &p,
                    &table,
                    n,
                    v,
                    if m < 0.1 { 3 } else { 1 },
                );
                let albedo = specular_albedo(&p, &table, nv, 2048, 512);
                for c in 0..3 {
                    let rel = (sum[c] - albedo[c]).abs() / albedo[c];
                    assert!(rel < 5e-5, "m {m}, nv {nv}: {sum:?} vs {albedo:?}");
                }
            }
        }
    }

    /// A small bright disc seen through a wide lobe: the integral is f_spec·(N·s)·L·Ω at the
    /// disc's direction, Ω the solid angle of the pixels inside it (counted here, independently of
    /// the sum). 2 %: f_spec of m = 0.5 changes by less than that across a 2° disc.
    #[test]
    fn a_small_disc_reflects_as_the_brdf_at_its_direction() {
        let disc = DVec3::new(0.4, 0.7, 0.6).normalize();
        let inside = |d: DVec3| d.dot(disc) > 2.0_f64.to_radians().cos();
        let map = Equirect::from_fn(
            1024,
            512,
            |d| if inside(d) { [1000.0; 3] } else { [0.0; 3] },
        );
        let mut omega = 0.0;
        for y in 0..map.height {
            let top = PI * f64::from(y) / 512.0;
            let bottom = PI * f64::from(y + 1) / 512.0;
            for x in 0..map.width {
                if map.get(x, y)[0] > 0.0 {
                    omega += TAU / 1024.0 * (top.cos() - bottom.cos());
                }
            }
        }
        let table = fresnel();
        let p = params(0.5);
        let n = DVec3::Y;
        let v = DVec3::new(-0.5, 0.6, -0.3).normalize();
        let sum =
            specular_integral_definition(&map, EnvironmentLight::default(), &p, &table, n, v, 1);
        let f = lacquer_specular(&p, &table, n, v, disc);
        let want = f[1] * n.dot(disc) * 1000.0 * omega;
        assert!((sum[1] - want).abs() <= 0.02 * want, "{sum:?} vs {want}");
    }

    #[test]
    fn albedo_is_below_one_and_falls_with_the_fresnel_table() {
        // A lossless mirror table (F = 1) bounds the lacquer's: F_lacquer ≤ 1 everywhere.
        let one = FresnelTable::new(vec![0.0, 90.0], vec![[1.0; 3]; 2]).unwrap();
        for m in [0.05, 0.5] {
            for nv in [1.0, 0.5, 0.1] {
                let mirror = specular_albedo(&params(m), &one, nv, 512, 256);
                let lacquer = specular_albedo(&params(m), &fresnel(), nv, 512, 256);
                assert!(mirror[0] <= 1.0 + 1e-9, "{mirror:?}");
                assert!(lacquer[0] < mirror[0], "{lacquer:?} vs {mirror:?}");
            }
        }
    }

    #[test]
    fn rotation_turns_the_map_with_the_frame_and_intensity_scales() {
        // A map bright only around +X; N = (1, 1, 0)/√2 and V = +Y mirror to R = +X, which sees
        // it. Turned by 90° about +Y, the map shows world +X its own +Z (world_to_environment),
        // which is dark.
        let map = Equirect::from_fn(256, 128, |d| if d.x > 0.95 { [1.0; 3] } else { [0.0; 3] });
        let table = fresnel();
        let p = params(0.05);
        let n = DVec3::new(1.0, 1.0, 0.0).normalize();
        let v = DVec3::Y;
        let plain =
            specular_integral_definition(&map, EnvironmentLight::default(), &p, &table, n, v, 1);
        assert!(plain[0] > 0.0);
        let doubled = specular_integral_definition(
            &map,
            EnvironmentLight::new(2.0, 0.0),
            &p,
            &table,
            n,
            v,
            1,
        );
        assert!((doubled[0] - 2.0 * plain[0]).abs() <= 1e-12 * plain[0]);
        let turned = specular_integral_definition(
            &map,
            EnvironmentLight::new(1.0, 90.0),
            &p,
            &table,
            n,
            v,
            1,
        );
        assert!(turned[0] < 1e-3 * plain[0], "{turned:?} vs {plain:?}");
    }
}
