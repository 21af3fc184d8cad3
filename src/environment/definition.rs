//! SPEC §4's integrals evaluated by brute force over every pixel of the equirectangular source,
//! without the cube, the mips or the lobe cut-off: what the prefilter approximates, for tests.
//! Directions are in the environment's frame (no rotation, intensity 1). Owns nothing else.

use glam::DVec3;

use super::cube::equirect_to_direction;
use super::image::Equirect;
use super::oracle::sample_bilinear;

/// Lpre(d, β) = ∫ L(s) w_β(d·s) dω_s / ∫ w_β(d·s) dω_s with w_β(c) = exp((c − 1)/β²), as the sum
/// over pixels p of L_p·w·dω_p / Σ w·dω_p, s_p the pixel centre and dω_p its exact solid angle.
/// β = 0 is the source itself, read bilinearly as the cube's step 1 reads it.
///
/// w is evaluated as exp(−(q − q_min)/β²) with q = |d − s|²/2 = 1 − d·s (no cancellation) and
/// q_min the smallest q of any pixel: the common factor exp(−q_min/β²) cancels in the ratio, and
/// without it every weight underflows to 0 once q_min/β² > 745 (a small β far from any centre).
pub fn prefiltered_radiance_definition(src: &Equirect, d: DVec3, beta: f64) -> [f64; 3] {
    let d = d.normalize();
    if beta <= 0.0 {
        return sample_bilinear(src, d);
    }
    let grid = PixelGrid::new(src);
    let q_of = |x: usize, y: usize| (d - grid.direction(x, y)).length_squared() / 2.0;
    let mut q_min = f64::INFINITY;
    for y in 0..grid.height {
        for x in 0..grid.width {
            q_min = q_min.min(q_of(x, y));
        }
    }
    let mut sum = [0.0; 3];
    let mut weight = 0.0;
    for y in 0..grid.height {
        for x in 0..grid.width {
            let w = (-(q_of(x, y) - q_min) / (beta * beta)).exp() * grid.solid_angle[y];
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
    /// (sin θ, cos θ) of each row's centre.
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
        let solid_angle = (0..height)
            .map(|y| {
                let top = pi * y as f64 / height as f64;
                let bottom = pi * (y + 1) as f64 / height as f64;
                std::f64::consts::TAU / width as f64 * (top.cos() - bottom.cos())
            })
            .collect();
        Self {
            width,
            height,
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
