//! Synthetic measurements from the model (`shikki synth`): the model's reflectance factor π·f_r
//! on a goniometer grid, one board per lacquer ratio, with optional multiplicative Gaussian noise
//! from a seeded generator, so a given seed always gives the same file.
//!
//! Boards differ only in r, i.e. in g(r), which scales their diffuse part (SPEC §2). Owns the
//! grid, the noise and the generator; the values come from [`crate::model::lacquer_brdf`].

use glam::DVec3;
use std::f64::consts::PI;

use super::csv::goniometer_csv;
use super::data::{light_direction, view_direction, Measurement, Measurements, Sample};
use super::merl::merl_bytes;
use crate::model::{lacquer_brdf, LacquerMaterial};
use crate::Result;

/// The lacquer ratios `shikki synth` uses by default.
pub const DEFAULT_RATIOS: [f64; 5] = [1.0, 2.0, 3.0, 4.0, 5.0];

/// SplitMix64 (Steele, Lea & Flood 2014): small, fast, and its output is fixed by the seed.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1): the top 53 bits.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal by Box–Muller (one of the pair; 1 − u keeps the logarithm finite).
    pub fn normal(&mut self) -> f64 {
        let (u1, u2) = (1.0 - self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
}

/// The goniometer grid, (θ_i, θ_o, φ) in degrees: θ_i = 0..80 step 5; in the plane of incidence
/// θ_o = −85..85 step 1 (fine enough for a smooth lobe, m = 0.05 ≈ 3°); out of the plane
/// φ = 30..150 step 30 with θ_o = 5..85 step 5.
pub fn goniometer_grid() -> Vec<[f64; 3]> {
    let mut grid = Vec::new();
    for theta_i in (0..=80).step_by(5) {
        let ti = f64::from(theta_i);
        for theta_o in -85..=85 {
            grid.push([ti, f64::from(theta_o), 0.0]);
        }
        for phi in (30..=150).step_by(30) {
            for theta_o in (5..=85).step_by(5) {
                grid.push([ti, f64::from(theta_o), f64::from(phi)]);
            }
        }
    }
    grid
}

/// Noise and seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// σ of the multiplicative noise: value × (1 + σ·n), n standard normal.
    pub relative: f64,
    pub seed: u64,
}

/// Measurements of `material` on [`goniometer_grid`], one board per ratio (named `board-1`, …),
/// with each row's angles. Every ratio must be valid for the material (SPEC §2's domain of r).
pub fn synthesize(
    material: &LacquerMaterial,
    ratios: &[f64],
    noise: Noise,
) -> Result<(Measurements, Vec<[f64; 3]>)> {
    check_noise(noise)?;
    let fresnel = material.fresnel_table()?;
    let grid = goniometer_grid();
    let mut rng = Rng::new(noise.seed);
    let mut data = Measurements {
        source: "synthetic".into(),
        samples: Vec::new(),
        rows: Vec::with_capacity(grid.len() * ratios.len()),
        notes: Vec::new(),
    };
    let mut angles = Vec::with_capacity(grid.len() * ratios.len());
    for (s, &r) in ratios.iter().enumerate() {
        let board = LacquerMaterial {
            lacquer_ratio: r,
            ..material.clone()
        };
        let params = board.brdf_params()?;
        data.samples.push(Sample {
            name: format!("board-{}", s + 1),
            lacquer_ratio: r,
        });
        for &[ti, to, phi] in &grid {
            let (light, view) = (light_direction(ti), view_direction(to, phi));
            let f = lacquer_brdf(&params, &fresnel, DVec3::Z, view, light);
            data.rows.push(Measurement {
                sample: s,
                light,
                view,
                reflectance: f.map(|v| with_noise(PI * v, noise.relative, &mut rng)),
                line: 0,
            });
            angles.push([ti, to, phi]);
        }
    }
    Ok((data, angles))
}

/// [`synthesize`] as goniometer CSV text, with a comment naming what made it.
pub fn synthesize_csv(
    material: &LacquerMaterial,
    ratios: &[f64],
    noise: Noise,
    origin: &str,
) -> Result<String> {
    let (data, angles) = synthesize(material, ratios, noise)?;
    let comment = format!(
        "synthetic measurements from shikki synth: {origin}, noise {}, seed {}\n\
         values are reflectance factors pi*f_r (1 = a white Lambertian diffuser)",
        noise.relative, noise.seed
    );
    Ok(goniometer_csv(&data, &angles, &comment))
}

/// A MERL file of `material` (its own r), with the same noise model.
pub fn synthesize_merl(material: &LacquerMaterial, noise: Noise) -> Result<Vec<u8>> {
    check_noise(noise)?;
    let params = material.brdf_params()?;
    let fresnel = material.fresnel_table()?;
    let mut rng = Rng::new(noise.seed);
    Ok(merl_bytes(|light, view| {
        lacquer_brdf(&params, &fresnel, DVec3::Z, view, light)
            .map(|v| with_noise(v, noise.relative, &mut rng))
    }))
}

fn check_noise(noise: Noise) -> Result<()> {
    if noise.relative.is_finite() && (0.0..0.5).contains(&noise.relative) {
        Ok(())
    } else {
        Err(crate::Error::invalid(
            "--noise",
            noise.relative,
            "the relative noise σ must be in [0, 0.5) (0.02 is 2 %)",
        ))
    }
}

/// value × (1 + σ·n), never below 0; no draw at all when σ = 0 (so noiseless data are exact).
fn with_noise(value: f64, sigma: f64, rng: &mut Rng) -> f64 {
    if sigma == 0.0 {
        value
    } else {
        (value * (1.0 + sigma * rng.normal())).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_reference_values() {
        // SplitMix64 from seed 0: the first outputs of the reference implementation (Vigna's
        // splitmix64.c) are 0xe220a8397b1dcdaf, 0x6e789e6aa1b965f4.
        let mut rng = Rng::new(0);
        assert_eq!(rng.next_u64(), 0xe220_a839_7b1d_cdaf);
        assert_eq!(rng.next_u64(), 0x6e78_9e6a_a1b9_65f4);
    }

    #[test]
    fn normal_draws_have_unit_variance() {
        // 200 000 draws: the sample mean's σ is 1/√200000 ≈ 0.0022 and the variance's ≈ 0.0032,
        // so ±0.01 is more than 3σ for both.
        let mut rng = Rng::new(7);
        let n = 200_000;
        let draws: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
        let mean = draws.iter().sum::<f64>() / n as f64;
        let var = draws.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(
            mean.abs() < 0.01 && (var - 1.0).abs() < 0.01,
            "{mean} {var}"
        );
    }

    #[test]
    fn grid_covers_the_mirror_direction_of_every_incidence() {
        let grid = goniometer_grid();
        assert_eq!(grid.len(), 17 * (171 + 5 * 17));
        for ti in (0..=80).step_by(5) {
            let ti = f64::from(ti);
            assert!(grid.contains(&[ti, ti, 0.0]));
        }
    }

    #[test]
    fn same_seed_same_data_and_boards_differ_in_g_only() {
        let material = LacquerMaterial::preset("rough-red").unwrap();
        let noise = Noise {
            relative: 0.02,
            seed: 3,
        };
        let (a, _) = synthesize(&material, &[1.0, 3.0], noise).unwrap();
        let (b, _) = synthesize(&material, &[1.0, 3.0], noise).unwrap();
        assert_eq!(a, b);
        // Noiseless: the difference of two boards is the diffuse part scaled by g(3) − g(1),
        // i.e. k_d·(a + b·nv)·(g(3) − g(1)) with g(3) − g(1) = 0.7271 − 1.0159 (hand values).
        let (clean, _) = synthesize(
            &material,
            &[1.0, 3.0],
            Noise {
                relative: 0.0,
                seed: 0,
            },
        )
        .unwrap();
        let half = clean.rows.len() / 2;
        for i in [0, 100, 2000] {
            let (r1, r3) = (&clean.rows[i], &clean.rows[half + i]);
            let nv = r1.view.z;
            let expected = 0.5 * (0.01 + 0.96 * nv) * (0.7271 - 1.0159);
            // 1e-12: the specular parts cancel to rounding.
            assert!((r3.reflectance[0] - r1.reflectance[0] - expected).abs() < 1e-12);
        }
    }

    #[test]
    fn ratios_outside_the_domain_are_refused() {
        let material = LacquerMaterial::preset("smooth").unwrap();
        let err = synthesize(
            &material,
            &[1.0, 7.0],
            Noise {
                relative: 0.0,
                seed: 0,
            },
        );
        assert!(err.unwrap_err().to_string().contains("invalid r = 7"));
        let err = synthesize(
            &material,
            &[1.0],
            Noise {
                relative: -0.1,
                seed: 0,
            },
        );
        assert!(err.unwrap_err().to_string().contains("--noise"));
    }
}
