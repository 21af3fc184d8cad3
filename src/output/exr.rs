//! OpenEXR encoding of an [`HdrImage`]: linear radiance exactly as rendered (SPEC §1: no
//! exposure, no tone curve), channels R, G, B, A as float32, alpha = coverage, premultiplied as
//! OpenEXR defines it. Owns only the byte encoding; files are written by `atomic.rs`.
//!
//! OpenEXR's y axis points down and the first scan line of the data window is the top row, so
//! row 0 of the image (the top, SPEC §1) is written first, with no flip.

use std::io::Cursor;

use exr::prelude::traits::*;
use exr::prelude::{
    Blocks, Compression, Encoding, Image, Layer, LayerAttributes, LineOrder, SpecificChannels, Vec2,
};

use super::image::HdrImage;
use crate::{Error, Result};

/// ZIP (deflate over 16 scan lines) is lossless for float32, so a decode gives back the exact
/// bits; increasing line order fixes the block order in the file.
const ENCODING: Encoding = Encoding {
    compression: Compression::ZIP16,
    blocks: Blocks::ScanLines,
    line_order: LineOrder::Increasing,
};

/// Linear RGBA float32 (SPEC §1: no exposure, no tone curve), lossless compression, deterministic
/// (encode single-threaded if the crate's parallel encoder could reorder anything).
///
/// Non-finite pixels, an empty image and a pixel count that does not match the size are errors:
/// a NaN in an EXR poisons every later filter and average that reads it.
pub fn encode_exr(image: &HdrImage) -> Result<Vec<u8>> {
    image.validate_for_encoding()?;
    let width = image.width as usize;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let [r, g, b, a] = image.pixels[y * width + x];
        (r, g, b, a)
    });
    let layer = Layer::new(
        (width, image.height as usize),
        LayerAttributes::default(),
        ENCODING,
        channels,
    );
    let mut bytes = Vec::new();
    // `non_parallel`: the parallel encoder compresses blocks on a thread pool; with increasing
    // line order it sorts them again, but a single thread makes the byte stream obviously a
    // function of the pixels alone.
    Image::from_layer(layer)
        .write()
        .non_parallel()
        .to_buffered(Cursor::new(&mut bytes))
        .map_err(|e| {
            Error::invalid(
                "EXR image",
                format!("{}×{}", image.width, image.height),
                format!("the EXR encoder refused it ({e})"),
            )
        })?;
    Ok(bytes)
}

/// Reads the first RGBA layer of an EXR at its full resolution (for tests and for reading our own
/// output). A missing alpha channel reads as 1 (fully covered); half or u32 samples are converted
/// to f32. Pixel (0, 0) is the top-left corner of the data window.
pub fn decode_exr(bytes: &[u8]) -> Result<HdrImage> {
    let decoded = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution, _| HdrImage::new(resolution.width() as u32, resolution.height() as u32),
            |image: &mut HdrImage, Vec2(x, y), (r, g, b, a): (f32, f32, f32, f32)| {
                let index = y * image.width as usize + x;
                image.pixels[index] = [r, g, b, a];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| {
            Error::invalid(
                "EXR data",
                format!("{} bytes", bytes.len()),
                format!(
                    "not a readable RGB(A) OpenEXR ({e}); DWAA/DWAB and B44 compression are \
                     not supported, re-save as ZIP, PIZ or uncompressed"
                ),
            )
        })?;
    Ok(decoded.layer_data.channel_data.pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values chosen to expose any lossy path: a denormal, the largest f32, an f16-inexact value,
    /// negative zero, and alpha values other than 0 and 1.
    fn awkward_image() -> HdrImage {
        let mut image = HdrImage::new(3, 2);
        image.set(0, 0, [1.0e-40, f32::MAX, 0.1, 1.0]);
        image.set(1, 0, [1234.5677, -0.0, 3.0e-5, 0.25]);
        image.set(2, 0, [0.333_333_34, 0.0, 65_504.0, 0.75]);
        image.set(0, 1, [1.0, 2.0, 3.0, 0.5]);
        image
    }

    #[test]
    fn exr_round_trip_is_bit_exact_including_alpha() {
        let image = awkward_image();
        let decoded = decode_exr(&encode_exr(&image).unwrap()).unwrap();
        assert_eq!((decoded.width, decoded.height), (3, 2));
        // Exact bit comparison: the encoding is lossless float32, so no tolerance applies
        // (and `==` would hide a −0.0 → 0.0 change).
        for (got, want) in decoded.pixels.iter().zip(&image.pixels) {
            assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits));
        }
    }

    #[test]
    fn exr_encoding_is_deterministic() {
        let image = awkward_image();
        assert_eq!(
            encode_exr(&image).unwrap(),
            encode_exr(&image.clone()).unwrap()
        );
    }

    #[test]
    fn exr_encoding_rejects_non_finite_pixels() {
        let mut image = awkward_image();
        image.set(1, 1, [0.0, 0.0, f32::INFINITY, 1.0]);
        let message = encode_exr(&image).unwrap_err().to_string();
        assert!(message.contains("pixel (1, 1)"), "{message}");
    }

    #[test]
    fn decoding_garbage_is_an_error() {
        assert!(decode_exr(b"not an exr").is_err());
    }
}
