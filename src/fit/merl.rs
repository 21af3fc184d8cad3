//! MERL isotropic BRDF files (`.binary`, Matusik et al. 2003): a header of three int32 (90, 90,
//! 180) and three blocks (R, G, B) of 90·90·180 float64, little-endian, indexed by the
//! Rusinkiewicz angles (θ_h, θ_d, φ_d) with the standard scale factors (1, 1.15, 1.66)/1500.
//!
//! Owns the layout, the index ↔ direction mapping of MERL's reference reader (BRDFRead.cpp) and
//! both directions of conversion. Values are f_r [1/sr]; negative entries mean "not measured"
//! and are skipped, as are NaN, infinite and overflowing (π·f_r not finite) ones. Index → angles
//! uses each bin's lower edge, θ_h = (i/90)²·90°, θ_d = j°, φ_d = k°: the inverse of the
//! reference reader's index functions (which floor).
//!
//! MERL assumes reciprocity (φ_d covers only [0°, 360°/2)); shikki's diffuse term is not
//! reciprocal (SPEC §2), so a file written from the model holds f_r with `in` = L (MERL's light)
//! and `out` = V, and reading assigns them the same way: the round trip is exact.

use std::f64::consts::FRAC_PI_2;
use std::path::Path;

use glam::DVec3;

use super::data::{Measurement, Measurements, Sample};
use crate::{Error, Result};

/// (θ_h, θ_d, φ_d) resolutions.
pub const MERL_DIMS: [usize; 3] = [90, 90, 180];
/// f_r = stored value × scale, per channel (R, G, B).
pub const MERL_SCALE: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];
/// Entries per channel.
pub const MERL_ENTRIES: usize = MERL_DIMS[0] * MERL_DIMS[1] * MERL_DIMS[2];
/// The size of a MERL file: header + three float64 blocks.
pub const MERL_FILE_BYTES: usize = 12 + 3 * MERL_ENTRIES * 8;
/// Every this many φ_d bins one is read for the fit: φ_d matters little for an isotropic lobe,
/// and 18 of 180 keep 145 800 of the 1 458 000 entries, so the fit stays fast.
pub const MERL_PHI_D_STRIDE: usize = 10;

/// (L, V) of entry (θ_h index i, θ_d index j, φ_d index k), N = +Z, φ_h = 0.
pub fn merl_directions(i: usize, j: usize, k: usize) -> (DVec3, DVec3) {
    let ratio = i as f64 / MERL_DIMS[0] as f64;
    let theta_h = ratio * ratio * FRAC_PI_2;
    let theta_d = j as f64 / MERL_DIMS[1] as f64 * FRAC_PI_2;
    // 180 bins over [0°, 180°): reciprocity folds φ_d and φ_d + 180° together.
    let phi_d = k as f64 / MERL_DIMS[2] as f64 * std::f64::consts::PI;
    // The difference vector in the half-vector frame; `out` is its mirror about H (x, y negated).
    let (st, ct) = theta_d.sin_cos();
    let (sp, cp) = phi_d.sin_cos();
    let diff = DVec3::new(st * cp, st * sp, ct);
    // Rotate the half frame by θ_h about the binormal (+Y): MERL's inverse of
    // rotate_vector(in, binormal, −θ_h).
    let (sh, ch) = theta_h.sin_cos();
    let rotate = |d: DVec3| DVec3::new(d.x * ch + d.z * sh, d.y, -d.x * sh + d.z * ch);
    (rotate(diff), rotate(DVec3::new(-diff.x, -diff.y, diff.z)))
}

/// A MERL file from an f_r evaluator (L, V) → RGB [1/sr]; directions below the horizon are
/// written as −1 (not measured).
pub fn merl_bytes(mut brdf: impl FnMut(DVec3, DVec3) -> [f64; 3]) -> Vec<u8> {
    let mut values = vec![[-1.0; 3]; MERL_ENTRIES];
    for i in 0..MERL_DIMS[0] {
        for j in 0..MERL_DIMS[1] {
            for k in 0..MERL_DIMS[2] {
                let (l, v) = merl_directions(i, j, k);
                if l.z > 0.0 && v.z > 0.0 {
                    let f = brdf(l, v);
                    values[index(i, j, k)] = std::array::from_fn(|c| f[c] / MERL_SCALE[c]);
                }
            }
        }
    }
    let mut bytes = Vec::with_capacity(MERL_FILE_BYTES);
    for dim in MERL_DIMS {
        bytes.extend_from_slice(&(dim as i32).to_le_bytes());
    }
    for c in 0..3 {
        for v in &values {
            bytes.extend_from_slice(&v[c].to_le_bytes());
        }
    }
    bytes
}

/// Reads a MERL file as one sample (`r` = 1), every [`MERL_PHI_D_STRIDE`]-th φ_d bin.
/// A file whose length is not [`MERL_FILE_BYTES`] is refused before it is read.
pub fn read_merl(path: &Path) -> Result<Measurements> {
    let read_error = |source| Error::Read {
        path: path.to_path_buf(),
        source,
    };
    let length = std::fs::metadata(path).map_err(read_error)?.len();
    if length != MERL_FILE_BYTES as u64 {
        // The header, when there is one, says more than the length: read just it.
        let mut head = Vec::with_capacity(12);
        std::io::Read::read_to_end(
            &mut std::io::Read::take(std::fs::File::open(path).map_err(read_error)?, 12),
            &mut head,
        )
        .map_err(read_error)?;
        let source = path.display().to_string();
        check_merl_header(&head, &source)?;
        return Err(wrong_merl_length(length, &source));
    }
    let bytes = std::fs::read(path).map_err(read_error)?;
    parse_merl(&bytes, &path.display().to_string(), MERL_PHI_D_STRIDE)
}

/// Parses MERL bytes into measurements (reflectance factor π·f_r), keeping every
/// `phi_d_stride`-th φ_d bin and skipping entries that are not measured or below the horizon.
pub fn parse_merl(bytes: &[u8], source: &str, phi_d_stride: usize) -> Result<Measurements> {
    check_merl_header(bytes, source)?;
    if bytes.len() != MERL_FILE_BYTES {
        return Err(wrong_merl_length(bytes.len() as u64, source));
    }
    let value = |c: usize, at: usize| {
        let start = 12 + (c * MERL_ENTRIES + at) * 8;
        let mut raw = [0u8; 8];
        raw.copy_from_slice(&bytes[start..start + 8]);
        f64::from_le_bytes(raw)
    };
    let mut rows = Vec::new();
    for i in 0..MERL_DIMS[0] {
        for j in 0..MERL_DIMS[1] {
            for k in (0..MERL_DIMS[2]).step_by(phi_d_stride.max(1)) {
                let (light, view) = merl_directions(i, j, k);
                let at = index(i, j, k);
                let stored = [value(0, at), value(1, at), value(2, at)];
                let reflectance: [f64; 3] =
                    std::array::from_fn(|c| std::f64::consts::PI * stored[c] * MERL_SCALE[c]);
                // A value near f64::MAX overflows π·f_r: as unusable as NaN, so not measured.
                let measured = stored.iter().all(|v| v.is_finite() && *v >= 0.0)
                    && reflectance.iter().all(|v| v.is_finite());
                if !measured || light.z <= 0.0 || view.z <= 0.0 {
                    continue;
                }
                rows.push(Measurement {
                    sample: 0,
                    light,
                    view,
                    reflectance,
                    line: 0,
                });
            }
        }
    }
    if rows.is_empty() {
        return Err(Error::invalid(
            format!("MERL file {source}"),
            "no measured entry",
            format!(
                "none of the {} entries read ({}, above the horizon) holds a measured value: \
                 each is negative (MERL's \"not measured\"), NaN or infinite; check that this is \
                 the BRDF you meant to fit",
                MERL_ENTRIES / phi_d_stride.max(1),
                match phi_d_stride {
                    0 | 1 => "every φ_d bin".to_string(),
                    n => format!("every {n}th φ_d bin"),
                }
            ),
        ));
    }
    Ok(Measurements {
        source: source.to_string(),
        samples: vec![Sample {
            name: "merl".into(),
            lacquer_ratio: 1.0,
        }],
        rows,
        notes: Vec::new(),
    })
}

/// The three int32 dimensions, if the bytes are long enough to have them, must be 90, 90, 180.
fn check_merl_header(bytes: &[u8], source: &str) -> Result<()> {
    let header: Vec<i32> = bytes
        .chunks_exact(4)
        .take(3)
        .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let expected_dims = MERL_DIMS.map(|d| d as i32);
    if header.len() == 3 && header != expected_dims {
        return Err(Error::invalid(
            format!("MERL file {source}"),
            format!("header {} × {} × {}", header[0], header[1], header[2]),
            "an isotropic MERL BRDF has the header 90 × 90 × 180 (θ_h, θ_d, φ_d); this file is \
             another kind of data",
        ));
    }
    Ok(())
}

fn wrong_merl_length(length: u64, source: &str) -> Error {
    Error::invalid(
        format!("MERL file {source}"),
        format!("{length} bytes"),
        format!(
            "a MERL BRDF has exactly {MERL_FILE_BYTES} bytes (a 12-byte header, then R, G \
             and B blocks of {MERL_ENTRIES} float64); the file is truncated or not a MERL \
             BRDF"
        ),
    )
}

/// MERL's flat index: φ_d fastest, then θ_d, then θ_h.
fn index(i: usize, j: usize, k: usize) -> usize {
    k + MERL_DIMS[2] * (j + MERL_DIMS[1] * i)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// MERL's reference std_coords_to_half_diff_coords: (L, V) → (θ_h, θ_d, φ_d).
    fn half_diff(l: DVec3, v: DVec3) -> (f64, f64, f64) {
        let h = (l + v).normalize();
        let theta_h = h.z.acos();
        let phi_h = h.y.atan2(h.x);
        // rotate_vector(in, normal, −φ_h), then rotate_vector(·, binormal, −θ_h).
        let (s, c) = (-phi_h).sin_cos();
        let t = DVec3::new(l.x * c - l.y * s, l.x * s + l.y * c, l.z);
        let (s, c) = (-theta_h).sin_cos();
        let d = DVec3::new(t.x * c + t.z * s, t.y, -t.x * s + t.z * c);
        (theta_h, d.z.acos(), d.y.atan2(d.x))
    }

    #[test]
    fn directions_map_back_to_their_bins() {
        // The reference reader's index functions applied to our directions give i, j, k back.
        for (i, j, k) in [
            (0, 0, 0),
            (1, 30, 45),
            (45, 10, 90),
            (80, 60, 179),
            (89, 89, 1),
        ] {
            let (l, v) = merl_directions(i, j, k);
            assert!((l.length() - 1.0).abs() < 1e-12 && (v.length() - 1.0).abs() < 1e-12);
            let (th, td, mut pd) = half_diff(l, v);
            if pd < 0.0 {
                pd += std::f64::consts::PI;
            }
            // Lower-edge sampling: add half a bin before flooring, as rounding may land 1 ulp low.
            let ti = (90.0 * (th / FRAC_PI_2).sqrt() + 0.5).floor() as usize;
            let tj = (td / FRAC_PI_2 * 90.0 + 0.5).floor() as usize;
            let tk = (pd / std::f64::consts::PI * 180.0 + 0.5).floor() as usize % 180;
            if i == 0 {
                // θ_h = 0: φ_d is measured from an arbitrary plane; only θ_d is defined.
                assert_eq!((ti, tj), (0, j));
            } else {
                assert_eq!((ti, tj, tk), (i, j, k));
            }
        }
    }

    #[test]
    fn half_vector_is_at_theta_h() {
        // H = normalize(L + V) = (sin θ_h, 0, cos θ_h) by construction; θ_h(45) = (1/2)²·90°.
        let (l, v) = merl_directions(45, 20, 33);
        let h = (l + v).normalize();
        let expected = (22.5f64).to_radians();
        assert!((h.z.acos() - expected).abs() < 1e-12 && h.y.abs() < 1e-12);
    }

    /// A file whose every entry is "not measured" said `0 rows, all grazing … within 87°`.
    #[test]
    fn a_file_with_no_measured_entry_says_so() {
        let bytes = merl_bytes(|_, _| [-1.0; 3]);
        let err = parse_merl(&bytes, "x.binary", MERL_PHI_D_STRIDE)
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with(
                "invalid MERL file x.binary = no measured entry: none of the 145800 entries read \
                 (every 10th φ_d bin, above the horizon) holds a measured value"
            ),
            "{err}"
        );
    }

    #[test]
    fn wrong_size_and_header_are_errors() {
        let err = parse_merl(&[0u8; 100], "x.binary", 1)
            .unwrap_err()
            .to_string();
        assert!(err.contains("header 0 × 0 × 0"), "{err}");
        let mut bytes = Vec::new();
        for d in MERL_DIMS {
            bytes.extend_from_slice(&(d as i32).to_le_bytes());
        }
        bytes.extend_from_slice(&[0u8; 80]);
        let err = parse_merl(&bytes, "x.binary", 1).unwrap_err().to_string();
        assert_eq!(
            err,
            format!(
                "invalid MERL file x.binary = 92 bytes: a MERL BRDF has exactly 34992012 bytes \
                 (a 12-byte header, then R, G and B blocks of 1458000 float64); the file is \
                 truncated or not a MERL BRDF"
            )
        );
    }
}
