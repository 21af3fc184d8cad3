//! `contact_sheet.png`: every job's image as a small tile with its id and swept values written
//! under it, so a person sees the whole sweep at a glance.
//!
//! Owns thumbnails (downsampled, tone-mapped like the job's PNG) and the sheet layout. Text is
//! DejaVu Sans (assets/fonts) through plotters, as in the fit plots.

use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use crate::output::tonemap::Srgb8Encoder;
use crate::output::{HdrImage, PngSettings};
use crate::{Error, Result};

const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
const FONT_FAMILY: &str = "shikki-sheet";
/// The longest side of a tile's image, in pixels.
pub const TILE: u32 = 192;
const LINE_HEIGHT: u32 = 15;
const FONT_SIZE: u32 = 12;
const GAP: u32 = 8;
/// Where the image is transparent, tiles show this grey (sRGB 8-bit), like an image viewer.
const BACKDROP: [u8; 3] = [128, 128, 128];

/// A tile image, RGB8 rows top first.
#[derive(Clone, Debug)]
pub struct Thumbnail {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<[u8; 3]>,
}

impl Thumbnail {
    /// Box-filtered to fit in [`TILE`]², then exposure → tone curve → sRGB, composited over the
    /// backdrop by coverage.
    pub fn from_hdr(image: &HdrImage, png: &PngSettings) -> Self {
        let (width, height, factor) = fit(image.width, image.height);
        let encoder = Srgb8Encoder::new(png);
        let mut rgb = Vec::with_capacity((width * height) as usize);
        for ty in 0..height {
            for tx in 0..width {
                let mut sum = [0.0f32; 4];
                let mut count = 0.0;
                for y in ty * factor..((ty + 1) * factor).min(image.height) {
                    for x in tx * factor..((tx + 1) * factor).min(image.width) {
                        let p = image.pixels[(y * image.width + x) as usize];
                        for (s, v) in sum.iter_mut().zip(p) {
                            *s += if v.is_finite() { v } else { 0.0 };
                        }
                        count += 1.0;
                    }
                }
                let alpha = (sum[3] / count).clamp(0.0, 1.0);
                let pixel = std::array::from_fn(|c| {
                    // Colour is premultiplied; straight colour for the display transform.
                    let straight = if alpha > 0.0 {
                        sum[c] / count / alpha
                    } else {
                        0.0
                    };
                    let shown = f32::from(encoder.encode(straight));
                    (shown * alpha + f32::from(BACKDROP[c]) * (1.0 - alpha)).round() as u8
                });
                rgb.push(pixel);
            }
        }
        Thumbnail { width, height, rgb }
    }

    /// From an 8-bit RGBA image (a PNG already on disk), nearest-sampled.
    pub fn from_rgba8(width: u32, height: u32, pixels: &[[u8; 4]]) -> Self {
        let (tw, th, factor) = fit(width, height);
        let mut rgb = Vec::with_capacity((tw * th) as usize);
        for ty in 0..th {
            for tx in 0..tw {
                let x = (tx * factor + factor / 2).min(width.saturating_sub(1));
                let y = (ty * factor + factor / 2).min(height.saturating_sub(1));
                let p = pixels
                    .get((y * width + x) as usize)
                    .copied()
                    .unwrap_or([0; 4]);
                let a = f32::from(p[3]) / 255.0;
                rgb.push(std::array::from_fn(|c| {
                    (f32::from(p[c]) * a + f32::from(BACKDROP[c]) * (1.0 - a)).round() as u8
                }));
            }
        }
        Thumbnail {
            width: tw,
            height: th,
            rgb,
        }
    }
}

/// Thumbnail size and the integer downsampling factor that makes the longer side ≤ TILE.
fn fit(width: u32, height: u32) -> (u32, u32, u32) {
    let factor = width.max(height).div_ceil(TILE).max(1);
    ((width / factor).max(1), (height / factor).max(1), factor)
}

/// One tile: its image (None for a failed job) and its label lines.
pub struct Tile {
    pub image: Option<Thumbnail>,
    pub lines: Vec<String>,
}

fn ensure_font() -> Result<()> {
    static REGISTERED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            register_font(FONT_FAMILY, FontStyle::Normal, FONT)
                .map_err(|_| "the embedded DejaVu Sans font did not parse".to_string())
        })
        .clone()
        .map_err(|message| Error::Write {
            path: "contact_sheet.png".into(),
            message,
        })
}

/// The sheet as PNG bytes: tiles in rows of ⌈√n⌉, labels under each.
pub fn contact_sheet_png(tiles: &[Tile]) -> Result<Vec<u8>> {
    ensure_font()?;
    let n = tiles.len().max(1) as u32;
    let columns = (n as f64).sqrt().ceil() as u32;
    let rows = n.div_ceil(columns);
    let label_lines = tiles.iter().map(|t| t.lines.len()).max().unwrap_or(0) as u32;
    let cell_w = TILE + GAP;
    let cell_h = TILE + label_lines * LINE_HEIGHT + 2 * GAP;
    let (width, height) = (columns * cell_w + GAP, rows * cell_h + GAP);
    let mut pixels = vec![255u8; (width * height * 3) as usize];
    let origin = |k: u32| (GAP + (k % columns) * cell_w, GAP + (k / columns) * cell_h);
    for (k, tile) in tiles.iter().enumerate() {
        let (x0, y0) = origin(k as u32);
        if let Some(image) = &tile.image {
            for y in 0..image.height {
                for x in 0..image.width {
                    let at = (((y0 + y) * width + x0 + x) * 3) as usize;
                    pixels[at..at + 3].copy_from_slice(&image.rgb[(y * image.width + x) as usize]);
                }
            }
        }
    }
    let failed = |e: String| Error::Write {
        path: "contact_sheet.png".into(),
        message: e,
    };
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
        let style = TextStyle::from((FONT_FAMILY, FONT_SIZE).into_font()).color(&BLACK);
        let red = TextStyle::from((FONT_FAMILY, FONT_SIZE).into_font()).color(&RED);
        for (k, tile) in tiles.iter().enumerate() {
            let (x0, y0) = origin(k as u32);
            let text_top = y0 + tile.image.as_ref().map_or(TILE, |i| i.height) + 4;
            for (line, text) in tile.lines.iter().enumerate() {
                let style = if tile.image.is_none() { &red } else { &style };
                root.draw_text(
                    text,
                    style,
                    (x0 as i32, (text_top + line as u32 * LINE_HEIGHT) as i32),
                )
                .map_err(|e| failed(e.to_string()))?;
            }
        }
        root.present().map_err(|e| failed(e.to_string()))?;
    }
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &pixels,
        width,
        height,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| failed(e.to_string()))?;
    Ok(png)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thumbnail_of_uniform_grey_keeps_its_srgb_value() {
        // Radiance 0.2140 with no tone curve → sRGB 0.5 → 128 (IEC 61966-2-1: 0.5 encodes 0.2140).
        let mut image = HdrImage::new(400, 200);
        image.pixels.fill([0.214, 0.214, 0.214, 1.0]);
        let png = PngSettings {
            exposure_ev: 0.0,
            tone_curve: crate::output::ToneCurve::None,
        };
        let t = Thumbnail::from_hdr(&image, &png);
        assert_eq!((t.width, t.height), (133, 66)); // factor ⌈400/192⌉ = 3
        assert!(t
            .rgb
            .iter()
            .all(|p| p.iter().all(|&c| (127..=128).contains(&c))));
    }

    #[test]
    fn sheet_has_a_cell_per_tile() {
        let tile = || Tile {
            image: Some(Thumbnail {
                width: 10,
                height: 10,
                rgb: vec![[255, 0, 0]; 100],
            }),
            lines: vec!["r=1".into(), "orbit=45".into()],
        };
        let png = contact_sheet_png(&[tile(), tile(), tile()]).unwrap();
        let (w, h, px) = crate::output::png::decode_png_rgba8(&png).unwrap();
        // 3 tiles → 2 columns, 2 rows (hand layout with the constants above).
        assert_eq!(w, 2 * (TILE + GAP) + GAP);
        assert_eq!(h, 2 * (TILE + 2 * LINE_HEIGHT + 2 * GAP) + GAP);
        assert_eq!(px[(GAP * w + GAP) as usize], [255, 0, 0, 255]);
    }
}
