//! Output: the read-back [`HdrImage`] → file. EXR holds linear radiance (SPEC §1); PNG is
//! radiance × 2^exposure_ev → tone curve → sRGB → 8 bits. Files are encoded fully in memory and
//! written atomically. This module owns formats, the display transform and file replacement; it
//! never renders, never touches the GPU, and never changes pixel values on the EXR path.
//!
//! The order a renderer follows:
//! 1. [`preflight_output`] before any rendering, so a bad path fails in a second, not after the
//!    render;
//! 2. render, read back into an [`HdrImage`];
//! 3. [`write_image`]. If the run fails anywhere after step 1, a file already at the path is
//!    removed ([`atomic::discard_stale_output`]; [`write_image`] does it itself), so a failed run
//!    never leaves the previous run's image looking like its own.

pub mod atomic;
pub mod exr;
pub mod image;
pub mod png;
pub mod text;
pub mod tonemap;

use std::path::Path;

pub use self::image::HdrImage;
pub use self::tonemap::{PngSettings, ToneCurve};
use crate::{Error, Result};

/// The file formats shikki writes, chosen by the output path's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// 8-bit sRGB, tone-mapped, straight alpha.
    Png,
    /// Linear float32 RGBA radiance, premultiplied alpha.
    Exr,
}

impl OutputFormat {
    /// By extension, case-insensitive: `.png` or `.exr`. Anything else is an error naming the
    /// path and the valid extensions.
    pub fn from_path(path: &Path) -> Result<Self> {
        let extension = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match extension.as_deref() {
            Some("png") => Ok(OutputFormat::Png),
            Some("exr") => Ok(OutputFormat::Exr),
            _ => Err(Error::invalid(
                "output path",
                path.display(),
                "the file name must end in .png (8-bit sRGB after exposure and tone curve) or \
                 .exr (linear float32 radiance)",
            )),
        }
    }
}

/// Checks before any rendering that `path` has a known extension and that its directory exists and
/// is writable (create and delete a temp file there), so a long render never fails at the end for a
/// reason known at the start. Error names the path and the fix.
///
/// Nothing at `path` is touched: a previous file stays until [`write_image`] replaces it (or
/// removes it because this run failed).
pub fn preflight_output(path: &Path) -> Result<OutputFormat> {
    let format = OutputFormat::from_path(path)?;
    atomic::probe_directory(path).map_err(|message| Error::Write {
        path: path.to_path_buf(),
        message: format!("{message} (checked before rendering; nothing was rendered)"),
    })?;
    Ok(format)
}

/// Encode fully in memory, then write_atomically. Non-finite pixels are an error (name the first
/// pixel's coordinates) — never write NaN.
///
/// The format comes from the extension ([`OutputFormat::from_path`]); `settings` apply to PNG
/// only, since EXR holds radiance as rendered. The arguments are checked first (the path's
/// extension, the image, the settings): an invalid one is an [`Error::InvalidParameter`] and
/// leaves `path` as it was. A failure after that removes a previous file at `path` and says so
/// in the error (stale-file policy in [`atomic`]).
pub fn write_image(path: &Path, image: &HdrImage, settings: &PngSettings) -> Result<()> {
    let encoded = OutputFormat::from_path(path).and_then(|format| match format {
        OutputFormat::Png => png::encode_png(image, settings),
        OutputFormat::Exr => exr::encode_exr(image),
    });
    match encoded {
        Ok(bytes) => atomic::write_atomically(path, &bytes),
        // The extension and the encoders' own checks of the image and settings: the caller's
        // arguments, refused with `path` as it was.
        Err(invalid @ Error::InvalidParameter { .. }) => Err(invalid),
        Err(cause) => Err(atomic::failed_write(path, &cause.to_string())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn format_follows_the_extension_case_insensitively() {
        let cases = [
            ("out.png", OutputFormat::Png),
            ("dir/OUT.PNG", OutputFormat::Png),
            ("a.b.Exr", OutputFormat::Exr),
            ("/tmp/x.exr", OutputFormat::Exr),
        ];
        for (path, format) in cases {
            assert_eq!(OutputFormat::from_path(Path::new(path)).unwrap(), format);
        }
    }

    #[test]
    fn unknown_extensions_are_rejected_naming_the_path_and_the_choices() {
        for path in ["render.jpg", "render", "render.png.bak", ".png"] {
            let message = OutputFormat::from_path(Path::new(path))
                .unwrap_err()
                .to_string();
            assert!(message.contains(path), "{message}");
            assert!(
                message.contains(".png") && message.contains(".exr"),
                "{message}"
            );
        }
    }

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("shikki-output-mod-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn preflight_rejects_bad_extension_and_missing_directory_and_creates_nothing() {
        let dir = scratch("preflight");
        let jpg = preflight_output(&dir.join("out.jpg"))
            .unwrap_err()
            .to_string();
        assert!(jpg.contains("out.jpg") && jpg.contains(".exr"), "{jpg}");
        let missing = preflight_output(&dir.join("nope").join("out.png"))
            .unwrap_err()
            .to_string();
        assert!(missing.contains("does not exist"), "{missing}");
        assert!(missing.contains("before rendering"), "{missing}");
        assert_eq!(
            preflight_output(&dir.join("out.EXR")).unwrap(),
            OutputFormat::Exr
        );
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn preflight_leaves_an_existing_output_alone() {
        let dir = scratch("preflight-existing");
        let path = dir.join("out.png");
        std::fs::write(&path, b"old").unwrap();
        assert_eq!(preflight_output(&path).unwrap(), OutputFormat::Png);
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn invalid_arguments_are_refused_naming_them_and_leave_the_path_alone() {
        // A NaN pixel or exposure is the caller's argument, refused before the path is touched
        // (the CLI and the C API remove a stale output themselves when a render fails).
        let dir = scratch("nan");
        for name in ["out.png", "out.exr"] {
            let path = dir.join(name);
            std::fs::write(&path, b"previous run").unwrap();
            let mut image = HdrImage::new(4, 4);
            image.set(3, 2, [0.0, f32::NAN, 0.0, 1.0]);
            let error = write_image(&path, &image, &PngSettings::default()).unwrap_err();
            assert!(matches!(error, Error::InvalidParameter { .. }), "{error}");
            let message = error.to_string();
            assert!(message.contains("pixel (3, 2)"), "{message}");
            assert!(
                !message.contains("nothing was written; nothing"),
                "{message}"
            );
            assert_eq!(std::fs::read(&path).unwrap(), b"previous run", "{name}");
        }
        let path = dir.join("out.png");
        let settings = PngSettings {
            exposure_ev: f32::NAN,
            tone_curve: ToneCurve::Aces,
        };
        let error = write_image(&path, &HdrImage::new(2, 2), &settings).unwrap_err();
        assert!(matches!(error, Error::InvalidParameter { .. }), "{error}");
        assert_eq!(std::fs::read(&path).unwrap(), b"previous run");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn write_image_picks_the_encoder_from_the_extension() {
        let dir = scratch("dispatch");
        let mut image = HdrImage::new(2, 1);
        image.set(0, 0, [4.0, 0.5, 0.0, 1.0]);
        let settings = PngSettings {
            exposure_ev: 0.0,
            tone_curve: ToneCurve::None,
        };
        write_image(&dir.join("a.PNG"), &image, &settings).unwrap();
        write_image(&dir.join("a.exr"), &image, &settings).unwrap();
        let (_, _, png_pixels) =
            png::decode_png_rgba8(&std::fs::read(dir.join("a.PNG")).unwrap()).unwrap();
        // 4.0 clamps to 255 with no curve; 0.5 → sRGB 0.7353569 → 188 (hand values, tonemap.rs).
        assert_eq!(png_pixels[0], [255, 188, 0, 255]);
        let exr_image = exr::decode_exr(&std::fs::read(dir.join("a.exr")).unwrap()).unwrap();
        // EXR is linear radiance: the 4.0 survives untouched.
        assert_eq!(exr_image, image);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
