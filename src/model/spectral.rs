//! The "spectral path" of SPEC §3: a reflectance spectrum → linear sRGB, through the CIE 1931 2°
//! observer under D65 (tables in [`super::cie`]), normalised so that a spectrally flat reflectance
//! of 1 is exactly RGB (1, 1, 1).
//!
//! Owns only the conversion and the linear-interpolation helpers the Fresnel table shares. It does
//! not read files or validate user input: the CSV reader in [`super::fresnel`] rejects malformed
//! spectra before they get here. The result is not clamped (SPEC §3 does not say to clamp):
//! a saturated spectrum can give channels slightly outside [0, 1].

use super::cie::{
    CIE1931_X_BAR, CIE1931_Y_BAR, CIE1931_Z_BAR, D65_SPD, GRID_LEN, GRID_START_NM, GRID_STEP_NM,
};

/// XYZ → linear sRGB, IEC 61966-2-1 (the 4-digit matrix SPEC §3 prescribes, rows R, G, B).
pub const SRGB_FROM_XYZ: [[f64; 3]; 3] = [
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
];

/// Rec. 709 luminance of linear RGB (the Y row of the sRGB matrix).
pub fn luminance(rgb: [f64; 3]) -> f64 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// The wavelength [nm] of grid sample `i` (380 + 5·i).
pub fn grid_wavelength_nm(i: usize) -> f64 {
    GRID_START_NM + GRID_STEP_NM * i as f64
}

/// Resample (wavelengths_nm, reflectance) linearly to 380..=780 step 5 and convert to linear sRGB:
/// XYZ = Σ R·S·cmf / Σ S·ȳ (CIE 1931 2°, D65), RGB = M·XYZ (IEC 61966-2-1 matrix in SPEC),
/// then divide each channel by the RGB of a flat reflectance of 1 (so flat 1 → exactly (1,1,1)).
///
/// Preconditions (the CSV reader guarantees them): `wavelengths_nm` strictly increasing and as
/// long as `reflectance`, covering 380–780 nm. Outside the given range the end values are held,
/// extra entries of the longer slice are ignored, and an empty spectrum gives (0, 0, 0).
pub fn reflectance_to_rgb(wavelengths_nm: &[f64], reflectance: &[f64]) -> [f64; 3] {
    let len = wavelengths_nm.len().min(reflectance.len());
    if len == 0 {
        return [0.0; 3];
    }
    let (xs, ys) = (&wavelengths_nm[..len], &reflectance[..len]);
    let mut grid = [0.0; GRID_LEN];
    for (i, sample) in grid.iter_mut().enumerate() {
        let (k, t) = locate(xs, grid_wavelength_nm(i));
        *sample = if len == 1 {
            ys[0]
        } else {
            lerp(ys[k], ys[k + 1], t)
        };
    }
    grid_reflectance_to_rgb(&grid)
}

/// The same for a spectrum already on the 81-sample 380..=780/5 grid.
pub fn grid_reflectance_to_rgb(reflectance: &[f64; GRID_LEN]) -> [f64; 3] {
    let rgb = srgb_unnormalised(&grid_reflectance_to_xyz(reflectance));
    let white = srgb_unnormalised(&grid_reflectance_to_xyz(&[1.0; GRID_LEN]));
    // x / x is exactly 1 in IEEE arithmetic, and the flat spectrum goes through the same sums in
    // the same order, so flat 1 maps to exactly (1, 1, 1).
    [rgb[0] / white[0], rgb[1] / white[1], rgb[2] / white[2]]
}

/// CIE XYZ of a reflectance on the 5 nm grid under D65: Σ R·S·cmf / Σ S·ȳ (so Y of white is 1).
pub fn grid_reflectance_to_xyz(reflectance: &[f64; GRID_LEN]) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    let mut norm = 0.0;
    for i in 0..GRID_LEN {
        let rs = reflectance[i] * D65_SPD[i];
        xyz[0] += rs * CIE1931_X_BAR[i];
        xyz[1] += rs * CIE1931_Y_BAR[i];
        xyz[2] += rs * CIE1931_Z_BAR[i];
        norm += D65_SPD[i] * CIE1931_Y_BAR[i];
    }
    xyz.map(|c| c / norm)
}

/// M·XYZ with the IEC 61966-2-1 matrix, before the flat-white normalisation.
pub fn srgb_unnormalised(xyz: &[f64; 3]) -> [f64; 3] {
    SRGB_FROM_XYZ.map(|row| row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2])
}

/// The segment of the strictly increasing `xs` that holds `x`: (k, t) with
/// x = xs[k] + t·(xs[k+1] − xs[k]) and t in [0, 1]. Outside the range x is clamped to the nearest
/// end (t = 0 or 1); NaN is treated as the first end. With fewer than two entries it gives (0, 0).
pub(crate) fn locate(xs: &[f64], x: f64) -> (usize, f64) {
    let n = xs.len();
    if n < 2 || x.is_nan() || x <= xs[0] {
        return (0, 0.0);
    }
    if x >= xs[n - 1] {
        return (n - 2, 1.0);
    }
    // First index whose abscissa exceeds x; in 1..n because xs[0] < x < xs[n-1].
    let upper = xs.partition_point(|&a| a <= x);
    let k = upper - 1;
    (k, (x - xs[k]) / (xs[k + 1] - xs[k]))
}

/// Linear interpolation written as v0 + t·(v1 - v0), so equal end values give that value exactly
/// (a flat spectrum stays flat), with t = 1 returning v1 exactly (the table's last entry).
pub(crate) fn lerp(v0: f64, v1: f64, t: f64) -> f64 {
    if t >= 1.0 {
        v1
    } else {
        v0 + t * (v1 - v0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_reflectance_of_one_is_exactly_white() {
        // Exact by construction (x / x), on the grid and through resampling from any grid.
        assert_eq!(grid_reflectance_to_rgb(&[1.0; GRID_LEN]), [1.0, 1.0, 1.0]);
        assert_eq!(reflectance_to_rgb(&[300.0, 900.0], &[1.0, 1.0]), [1.0; 3]);
        let fine: Vec<f64> = (0..=400).map(|i| 380.0 + i as f64).collect();
        assert_eq!(reflectance_to_rgb(&fine, &vec![1.0; fine.len()]), [1.0; 3]);
    }

    #[test]
    fn flat_reflectance_scales_linearly() {
        // The path is linear in R: flat 0.25 is 0.25 · white, to rounding (1e-15).
        let rgb = grid_reflectance_to_rgb(&[0.25; GRID_LEN]);
        for c in rgb {
            assert!((c - 0.25).abs() < 1e-15, "{rgb:?}");
        }
    }

    #[test]
    fn d65_white_point_from_the_5nm_tables() {
        // CIE D65 white (0.95047, 1, 1.08883) is defined with 1 nm sums; the 5 nm sums of the same
        // tables differ by about 1e-4, so 1e-3 is a safe bound that still catches a wrong row.
        let xyz = grid_reflectance_to_xyz(&[1.0; GRID_LEN]);
        let expected = [0.95047, 1.0, 1.08883];
        for (got, want) in xyz.iter().zip(expected) {
            assert!((got - want).abs() < 1e-3, "{xyz:?}");
        }
        assert!(
            (xyz[1] - 1.0).abs() < 1e-15,
            "Y of white is 1 by the normalisation"
        );
        // The 4-digit IEC matrix maps D65 to (1, 1, 1) to about 2e-4; 1e-3 as above.
        for c in srgb_unnormalised(&xyz) {
            assert!((c - 1.0).abs() < 1e-3, "{c}");
        }
    }

    #[test]
    fn cie_tables_hold_the_published_anchor_values() {
        // CIE 015: ȳ(555) = 1, D65(560) = 100 (the normalisation point), x̄(600) = 1.0622,
        // z̄(450) = 1.77211; D65(380) = 49.9755, D65(780) = 63.3828.
        let at = |nm: f64| ((nm - GRID_START_NM) / GRID_STEP_NM) as usize;
        assert_eq!(CIE1931_Y_BAR[at(555.0)], 1.0);
        assert_eq!(D65_SPD[at(560.0)], 100.0);
        assert_eq!(CIE1931_X_BAR[at(600.0)], 1.0622);
        assert_eq!(CIE1931_Z_BAR[at(450.0)], 1.77211);
        assert_eq!(D65_SPD[0], 49.9755);
        assert_eq!(D65_SPD[GRID_LEN - 1], 63.3828);
        assert_eq!(grid_wavelength_nm(GRID_LEN - 1), 780.0);
    }

    #[test]
    fn resampling_a_linear_spectrum_is_exact() {
        // Two samples at 380 and 780 describe the line R = (λ - 380)/400; its linear resample must
        // equal the line sampled directly on the grid (rounding only: 1e-14).
        let line: [f64; GRID_LEN] =
            std::array::from_fn(|i| (grid_wavelength_nm(i) - 380.0) / 400.0);
        let direct = grid_reflectance_to_rgb(&line);
        let resampled = reflectance_to_rgb(&[380.0, 780.0], &[0.0, 1.0]);
        for (a, b) in direct.iter().zip(resampled) {
            assert!((a - b).abs() < 1e-14, "{direct:?} vs {resampled:?}");
        }
    }

    #[test]
    fn blue_and_red_spectra_land_in_the_right_channels() {
        // A band 430–470 nm is blue; a band 610–680 nm is red (qualitative, no tolerance needed).
        let band = |lo: f64, hi: f64| -> [f64; GRID_LEN] {
            std::array::from_fn(|i| {
                let nm = grid_wavelength_nm(i);
                if (lo..=hi).contains(&nm) {
                    1.0
                } else {
                    0.0
                }
            })
        };
        let blue = grid_reflectance_to_rgb(&band(430.0, 470.0));
        assert!(blue[2] > blue[1] && blue[2] > blue[0], "{blue:?}");
        let red = grid_reflectance_to_rgb(&band(610.0, 680.0));
        assert!(red[0] > red[1] && red[0] > red[2], "{red:?}");
    }

    #[test]
    fn locate_and_lerp_follow_the_segments() {
        let xs = [0.0, 10.0, 40.0, 90.0];
        assert_eq!(locate(&xs, -5.0), (0, 0.0));
        assert_eq!(locate(&xs, 0.0), (0, 0.0));
        assert_eq!(locate(&xs, 10.0), (1, 0.0));
        assert_eq!(locate(&xs, 25.0), (1, 0.5));
        assert_eq!(locate(&xs, 90.0), (2, 1.0));
        assert_eq!(locate(&xs, 200.0), (2, 1.0));
        assert_eq!(locate(&xs, f64::NAN), (0, 0.0));
        assert_eq!(lerp(0.3, 0.3, 0.7), 0.3);
        assert_eq!(lerp(0.1, 0.7, 1.0), 0.7);
        assert_eq!(lerp(2.0, 4.0, 0.25), 2.5);
    }
}
