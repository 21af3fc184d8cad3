//! Sampling the Beckmann distribution of visible normals (Heitz & d'Eon 2014; the slope inversion
//! as Jakob 2014 describes it): the twin of shaders/common/visible_normals.glsl, formula by
//! formula. Half vectors are drawn with density D(h)·G1(V)·max(0, V·H)/(N·V), G1 Smith's masking
//! for Beckmann, so the reflected direction's density is D·G1/(4·N·V) and the specular weight
//! f_spec·(N·s)/pdf = F·G/G1 stays bounded at grazing views.
//!
//! The sampler works in f32, as the shader does (light_between's twin forms directions in f32);
//! the densities come in f64 for the twin's weights.

use glam::Vec3;

use crate::gpu::shaders::interface::VISIBLE_SLOPE_STEPS;

const INV_SQRT_PI: f64 = 0.564_189_583_547_756_3;

/// erfc(x) for x ≥ 0 (Abramowitz & Stegun 7.1.26, |error| ≤ 1.5e-7).
pub fn erfc_positive(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let p = (((1.061_405_429 * t - 1.453_152_027) * t + 1.421_413_741) * t - 0.284_496_736) * t
        + 0.254_829_592;
    p * t * (-x * x).exp()
}

/// [`erfc_positive`] in f32, as the shader evaluates it.
fn erfc_positive_f32(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let p =
        (((1.061_405_4 * t - 1.453_152) * t + 1.421_413_8) * t - 0.284_496_74) * t + 0.254_829_6;
    p * t * (-x * x).exp()
}

fn erf_odd(x: f32) -> f32 {
    let e = 1.0 - erfc_positive_f32(x.abs());
    if x < 0.0 {
        -e
    } else {
        e
    }
}

/// erf⁻¹(x) on (−1, 1) (Giles 2011, single precision).
pub fn erfinv_odd(x: f32) -> f32 {
    let mut w = -((1.0 - x) * (1.0 + x)).max(1e-30).ln();
    let p = if w < 5.0 {
        w -= 2.5;
        [
            3.432_739_4e-7,
            -3.523_387_7e-6,
            -4.391_506_5e-6,
            0.000_218_580_87,
            -0.001_253_725,
            -0.004_177_681_6,
            0.246_640_73,
            1.501_409_4,
        ]
        .iter()
        .fold(2.810_226_4e-8, |p, c| c + p * w)
    } else {
        w = w.sqrt() - 3.0;
        [
            0.000_100_950_56,
            0.001_349_343_2,
            -0.003_673_428_4,
            0.005_739_507_7,
            -0.007_622_461,
            0.009_438_870_5,
            1.001_674,
            2.832_976_8,
        ]
        .iter()
        .fold(-0.000_200_214_26, |p, c| c + p * w)
    };
    p * x
}

/// Smith's G1 for Beckmann roughness m at N·V = nv > 0: 1/(1 + Λ(a)), a = 1/(m·tan θ_V),
/// Λ(a) = (e^{−a²}/(a√π) − erfc(a))/2.
pub fn beckmann_g1(nv: f64, m: f64) -> f64 {
    let sin_v = (1.0 - nv * nv).max(0.0).sqrt();
    if sin_v <= 0.0 {
        return 1.0;
    }
    let a = nv / (m * sin_v);
    let lambda = 0.5 * ((-a * a).exp() * INV_SQRT_PI / a - erfc_positive(a));
    1.0 / (1.0 + lambda.max(0.0))
}

/// The density of the reflected direction when h comes from [`sample_visible_normal`]:
/// D(h)·G1(V)/(4·N·V), 0 where V·H ≤ 0. `d` = D(h), `g1` = [`beckmann_g1`].
pub fn visible_normal_pdf(d: f64, g1: f64, nv: f64, vh: f64) -> f64 {
    match vh > 0.0 {
        true => d * g1 / (4.0 * nv),
        false => 0.0,
    }
}

/// Slopes of the unit-roughness visible-slope distribution seen from θ (see the shader's
/// `visible_slopes`): ỹ = erf⁻¹(2u_y − 1); x̃ by `VISIBLE_SLOPE_STEPS` safeguarded Newton steps on
/// the CDF in b = erf(x̃). Returns the slopes and the CDF's residual after the last step.
pub fn visible_slopes(theta: f32, u: [f32; 2]) -> ([f32; 2], f32) {
    let ux = u[0].clamp(1e-6, 1.0 - 1e-6);
    let uy = u[1].clamp(1e-6, 1.0 - 1e-6);
    let y = erfinv_odd(2.0 * uy - 1.0);
    if theta < 1e-4 {
        return ([erfinv_odd(2.0 * ux - 1.0), y], 0.0);
    }
    let tan_t = theta.tan();
    let cot_t = 1.0 / tan_t;
    let inv_sqrt_pi = INV_SQRT_PI as f32;
    let (mut lo, mut hi) = (-1.0_f32, erf_odd(cot_t));
    let fit = 1.0 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta));
    let mut b = hi - (1.0 + hi) * (1.0 - ux).powf(fit);
    let norm = 1.0 / (1.0 + hi + inv_sqrt_pi * tan_t * (-cot_t * cot_t).exp());
    let cdf = |b: f32| {
        let x = erfinv_odd(b);
        norm * (1.0 + b + inv_sqrt_pi * tan_t * (-x * x).exp()) - ux
    };
    for _ in 0..VISIBLE_SLOPE_STEPS {
        if !(b >= lo && b <= hi) {
            b = 0.5 * (lo + hi);
        }
        let x = erfinv_odd(b);
        let value = cdf(b);
        let derivative = norm * (1.0 - x * tan_t);
        if value > 0.0 {
            hi = b;
        } else {
            lo = b;
        }
        b -= value / derivative;
    }
    if !(b >= lo && b <= hi) {
        b = 0.5 * (lo + hi);
    }
    ([erfinv_odd(b), y], cdf(b))
}

/// A half vector of the Beckmann lobe (roughness m) drawn from the visible normals seen from
/// `v_local` (the view in the frame (t, b, n), z along n, z > 0), in that frame.
pub fn sample_visible_normal(v_local: Vec3, m: f32, u: [f32; 2]) -> Vec3 {
    let stretched = Vec3::new(m * v_local.x, m * v_local.y, v_local.z).normalize();
    let r = (stretched.x * stretched.x + stretched.y * stretched.y).sqrt();
    let theta = r.atan2(stretched.z);
    let (cos_phi, sin_phi) = match r > 0.0 {
        true => (stretched.x / r, stretched.y / r),
        false => (1.0, 0.0),
    };
    let ([sx, sy], _) = visible_slopes(theta, u);
    let slope = [cos_phi * sx - sin_phi * sy, sin_phi * sx + cos_phi * sy].map(|c| c * m);
    Vec3::new(-slope[0], -slope[1], 1.0).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::environment::brdf_definition::specular_albedo;
    use crate::model::brdf::{beckmann_d, lacquer_specular, BrdfParams};
    use crate::model::FresnelTable;
    use glam::DVec3;

    #[test]
    fn erf_approximations_invert_each_other() {
        // erfc to A&S's 1.5e-7 (checked at known values), erf⁻¹ its inverse to f32 rounding.
        assert!((erfc_positive(0.5) - 0.479_500_122_186_953_5).abs() < 2e-7);
        assert!((erfc_positive(2.0) - 0.004_677_734_981_047_266).abs() < 2e-7);
        for k in -99..=99 {
            let x = k as f32 / 100.0;
            let back = erf_odd(erfinv_odd(x));
            assert!((back - x).abs() < 2e-6, "{x}: {back}");
        }
    }

    #[test]
    fn slope_inversion_leaves_no_residual() {
        // The CDF's residual after the steps, over θ and u: measured 2.1e-7 (f32 rounding of its
        // terms); 1.8e-7 after 4 steps, 2.2e-6 after 2.
        let mut worst: f32 = 0.0;
        for t in 1..90 {
            let theta = t as f32 * (std::f32::consts::FRAC_PI_2 / 90.0);
            for k in 0..200 {
                let u = (k as f32 + 0.5) / 200.0;
                let (_, residual) = visible_slopes(theta, [u, 0.5]);
                worst = worst.max(residual.abs());
            }
        }
        assert!(worst < 2e-6, "{worst}");
    }

    /// The sampler draws what its density says: over many draws the mean of
    /// f_spec·(N·s)/pdf(s) is the directional albedo ∫ f_spec·(N·s) dω, an independent quadrature
    /// (`specular_albedo`). A sampler whose draws and density disagree is biased by their ratio.
    #[test]
    fn draws_follow_the_visible_normal_density() {
        let fresnel = FresnelTable::dielectric(1.5, 0.0045).unwrap();
        for m in [0.05, 0.2, 0.5] {
            let brdf = BrdfParams {
                beckmann_m: m,
                diffuse_a: 0.0,
                diffuse_b: 0.0,
                lacquer_g: 1.0,
                albedo: [0.0; 3],
            };
            for nv in [0.05_f64, 0.3, 0.7, 0.98] {
                let v = Vec3::new((1.0 - nv * nv).sqrt() as f32, 0.0, nv as f32);
                let (n, vd) = (DVec3::Z, v.as_dvec3());
                let g1 = beckmann_g1(nv, m);
                let count = 256 * 256;
                let mut sum = 0.0;
                for i in 0..count {
                    let u = [
                        ((i / 256) as f32 + 0.5) / 256.0,
                        ((i % 256) as f32 + 0.5) / 256.0,
                    ];
                    let h = sample_visible_normal(v, m as f32, u).as_dvec3();
                    let s = 2.0 * vd.dot(h) * h - vd;
                    if s.z <= 0.0 {
                        continue;
                    }
                    let hd = (vd + s).normalize();
                    let pdf = visible_normal_pdf(beckmann_d(hd.z, m), g1, nv, vd.dot(hd));
                    let f = lacquer_specular(&brdf, &fresnel, n, vd, s);
                    sum += f[1] * s.z / pdf;
                }
                let estimate = sum / count as f64;
                let albedo = specular_albedo(&brdf, &fresnel, nv, 256, 64)[1];
                // A stratified grid of 65,536 draws of a bounded weight (F·G/G1 ≤ 1): measured at
                // most 2.6e-3 apart (m 0.5, nv 0.05), so 5e-3; a density without G1 would be off
                // by 1/G1, 2.5 % (m 0.05, nv 0.05) to 3.3× (m 0.5, nv 0.05).
                let rel = (estimate - albedo).abs() / albedo;
                assert!(rel < 5e-3, "m {m}, nv {nv}: {estimate} vs {albedo} ({rel})");
            }
        }
    }
}
