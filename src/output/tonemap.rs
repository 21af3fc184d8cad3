//! The display transform of SPEC §1 for PNG output: radiance × 2^exposure_ev → tone curve →
//! sRGB transfer function → 8 bits, rounded to nearest. Pure scalar functions, one definition
//! each (the GPU never tone-maps: it hands linear radiance to `output/`). EXR output must not
//! pass through here.

use std::fmt;
use std::str::FromStr;

use crate::Error;

/// The tone curve applied per channel after exposure (SPEC §1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ToneCurve {
    /// Clamp to [0, 1]: highlights above 1 clip.
    None,
    /// x / (1 + x).
    Reinhard,
    /// Narkowicz 2015 fit of the ACES filmic curve, the default: it keeps lacquer highlights,
    /// hundreds of times the diffuse level, from blowing out (the paper's open problem).
    #[default]
    Aces,
}

impl ToneCurve {
    /// Every curve with its name as the CLI and material files spell it.
    pub const ALL: [(ToneCurve, &'static str); 3] = [
        (ToneCurve::None, "none"),
        (ToneCurve::Reinhard, "reinhard"),
        (ToneCurve::Aces, "aces"),
    ];

    /// The name `FromStr` accepts for this curve.
    pub fn name(self) -> &'static str {
        match self {
            ToneCurve::None => "none",
            ToneCurve::Reinhard => "reinhard",
            ToneCurve::Aces => "aces",
        }
    }
}

impl fmt::Display for ToneCurve {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ToneCurve {
    type Err = Error;

    /// "none", "reinhard" or "aces", ignoring ASCII case and surrounding spaces.
    fn from_str(s: &str) -> Result<Self, Error> {
        let wanted = s.trim();
        ToneCurve::ALL
            .iter()
            .find(|(_, name)| name.eq_ignore_ascii_case(wanted))
            .map(|(curve, _)| *curve)
            .ok_or_else(|| {
                Error::invalid(
                    "tone_curve",
                    format!("{s:?}"),
                    "valid tone curves are none (clamp to 1), reinhard (x/(1+x)) and aces \
                     (Narkowicz 2015 fit, the default)",
                )
            })
    }
}

/// Maps exposed linear radiance `x` to display-linear [0, 1] (SPEC §1).
///
/// - `none`: clamp to [0, 1];
/// - `reinhard`: x / (1 + x);
/// - `aces`: Narkowicz 2015, x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14), clamped to [0, 1]
///   (the fit exceeds 1 above x ≈ 7.24, the root of 0.08x² − 0.56x − 0.14, and tends to
///   2.51/2.43).
///
/// Negative and NaN inputs give 0 (no light); +∞ gives each curve's limit, 1.
pub fn tone_curve(curve: ToneCurve, x: f64) -> f64 {
    // `max` returns the non-NaN operand, so NaN becomes 0 here.
    let x = x.max(0.0);
    if x == f64::INFINITY {
        // Every formula below is ∞/∞ = NaN at infinity; all three tend to (at least) 1.
        return 1.0;
    }
    let mapped = match curve {
        ToneCurve::None => x,
        ToneCurve::Reinhard => x / (1.0 + x),
        // Above 7.24 the fit exceeds 1 and is clamped; answering 1 from 8 on gives the same
        // values and keeps x² from overflowing to ∞/∞ = NaN.
        ToneCurve::Aces if x >= 8.0 => 1.0,
        ToneCurve::Aces => (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14),
    };
    mapped.clamp(0.0, 1.0)
}

/// The sRGB transfer function (IEC 61966-2-1 OETF): 12.92·x for x ≤ 0.0031308, else
/// 1.055·x^(1/2.4) − 0.055. The standard includes the threshold in the linear segment.
/// Input is clamped to [0, 1] (NaN → 0): it is only defined for display-linear values.
pub fn srgb_encode(linear: f64) -> f64 {
    let x = if linear.is_nan() {
        0.0
    } else {
        linear.clamp(0.0, 1.0)
    };
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// How linear radiance becomes 8-bit PNG values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PngSettings {
    /// Exposure in stops: radiance is multiplied by 2^exposure_ev before the tone curve.
    pub exposure_ev: f32,
    pub tone_curve: ToneCurve,
}

impl Default for PngSettings {
    /// 0 EV (radiance as rendered) and the ACES curve.
    fn default() -> Self {
        PngSettings {
            exposure_ev: 0.0,
            tone_curve: ToneCurve::Aces,
        }
    }
}

impl PngSettings {
    /// Rejects a non-finite exposure, which would turn every pixel black or white.
    pub fn validate(&self) -> crate::Result<()> {
        if self.exposure_ev.is_finite() {
            Ok(())
        } else {
            Err(Error::invalid(
                "exposure_ev",
                self.exposure_ev,
                "exposure is a finite number of stops (e.g. -2 halves twice, 0 leaves radiance \
                 unchanged)",
            ))
        }
    }
}

/// radiance × 2^ev → curve → sRGB → round to nearest 8-bit. NaN or negative → 0.
///
/// Evaluated in f64: each step is non-decreasing in exact arithmetic, and in f64 its rounding
/// error (~1e-16) is far below the spacing of f32 inputs, so the result is non-decreasing in the
/// radiance — which [`Srgb8Encoder`] relies on. (In f32 the ACES quotient's rounding makes the
/// code step back by one near some thresholds, e.g. 29 → 28 around 0.0217475.)
pub fn to_srgb8(radiance: f32, settings: &PngSettings) -> u8 {
    let exposed = f64::from(radiance) * f64::from(settings.exposure_ev).exp2();
    let display = tone_curve(settings.tone_curve, exposed);
    let unit = srgb_encode(display);
    // srgb_encode returns [0, 1] (NaN-free), so the cast never saturates.
    (unit * 255.0).round() as u8
}

/// [`to_srgb8`] for fixed settings as 255 thresholds: the code of x is the number of thresholds
/// ≤ x, read from a table instead of computing a tone curve and a `powf` per channel, which
/// was most of `encode_png`'s time (BENCHMARKS.md, "PNG display transform"). Same bytes as
/// `to_srgb8`:
///
/// `to_srgb8` is non-decreasing in x, so the x with code ≥ k form a half-line starting at
/// threshold t_k, the smallest f32 with `to_srgb8 ≥ k`. Non-negative f32 order like their bit
/// patterns, so each t_k is a bisection over bits. To count the thresholds ≤ x quickly, the
/// positive floats are cut into buckets of 2^16 consecutive bit patterns (1/128 of an octave)
/// that know their first float's code; a bucket spans at most a couple of thresholds, so a step
/// or two from there finishes the count. Tests compare both on every float around every threshold
/// and on random floats; an ignored test compares every non-negative f32 for each curve. NaN,
/// negative, zero and infinite inputs go to `to_srgb8` itself.
#[derive(Clone, Debug)]
pub struct Srgb8Encoder {
    settings: PngSettings,
    /// t_1 … t_255, non-decreasing; +∞ when no finite input reaches the code.
    thresholds: [f32; 255],
    /// Code of the first float of each bucket (`bits >> BUCKET_SHIFT`) of the positive finite f32.
    bucket_code: Vec<u8>,
}

const BUCKET_SHIFT: u32 = 16;

impl Srgb8Encoder {
    pub fn new(settings: &PngSettings) -> Self {
        let code = |bits: u32| to_srgb8(f32::from_bits(bits), settings);
        let top = f32::MAX.to_bits();
        let mut thresholds = [f32::INFINITY; 255];
        for (threshold, k) in thresholds.iter_mut().zip(1u8..=255) {
            if code(top) < k {
                continue;
            }
            // code(lo) < k ≤ code(hi); code(0) = 0 < k.
            let (mut lo, mut hi) = (0u32, top);
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if code(mid) >= k {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            *threshold = f32::from_bits(hi);
        }
        let bucket_code = (0..=top >> BUCKET_SHIFT)
            .map(|bucket| {
                let first = f32::from_bits(bucket << BUCKET_SHIFT);
                // At most 255 thresholds, so the count fits.
                thresholds.partition_point(|&t| t <= first) as u8
            })
            .collect();
        Srgb8Encoder {
            settings: *settings,
            thresholds,
            bucket_code,
        }
    }

    /// `to_srgb8(radiance, settings)`.
    pub fn encode(&self, radiance: f32) -> u8 {
        if radiance > 0.0 && radiance.is_finite() {
            // Thresholds ≤ the bucket's first float are ≤ radiance too; count the rest in order.
            let mut code =
                usize::from(self.bucket_code[(radiance.to_bits() >> BUCKET_SHIFT) as usize]);
            while code < self.thresholds.len() && self.thresholds[code] <= radiance {
                code += 1;
            }
            code as u8
        } else {
            to_srgb8(radiance, &self.settings)
        }
    }
}

/// Rounds a [0, 1] value to the nearest of 256 levels (0.5 rounds up); out-of-range input clamps.
pub(crate) fn unit_to_u8(value: f32) -> u8 {
    // Clamped and NaN-free, so the cast never saturates or truncates silently.
    let unit = if value.is_nan() {
        0.0
    } else {
        value.clamp(0.0, 1.0)
    };
    (unit * 255.0).round() as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    /// sRGB decode (the EOTF), written independently of `srgb_encode` so rounding tests can pick
    /// radiance values whose 8-bit code is known by hand.
    fn srgb_decode(v: f64) -> f64 {
        if v <= 0.040_45 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    }

    fn settings(exposure_ev: f32, tone_curve: ToneCurve) -> PngSettings {
        PngSettings {
            exposure_ev,
            tone_curve,
        }
    }

    /// `actual` against a hand-computed value written to 9 digits (so 1e-9 of its own rounding).
    fn close(actual: f64, expected: f64) -> bool {
        (actual - expected).abs() < 2e-9
    }

    #[test]
    fn aces_matches_hand_computed_values() {
        // x = 1: (2.51 + 0.03) / (2.43 + 0.59 + 0.14) = 2.54 / 3.16 = 0.803797468…
        assert!(close(tone_curve(ToneCurve::Aces, 1.0), 0.803_797_468));
        // x = 0.5: 0.5·1.285 / (0.5·1.805 + 0.14) = 0.6425 / 1.0425 = 0.616306954…
        assert!(close(tone_curve(ToneCurve::Aces, 0.5), 0.616_306_954));
        // x = 0: 0 / 0.14.
        assert_eq!(tone_curve(ToneCurve::Aces, 0.0), 0.0);
        // x = 100: 25103 / 24359.14 = 1.0305… > 1, so the clamp must bite.
        assert_eq!(tone_curve(ToneCurve::Aces, 100.0), 1.0);
    }

    #[test]
    fn reinhard_and_none_match_their_closed_forms() {
        assert!(close(tone_curve(ToneCurve::Reinhard, 1.0), 0.5));
        assert!(close(tone_curve(ToneCurve::Reinhard, 3.0), 0.75));
        assert_eq!(tone_curve(ToneCurve::None, 0.25), 0.25);
        assert_eq!(tone_curve(ToneCurve::None, 7.0), 1.0);
    }

    /// Settings that exercise every curve, both signs of exposure, and exposures that overflow or
    /// underflow the product.
    fn encoder_settings() -> Vec<PngSettings> {
        let mut all = Vec::new();
        for tone_curve in [ToneCurve::Aces, ToneCurve::Reinhard, ToneCurve::None] {
            for exposure_ev in [0.0, 1.3, -3.0, 140.0, -160.0] {
                all.push(PngSettings {
                    exposure_ev,
                    tone_curve,
                });
            }
        }
        all
    }

    #[test]
    fn srgb8_encoder_equals_to_srgb8_around_every_threshold_and_on_random_floats() {
        for settings in encoder_settings() {
            let encoder = Srgb8Encoder::new(&settings);
            let check = |x: f32| {
                assert_eq!(
                    encoder.encode(x),
                    to_srgb8(x, &settings),
                    "{settings:?} at {x:e} ({:#x})",
                    x.to_bits()
                );
            };
            // Every float within 4096 ulps of every threshold: where a code changes.
            for t in encoder.thresholds.iter().filter(|t| t.is_finite()) {
                let bits = t.to_bits();
                for b in
                    bits.saturating_sub(4096)..=bits.saturating_add(4096).min(f32::MAX.to_bits())
                {
                    check(f32::from_bits(b));
                }
            }
            // Random bit patterns over every exponent (a fixed xorshift), and the special values.
            let mut state = 0x2545_f491_4f6c_dd1du64;
            for _ in 0..200_000 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                check(f32::from_bits((state >> 32) as u32));
            }
            for x in [
                0.0,
                -0.0,
                f32::NAN,
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::MIN_POSITIVE,
                1e-45,
                f32::MAX,
                -1.0,
            ] {
                check(x);
            }
        }
    }

    /// Every non-negative finite f32 (2^31 of them) for each curve at 0 EV; too slow for every
    /// run (its time is in BENCHMARKS.md, "PNG display transform"):
    /// `cargo test --release --lib srgb8_encoder_equals_to_srgb8_on_every_float -- --ignored`.
    #[test]
    #[ignore]
    fn srgb8_encoder_equals_to_srgb8_on_every_float() {
        use rayon::prelude::*;
        for (tone_curve, _) in ToneCurve::ALL {
            let settings = settings(0.0, tone_curve);
            let encoder = Srgb8Encoder::new(&settings);
            let mismatches: u64 = (0..=f32::MAX.to_bits() >> 16)
                .into_par_iter()
                .map(|high| {
                    (0..1u32 << 16)
                        .filter(|low| {
                            let x = f32::from_bits(high << 16 | low);
                            encoder.encode(x) != to_srgb8(x, &settings)
                        })
                        .count() as u64
                })
                .sum();
            assert_eq!(mismatches, 0, "{tone_curve}");
        }
    }

    #[test]
    fn curves_are_one_for_every_huge_finite_input() {
        for curve in [ToneCurve::None, ToneCurve::Reinhard, ToneCurve::Aces] {
            for x in [1e19, 1e30, f64::from(f32::MAX), f64::MAX] {
                assert_eq!(tone_curve(curve, x), 1.0, "{curve:?} at {x}");
            }
        }
        assert_eq!(tone_curve(ToneCurve::Aces, 8.0), 1.0);
        // The formula itself, just below the shortcut, is already clamped to 1.
        assert_eq!(tone_curve(ToneCurve::Aces, 7.99), 1.0);
    }

    #[test]
    fn curves_send_negative_and_nan_to_zero_and_infinity_to_one() {
        for (curve, _) in ToneCurve::ALL {
            assert_eq!(tone_curve(curve, -2.0), 0.0, "{curve}");
            assert_eq!(tone_curve(curve, f64::NAN), 0.0, "{curve}");
            assert_eq!(tone_curve(curve, f64::INFINITY), 1.0, "{curve}");
        }
    }

    #[test]
    fn srgb_encode_matches_iec_61966_2_1() {
        // Threshold is in the linear segment: 12.92 · 0.0031308 = 0.040449936.
        assert!(close(srgb_encode(0.003_130_8), 0.040_449_936));
        // 1.055 · 0.5^(1/2.4) − 0.055 = 1.055 · 0.7491535… − 0.055 = 0.7353569…
        assert!(close(srgb_encode(0.5), 0.735_356_983));
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!(close(srgb_encode(1.0), 1.0));
        assert_eq!(srgb_encode(-1.0), 0.0);
        assert_eq!(srgb_encode(f64::NAN), 0.0);
    }

    #[test]
    fn to_srgb8_rounds_to_nearest_code() {
        // With no curve and 0 EV, radiance = decode((k + f)/255) must give k for f = 0.4 and
        // k + 1 for f = 0.6: 0.1 of a code is far outside f32 error, so no tolerance is needed.
        let linear = settings(0.0, ToneCurve::None);
        for k in [0u8, 1, 10, 57, 128, 200, 254] {
            let below = srgb_decode((k as f64 + 0.4) / 255.0) as f32;
            let above = srgb_decode((k as f64 + 0.6) / 255.0) as f32;
            assert_eq!(to_srgb8(below, &linear), k, "k + 0.4 → k");
            assert_eq!(to_srgb8(above, &linear), k + 1, "k + 0.6 → k + 1");
        }
        // 0.5 linear → 0.7353569 · 255 = 187.516 → 188 (truncation would give 187).
        assert_eq!(to_srgb8(0.5, &linear), 188);
        assert_eq!(to_srgb8(1.0, &linear), 255);
        assert_eq!(to_srgb8(1000.0, &linear), 255);
    }

    #[test]
    fn to_srgb8_sends_nan_and_negative_to_zero() {
        for (curve, _) in ToneCurve::ALL {
            assert_eq!(to_srgb8(f32::NAN, &settings(0.0, curve)), 0);
            assert_eq!(to_srgb8(-5.0, &settings(0.0, curve)), 0);
            assert_eq!(to_srgb8(f32::INFINITY, &settings(0.0, curve)), 255);
        }
    }

    #[test]
    fn exposure_multiplies_radiance_by_two_to_the_ev() {
        // +2 EV on 0.125 is 0.5 → 188 (see above); −1 EV on 1.0 is 0.5 too.
        assert_eq!(to_srgb8(0.125, &settings(2.0, ToneCurve::None)), 188);
        assert_eq!(to_srgb8(1.0, &settings(-1.0, ToneCurve::None)), 188);
        // Reinhard after +1 EV on 0.5: x = 1 → 0.5 display-linear → 188.
        assert_eq!(to_srgb8(0.5, &settings(1.0, ToneCurve::Reinhard)), 188);
        // ACES at 0 EV on 1.0: 0.8037975 → sRGB 1.055·0.8037975^(1/2.4) − 0.055 = 0.90820… →
        // 231.59 → 232.
        assert_eq!(to_srgb8(1.0, &PngSettings::default()), 232);
    }

    #[test]
    fn default_settings_are_zero_ev_and_aces() {
        assert_eq!(PngSettings::default(), settings(0.0, ToneCurve::Aces));
        assert_eq!(ToneCurve::default(), ToneCurve::Aces);
    }

    #[test]
    fn non_finite_exposure_is_rejected() {
        assert!(settings(f32::NAN, ToneCurve::Aces).validate().is_err());
        assert!(settings(f32::INFINITY, ToneCurve::Aces).validate().is_err());
        assert!(settings(-3.5, ToneCurve::Aces).validate().is_ok());
    }

    #[test]
    fn tone_curve_names_parse_and_errors_list_the_valid_names() {
        assert_eq!("none".parse::<ToneCurve>().unwrap(), ToneCurve::None);
        assert_eq!(
            "Reinhard".parse::<ToneCurve>().unwrap(),
            ToneCurve::Reinhard
        );
        assert_eq!(" ACES ".parse::<ToneCurve>().unwrap(), ToneCurve::Aces);
        let message = "filmic".parse::<ToneCurve>().unwrap_err().to_string();
        for name in ["filmic", "none", "reinhard", "aces"] {
            assert!(message.contains(name), "{message}");
        }
        for (curve, name) in ToneCurve::ALL {
            assert_eq!(curve.to_string(), name);
        }
    }
}
