//! Loading an HDR environment into an [`Equirect`] of linear RGB (SPEC §4): Radiance `.hdr`
//! (our own RGBE decoder), OpenEXR (the `exr` crate) and `builtin:studio`, the CC0 studio HDRI
//! embedded in the binary. Owns decoding and the clean-up of non-finite or negative pixels; it
//! does not know about cubes, the prefilter or who is told about replaced pixels (`prepare.rs`
//! turns the count into a `Warning`).
//!
//! Every size is checked against [`MAX_SIDE`] and [`MAX_PIXELS`] before anything is allocated, so
//! a hostile header cannot make us ask for gigabytes; a file larger than [`MAX_ENV_FILE_BYTES`]
//! is refused from its length before it is read.

use std::io::Cursor;
use std::path::Path;

use exr::prelude::{read, Compression, MetaData, ReadChannels, ReadLayers};

use super::image::Equirect;
use crate::text::builtin_name;
use crate::{Error, Result};

/// The spec that selects the embedded environment (the CLI's default).
pub const BUILTIN_STUDIO: &str = "builtin:studio";

/// `assets/env/studio.hdr`: Greg Zaal's "studio" from HDRI Haven (CC0; licence beside the file),
/// 1024 × 512, re-saved from Debian's blender-data as Radiance RGBE.
const STUDIO_HDR: &[u8] = include_bytes!("../../assets/env/studio.hdr");

/// Largest width or height accepted (a 32k equirect is already 4 GiB of f32 RGB).
pub const MAX_SIDE: usize = 32768;
/// Largest pixel count accepted: 2^28 pixels are 3 GiB as f32 RGB.
pub const MAX_PIXELS: usize = 1 << 28;

/// Largest environment file read (4 GiB): an uncompressed float RGBA EXR at [`MAX_PIXELS`].
pub const MAX_ENV_FILE_BYTES: u64 = 1 << 32;

/// How a Radiance header may spend at most before its blank line: real headers are < 1 KiB.
const MAX_HDR_HEADER: usize = 64 * 1024;

/// An environment as loaded: the radiance, how many pixels had a non-finite or negative component
/// (those components are now 0; preparation returns one warning), and where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedEnvironment {
    pub image: Equirect,
    pub replaced_pixels: usize,
    pub source: String,
}

/// The file an environment `spec` names: None for a built-in (`builtin:…`) or `none`. A render
/// must neither write its image over that file nor remove it as a failed run's output.
pub fn environment_file(spec: &str) -> Option<&Path> {
    let named = builtin_name(spec).is_none() && !spec.eq_ignore_ascii_case("none");
    named.then(|| Path::new(spec))
}

/// Loads `spec`: a path ending in `.hdr` or `.exr` (any case), or `builtin:studio`.
pub fn load_environment(spec: &str) -> Result<LoadedEnvironment> {
    if spec.eq_ignore_ascii_case(BUILTIN_STUDIO) {
        return sanitized(decode_hdr(STUDIO_HDR, spec)?, spec);
    }
    let extension = Path::new(spec)
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let decode: fn(&[u8], &str) -> Result<Equirect> = match extension.as_deref() {
        Some("hdr") => decode_hdr,
        Some("exr") => decode_exr,
        _ => {
            return Err(Error::invalid(
                "environment",
                spec,
                format!("expected a Radiance .hdr or OpenEXR .exr file, or {BUILTIN_STUDIO}"),
            ))
        }
    };
    let read_error = |source| Error::Read {
        path: spec.into(),
        source,
    };
    let length = std::fs::metadata(spec).map_err(read_error)?.len();
    if length > MAX_ENV_FILE_BYTES {
        return Err(Error::invalid(
            "environment file",
            format!("{spec} ({length} bytes)"),
            format!(
                "at most {MAX_ENV_FILE_BYTES} bytes (4 GiB) are read; downscale the image or \
                 re-save it compressed (e.g. EXR with PIZ or ZIP)"
            ),
        ));
    }
    let bytes = std::fs::read(spec).map_err(read_error)?;
    sanitized(decode(&bytes, spec)?, spec)
}

/// Decodes in-memory bytes by their magic number (OpenEXR or Radiance), then replaces bad pixels
/// like [`load_environment`]. For callers without a file name extension (the C API).
pub fn decode_environment(bytes: &[u8], source: &str) -> Result<LoadedEnvironment> {
    let image = if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        decode_exr(bytes, source)?
    } else {
        decode_hdr(bytes, source)?
    };
    sanitized(image, source)
}

fn sanitized(mut image: Equirect, source: &str) -> Result<LoadedEnvironment> {
    let replaced_pixels = replace_invalid_pixels(&mut image);
    Ok(LoadedEnvironment {
        image,
        replaced_pixels,
        source: source.to_string(),
    })
}

/// Sets every non-finite or negative component to 0 and returns how many pixels had one: radiance
/// is non-negative, and one NaN would spread through every blurred layer.
pub fn replace_invalid_pixels(image: &mut Equirect) -> usize {
    let mut replaced = 0;
    for pixel in &mut image.pixels {
        let mut bad = false;
        for c in pixel.iter_mut() {
            // `!(c >= 0)` is also true for NaN.
            if !(c.is_finite() && *c >= 0.0) {
                *c = 0.0;
                bad = true;
            }
        }
        replaced += usize::from(bad);
    }
    replaced
}

fn check_size(source: &str, width: usize, height: usize) -> Result<()> {
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(Error::invalid(
            "environment size",
            format!("{width}×{height} ({source})"),
            format!("width and height must be in 1..={MAX_SIDE}; downscale the image"),
        ));
    }
    if width * height > MAX_PIXELS {
        return Err(Error::invalid(
            "environment size",
            format!("{width}×{height} ({source})"),
            format!("at most {MAX_PIXELS} pixels (2^28); downscale the image"),
        ));
    }
    Ok(())
}

// ---- Radiance RGBE -------------------------------------------------------------------------

/// Decodes a Radiance RGBE picture: header `#?RADIANCE` or `#?RGBE`, `FORMAT=32-bit_rle_rgbe`
/// (or none), resolution line `-Y H +X W`, then H scan lines top to bottom, each new-style RLE
/// (`2 2 W_hi W_lo`, four run-length coded component planes) or flat 4-byte pixels (with
/// Radiance's old `1 1 1 n` repeat runs). `EXPOSURE=` is ignored, as by most readers.
pub fn decode_hdr(bytes: &[u8], source: &str) -> Result<Equirect> {
    let (width, height, data) = parse_hdr_header(bytes, source)?;
    // No scan line is shorter than 12 bytes (4·W if W < 3): new-style RLE needs 4 + 4·2·⌈W/127⌉,
    // flat pixels with Radiance's old repeat runs a pixel and two runs (255 and 255·256). Refuse
    // a file too short to hold the picture before allocating it.
    let shortest_line = (4 * width).min(12);
    if data.len() < height * shortest_line {
        return Err(hdr_data_error(
            source,
            format!(
                "{} bytes of pixel data cannot hold {height} scan lines: the file is truncated",
                data.len()
            ),
        ));
    }
    let mut pixels = Vec::with_capacity(width * height);
    let mut reader = ByteReader { data, at: 0 };
    let mut line = vec![[0u8; 4]; width];
    for y in 0..height {
        read_scanline(&mut reader, &mut line).map_err(|message| {
            hdr_data_error(source, format!("scan line {y} of {height}: {message}"))
        })?;
        pixels.extend(line.iter().map(|&rgbe| rgbe_to_linear(rgbe)));
    }
    Ok(Equirect {
        width: width as u32,
        height: height as u32,
        pixels,
    })
}

fn hdr_data_error(source: &str, message: String) -> Error {
    Error::invalid(
        "Radiance HDR data",
        source,
        format!("{message} (0 = top); re-export the file"),
    )
}

/// Returns (width, height, pixel bytes).
fn parse_hdr_header<'a>(bytes: &'a [u8], source: &str) -> Result<(usize, usize, &'a [u8])> {
    let mut at = 0;
    let mut line_number = 0;
    // A header written with CRLF line ends (a Windows tool's) reads as the same lines: the
    // first line was refused as not #?RADIANCE although it was, with a \r after it.
    let next_line = |at: &mut usize| -> Option<&'a [u8]> {
        let rest = bytes.get(*at..)?;
        let end = rest.iter().take(MAX_HDR_HEADER).position(|&b| b == b'\n')?;
        *at += end + 1;
        let line = &rest[..end];
        Some(line.strip_suffix(b"\r").unwrap_or(line))
    };
    let unterminated = |line: usize| {
        Error::parse(
            source,
            line,
            "the Radiance header ends without its resolution line (-Y <height> +X <width>): \
             the file is truncated or not an HDR image; re-export it",
        )
    };
    if bytes.is_empty() {
        return Err(Error::parse(
            source,
            1,
            "the file is empty; a Radiance HDR starts with the line #?RADIANCE",
        ));
    }

    line_number += 1;
    let magic = next_line(&mut at).ok_or_else(|| unterminated(line_number))?;
    if magic != b"#?RADIANCE" && magic != b"#?RGBE" {
        return Err(Error::parse(
            source,
            1,
            "not a Radiance HDR file: the first line must be #?RADIANCE or #?RGBE",
        ));
    }
    loop {
        line_number += 1;
        let line = next_line(&mut at).ok_or_else(|| unterminated(line_number))?;
        if line.is_empty() {
            break;
        }
        if let Some(format) = line.strip_prefix(b"FORMAT=") {
            if format != b"32-bit_rle_rgbe" {
                return Err(Error::parse(
                    source,
                    line_number,
                    format!(
                        "FORMAT={} is not supported: only 32-bit_rle_rgbe (convert XYZE to RGB first)",
                        String::from_utf8_lossy(format)
                    ),
                ));
            }
        }
        if at > MAX_HDR_HEADER {
            return Err(unterminated(line_number));
        }
    }
    line_number += 1;
    let resolution = next_line(&mut at).ok_or_else(|| unterminated(line_number))?;
    let text = String::from_utf8_lossy(resolution);
    let words: Vec<&str> = text.split_ascii_whitespace().collect();
    let (height, width) = match words.as_slice() {
        ["-Y", h, "+X", w] => (h.parse::<usize>().ok(), w.parse::<usize>().ok()),
        _ => {
            return Err(Error::parse(
                source,
                line_number,
                format!(
                    "resolution line \"{text}\": only the standard orientation \"-Y <height> +X <width>\" \
                     (rows top to bottom, left to right) is supported; re-save the file, e.g. \
                     `oiiotool in.hdr -o out.hdr`"
                ),
            ))
        }
    };
    let (Some(height), Some(width)) = (height, width) else {
        return Err(Error::parse(
            source,
            line_number,
            format!("resolution line \"{text}\": height and width must be whole numbers"),
        ));
    };
    check_size(source, width, height)?;
    Ok((width, height, &bytes[at..]))
}

struct ByteReader<'a> {
    data: &'a [u8],
    at: usize,
}

impl ByteReader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let bytes = self
            .data
            .get(self.at..self.at + N)
            .ok_or_else(|| format!("truncated at byte {} of the pixel data", self.data.len()))?;
        self.at += N;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        Ok(out)
    }
}

fn read_scanline(reader: &mut ByteReader, line: &mut [[u8; 4]]) -> Result<(), String> {
    let width = line.len();
    let first = reader.take::<4>()?;
    let new_rle = (8..0x8000).contains(&width) && first[0] == 2 && first[1] == 2 && first[2] < 128;
    if !new_rle {
        return read_flat_scanline(reader, line, first);
    }
    let declared = (usize::from(first[2]) << 8) | usize::from(first[3]);
    if declared != width {
        return Err(format!(
            "declares width {declared}, the header says {width}"
        ));
    }
    for component in 0..4 {
        let mut x = 0;
        while x < width {
            let [count] = reader.take::<1>()?;
            if count > 128 {
                let run = usize::from(count - 128);
                let [value] = reader.take::<1>()?;
                let Some(texels) = line.get_mut(x..x + run) else {
                    return Err(format!("a run of {run} overflows the line at x = {x}"));
                };
                texels.iter_mut().for_each(|t| t[component] = value);
                x += run;
            } else {
                let count = usize::from(count);
                if count == 0 || x + count > width {
                    return Err(format!("a literal of {count} bytes at x = {x} is invalid"));
                }
                for texel in &mut line[x..x + count] {
                    texel[component] = reader.take::<1>()?[0];
                }
                x += count;
            }
        }
    }
    Ok(())
}

/// Flat pixels; `1 1 1 n` repeats the previous pixel n << shift times, the shift growing by 8 for
/// each consecutive repeat (Radiance's `oldreadcolrs`).
fn read_flat_scanline(
    reader: &mut ByteReader,
    line: &mut [[u8; 4]],
    first: [u8; 4],
) -> Result<(), String> {
    let mut x = 0;
    let mut shift = 0u32;
    let mut pixel = first;
    loop {
        if pixel[..3] == [1, 1, 1] {
            let run = usize::from(pixel[3]) << shift;
            if x == 0 || shift > 16 || x + run > line.len() {
                return Err(format!("an invalid repeat run of {run} at x = {x}"));
            }
            let previous = line[x - 1];
            line[x..x + run].fill(previous);
            x += run;
            shift += 8;
        } else {
            line[x] = pixel;
            x += 1;
            shift = 0;
        }
        if x == line.len() {
            return Ok(());
        }
        pixel = reader.take::<4>()?;
    }
}

/// Radiance's `colr_color`: mantissa m with shared exponent e means (m + ½)·2^(e − 136), the centre
/// of the interval Radiance's encoder truncates into; e = 0 is black.
fn rgbe_to_linear([r, g, b, e]: [u8; 4]) -> [f32; 3] {
    if e == 0 {
        return [0.0; 3];
    }
    let scale = 2f64.powi(i32::from(e) - 136);
    [r, g, b].map(|m| ((f64::from(m) + 0.5) * scale) as f32)
}

// ---- OpenEXR --------------------------------------------------------------------------------

/// Decodes the first layer of an OpenEXR file that has R, G and B channels (A and others are
/// ignored; half, float or uint samples), at its largest resolution level. Every compression the
/// `exr` crate decodes is accepted — including DWAA/DWAB and B44/B44A since exr 1.74; the header
/// is read first so that sizes are checked before allocating and an undecodable compression
/// (HTJ2K) gets an error saying how to convert the file.
pub fn decode_exr(bytes: &[u8], source: &str) -> Result<Equirect> {
    let exr_error = |what: &str, e: exr::error::Error| {
        Error::invalid(
            "OpenEXR file",
            source,
            format!("{what}: {e}; check that the file is a complete, valid OpenEXR image"),
        )
    };
    let meta = MetaData::read_from_buffered(Cursor::new(bytes), false)
        .map_err(|e| exr_error("cannot read the header", e))?;
    let has = |header: &exr::meta::header::Header, name: &str| {
        header.channels.list.iter().any(|c| c.name == *name)
    };
    let Some(header) = meta
        .headers
        .iter()
        .find(|h| !h.deep && has(h, "R") && has(h, "G") && has(h, "B"))
    else {
        let found: Vec<String> = meta
            .headers
            .iter()
            .flat_map(|h| h.channels.list.iter().map(|c| c.name.to_string()))
            .collect();
        return Err(Error::invalid(
            "OpenEXR file",
            source,
            format!(
                "no flat layer has channels named R, G and B (found {}); an environment must be \
                 an RGB(A) image: rename the channels, e.g. `oiiotool in.exr --ch R=diffuse.R,\
                 G=diffuse.G,B=diffuse.B -o out.exr`",
                found.join(", ")
            ),
        ));
    };
    let display = header.shared_attributes.display_window;
    check_size(source, display.size.width(), display.size.height())?;
    check_size(
        source,
        header.layer_size.width(),
        header.layer_size.height(),
    )?;
    if matches!(
        header.compression,
        Compression::HTJ2K32 | Compression::HTJ2K256
    ) {
        return Err(Error::invalid(
            "OpenEXR compression",
            format!("{} ({source})", header.compression),
            "this decoder cannot read it; re-save with PIZ or ZIP, e.g. \
             `oiiotool in.exr --compression zip -o out.exr`",
        ));
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |resolution, _| {
                Equirect::constant(
                    resolution.width() as u32,
                    resolution.height() as u32,
                    [0.0; 3],
                )
            },
            |image: &mut Equirect, position, (r, g, b): (f32, f32, f32)| {
                let index = position.y() * image.width as usize + position.x();
                image.pixels[index] = [r, g, b];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| exr_error("cannot decode the pixels", e))?;
    let data = image.layer_data.channel_data.pixels;
    Ok(in_display_window(
        data,
        header.own_attributes.layer_position,
        display,
    ))
}

/// The pixels of the data window placed in the display window, which is the image: outside the
/// data window 0, data beyond the display window (overscan) cropped. A map whose data window
/// covered a band of the display window was stretched over the whole sphere (a probe,
/// 2026-12-06).
fn in_display_window(
    data: Equirect,
    data_position: exr::math::Vec2<i32>,
    display: exr::meta::attribute::IntegerBounds,
) -> Equirect {
    let (width, height) = (display.size.width(), display.size.height());
    let offset = (
        i64::from(data_position.x()) - i64::from(display.position.x()),
        i64::from(data_position.y()) - i64::from(display.position.y()),
    );
    if offset == (0, 0) && (data.width as usize, data.height as usize) == (width, height) {
        return data;
    }
    let mut image = Equirect::constant(width as u32, height as u32, [0.0; 3]);
    for (i, pixel) in data.pixels.iter().enumerate() {
        let x = (i % data.width as usize) as i64 + offset.0;
        let y = (i / data.width as usize) as i64 + offset.1;
        if (0..width as i64).contains(&x) && (0..height as i64).contains(&y) {
            image.pixels[y as usize * width + x as usize] = *pixel;
        }
    }
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Radiance file with the standard header and the given pixel bytes.
    fn hdr_file(width: usize, height: usize, pixel_bytes: &[u8]) -> Vec<u8> {
        let mut bytes = format!(
            "#?RADIANCE\n# test\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y {height} +X {width}\n"
        )
        .into_bytes();
        bytes.extend_from_slice(pixel_bytes);
        bytes
    }

    fn error_text(result: Result<impl std::fmt::Debug>) -> String {
        result.expect_err("must fail").to_string()
    }

    #[test]
    fn an_exr_without_flat_rgb_channels_lists_what_it_has() {
        use exr::prelude::*;
        let channel = AnyChannel::new("diffuse.R", FlatSamples::F32(vec![0.5; 8]));
        let layer = Layer::new(
            (4, 2),
            LayerAttributes::default(),
            Encoding::UNCOMPRESSED,
            AnyChannels::sort(SmallVec::from_vec(vec![channel])),
        );
        let mut bytes = Vec::new();
        Image::from_layer(layer)
            .write()
            .to_buffered(Cursor::new(&mut bytes))
            .unwrap();
        let message = error_text(decode_exr(&bytes, "aov.exr"));
        assert!(
            message.contains("found diffuse.R") && message.contains("oiiotool"),
            "{message}"
        );
    }

    #[test]
    fn an_exr_data_window_is_placed_in_its_display_window() {
        use exr::math::Vec2;
        use exr::meta::attribute::IntegerBounds;
        // A 4 × 2 display; data 2 × 1 pixels numbered 1, 2.
        let data = Equirect {
            width: 2,
            height: 1,
            pixels: vec![[1.0; 3], [2.0; 3]],
        };
        let display = IntegerBounds::new(Vec2(10, -5), Vec2(4, 2));
        let green = |image: &Equirect| image.pixels.iter().map(|p| p[1]).collect::<Vec<_>>();
        // A band: data at display (1, 1).
        let band = in_display_window(data.clone(), Vec2(11, -4), display);
        assert_eq!((band.width, band.height), (4, 2));
        assert_eq!(green(&band), [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 0.0]);
        // Overscan: the first data pixel left of the display is cropped.
        let over = in_display_window(data.clone(), Vec2(9, -5), display);
        assert_eq!(green(&over), [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        // The same window: the data as it is.
        let same = IntegerBounds::new(Vec2(3, 3), Vec2(2, 1));
        assert_eq!(in_display_window(data.clone(), Vec2(3, 3), same), data);
    }

    #[test]
    fn a_header_with_crlf_line_ends_reads_as_with_lf() {
        let pixels = [128, 64, 32, 129, 255, 0, 0, 136];
        let lf = hdr_file(2, 1, &pixels);
        let text_end = lf.len() - pixels.len();
        let header = String::from_utf8(lf[..text_end].to_vec()).unwrap();
        let mut crlf = header.replace('\n', "\r\n").into_bytes();
        crlf.extend_from_slice(&pixels);
        let (a, b) = (decode_hdr(&lf, "lf.hdr"), decode_hdr(&crlf, "crlf.hdr"));
        assert_eq!(a.unwrap().pixels, b.unwrap().pixels);
    }

    #[test]
    fn flat_rgbe_pixels_decode_to_radiance_centres() {
        // Radiance's colr_color by hand: (m + ½)·2^(e−136). (128, 64, 32, 129) → 128.5/128 …;
        // (255, 0, 0, 136) → 255.5, 0.5, 0.5; e = 0 → black.
        let bytes = hdr_file(3, 1, &[128, 64, 32, 129, 255, 0, 0, 136, 200, 200, 200, 0]);
        let image = decode_hdr(&bytes, "t.hdr").unwrap();
        assert_eq!((image.width, image.height), (3, 1));
        assert_eq!(image.pixels[0], [128.5 / 128.0, 64.5 / 128.0, 32.5 / 128.0]);
        assert_eq!(image.pixels[1], [255.5, 0.5, 0.5]);
        assert_eq!(image.pixels[2], [0.0; 3]);
    }

    #[test]
    fn new_style_rle_scanlines_decode_runs_and_literals() {
        // Width 8, two lines. Line 0: R = run of 8 × 128; G = literal 8 bytes 0..7 ·16;
        // B = run 3 × 64 then literal 5 × 32; E = run of 8 × 128 (2^-8 scale).
        let mut line0 = vec![2, 2, 0, 8, 128 + 8, 128, 8];
        line0.extend((0..8).map(|x| x * 16));
        line0.extend([128 + 3, 64, 5, 32, 32, 32, 32, 32, 128 + 8, 128]);
        // Line 1: every component one run of 8; R = 0 with e = 0 is black.
        let line1 = [2, 2, 0, 8, 136, 9, 136, 9, 136, 9, 136, 0];
        let bytes = hdr_file(8, 2, &[line0, line1.to_vec()].concat());
        let image = decode_hdr(&bytes, "rle.hdr").unwrap();
        let scale = 2f32.powi(-8);
        for x in 0..8 {
            let b = if x < 3 { 64.5 } else { 32.5 };
            assert_eq!(
                image.get(x, 0),
                [128.5 * scale, (x as f32 * 16.0 + 0.5) * scale, b * scale]
            );
            assert_eq!(image.get(x, 1), [0.0; 3]);
        }
    }

    #[test]
    fn old_style_repeat_runs_copy_the_previous_pixel() {
        // Width 300 (flat, no new RLE because the line does not start 2 2): a pixel, then
        // "1 1 1 43" (43 copies), then "1 1 1 1" (1 << 8 = 256 more): 1 + 43 + 256 = 300.
        let bytes = hdr_file(300, 1, &[128, 128, 128, 129, 1, 1, 1, 43, 1, 1, 1, 1]);
        let image = decode_hdr(&bytes, "old.hdr").unwrap();
        let one = 128.5 / 128.0;
        assert!(image.pixels.iter().all(|&p| p == [one; 3]));
    }

    #[test]
    fn truncated_hdr_names_the_file_and_the_scan_line() {
        // Width 16, every component one literal of 16 bytes: 4 + 4·17 = 72 bytes a line.
        let mut line = vec![2, 2, 0, 16];
        for _ in 0..4 {
            line.push(16);
            line.extend([130; 16]);
        }
        let mut bytes = hdr_file(16, 3, &[line.clone(), line.clone(), line].concat());
        bytes.truncate(bytes.len() - 3);
        let message = error_text(decode_hdr(&bytes, "cut.hdr"));
        assert!(
            message.contains("cut.hdr") && message.contains("scan line 2 of 3"),
            "{message}"
        );
        // Far too short for the size the header claims: refused before allocating.
        let message = error_text(decode_hdr(&hdr_file(30000, 8000, &[0; 64]), "tiny.hdr"));
        assert!(message.contains("truncated"), "{message}");
    }

    #[test]
    fn corrupt_rle_is_an_error_not_a_panic() {
        // Declared scan-line width 9 ≠ 8; a run past the end; a zero-length literal.
        for line in [
            vec![2, 2, 0, 9, 0, 0, 0, 0],
            vec![2, 2, 0, 8, 128 + 9, 1],
            vec![2, 2, 0, 8, 0],
        ] {
            let bytes = hdr_file(8, 1, &[line, vec![0; 64]].concat());
            let message = error_text(decode_hdr(&bytes, "bad.hdr"));
            assert!(
                message.contains("bad.hdr") && message.contains("scan line 0"),
                "{message}"
            );
        }
        // A repeat run with nothing before it.
        let message = error_text(decode_hdr(
            &hdr_file(4, 1, &[1, 1, 1, 3, 0, 0, 0, 0, 0, 0, 0, 0]),
            "r.hdr",
        ));
        assert!(message.contains("repeat"), "{message}");
    }

    #[test]
    fn unsupported_headers_say_what_is_supported() {
        let cases = [
            (b"P6\n3 1\n255\n".to_vec(), "#?RADIANCE"),
            (
                b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n".to_vec(),
                "32-bit_rle_rgbe",
            ),
            (
                b"#?RADIANCE\n\n+Y 1 +X 1\n\0\0\0\0".to_vec(),
                "-Y <height> +X <width>",
            ),
            (b"#?RADIANCE\n\n-Y 1 +X many\n".to_vec(), "whole numbers"),
            (
                b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n".to_vec(),
                "resolution line",
            ),
            (b"#?RGBE\n\n-Y 40000 +X 8\n".to_vec(), "1..=32768"),
            (b"#?RGBE\n\n-Y 32768 +X 32768\n".to_vec(), "2^28"),
            (b"#?RGBE\n\n-Y 0 +X 8\n".to_vec(), "1..=32768"),
        ];
        for (bytes, expected) in cases {
            let message = error_text(decode_hdr(&bytes, "h.hdr"));
            assert!(
                message.contains("h.hdr") && message.contains(expected),
                "{message}"
            );
        }
    }

    #[test]
    fn invalid_pixels_are_zeroed_and_counted_once_per_pixel() {
        let mut image = Equirect::constant(4, 1, [1.0; 3]);
        image.pixels[0] = [f32::NAN, -1.0, 2.0];
        image.pixels[2] = [f32::INFINITY, 0.5, 0.5];
        image.pixels[3] = [-0.0, 0.0, 3.0]; // −0 is a valid zero, not negative radiance
        assert_eq!(replace_invalid_pixels(&mut image), 2);
        assert_eq!(
            image.pixels,
            vec![[0.0, 0.0, 2.0], [1.0; 3], [0.0, 0.5, 0.5], [-0.0, 0.0, 3.0]]
        );
    }

    #[test]
    fn builtin_studio_is_the_embedded_1024_by_512_hdri() {
        let loaded = load_environment(BUILTIN_STUDIO).unwrap();
        assert_eq!((loaded.image.width, loaded.image.height), (1024, 512));
        assert_eq!(loaded.replaced_pixels, 0);
        assert_eq!(loaded.source, BUILTIN_STUDIO);
        assert!(
            loaded.image.pixels.iter().any(|p| p[0] > 1.0),
            "an HDRI has values above 1"
        );
    }

    #[test]
    fn unknown_extensions_and_missing_files_are_clear_errors() {
        assert!(error_text(load_environment("room.png")).contains(".hdr or OpenEXR .exr"));
        // The extension is matched in any case; the file does not exist.
        let message = error_text(load_environment("/nonexistent/Room.HDR"));
        assert!(
            message.contains("cannot read /nonexistent/Room.HDR"),
            "{message}"
        );
    }
}
