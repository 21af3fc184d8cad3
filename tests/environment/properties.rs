//! Property tests of the environment decoders (Radiance HDR, OpenEXR, the sniffing in-memory
//! entry point): on arbitrary bytes, on mutations of valid files and on near-valid headers they
//! return Ok (an image whose size agrees with its pixels and the limits) or a well-formed error,
//! never panic and never hang. Case counts: tests/common/prop.rs.

use crate::common::prop as prop_support;

use exr::prelude::{
    Blocks, Compression, Encoding, Image, Layer, LayerAttributes, LineOrder, SpecificChannels,
    WritableImage,
};
use prop_support::*;
use proptest::prelude::*;
use shikki::environment::load::{decode_environment, decode_exr, decode_hdr, MAX_PIXELS, MAX_SIDE};
use shikki::environment::Equirect;

fn image_ok(image: &Equirect) -> Result<(), TestCaseError> {
    let (w, h) = (image.width as usize, image.height as usize);
    prop_assert!(w >= 1 && h >= 1 && w <= MAX_SIDE && h <= MAX_SIDE && w * h <= MAX_PIXELS);
    prop_assert_eq!(image.pixels.len(), w * h);
    Ok(())
}

fn check_hdr(bytes: Vec<u8>) -> Result<(), TestCaseError> {
    let result = within("decode_hdr", move || decode_hdr(&bytes, "p.hdr"));
    well_formed(&result)?;
    if let Ok(image) = &result {
        image_ok(image)?;
    }
    Ok(())
}

fn check_exr(bytes: Vec<u8>) -> Result<(), TestCaseError> {
    let sniffed = bytes.clone();
    let result = within("decode_exr", move || decode_exr(&bytes, "p.exr"));
    well_formed(&result)?;
    if let Ok(image) = &result {
        image_ok(image)?;
    }
    let loaded = within("decode_environment", move || {
        decode_environment(&sniffed, "p")
    });
    well_formed(&loaded)?;
    if let Ok(loaded) = &loaded {
        image_ok(&loaded.image)?;
        // Sanitised: every component finite and ≥ 0.
        prop_assert!(loaded
            .image
            .pixels
            .iter()
            .flatten()
            .all(|c| c.is_finite() && *c >= 0.0));
    }
    Ok(())
}

/// A valid 9 × 3 HDR: a flat line, a new-style RLE line (width ≥ 8) with runs and literals, and
/// an old-style repeat line.
fn valid_hdr() -> Vec<u8> {
    let mut bytes =
        b"#?RADIANCE\n# made by a test\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1\n\n-Y 3 +X 9\n".to_vec();
    bytes.extend([128, 64, 32, 130].repeat(9));
    bytes.extend([2, 2, 0, 9]);
    for _ in 0..4 {
        bytes.extend([128 + 4, 100, 5, 1, 2, 3, 4, 5]);
    }
    bytes.extend([10, 20, 30, 131, 1, 1, 1, 8]);
    bytes
}

/// A 6 × 5 RGB EXR (float, values of every sign and size) with `compression`.
fn valid_exr(compression: Compression, tiles: bool) -> Vec<u8> {
    let encoding = Encoding {
        compression,
        blocks: if tiles {
            Blocks::Tiles(exr::prelude::Vec2(4, 4))
        } else {
            Blocks::ScanLines
        },
        line_order: LineOrder::Increasing,
    };
    let channels = SpecificChannels::rgb(|p: exr::prelude::Vec2<usize>| {
        let v = (p.0 * 7 + p.1 * 3) as f32 - 10.0;
        (v, v * 0.5, 1.0 / (v + 0.5))
    });
    let layer = Layer::new((6, 5), LayerAttributes::default(), encoding, channels);
    let mut bytes = Vec::new();
    Image::from_layer(layer)
        .write()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .expect("encode EXR");
    bytes
}

fn exr_originals() -> &'static [Vec<u8>] {
    static ORIGINALS: std::sync::OnceLock<Vec<Vec<u8>>> = std::sync::OnceLock::new();
    ORIGINALS.get_or_init(|| {
        vec![
            valid_exr(Compression::Uncompressed, false),
            valid_exr(Compression::ZIP16, false),
            valid_exr(Compression::RLE, false),
            valid_exr(Compression::PIZ, false),
            valid_exr(Compression::PXR24, false),
            valid_exr(Compression::ZIP1, true),
        ]
    })
}

/// Radiance header lines, near-valid.
const HDR_HEADER_LINES: &[&str] = &[
    "#?RADIANCE",
    "#?RGBE",
    "FORMAT=32-bit_rle_rgbe",
    "FORMAT=32-bit_rle_xyze",
    "EXPOSURE=2",
    "# comment",
    "",
    "-Y 2 +X 9",
    "-Y 1 +X 1",
    "+Y 2 +X 9",
    "-Y 0 +X 0",
    "-Y 32768 +X 8192",
    "-Y 99999999999999999999 +X 2",
    "-Y 4 +X",
];

proptest! {
    #![proptest_config(config(1024))]

    #[test]
    fn hdr_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        check_hdr(bytes)?;
    }

    #[test]
    fn hdr_with_a_valid_header_and_arbitrary_pixels(
        width in 1usize..40,
        height in 1usize..6,
        pixels in prop::collection::vec(any::<u8>(), 0..1024),
    ) {
        let mut bytes = format!("#?RADIANCE\n\n-Y {height} +X {width}\n").into_bytes();
        bytes.extend(pixels);
        check_hdr(bytes)?;
    }

    #[test]
    fn hdr_mutations_of_a_valid_file(edits in mutations()) {
        check_hdr(apply(&valid_hdr(), &edits))?;
    }

    #[test]
    fn hdr_near_valid_headers(
        lines in prop::collection::vec(prop::sample::select(HDR_HEADER_LINES), 0..8),
        tail in prop::collection::vec(any::<u8>(), 0..256),
    ) {
        let mut bytes = lines.join("\n").into_bytes();
        bytes.push(b'\n');
        bytes.extend(tail);
        check_hdr(bytes)?;
    }
}

proptest! {
    #![proptest_config(config(1024))]

    #[test]
    fn exr_arbitrary_bytes_after_the_magic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        let mut file = vec![0x76, 0x2f, 0x31, 0x01];
        file.extend(bytes);
        check_exr(file)?;
    }

    #[test]
    fn exr_mutations_of_valid_files(which in 0usize..6, edits in mutations()) {
        check_exr(apply(&exr_originals()[which], &edits))?;
    }
}

#[test]
fn the_originals_decode() {
    // The mutation properties start from files that load, so they explore the decoders' depth.
    assert_eq!(decode_hdr(&valid_hdr(), "v.hdr").unwrap().pixels.len(), 27);
    for bytes in exr_originals().iter() {
        assert_eq!(decode_exr(bytes, "v.exr").unwrap().pixels.len(), 30);
    }
}
