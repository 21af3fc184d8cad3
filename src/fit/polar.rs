//! The plotting plumbing of the report: the embedded font, a PNG canvas, a palette, and the
//! polar panel of the paper's Figs. 1–4 (θ_o as the angle from the normal, straight up, the
//! mirror side to the right; reflectance as the radius, linear or in decades).
//!
//! Owns only drawing; [`super::plots`] decides what is drawn. Text uses DejaVu Sans embedded from
//! assets/fonts (its licence is beside it), registered with plotters' ab_glyph backend, so no
//! system font is needed.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::{Error, Result};

/// What a drawing closure returns; plotters' errors convert into it with `?`.
pub type PlotResult = std::result::Result<(), Box<dyn std::error::Error>>;
/// A drawing area on the in-memory bitmap.
pub type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// The family name the plots ask for (the embedded font of `output::text`).
pub use crate::output::text::FONT_FAMILY;

/// Colours for boards and channels (Okabe–Ito, readable by colour-blind viewers).
pub const PALETTE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
];

/// The linear-RGB channels' colours in plots.
pub const CHANNEL_COLOURS: [RGBColor; 3] = [
    RGBColor(200, 30, 30),
    RGBColor(20, 150, 40),
    RGBColor(30, 60, 210),
];

/// Draws `width` × `height` pixels with `draw` on a white canvas and encodes them as PNG.
pub fn render_png(
    name: &str,
    (width, height): (u32, u32),
    draw: impl FnOnce(&Area) -> PlotResult,
) -> Result<Vec<u8>> {
    crate::output::text::ensure_font()?;
    let failed = |message: String| Error::Write {
        path: name.into(),
        message,
    };
    let mut pixels = vec![0u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| failed(e.to_string()))?;
        draw(&root).map_err(|e| failed(e.to_string()))?;
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

/// A text style of the embedded font.
pub fn font(size: u32) -> TextStyle<'static> {
    (FONT_FAMILY, size).into_font().color(&BLACK)
}

/// How reflectance maps to the radius [0, 1].
#[derive(Clone, Copy, Debug)]
pub enum RadialScale {
    /// r = value / max.
    Linear { max: f64 },
    /// r = log10(value / min) / decades; values ≤ min sit at the centre.
    Decades { min: f64, decades: f64 },
}

impl RadialScale {
    /// The log scale of values in [min, max], widened to whole decades, at most `limit` of them.
    pub fn decades(min: f64, max: f64, limit: f64) -> Self {
        let top = max.max(f64::MIN_POSITIVE).log10().ceil();
        let bottom = min.max(f64::MIN_POSITIVE).log10().floor().max(top - limit);
        RadialScale::Decades {
            min: 10f64.powf(bottom),
            decades: (top - bottom).max(1.0),
        }
    }

    pub fn radius(&self, value: f64) -> f64 {
        match *self {
            RadialScale::Linear { max } => (value / max).clamp(0.0, 1.05),
            RadialScale::Decades { min, decades } => {
                if value <= min {
                    0.0
                } else {
                    ((value / min).log10() / decades).min(1.05)
                }
            }
        }
    }

    /// Grid circles: (value, label).
    fn rings(&self) -> Vec<(f64, String)> {
        match *self {
            RadialScale::Linear { max } => (1..=4)
                .map(|i| {
                    let v = max * f64::from(i) / 4.0;
                    (v, format!("{v:.3}"))
                })
                .collect(),
            RadialScale::Decades { min, decades } => (1..=decades as i32)
                .map(|k| {
                    let exponent = min.log10().round() as i32 + k;
                    let v = 10f64.powi(exponent);
                    let label = if (-3..=3).contains(&exponent) {
                        format!("{v}")
                    } else {
                        format!("1e{exponent}")
                    };
                    (v, label)
                })
                .collect(),
        }
    }
}

/// One thing drawn in a polar panel: (θ_o in degrees, value) pairs.
pub struct PolarSeries {
    pub points: Vec<(f64, f64)>,
    pub colour: RGBColor,
    /// Markers (measured) or a line (fitted).
    pub markers: bool,
}

/// A polar panel: the upper half-plane, spokes every 30°, rings at the scale's values, the
/// light's direction (at −θ_i) drawn in grey, then the series.
pub fn polar_panel(
    area: &Area,
    title: &str,
    scale: RadialScale,
    theta_i_deg: Option<f64>,
    series: &[PolarSeries],
) -> PlotResult {
    let mut chart = ChartBuilder::on(area)
        .caption(title, font(16))
        .margin(6)
        .build_cartesian_2d(-1.2f64..1.2f64, -0.12f64..1.15f64)?;
    let xy = |deg: f64, r: f64| {
        let t = deg.to_radians();
        (r * t.sin(), r * t.cos())
    };
    let grey = RGBColor(190, 190, 190);
    for (value, label) in scale.rings() {
        let r = scale.radius(value);
        let ring: Vec<(f64, f64)> = (-90..=90).map(|d| xy(f64::from(d), r)).collect();
        chart.draw_series(LineSeries::new(ring, grey))?;
        chart.draw_series(std::iter::once(Text::new(
            label,
            (r - 0.04, -0.03),
            font(11),
        )))?;
    }
    for spoke in (-90..=90).step_by(30) {
        let d = f64::from(spoke);
        chart.draw_series(LineSeries::new([(0.0, 0.0), xy(d, 1.0)], grey))?;
        let (x, y) = xy(d, 1.1);
        chart.draw_series(std::iter::once(Text::new(
            format!("{spoke}°"),
            (x - 0.06, y + 0.03),
            font(11),
        )))?;
    }
    if let Some(theta_i) = theta_i_deg {
        let light = RGBColor(150, 150, 150);
        chart.draw_series(LineSeries::new(
            [(0.0, 0.0), xy(-theta_i, 1.0)],
            light.stroke_width(2),
        ))?;
    }
    for s in series {
        let points: Vec<(f64, f64)> = s
            .points
            .iter()
            .map(|&(deg, v)| xy(deg, scale.radius(v)))
            .collect();
        if s.markers {
            let style = s.colour.mix(0.7).filled();
            chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, style)))?;
        } else {
            chart.draw_series(LineSeries::new(points, s.colour.stroke_width(1)))?;
        }
    }
    Ok(())
}

/// Coloured legend lines in the area's top-left corner.
pub fn legend(area: &Area, entries: &[(String, RGBColor)]) -> PlotResult {
    for (i, (label, colour)) in entries.iter().enumerate() {
        let y = 30 + 18 * i as i32;
        area.draw(&Circle::new((14, y + 7), 5, colour.filled()))?;
        area.draw(&Text::new(label.clone(), (24, y), font(13)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decade_scale_maps_whole_decades() {
        // Values 0.003..4 → decades 1e-3..1e1 (4 decades): 0.01 sits at 1/4, 1 at 3/4.
        let s = RadialScale::decades(0.003, 4.0, 6.0);
        assert!((s.radius(0.01) - 0.25).abs() < 1e-12 && (s.radius(1.0) - 0.75).abs() < 1e-12);
        assert_eq!(s.radius(1e-5), 0.0);
        // A limit of 2 decades keeps the top: 1e-1..1e1.
        let s = RadialScale::decades(0.003, 4.0, 2.0);
        assert!((s.radius(1.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn renders_a_png_with_text() {
        let png = render_png("t", (200, 120), |area| {
            polar_panel(
                area,
                "θ_i = 30°",
                RadialScale::Linear { max: 1.0 },
                Some(30.0),
                &[PolarSeries {
                    points: vec![(0.0, 0.5), (30.0, 0.8)],
                    colour: PALETTE[0],
                    markers: true,
                }],
            )
        })
        .unwrap();
        // The PNG signature, then decodable at the requested size.
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        let (w, h, pixels) = crate::output::png::decode_png_rgba8(&png).unwrap();
        assert_eq!((w, h), (200, 120));
        // Something other than white was drawn (rings, text, markers).
        assert!(pixels.iter().any(|p| p[..3] != [255, 255, 255]));
    }
}
