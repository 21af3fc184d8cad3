//! The in-memory HDR image every renderer path hands to `output/`: linear radiance, RGBA `f32`,
//! row 0 at the top (SPEC §1). Owns the pixel layout and the checks that an image is fit to be
//! encoded (consistent size, finite values). It knows nothing of files, tone curves or the GPU.

use crate::{Error, Result};

/// Linear radiance, RGBA f32, alpha = coverage; row 0 is the TOP row (SPEC §1).
/// Colour is premultiplied by coverage (it is the MSAA-resolved average of covered samples'
/// radiance over a transparent black background), as EXR expects.
///
/// `pixels` is row-major: pixel (x, y) is `pixels[y · width + x]`.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

impl HdrImage {
    /// A `width × height` image of transparent black (no coverage, no radiance).
    pub fn new(width: u32, height: u32) -> Self {
        let count = width as usize * height as usize;
        HdrImage {
            width,
            height,
            pixels: vec![[0.0; 4]; count],
        }
    }

    /// The pixel at column `x`, row `y` (row 0 is the top).
    ///
    /// # Panics
    /// If (x, y) is outside the image, like slice indexing: coordinates come from code, not input.
    pub fn get(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[self.index(x, y)]
    }

    /// Sets the pixel at column `x`, row `y` (row 0 is the top).
    ///
    /// # Panics
    /// If (x, y) is outside the image, like slice indexing: coordinates come from code, not input.
    pub fn set(&mut self, x: u32, y: u32, rgba: [f32; 4]) {
        let index = self.index(x, y);
        self.pixels[index] = rgba;
    }

    fn index(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) is outside the {}×{} image",
            self.width,
            self.height
        );
        y as usize * self.width as usize + x as usize
    }

    /// The first pixel, in row-major order from the top-left, with a NaN or infinite channel.
    pub fn first_non_finite(&self) -> Option<(u32, u32)> {
        let width = self.width.max(1) as usize;
        self.pixels
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
            .map(|i| ((i % width) as u32, (i / width) as u32))
    }

    /// Checks what every encoder needs: a non-empty image whose pixel count matches its size
    /// (the fields are public, so this cannot be an invariant) and no NaN or infinity, which
    /// would otherwise be written into an EXR or silently become black in a PNG.
    pub fn validate_for_encoding(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::invalid(
                "image size",
                format!("{}×{}", self.width, self.height),
                "width and height must both be at least 1 pixel",
            ));
        }
        let expected = self.width as u64 * self.height as u64;
        if self.pixels.len() as u64 != expected {
            return Err(Error::invalid(
                "image pixels",
                self.pixels.len(),
                format!(
                    "a {}×{} image needs exactly {expected} pixels (row-major, top row first)",
                    self.width, self.height
                ),
            ));
        }
        if let Some((x, y)) = self.first_non_finite() {
            let [r, g, b, a] = self.get(x, y);
            return Err(Error::invalid(
                format!("pixel ({x}, {y})"),
                format!("({r}, {g}, {b}, {a})"),
                "every channel must be finite (no NaN or infinity); from a render, a \
                 non-finite pixel is a bug: please report it with the scene",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn new_image_is_transparent_black_of_the_right_size() {
        let image = HdrImage::new(3, 2);
        assert_eq!(image.pixels.len(), 6);
        assert!(image.pixels.iter().all(|p| *p == [0.0; 4]));
    }

    #[test]
    fn set_and_get_use_row_major_top_row_first_layout() {
        let mut image = HdrImage::new(3, 2);
        image.set(2, 0, [1.0, 2.0, 3.0, 1.0]);
        image.set(0, 1, [4.0, 5.0, 6.0, 0.5]);
        // (2, 0) is the last pixel of the top row: index 2; (0, 1) starts row 1: index 3.
        assert_eq!(image.pixels[2], [1.0, 2.0, 3.0, 1.0]);
        assert_eq!(image.pixels[3], [4.0, 5.0, 6.0, 0.5]);
        assert_eq!(image.get(2, 0), [1.0, 2.0, 3.0, 1.0]);
        assert_eq!(image.get(0, 1), [4.0, 5.0, 6.0, 0.5]);
    }

    #[test]
    #[should_panic(expected = "outside")]
    fn get_outside_the_image_panics_with_the_coordinates() {
        HdrImage::new(2, 2).get(2, 0);
    }

    #[test]
    fn first_non_finite_names_the_first_bad_pixel_in_row_major_order() {
        let mut image = HdrImage::new(4, 3);
        assert_eq!(image.first_non_finite(), None);
        image.set(1, 2, [0.0, f32::INFINITY, 0.0, 1.0]);
        image.set(3, 1, [0.0, 0.0, 0.0, f32::NAN]);
        assert_eq!(image.first_non_finite(), Some((3, 1)));
    }

    #[test]
    fn validation_rejects_empty_mismatched_and_non_finite_images() {
        assert!(HdrImage::new(0, 5).validate_for_encoding().is_err());
        let mut short = HdrImage::new(2, 2);
        short.pixels.pop();
        let message = short.validate_for_encoding().unwrap_err().to_string();
        assert!(message.contains("exactly 4 pixels"), "{message}");
        let mut nan = HdrImage::new(2, 2);
        nan.set(1, 1, [f32::NAN, 0.0, 0.0, 1.0]);
        let message = nan.validate_for_encoding().unwrap_err().to_string();
        assert!(message.contains("pixel (1, 1)"), "{message}");
        assert!(HdrImage::new(2, 2).validate_for_encoding().is_ok());
    }
}
