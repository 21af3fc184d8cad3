//! `preview.png` of `shikki prefilter`: every layer's six faces in a row (+X −X +Y −Y +Z −Z), one
//! row per layer labelled with k, β and its face size, the irradiance last, tone-mapped (ACES,
//! 0 EV) for a person to look at.

use super::image::{CubeImage, PrefilteredEnvironment};
use crate::output::text::{draw_labels, encode_rgb8_png, Label};
use crate::output::tonemap::{to_srgb8, PngSettings};
use crate::Result;

/// Width of one face in the preview, whatever its stored size (nearest-texel magnification, so
/// coarse layers show their real resolution).
const TILE: u32 = 128;
const GAP: u32 = 4;
/// Room for the row labels on the left and the face names on top.
const LEFT: u32 = 150;
const TOP: u32 = 24;
const FACE_NAMES: [&str; 6] = ["+X", "-X", "+Y", "-Y", "+Z", "-Z"];

/// The preview as PNG bytes.
pub fn preview_image(env: &PrefilteredEnvironment) -> Result<Vec<u8>> {
    let rows: Vec<(&CubeImage, String)> = env
        .layers
        .iter()
        .enumerate()
        .map(|(k, cube)| {
            let beta = env.betas.get(k).copied().unwrap_or(0.0);
            (cube, format!("layer {k}  β {beta:.3}"))
        })
        .chain(std::iter::once((
            &env.irradiance,
            "irradiance / π".to_string(),
        )))
        .collect();
    let width = LEFT + 6 * (TILE + GAP);
    let height = TOP + rows.len() as u32 * (TILE + GAP);
    let mut rgb = vec![24u8; (width * height * 3) as usize];
    let settings = PngSettings::default();
    let last = rows.len() - 1;
    let mut labels = Vec::new();
    for (row, (cube, text)) in rows.iter().enumerate() {
        // The irradiance is π × a radiance: show it on the layers' scale.
        let scale = if row == last {
            1.0 / std::f32::consts::PI
        } else {
            1.0
        };
        let top = TOP + row as u32 * (TILE + GAP);
        for face in 0..6 {
            let left = LEFT + face as u32 * (TILE + GAP);
            for y in 0..TILE {
                for x in 0..TILE {
                    let t = cube.get(face, x * cube.face_size / TILE, y * cube.face_size / TILE);
                    let at = (((top + y) * width + left + x) * 3) as usize;
                    for c in 0..3 {
                        rgb[at + c] = to_srgb8(t[c] * scale, &settings);
                    }
                }
            }
        }
        labels.push((row, top, text.clone(), cube.face_size));
    }
    let owned: Vec<(i32, i32, String)> = labels
        .iter()
        .flat_map(|(_, top, text, face)| {
            [
                (8, *top as i32 + 40, text.clone()),
                (8, *top as i32 + 62, format!("face {face}²")),
            ]
        })
        .chain(FACE_NAMES.iter().enumerate().map(|(f, name)| {
            (
                (LEFT + f as u32 * (TILE + GAP) + TILE / 2 - 8) as i32,
                4,
                name.to_string(),
            )
        }))
        .collect();
    let labels: Vec<Label<'_>> = owned
        .iter()
        .map(|(x, y, text)| Label {
            x: *x,
            y: *y,
            text,
            size: 16,
            rgb: [230, 230, 230],
        })
        .collect();
    draw_labels(&mut rgb, width, height, &labels)?;
    encode_rgb8_png(&rgb, width, height)
}
