//! Text on pictures meant for people (prefilter preview, contact sheets, plots): DejaVu Sans,
//! embedded from assets/fonts (licence beside it) and registered with plotters' ab_glyph backend
//! once, so no system font is needed.

use crate::{Error, Result};
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use std::sync::OnceLock;

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// The family name to ask plotters for.
pub const FONT_FAMILY: &str = "sans-serif";

/// Registers the embedded font once; later calls return the first result.
pub fn ensure_font() -> Result<()> {
    static REGISTERED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            register_font(FONT_FAMILY, FontStyle::Normal, FONT)
                .map_err(|_| "the embedded DejaVu Sans font did not parse".to_string())
        })
        .clone()
        .map_err(|message| Error::Write {
            path: "font".into(),
            message,
        })
}

/// A label: top-left position in pixels, text, size in pixels, colour.
pub struct Label<'a> {
    pub x: i32,
    pub y: i32,
    pub text: &'a str,
    pub size: u32,
    pub rgb: [u8; 3],
}

/// Draws `labels` onto an RGB8 picture (row 0 at the top), in place.
pub fn draw_labels(rgb: &mut [u8], width: u32, height: u32, labels: &[Label<'_>]) -> Result<()> {
    ensure_font()?;
    let failed = |message: String| Error::Write {
        path: "label".into(),
        message,
    };
    if rgb.len() != (width as usize) * (height as usize) * 3 {
        return Err(failed(format!(
            "picture buffer of {} bytes is not {width}×{height}×3",
            rgb.len()
        )));
    }
    let root = BitMapBackend::with_buffer(rgb, (width, height)).into_drawing_area();
    for label in labels {
        let [r, g, b] = label.rgb;
        let style = (FONT_FAMILY, label.size)
            .into_font()
            .color(&RGBColor(r, g, b));
        root.draw_text(label.text, &style, (label.x, label.y))
            .map_err(|e| failed(e.to_string()))?;
    }
    root.present().map_err(|e| failed(e.to_string()))
}

/// RGB8 → PNG bytes.
pub fn encode_rgb8_png(rgb: &[u8], width: u32, height: u32) -> Result<Vec<u8>> {
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        rgb,
        width,
        height,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| Error::Write {
        path: "png".into(),
        message: e.to_string(),
    })?;
    Ok(png)
}
