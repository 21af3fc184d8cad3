//! The lacquer BRDF of SPEC §2: a view-dependent diffuse term scaled by the lacquer-content law,
//! plus a Cook-Torrance specular lobe with the normalised Beckmann D and the tabulated Fresnel F.
//!
//! Owns only the evaluation, in f64, as the reference the CPU oracle and the shaders
//! (`shaders/common/lacquer_brdf.glsl`) are checked against — it does not validate parameters
//! (see [`super::material::LacquerMaterial::brdf_params`]).
//!
//! The GPU runs this in fp32 and must agree to 1e-4 relative, so the formulas are written in forms
//! that stay accurate in fp32; the shader must use the same forms:
//! - Beckmann's exponent (nh² - 1)/(m²·nh²) = -tan²α/m² is computed as -|N×H|²/(m²·nh²): near the
//!   peak (nh → 1) `1 - nh²` cancels and keeps only an absolute precision of ~6e-8 in fp32, while
//!   |N×H|² = sin²α keeps full relative precision. For smooth lacquer (m = 0.05) the exponent is
//!   400·tan²α, so the cancelling form alone would spend 2.4e-5 of the 1e-4 budget on D.
//! - H = (V + L)/|V + L|; |V + L| = 0 only when V = -L, which nv > 0, nl > 0 excludes (N·(V+L) =
//!   nv + nl > 0), but the guard stays so that degenerate input gives 0, never NaN.
//! - The Fresnel angle is θ = acos(clamp(vh, 0, 1)) in degrees. acos is ill-conditioned at vh → 1
//!   (fp32 error ≈ 0.02° there), but F is flat near normal incidence, so F(θ) is not. Where F is
//!   steep (towards grazing) the accuracy of the shader's acos itself matters: an acos off by
//!   1e-4 rad costs 3e-4 relative in the dielectric F at 60° and 5e-4 at 80° (quirk
//!   `imprecise_inverse_trig`: the shaders use `common/math.glsl`'s).
//! - Where exp(-tan²α/m²) underflows (far from the lobe, below 1e-38 in fp32) D is 0; compare
//!   GPU and CPU with an absolute floor there, not a relative tolerance.

use std::f64::consts::PI;

use glam::DVec3;

use super::fresnel::FresnelTable;

/// The evaluated parameters of one lacquer material (SPEC §2), ready for the BRDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrdfParams {
    /// Beckmann RMS slope m, in (0, 1].
    pub beckmann_m: f64,
    /// a of the view-dependent diffuse law f(N·V) = a + b·N·V.
    pub diffuse_a: f64,
    /// b of the view-dependent diffuse law f(N·V) = a + b·N·V.
    pub diffuse_b: f64,
    /// g(r), already evaluated.
    pub lacquer_g: f64,
    /// k_d, the colorant albedo (linear RGB).
    pub albedo: [f64; 3],
}

/// f_r of SPEC §2 [1/sr], RGB. n, v, l: unit vectors. 0 if nv <= 0 or nl <= 0.
///
/// f_r = k_d·max(a + b·nv, 0)·g/π + F(acos vh)·D(nh)·G / (4·nv·nl).
pub fn lacquer_brdf(
    p: &BrdfParams,
    fresnel: &FresnelTable,
    n: DVec3,
    v: DVec3,
    l: DVec3,
) -> [f64; 3] {
    let Some((f, spec)) = specular_factors(p, fresnel, n, v, l) else {
        return [0.0; 3];
    };
    let diffuse = view_dependent_diffuse(p, n.dot(v));
    [
        diffuse[0] + f[0] * spec,
        diffuse[1] + f[1] * spec,
        diffuse[2] + f[2] * spec,
    ]
}

/// f_spec of SPEC §2 alone [1/sr], RGB: F(acos vh)·D(nh)·G / (4·nv·nl); 0 where f_r is 0.
pub fn lacquer_specular(
    p: &BrdfParams,
    fresnel: &FresnelTable,
    n: DVec3,
    v: DVec3,
    l: DVec3,
) -> [f64; 3] {
    match specular_factors(p, fresnel, n, v, l) {
        Some((f, spec)) => f.map(|f| f * spec),
        None => [0.0; 3],
    }
}

/// F and D·G/(4·nv·nl), or `None` where the BRDF is 0 (nv or nl not positive, or no H).
fn specular_factors(
    p: &BrdfParams,
    fresnel: &FresnelTable,
    n: DVec3,
    v: DVec3,
    l: DVec3,
) -> Option<([f64; 3], f64)> {
    let (nv, nl) = (n.dot(v), n.dot(l));
    // Written positively so that NaN input also lands here.
    let visible = nv > 0.0 && nl > 0.0;
    if !visible {
        return None;
    }
    let half = v + l;
    let half_len2 = half.length_squared();
    if half_len2 <= 0.0 || !half_len2.is_finite() {
        return None;
    }
    let h = half / half_len2.sqrt();
    let nh = n.dot(h);
    let vh = v.dot(h);
    let sin2_alpha = n.cross(h).length_squared();
    let d = beckmann_d_sin2(nh, sin2_alpha, p.beckmann_m);
    let g = cook_torrance_g(nh, nv, nl, vh);
    let f = fresnel.eval(vh.clamp(0.0, 1.0).acos().to_degrees());
    Some((f, d * g / (4.0 * nv * nl)))
}

/// Normalised Beckmann distribution D(nh) = exp((nh² - 1)/(m²·nh²)) / (π·m²·nh⁴) [1/sr].
///
/// From nh alone, sin²α = 1 - nh² is formed as (1 - nh)(1 + nh), which is exact to rounding
/// (Sterbenz) for nh ≥ 0.5; [`lacquer_brdf`] has the vectors and uses |N×H|² instead. 0 for
/// nh <= 0 (H below the surface).
pub fn beckmann_d(nh: f64, m: f64) -> f64 {
    beckmann_d_sin2(nh, (1.0 - nh) * (1.0 + nh), m)
}

/// D with sin²α = |N×H|² supplied by the caller (the accurate form; see the module doc).
pub fn beckmann_d_sin2(nh: f64, sin2_alpha: f64, m: f64) -> f64 {
    if nh <= 0.0 {
        return 0.0;
    }
    let nh2 = nh * nh;
    let m2 = m * m;
    let lobe = (-sin2_alpha / (m2 * nh2)).exp();
    if lobe == 0.0 {
        // Also keeps 0/0 away when nh⁴ underflows at grazing H.
        return 0.0;
    }
    lobe / (PI * m2 * nh2 * nh2)
}

/// Cook-Torrance geometric attenuation G = min(1, 2·nh·nv/vh, 2·nh·nl/vh). 0 if vh <= 0 (H
/// undefined or facing away from V, where the BRDF is 0 anyway).
pub fn cook_torrance_g(nh: f64, nv: f64, nl: f64, vh: f64) -> f64 {
    if vh <= 0.0 {
        return 0.0;
    }
    let masking = 2.0 * nh * nv / vh;
    let shadowing = 2.0 * nh * nl / vh;
    1.0_f64.min(masking).min(shadowing)
}

/// k_d · max(a + b·nv, 0) · g / π  (per channel)
pub fn view_dependent_diffuse(p: &BrdfParams, nv: f64) -> [f64; 3] {
    let scale = (p.diffuse_a + p.diffuse_b * nv).max(0.0) * p.lacquer_g / PI;
    p.albedo.map(|k| k * scale)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn smooth_black() -> BrdfParams {
        BrdfParams {
            beckmann_m: 0.05,
            diffuse_a: -0.03,
            diffuse_b: 1.05,
            lacquer_g: 1.22 - 0.224 + 0.0199,
            albedo: [0.02; 3],
        }
    }

    /// A table F(θ) = 0.04 + 0.96·θ/90 (grey), so F at any angle is known by hand.
    fn linear_fresnel() -> FresnelTable {
        FresnelTable::new(vec![0.0, 90.0], vec![[0.04; 3], [1.0; 3]]).unwrap()
    }

    /// ∫ D(h)(n·h) dω_h = 2π ∫_0^{π/2} D(cos θ) cos θ sin θ dθ by composite Simpson.
    fn projected_d_integral(m: f64, intervals: usize) -> f64 {
        let h = 0.5 * PI / intervals as f64;
        let f = |theta: f64| beckmann_d(theta.cos(), m) * theta.cos() * theta.sin();
        let mut sum = f(0.0) + f(0.5 * PI);
        for i in 1..intervals {
            sum += if i % 2 == 1 { 4.0 } else { 2.0 } * f(i as f64 * h);
        }
        2.0 * PI * sum * h / 3.0
    }

    #[test]
    fn beckmann_d_is_normalised() {
        // Simpson's error is ~ (h/m)⁴ of the integrand's scale; with 20 000 intervals and m ≥ 0.05,
        // h/m ≤ 1.6e-3, so the error is < 1e-10; 1e-8 leaves room for rounding in the sum.
        for m in [0.05, 0.2, 0.5] {
            let integral = projected_d_integral(m, 20_000);
            assert!((integral - 1.0).abs() < 1e-8, "m = {m}: {integral}");
        }
    }

    #[test]
    fn beckmann_d_spot_values() {
        // Peak D(1) = 1/(π m²); at α = 45°, tan²α = 1, nh⁴ = 1/4: D = 4·exp(-1/m²)/(π m²).
        let m: f64 = 0.2;
        assert!((beckmann_d(1.0, m) - 1.0 / (PI * m * m)).abs() < 1e-12);
        let nh = 0.5_f64.sqrt();
        let expected = 4.0 * (-1.0 / (m * m)).exp() / (PI * m * m);
        assert!((beckmann_d(nh, m) / expected - 1.0).abs() < 1e-12);
        assert_eq!(beckmann_d(0.0, m), 0.0);
        assert_eq!(beckmann_d(-0.5, m), 0.0);
        assert_eq!(beckmann_d(1e-200, m), 0.0);
    }

    #[test]
    fn beckmann_d_cross_product_form_agrees_near_the_peak() {
        // α = 1e-4 rad: sin²α from the cross product vs (1-nh)(1+nh); both accurate in f64 (1e-9).
        let alpha: f64 = 1e-4;
        let via_sin2 = beckmann_d_sin2(alpha.cos(), alpha.sin().powi(2), 0.05);
        assert!((via_sin2 / beckmann_d(alpha.cos(), 0.05) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn cook_torrance_g_spot_values() {
        // Hand-computed: 2·0.9·0.2/0.6 = 0.6 (masking); 2·0.8·0.1/0.5 = 0.32 (shadowing).
        assert_eq!(cook_torrance_g(1.0, 1.0, 1.0, 1.0), 1.0);
        assert!((cook_torrance_g(0.9, 0.2, 0.8, 0.6) - 0.6).abs() < 1e-15);
        assert!((cook_torrance_g(0.8, 0.9, 0.1, 0.5) - 0.32).abs() < 1e-15);
        assert_eq!(cook_torrance_g(0.9, 0.9, 0.9, 0.0), 0.0);
    }

    #[test]
    fn brdf_is_zero_below_the_horizon() {
        let (p, f) = (smooth_black(), linear_fresnel());
        let n = DVec3::Y;
        let up = DVec3::new(0.3, 0.9, 0.1).normalize();
        let below = DVec3::new(0.3, -0.2, 0.1).normalize();
        let grazing = DVec3::X;
        assert_eq!(lacquer_brdf(&p, &f, n, below, up), [0.0; 3]);
        assert_eq!(lacquer_brdf(&p, &f, n, up, below), [0.0; 3]);
        assert_eq!(lacquer_brdf(&p, &f, n, grazing, up), [0.0; 3]);
        assert_eq!(lacquer_brdf(&p, &f, n, up, grazing), [0.0; 3]);
        assert_eq!(lacquer_brdf(&p, &f, n, DVec3::NAN, up), [0.0; 3]);
    }

    #[test]
    fn brdf_matches_a_hand_computation() {
        // N = +Z; V at 30° and L at 40° from N on opposite sides of the XZ plane, so H lies in the
        // plane at α = 5° from N and θ = acos(vh) = 35°. By hand (trigonometry, no vectors):
        let (deg30, deg40, deg5, deg35) = (
            30f64.to_radians(),
            40f64.to_radians(),
            5f64.to_radians(),
            35f64.to_radians(),
        );
        let (nv, nl, nh, vh) = (deg30.cos(), deg40.cos(), deg5.cos(), deg35.cos());
        let m = 0.05;
        let d = (-(deg5.tan().powi(2)) / (m * m)).exp() / (PI * m * m * nh.powi(4));
        let g = 1f64.min(2.0 * nh * nv / vh).min(2.0 * nh * nl / vh);
        let f = 0.04 + 0.96 * 35.0 / 90.0;
        let g_r = 1.22 - 0.224 + 0.0199;
        let expected = 0.02 * (-0.03 + 1.05 * nv) * g_r / PI + f * d * g / (4.0 * nv * nl);
        // The same number typed from an independent evaluation (Python, float64): 0.948242228...
        assert!((expected - 0.948_242_228).abs() < 1e-9, "{expected}");

        let n = DVec3::Z;
        let v = DVec3::new(deg30.sin(), 0.0, deg30.cos());
        let l = DVec3::new(-deg40.sin(), 0.0, deg40.cos());
        let got = lacquer_brdf(&smooth_black(), &linear_fresnel(), n, v, l);
        // Vector vs trigonometric route: rounding differences only, amplified by the exponent
        // (≈ 3), so 1e-12 relative.
        for c in got {
            assert!((c / expected - 1.0).abs() < 1e-12, "{got:?} vs {expected}");
        }
    }

    #[test]
    fn diffuse_term_clamps_and_scales() {
        let p = BrdfParams {
            albedo: [0.5, 0.06, 0.03],
            ..smooth_black()
        };
        // nv = 0.02: a + b·nv = -0.03 + 0.021 < 0 → 0.
        assert_eq!(view_dependent_diffuse(&p, 0.02), [0.0; 3]);
        // nv = 1: (a + b)·g/π = 1.02·1.0159/π, times k_d per channel.
        let scale = 1.02 * 1.0159 / PI;
        let got = view_dependent_diffuse(&p, 1.0);
        for (c, k) in got.iter().zip([0.5, 0.06, 0.03]) {
            assert!((c - k * scale).abs() < 1e-15, "{got:?}");
        }
    }

    #[test]
    fn mirror_configuration_peaks_at_one_over_pi_m_squared() {
        // V = L = N: nh = vh = nv = nl = 1, G = 1, F = F(0) = 0.04, D = 1/(π m²):
        // f_spec = 0.04 / (4 π m²) = 1.2732395 for m = 0.05.
        let p = BrdfParams {
            albedo: [0.0; 3],
            ..smooth_black()
        };
        let got = lacquer_brdf(&p, &linear_fresnel(), DVec3::Z, DVec3::Z, DVec3::Z);
        let expected = 0.04 / (4.0 * PI * 0.0025);
        for c in got {
            assert!((c / expected - 1.0).abs() < 1e-14, "{got:?}");
        }
    }
}
