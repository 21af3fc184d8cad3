//! The diffuse laws of paper §3.2 from the separated diffuse part: f(N·V) = a + b·N·V shared by
//! all boards, an apparent albedo per board, g(r) from the boards' luminances normalised to the
//! least-lacquer board, and k_d.
//!
//! The data fix only the product k_d·g(r)·f(N·V): scaling f by α, g by γ and k_d by 1/(α·γ)
//! predicts the same reflectance. Two conventions pick one member of that family:
//! f(1) = a + b = `f_at_normal` and g(r_min) = `lacquer_law(r_min)` of [`Normalisation`] (the
//! least-lacquer board). By default both are 1, so k_d is the least-lacquer board's diffuse
//! reflectance factor seen along the normal; `--normalise-like` takes both from a reference
//! material, which is how a fit of the paper's own boards reproduces eqs. (6)–(8) (their g(1) is
//! 1.0159 and a + b is 1.02 or 0.97, not 1). Owns these laws; the separation is
//! [`super::separation`]'s.

use super::data::luminance;
use super::linalg::{minimise_1d, SymmetricMatrix};
use crate::{Error, Result};

/// The conventions that split k_d·g·f into its factors (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normalisation {
    /// f(N·V = 1) = a + b.
    pub f_at_normal: f64,
    /// g's value at the least-lacquer board comes from this law, and it is g's shape when the
    /// data hold a single lacquer ratio (g cannot be fitted then).
    pub lacquer_law: [f64; 3],
}

/// Per board and channel: Σw, Σw·nv, Σw·nv², Σw·z, Σw·z·nv, Σw·z² of the separated diffuse z.
#[derive(Clone, Copy, Debug, Default)]
pub struct DiffuseSums {
    pub w: f64,
    pub w_nv: f64,
    pub w_nv2: f64,
    pub w_z: f64,
    pub w_z_nv: f64,
    pub w_z2: f64,
}

impl DiffuseSums {
    pub fn add(&mut self, weight: f64, nv: f64, z: f64) {
        self.w += weight;
        self.w_nv += weight * nv;
        self.w_nv2 += weight * nv * nv;
        self.w_z += weight * z;
        self.w_z_nv += weight * z * nv;
        self.w_z2 += weight * z * z;
    }

    /// With u = 1 + β·(nv − 1) = (1 − β) + β·nv: (Σw·z·u, Σw·u²).
    fn projections(&self, beta: f64) -> (f64, f64) {
        let (p, q) = (1.0 - beta, beta);
        (
            p * self.w_z + q * self.w_z_nv,
            p * p * self.w + 2.0 * p * q * self.w_nv + q * q * self.w_nv2,
        )
    }
}

/// The diffuse result.
#[derive(Clone, Debug, PartialEq)]
pub struct DiffuseFit {
    /// β = b/(a + b), the shape of f.
    pub beta: f64,
    pub diffuse_a: f64,
    pub diffuse_b: f64,
    /// Per board: its diffuse reflectance factor at N·V = 1, k_d·g(r)·f(1), RGB.
    pub board_albedo: Vec<[f64; 3]>,
    /// Per board: its luminance divided by the least-lacquer board's (what g is fitted to).
    pub normalised_luminance: Vec<f64>,
    /// (c0, c1, c2) of g.
    pub lacquer_law: [f64; 3],
    /// False when the data hold one lacquer ratio and g kept the normalisation's law.
    pub lacquer_law_fitted: bool,
    /// Per board: k_d = board albedo / (f(1)·g(r)).
    pub board_kd: Vec<[f64; 3]>,
    /// The material's k_d: least squares over the boards of board albedo ≈ k_d·f(1)·g(r).
    pub albedo: [f64; 3],
}

/// g(r) = c0 + c1·r + c2·r².
pub fn eval_law(law: [f64; 3], r: f64) -> f64 {
    law[0] + r * (law[1] + law[2] * r)
}

/// Fits the diffuse laws. `sums[s][c]` are the separated diffuse part's sums for board s and
/// channel c, `ratios[s]` the boards' lacquer ratios.
pub fn fit_diffuse(
    sums: &[[DiffuseSums; 3]],
    ratios: &[f64],
    normalisation: &Normalisation,
) -> Result<DiffuseFit> {
    // J(β) = Σ_sc [Σw·z² − (Σw·z·u)²/Σw·u²], each board's albedo eliminated in closed form.
    // β = b/(a + b) is 1.03 and 0.99 in the paper; [−2, 4] leaves wide margins either side.
    let objective = |beta: f64| {
        sums.iter()
            .flatten()
            .map(|s| {
                let (zu, uu) = s.projections(beta);
                s.w_z2 - if uu > 0.0 { zu * zu / uu } else { 0.0 }
            })
            .sum::<f64>()
    };
    let (beta, _, _) = minimise_1d(objective, -2.0, 4.0, 61, 1e-12);
    let board_albedo: Vec<[f64; 3]> = sums
        .iter()
        .map(|board| {
            board.map(|s| {
                let (zu, uu) = s.projections(beta);
                if uu > 0.0 {
                    zu / uu
                } else {
                    0.0
                }
            })
        })
        .collect();
    let (normalised_luminance, lacquer_law, fitted) =
        fit_lacquer_law(&board_albedo, ratios, normalisation)?;
    let f1 = normalisation.f_at_normal;
    let g: Vec<f64> = ratios.iter().map(|&r| eval_law(lacquer_law, r)).collect();
    let board_kd = board_albedo
        .iter()
        .zip(&g)
        .map(|(k, g)| k.map(|v| v / (f1 * g)))
        .collect();
    let g2: f64 = g.iter().map(|v| v * v).sum();
    let albedo = std::array::from_fn(|c| {
        board_albedo
            .iter()
            .zip(&g)
            .map(|(k, g)| k[c] * g)
            .sum::<f64>()
            / (f1 * g2)
    });
    Ok(DiffuseFit {
        beta,
        diffuse_a: f1 * (1.0 - beta),
        diffuse_b: f1 * beta,
        board_albedo,
        normalised_luminance,
        lacquer_law,
        lacquer_law_fitted: fitted,
        board_kd,
        albedo,
    })
}

/// The distinct lacquer ratios, ascending; an error if there are exactly two (too few for the
/// three coefficients of g, too many to keep one board's law).
pub fn check_lacquer_ratios(ratios: &[f64]) -> Result<Vec<f64>> {
    let mut distinct: Vec<f64> = ratios.to_vec();
    distinct.sort_by(f64::total_cmp);
    distinct.dedup();
    if distinct.len() == 2 {
        return Err(Error::invalid(
            "data for g(r)",
            format!("2 lacquer ratios ({}, {})", distinct[0], distinct[1]),
            "too few to fit c0, c1, c2: measure boards at 3 or more lacquer ratios r, or fit one \
             board at a time (g then keeps the normalisation's law)",
        ));
    }
    Ok(distinct)
}

/// g from the boards' luminances: (normalised luminances, law, whether it was fitted).
fn fit_lacquer_law(
    board_albedo: &[[f64; 3]],
    ratios: &[f64],
    normalisation: &Normalisation,
) -> Result<(Vec<f64>, [f64; 3], bool)> {
    let r_min = ratios.iter().copied().fold(f64::INFINITY, f64::min);
    let least: Vec<f64> = board_albedo
        .iter()
        .zip(ratios)
        .filter(|(_, &r)| r == r_min)
        .map(|(k, _)| luminance(*k))
        .collect();
    let reference = least.iter().sum::<f64>() / least.len().max(1) as f64;
    if reference.is_nan() || reference <= 0.0 {
        return Err(Error::invalid(
            "diffuse luminance of the least-lacquer board",
            reference,
            "must be > 0 to normalise g(r) by it; the separated diffuse part is zero or \
             negative, so check that the values are reflectance factors (π·f_r)",
        ));
    }
    let normalised: Vec<f64> = board_albedo
        .iter()
        .map(|k| luminance(*k) / reference)
        .collect();
    let g_min = eval_law(normalisation.lacquer_law, r_min);
    let distinct = check_lacquer_ratios(ratios)?;
    match distinct.len() {
        1 => Ok((normalised, normalisation.lacquer_law, false)),
        _ => {
            // Least squares on (1, r, r²); the paper's normalised data are 1 at r_min, and the fit
            // is scaled by g_min so that g(r_min) ≈ the normalisation's value (exactly, without
            // noise) — the fitted quadratic passes near, not through, its first point.
            let mut normal = SymmetricMatrix::zeros(3);
            let mut rhs = [0.0; 3];
            for (&r, &y) in ratios.iter().zip(&normalised) {
                let basis = [1.0, r, r * r];
                for i in 0..3 {
                    rhs[i] += basis[i] * y;
                    for j in i..3 {
                        normal.add(i, j, basis[i] * basis[j]);
                    }
                }
            }
            let d = normal.solve(&rhs).ok_or_else(|| {
                Error::invalid(
                    "data for g(r)",
                    format!("lacquer ratios {distinct:?}"),
                    "the quadratic g(r) is not determined by these ratios",
                )
            })?;
            Ok((normalised, [0, 1, 2].map(|i| g_min * d[i]), true))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PAPER_LAW: [f64; 3] = [1.22, -0.224, 0.0199];

    /// Sums of noiseless diffuse data k·g(r)·(a + b·nv) at a few nv, unit weights.
    fn sums_for(k: [f64; 3], g: f64, a: f64, b: f64) -> [DiffuseSums; 3] {
        k.map(|kc| {
            let mut s = DiffuseSums::default();
            for nv in [0.1, 0.3, 0.5, 0.7, 0.9, 1.0] {
                s.add(1.0, nv, kc * g * (a + b * nv));
            }
            s
        })
    }

    #[test]
    fn recovers_the_paper_laws_with_the_paper_normalisation() {
        // Data built from (a, b) = (−0.03, 1.05), g = the paper's, k_d = red; with f(1) = 1.02 and
        // the paper's law as normalisation every factor comes back. The golden section resolves β
        // to ≈ √ε (J is a difference of O(1) sums that vanishes quadratically): 1e-7.
        let ratios = [1.0, 2.0, 3.0, 4.0, 5.0];
        let kd = [0.5, 0.06, 0.03];
        let sums: Vec<_> = ratios
            .iter()
            .map(|&r| sums_for(kd, eval_law(PAPER_LAW, r), -0.03, 1.05))
            .collect();
        let norm = Normalisation {
            f_at_normal: 1.02,
            lacquer_law: PAPER_LAW,
        };
        let fit = fit_diffuse(&sums, &ratios, &norm).unwrap();
        assert!((fit.diffuse_a + 0.03).abs() < 1e-7 && (fit.diffuse_b - 1.05).abs() < 1e-7);
        for (got, want) in fit.lacquer_law.iter().zip(PAPER_LAW) {
            assert!((got - want).abs() < 1e-7, "{:?}", fit.lacquer_law);
        }
        for (got, want) in fit.albedo.iter().zip(kd) {
            assert!((got - want).abs() < 1e-7, "{:?}", fit.albedo);
        }
        // Normalised luminance of board r = 3: g(3)/g(1) = 0.7271/1.0159 (hand values).
        assert!((fit.normalised_luminance[2] - 0.7271 / 1.0159).abs() < 1e-7);
        assert!(fit.lacquer_law_fitted);
    }

    #[test]
    fn default_normalisation_sets_f_and_g_to_one_at_the_reference() {
        // Same data, f(1) = 1 and g(1) = 1: a + b = 1, g(1) = 1, and k_d takes the scale
        // 1.02·1.0159 (hand value), so the product is unchanged.
        let ratios = [1.0, 3.0, 5.0];
        let sums: Vec<_> = ratios
            .iter()
            .map(|&r| sums_for([0.02; 3], eval_law(PAPER_LAW, r), 0.01, 0.96))
            .collect();
        let unit_law = PAPER_LAW.map(|c| c / 1.0159);
        let norm = Normalisation {
            f_at_normal: 1.0,
            lacquer_law: unit_law,
        };
        let fit = fit_diffuse(&sums, &ratios, &norm).unwrap();
        assert!((fit.diffuse_a + fit.diffuse_b - 1.0).abs() < 1e-12);
        assert!((eval_law(fit.lacquer_law, 1.0) - 1.0).abs() < 1e-7);
        assert!((fit.albedo[0] - 0.02 * 0.97 * 1.0159).abs() < 1e-9);
    }

    #[test]
    fn one_ratio_keeps_the_law_and_two_are_an_error() {
        let norm = Normalisation {
            f_at_normal: 1.0,
            lacquer_law: PAPER_LAW,
        };
        let one = fit_diffuse(&[sums_for([0.1; 3], 1.0, 0.0, 1.0)], &[1.0], &norm).unwrap();
        assert_eq!(
            (one.lacquer_law, one.lacquer_law_fitted),
            (PAPER_LAW, false)
        );
        let two = [
            sums_for([0.1; 3], 1.0, 0.0, 1.0),
            sums_for([0.1; 3], 0.8, 0.0, 1.0),
        ];
        let err = fit_diffuse(&two, &[1.0, 2.0], &norm)
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "invalid data for g(r) = 2 lacquer ratios (1, 2): too few to fit c0, c1, c2: measure \
             boards at 3 or more lacquer ratios r, or fit one board at a time (g then keeps the \
             normalisation's law)"
        );
    }
}
