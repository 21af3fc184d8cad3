//! PNG encoding of an [`HdrImage`]: the display transform of SPEC §1 (exposure → tone curve →
//! sRGB → 8 bits, in `tonemap.rs`) plus un-premultiplying, since PNG alpha is straight. Owns only
//! the byte encoding; writing files is `atomic.rs`'s job, and the pixels are never altered here.

use std::io::Cursor;

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder, ImageFormat};

use rayon::prelude::*;

use super::image::HdrImage;
use super::tonemap::{to_srgb8, unit_to_u8, PngSettings, Srgb8Encoder};
use crate::{Error, Result};

/// zlib level of the PNG encoder (1 fastest … 9 smallest).
pub const PNG_ZLIB_LEVEL: u8 = 3;

/// RGBA8 PNG. PNG alpha is straight (not premultiplied): colour = rgb/alpha where alpha > 0, then
/// to_srgb8; alpha8 = round(255·alpha). Deterministic: identical input → identical bytes.
///
/// Alpha is coverage and is clamped to [0, 1] first. Where alpha is 0 the colour is encoded as
/// stored (it is black for a rendered image). Non-finite pixels, an empty image, a pixel count
/// that does not match the size and a non-finite exposure are errors.
pub fn encode_png(image: &HdrImage, settings: &PngSettings) -> Result<Vec<u8>> {
    image.validate_for_encoding()?;
    settings.validate()?;
    // Rows in parallel (the display transform is per pixel, so the bytes are the same).
    let encoder = Srgb8Encoder::new(settings);
    let row_bytes = image.width as usize * 4;
    let mut rgba8 = vec![0u8; image.pixels.len() * 4];
    rgba8
        .par_chunks_mut(row_bytes.max(4))
        .zip(image.pixels.par_chunks((image.width as usize).max(1)))
        .for_each(|(out, row)| {
            for (texel, &pixel) in out.chunks_exact_mut(4).zip(row) {
                texel.copy_from_slice(&straight_srgb8_with(pixel, &encoder));
            }
        });

    let mut bytes = Vec::new();
    // Fixed compression and filter choices and no metadata chunks (no time stamp): the same
    // pixels always give the same bytes with a given `png` crate version. zlib level 3 instead of
    // the encoder's "balanced" default: far faster for slightly larger files, where encoding was
    // the slowest part of a batch job (figures in BENCHMARKS.md, "Before / after").
    let encoder = PngEncoder::new_with_quality(
        Cursor::new(&mut bytes),
        CompressionType::Level(PNG_ZLIB_LEVEL),
        FilterType::Adaptive,
    );
    encoder
        .write_image(&rgba8, image.width, image.height, ExtendedColorType::Rgba8)
        .map_err(|e| {
            Error::invalid(
                "PNG image",
                format!("{}×{}", image.width, image.height),
                format!("the PNG encoder refused it ({e}); PNG allows 1 to 2^31−1 pixels per side"),
            )
        })?;
    Ok(bytes)
}

/// One pixel as PNG stores it: colour un-premultiplied by coverage, then exposure → tone curve →
/// sRGB → 8 bits; alpha rounded to 8 bits. Also the C API's RGBA8 render.
pub fn straight_srgb8(pixel: [f32; 4], settings: &PngSettings) -> [u8; 4] {
    straight_pixel(pixel, |radiance| to_srgb8(radiance, settings))
}

/// [`straight_srgb8`] through the encoder of its settings, made once per image (the same bytes).
pub fn straight_srgb8_with(pixel: [f32; 4], encoder: &Srgb8Encoder) -> [u8; 4] {
    straight_pixel(pixel, |radiance| encoder.encode(radiance))
}

fn straight_pixel(pixel: [f32; 4], encode: impl Fn(f32) -> u8) -> [u8; 4] {
    let [r, g, b, a] = pixel;
    let alpha = a.clamp(0.0, 1.0);
    // Premultiplied colour is radiance × coverage; dividing by coverage recovers the radiance of
    // the covered part, which is what a straight-alpha viewer composites.
    let unpremultiply = if alpha > 0.0 { 1.0 / alpha } else { 1.0 };
    [
        encode(r * unpremultiply),
        encode(g * unpremultiply),
        encode(b * unpremultiply),
        unit_to_u8(alpha),
    ]
}

/// Decodes PNG bytes (any colour type and bit depth) to RGBA8, rows top first.
pub fn decode_png_rgba8(bytes: &[u8]) -> Result<(u32, u32, Vec<[u8; 4]>)> {
    let decoded = image::load_from_memory_with_format(bytes, ImageFormat::Png).map_err(|e| {
        Error::invalid(
            "PNG data",
            format!("{} bytes", bytes.len()),
            format!("not a readable PNG ({e}); pass the bytes of a complete PNG file"),
        )
    })?;
    let rgba = decoded.to_rgba8();
    let (width, height) = rgba.dimensions();
    let pixels = rgba.pixels().map(|p| p.0).collect();
    Ok((width, height, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::tonemap::ToneCurve;

    const LINEAR: PngSettings = PngSettings {
        exposure_ev: 0.0,
        tone_curve: ToneCurve::None,
    };

    #[test]
    fn straight_alpha_undoes_the_premultiplication() {
        // Half coverage of radiance 0.5 is stored premultiplied as 0.25. Straight colour must be
        // sRGB(0.5) = 0.7353569 → 187.52 → 188, alpha 0.5 → 127.5 → 128.
        assert_eq!(
            straight_srgb8([0.25, 0.25, 0.25, 0.5], &LINEAR),
            [188, 188, 188, 128]
        );
        // Full coverage: no division. Quarter coverage of radiance 1 (0.25 stored) → 255.
        assert_eq!(
            straight_srgb8([0.5, 0.0, 1.0, 1.0], &LINEAR),
            [188, 0, 255, 255]
        );
        assert_eq!(
            straight_srgb8([0.25, 0.0, 0.0, 0.25], &LINEAR),
            [255, 0, 0, 64]
        );
    }

    #[test]
    fn zero_coverage_is_transparent_black_and_alpha_is_clamped() {
        assert_eq!(straight_srgb8([0.0; 4], &LINEAR), [0, 0, 0, 0]);
        // Alpha above 1 (resolve round-off) clamps to 1, so colour is not darkened by it.
        assert_eq!(
            straight_srgb8([0.5, 0.5, 0.5, 1.5], &LINEAR),
            [188, 188, 188, 255]
        );
    }

    #[test]
    fn png_round_trip_gives_the_hand_computed_bytes() {
        let mut image = HdrImage::new(2, 2);
        image.set(0, 0, [1.0, 0.0, 0.0, 1.0]);
        image.set(1, 0, [0.5, 0.5, 0.5, 1.0]);
        image.set(0, 1, [0.25, 0.25, 0.25, 0.5]);
        let bytes = encode_png(&image, &LINEAR).unwrap();
        let (width, height, pixels) = decode_png_rgba8(&bytes).unwrap();
        assert_eq!((width, height), (2, 2));
        assert_eq!(
            pixels,
            vec![
                [255, 0, 0, 255],
                [188, 188, 188, 255],
                [188, 188, 188, 128],
                [0, 0, 0, 0]
            ]
        );
    }

    #[test]
    fn png_encoding_is_deterministic() {
        let mut image = HdrImage::new(17, 9);
        for (i, pixel) in image.pixels.iter_mut().enumerate() {
            let t = i as f32 * 0.37;
            *pixel = [t.sin().abs() * 4.0, t.cos().abs(), (t * 0.1).fract(), 1.0];
        }
        let settings = PngSettings::default();
        assert_eq!(
            encode_png(&image, &settings).unwrap(),
            encode_png(&image.clone(), &settings).unwrap()
        );
    }

    #[test]
    fn png_encoding_rejects_nan_pixels_and_bad_exposure() {
        let mut image = HdrImage::new(3, 3);
        image.set(2, 1, [f32::NAN, 0.0, 0.0, 1.0]);
        let message = encode_png(&image, &LINEAR).unwrap_err().to_string();
        assert!(message.contains("pixel (2, 1)"), "{message}");
        let bad_exposure = PngSettings {
            exposure_ev: f32::NAN,
            ..LINEAR
        };
        assert!(encode_png(&HdrImage::new(1, 1), &bad_exposure).is_err());
    }

    #[test]
    fn decoding_garbage_is_an_error() {
        assert!(decode_png_rgba8(b"not a png").is_err());
    }
}
