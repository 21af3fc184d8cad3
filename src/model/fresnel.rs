//! The Fresnel table of SPEC §3: RGB reflectance against θ = acos(V·H) in degrees, 0..=90,
//! linearly interpolated. Built from a CSV file (RGB, or spectral through [`super::spectral`]) or,
//! by default, from the exact unpolarised dielectric Fresnel equations for the dispersive lacquer
//! n(λ) = A + B/λ².
//!
//! Owns the table type, its CSV format (written here, read by the `csv` submodule) and the
//! dielectric equations. It does not know about materials or the BRDF; those call
//! [`FresnelTable::eval`].

use std::path::Path;

use super::cie::GRID_LEN;
use super::spectral::{grid_reflectance_to_rgb, grid_wavelength_nm, lerp, locate};
use crate::{Error, Result};

mod csv;

pub use csv::wavelength_nm;

/// The header of an RGB table, exactly as SPEC §3 writes it.
pub const RGB_HEADER: &str = "angle_deg,r,g,b";

/// The largest Fresnel CSV read (16 MiB): a table at every 0.01° is 9001 rows.
pub const MAX_FRESNEL_CSV_BYTES: u64 = 16 << 20;

/// n(λ) = A + B/λ² of the default lacquer (SPEC §3): A = 1.500, B = 0.0045 µm², n ≈ 1.51 at 589 nm.
pub const DEFAULT_IOR_A: f64 = 1.5;
/// See [`DEFAULT_IOR_A`].
pub const DEFAULT_IOR_B: f64 = 0.0045;

/// The largest A of n(λ) = A + B/λ². Real lacquers and glasses have A ≈ 1.4–1.9 (diamond 2.4);
/// 10 leaves room for anything a user may try while keeping n finite. A ≥ 1 is the lower bound
/// (lacquer is denser than air).
pub const MAX_IOR_A: f64 = 10.0;
/// The largest B of n(λ) = A + B/λ² [µm²]. Real lacquers and glasses have B ≤ 0.02 µm²; at 1 µm²
/// n(380 nm) ≤ 10 + 1/0.38² ≈ 17 stays finite. B = 1e308 made n infinite and every table entry
/// NaN, an error that named neither B nor its range. B ≥ 0 (normal dispersion) is the lower bound.
pub const MAX_IOR_B: f64 = 1.0;

/// The spectral range a spectral table must cover [nm] (SPEC §3: "covering 380–780 nm").
const SPECTRAL_COVER_NM: (f64, f64) = (380.0, 780.0);

/// F(θ) as a table: angles in degrees (first 0, last 90, strictly increasing) and linear RGB.
#[derive(Clone, Debug, PartialEq)]
pub struct FresnelTable {
    angles_deg: Vec<f64>,
    rgb: Vec<[f64; 3]>,
}

impl FresnelTable {
    /// A table from its entries, validated as SPEC §3 requires of an RGB table: at least two rows,
    /// equal lengths, angles finite and strictly increasing from exactly 0 to exactly 90, values
    /// finite and in [0, 1].
    pub fn new(angles_deg: Vec<f64>, rgb: Vec<[f64; 3]>) -> Result<Self> {
        Self::checked(angles_deg, rgb, true)
    }

    /// Reads a CSV file and parses it with [`FresnelTable::from_csv_str`]; errors name the file.
    /// Files above [`MAX_FRESNEL_CSV_BYTES`] are refused before reading.
    pub fn from_csv_file(path: &Path) -> Result<Self> {
        let text = crate::text::read_text_file(path, MAX_FRESNEL_CSV_BYTES, "Fresnel CSV")?;
        Self::from_csv_str(&text, &path.display().to_string())
    }

    /// Parses a CSV table: header `angle_deg,r,g,b` (RGB) or `angle_deg,<nm>,<nm>,…` (spectral,
    /// converted through the spectral path). Header names are read in any case and wavelengths
    /// may carry their unit (`380`, `380.0`, `380nm`, `380 nm`). A UTF-8 BOM, any line end (LF,
    /// CRLF, CR), the separators, quotes and decimal commas of [`crate::text`], a trailing
    /// separator, `#` comment lines, whitespace around cells and blank lines before the header or
    /// at the end are accepted; anything else that is off is an [`Error::Parse`] naming `source`
    /// and the 1-based line.
    pub fn from_csv_str(text: &str, source: &str) -> Result<Self> {
        csv::parse_table(text, source)
    }

    /// The default table (SPEC §3): exact unpolarised dielectric Fresnel for n(λ) = A + B/λ²,
    /// through the spectral path, at every whole degree 0..=90.
    pub fn dielectric(ior_a: f64, ior_b: f64) -> Result<Self> {
        check_ior(ior_a, ior_b)?;
        let angles_deg: Vec<f64> = (0..=90).map(f64::from).collect();
        let rgb = angles_deg
            .iter()
            .map(|&deg| {
                // cos(90°) in floating point is 6e-17, not 0; the grazing row is exactly F = 1.
                let cos_theta = if deg == 90.0 {
                    0.0
                } else {
                    deg.to_radians().cos()
                };
                let spectrum: [f64; GRID_LEN] = std::array::from_fn(|i| {
                    dielectric_reflectance(
                        cos_theta,
                        lacquer_ior(grid_wavelength_nm(i), ior_a, ior_b),
                    )
                });
                grid_reflectance_to_rgb(&spectrum)
            })
            .collect();
        Self::checked(angles_deg, rgb, false)
    }

    /// F(θ), linear interpolation between entries; θ in degrees, clamped to [0, 90] (NaN → 0).
    pub fn eval(&self, theta_deg: f64) -> [f64; 3] {
        let (k, t) = locate(&self.angles_deg, theta_deg);
        let (lo, hi) = (self.rgb[k], self.rgb[k + 1]);
        std::array::from_fn(|c| lerp(lo[c], hi[c], t))
    }

    /// The table's angles [degrees].
    pub fn angles_deg(&self) -> &[f64] {
        &self.angles_deg
    }

    /// The table's linear RGB reflectances, one per angle.
    pub fn rgb(&self) -> &[[f64; 3]] {
        &self.rgb
    }

    /// The table as an RGB CSV (header [`RGB_HEADER`]). Values use Rust's `{}` for f64, the
    /// shortest text that parses back to the same bits, so `from_csv_str(to_csv())` is exact.
    pub fn to_csv(&self) -> String {
        let mut csv = format!("{RGB_HEADER}\n");
        for (angle, c) in self.angles_deg.iter().zip(&self.rgb) {
            csv.push_str(&format!("{angle},{},{},{}\n", c[0], c[1], c[2]));
        }
        csv
    }

    /// The checks shared by every constructor: ≥ 2 rows, equal lengths, finite values, angles
    /// strictly increasing from exactly 0 to exactly 90; values in [0, 1] if `unit_range`.
    fn checked(angles_deg: Vec<f64>, rgb: Vec<[f64; 3]>, unit_range: bool) -> Result<Self> {
        let (n, last) = (angles_deg.len(), angles_deg.len().saturating_sub(1));
        if rgb.len() != n || n < 2 {
            let value = format!("{n} angles, {} rgb rows", rgb.len());
            let reason = "needs one rgb row per angle and at least two rows (0 and 90 degrees)";
            return Err(Error::invalid("fresnel table", value, reason));
        }
        let in_range = |v: &f64| v.is_finite() && (!unit_range || (0.0..=1.0).contains(v));
        if let Some(i) = rgb.iter().position(|c| !c.iter().all(in_range)) {
            let reason = if unit_range {
                "each channel is a reflectance and must be a finite value in [0, 1]"
            } else {
                "values must be finite"
            };
            return Err(Error::invalid(
                format!("fresnel table rgb[{i}]"),
                format!("{:?}", rgb[i]),
                reason,
            ));
        }
        if angles_deg[0] != 0.0 || angles_deg[last] != 90.0 {
            let value = format!("{} .. {}", angles_deg[0], angles_deg[last]);
            let reason = "the angles must start at exactly 0 and end at exactly 90 degrees";
            return Err(Error::invalid("fresnel table angles_deg", value, reason));
        }
        // Written as "not (a < b)" so that NaN is rejected too.
        let increasing = |i: &usize| angles_deg[i - 1] < angles_deg[*i];
        if let Some(i) = (1..n).find(|i| !increasing(i)) {
            let reason = "angles must be finite and strictly increasing";
            return Err(Error::invalid(
                format!("fresnel table angles_deg[{i}]"),
                angles_deg[i],
                reason,
            ));
        }
        Ok(FresnelTable { angles_deg, rgb })
    }
}

/// The IOR law's parameter ranges: A in [1, [`MAX_IOR_A`]] (A ≥ 1 keeps n ≥ 1: air → lacquer,
/// no total internal reflection) and B in [0, [`MAX_IOR_B`]] µm² (B ≥ 0 is normal dispersion).
pub(crate) fn check_ior(ior_a: f64, ior_b: f64) -> Result<()> {
    if !(ior_a.is_finite() && (1.0..=MAX_IOR_A).contains(&ior_a)) {
        let reason = format!(
            "must be a finite number in [1, {MAX_IOR_A}] (A >= 1: lacquer is denser than air; \
             real lacquers and glasses have A ≈ 1.4–1.9; default {DEFAULT_IOR_A})"
        );
        return Err(Error::invalid("ior_a", ior_a, reason));
    }
    if !(ior_b.is_finite() && (0.0..=MAX_IOR_B).contains(&ior_b)) {
        let reason = format!(
            "must be a finite number in [0, {MAX_IOR_B}] µm² (B >= 0: normal dispersion; real \
             lacquers and glasses have B ≤ 0.02 µm²; default {DEFAULT_IOR_B})"
        );
        return Err(Error::invalid("ior_b", ior_b, reason));
    }
    Ok(())
}

/// Unpolarised dielectric reflectance from air, F = (r_s² + r_p²)/2, exact; n = relative IOR.
///
/// Snell: sin²θt = sin²θi / n², with sin²θi = (1 - cos θi)(1 + cos θi) (no cancellation at
/// normal incidence). cos θi is clamped to [0, 1]. n must be positive; for n < 1 total internal
/// reflection gives 1. At grazing incidence r_s = r_p = -1 exactly, so F(0) = 1 exactly.
pub fn dielectric_reflectance(cos_theta_i: f64, n: f64) -> f64 {
    let cos_i = cos_theta_i.clamp(0.0, 1.0);
    let sin_t2 = (1.0 - cos_i) * (1.0 + cos_i) / (n * n);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    let r_s = (cos_i - n * cos_t) / (cos_i + n * cos_t);
    let r_p = (n * cos_i - cos_t) / (n * cos_i + cos_t);
    0.5 * (r_s * r_s + r_p * r_p)
}

/// n(λ) = A + B/λ², λ in µm.
pub fn lacquer_ior(wavelength_nm: f64, ior_a: f64, ior_b: f64) -> f64 {
    let lambda_um = wavelength_nm * 1e-3;
    ior_a + ior_b / (lambda_um * lambda_um)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_close(got: f64, want: f64, tolerance: f64, what: &str) {
        assert!((got - want).abs() < tolerance, "{what}: {got} vs {want}");
    }

    #[test]
    fn dielectric_normal_incidence_is_the_closed_form() {
        // ((n-1)/(n+1))² at cos = 1; the exact equations reduce to it, so only rounding (1e-15).
        for n in [1.0_f64, 1.33, 1.5, 1.51, 2.4] {
            let expected = ((n - 1.0) / (n + 1.0)).powi(2);
            assert_close(dielectric_reflectance(1.0, n), expected, 1e-15, "n");
        }
    }

    #[test]
    fn dielectric_grazing_incidence_is_one() {
        assert_eq!(dielectric_reflectance(0.0, 1.5), 1.0);
        // Continuity: for small c = cos θi, 1 - F ≈ 2c·(1/(n·cos θt) + n/cos θt) = 5.8c at n = 1.5.
        assert_close(
            dielectric_reflectance(1e-6, 1.5),
            1.0 - 5.8e-6,
            1e-7,
            "near grazing",
        );
    }

    #[test]
    fn dielectric_brewster_angle_has_no_p_reflection() {
        // At tan θB = n, r_p = 0 and θB + θt = 90°, so r_s = -sin(θB - θt) and F = sin²(θB - θt)/2.
        for n in [1.33, 1.5, 1.7] {
            let theta_b = f64::atan(n);
            let theta_t = (theta_b.sin() / n).asin();
            let expected = 0.5 * (theta_b - theta_t).sin().powi(2);
            assert_close(
                dielectric_reflectance(theta_b.cos(), n),
                expected,
                1e-14,
                "Brewster",
            );
        }
    }

    #[test]
    fn dielectric_matches_the_sine_and_tangent_forms() {
        // r_s = -sin(θi-θt)/sin(θi+θt), r_p = tan(θi-θt)/tan(θi+θt): Fresnel's angle forms, an
        // independent route to the same numbers (rounding: 1e-14).
        let n = 1.5;
        for deg in [10.0, 35.0, 50.0, 75.0, 89.0] {
            let ti: f64 = f64::to_radians(deg);
            let tt = (ti.sin() / n).asin();
            let rs = -(ti - tt).sin() / (ti + tt).sin();
            let rp = (ti - tt).tan() / (ti + tt).tan();
            let expected = 0.5 * (rs * rs + rp * rp);
            assert_close(
                dielectric_reflectance(ti.cos(), n),
                expected,
                1e-14,
                "angle form",
            );
        }
    }

    #[test]
    fn lacquer_ior_is_cauchy_in_micrometres() {
        // n(589 nm) = 1.5 + 0.0045 / 0.589² ≈ 1.51297 (SPEC: "n ≈ 1.51 at 589 nm").
        let n = lacquer_ior(589.0, 1.5, 0.0045);
        assert_close(n, 1.5 + 0.0045 / 0.346921, 1e-12, "n(589)");
        assert_close(n, 1.51297, 1e-5, "n(589)");
    }

    #[test]
    fn default_dielectric_table_is_grey_and_about_four_percent_face_on() {
        let table = FresnelTable::dielectric(1.5, 0.0045).unwrap();
        let expected_angles: Vec<f64> = (0..=90).map(f64::from).collect();
        assert_eq!(table.angles_deg(), expected_angles.as_slice());
        // Each channel is a weighted average of R(λ) between R(780 nm) and R(380 nm) (closed form
        // at normal incidence); the sRGB weights have small negative lobes, hence 2% slack.
        let r0 = |nm: f64| {
            let n = lacquer_ior(nm, 1.5, 0.0045);
            ((n - 1.0) / (n + 1.0)).powi(2)
        };
        let (lo, hi) = (r0(780.0) * 0.98, r0(380.0) * 1.02);
        let f0 = table.eval(0.0);
        for c in f0 {
            assert!(c > lo && c < hi, "{f0:?} not in [{lo}, {hi}]");
            // SPEC: ≈ ((1.51 - 1)/2.51)² = 0.0413; the ȳ-weighted n is ≈ 1.514, so 0.0413..0.043.
            assert!((0.0405..0.0435).contains(&c), "{f0:?}");
        }
        // Dispersion makes blue reflect slightly more, but the table is grey to within 5%.
        assert!(f0[2] > f0[0]);
        assert!((f0[2] - f0[0]) / f0[1] < 0.05, "{f0:?}");
        // Grazing: F = 1 for every λ, and flat 1 maps to exactly (1, 1, 1).
        assert_eq!(table.eval(90.0), [1.0; 3]);
    }

    #[test]
    fn dielectric_rejects_bad_ior() {
        for (a, b, field, range) in [
            (0.9, 0.0, "ior_a", "[1, 10]"),
            (f64::NAN, 0.0, "ior_a", "[1, 10]"),
            (10.5, 0.0, "ior_a", "[1, 10]"),
            (1e308, 0.0, "ior_a", "[1, 10]"),
            (1.5, -0.1, "ior_b", "[0, 1] µm²"),
            (1.5, f64::INFINITY, "ior_b", "[0, 1] µm²"),
            (1.5, 1.5, "ior_b", "[0, 1] µm²"),
            (1.5, 1e308, "ior_b", "[0, 1] µm²"),
        ] {
            match FresnelTable::dielectric(a, b) {
                Err(Error::InvalidParameter {
                    field: f, reason, ..
                }) => {
                    assert_eq!(f, field);
                    assert!(reason.contains(range), "{reason}");
                }
                other => panic!("({a}, {b}): {other:?}"),
            }
        }
    }

    #[test]
    fn dielectric_table_is_finite_at_the_ior_bounds() {
        // The largest A and B still give a table of reflectances (n ≈ 17 at 380 nm), so the
        // bounds, not a NaN entry, are what refuses a larger value.
        for (a, b) in [(1.0, 0.0), (MAX_IOR_A, MAX_IOR_B), (1.0, MAX_IOR_B)] {
            let table = FresnelTable::dielectric(a, b).expect("the bounds are valid");
            assert!(
                table.rgb().iter().flatten().all(|c| c.is_finite()),
                "({a}, {b})"
            );
        }
    }

    #[test]
    fn eval_interpolates_linearly_and_clamps() {
        let table = FresnelTable::new(
            vec![0.0, 30.0, 90.0],
            vec![[0.0, 0.1, 0.2], [0.3, 0.4, 0.5], [1.0, 1.0, 1.0]],
        )
        .unwrap();
        // Midpoint of the first segment: (0.15, 0.25, 0.35) to rounding (1e-15).
        let mid = table.eval(15.0);
        for (got, want) in mid.into_iter().zip([0.15, 0.25, 0.35]) {
            assert_close(got, want, 1e-15, "midpoint");
        }
        assert_eq!(table.eval(30.0), [0.3, 0.4, 0.5]);
        assert_eq!(table.eval(-5.0), [0.0, 0.1, 0.2]);
        assert_eq!(table.eval(f64::NAN), [0.0, 0.1, 0.2]);
        assert_eq!(table.eval(120.0), [1.0; 3]);
        assert_eq!(table.eval(90.0), [1.0; 3]);
    }

    #[test]
    fn new_rejects_every_malformed_table() {
        let ok = [0.5; 3];
        #[rustfmt::skip]
        let cases: Vec<(Vec<f64>, Vec<[f64; 3]>)> = vec![
            (vec![0.0], vec![ok]),                               // one row
            (vec![0.0, 90.0], vec![ok]),                         // length mismatch
            (vec![1.0, 90.0], vec![ok, ok]),                     // first not 0
            (vec![0.0, 89.0], vec![ok, ok]),                     // last not 90
            (vec![0.0, 50.0, 40.0, 90.0], vec![ok, ok, ok, ok]), // not increasing
            (vec![0.0, 50.0, 50.0, 90.0], vec![ok, ok, ok, ok]), // repeated angle
            (vec![0.0, f64::NAN, 90.0], vec![ok, ok, ok]),       // NaN angle
            (vec![0.0, 90.0], vec![ok, [0.5, 1.5, 0.5]]),        // above 1
            (vec![0.0, 90.0], vec![[-0.1, 0.5, 0.5], ok]),       // below 0
            (vec![0.0, 90.0], vec![ok, [f64::NAN, 0.5, 0.5]]),   // NaN value
        ];
        for (angles, rgb) in cases {
            let shown = format!("{angles:?} {rgb:?}");
            assert!(
                matches!(
                    FresnelTable::new(angles, rgb),
                    Err(Error::InvalidParameter { .. })
                ),
                "{shown}"
            );
        }
    }
}
