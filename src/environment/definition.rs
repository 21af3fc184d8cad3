//! SPEC §4's integrals evaluated by brute force over every pixel of the equirectangular source,
//! without the cube, the mips or the lobe cut-off: what the prefilter approximates, for tests.
//! Directions are in the environment's frame (no rotation, intensity 1). Owns nothing else.

use glam::DVec3;

use super::cube::{direction_to_equirect, equirect_row_solid_angle, equirect_to_direction};
use super::image::Equirect;
use super::oracle::source_pixel;

/// Lpre(d, β) = ∫ L(s) w_β(d·s) dω_s / ∫ w_β(d·s) dω_s with w_β(c) = exp((c − 1)/β²), as the sum
/// over pixels p of L_p·w·dω_p / Σ w·dω_p, s_p the pixel centre and dω_p its exact solid angle.
/// β = 0 is the source itself: the pixel that contains d, as the cube's step 1 reads it.
///
/// w is evaluated as exp(−(q − q_ref)/β²) with q = |d − s|²/2 = 1 − d·s (no cancellation) and
/// q_ref the q of the pixel that holds d: the common factor exp(−q_ref/β²) cancels in the ratio,
/// and without it every weight underflows to 0 once q/β² > 745 everywhere (a small β far from
/// any pixel centre). Valid for β above ~1/50 of a pixel's height h, where exp((q_ref − q)/β²) ≤
/// exp(h²/4β²) cannot overflow.
pub fn prefiltered_radiance_definition(src: &Equirect, d: DVec3, beta: f64) -> [f64; 3] {
    let d = d.normalize();
    if beta <= 0.0 {
        return source_pixel(src, d);
    }
    let grid = PixelGrid::new(src);
    let q_of = |x: usize, y: usize| (d - grid.direction(x, y)).length_squared() / 2.0;
    let (u, v) = direction_to_equirect(d);
    let x_ref = ((u * grid.width as f64) as usize).min(grid.width - 1);
    let y_ref = ((v * grid.height as f64) as usize).min(grid.height - 1);
    let q_ref = q_of(x_ref, y_ref);
    let theta_d = std::f64::consts::PI * v;
    let inv_beta2 = 1.0 / (beta * beta);
    let mut sum = [0.0; 3];
    let mut weight = 0.0;
    for y in 0..grid.height {
        // Every pixel of row y is at least |θ_y − θ_d| from d, so its q ≥ 1 − cos(θ_y − θ_d) =
        // 2·sin²((θ_y − θ_d)/2). When even that is 800·β² beyond q_ref, each weight of the row is
        // below e^−800, which is exactly 0 in f64 (the smallest subnormal is e^−744.4): skipping
        // the row leaves every bit of the sums as it was. This is not a cut-off.
        let q_row = 2.0 * ((grid.theta[y] - theta_d) / 2.0).sin().powi(2);
        if (q_row - q_ref) * inv_beta2 > 800.0 {
            continue;
        }
        for x in 0..grid.width {
            let w = (-(q_of(x, y) - q_ref) * inv_beta2).exp() * grid.solid_angle[y];
            let l = src.get(x as u32, y as u32);
            for c in 0..3 {
                sum[c] += w * f64::from(l[c]);
            }
            weight += w;
        }
    }
    sum.map(|s| s / weight)
}

/// E(n) = ∫ L(s)·max(n·s, 0) dω_s as Σ_p L_p·max(n·s_p, 0)·dω_p: the definition, not normalised.
pub fn irradiance_definition(src: &Equirect, n: DVec3) -> [f64; 3] {
    let n = n.normalize();
    let grid = PixelGrid::new(src);
    let mut sum = [0.0; 3];
    for y in 0..grid.height {
        for x in 0..grid.width {
            let w = n.dot(grid.direction(x, y)).max(0.0) * grid.solid_angle[y];
            let l = src.get(x as u32, y as u32);
            for c in 0..3 {
                sum[c] += w * f64::from(l[c]);
            }
        }
    }
    sum
}

/// Pixel-centre directions (separable: a row's θ, a column's φ) and per-row solid angles.
struct PixelGrid {
    width: usize,
    height: usize,
    /// θ and (sin θ, cos θ) of each row's centre.
    theta: Vec<f64>,
    rows: Vec<(f64, f64)>,
    /// (sin φ, cos φ) of each column's centre.
    columns: Vec<(f64, f64)>,
    /// dω of a pixel in each row: (2π/W)·(cos θ_top − cos θ_bottom), exact.
    solid_angle: Vec<f64>,
}

impl PixelGrid {
    fn new(src: &Equirect) -> Self {
        let (width, height) = (src.width as usize, src.height as usize);
        let pi = std::f64::consts::PI;
        let theta = (0..height)
            .map(|y| pi * (y as f64 + 0.5) / height as f64)
            .collect();
        let rows = (0..height)
            .map(|y| {
                let d = equirect_to_direction(0.5, (y as f64 + 0.5) / height as f64);
                // At u = ½ the direction is (0, cos θ, −sin θ).
                (-d.z, d.y)
            })
            .collect();
        let columns = (0..width)
            .map(|x| {
                let phi = std::f64::consts::TAU * ((x as f64 + 0.5) / width as f64 - 0.5);
                phi.sin_cos()
            })
            .collect();
        let solid_angle = (0..src.height)
            .map(|y| equirect_row_solid_angle(y, src.width, src.height))
            .collect();
        Self {
            width,
            height,
            theta,
            rows,
            columns,
            solid_angle,
        }
    }

    /// SPEC §4: d = (sin θ sin φ, cos θ, −sin θ cos φ).
    fn direction(&self, x: usize, y: usize) -> DVec3 {
        let (sin_theta, cos_theta) = self.rows[y];
        let (sin_phi, cos_phi) = self.columns[x];
        DVec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_linear_radiance_blurs_to_the_langevin_mean() {
        // L(s) = 1 + ½·s_x: by symmetry Lpre(d) = 1 + ½·d_x·⟨d·s⟩, and with dω = 2π d(d·s) the
        // mean cosine of w = exp(k(c − 1)), k = 1/β², over c ∈ [−1, 1] is coth k − 1/k (the
        // Langevin function). At 512 × 256 the pixel-centre quadrature is second order in the
        // pixel size (0.012 rad): 1e-4 for lobes ≥ 0.05 wide.
        let src = Equirect::from_fn(512, 256, |s| [(1.0 + 0.5 * s.x) as f32; 3]);
        for beta in [0.05f64, 0.2, 1.0] {
            let k = 1.0 / (beta * beta);
            let mean_cos = 1.0 / k.tanh() - 1.0 / k;
            for d in [
                DVec3::X,
                DVec3::new(0.3, -0.8, 0.5),
                DVec3::new(-1.0, 0.02, 0.0),
            ] {
                let want = 1.0 + 0.5 * d.normalize().x * mean_cos;
                let got = prefiltered_radiance_definition(&src, d, beta)[0];
                assert!(
                    (got - want).abs() < 1e-4,
                    "β {beta}, d {d}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn a_narrow_lobe_between_pixel_centres_does_not_underflow() {
        // 16 × 8 pixels (0.39 rad), d on a pixel corner, β = 0.005: the nearest centre has
        // q/β² ≈ 1200, so every unscaled weight e^(−q/β²) would be 0 and the ratio 0/0. Scaled
        // by the reference pixel, the result is a mix of the four pixels around the corner.
        let src = Equirect::from_fn(16, 8, |s| [(2.0 + s.y + s.x) as f32; 3]);
        let d = equirect_to_direction(2.0 / 16.0, 3.0 / 8.0);
        let got = prefiltered_radiance_definition(&src, d, 0.005)[0];
        let around = [(1, 2), (2, 2), (1, 3), (2, 3)].map(|(x, y)| f64::from(src.get(x, y)[0]));
        let (lo, hi) = around
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        assert!(
            got.is_finite() && (lo..=hi).contains(&got),
            "{got} not in [{lo}, {hi}]"
        );
    }

    #[test]
    fn irradiance_of_a_constant_is_pi_and_of_a_cosine_is_two_pi_over_three() {
        // ∫ max(n·s, 0) dω = π; ∫ max(s_y, 0)·max(s_y, 0) dω over the upper hemisphere = 2π/3.
        // Pixel-centre quadrature with exact pixel solid angles: 1e-4 relative at 512 × 256.
        let constant = Equirect::constant(512, 256, [1.0; 3]);
        let pi = std::f64::consts::PI;
        for n in [DVec3::Y, DVec3::new(0.4, 0.1, -0.9)] {
            let e = irradiance_definition(&constant, n)[0];
            assert!((e - pi).abs() < 1e-4 * pi, "{e}");
        }
        let cosine = Equirect::from_fn(512, 256, |s| [s.y.max(0.0) as f32; 3]);
        let e = irradiance_definition(&cosine, DVec3::Y)[0];
        assert!((e - 2.0 * pi / 3.0).abs() < 1e-4 * 2.0 * pi / 3.0, "{e}");
    }
}
