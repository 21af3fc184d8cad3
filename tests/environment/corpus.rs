//! Bad-input corpus, environments (tests/common/corpus.md lists every case): truncated, corrupted,
//! empty and enormous Radiance `.hdr` and OpenEXR files, and NaN/Inf/negative pixels. Each case
//! asserts the exact error kind, that the message says what, where and how to fix it, and through
//! the CLI (`shikki prefilter`, which loads before it opens a GPU) exit code 1 with nothing
//! written. The files are generated here: most are binary, and all are a few bytes.

use crate::common::corpus as support;

use std::time::Duration;

use exr::prelude::{
    Blocks, Compression, Encoding, Image, Layer, LayerAttributes, LineOrder, SpecificChannels,
    WritableImage,
};
use shikki::environment::load::{
    decode_environment, decode_exr, decode_hdr, load_environment, MAX_ENV_FILE_BYTES, MAX_PIXELS,
    MAX_SIDE,
};
use support::*;

/// A header claiming a huge image is refused from the header: 2 s is ~1000× the time it takes.
const HEADER_ONLY: Duration = Duration::from_secs(2);

fn hdr(width: usize, height: usize, pixels: &[u8]) -> Vec<u8> {
    let mut bytes =
        format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n").into_bytes();
    bytes.extend_from_slice(pixels);
    bytes
}

/// A valid 4 × 2 flat-pixel HDR (every pixel 1.0).
fn valid_hdr() -> Vec<u8> {
    hdr(4, 2, &[128, 128, 128, 129].repeat(8))
}

/// A 4 × 2 float RGB EXR, ZIP16, with the given pixels (row-major).
fn exr_rgb(pixels: [[f32; 3]; 8]) -> Vec<u8> {
    let encoding = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let channels = SpecificChannels::rgb(|p: exr::prelude::Vec2<usize>| {
        let [r, g, b] = pixels[p.1 * 4 + p.0];
        (r, g, b)
    });
    let layer = Layer::new((4, 2), LayerAttributes::default(), encoding, channels);
    let mut bytes = Vec::new();
    Image::from_layer(layer)
        .write()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .expect("encode EXR");
    bytes
}

fn valid_exr() -> Vec<u8> {
    exr_rgb([[1.0, 0.5, 0.25]; 8])
}

/// Rewrites an EXR header's box2i attribute `name` (dataWindow/displayWindow) to 0..=max.
fn with_window(mut bytes: Vec<u8>, name: &str, max_x: i32, max_y: i32) -> Vec<u8> {
    let key = [name.as_bytes(), b"\0box2i\0\x10\0\0\0"].concat();
    let at = bytes
        .windows(key.len())
        .position(|w| w == key.as_slice())
        .expect("attribute present")
        + key.len();
    for (k, v) in [0, 0, max_x, max_y].into_iter().enumerate() {
        bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
    bytes
}

/// `shikki prefilter FILE -o out/pf` fails with exit 1 and writes nothing.
fn cli_refuses(ws: &Workspace, file: &str, fragments: &[&str]) {
    assert_cli_fails(ws, &["prefilter", file, "-o", "out/pf"], fragments);
}

// ---- Radiance .hdr ----------------------------------------------------------------------------

#[test]
fn valid_files_load_so_the_corpus_cases_fail_for_their_own_reason() {
    let ws = Workspace::new();
    let hdr_path = ws.file("ok.hdr", valid_hdr());
    let exr_path = ws.file("ok.exr", valid_exr());
    for path in [hdr_path, exr_path] {
        let loaded = load_environment(path.to_str().unwrap()).unwrap();
        assert_eq!((loaded.image.width, loaded.image.height), (4, 2));
        assert_eq!(loaded.replaced_pixels, 0);
    }
}

#[test]
fn empty_hdr_is_a_parse_error_at_line_1() {
    let ws = Workspace::new();
    let path = ws.file("empty.hdr", b"");
    let message = expect_parse(load_environment(path.to_str().unwrap()), "empty.hdr", 1);
    assert_names(&message, &["empty", "#?RADIANCE"]);
    cli_refuses(&ws, "empty.hdr", &["empty.hdr:1", "empty"]);
}

#[test]
fn hdr_with_a_foreign_magic_names_the_expected_first_line() {
    let ws = Workspace::new();
    let path = ws.file("ppm.hdr", b"P6\n4 2\n255\n");
    let message = expect_parse(load_environment(path.to_str().unwrap()), "ppm.hdr", 1);
    assert_names(&message, &["not a Radiance HDR", "#?RADIANCE or #?RGBE"]);
    cli_refuses(&ws, "ppm.hdr", &["ppm.hdr:1", "#?RADIANCE"]);
}

#[test]
fn hdr_truncated_inside_the_header_names_the_missing_resolution_line() {
    let ws = Workspace::new();
    let path = ws.file("cut_header.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n");
    let message = expect_parse(
        load_environment(path.to_str().unwrap()),
        "cut_header.hdr",
        3,
    );
    assert_names(&message, &["resolution line", "truncated", "re-export"]);
    cli_refuses(
        &ws,
        "cut_header.hdr",
        &["cut_header.hdr:3", "resolution line"],
    );
}

#[test]
fn hdr_xyze_format_says_to_convert() {
    let ws = Workspace::new();
    let path = ws.file(
        "xyze.hdr",
        b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\0\0\0\0",
    );
    let message = expect_parse(load_environment(path.to_str().unwrap()), "xyze.hdr", 2);
    assert_names(
        &message,
        &["32-bit_rle_xyze", "only 32-bit_rle_rgbe", "convert"],
    );
}

#[test]
fn hdr_flipped_orientation_and_non_numeric_sizes_are_parse_errors() {
    let ws = Workspace::new();
    let path = ws.file("flip.hdr", b"#?RADIANCE\n\n+Y 2 +X 4\n");
    let message = expect_parse(load_environment(path.to_str().unwrap()), "flip.hdr", 3);
    assert_names(&message, &["-Y <height> +X <width>", "oiiotool"]);
    for (name, line) in [
        ("nan.hdr", "-Y NaN +X 4"),
        ("neg.hdr", "-Y -2 +X 4"),
        ("inf.hdr", "-Y 2 +X inf"),
        ("overflow.hdr", "-Y 99999999999999999999999 +X 4"),
    ] {
        let path = ws.file(name, format!("#?RADIANCE\n\n{line}\n"));
        let message = expect_parse(load_environment(path.to_str().unwrap()), name, 3);
        assert_names(&message, &["whole numbers"]);
    }
}

#[test]
fn hdr_claiming_a_million_squared_pixels_is_refused_from_the_header() {
    let ws = Workspace::new();
    // 10^12 pixels (12 TB as f32 RGB) in a 40-byte file.
    ws.file("huge.hdr", hdr(1_000_000, 1_000_000, &[]));
    let path = ws.path().join("huge.hdr");
    let message = quickly("huge.hdr", HEADER_ONLY, || {
        expect_invalid(load_environment(path.to_str().unwrap()), "environment size")
    });
    assert_names(
        &message,
        &[
            "1000000×1000000",
            "huge.hdr",
            &format!("1..={MAX_SIDE}"),
            "downscale",
        ],
    );
    // Each side within the limit, the product (2^30) above MAX_PIXELS.
    ws.file("wide.hdr", hdr(32768, 32768, &[]));
    let message = expect_invalid(
        load_environment(ws.path().join("wide.hdr").to_str().unwrap()),
        "environment size",
    );
    assert_names(
        &message,
        &[&format!("at most {MAX_PIXELS} pixels"), "downscale"],
    );
    // Under a 512 MiB address space: any allocation from the claimed size would abort.
    let args = ["prefilter", "huge.hdr", "-o", "out/pf"];
    let out = shikki_limited(ws.path(), &args, 512 * 1024);
    check_failure(&ws, &args, &out, &["environment size", "downscale"]);
}

#[test]
fn hdr_at_the_pixel_limit_with_no_data_is_refused_before_allocating() {
    let ws = Workspace::new();
    // 32768 × 8192 = 2^28 pixels (3 GiB as f32 RGB) is allowed, but 64 bytes cannot hold it.
    ws.file("at_limit.hdr", hdr(32768, 8192, &[0; 64]));
    let path = ws.path().join("at_limit.hdr");
    let message = quickly("at_limit.hdr", HEADER_ONLY, || {
        expect_invalid(
            load_environment(path.to_str().unwrap()),
            "Radiance HDR data",
        )
    });
    assert_names(&message, &["at_limit.hdr", "truncated", "re-export"]);
    let args = ["prefilter", "at_limit.hdr", "-o", "out/pf"];
    let out = shikki_limited(ws.path(), &args, 512 * 1024);
    check_failure(&ws, &args, &out, &["truncated"]);
}

#[test]
fn hdr_truncated_in_the_pixels_names_the_scan_line() {
    let ws = Workspace::new();
    // 8 × 4 new-style RLE lines: 2 2 0 8, then per component a literal of 8 (9 bytes) = 40
    // bytes, so the cut file still passes the up-front length check and fails in line 3.
    let mut line = vec![2, 2, 0, 8];
    for _ in 0..4 {
        line.push(8);
        line.extend([128; 8]);
    }
    let mut bytes = hdr(8, 4, &line.repeat(4));
    bytes.truncate(bytes.len() - 5);
    let path = ws.file("cut_pixels.hdr", bytes);
    let message = expect_invalid(
        load_environment(path.to_str().unwrap()),
        "Radiance HDR data",
    );
    assert_names(
        &message,
        &["cut_pixels.hdr", "scan line 3 of 4", "re-export"],
    );
    cli_refuses(&ws, "cut_pixels.hdr", &["scan line 3 of 4"]);
}

#[test]
fn hdr_with_corrupt_run_lengths_names_the_scan_line() {
    let ws = Workspace::new();
    for (name, line) in [
        // Scan line declares width 9, the header 8.
        ("rle_width.hdr", vec![2, 2, 0, 9, 0, 0, 0, 0]),
        // A run of 9 in a line of 8.
        ("rle_run.hdr", vec![2, 2, 0, 8, 128 + 9, 1]),
        // A zero-length literal (would loop forever if accepted).
        ("rle_zero.hdr", vec![2, 2, 0, 8, 0]),
    ] {
        let path = ws.file(name, hdr(8, 1, &[line, vec![0; 64]].concat()));
        let message = expect_invalid(
            load_environment(path.to_str().unwrap()),
            "Radiance HDR data",
        );
        assert_names(&message, &[name, "scan line 0 of 1", "re-export"]);
    }
    // An old-style repeat run before any pixel.
    let path = ws.file(
        "repeat.hdr",
        hdr(4, 1, &[1, 1, 1, 3, 0, 0, 0, 0, 0, 0, 0, 0]),
    );
    let message = expect_invalid(
        load_environment(path.to_str().unwrap()),
        "Radiance HDR data",
    );
    assert_names(&message, &["repeat run", "x = 0"]);
}

#[test]
fn hdr_header_without_a_newline_for_megabytes_is_bounded() {
    let ws = Workspace::new();
    // 4 MiB of header text without a line end: refused after the 64 KiB header limit.
    let mut bytes = b"#?RADIANCE\n".to_vec();
    bytes.extend(std::iter::repeat_n(b'A', 4 << 20));
    let path = ws.file("endless.hdr", bytes);
    let message = quickly("endless.hdr", HEADER_ONLY, || {
        expect_parse(load_environment(path.to_str().unwrap()), "endless.hdr", 2)
    });
    assert_names(&message, &["resolution line"]);
}

#[test]
fn environment_file_larger_than_the_limit_is_refused_before_reading() {
    let ws = Workspace::new();
    // A sparse 1 TiB file with a valid header: reading it would take hours and a terabyte.
    let path = ws.path().join("terabyte.hdr");
    sparse_file(&path, &hdr(4, 2, &[]), 1 << 40);
    let message = quickly("terabyte.hdr", HEADER_ONLY, || {
        expect_invalid(load_environment(path.to_str().unwrap()), "environment file")
    });
    assert_names(
        &message,
        &[
            "terabyte.hdr",
            &format!("{MAX_ENV_FILE_BYTES}"),
            "downscale",
        ],
    );
    cli_refuses(&ws, "terabyte.hdr", &["environment file", "terabyte.hdr"]);
}

// ---- OpenEXR -------------------------------------------------------------------------------

#[test]
fn empty_exr_is_an_invalid_openexr_file() {
    let ws = Workspace::new();
    let path = ws.file("empty.exr", b"");
    let message = expect_invalid(load_environment(path.to_str().unwrap()), "OpenEXR file");
    assert_names(
        &message,
        &[
            "empty.exr",
            "cannot read the header",
            "complete, valid OpenEXR",
        ],
    );
    cli_refuses(&ws, "empty.exr", &["OpenEXR file", "empty.exr"]);
}

#[test]
fn truncated_exr_is_an_invalid_openexr_file_at_every_cut() {
    let ws = Workspace::new();
    let bytes = valid_exr();
    // Cuts in the magic, the header, the offset table and the pixel data.
    for cut in [3, 20, bytes.len() / 2, bytes.len() - 1] {
        let name = format!("cut{cut}.exr");
        let path = ws.file(&name, &bytes[..cut]);
        let message = expect_invalid(load_environment(path.to_str().unwrap()), "OpenEXR file");
        assert_names(&message, &[&name, "complete, valid OpenEXR"]);
    }
    cli_refuses(&ws, "cut20.exr", &["OpenEXR file"]);
}

#[test]
fn exr_with_corrupted_bytes_loads_or_fails_cleanly() {
    // Every single-byte corruption of the file (each byte XOR 0xFF): Ok or an OpenEXR error,
    // never a panic. A corrupted pixel may decode; a corrupted structure must be refused.
    let bytes = valid_exr();
    let mut refused = 0;
    for at in 0..bytes.len() {
        let mut broken = bytes.clone();
        broken[at] ^= 0xFF;
        match decode_exr(&broken, "flip.exr") {
            Ok(image) => assert_eq!(
                image.pixels.len(),
                image.width as usize * image.height as usize
            ),
            Err(e) => {
                let message = e.to_string();
                assert!(message.contains("flip.exr"), "{message}");
                refused += 1;
            }
        }
    }
    assert!(
        refused > bytes.len() / 4,
        "only {refused} of {} refused",
        bytes.len()
    );
}

#[test]
fn exr_claiming_a_million_squared_pixels_is_refused_from_the_header() {
    let ws = Workspace::new();
    let bytes = with_window(valid_exr(), "dataWindow", 999_999, 999_999);
    let bytes = with_window(bytes, "displayWindow", 999_999, 999_999);
    let path = ws.file("huge.exr", &bytes);
    let result = quickly("huge.exr", HEADER_ONLY, || {
        load_environment(path.to_str().unwrap())
    });
    // Either the size check or the exr crate's own header check refuses it; never an allocation.
    let message = match result {
        Err(shikki::Error::InvalidParameter { ref field, .. }) if field == "environment size" => {
            result.unwrap_err().to_string()
        }
        other => expect_invalid(other, "OpenEXR file"),
    };
    assert_names(&message, &["huge.exr"]);
    let args = ["prefilter", "huge.exr", "-o", "out/pf"];
    let out = shikki_limited(ws.path(), &args, 512 * 1024);
    check_failure(&ws, &args, &out, &["huge.exr"]);
}

#[test]
fn exr_wider_than_the_side_limit_is_refused_with_the_limit() {
    let ws = Workspace::new();
    // 40000 × 2 pixels: the header is consistent except for the missing pixel blocks.
    let bytes = with_window(valid_exr(), "dataWindow", 39_999, 1);
    let path = ws.file("wide.exr", &bytes);
    let result = quickly("wide.exr", HEADER_ONLY, || {
        load_environment(path.to_str().unwrap())
    });
    let message = expect_invalid(result, "environment size");
    assert_names(
        &message,
        &[
            "40000×2",
            "wide.exr",
            &format!("1..={MAX_SIDE}"),
            "downscale",
        ],
    );
}

#[test]
fn exr_without_rgb_channels_says_an_environment_is_rgb() {
    let ws = Workspace::new();
    let encoding = Encoding::FAST_LOSSLESS;
    let channels = SpecificChannels::build()
        .with_channel("Y")
        .with_pixel_fn(|_| (0.5f32,));
    let layer = Layer::new((4, 2), LayerAttributes::default(), encoding, channels);
    let mut bytes = Vec::new();
    Image::from_layer(layer)
        .write()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .unwrap();
    let path = ws.file("luma.exr", &bytes);
    let message = expect_invalid(load_environment(path.to_str().unwrap()), "OpenEXR file");
    assert_names(&message, &["luma.exr", "R, G and B", "RGB(A)"]);
    cli_refuses(&ws, "luma.exr", &["R, G and B"]);
}

#[test]
fn nan_inf_and_negative_pixels_are_zeroed_and_counted() {
    let ws = Workspace::new();
    let mut pixels = [[1.0f32, 0.5, 0.25]; 8];
    pixels[0] = [f32::NAN, 1.0, 1.0];
    pixels[3] = [1.0, f32::INFINITY, 1.0];
    pixels[5] = [1.0, 1.0, -2.0];
    pixels[6] = [f32::NEG_INFINITY, f32::NAN, -0.0];
    let path = ws.file("nan.exr", exr_rgb(pixels));
    let loaded = load_environment(path.to_str().unwrap()).unwrap();
    // SPEC §4 policy: radiance is finite and ≥ 0; bad components become 0, counted per pixel.
    assert_eq!(loaded.replaced_pixels, 4);
    assert!(loaded
        .image
        .pixels
        .iter()
        .flatten()
        .all(|c| c.is_finite() && *c >= 0.0));
    assert_eq!(loaded.image.get(0, 0), [0.0, 1.0, 1.0]);
    assert_eq!(loaded.image.get(1, 1), [1.0, 1.0, 0.0]);
}

#[test]
fn environment_spec_errors_name_the_valid_forms() {
    let ws = Workspace::new();
    let message = expect_invalid(load_environment("studio.png"), "environment");
    assert_names(&message, &["studio.png", ".hdr", ".exr", "builtin:studio"]);
    let missing = ws.path().join("missing.hdr");
    let message = expect_read(load_environment(missing.to_str().unwrap()), &missing);
    assert_names(&message, &["missing.hdr", "no such file"]);
    cli_refuses(&ws, "missing.hdr", &["cannot read", "missing.hdr"]);
}

#[test]
fn in_memory_decoding_refuses_garbage_and_hostile_headers() {
    // decode_environment (the C API's entry point) sniffs the format: garbage is a Radiance
    // parse error, an EXR magic with nothing after it an OpenEXR error.
    let message = expect_parse(decode_environment(b"\xFF\xFEgarbage\n", "mem"), "mem", 1);
    assert_names(&message, &["#?RADIANCE"]);
    expect_invalid(
        decode_environment(&[0x76, 0x2f, 0x31, 0x01], "mem"),
        "OpenEXR file",
    );
    expect_invalid(
        decode_hdr(&hdr(1_000_000, 1_000_000, &[]), "mem"),
        "environment size",
    );
    let message = expect_invalid(decode_exr(&[], "mem.exr"), "OpenEXR file");
    assert_names(&message, &["mem.exr"]);
}

#[test]
fn render_with_a_bad_environment_leaves_no_image() {
    // The render command opens the GPU before it loads the environment: the failure must still
    // leave nothing behind.
    let ws = Workspace::new();
    ws.file("empty.hdr", b"");
    assert_cli_fails(
        &ws,
        &[
            "render",
            "--env",
            "empty.hdr",
            "--size",
            "16x16",
            "-o",
            "out/r.png",
        ],
        &["empty.hdr:1"],
    );
}
