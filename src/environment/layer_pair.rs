//! How the `brdf` model's layer texels are stored: two horizontally adjacent texels of a face
//! (with its apron) in one RGBA32UI texel, each channel in `LAYER_CODE_BITS` bits, so that a
//! bilinear lookup reads two texels, one a row, instead of four. On lavapipe a lookup's cost is
//! its gathers, not their bytes (BENCHMARKS.md, "Two layer texels in one").
//!
//! A channel's code is its f32 less the sign and the `31 − LAYER_CODE_BITS` lowest mantissa bits,
//! rounded to nearest even: the same exponent range, 13 mantissa bits, relative error ≤ 2⁻¹⁴.
//! Radiance is never negative; a negative value, −0, NaN or a value below the smallest normal
//! f32 is stored as 0 (a device may flush such a subnormal to 0 when it reads the layer), and
//! nothing rounds up to infinity (the largest code is the largest finite f32's).
//!
//! The words: the first texel's codes in the low bits of x, y, z; the second's low
//! `32 − LAYER_CODE_BITS` bits above them, and its high bits in w, red first. The GPU twin is
//! shaders/common/layer_pair.glsl (written by layer_apron.comp, read by brdf_environment.glsl);
//! brdf_quadrature.rs reads every layer texel through [`stored`].

use crate::gpu::shaders::interface::LAYER_CODE_BITS;

/// Mantissa bits dropped from a channel's f32.
const DROPPED: u32 = 31 - LAYER_CODE_BITS;
const CODE_MASK: u32 = (1 << LAYER_CODE_BITS) - 1;
/// The second texel's bits beside the first's in each of x, y, z.
const LOW_BITS: u32 = 32 - LAYER_CODE_BITS;
/// The rest of each of its codes, in w.
const HIGH_BITS: u32 = LAYER_CODE_BITS - LOW_BITS;
const _: () = assert!(3 * HIGH_BITS <= 32, "three high parts must share one word");
/// The smallest positive normal f32's bits.
const SMALLEST_NORMAL: u32 = 0x0080_0000;
/// The largest finite f32's code (its bits 0x7F7F_FFFF; `f32::to_bits` is not const at the
/// crate's MSRV).
const MAX_CODE: u32 = 0x7F7F_FFFF >> DROPPED;

/// The code of `x` (module doc).
pub fn encode(x: f32) -> u32 {
    let bits = x.to_bits();
    // Below the smallest normal the subtraction wraps; negative values and −0 have the sign
    // bit, NaNs are above +∞: all beyond the range of normal numbers and +∞.
    if bits.wrapping_sub(SMALLEST_NORMAL) > f32::INFINITY.to_bits() - SMALLEST_NORMAL {
        return 0;
    }
    let round = (1 << (DROPPED - 1)) - 1 + ((bits >> DROPPED) & 1);
    ((bits + round) >> DROPPED).min(MAX_CODE)
}

/// The f32 that `code` stands for.
pub fn decode(code: u32) -> f32 {
    f32::from_bits((code & CODE_MASK) << DROPPED)
}

/// `x` as a layer texel stores it.
pub fn stored(x: f32) -> f32 {
    decode(encode(x))
}

/// Texels `a` and `b` (RGB) in one RGBA32UI texel.
pub fn pack(a: [f32; 3], b: [f32; 3]) -> [u32; 4] {
    let (a, b) = (a.map(encode), b.map(encode));
    let mut words = [0; 4];
    for c in 0..3 {
        words[c] = a[c] | (b[c] << LAYER_CODE_BITS);
        words[3] |= (b[c] >> LOW_BITS) << (HIGH_BITS * c as u32);
    }
    words
}

/// The two texels of [`pack`], as stored.
pub fn unpack(words: [u32; 4]) -> ([f32; 3], [f32; 3]) {
    let high_mask = (1 << HIGH_BITS) - 1;
    let a = std::array::from_fn(|c| decode(words[c]));
    let b = std::array::from_fn(|c| {
        let high = (words[3] >> (HIGH_BITS * c as u32)) & high_mask;
        decode((words[c] >> LAYER_CODE_BITS) | (high << LOW_BITS))
    });
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stored_channel_is_within_its_rounding() {
        // Across the exponent range, at and between the codes' rounding points.
        let mut x = 1e-30f32;
        while x < 1e30 {
            for y in [x, x * 1.000_03, x * 1.000_061, x * 1.5] {
                let s = stored(y);
                assert!(((s - y) / y).abs() <= 2f32.powi(-14), "{y}: {s}");
            }
            x *= 1.37;
        }
        // Round to nearest even: a tie goes to the even code (1.0's code is even).
        let one = 1f32.to_bits() >> DROPPED;
        assert_eq!(one % 2, 0);
        let tie = |code: u32| f32::from_bits((code << DROPPED) + (1 << (DROPPED - 1)));
        assert_eq!(encode(tie(one)), one);
        assert_eq!(encode(tie(one + 1)), one + 2);
        assert_eq!(stored(1.0), 1.0);
        assert_eq!(stored(0.0), 0.0);
    }

    #[test]
    fn nothing_outside_radiance_is_stored_as_anything_but_zero_or_finite() {
        let subnormal = f32::from_bits(SMALLEST_NORMAL - 1);
        for x in [
            -1.0,
            -0.0,
            f32::NAN,
            -f32::INFINITY,
            subnormal,
            f32::from_bits(1),
        ] {
            assert_eq!(stored(x).to_bits(), 0, "{x}");
        }
        assert_eq!(SMALLEST_NORMAL, f32::MIN_POSITIVE.to_bits());
        assert_eq!(stored(f32::MIN_POSITIVE), f32::MIN_POSITIVE);
        assert_eq!(MAX_CODE, f32::MAX.to_bits() >> DROPPED);
        assert_eq!(stored(f32::INFINITY), f32::from_bits(MAX_CODE << DROPPED));
        assert!(stored(f32::MAX).is_finite());
        assert!(stored(f32::MAX) <= f32::MAX);
    }

    #[test]
    fn a_pair_unpacks_to_its_stored_texels() {
        let values = [0.0, 1e-20, 0.123_456_7, 1.0, 3.75e4, 6.5e8, f32::MAX];
        for (i, &x) in values.iter().enumerate() {
            for (j, &y) in values.iter().enumerate() {
                let a = [x, y, values[(i + j) % values.len()]];
                let b = [y, values[(i * 3 + j) % values.len()], x];
                let (ga, gb) = unpack(pack(a, b));
                assert_eq!(ga, a.map(stored));
                assert_eq!(gb, b.map(stored));
            }
        }
    }
}
