//! Files written by `shikki::output`, read back with the format crates directly (not with our
//! own decoders), so a convention error that our encoder and decoder share cannot hide: row 0 is
//! the top (SPEC §1), EXR is linear float32 with alpha, PNG is straight-alpha sRGB8, identical
//! inputs give identical files, and failed writes leave nothing behind.

use std::fs;
use std::path::{Path, PathBuf};

use shikki::output::{
    preflight_output, write_image, HdrImage, OutputFormat, PngSettings, ToneCurve,
};

/// A fresh empty directory for one test under Cargo's per-target scratch directory.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("output_roundtrip")
        .join(name);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

const RED: [f32; 4] = [1.0, 0.0, 0.0, 1.0];
const BLUE: [f32; 4] = [0.0, 0.0, 1.0, 1.0];

/// 3 × 2: the top row red, the bottom row blue, with one half-covered HDR pixel bottom-right.
fn red_over_blue() -> HdrImage {
    let mut image = HdrImage::new(3, 2);
    for x in 0..3 {
        image.set(x, 0, RED);
        image.set(x, 1, BLUE);
    }
    // Premultiplied: radiance 6.5 at coverage 0.5.
    image.set(2, 1, [3.25, 0.125, 0.0, 0.5]);
    image
}

const LINEAR: PngSettings = PngSettings {
    exposure_ev: 0.0,
    tone_curve: ToneCurve::None,
};

#[test]
fn exr_first_row_in_the_file_is_the_top_row_and_values_are_exact() {
    let dir = scratch("exr-rows");
    let path = dir.join("rows.exr");
    let image = red_over_blue();
    write_image(&path, &image, &PngSettings::default()).unwrap();

    let read = exr::prelude::read_first_rgba_layer_from_file(
        &path,
        |resolution, _| vec![[0.0f32; 4]; resolution.width() * resolution.height()],
        |pixels: &mut Vec<[f32; 4]>, position, (r, g, b, a): (f32, f32, f32, f32)| {
            pixels[position.y() * 3 + position.x()] = [r, g, b, a];
        },
    )
    .unwrap();
    let header = &read.layer_data;
    assert_eq!(header.size.width(), 3);
    assert_eq!(header.size.height(), 2);
    // OpenEXR: y grows downward and the data window's first scan line (y = 0 here) is the top.
    assert_eq!(header.attributes.layer_position, exr::math::Vec2(0, 0));
    let pixels = &header.channel_data.pixels;
    assert_eq!(
        &pixels[0..3],
        &[RED; 3],
        "file row 0 must be the image's top (red) row"
    );
    assert_eq!(&pixels[3..5], &[BLUE; 2]);
    // No exposure, no tone curve, alpha kept: the HDR value and coverage survive bit for bit.
    assert_eq!(pixels[5], [3.25, 0.125, 0.0, 0.5]);

    // The channels are stored as float32, not half.
    let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
    let channels = &meta.headers[0].channels.list;
    assert_eq!(channels.len(), 4);
    for channel in channels {
        assert_eq!(channel.sample_type, exr::meta::attribute::SampleType::F32);
    }
}

#[test]
fn png_first_row_in_the_file_is_the_top_row_with_straight_alpha() {
    let dir = scratch("png-rows");
    let path = dir.join("rows.png");
    write_image(&path, &red_over_blue(), &LINEAR).unwrap();

    let decoded = image::open(&path).unwrap().to_rgba8();
    assert_eq!(decoded.dimensions(), (3, 2));
    for x in 0..3 {
        assert_eq!(decoded.get_pixel(x, 0).0, [255, 0, 0, 255], "top row red");
    }
    assert_eq!(decoded.get_pixel(0, 1).0, [0, 0, 255, 255]);
    // Straight alpha: 3.25/0.5 = 6.5 clips to 255; 0.125/0.5 = 0.25 → sRGB 1.055·0.25^(1/2.4) −
    // 0.055 = 0.537099… → 136.96 → 137; alpha 0.5 → 127.5 → 128.
    assert_eq!(decoded.get_pixel(2, 1).0, [255, 137, 0, 128]);
}

#[test]
fn identical_inputs_give_bit_identical_files() {
    let dir = scratch("determinism");
    let mut image = HdrImage::new(64, 48);
    for y in 0..48 {
        for x in 0..64 {
            let t = (x * 48 + y) as f32;
            image.set(
                x,
                y,
                [(t * 0.013).sin().abs() * 300.0, t / 3072.0, 0.02, 1.0],
            );
        }
    }
    let settings = PngSettings {
        exposure_ev: -1.5,
        tone_curve: ToneCurve::Aces,
    };
    for extension in ["png", "exr"] {
        let first = dir.join(format!("first.{extension}"));
        let second = dir.join(format!("second.{extension}"));
        write_image(&first, &image, &settings).unwrap();
        write_image(&second, &image.clone(), &settings).unwrap();
        assert_eq!(
            fs::read(&first).unwrap(),
            fs::read(&second).unwrap(),
            "{extension}"
        );
    }
}

#[test]
fn writing_into_a_missing_directory_fails_clearly_and_leaves_no_file() {
    let dir = scratch("missing-dir");
    let path = dir.join("absent").join("out.png");
    let message = write_image(&path, &red_over_blue(), &LINEAR)
        .unwrap_err()
        .to_string();
    assert!(message.contains("out.png"), "{message}");
    assert!(message.contains("does not exist"), "{message}");
    assert_eq!(
        fs::read_dir(&dir).unwrap().count(),
        0,
        "no temp file either"
    );
}

#[test]
fn preflight_rejects_jpg_and_accepts_png_and_exr() {
    let dir = scratch("preflight");
    let message = preflight_output(&dir.join("render.jpg"))
        .unwrap_err()
        .to_string();
    assert!(message.contains("render.jpg"), "{message}");
    assert!(
        message.contains(".png") && message.contains(".exr"),
        "{message}"
    );
    assert_eq!(
        preflight_output(&dir.join("r.png")).unwrap(),
        OutputFormat::Png
    );
    assert_eq!(
        preflight_output(&dir.join("r.exr")).unwrap(),
        OutputFormat::Exr
    );
    assert_eq!(
        fs::read_dir(&dir).unwrap().count(),
        0,
        "preflight leaves nothing"
    );
}

#[test]
fn a_non_finite_image_is_refused_before_the_path_is_touched() {
    // The image is the caller's argument: refused whole, nothing written, the previous file as it
    // was (a failed render removes it: the CLI and the C API do that, not the encoder). A write
    // that fails after the checks removes it: src/output/atomic.rs's tests.
    let dir = scratch("stale");
    let path = dir.join("out.exr");
    write_image(&path, &red_over_blue(), &LINEAR).unwrap();
    let before = fs::read(&path).unwrap();
    let mut broken = red_over_blue();
    broken.set(1, 0, [f32::NAN, 0.0, 0.0, 1.0]);
    let message = write_image(&path, &broken, &LINEAR)
        .unwrap_err()
        .to_string();
    assert!(message.contains("pixel (1, 0)"), "{message}");
    assert_eq!(fs::read(&path).unwrap(), before);
    assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
}
