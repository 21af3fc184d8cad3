//! `preview.png` of `shikki prefilter`: every layer's six faces in a row, one row per layer, the
//! irradiance last, tone-mapped for a person to look at.

use super::image::{CubeImage, PrefilteredEnvironment};
use crate::output::{self, HdrImage, PngSettings};
use crate::Result;

/// Width of one face in the preview, whatever its stored size (nearest-texel magnification, so
/// coarse layers show their real resolution).
const TILE: u32 = 128;
const GAP: u32 = 4;

/// The preview as PNG bytes.
pub fn preview_image(env: &PrefilteredEnvironment) -> Result<Vec<u8>> {
    let rows: Vec<&CubeImage> = env
        .layers
        .iter()
        .chain(std::iter::once(&env.irradiance))
        .collect();
    let width = 6 * TILE + 7 * GAP;
    let height = rows.len() as u32 * (TILE + GAP) + GAP;
    let mut image = HdrImage::new(width, height);
    for pixel in &mut image.pixels {
        *pixel = [0.02, 0.02, 0.02, 1.0];
    }
    for (row, cube) in rows.iter().enumerate() {
        // The irradiance is π × radiance: show it on the same scale as the layers.
        let scale = if row + 1 == rows.len() {
            1.0 / std::f32::consts::PI
        } else {
            1.0
        };
        let top = GAP + row as u32 * (TILE + GAP);
        for face in 0..6 {
            let left = GAP + face as u32 * (TILE + GAP);
            for y in 0..TILE {
                for x in 0..TILE {
                    let i = x * cube.face_size / TILE;
                    let j = y * cube.face_size / TILE;
                    let t = cube.get(face, i, j);
                    image.set(
                        left + x,
                        top + y,
                        [t[0] * scale, t[1] * scale, t[2] * scale, 1.0],
                    );
                }
            }
        }
    }
    output::png::encode_png(&image, &PngSettings::default())
}
